// The view's walks (roam/view/mesh_walk.cpp): the measured error against the bounds and the
// threshold, and the mesh hash pinned for fixed inputs.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <utility>

#include "ridgeline/roam_view.h"
#include "roam_landscapes.h"

using namespace ridgeline;
using namespace ridgeline::test;

TEST(Roam, MeasuredErrorNeverExceedsTheBound) {
  auto l = make_landscape(129, 5);
  auto view = RoamView::create(l, {.metric = ErrorMetric::kWorldMetres, .threshold = 1.5}).value();
  ASSERT_TRUE(view->update(Camera{}));
  const Heightfield hf = l->terrain().surface().to_heightfield().value();
  double worst = 0;
  view->for_each_leaf([&](std::uint32_t root, std::uint64_t heap, const LatticeTriangle& t) {
    // Measure: every lattice vertex under the triangle against the triangle's plane.
    const double b = l->bound(root, heap);
    const std::int64_t i0 = std::min({t.ax, t.lx, t.rx}), i1 = std::max({t.ax, t.lx, t.rx});
    const std::int64_t j0 = std::min({t.az, t.lz, t.rz}), j1 = std::max({t.az, t.lz, t.rz});
    const double w = double((t.lx - t.ax) * (t.rz - t.az) - (t.lz - t.az) * (t.rx - t.ax));
    for (std::int64_t j = j0; j <= j1; ++j)
      for (std::int64_t i = i0; i <= i1; ++i) {
        const double wr = double((t.lx - t.ax) * (j - t.az) - (t.lz - t.az) * (i - t.ax)) / w;
        const double wa = double((t.rx - t.lx) * (j - t.lz) - (t.rz - t.lz) * (i - t.lx)) / w;
        const double wl = 1 - wr - wa;
        if (wr < -1e-12 || wa < -1e-12 || wl < -1e-12) continue;
        if (i >= hf.width() || j >= hf.height()) continue;
        const double plane = wa * test::lattice_height(*l, t.ax, t.az) +
                             wl * test::lattice_height(*l, t.lx, t.lz) +
                             wr * test::lattice_height(*l, t.rx, t.rz);
        const double err = std::abs(plane - hf.local(std::uint32_t(i), std::uint32_t(j)));
        EXPECT_LE(err, b + 1e-4);
        EXPECT_LE(err, 1.5 + 1e-4);
        worst = std::max(worst, err);
      }
  });
  EXPECT_GT(worst, 0.1);  // the test saw real error
}

TEST(Roam, MeasuredErrorAgreesWithTheBoundsAndTheThreshold) {
  auto l = make_landscape(257, 5);
  auto view = RoamView::create(l, {.threshold = 2.0}).value();
  const Camera c = camera_at({20, 120, 30}, {300, 60, 260});
  ASSERT_TRUE(view->update(c));
  const auto e = view->measure_error(c);
  EXPECT_GT(e.vertices, 10000u);
  EXPECT_GT(e.max_m, 0.0);
  EXPECT_LE(e.rms_m, e.max_m);
  // Converged: the measured screen error at each vertex is at most the threshold, since each
  // vertex is at least as far as its leaf's bounding box and under its leaf's bound.
  EXPECT_LE(e.max_px, 2.0 * (1 + 1e-6));
  // A stratified sample sees fewer vertices and no larger error.
  const auto s = view->measure_error(c, 4);
  EXPECT_LT(s.vertices, e.vertices / 8);
  EXPECT_LE(s.max_m, e.max_m);
  // World-metre mode: every vertex, error within the tolerance.
  auto w = RoamView::create(l, {.metric = ErrorMetric::kWorldMetres, .threshold = 3.0}).value();
  ASSERT_TRUE(w->update(Camera{}));
  const auto we = w->measure_error(Camera{});
  EXPECT_EQ(we.vertices, 257u * 257u);
  EXPECT_LE(we.max_m, 3.0);
  EXPECT_GT(we.max_m, 1.0);
}

// The mesh of a fixed terrain, camera path and setting is pinned to a value, not only compared
// between two runs in one process: a change anywhere in the bounds, the front's test or the
// refinement that moves a single triangle shows here. One value per path an unbudgeted update
// can take: converged at a threshold along a flight, the tolerance mode, and the threshold search
// of a triangle cap (time budgets depend on the clock). The same values with g++ 12 and clang 14,
// with and without the AVX2 pass (RIDGELINE_PORTABLE): the inputs are integers and floats whose
// operations are written out in a fixed order, with no fused multiply-adds (docs/roam.md).
TEST(Roam, DeterministicMeshHash) {
  auto l = make_landscape(257, 5);
  auto fly = [&](const RoamSettings& s) {
    auto view = RoamView::create(l, s).value();
    Camera c = camera_at({10, 150, 10}, {200, 50, 200});
    for (int k = 0; k < 30; ++k) {
      c.eye += glm::dvec3(5, 0.5, 2);
      c.target += glm::dvec3(3, 0, 6);
      EXPECT_TRUE(view->update(c));
    }
    EXPECT_EQ(view->check_invariants(), "");
    std::printf("%u triangles, hash 0x%016llx\n", view->triangle_count(),
                static_cast<unsigned long long>(view->mesh_hash()));
    return std::pair{view->triangle_count(), view->mesh_hash()};
  };
  const auto flight = fly({.threshold = 2.0});
  EXPECT_EQ(flight, std::pair(30653u, std::uint64_t{0x62168e72bba063d1}));
  const auto tolerance = fly({.metric = ErrorMetric::kWorldMetres, .threshold = 0.5});
  EXPECT_EQ(tolerance, std::pair(99826u, std::uint64_t{0x095ca8e3844bd328}));
  const auto capped = fly({.threshold = 0.0, .max_triangles = 6000});
  EXPECT_EQ(capped, std::pair(5995u, std::uint64_t{0xb0f840cb37742860}));
  // A second run in the same process (whose memory may be reused) gives the same mesh.
  EXPECT_EQ(fly({.threshold = 2.0}), flight);
}
