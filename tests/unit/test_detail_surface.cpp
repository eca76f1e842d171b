// Procedural detail as part of the surface: queries on the finest lattice (with and without cached
// tiles, across tile seams and the stored-to-detail boundary), ROAM refining below the stored
// resolution with honest bounds and no cracks, splits that wait for tiles, edits and save files.
#include <gtest/gtest.h>

#include <cmath>
#include <glm/geometric.hpp>
#include <random>

#include "ridgeline/detail.h"
#include "ridgeline/edit.h"
#include "ridgeline/roam_view.h"
#include "roam_test_util.h"

using namespace ridgeline;
using namespace ridgeline::test;

namespace {

DetailParams params(std::uint32_t levels, std::uint64_t seed = 5) {
  DetailParams p;
  p.levels = levels;
  p.seed = seed;
  p.amplitude = 1.5;
  return p;
}

std::shared_ptr<Terrain> detail_terrain(std::uint32_t size, std::uint32_t levels,
                                        std::uint32_t workers = 0, std::uint64_t seed = 5) {
  auto hf = make_default_heightfield({.size = size, .spacing = 4.0, .seed = 21});
  DetailCacheDesc cache;
  cache.budget_bytes = std::size_t{64} << 20;
  cache.worker_threads = workers;
  auto t = Terrain::create(std::move(hf).value(), params(levels, seed), cache);
  EXPECT_TRUE(t) << (t ? "" : t.error().message);
  return t.value();
}

}  // namespace

TEST(DetailSurface, QueriesInterpolateTheFinestLattice) {
  auto t = detail_terrain(65, 3);
  ASSERT_EQ(t->surface().detail_levels(), 3u);
  EXPECT_EQ(t->surface().lattice().vertices_x, 64 * 8 + 1);
  const double fs = 4.0 / 8;  // finest spacing
  // At finest vertices the height is the lattice height; at stored vertices the detail is 0.
  for (std::int64_t j = 0; j < t->surface().lattice().vertices_z; j += 37)
    for (std::int64_t i = 0; i < t->surface().lattice().vertices_x; i += 29) {
      EXPECT_NEAR(*t->height(i * fs, j * fs), t->surface().vertex_height(i, j), 1e-9);
      if (i % 8 == 0 && j % 8 == 0) {
        EXPECT_EQ(t->surface().vertex_detail(i, j), 0.0);
        EXPECT_NEAR(t->surface().vertex_height(i, j), t->surface().stored_height(i / 8, j / 8), 1e-5);
      }
    }
  // Detail is really there: some finest vertex differs from the stored interpolation.
  double largest = 0;
  for (std::int64_t i = 1; i < 400; i += 2)
    largest = std::max(largest, std::abs(t->surface().vertex_detail(i, 77)));
  EXPECT_GT(largest, 0.01);
  // Inside a finest triangle the height is the barycentric blend of its corners: at the centre
  // of a cell's edge midpoint between two vertices, the mean.
  EXPECT_NEAR(*t->height(10 * fs + 0.25 * fs, 20 * fs),
              0.75 * t->surface().vertex_height(10, 20) + 0.25 * t->surface().vertex_height(11, 20), 1e-9);
  // Face normal is the finest triangle's; off-terrain and NaN give nothing.
  auto n = t->face_normal(33.3, 47.1);
  ASSERT_TRUE(n);
  EXPECT_NEAR(glm::length(*n), 1.0f, 1e-6f);
  EXPECT_FALSE(t->height(-1, 5));
  EXPECT_FALSE(t->height(NAN, 5));
  EXPECT_FALSE(t->height(256.001, 5));
}

TEST(DetailSurface, CachedTilesAndDirectEvaluationGiveTheSameSurface) {
  auto a = detail_terrain(65, 4);  // nothing cached: direct evaluation
  auto b = detail_terrain(65, 4);
  // Fill b's cache with every tile of every level (synchronous cache: request() generates).
  for (std::uint32_t l = 1; l <= 4; ++l) {
    const std::int32_t n = std::int32_t((64 << l) / kDetailTileCells) + 1;
    for (std::int32_t tz = 0; tz < n; ++tz)
      for (std::int32_t tx = 0; tx < n; ++tx) ASSERT_TRUE(b->surface().detail_cache()->request({l, tx, tz}));
  }
  ASSERT_GT(b->surface().detail_cache()->stats().resident_tiles, 10u);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 256);
  for (int k = 0; k < 2000; ++k) {
    const double x = u(rng), z = u(rng);
    ASSERT_EQ(*a->height(x, z), *b->height(x, z)) << x << ", " << z;
  }
}

TEST(DetailSurface, ContinuousAcrossTileSeamsAndTheStoredBoundary) {
  auto t = detail_terrain(129, 4);
  // Level-4 tiles span 128 finest cells = 32 m here; walk across several seams in tiny steps.
  const double dx = 1e-3;
  double prev = *t->height(20.0, 70.3);
  double worst = 0;
  for (double x = 20.0 + dx; x < 140.0; x += dx) {
    const double h = *t->height(x, 70.3);
    worst = std::max(worst, std::abs(h - prev));
    prev = h;
  }
  // A continuous piecewise-linear surface moves by at most its steepest slope times the step.
  EXPECT_LT(worst, 50 * dx);
}

namespace {

// Every node of a few roots down to the finest level: |surface - plane| over every finest vertex
// of its triangle stays within the bound, and bounds are nested. Returns how many nodes had a
// bound below the analytic one (measured bounds in use).
int check_bounds_against_brute_force(const Terrain& terrain, const Landscape& landscape) {
  const Landscape* l = &landscape;
  int tighter = 0;
  const DetailField& field = *terrain.surface().detail();
  EXPECT_EQ(l->max_level(), 2u * (3 + 3));
  // Every node of a few roots down to the finest level: |surface - plane| over every finest
  // vertex of its triangle stays within the bound, and bounds are nested.
  std::mt19937 rng(1);
  for (std::uint32_t root : {0u, 5u, l->root_count() - 1}) {
    std::vector<std::pair<std::uint64_t, LatticeTriangle>> stack{{1, l->triangle(root, 1)}};
    std::size_t checked = 0;
    while (!stack.empty()) {
      auto [heap, tri] = stack.back();
      stack.pop_back();
      const float b = l->bound(root, heap);
      const int level = 63 - __builtin_clzll(heap);
      // Exact error against the finest lattice.
      const double ha = lattice_height(*l, tri.ax, tri.az), hl = lattice_height(*l, tri.lx, tri.lz),
                   hr = lattice_height(*l, tri.rx, tri.rz);
      const std::int64_t x0 = std::min({tri.ax, tri.lx, tri.rx}),
                         x1 = std::max({tri.ax, tri.lx, tri.rx});
      const std::int64_t z0 = std::min({tri.az, tri.lz, tri.rz}),
                         z1 = std::max({tri.az, tri.lz, tri.rz});
      const double w =
          double((tri.lx - tri.ax) * (tri.rz - tri.az) - (tri.lz - tri.az) * (tri.rx - tri.ax));
      double worst = 0;
      for (std::int64_t z = z0; z <= z1; ++z)
        for (std::int64_t x = x0; x <= x1; ++x) {
          const double wr =
              double((tri.lx - tri.ax) * (z - tri.az) - (tri.lz - tri.az) * (x - tri.ax)) / w;
          const double wa =
              double((tri.rx - tri.lx) * (z - tri.lz) - (tri.rz - tri.lz) * (x - tri.lx)) / w;
          const double wl = 1 - wa - wr;
          if (wa < -1e-12 || wr < -1e-12 || wl < -1e-12) continue;
          worst =
              std::max(worst, std::abs(lattice_height(*l, x, z) - (wa * ha + wl * hl + wr * hr)));
        }
      EXPECT_LE(worst, double(b) + 1e-4) << "root " << root << " level " << level;
      if (worst > double(b) + 1e-4) return -1;
      if (level >= int(l->base_level())) {
        const int from = (level - int(l->base_level())) / 2 + 1;
        const double analytic =
            2.0 * field.contribution_bound(std::uint32_t(from), l->detail_levels(), x0, z0, x1, z1);
        tighter += double(b) < analytic * 0.999;
      }
      ++checked;
      if (std::uint32_t(level) < l->max_level()) {
        // Descend fully near the top, then along one random child (keeps the test short).
        const int c = int(rng() & 1);
        for (int k = 0; k < 2; ++k) {
          if (level >= 4 && k != c) continue;
          const LatticeTriangle ct = Landscape::child_triangle(tri, k);
          EXPECT_LE(l->bound(root, 2 * heap + k), b) << "nested";
          stack.push_back({2 * heap + k, ct});
        }
      }
    }
    EXPECT_GT(checked, 20u);
  }
  return tighter;
}

}  // namespace

TEST(DetailSurface, BoundsHoldBelowTheStoredLevels) {
  auto t = detail_terrain(33, 3);
  auto l = Landscape::create(t, {.patch_exponent = 3}).value();
  EXPECT_EQ(check_bounds_against_brute_force(*t, *l), 0) << "no tile resident: analytic only";
}

TEST(DetailSurface, MeasuredBoundsFromResidentTilesHoldAndAreTighter) {
  auto t = detail_terrain(33, 3);
  // Every finest tile resident (synchronous cache): nodes inside one take its measured bound.
  const std::int32_t n = std::int32_t((32 << 3) / kDetailTileCells) + 1;
  for (std::int32_t tz = 0; tz < n; ++tz)
    for (std::int32_t tx = 0; tx < n; ++tx) ASSERT_TRUE(t->surface().detail_cache()->request({3, tx, tz}));
  auto l = Landscape::create(t, {.patch_exponent = 3}).value();
  EXPECT_GT(check_bounds_against_brute_force(*t, *l), 20);
}

TEST(DetailSurface, RoamRefinesBelowTheStoredSpacingNearTheCamera) {
  auto t = detail_terrain(129, 3);
  auto l = Landscape::create(t, {.patch_exponent = 5}).value();
  auto v = RoamView::create(l, {.threshold = 1.0}).value();
  const double y = *t->height(256, 256) + 6;
  const Camera cam = camera_at({256, y, 240}, {256, y - 8, 300});
  auto st = v->converge(cam);
  ASSERT_TRUE(st);
  EXPECT_EQ(st->pending_splits, 0u);  // synchronous cache: tiles arrive at once
  ASSERT_EQ(v->check_invariants(), "");
  ASSERT_EQ(check_crack_free(*v), "");
  int below = 0;
  v->for_each_leaf([&](std::uint32_t, std::uint64_t heap, const LatticeTriangle&) {
    below += (63 - __builtin_clzll(heap)) > int(l->base_level());
  });
  EXPECT_GT(below, 100) << "triangles smaller than the stored spacing near the camera";
  // Converged: the measured screen error stays within the threshold (sampled finest lattice).
  const auto err = v->measure_error(cam, 3);
  EXPECT_GT(err.vertices, 10000u);
  EXPECT_LE(err.max_px, 1.0 + 1e-3);
  // The mesh is the surface the queries see: every vertex height equals height() there.
  const std::size_t checked = expect_mesh_on_surface(*v, *t, 5, 1e-3);
  EXPECT_GT(checked, 1000u);
}

TEST(DetailSurface, SplitsWaitForTilesWithoutBlocking) {
  auto t = detail_terrain(129, 4, /*workers=*/1);
  auto l = Landscape::create(t, {.patch_exponent = 5}).value();
  auto v = RoamView::create(l, {.threshold = 1.0}).value();
  const double y = *t->height(256, 256) + 5;
  const Camera cam = camera_at({256, y, 240}, {256, y - 8, 300});
  auto first = v->update(cam);
  ASSERT_TRUE(first);
  EXPECT_GT(first->pending_splits, 0u) << "tiles were requested, not waited for";
  ASSERT_EQ(v->check_invariants(), "");
  // Frames go on; the tiles arrive on the worker and the mesh refines.
  std::uint32_t pending = first->pending_splits;
  for (int frame = 0; frame < 400 && pending > 0; ++frame) {
    t->surface().detail_cache()->wait_idle(5.0);
    auto st = v->update(cam);
    ASSERT_TRUE(st);
    pending = st->pending_splits;
    ASSERT_EQ(v->check_invariants(), "");
  }
  EXPECT_EQ(pending, 0u);
  EXPECT_LE(v->measure_error(cam, 3).max_px, 1.0 + 1e-3);
}

TEST(DetailSurface, EditsAndSaveFilesWithDetail) {
  auto t = detail_terrain(65, 2);
  auto l = Landscape::create(t, {.patch_exponent = 4}).value();
  auto v = RoamView::create(l, {.metric = ErrorMetric::kWorldMetres, .threshold = 0.3}).value();
  const Camera cam = camera_at({128, 300, -50}, {128, 0, 128});
  ASSERT_TRUE(v->converge(cam));
  const double d0 = t->surface().vertex_detail(101, 77);
  ASSERT_TRUE(t->apply_edit({.x = 100, .z = 80, .radius = 20, .depth = 6}));
  EXPECT_EQ(t->surface().vertex_detail(101, 77), d0) << "detail rides on top of edits";
  ASSERT_TRUE(v->converge(cam));
  ASSERT_EQ(v->check_invariants(), "");
  ASSERT_EQ(check_crack_free(*v), "");
  EXPECT_LE(v->measure_error(cam, 1).max_m, 0.3 + 1e-4);
  const std::string saved = save_edits_to_memory(*t);
  auto same = detail_terrain(65, 2);
  ASSERT_TRUE(load_edits_from_memory(*same, saved));
  EXPECT_EQ(*same->height(100, 80), *t->height(100, 80));
  auto other_seed = detail_terrain(65, 2, 0, /*seed=*/6);
  auto r = load_edits_from_memory(*other_seed, saved);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("detail"), std::string::npos) << r.error().message;
}

TEST(DetailSurface, RaysHitTheFinestSurface) {
  auto t = detail_terrain(65, 3);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(5, 250), a(0, 2 * M_PI), e(0.05, 0.6);
  int hits = 0;
  for (int k = 0; k < 300; ++k) {
    const double x = u(rng), z = u(rng);
    // Vertical: the hit is the height there.
    auto v = t->raycast({x, 1000, z}, {0, -1, 0}, 5000);
    ASSERT_TRUE(v);
    EXPECT_NEAR(v->point.y, *t->height(x, z), 2e-5);  // height() blends with float weights
    // Slanted, grazing-ish: the hit lies on the surface and no earlier sample of the ray is
    // below it.
    const double az = a(rng), el = e(rng);
    const glm::dvec3 dir(std::cos(az) * std::cos(el), -std::sin(el), std::sin(az) * std::cos(el));
    const glm::dvec3 o(x, *t->height(x, z) + 3.0, z);
    auto h = t->raycast(o, dir, 400);
    if (!h) continue;
    ++hits;
    ASSERT_FALSE(h->started_below);
    auto at = t->height(h->point.x, h->point.z);
    ASSERT_TRUE(at);
    EXPECT_NEAR(h->point.y, *at, 2e-5);
    for (double s = 0; s < h->distance - 1e-3; s += 0.02) {
      const glm::dvec3 p = o + dir * s;
      if (auto hp = t->height(p.x, p.z)) {
        ASSERT_GT(p.y - *hp, -2e-5) << "ray " << k << " at " << s;
      }
    }
    // The normal is the finest triangle's.
    auto n = t->face_normal(h->point.x, h->point.z);
    EXPECT_GT(glm::dot(glm::dvec3(*n), glm::dvec3(h->normal)), 0.999);
  }
  EXPECT_GT(hits, 100);
  // Starting below the surface.
  auto below = t->raycast({100, *t->height(100, 100) - 0.01, 100}, {1, 0, 0}, 10);
  ASSERT_TRUE(below);
  EXPECT_TRUE(below->started_below);
}

TEST(DetailSurface, BoxQueryReturnsFinestTriangles) {
  auto t = detail_terrain(65, 2);  // finest spacing 1 m
  std::vector<SurfaceTriangle> tris;
  // A box strictly inside cells [10, 19] x [20, 24] of the finest lattice, spanning all heights.
  const Box box{{10.5, -1e4, 20.5}, {19.5, 1e4, 24.5}};
  const std::size_t n = t->triangles_in_box(box, tris);
  EXPECT_EQ(n, 2u * 10 * 5);
  for (const SurfaceTriangle& s : tris)
    for (const glm::dvec3& v : s.v) EXPECT_NEAR(v.y, *t->height(v.x, v.z), 2e-5);
  // A height range above everything: nothing.
  tris.clear();
  EXPECT_EQ(t->triangles_in_box({{10.5, 1e4, 20.5}, {19.5, 2e4, 24.5}}, tris), 0u);
  EXPECT_EQ(t->triangles_in_box({{10.5, -1e4, 20.5}, {19.5, 1e4, 24.5}}, tris, 7), 7u);
}

// A view that refined while its tiles streamed in ends with the mesh of a view created after
// every tile was resident: the diamonds created with analytic bounds take the measured ones when
// their tile arrives (RoamStats::rebounded), so no triangle is kept for a bound that is gone.
TEST(DetailSurface, TilesArrivingLaterTightenTheBounds) {
  auto hf = make_default_heightfield({.size = 129, .spacing = 4.0, .seed = 21});
  DetailParams p = params(3);
  p.amplitude = 0.4;  // ~0.1 x the stored spacing
  DetailCacheDesc cache;
  cache.budget_bytes = std::size_t{256} << 20;
  cache.worker_threads = 1;
  auto t = Terrain::create(std::move(hf).value(), p, cache).value();
  auto l = Landscape::create(t, {.patch_exponent = 5}).value();
  auto streamed = RoamView::create(l, {.threshold = 2.0}).value();
  const double y = *t->height(256, 256) + 12;
  const Camera cam = camera_at({256, y, 200}, {256, y - 10, 320});
  std::uint32_t rebounded = 0;
  RoamStats st{};
  for (int frame = 0; frame < 600; ++frame) {
    t->surface().detail_cache()->wait_idle(5.0);
    auto s = streamed->update(cam);
    ASSERT_TRUE(s);
    st = *s;
    rebounded += st.rebounded;
    if (frame > 3 && st.pending_splits == 0 && st.splits + st.merges + st.forced_splits == 0) break;
  }
  ASSERT_EQ(st.pending_splits, 0u);
  EXPECT_GT(rebounded, 0u) << "tiles arrived after their diamonds were created";
  auto fresh = RoamView::create(l, {.threshold = 2.0}).value();
  auto f = fresh->converge(cam);
  ASSERT_TRUE(f);
  EXPECT_EQ(f->pending_splits, 0u);
  std::printf("streamed %u triangles, fresh with every tile resident %u (rebounded %u)\n",
              st.triangles, f->triangles, rebounded);
  EXPECT_LE(double(st.triangles), 1.05 * f->triangles);
  EXPECT_EQ(streamed->check_invariants(), "");
  EXPECT_EQ(check_crack_free(*streamed), "");
}
