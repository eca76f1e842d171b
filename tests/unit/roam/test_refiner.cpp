// The refiner's splits and merges (roam/view/refiner.cpp): crack-free along a random walk through
// every kind of update, and a mesh that ends exactly on the border of the sampled data.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "ridgeline/roam_view.h"
#include "roam_landscapes.h"

using namespace ridgeline;
using namespace ridgeline::test;

TEST(Roam, CrackFreeAlongARandomWalkWithChangingThresholdsAndBudgets) {
  auto l = make_landscape(257, 5);
  auto view = RoamView::create(l).value();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(0, 1);
  glm::dvec3 eye(100, 200, 100);
  double yaw = 0.6;
  for (int frame = 0; frame < 150; ++frame) {
    eye += glm::dvec3(std::cos(yaw), 0, std::sin(yaw)) * (U(rng) * 20.0);
    eye.x = std::clamp(eye.x, -100.0, 612.0);
    eye.z = std::clamp(eye.z, -100.0, 612.0);
    eye.y = 80 + 200 * U(rng);
    yaw += (U(rng) - 0.5) * (frame % 37 == 0 ? 6.0 : 0.4);
    const Camera c =
        camera_at(eye, eye + glm::dvec3(std::cos(yaw), -0.4, std::sin(yaw)), 40 + 50 * U(rng));
    RoamSettings s = view->settings();
    if (frame % 10 == 0) s.threshold = 0.5 + 8 * U(rng);
    if (frame % 25 == 5) s.max_triangles = frame % 50 == 5 ? 3000 : 0;
    if (frame % 30 == 7) s.budget_ms = frame % 60 == 7 ? 0.2 : 0.0;
    ASSERT_TRUE(view->set_settings(s));
    auto st = view->update(c);
    ASSERT_TRUE(st);
    ASSERT_EQ(view->check_invariants(), "") << "frame " << frame;
    ASSERT_EQ(check_crack_free(*view), "") << "frame " << frame;
    if (s.max_triangles) {
      EXPECT_LE(st->triangles, s.max_triangles);
    }
  }
}

// On a field whose size is not 2^k + 1 (and not square) the drawn mesh covers exactly the data:
// no vertex beyond the last sample, and the drawn triangles' areas add up to the data's area, so
// there is neither a gap nor an overhang; at a fine threshold and at the coarsest tolerance.
TEST(Roam, MeshEndsExactlyOnTheDataBorder) {
  auto l = make_padded_landscape(4);
  const double w = (kPaddedW - 1) * 2.0, hz = (kPaddedH - 1) * 2.0;
  // At a fine threshold, at the coarsest tolerance, and under a triangle cap far below what the
  // threshold asks for (the border's splits are forced: they go past the cap, as crack fixes do).
  const std::uint32_t roots = l->root_count();
  for (const RoamSettings& s :
       {RoamSettings{.threshold = 1.0},
        RoamSettings{.metric = ErrorMetric::kWorldMetres, .threshold = 1000.0},
        RoamSettings{.threshold = 1.0, .max_triangles = roots},
        RoamSettings{.threshold = 0.0, .max_triangles = roots + 40}}) {
    auto view = RoamView::create(l, s).value();
    ASSERT_TRUE(view->converge(camera_at({-20, 60, -30}, {80, 0, 60})));
    double area = 0;
    for (std::uint32_t p = 0; p < l->patch_count(); ++p) {
      const PatchMesh& m = view->patch_mesh(p);
      for (std::size_t k = 0; k + 2 < m.indices.size(); k += 3) {
        if (m.indices[k] == m.indices[k + 1]) continue;  // an unused or padding slot
        const MeshVertex* v[3] = {&m.vertices[m.indices[k]], &m.vertices[m.indices[k + 1]],
                                  &m.vertices[m.indices[k + 2]]};
        for (const MeshVertex* x : v) {
          EXPECT_LE(m.origin_x + x->x, w + 1e-4) << "overhang past the last column";
          EXPECT_LE(m.origin_z + x->z, hz + 1e-4) << "overhang past the last row";
        }
        area += 0.5 * (double(v[1]->z - v[0]->z) * (v[2]->x - v[0]->x) -
                       double(v[1]->x - v[0]->x) * (v[2]->z - v[0]->z));
      }
    }
    EXPECT_NEAR(area, w * hz, 1e-6 * w * hz)
        << "threshold " << s.threshold << " cap " << s.max_triangles;
    EXPECT_EQ(check_crack_free(*view), "");
    EXPECT_EQ(view->check_invariants(), "");
  }
}
