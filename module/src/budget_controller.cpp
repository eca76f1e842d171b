// Frame-time feedback on a game's quality: a multiplicative integral controller with a dead band,
// a reversal hold (hysteresis in value and in time), a warm-up and a median filter, acting on one
// ladder of quality levels that spans the ROAM pixel threshold and the render scale.
#include "ridgeline/budget_controller.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace ridgeline {
namespace {

bool finite_positive(double v) {
  return std::isfinite(v) && v > 0;
}

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

Status check_scale(double min_scale, double from_px, double lo, double hi) {
  if (!finite_positive(min_scale) || min_scale > 1)
    return Error{"budget controller: min_render_scale " + num(min_scale) + "; need 0 < scale <= 1"};
  if (!std::isfinite(from_px) || (from_px != 0 && (from_px < lo || from_px > hi)))
    return Error{"budget controller: render_scale_from_px " + num(from_px) +
                 "; need 0 (the maximum threshold) or a threshold within [" + num(lo) + ", " +
                 num(hi) + "]"};
  return {};
}

}  // namespace

const char* to_string(BudgetAction action) noexcept {
  switch (action) {
    case BudgetAction::kRaise:
      return "raise";
    case BudgetAction::kLower:
      return "lower";
    default:
      return "hold";
  }
}

BudgetController::BudgetController(const BudgetControllerDesc& desc) : desc_(desc) {
  state_.smoothed_ms = desc.target_ms;
  x_ = x_of(desc.initial_threshold, 1.0);
  apply_x();
}

Result<BudgetController> BudgetController::create(const BudgetControllerDesc& d) {
  if (!finite_positive(d.target_ms))
    return Error{"budget controller: target_ms " + num(d.target_ms) + "; need a finite value > 0"};
  if (Status s = check_range(d.min_threshold, d.max_threshold); !s) return Error{s.message()};
  if (!std::isfinite(d.initial_threshold) || d.initial_threshold < d.min_threshold ||
      d.initial_threshold > d.max_threshold)
    return Error{"budget controller: initial_threshold " + num(d.initial_threshold) + " outside [" +
                 num(d.min_threshold) + ", " + num(d.max_threshold) + "]"};
  if (!std::isfinite(d.deadband) || d.deadband < 0 || d.deadband >= 0.5)
    return Error{"budget controller: deadband " + num(d.deadband) + "; need 0 <= deadband < 0.5"};
  if (!std::isfinite(d.headroom_gain) || d.headroom_gain < 0)
    return Error{"budget controller: headroom_gain " + num(d.headroom_gain) +
                 "; need a finite value >= 0"};
  if (!std::isfinite(d.smoothing_s) || d.smoothing_s < 0)
    return Error{"budget controller: smoothing_s " + num(d.smoothing_s) + "; need >= 0 seconds"};
  if (!finite_positive(d.raise_gain) || !finite_positive(d.lower_gain))
    return Error{"budget controller: gains " + num(d.raise_gain) + ", " + num(d.lower_gain) +
                 "; need finite values > 0"};
  if (!std::isfinite(d.reverse_hold_s) || d.reverse_hold_s < 0)
    return Error{"budget controller: reverse_hold_s " + num(d.reverse_hold_s) +
                 "; need >= 0 seconds"};
  if (d.warmup_frames > 1000)
    return Error{"budget controller: warmup_frames " + std::to_string(d.warmup_frames) +
                 "; need 0 .. 1000"};
  if (d.median_frames < 1 || d.median_frames > 15 || d.median_frames % 2 == 0)
    return Error{"budget controller: median_frames " + std::to_string(d.median_frames) +
                 "; need an odd count 1 .. 15"};
  if (!finite_positive(d.max_step_s))
    return Error{"budget controller: max_step_s " + num(d.max_step_s) +
                 "; need a finite value > 0 seconds"};
  if (Status s =
          check_scale(d.min_render_scale, d.render_scale_from_px, d.min_threshold, d.max_threshold);
      !s)
    return Error{s.message()};
  return BudgetController(d);
}

double BudgetController::knee_px() const noexcept {
  return desc_.render_scale_from_px > 0
             ? std::clamp(desc_.render_scale_from_px, desc_.min_threshold, desc_.max_threshold)
             : desc_.max_threshold;
}

// Ladder: [0, k] threshold min -> knee; [k, k + m] scale 1 -> min; [k + m, X] threshold knee ->
// max. Every segment is logarithmic in its output.
double BudgetController::x_of(double threshold, double render_scale) const noexcept {
  const double knee = knee_px();
  const double k = std::log(knee / desc_.min_threshold);
  const double m = std::log(1.0 / desc_.min_render_scale);
  if (threshold > knee * (1 + 1e-12)) return k + m + std::log(threshold / knee);
  // A scale below 1 only exists at the step; below it the scale is 1.
  if (threshold >= knee * (1 - 1e-12) && render_scale < 1 && m > 0)
    return k + std::min(m, std::log(1.0 / render_scale));
  return std::min(k, std::log(std::max(threshold, desc_.min_threshold) / desc_.min_threshold));
}

void BudgetController::apply_x() noexcept {
  const double knee = knee_px();
  const double k = std::log(knee / desc_.min_threshold);
  const double m = std::log(1.0 / desc_.min_render_scale);
  const double top = k + m + std::log(desc_.max_threshold / knee);
  x_ = std::clamp(x_, 0.0, top);
  // Piecewise, with the ends exact (no rounding drift at the limits and the step).
  double t = knee, s = 1.0;
  if (x_ < k) t = x_ <= 0 ? desc_.min_threshold : desc_.min_threshold * std::exp(x_);
  if (x_ > k + m) t = x_ >= top ? desc_.max_threshold : knee * std::exp(x_ - k - m);
  if (x_ > k) s = x_ >= k + m ? desc_.min_render_scale : std::exp(-(x_ - k));
  state_.threshold = std::clamp(t, desc_.min_threshold, desc_.max_threshold);
  state_.render_scale = std::clamp(s, desc_.min_render_scale, 1.0);
  state_.at_min = x_ <= 0;
  state_.at_max = x_ >= top;
}

void BudgetController::keep_exact(double threshold) noexcept {
  // exp(log(t)) need not give t back: a threshold set by the caller stays as given.
  if (std::abs(state_.threshold / threshold - 1) < 1e-9) state_.threshold = threshold;
}

double BudgetController::update(double frame_ms, double dt_s) noexcept {
  if (!std::isfinite(frame_ms) || frame_ms < 0 || !std::isfinite(dt_s) || dt_s < 0)
    return state_.threshold;
  ++state_.updates;
  state_.last_frame_ms = frame_ms;
  if (fed_ < desc_.warmup_frames) {
    ++fed_;
    state_.warming_up = true;
    state_.action = BudgetAction::kHold;
    return state_.threshold;
  }
  state_.warming_up = false;
  // Median of the last median_frames frames (the lower median while the ring fills up).
  const std::uint32_t n = desc_.median_frames;
  recent_[recent_next_] = frame_ms;
  recent_next_ = (recent_next_ + 1) % n;
  recent_count_ = std::min(recent_count_ + 1, n);
  const std::uint32_t count = std::min<std::uint32_t>(recent_count_, 15);
  double sorted[15];
  std::copy(recent_, recent_ + count, sorted);
  std::sort(sorted, sorted + count);
  const double filtered = sorted[(count - 1) / 2];
  state_.filtered_ms = filtered;
  const double dt = std::min(dt_s, desc_.max_step_s);
  // Moving average with a time constant, so the response does not depend on the frame rate.
  if (!primed_ || desc_.smoothing_s == 0) {
    state_.smoothed_ms = filtered;
    primed_ = true;
  } else {
    const double alpha = 1.0 - std::exp(-dt / desc_.smoothing_s);
    state_.smoothed_ms += alpha * (filtered - state_.smoothed_ms);
  }
  const double rel = state_.smoothed_ms / desc_.target_ms - 1.0;
  // rate: how far the quality level moves per second (gain x relative error).
  BudgetAction want = BudgetAction::kHold;
  double rate = 0;
  if (rel > desc_.deadband) {
    want = BudgetAction::kRaise;
    rate = desc_.raise_gain * std::min(rel - desc_.deadband, 2.0);
  } else if (rel < -desc_.deadband) {
    want = BudgetAction::kLower;
    rate = desc_.lower_gain * std::min(-rel - desc_.deadband, 1.0);
  } else if (desc_.headroom_gain > 0 && rel < -desc_.deadband / 2) {
    // Inside the band, in its lower half: spend the headroom slowly.
    want = BudgetAction::kLower;
    rate = desc_.headroom_gain * -rel;
  }
  // Reversal hold: the opposite error must persist before the direction flips.
  if (want != BudgetAction::kHold && direction_ != BudgetAction::kHold && want != direction_) {
    opposite_s_ += dt;
    if (opposite_s_ < desc_.reverse_hold_s) want = BudgetAction::kHold;
  } else if (want == direction_) {
    opposite_s_ = 0;
  }
  const double before = x_;
  if (want == BudgetAction::kRaise && !state_.at_max) {
    x_ += rate * dt;
  } else if (want == BudgetAction::kLower && !state_.at_min) {
    x_ -= rate * dt;
  } else {
    want = BudgetAction::kHold;  // nothing to move (at a limit)
  }
  if (x_ != before) apply_x();  // (unchanged: the outputs stay exactly as they were)
  if (x_ == before) want = BudgetAction::kHold;
  if (want != BudgetAction::kHold) {
    if (direction_ != BudgetAction::kHold && want != direction_) ++state_.reversals;
    direction_ = want;
    opposite_s_ = 0;
  }
  state_.action = want;
  return state_.threshold;
}

Status BudgetController::set_target_ms(double target_ms) {
  if (!finite_positive(target_ms))
    return Error{"budget controller: target_ms " + num(target_ms) + "; need a finite value > 0"};
  desc_.target_ms = target_ms;
  return {};
}

Status BudgetController::set_deadband(double deadband) {
  if (!std::isfinite(deadband) || deadband < 0 || deadband >= 0.5)
    return Error{"budget controller: deadband " + num(deadband) + "; need 0 <= deadband < 0.5"};
  desc_.deadband = deadband;
  return {};
}

Status BudgetController::set_headroom_gain(double gain) {
  if (!std::isfinite(gain) || gain < 0)
    return Error{"budget controller: headroom_gain " + num(gain) + "; need a finite value >= 0"};
  desc_.headroom_gain = gain;
  return {};
}

Status BudgetController::set_range(double lo, double hi) {
  if (Status s = check_range(lo, hi); !s) return s;
  const double t = state_.threshold, s = state_.render_scale;
  desc_.min_threshold = lo;
  desc_.max_threshold = hi;
  if (desc_.render_scale_from_px != 0)
    desc_.render_scale_from_px = std::clamp(desc_.render_scale_from_px, lo, hi);
  x_ = x_of(std::clamp(t, lo, hi), s);
  apply_x();
  keep_exact(std::clamp(t, lo, hi));
  return {};
}

Status BudgetController::set_render_scale_range(double min_scale, double from_px) {
  if (Status s = check_scale(min_scale, from_px, desc_.min_threshold, desc_.max_threshold); !s)
    return s;
  const double t = state_.threshold, s = state_.render_scale;
  desc_.min_render_scale = min_scale;
  desc_.render_scale_from_px = from_px;
  x_ = x_of(t, std::max(s, min_scale));
  apply_x();
  keep_exact(t);
  return {};
}

Status BudgetController::reset(double threshold, double render_scale) {
  if (!std::isfinite(threshold) || threshold < desc_.min_threshold ||
      threshold > desc_.max_threshold)
    return Error{"budget controller: threshold " + num(threshold) + " outside [" +
                 num(desc_.min_threshold) + ", " + num(desc_.max_threshold) + "]"};
  if (!std::isfinite(render_scale) || render_scale < desc_.min_render_scale || render_scale > 1)
    return Error{"budget controller: render scale " + num(render_scale) + " outside [" +
                 num(desc_.min_render_scale) + ", 1]"};
  BudgetControllerDesc d = desc_;
  d.initial_threshold = threshold;
  *this = BudgetController(d);
  x_ = x_of(threshold, render_scale);
  apply_x();
  keep_exact(threshold);
  return {};
}

}  // namespace ridgeline
