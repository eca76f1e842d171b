// BudgetController against synthetic frame-time series: a plant model whose frame time falls as
// the threshold rises, plus injected load. No clock, no timing: every series is deterministic.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "ridgeline/budget_controller.h"

using ridgeline::BudgetAction;
using ridgeline::BudgetController;
using ridgeline::BudgetControllerDesc;

namespace {

constexpr double kDt = 1.0 / 30.0;  // seconds per simulated frame

// A game whose render cost is 60 ms at a 1-pixel threshold and falls as 1 / threshold (a view's
// triangles fall as about 1 / threshold^2; fill and fixed costs make it flatter), plus 5 ms of
// fixed work and `extra_ms` of injected load.
double plant_ms(double threshold, double extra_ms) { return 5.0 + 60.0 / threshold + extra_ms; }

struct Trace {
  std::vector<double> threshold, frame_ms;
};

// Runs `seconds` of frames; `extra(t)` gives the injected load at time t (seconds).
template <class F>
Trace run(BudgetController& c, double seconds, double t0, F extra) {
  Trace tr;
  const int n = static_cast<int>(std::lround(seconds / kDt));
  for (int i = 0; i < n; ++i) {
    const double ms = plant_ms(c.threshold(), extra(t0 + i * kDt));
    tr.frame_ms.push_back(ms);
    tr.threshold.push_back(c.update(ms, kDt));
  }
  return tr;
}

BudgetController make(BudgetControllerDesc d = {}) {
  auto c = BudgetController::create(d);
  EXPECT_TRUE(c.ok()) << (c.ok() ? "" : c.error().message);
  return std::move(c).value();
}

}  // namespace

TEST(BudgetController, SettlesInsideTheBandOnSteadyLoadWithoutOscillating) {
  BudgetController c = make();  // target 33 ms, threshold starts at 2 (35 ms: inside the band)
  ASSERT_TRUE(c.reset(1.0).ok());  // 65 ms: far too slow
  run(c, 10, 0, [](double) { return 0.0; });
  const double settled = c.threshold();
  // 5 + 60 / t within 33 * (1 +- 0.08): t in [1.94, 2.4].
  EXPECT_GT(settled, 1.9);
  EXPECT_LT(settled, 2.45);
  const auto reversals = c.state().reversals;
  // The smoothed time approaches the band's edge from outside, so the threshold may still creep
  // by a fraction of a percent; it never turns back (no reversal).
  Trace steady = run(c, 20, 10, [](double) { return 0.0; });
  for (double t : steady.threshold) EXPECT_NEAR(t, settled, 0.005 * settled);
  EXPECT_EQ(c.state().reversals, reversals);
  for (double ms : steady.frame_ms) {
    EXPECT_LT(ms, 33.0 * 1.09);
    EXPECT_GT(ms, 33.0 * 0.91);
  }
}

TEST(BudgetController, NoisySteadyLoadDoesNotReverseBackAndForth) {
  BudgetController c = make();
  run(c, 5, 0, [](double) { return 0.0; });
  const auto before = c.state().reversals;
  // +-3 ms of alternating jitter (deterministic) and a single 40 ms outlier every 2 s.
  int frame = 0;
  Trace tr = run(c, 30, 5, [&frame](double t) {
    ++frame;
    const double jitter = (frame % 2 == 0) ? 3.0 : -3.0;
    return jitter + (std::fmod(t, 2.0) < kDt ? 40.0 : 0.0);
  });
  EXPECT_LE(c.state().reversals - before, 2u);
  double lo = 1e9, hi = 0;
  for (std::size_t i = tr.threshold.size() / 2; i < tr.threshold.size(); ++i) {
    lo = std::min(lo, tr.threshold[i]);
    hi = std::max(hi, tr.threshold[i]);
  }
  EXPECT_LT(hi / lo, 1.25) << "threshold wandered from " << lo << " to " << hi;
}

TEST(BudgetController, A20MsSpikeFor5SecondsRaisesTheThresholdWhichReturnsAfterwards) {
  BudgetController c = make();
  run(c, 10, 0, [](double) { return 0.0; });
  const double before = c.threshold();
  // 20 ms of extra work per frame from t = 10 s to 15 s, then 15 s of normal load.
  auto spike = [](double t) { return (t >= 10.0 && t < 15.0) ? 20.0 : 0.0; };
  Trace during = run(c, 5, 10, spike);
  const double peak = c.threshold();
  EXPECT_GT(peak, 2.0 * before) << "the threshold did not rise under load";
  // Holding the target under the spike needs 5 + 60 / t + 20 <= 33 * 1.08: t >= 5.0.
  EXPECT_GT(peak, 4.8);
  // By the end of the spike the frame time is back near the target.
  EXPECT_LT(during.frame_ms.back(), 33.0 * 1.15);
  Trace after = run(c, 15, 15, spike);
  // Back inside the band: 5 + 60 / t within 33 * (1 +- 0.08) means t in [1.96, 2.37].
  EXPECT_GT(before, 1.95);
  EXPECT_LT(before, 2.38);
  EXPECT_GT(c.threshold(), 1.95) << "the threshold did not come back";
  EXPECT_LT(c.threshold(), 2.38) << "the threshold did not come back";
  EXPECT_LT(after.frame_ms.back(), 33.0 * 1.1);
  EXPECT_GT(after.frame_ms.back(), 33.0 * 0.9);
  // It came back down without overshooting to the far side and climbing again.
  int raises_after_drop = 0;
  for (std::size_t i = 1; i < after.threshold.size(); ++i)
    if (after.threshold[i] > after.threshold[i - 1]) ++raises_after_drop;
  EXPECT_LE(raises_after_drop, 5);
}

TEST(BudgetController, StaysWithinItsRange) {
  BudgetControllerDesc d;
  d.min_threshold = 1.5;
  d.max_threshold = 3.0;
  BudgetController c = make(d);
  run(c, 10, 0, [](double) { return 100.0; });  // impossible load: pinned at max
  EXPECT_EQ(c.threshold(), 3.0);
  EXPECT_TRUE(c.state().at_max);
  for (int i = 0; i < 900; ++i) c.update(5.0, kDt);  // cheap frames: pinned at min
  EXPECT_EQ(c.threshold(), 1.5);
  EXPECT_TRUE(c.state().at_min);
  ASSERT_TRUE(c.set_range(2.0, 2.5).ok());
  EXPECT_EQ(c.threshold(), 2.0);
}

TEST(BudgetController, ResponseDoesNotDependOnTheFrameRate) {
  // The same 2 s of 60 ms frames fed as 30 frames or as 120 frames move the threshold alike.
  BudgetController a = make(), b = make();
  for (int i = 0; i < 30; ++i) a.update(60.0, 2.0 / 30);
  for (int i = 0; i < 120; ++i) b.update(60.0, 2.0 / 120);
  EXPECT_NEAR(a.threshold(), b.threshold(), 0.05 * a.threshold());
}

TEST(BudgetController, IgnoresBadSamples) {
  BudgetController c = make();
  const double t = c.threshold();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(c.update(nan, kDt), t);
  EXPECT_EQ(c.update(inf, kDt), t);
  EXPECT_EQ(c.update(-1, kDt), t);
  EXPECT_EQ(c.update(50, nan), t);
  EXPECT_EQ(c.update(50, -1), t);
  EXPECT_EQ(c.state().updates, 0u);
}

TEST(BudgetController, RefusesBadSettingsWithTheFieldNamed) {
  auto expect_error = [](BudgetControllerDesc d, const char* needle) {
    auto c = BudgetController::create(d);
    ASSERT_FALSE(c.ok());
    EXPECT_NE(c.error().message.find(needle), std::string::npos) << c.error().message;
  };
  BudgetControllerDesc d;
  d.target_ms = 0;
  expect_error(d, "target_ms 0");
  d = {};
  d.min_threshold = 4;
  d.max_threshold = 2;
  expect_error(d, "threshold range [4, 2]");
  d = {};
  d.initial_threshold = 40;
  expect_error(d, "initial_threshold 40");
  d = {};
  d.deadband = 0.5;
  expect_error(d, "deadband 0.5");
  d = {};
  d.smoothing_s = -1;
  expect_error(d, "smoothing_s -1");
  d = {};
  d.raise_gain = std::numeric_limits<double>::infinity();
  expect_error(d, "gains inf");
  d = {};
  d.reverse_hold_s = std::numeric_limits<double>::quiet_NaN();
  expect_error(d, "reverse_hold_s nan");
  BudgetController c = make();
  EXPECT_FALSE(c.set_target_ms(-3).ok());
  EXPECT_FALSE(c.set_range(0, 1).ok());
  EXPECT_FALSE(c.reset(100).ok());
  EXPECT_EQ(c.desc().target_ms, 33.0);
}
