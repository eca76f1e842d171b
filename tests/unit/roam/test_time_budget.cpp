// Updates under a time budget (roam/view/time_budget.cpp): the budget stops an update, the rest
// continues on the next, and a tight budget still moves the mesh.
#include <gtest/gtest.h>

#include <cmath>

#include "ridgeline/roam_view.h"
#include "roam_landscapes.h"

using namespace ridgeline;
using namespace ridgeline::test;

TEST(Roam, TimeBudgetStopsTheUpdateAndTheRestContinuesNextUpdate) {
  auto l = make_landscape(257, 5);
  // A budget far below what converging takes: the first clock check (after 8 operations) stops
  // it.
  auto view = RoamView::create(l, {.threshold = 1.0, .budget_ms = 1e-6}).value();
  const Camera c = camera_at({20, 120, 30}, {300, 60, 260});
  auto st = view->update(c);
  ASSERT_TRUE(st);
  EXPECT_EQ(st->stop, StopReason::kTimeBudget);
  EXPECT_GT(st->max_remaining_error, 1.0);
  EXPECT_EQ(check_crack_free(*view), "");
  // Lift the budget: the same camera converges from where it stopped, without a rebuild.
  RoamSettings s = view->settings();
  s.budget_ms = 0;
  ASSERT_TRUE(view->set_settings(s));
  st = view->update(c);
  ASSERT_TRUE(st);
  EXPECT_EQ(st->stop, StopReason::kConverged);
  EXPECT_FALSE(st->rebuilt);
  expect_converged(*view, c, 1.0);
}

TEST(Roam, ATightTimeBudgetStillSplitsAndMerges) {
  // A camera moving fast under a tiny budget: splits and merges still happen every frame and the
  // mesh follows the camera (with the old core's lazy keys it froze: every frame's budget went to
  // re-keying). A budget of 0.1 us is spent before the first change on any machine: the first
  // operations of an update run regardless (docs/roam.md, "Budgets"), so the mesh still moves.
  auto l = make_landscape(257, 5);
  for (const double budget : {0.02, 1e-4}) {
    auto view = RoamView::create(l, {.threshold = 1.0, .budget_ms = budget}).value();
    std::uint64_t changes = 0;
    std::uint32_t frames_with_changes = 0;
    for (int f = 0; f < 120; ++f) {
      const double a = f * 0.05;
      const Camera c =
          camera_at({256 + 200 * std::cos(a), 90, 256 + 200 * std::sin(a)}, {256, 40, 256});
      auto st = view->update(c);
      ASSERT_TRUE(st);
      if (f >= 20) {
        changes += st->splits + st->merges;
        frames_with_changes += st->splits + st->merges > 0;
      }
    }
    EXPECT_GT(changes, 0u) << "budget " << budget;
    EXPECT_GT(frames_with_changes, 50u) << "budget " << budget;
    EXPECT_EQ(check_crack_free(*view), "") << "budget " << budget;
    EXPECT_EQ(view->check_invariants(), "") << "budget " << budget;
  }
}
