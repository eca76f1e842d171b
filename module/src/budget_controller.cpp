// Frame-time feedback on the ROAM pixel threshold: a multiplicative integral controller with a
// dead band and a reversal hold (hysteresis in value and in time).
#include "ridgeline/budget_controller.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace ridgeline {
namespace {

bool finite_positive(double v) { return std::isfinite(v) && v > 0; }

std::string num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

Status check_range(double lo, double hi) {
  if (!finite_positive(lo) || !std::isfinite(hi) || hi < lo)
    return Error{"budget controller: threshold range [" + num(lo) + ", " + num(hi) +
                 "]; need finite 0 < min <= max pixels"};
  return {};
}

}  // namespace

const char* to_string(BudgetAction action) noexcept {
  switch (action) {
    case BudgetAction::kRaise: return "raise";
    case BudgetAction::kLower: return "lower";
    default: return "hold";
  }
}

BudgetController::BudgetController(const BudgetControllerDesc& desc) : desc_(desc) {
  state_.threshold = desc.initial_threshold;
  state_.smoothed_ms = desc.target_ms;
}

Result<BudgetController> BudgetController::create(const BudgetControllerDesc& d) {
  if (!finite_positive(d.target_ms))
    return Error{"budget controller: target_ms " + num(d.target_ms) + "; need a finite value > 0"};
  if (Status s = check_range(d.min_threshold, d.max_threshold); !s) return Error{s.message()};
  if (!std::isfinite(d.initial_threshold) || d.initial_threshold < d.min_threshold ||
      d.initial_threshold > d.max_threshold)
    return Error{"budget controller: initial_threshold " + num(d.initial_threshold) +
                 " outside [" + num(d.min_threshold) + ", " + num(d.max_threshold) + "]"};
  if (!std::isfinite(d.deadband) || d.deadband < 0 || d.deadband >= 0.5)
    return Error{"budget controller: deadband " + num(d.deadband) + "; need 0 <= deadband < 0.5"};
  if (!std::isfinite(d.smoothing_s) || d.smoothing_s < 0)
    return Error{"budget controller: smoothing_s " + num(d.smoothing_s) + "; need >= 0 seconds"};
  if (!finite_positive(d.raise_gain) || !finite_positive(d.lower_gain))
    return Error{"budget controller: gains " + num(d.raise_gain) + ", " + num(d.lower_gain) +
                 "; need finite values > 0"};
  if (!std::isfinite(d.reverse_hold_s) || d.reverse_hold_s < 0)
    return Error{"budget controller: reverse_hold_s " + num(d.reverse_hold_s) +
                 "; need >= 0 seconds"};
  return BudgetController(d);
}

double BudgetController::update(double frame_ms, double dt_s) noexcept {
  if (!std::isfinite(frame_ms) || frame_ms < 0 || !std::isfinite(dt_s) || dt_s < 0)
    return state_.threshold;
  ++state_.updates;
  state_.last_frame_ms = frame_ms;
  // Moving average with a time constant, so the response does not depend on the frame rate.
  if (!primed_ || desc_.smoothing_s == 0) {
    state_.smoothed_ms = frame_ms;
    primed_ = true;
  } else {
    const double alpha = 1.0 - std::exp(-dt_s / desc_.smoothing_s);
    state_.smoothed_ms += alpha * (frame_ms - state_.smoothed_ms);
  }
  const double rel = state_.smoothed_ms / desc_.target_ms - 1.0;
  BudgetAction want = BudgetAction::kHold;
  double e = 0;
  if (rel > desc_.deadband) {
    want = BudgetAction::kRaise;
    e = std::min(rel - desc_.deadband, 2.0);
  } else if (rel < -desc_.deadband) {
    want = BudgetAction::kLower;
    e = std::min(-rel - desc_.deadband, 1.0);
  }
  // Reversal hold: the opposite error must persist before the direction flips.
  if (want != BudgetAction::kHold && direction_ != BudgetAction::kHold && want != direction_) {
    opposite_s_ += dt_s;
    if (opposite_s_ < desc_.reverse_hold_s) want = BudgetAction::kHold;
  } else if (want == direction_) {
    opposite_s_ = 0;
  }
  const double lo = desc_.min_threshold, hi = desc_.max_threshold;
  double t = state_.threshold;
  if (want == BudgetAction::kRaise && t < hi) {
    t = std::min(hi, t * std::exp(desc_.raise_gain * e * dt_s));
  } else if (want == BudgetAction::kLower && t > lo) {
    t = std::max(lo, t * std::exp(-desc_.lower_gain * e * dt_s));
  } else {
    want = BudgetAction::kHold;  // nothing to move (at a limit)
  }
  if (want != BudgetAction::kHold) {
    if (direction_ != BudgetAction::kHold && want != direction_) ++state_.reversals;
    direction_ = want;
    opposite_s_ = 0;
  }
  state_.action = want;
  state_.threshold = t;
  state_.at_min = t <= lo;
  state_.at_max = t >= hi;
  return t;
}

Status BudgetController::set_target_ms(double target_ms) {
  if (!finite_positive(target_ms))
    return Error{"budget controller: target_ms " + num(target_ms) + "; need a finite value > 0"};
  desc_.target_ms = target_ms;
  return {};
}

Status BudgetController::set_range(double lo, double hi) {
  if (Status s = check_range(lo, hi); !s) return s;
  desc_.min_threshold = lo;
  desc_.max_threshold = hi;
  state_.threshold = std::clamp(state_.threshold, lo, hi);
  state_.at_min = state_.threshold <= lo;
  state_.at_max = state_.threshold >= hi;
  return {};
}

Status BudgetController::reset(double threshold) {
  if (!std::isfinite(threshold) || threshold < desc_.min_threshold ||
      threshold > desc_.max_threshold)
    return Error{"budget controller: threshold " + num(threshold) + " outside [" +
                 num(desc_.min_threshold) + ", " + num(desc_.max_threshold) + "]"};
  const BudgetControllerDesc d = desc_;
  *this = BudgetController(d);
  state_.threshold = threshold;
  return {};
}

}  // namespace ridgeline
