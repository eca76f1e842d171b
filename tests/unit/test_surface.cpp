// The Surface (surface.h): every point query and vertex accessor against a brute-force reference
// built from the definition in docs/surface.md (the finest lattice's vertices, the diagonal rule,
// barycentric blends, cross products), with no detail (L = 0) and with detail (L = 2, 3); the
// batched queries equal the single ones; Terrain's forwards equal the surface's; a clone shares
// the immutable detail field and answers the same.
#include <gtest/gtest.h>

#include <cmath>
#include <glm/geometric.hpp>
#include <limits>
#include <random>
#include <vector>

#include "ridgeline/detail.h"
#include "ridgeline/scenes.h"
#include "ridgeline/surface.h"
#include "ridgeline/terrain.h"

namespace ridgeline {
namespace {

// 33 x 25 samples, 3 m by 2 m apart, far from the world origin, with hills, a cliff and a
// material per cell (i + 2j) mod 7.
Heightfield make_samples() {
  std::vector<std::uint8_t> mats;
  for (int j = 0; j < 24; ++j)
    for (int i = 0; i < 32; ++i) mats.push_back(std::uint8_t((i + 2 * j) % 7));
  auto hf = scenes::field(
      {.width = 33,
       .height = 25,
       .spacing_x = 3,
       .spacing_z = 2,
       .origin_x = 1e5,
       .origin_z = -7e4,
       .height_offset = 1200},
      [](int i, int j) {
        return 20 * std::sin(i * 0.31) * std::cos(j * 0.23) + (i > 20 ? 35.0 : 0.0) + 0.7 * j;
      },
      mats);
  EXPECT_TRUE(hf.ok()) << (hf.ok() ? "" : hf.error().message);
  return std::move(hf).value();
}

std::shared_ptr<const Terrain> make_terrain(std::uint32_t levels) {
  if (levels == 0) return Terrain::create(make_samples()).value();
  DetailParams p;
  p.levels = levels;
  p.seed = 9;
  p.amplitude = 2.5;
  p.gain = 0.6;
  DetailCacheDesc cache;
  cache.worker_threads = 0;
  auto t = Terrain::create(make_samples(), p, cache);
  EXPECT_TRUE(t.ok()) << (t.ok() ? "" : t.error().message);
  return std::move(t).value();
}

// The reference: the finest lattice's vertices computed from the definition, once.
struct Reference {
  const Heightfield hf;
  std::uint32_t L;
  std::int64_t w, h;  // vertices per axis
  double sx, sz;      // finest spacing
  std::vector<double> local;

  Reference(const Terrain& t)
      : hf(t.surface().to_heightfield().value()), L(t.surface().detail_levels()) {
    w = (std::int64_t(hf.width()) - 1) * (std::int64_t{1} << L) + 1;
    h = (std::int64_t(hf.height()) - 1) * (std::int64_t{1} << L) + 1;
    sx = hf.spacing_x() / double(1 << L);
    sz = hf.spacing_z() / double(1 << L);
    local.resize(std::size_t(w * h));
    const std::int64_t n = std::int64_t{1} << L;
    for (std::int64_t j = 0; j < h; ++j)
      for (std::int64_t i = 0; i < w; ++i) {
        // The stored cell holding the vertex (the last one for the far edges), the vertex's
        // fractions in it, the stored triangle's barycentric blend, plus the detail there.
        const std::int64_t ci = std::min<std::int64_t>(i / n, hf.width() - 2);
        const std::int64_t cj = std::min<std::int64_t>(j / n, hf.height() - 2);
        const double fu = double(i - ci * n) / double(n), fv = double(j - cj * n) / double(n);
        const CellTriangle tri = locate_in_cell(ci, cj, float(fu), float(fv));
        double base = 0;
        for (int k = 0; k < 3; ++k)
          base += double(tri.w[k]) *
                  hf.local(std::uint32_t(ci + tri.di[k]), std::uint32_t(cj + tri.dj[k]));
        const double d = L == 0 ? 0.0 : t.surface().detail()->detail(L, i, j);
        local[std::size_t(i + j * w)] = base + d;
      }
  }
  double at(std::int64_t i, std::int64_t j) const { return local[std::size_t(i + j * w)]; }
  glm::dvec3 pos(std::int64_t i, std::int64_t j) const { return {i * sx, at(i, j), j * sz}; }
  // The unnormalised upward normal of triangle `t` of cell (i, j).
  glm::dvec3 cross(std::int64_t i, std::int64_t j, const CellTriangle& t) const {
    const glm::dvec3 a = pos(i + t.di[0], j + t.dj[0]), b = pos(i + t.di[1], j + t.dj[1]);
    const glm::dvec3 c = pos(i + t.di[2], j + t.dj[2]);
    return glm::cross(b - a, c - a);
  }
};

// The two finest triangles of a cell: they hold (0.2, 0.1) and (0.1, 0.2) for the main diagonal,
// (0.1, 0.1) and (0.9, 0.9) for the anti diagonal.
std::vector<CellTriangle> triangles_of(std::int64_t i, std::int64_t j) {
  if (cell_has_main_diagonal(i, j))
    return {locate_in_cell(i, j, 0.2f, 0.1f), locate_in_cell(i, j, 0.1f, 0.2f)};
  return {locate_in_cell(i, j, 0.1f, 0.1f), locate_in_cell(i, j, 0.9f, 0.9f)};
}

glm::dvec3 vertex_normal_ref(const Reference& r, std::int64_t i, std::int64_t j) {
  glm::dvec3 sum(0.0);
  for (std::int64_t cj = j - 1; cj <= j; ++cj)
    for (std::int64_t ci = i - 1; ci <= i; ++ci) {
      if (ci < 0 || cj < 0 || ci + 1 >= r.w || cj + 1 >= r.h) continue;
      for (const CellTriangle& t : triangles_of(ci, cj)) {
        bool corner = false;
        for (int k = 0; k < 3; ++k) corner |= (ci + t.di[k] == i && cj + t.dj[k] == j);
        if (corner) sum += r.cross(ci, cj, t);
      }
    }
  return glm::normalize(sum);
}

void expect_near(const glm::vec3& a, const glm::dvec3& b, double tol, const char* what) {
  EXPECT_NEAR(a.x, b.x, tol) << what;
  EXPECT_NEAR(a.y, b.y, tol) << what;
  EXPECT_NEAR(a.z, b.z, tol) << what;
}

void check_against_brute_force(std::uint32_t levels) {
  SCOPED_TRACE("detail levels " + std::to_string(levels));
  auto terrain = make_terrain(levels);
  const Surface& s = terrain->surface();
  const Reference ref(*terrain);
  const Heightfield hf = terrain->surface().to_heightfield().value();

  // The lattice as documented.
  const SurfaceLattice& at = s.lattice();
  EXPECT_EQ(at.levels, levels);
  EXPECT_EQ(at.vertices_x, ref.w);
  EXPECT_EQ(at.vertices_z, ref.h);
  EXPECT_EQ(at.spacing_x, ref.sx);
  EXPECT_EQ(at.spacing_z, ref.sz);
  EXPECT_EQ(at.origin_x, hf.origin_x());
  EXPECT_EQ(at.height_offset, hf.height_offset());
  EXPECT_EQ(s.detail_levels(), levels);
  EXPECT_EQ(s.detail() != nullptr, levels > 0);
  EXPECT_EQ(s.detail_bound() > 0, levels > 0);

  // Vertex by vertex: heights, detail, normals; clamped outside.
  for (std::int64_t j = 0; j < ref.h; ++j)
    for (std::int64_t i = 0; i < ref.w; ++i) {
      ASSERT_NEAR(s.vertex_height(i, j), ref.at(i, j), 1e-5) << i << ", " << j;
      // The stored surface alone: the height without the vertex's detail.
      ASSERT_NEAR(s.vertex_base_height(i, j), s.vertex_height(i, j) - s.vertex_detail(i, j), 1e-9)
          << i << ", " << j;
      if (i % 3 == 0 && j % 2 == 0)
        expect_near(s.vertex_normal(i, j), vertex_normal_ref(ref, i, j), 1e-5, "vertex normal");
    }
  EXPECT_EQ(s.vertex_height(-5, 3), s.vertex_height(0, 3));
  EXPECT_EQ(s.vertex_height(ref.w + 9, ref.h), s.vertex_height(ref.w - 1, ref.h - 1));
  EXPECT_EQ(s.vertex_normal(-1, -1), s.vertex_normal(0, 0));
  EXPECT_EQ(s.vertex_base_height(-2, ref.h + 4), s.vertex_base_height(0, ref.h - 1));
  if (levels == 0) {
    EXPECT_EQ(s.vertex_detail(3, 4), 0.0);
  }
  const std::int64_t n = std::int64_t{1} << levels;
  EXPECT_EQ(s.vertex_detail(5 * n, 7 * n), 0.0);  // stored samples carry no detail
  for (std::int64_t j = 0; j + 1 < ref.h; j += 3)
    for (std::int64_t i = 0; i + 1 < ref.w; i += 2)
      EXPECT_EQ(s.cell_material(i, j), hf.material(std::uint32_t(i / n), std::uint32_t(j / n)));
  EXPECT_EQ(s.cell_material(ref.w, -3), hf.material(hf.width() - 2, 0));

  // Point queries at random points, cell edges, vertices and the far edges.
  std::mt19937_64 rng(levels + 1);
  std::uniform_real_distribution<double> fu(0.0, 1.0);
  std::vector<glm::dvec2> points;
  for (int k = 0; k < 3000; ++k)
    points.push_back({fu(rng) * double(ref.w - 1), fu(rng) * double(ref.h - 1)});
  for (std::int64_t k = 0; k < 40; ++k) {
    points.push_back({double(k % (ref.w - 1)), fu(rng) * double(ref.h - 1)});  // a cell side
    points.push_back({double(k % ref.w), double((3 * k) % ref.h)});            // a vertex
  }
  points.push_back({double(ref.w - 1), double(ref.h - 1)});  // the far corner: on the surface
  for (glm::dvec2& p : points) {
    const double u = p.x, v = p.y;
    const double x = hf.origin_x() + u * ref.sx, z = hf.origin_z() + v * ref.sz;
    p = {x, z};
    // The reference: the finest cell by floor (the last one on the far edges), the diagonal
    // rule, the barycentric blend, the triangle's cross product, the stored cell's material.
    const std::int64_t i = std::min<std::int64_t>(std::int64_t(u), ref.w - 2);
    const std::int64_t j = std::min<std::int64_t>(std::int64_t(v), ref.h - 2);
    const CellTriangle t = locate_in_cell(i, j, float(u - double(i)), float(v - double(j)));
    double hr = hf.height_offset();
    glm::dvec3 smooth(0.0);
    for (int k = 0; k < 3; ++k) {
      hr += double(t.w[k]) * ref.at(i + t.di[k], j + t.dj[k]);
      smooth += double(t.w[k]) * vertex_normal_ref(ref, i + t.di[k], j + t.dj[k]);
    }
    const glm::dvec3 face = glm::normalize(ref.cross(i, j, t));
    const std::uint8_t mat = hf.material(std::uint32_t(i / n), std::uint32_t(j / n));

    const auto h = s.height(x, z);
    ASSERT_TRUE(h) << u << ", " << v;
    ASSERT_NEAR(*h, hr, 1e-4) << u << ", " << v;
    expect_near(*s.face_normal(x, z), face, 2e-5, "face normal");
    expect_near(*s.smooth_normal(x, z), glm::normalize(smooth), 2e-5, "smooth normal");
    EXPECT_EQ(*s.material(x, z), mat);
    // The combined queries are the single ones, bit for bit.
    const auto hn = s.height_normal(x, z);
    const auto sm = s.sample(x, z);
    ASSERT_TRUE(hn && sm);
    EXPECT_EQ(hn->height, *h);
    EXPECT_EQ(hn->face_normal, *s.face_normal(x, z));
    EXPECT_EQ(hn->material, mat);
    EXPECT_EQ(sm->height, *h);
    EXPECT_EQ(sm->face_normal, hn->face_normal);
    EXPECT_EQ(sm->smooth_normal, *s.smooth_normal(x, z));
    EXPECT_EQ(sm->material, mat);
    // Terrain's forwards are the surface's.
    EXPECT_EQ(*terrain->height(x, z), *h);
    EXPECT_EQ(terrain->sample(x, z)->smooth_normal, sm->smooth_normal);
  }

  // Off the footprint and bad input: nothing, from every query.
  const double far_x = hf.origin_x() + hf.extent_x(), far_z = hf.origin_z() + hf.extent_z();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const glm::dvec2& p :
       {glm::dvec2{hf.origin_x() - 1e-6, hf.origin_z() + 1},
        glm::dvec2{far_x + 1e-6, hf.origin_z() + 1},
        glm::dvec2{hf.origin_x() + 1, far_z * (1 + 1e-12) + 1e-6},
        glm::dvec2{nan, hf.origin_z() + 1}, glm::dvec2{hf.origin_x(), INFINITY}}) {
    EXPECT_FALSE(s.height(p.x, p.y));
    EXPECT_FALSE(s.face_normal(p.x, p.y));
    EXPECT_FALSE(s.smooth_normal(p.x, p.y));
    EXPECT_FALSE(s.material(p.x, p.y));
    EXPECT_FALSE(s.height_normal(p.x, p.y));
    EXPECT_FALSE(s.sample(p.x, p.y));
    points.push_back(p);
  }

  // Batched: the single queries, NaN / invalid off the footprint; short outputs bound the work.
  std::vector<double> heights(points.size(), -1.0);
  s.heights(points, heights);
  std::vector<SurfaceSample> samples(points.size());
  std::vector<std::uint8_t> valid(points.size(), 7);
  s.samples(points, samples, valid);
  for (std::size_t k = 0; k < points.size(); ++k) {
    const auto h = s.height(points[k].x, points[k].y);
    if (h) {
      EXPECT_EQ(heights[k], *h);
      ASSERT_EQ(valid[k], 1);
      EXPECT_EQ(samples[k].smooth_normal, s.sample(points[k].x, points[k].y)->smooth_normal);
    } else {
      EXPECT_TRUE(std::isnan(heights[k]));
      EXPECT_EQ(valid[k], 0);
      EXPECT_EQ(samples[k].height, 0.0);
    }
  }
  std::vector<double> two(2, -1.0);
  s.heights(points, two);
  EXPECT_EQ(two[1], heights[1]);
  std::vector<double> spare(points.size() + 3, -1.0);
  s.heights(std::span(points).first(5), spare);
  EXPECT_EQ(spare[4], heights[4]);
  EXPECT_EQ(spare[5], -1.0);
}

TEST(Surface, QueriesMatchTheDefinitionWithoutDetail) {
  check_against_brute_force(0);
}
TEST(Surface, QueriesMatchTheDefinitionWithTwoDetailLevels) {
  check_against_brute_force(2);
}
TEST(Surface, QueriesMatchTheDefinitionWithThreeDetailLevels) {
  check_against_brute_force(3);
}

// Rays and boxes read the same lattice as the point queries: a vertical ray hits at height(),
// and every triangle in a box has the surface's vertex heights at its corners.
TEST(Surface, RaysAndBoxesReadTheSameLattice) {
  for (std::uint32_t levels : {0u, 2u}) {
    auto terrain = make_terrain(levels);
    const Surface& s = terrain->surface();
    const SurfaceLattice& at = s.lattice();
    std::mt19937_64 rng(levels + 11);
    std::uniform_real_distribution<double> ux(at.origin_x, at.origin_x + 96),
        uz(at.origin_z, at.origin_z + 48);
    for (int k = 0; k < 300; ++k) {
      const double x = ux(rng), z = uz(rng);
      const auto hit = terrain->raycast({x, 1e4, z}, {0, -1, 0}, INFINITY);
      ASSERT_TRUE(hit);
      EXPECT_NEAR(hit->point.y, 1e4 - hit->distance, 1e-9);
      // height() blends the stored samples in float (as the mesh does), the ray in double.
      EXPECT_NEAR(1e4 - hit->distance, *s.height(x, z), 2e-5);
      EXPECT_EQ(hit->normal, *s.face_normal(x, z));
      EXPECT_EQ(hit->material, *s.material(x, z));
    }
    std::vector<SurfaceTriangle> tris;
    const Box box{{at.origin_x + 10, -1e5, at.origin_z + 7},
                  {at.origin_x + 19, 1e5, at.origin_z + 12}};
    ASSERT_GT(terrain->triangles_in_box(box, tris), 0u);
    for (const SurfaceTriangle& t : tris)
      for (const glm::dvec3& v : t.v) {
        const double fi = (v.x - at.origin_x) / at.spacing_x,
                     fj = (v.z - at.origin_z) / at.spacing_z;
        const auto i = std::llround(fi), j = std::llround(fj);
        ASSERT_NEAR(fi, double(i), 1e-9);
        EXPECT_EQ(v.y, at.height_offset + s.vertex_height(i, j));
      }
  }
}

// A clone is a snapshot of the same surface: the same answers; the detail field (immutable, bound
// to no terrain) is shared, with a tile cache of the clone's own.
TEST(Surface, CloneSharesTheDetailFieldAndAnswersTheSame) {
  auto t = make_terrain(2);
  auto c = t->clone();
  EXPECT_EQ(c->surface().detail(), t->surface().detail());
  EXPECT_NE(c->surface().detail_cache(), t->surface().detail_cache());
  EXPECT_EQ(c->surface().detail_hash(), t->surface().detail_hash());
  EXPECT_EQ(c->surface().heights_hash(), t->surface().heights_hash());
  const SurfaceLattice at = t->surface().lattice();  // a copy: t goes below
  for (int k = 0; k < 200; ++k) {
    const double x = at.origin_x + 0.47 * k, z = at.origin_z + 0.23 * k;
    EXPECT_EQ(c->surface().sample(x, z)->smooth_normal, t->surface().sample(x, z)->smooth_normal);
    EXPECT_EQ(*c->height(x, z), *t->height(x, z));
  }
  t.reset();  // the clone does not need the original (nor does its field)
  EXPECT_TRUE(c->height(at.origin_x + 5, at.origin_z + 5));
}

}  // namespace
}  // namespace ridgeline
