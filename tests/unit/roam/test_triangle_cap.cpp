// Updates under a triangle cap (roam/view/triangle_cap.cpp, and the queues of a cap's first
// update): a hard cap, used and not wasted, followed at one threshold.
#include <gtest/gtest.h>

#include <cmath>

#include "ridgeline/roam_view.h"
#include "roam_landscapes.h"

using namespace ridgeline;
using namespace ridgeline::test;

TEST(Roam, TriangleBudgetIsAHardCap) {
  auto l = make_landscape(257, 5);
  auto view = RoamView::create(l, {.threshold = 0.1, .max_triangles = 5000}).value();
  const Camera c = camera_at({20, 120, 30}, {300, 60, 260});
  auto st = view->update(c);
  ASSERT_TRUE(st);
  EXPECT_EQ(st->stop, StopReason::kTriangleBudget);
  EXPECT_LE(st->triangles, 5000u);
  EXPECT_GT(st->triangles, 4900u);  // the budget is used, not wasted
  EXPECT_EQ(check_crack_free(*view), "");
  // Lower the cap: the mesh merges down to it.
  RoamSettings s = view->settings();
  s.max_triangles = 2000;
  ASSERT_TRUE(view->set_settings(s));
  st = view->update(c);
  ASSERT_TRUE(st);
  EXPECT_LE(st->triangles, 2000u);
  EXPECT_EQ(check_crack_free(*view), "");
}

// Under a cap alone the view follows a moving camera at the threshold that fills the cap: every
// update fits the cap and uses most of it, and its mesh is exactly the converged mesh of the
// threshold it reports (morph_threshold): what a fresh view at that threshold builds.
TEST(Roam, TriangleCapFollowsTheCameraAtOneThreshold) {
  auto l = make_landscape(257, 5);
  const std::uint32_t cap = 6000;
  auto view = RoamView::create(l, {.threshold = 0.0, .max_triangles = cap}).value();
  Camera c = camera_at({10, 150, 10}, {200, 50, 200});
  int searched = 0;
  for (int k = 0; k < 40; ++k) {
    c.eye += glm::dvec3(4, 0.3, 3);
    c.target += glm::dvec3(2, 0, 5);
    auto st = view->update(c);
    ASSERT_TRUE(st);
    EXPECT_LE(st->triangles, cap) << "update " << k;
    EXPECT_EQ(check_crack_free(*view), "") << "update " << k;
    if (k < 5) continue;  // the search settles
    EXPECT_GT(st->triangles, 0.9 * cap) << "update " << k;
    EXPECT_EQ(st->stop, StopReason::kTriangleBudget);
    EXPECT_LE(st->max_remaining_error, st->morph_threshold * (1 + 1e-6)) << "update " << k;
    if (k % 8 == 0) {
      auto fresh = RoamView::create(l, {.threshold = st->morph_threshold}).value();
      ASSERT_TRUE(fresh->update(c));
      EXPECT_EQ(fresh->mesh_hash(), view->mesh_hash()) << "update " << k;
      ++searched;
    }
  }
  EXPECT_GT(searched, 3);
  // A threshold above what the cap needs: the cap does not bind and the view converges.
  RoamSettings s = view->settings();
  s.threshold = 20.0;
  ASSERT_TRUE(view->set_settings(s));
  auto st = view->update(c);
  ASSERT_TRUE(st);
  EXPECT_EQ(st->stop, StopReason::kConverged);
  EXPECT_DOUBLE_EQ(st->morph_threshold, 20.0);
  auto fresh = RoamView::create(l, {.threshold = 20.0}).value();
  ASSERT_TRUE(fresh->update(c));
  EXPECT_EQ(fresh->mesh_hash(), view->mesh_hash());
}
