// BudgetController: keeps a game's frame time near a target by moving the ROAM pixel threshold.
#pragma once

#include <cstdint>

#include "ridgeline/result.h"

namespace ridgeline {

/// Settings of a BudgetController. Every field is validated by BudgetController::create().
struct BudgetControllerDesc {
  /// Frame time to hold, milliseconds; finite, > 0.
  double target_ms = 33.0;
  /// Range of the pixel threshold the controller may choose (pixels); 0 < min <= max, finite.
  double min_threshold = 1.0;
  double max_threshold = 16.0;
  /// Threshold at the start (pixels); must lie within [min, max] (outside is an error, not a
  /// silent clamp).
  double initial_threshold = 2.0;
  /// Hysteresis band, a fraction of the target in [0, 0.5): while the smoothed frame time stays
  /// within target * (1 +- deadband) the threshold does not move.
  double deadband = 0.08;
  /// Time constant of the exponential moving average of frame times, seconds; >= 0 (0: no
  /// smoothing).
  double smoothing_s = 0.25;
  /// Rate of change: per second the threshold is multiplied by exp(gain * e), e being the
  /// relative error outside the band (clamped to [-1, 2]). Finite, > 0.
  double raise_gain = 3.0;  ///< used when frames are too slow
  double lower_gain = 1.0;  ///< used when frames are fast (slower, to avoid overshoot)
  /// After the controller moved the threshold in one direction it will not move it the other way
  /// until this many seconds have passed outside the band on the other side (hysteresis in
  /// time: a single outlier frame never reverses it). >= 0.
  double reverse_hold_s = 0.5;
};

/// What the controller did on the last update.
enum class BudgetAction : std::uint8_t { kHold, kRaise, kLower };

/// State after an update, for debug panels and stats files.
struct BudgetState {
  double threshold = 0;    ///< pixels
  double smoothed_ms = 0;  ///< moving average of the frame times fed so far
  double last_frame_ms = 0;
  BudgetAction action = BudgetAction::kHold;
  std::uint64_t updates = 0;   ///< frames fed
  std::uint64_t reversals = 0; ///< times the direction of change flipped (raise <-> lower)
  bool at_min = false, at_max = false;  ///< the threshold sits at a limit of its range
};

/// A feedback controller for the ROAM pixel threshold: frame times in, threshold out.
///
/// The controller has no clock: the caller feeds it each frame's measured time and the time that
/// passed (usually the same, in seconds), so any time series can be injected (tests replay
/// synthetic series). A higher threshold means fewer triangles and so a faster frame. The
/// controller moves the threshold multiplicatively (the triangle count of a view goes roughly
/// with 1 / threshold^2, so equal ratios are equal steps), only outside a band around the target,
/// and only reverses direction after the error persisted on the other side for reverse_hold_s.
///
/// Threading: one thread at a time; no shared state. Pure arithmetic: no allocation.
class BudgetController {
 public:
  /// Validates `desc`; the error names the field and value.
  static Result<BudgetController> create(const BudgetControllerDesc& desc = {});

  /// Feeds one frame: `frame_ms` the measured frame time (milliseconds), `dt_s` the time it
  /// covers (seconds). Returns the threshold to use for the next frame. A non-finite or negative
  /// frame_ms or dt_s is ignored (the state and threshold stay as they were).
  double update(double frame_ms, double dt_s) noexcept;

  /// The current threshold, pixels.
  double threshold() const noexcept { return state_.threshold; }
  const BudgetState& state() const noexcept { return state_; }
  const BudgetControllerDesc& desc() const noexcept { return desc_; }

  /// Changes the target (ms, finite, > 0); the rest of the state is kept.
  Status set_target_ms(double target_ms);
  /// Changes the threshold range; the current threshold is clamped into it (that is the point).
  Status set_range(double min_threshold, double max_threshold);
  /// Puts the threshold to `threshold` (within the range) and forgets the history.
  Status reset(double threshold);

 private:
  explicit BudgetController(const BudgetControllerDesc& desc);
  BudgetControllerDesc desc_;
  BudgetState state_;
  BudgetAction direction_ = BudgetAction::kHold;  // last direction moved
  double opposite_s_ = 0;  // seconds spent outside the band opposite to direction_
  bool primed_ = false;    // the average holds at least one frame
};

/// Short name of an action: "hold", "raise", "lower".
const char* to_string(BudgetAction action) noexcept;

}  // namespace ridgeline
