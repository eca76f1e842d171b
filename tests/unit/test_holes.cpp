// Holes (docs/deformation.md, "Holes"): the `hole` and `fill_hole` brushes on a flat field,
// where every answer is analytic: queries empty inside and present on the edge, rays through to
// the far side, boxes without the hole's triangles, the mesh drawn over exactly the ground
// (conforming, no triangle over a hole, no crack or T-junction at its edge), filled back to the
// mesh it had, views updated in place equal fresh ones, the change log, clones, the edit file.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>

#include "ridgeline/detail.h"
#include "ridgeline/edit.h"
#include "ridgeline/roam_view.h"
#include "ridgeline/scenes.h"
#include "roam_test_util.h"

using namespace ridgeline;
using namespace ridgeline::test;

namespace {

std::shared_ptr<Terrain> field(std::uint32_t n, double (*h)(int, int)) {
  return Terrain::create(std::move(scenes::field({.width = n, .height = n}, h).value())).value();
}
std::shared_ptr<Terrain> flat(std::uint32_t n = 65) {
  return field(n, [](int, int) { return 5.0; });
}

// The cells whose centre lies within r of (x, z) on a unit grid: the brush's definition.
std::vector<std::array<int, 2>> cells_within(int n, double x, double z, double r) {
  std::vector<std::array<int, 2>> out;
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i)
      if (std::hypot(i + 0.5 - x, j + 0.5 - z) <= r) out.push_back({i, j});
  return out;
}

// The triangles a view draws (not degenerate), corners in lattice units of the stored lattice.
std::vector<std::array<glm::dvec3, 3>> drawn(const RoamView& v) {
  std::vector<std::array<glm::dvec3, 3>> out;
  const Landscape& l = v.landscape();
  for (std::uint32_t p = 0; p < l.patch_count(); ++p) {
    const PatchMesh& m = v.patch_mesh(p);
    for (std::size_t t = 0; t + 2 < m.indices.size(); t += 3) {
      if (m.indices[t] == m.indices[t + 1]) continue;
      std::array<glm::dvec3, 3> tri;
      for (int k = 0; k < 3; ++k) {
        const MeshVertex& q = m.vertices[m.indices[t + std::size_t(k)]];
        tri[std::size_t(k)] = {m.origin_x + q.x, m.origin_y + q.y, m.origin_z + q.z};
      }
      out.push_back(tri);
    }
  }
  return out;
}

// The drawn mesh covers exactly the ground: every half-cell (triangle of the diagonal rule) of a
// solid cell once, none of a hole cell (without detail); every drawn edge is shared by two drawn
// triangles unless across it lies a hole or the terrain's edge (no crack, no T-junction). Unit
// stored spacing; with L detail levels lattice coordinates are in finest cells. "" when it holds.
std::string check_drawn_over_ground(const RoamView& v, const Terrain& t) {
  const Surface& s = t.surface();
  const std::int64_t W = t.info().width - 1, H = t.info().height - 1;  // cells (unit spacing)
  const double scale = double(std::int64_t{1} << s.detail_levels());
  std::vector<int> covered(std::size_t(2 * W * H), 0);
  std::map<std::array<std::int64_t, 4>, int> edges;
  auto lat = [&](const glm::dvec3& p) {
    return std::array<std::int64_t, 2>{std::llround(p.x * scale), std::llround(p.z * scale)};
  };
  for (const auto& tri : drawn(v)) {
    std::array<std::int64_t, 2> c[3] = {lat(tri[0]), lat(tri[1]), lat(tri[2])};
    const double cx = (tri[0].x + tri[1].x + tri[2].x) / 3, cz = (tri[0].z + tri[1].z + tri[2].z) / 3;
    if (s.hole(std::int64_t(std::floor(cx)), std::int64_t(std::floor(cz))))
      return "a triangle with its centroid at (" + std::to_string(cx) + ", " + std::to_string(cz) +
             ") is drawn over a hole";
    for (int e = 0; e < 3; ++e) {
      auto a = c[e], b = c[(e + 1) % 3];
      if (b < a) std::swap(a, b);
      ++edges[{a[0], a[1], b[0], b[1]}];
    }
    if (s.detail_levels() != 0) continue;
    // Half-cells inside: their centroids (exact in thirds).
    const std::int64_t x0 = std::min({c[0][0], c[1][0], c[2][0]}), x1 = std::max({c[0][0], c[1][0], c[2][0]});
    const std::int64_t z0 = std::min({c[0][1], c[1][1], c[2][1]}), z1 = std::max({c[0][1], c[1][1], c[2][1]});
    const std::int64_t w = (c[1][0] - c[0][0]) * (c[2][1] - c[0][1]) - (c[1][1] - c[0][1]) * (c[2][0] - c[0][0]);
    for (std::int64_t j = z0; j < z1; ++j)
      for (std::int64_t i = x0; i < x1; ++i)
        for (int which = 0; which < 2; ++which) {
          const bool main = ((i + j) & 1) == 0;
          const std::int64_t px = 3 * i + (main ? (which ? 1 : 2) : (which ? 2 : 1));
          const std::int64_t pz = 3 * j + (main ? (which ? 2 : 1) : (which ? 2 : 1));
          bool in = true;
          for (int e = 0; e < 3 && in; ++e) {
            const auto& a = c[e];
            const auto& b = c[(e + 1) % 3];
            in = ((b[0] - a[0]) * (pz - 3 * a[1]) - (b[1] - a[1]) * (px - 3 * a[0])) * (w > 0 ? 1 : -1) > 0;
          }
          if (in) ++covered[std::size_t(2 * (i + j * W) + which)];
        }
  }
  for (std::int64_t j = 0; j < H && s.detail_levels() == 0; ++j)
    for (std::int64_t i = 0; i < W; ++i)
      for (int which = 0; which < 2; ++which) {
        const int n = covered[std::size_t(2 * (i + j * W) + which)];
        if (n != (s.hole(i, j) ? 0 : 1))
          return "half-cell " + std::to_string(which) + " of cell (" + std::to_string(i) + ", " +
                 std::to_string(j) + ") is drawn " + std::to_string(n) + " times";
      }
  // An edge drawn once has a hole or the terrain's edge on its other side (the triangle beside
  // it across the edge is not drawn because it is not ground, not because the mesh has a gap).
  for (const auto& [e, n] : edges) {
    if (n == 2) continue;
    const double mx = 0.5 * double(e[0] + e[2]), mz = 0.5 * double(e[1] + e[3]);
    // The two points just off the edge's midpoint: one of them is in the drawn triangle.
    const double nx = -double(e[3] - e[1]), nz = double(e[2] - e[0]);
    int ground = 0;
    for (const double side : {-1e-3, 1e-3}) {
      const double x = (mx + side * nx) / scale, z = (mz + side * nz) / scale;
      if (x < 0 || z < 0 || x > double(W) || z > double(H)) continue;
      ground += s.hole(std::int64_t(std::floor(x)), std::int64_t(std::floor(z))) ? 0 : 1;
    }
    if (n != 1 || ground != 1)
      return "edge (" + std::to_string(e[0]) + "," + std::to_string(e[1]) + ")-(" +
             std::to_string(e[2]) + "," + std::to_string(e[3]) + ") drawn " + std::to_string(n) +
             " times with ground on " + std::to_string(ground) + " side(s)";
  }
  return "";
}

std::unique_ptr<RoamView> converged_view(std::shared_ptr<const Landscape> l, const Camera& cam,
                                         double threshold) {
  auto v = RoamView::create(std::move(l), {.metric = ErrorMetric::kWorldMetres,
                                           .threshold = threshold})
               .value();
  EXPECT_TRUE(v->converge(cam));
  return v;
}

}  // namespace

TEST(Holes, QueriesAreEmptyInsideAndPresentOnTheEdge) {
  auto t = flat();
  const std::uint64_t v0 = t->edit_version();
  auto r = t->apply_edit({.brush = Brush::kHole, .x = 20.5, .z = 20.5, .radius = 3});
  ASSERT_TRUE(r) << r.error().message;
  const auto cells = cells_within(65, 20.5, 20.5, 3);
  EXPECT_EQ(r->cells_changed, cells.size());
  EXPECT_EQ(r->samples_changed, 0u);
  EXPECT_FALSE(r->empty());
  EXPECT_EQ(t->edit_version(), v0 + 1);
  const Surface& s = t->surface();
  EXPECT_EQ(s.hole_cells(), cells.size());
  for (const auto& c : cells) EXPECT_TRUE(s.hole(c[0], c[1]));
  // Row 20: cells 17..23 are holes (centres within 3 of 20.5), 16 and 24 ground.
  EXPECT_FALSE(t->height(20.5, 20.5));
  EXPECT_FALSE(t->height(23.99, 20.5));
  EXPECT_FALSE(t->height(17.01, 20.5));
  EXPECT_FALSE(s.face_normal(20.5, 20.5));
  EXPECT_FALSE(s.smooth_normal(20.5, 20.5));
  EXPECT_FALSE(s.material(20.5, 20.5));
  EXPECT_FALSE(s.height_normal(20.5, 20.5));
  EXPECT_FALSE(s.sample(20.5, 20.5));
  // The boundary belongs to the ground, from either side of it.
  EXPECT_EQ(t->height(24.0, 20.5), std::optional<double>(5.0));
  EXPECT_EQ(t->height(17.0, 20.5), std::optional<double>(5.0));
  EXPECT_EQ(t->height(24.01, 20.5), std::optional<double>(5.0));
  EXPECT_EQ(t->height(16.99, 20.5), std::optional<double>(5.0));
  // Batched: NaN inside, the height outside.
  const glm::dvec2 xz[3] = {{20.5, 20.5}, {24.0, 20.5}, {40, 40}};
  double out[3];
  s.heights(xz, out);
  EXPECT_TRUE(std::isnan(out[0]));
  EXPECT_EQ(out[1], 5.0);
  EXPECT_EQ(out[2], 5.0);
  // Filling gives the ground back, as it was.
  auto f = t->apply_edit({.brush = Brush::kFillHole, .x = 20.5, .z = 20.5, .radius = 10});
  ASSERT_TRUE(f);
  EXPECT_EQ(f->cells_changed, cells.size());
  EXPECT_EQ(s.hole_cells(), 0u);
  EXPECT_EQ(t->height(20.5, 20.5), std::optional<double>(5.0));
  // Filling where there is no hole changes nothing: no version.
  auto none = t->apply_edit({.brush = Brush::kFillHole, .x = 20.5, .z = 20.5, .radius = 10});
  ASSERT_TRUE(none);
  EXPECT_TRUE(none->empty());
  EXPECT_EQ(t->edit_version(), v0 + 2);
}

TEST(Holes, RaysPassThroughToTheFarSideAndBoxesHoldNoHoleTriangle) {
  auto t = flat();
  // Without the hole a shallow ray along z = 20.5 lands at x = 20.
  const glm::dvec3 o(10, 6, 20.5), d(1, -0.1, 0);
  auto before = t->raycast(o, d, 100);
  ASSERT_TRUE(before);
  EXPECT_NEAR(before->point.x, 20.0, 1e-9);
  ASSERT_TRUE(t->apply_edit({.brush = Brush::kHole, .x = 20.5, .z = 20.5, .radius = 3}));
  // Through the hole (cells 17..23 of row 20), below the ground, into the far wall at x = 24.
  auto through = t->raycast(o, d, 100);
  ASSERT_TRUE(through);
  EXPECT_NEAR(through->point.x, 24.0, 1e-9);
  EXPECT_NEAR(through->point.y, 6 - 1.4, 1e-9);
  // Straight down the hole: nothing; beside it: the ground.
  EXPECT_FALSE(t->raycast({20.5, 10, 20.5}, {0, -1, 0}, 100));
  auto beside = t->raycast({30.5, 10, 20.5}, {0, -1, 0}, 100);
  ASSERT_TRUE(beside);
  EXPECT_NEAR(beside->distance, 5.0, 1e-9);
  // Steeply down the hole: it stays inside its column and misses.
  EXPECT_FALSE(t->raycast({20.5, 10, 20.5}, {0.01, -1, 0}, 100));
  // A ray starting below the ground inside the hole is not "below the surface".
  auto up = t->raycast({20.5, 4, 20.5}, {0, 1, 0}, 100);
  EXPECT_FALSE(up);
  // Boxes: none of the hole's triangles.
  std::vector<SurfaceTriangle> tris;
  EXPECT_EQ(t->triangles_in_box({{19.2, 0, 19.2}, {21.8, 10, 21.8}}, tris), 0u);
  EXPECT_EQ(t->triangles_in_box({{23.2, 0, 20.2}, {24.8, 10, 20.8}}, tris), 2u);  // cell 24 only
  for (const SurfaceTriangle& st : tris)
    EXPECT_FALSE(t->surface().hole(std::int64_t(std::floor((st.v[0].x + st.v[1].x + st.v[2].x) / 3)),
                                   std::int64_t(std::floor((st.v[0].z + st.v[1].z + st.v[2].z) / 3))));
}

TEST(Holes, TheMeshEndsOnTheHoleAndFillingRestoresIt) {
  auto t = field(129, [](int i, int j) { return 0.02 * i + 0.01 * j + 0.3 * std::sin(i * 0.2); });
  auto l = Landscape::create(t, {.patch_exponent = 4}).value();
  const Camera cam = camera_at({64, 120, -40}, {64, 0, 64});
  auto v = converged_view(l, cam, 0.05);
  const std::uint64_t plain = v->mesh_hash();
  const std::uint32_t plain_triangles = v->triangle_count();
  // Two holes: one inside a patch, one over a patch corner (32, 32) and its seams.
  ASSERT_TRUE(t->apply_edit({.brush = Brush::kHole, .x = 70.3, .z = 50.7, .radius = 6.5}));
  ASSERT_TRUE(t->apply_edit({.brush = Brush::kHole, .x = 32, .z = 32, .radius = 4}));
  ASSERT_TRUE(v->converge(cam));
  ASSERT_EQ(v->check_invariants(), "");
  ASSERT_EQ(check_crack_free(*v), "");
  EXPECT_EQ(check_drawn_over_ground(*v, *t), "");
  EXPECT_NE(v->mesh_hash(), plain);
  // Honest where there is ground: the measured error stays under the threshold.
  EXPECT_LE(v->measure_error(cam).max_m, 0.05 + 1e-5);
  // Updated in place, the view is the one a fresh view over a fresh landscape converges to.
  auto fresh_l = Landscape::create(t, {.patch_exponent = 4}).value();
  auto fresh = converged_view(fresh_l, cam, 0.05);
  EXPECT_EQ(fresh->mesh_hash(), v->mesh_hash());
  EXPECT_EQ(check_drawn_over_ground(*fresh, *t), "");
  // Filled: the mesh it had, exactly.
  ASSERT_TRUE(t->apply_edit({.brush = Brush::kFillHole, .x = 70.3, .z = 50.7, .radius = 6.5}));
  ASSERT_TRUE(t->apply_edit({.brush = Brush::kFillHole, .x = 32, .z = 32, .radius = 4}));
  ASSERT_TRUE(v->converge(cam));
  ASSERT_EQ(v->check_invariants(), "");
  EXPECT_EQ(v->mesh_hash(), plain);
  EXPECT_EQ(v->triangle_count(), plain_triangles);
  EXPECT_EQ(check_drawn_over_ground(*v, *t), "");
}

TEST(Holes, AFlatFieldSplitsOnlyAroundTheHole) {
  auto t = flat(129);
  auto l = Landscape::create(t, {.patch_exponent = 5}).value();
  const Camera cam = camera_at({64, 200, -40}, {64, 0, 64});
  auto v = converged_view(l, cam, 0.01);
  EXPECT_EQ(v->triangle_count(), 2u * l->patch_count());  // flat: the roots
  ASSERT_TRUE(t->apply_edit({.brush = Brush::kHole, .x = 64.5, .z = 64.5, .radius = 0.5}));
  EXPECT_EQ(t->surface().hole_cells(), 1u);
  ASSERT_TRUE(v->converge(cam));
  ASSERT_EQ(v->check_invariants(), "");
  EXPECT_EQ(check_drawn_over_ground(*v, *t), "");
  EXPECT_GT(v->triangle_count(), 2u * l->patch_count());
  // The whole terrain but one cell: a drawn mesh leaves exactly the hole's inner vertices bare
  // (none for a single cell) and has no error.
  const auto e = v->measure_error(cam);
  EXPECT_EQ(e.max_m, 0.0);
  // A hole over a whole patch hides its roots without splitting them.
  ASSERT_TRUE(t->apply_edit({.brush = Brush::kFillHole, .x = 64.5, .z = 64.5, .radius = 1}));
  ASSERT_TRUE(t->apply_edit({.brush = Brush::kHole, .x = 16, .z = 16, .radius = 40}));
  ASSERT_TRUE(v->converge(cam));
  ASSERT_EQ(v->check_invariants(), "");
  EXPECT_EQ(check_drawn_over_ground(*v, *t), "");
  EXPECT_EQ(v->patch_mesh(0).triangles, 0u);
}

TEST(Holes, TheChangeLogReportsAHoleEditLikeAnyOther) {
  auto t = flat();
  const std::uint64_t v0 = t->edit_version();
  ASSERT_TRUE(t->apply_edit({.brush = Brush::kHole, .x = 20.5, .z = 30.5, .radius = 3}));
  const TerrainChanges c = t->changes_since(v0);
  ASSERT_EQ(c.changes.size(), 1u);
  const TerrainChange& ch = c.changes[0];
  EXPECT_EQ(ch.version, v0 + 1);
  // The cells 17..23 x 27..33: the box covers them, the vertices their corners.
  EXPECT_LE(ch.box.min.x, 17.0);
  EXPECT_GE(ch.box.max.x, 24.0);
  EXPECT_LE(ch.box.min.z, 27.0);
  EXPECT_GE(ch.box.max.z, 34.0);
  EXPECT_LE(ch.box.min.y, 5.0);
  EXPECT_GE(ch.box.max.y, 5.0);
  EXPECT_LE(ch.vertices.i0, 17);
  EXPECT_GE(ch.vertices.i1, 24);
  EXPECT_LE(ch.vertices.j0, 27);
  EXPECT_GE(ch.vertices.j1, 34);
}

TEST(Holes, ClonesKeepTheHolesTheyWereTakenWith) {
  auto t = flat();
  ASSERT_TRUE(t->apply_edit({.brush = Brush::kHole, .x = 10.5, .z = 10.5, .radius = 0.5}));
  auto c = t->clone();
  ASSERT_TRUE(t->apply_edit({.brush = Brush::kHole, .x = 40.5, .z = 40.5, .radius = 0.5}));
  ASSERT_TRUE(t->apply_edit({.brush = Brush::kFillHole, .x = 10.5, .z = 10.5, .radius = 0.5}));
  EXPECT_FALSE(c->height(10.5, 10.5));
  EXPECT_TRUE(c->height(40.5, 40.5));
  EXPECT_TRUE(t->height(10.5, 10.5));
  EXPECT_FALSE(t->height(40.5, 40.5));
}

TEST(Holes, EditFileRoundTripUndoAndVersionTwo) {
  auto t = flat();
  const std::string none = save_edits_to_memory(*t);
  ASSERT_TRUE(t->apply_edit({.brush = Brush::kHole, .x = 20.5, .z = 20.5, .radius = 3}));
  ASSERT_TRUE(t->apply_edit({.brush = Brush::kHole, .x = 60, .z = 3, .radius = 2}));  // block edge
  ASSERT_TRUE(t->apply_edit({.brush = Brush::kRaise, .x = 40, .z = 40, .radius = 5, .depth = 2}));
  const std::string saved = save_edits_to_memory(*t);
  const std::uint64_t holes = t->surface().hole_cells();
  auto u = flat();
  auto r = load_edits_from_memory(*u, saved);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->cells_changed, t->surface().hole_cells());
  EXPECT_GT(r->samples_changed, 0u);
  for (int j = 0; j < 64; ++j)
    for (int i = 0; i < 64; ++i) ASSERT_EQ(u->surface().hole(i, j), t->surface().hole(i, j));
  EXPECT_EQ(u->surface().heights_hash(), t->surface().heights_hash());
  EXPECT_EQ(save_edits_to_memory(*u), saved);
  // Loading the save made before the holes is an undo.
  ASSERT_TRUE(load_edits_from_memory(*u, none));
  EXPECT_EQ(u->surface().hole_cells(), 0u);
  EXPECT_TRUE(u->height(20.5, 20.5));
  // A version 2 file (no holes) still loads.
  std::string v2 = none;
  const std::uint32_t two = 2;
  std::memcpy(v2.data() + 8, &two, 4);
  std::uint64_t h = 1469598103934665603ull;
  for (std::size_t k = 0; k + 8 < v2.size(); ++k) {
    h ^= static_cast<unsigned char>(v2[k]);
    h *= 1099511628211ull;
  }
  std::memcpy(v2.data() + v2.size() - 8, &h, 8);
  ASSERT_TRUE(load_edits_from_memory(*t, v2)) << "version 2";
  EXPECT_EQ(t->surface().hole_cells(), 0u);
  // A hole block past the terrain's cells, or a cut hole section, is refused and changes nothing.
  ASSERT_TRUE(load_edits_from_memory(*u, saved));
  std::string bad = saved;
  bad.resize(bad.size() - 9);
  EXPECT_FALSE(load_edits_from_memory(*u, bad));
  EXPECT_EQ(u->surface().hole_cells(), holes);
}

TEST(Holes, EditFileHoleBlocksAreChecked) {
  // 50 x 50 samples: 49 cells a side, 2 x 2 blocks of 32 x 32 cells, the last ones partly past.
  auto t = field(50, [](int, int) { return 1.0; });
  ASSERT_TRUE(t->apply_edit({.brush = Brush::kHole, .x = 40.5, .z = 40.5, .radius = 2}));
  const std::string bytes = save_edits_to_memory(*t);
  ASSERT_EQ(bytes.size(), 64 + (8 + 128) + 8);  // no height chunk, one hole block
  auto reseal = [](std::string b) {
    std::uint64_t h = 1469598103934665603ull;
    for (std::size_t k = 0; k + 8 < b.size(); ++k) h = (h ^ static_cast<unsigned char>(b[k])) * 1099511628211ull;
    std::memcpy(b.data() + b.size() - 8, &h, 8);
    return b;
  };
  auto target = field(50, [](int, int) { return 1.0; });
  auto refused = [&](const std::string& b, const std::string& why) {
    auto r = load_edits_from_memory(*target, b);
    ASSERT_FALSE(r) << why;
    EXPECT_NE(r.error().message.find(why), std::string::npos) << r.error().message;
    EXPECT_EQ(target->surface().hole_cells(), 0u);
    EXPECT_EQ(target->edit_version(), 0u);
  };
  std::string c = bytes;
  c[64] = 2;  // block x 2: past the 2 x 2 blocks
  refused(reseal(c), "lies outside the terrain");
  c = bytes;
  c[64 + 8 + 3] = char(c[64 + 8 + 3] | (1 << 4));  // bit 28 of block (1, 1): cell (60, 32)
  refused(reseal(c), "past the terrain's cells");
  c = bytes;
  c[72] ^= 1;
  refused(c, "checksum mismatch");
  ASSERT_TRUE(load_edits_from_memory(*target, bytes));
  EXPECT_EQ(target->surface().hole_cells(), t->surface().hole_cells());
  EXPECT_FALSE(target->height(40.5, 40.5));
}

TEST(Holes, ANoDataValueMakesHolesAtLoadWithFiniteHeights) {
  // 5 x 4 samples, the no-data value -9999 at samples (2, 1) and (4, 3).
  std::vector<float> v(20, 7.0f);
  v[2 + 1 * 5] = -9999;
  v[4 + 3 * 5] = -9999;
  HeightfieldDesc d{.width = 5, .height = 4, .nodata = -9999.0, .fill = FillPolicy::kHole};
  auto hf = Heightfield::create(d, v);
  ASSERT_TRUE(hf) << hf.error().message;
  EXPECT_EQ(hf->filled_samples(), 2u);
  EXPECT_EQ(hf->local(2, 1), 7.0f) << "the nearest valid height: bounds stay finite";
  // Cells with a missing corner: (1, 0), (2, 0), (1, 1), (2, 1) around (2, 1); (3, 2) at (4, 3).
  const std::vector<std::uint64_t> want = {1, 2, 5, 6, 11};
  EXPECT_EQ(std::vector<std::uint64_t>(hf->hole_cells().begin(), hf->hole_cells().end()), want);
  auto t = Terrain::create(std::move(*hf)).value();
  EXPECT_EQ(t->edit_version(), 0u) << "part of the terrain as made, not an edit";
  EXPECT_EQ(t->surface().hole_cells(), 5u);
  EXPECT_FALSE(t->height(2.0, 1.0));
  EXPECT_FALSE(t->height(3.5, 2.5));
  EXPECT_EQ(t->height(0.5, 0.5), std::optional<double>(7.0));
  EXPECT_EQ(t->height(1.0, 2.0), std::optional<double>(7.0)) << "the holes' edge is ground";
  // Filled, the ground shows the filled height; the refuse policy still refuses.
  ASSERT_TRUE(t->apply_edit({.brush = Brush::kFillHole, .x = 2, .z = 1, .radius = 2}));
  EXPECT_EQ(t->height(2.0, 1.0), std::optional<double>(7.0));
  d.fill = FillPolicy::kRefuse;
  EXPECT_FALSE(Heightfield::create(d, v));
}

TEST(Holes, WithProceduralDetailEveryFinestCellOfAHoleIsNoGround) {
  auto hf = scenes::field({.width = 65, .height = 65},
                          [](int i, int j) { return 3.0 + 0.05 * i + 0.5 * std::sin(j * 0.3); });
  DetailParams dp;
  dp.levels = 2;
  dp.amplitude = 0.4;
  dp.seed = 3;
  auto t = Terrain::create(std::move(hf).value(), dp, {}).value();
  const double inside = *t->height(20.6, 30.3);  // a detail point of cell (20, 30)
  EXPECT_TRUE(std::isfinite(inside));
  ASSERT_TRUE(t->apply_edit({.brush = Brush::kHole, .x = 20.5, .z = 30.5, .radius = 1.2}));
  EXPECT_FALSE(t->height(20.6, 30.3));
  EXPECT_FALSE(t->height(20.25, 30.75)) << "a finest-lattice vertex inside the hole cell";
  EXPECT_TRUE(t->height(22.25, 30.5)) << "two cells away";
  EXPECT_FALSE(t->raycast({20.6, 50, 30.3}, {0, -1, 0}, 100));
  auto l = Landscape::create(t, {.patch_exponent = 4}).value();
  const Camera cam = camera_at({32, 60, -20}, {32, 0, 32});
  auto v = converged_view(l, cam, 0.05);
  ASSERT_EQ(v->check_invariants(), "");
  ASSERT_EQ(check_crack_free(*v), "");
  EXPECT_EQ(check_drawn_over_ground(*v, *t), "");
  ASSERT_TRUE(t->apply_edit({.brush = Brush::kFillHole, .x = 20.5, .z = 30.5, .radius = 1.2}));
  EXPECT_EQ(t->height(20.6, 30.3), std::optional<double>(inside));
  ASSERT_TRUE(v->converge(cam));
  ASSERT_EQ(v->check_invariants(), "");
  EXPECT_EQ(check_drawn_over_ground(*v, *t), "");
}
