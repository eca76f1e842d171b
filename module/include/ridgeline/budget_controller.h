// BudgetController: keeps a game's frame time near a target by moving the ROAM pixel threshold
// and, when the threshold alone is not enough, the render scale (dynamic resolution).
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
  /// within target * (1 +- deadband) nothing moves.
  double deadband = 0.08;
  /// Spending headroom: while the smoothed frame time is inside the band but below
  /// target * (1 - deadband / 2), the quality still rises, slowly: per second the quality level
  /// moves by headroom_gain * (1 - smoothed / target). Without it (0, the default) the controller
  /// stops wherever the frame time enters the band, which on a scene whose frame time hardly
  /// depends on the threshold can be far above the threshold the frame could afford. The upper
  /// part of the band, target * (1 - deadband / 2) .. target * (1 + deadband), stays dead, so the
  /// creep never ends in an oscillation. Finite, >= 0.
  double headroom_gain = 0.0;
  /// Time constant of the exponential moving average of frame times, seconds; >= 0 (0: no
  /// smoothing).
  double smoothing_s = 0.25;
  /// Rate of change: per second the quality level moves by gain * e (the threshold is multiplied
  /// by exp(gain * e), or the render scale divided by it), e being the relative error outside
  /// the band (clamped to [-1, 2]). Finite, > 0.
  double raise_gain = 3.0;  ///< used when frames are too slow
  double lower_gain = 2.5;  ///< used when frames are fast (slower, to avoid overshoot)
  /// After the controller moved in one direction it will not move the other way until this many
  /// seconds have passed outside the band on the other side (hysteresis in time: a single
  /// outlier frame never reverses it). >= 0.
  double reverse_hold_s = 0.5;

  /// Warm-up: the first `warmup_frames` frames fed after create() or reset() are recorded
  /// (state().updates counts them) but neither averaged nor acted on: start-up frames (shader
  /// compilation, first uploads, the first detail tiles) must not steer the controller. 0..1000.
  std::uint32_t warmup_frames = 10;
  /// Outlier rejection: the average is fed the median of the last `median_frames` frame times
  /// (odd, 1..15; 1 = off), so isolated slow frames (up to (median_frames - 1) / 2 in a row) are
  /// ignored while a lasting change of load shows after (median_frames + 1) / 2 frames.
  std::uint32_t median_frames = 5;
  /// Longest time one frame may count for, seconds (finite, > 0): a frame that took longer
  /// (a stall) moves the average and the threshold as if it had taken this long.
  double max_step_s = 0.1;

  /// Render scale (dynamic resolution): the fraction of the output resolution, per axis, that
  /// the scene is rendered at (the picture is upscaled; the pixel threshold stays in output
  /// pixels). The controller lowers it, down to `min_render_scale`, only while the threshold
  /// sits at `render_scale_from_px`: the ladder of quality is threshold min ->
  /// render_scale_from_px, then scale 1 -> min_render_scale, then threshold ->
  /// max_threshold, and back down in the reverse order. min_render_scale in (0, 1]; 1 turns the
  /// lever off (the render scale stays 1).
  double min_render_scale = 1.0;
  /// Threshold (pixels) at which the render scale starts to drop; 0 means max_threshold (the
  /// scale is the last resort). Otherwise within [min_threshold, max_threshold].
  double render_scale_from_px = 0.0;
};

/// What the controller did on the last update.
enum class BudgetAction : std::uint8_t { kHold, kRaise, kLower };

/// State after an update, for debug panels and stats files.
struct BudgetState {
  double threshold = 0;      ///< pixels
  double render_scale = 1;   ///< fraction of the output resolution per axis, (0, 1]
  double smoothed_ms = 0;    ///< moving average of the (median-filtered) frame times
  double last_frame_ms = 0;  ///< the last frame time fed, as given
  double filtered_ms = 0;    ///< the median the average was fed last
  /// kRaise: the quality went down (threshold up or render scale down) because frames were
  /// slow; kLower: the quality went up.
  BudgetAction action = BudgetAction::kHold;
  std::uint64_t updates = 0;            ///< frames fed (warm-up frames included)
  std::uint64_t reversals = 0;          ///< times the direction of change flipped (raise <-> lower)
  bool warming_up = true;               ///< still within the warm-up frames
  bool at_min = false, at_max = false;  ///< the threshold sits at a limit of its range
};

/// A feedback controller of a game's quality: frame times in, pixel threshold and render scale
/// out.
///
/// The controller has no clock: the caller feeds it each frame's measured time and the time that
/// passed (usually the same, in seconds), so any time series can be injected (tests replay
/// synthetic series). Both outputs sit on one ladder of quality levels x >= 0 (a single
/// integrator, so the two levers never fight): the threshold is min_threshold * exp(x) up to
/// render_scale_from_px, then the render scale is exp(-(x - x1)) down to min_render_scale, then
/// the threshold rises again to max_threshold. A view's triangle count goes with about
/// 1 / threshold^2 and the fill cost with render_scale^2, so a step in x costs about the same
/// on either lever. x moves only outside a band around the target, faster up (raise_gain) than
/// down (lower_gain), and reverses direction only after the error persisted on the other side
/// for reverse_hold_s. Start-up frames (warm-up) and isolated slow frames (a median filter)
/// are not acted on.
///
/// Threading: one thread at a time; no shared state. Pure arithmetic: no allocation; trivially
/// copyable and destructible.
class BudgetController {
 public:
  /// Validates `desc`; the error names the field and value.
  static Result<BudgetController> create(const BudgetControllerDesc& desc = {});

  /// Feeds one frame: `frame_ms` the measured frame time (milliseconds), `dt_s` the time it
  /// covers (seconds). Returns the threshold to use for the next frame (render_scale() gives the
  /// scale). A non-finite or negative frame_ms or dt_s is ignored (the state and outputs stay
  /// as they were).
  double update(double frame_ms, double dt_s) noexcept;

  /// The current threshold, pixels.
  double threshold() const noexcept { return state_.threshold; }
  /// The current render scale, (0, 1].
  double render_scale() const noexcept { return state_.render_scale; }
  const BudgetState& state() const noexcept { return state_; }
  const BudgetControllerDesc& desc() const noexcept { return desc_; }

  /// Changes the target (ms, finite, > 0); the rest of the state is kept.
  Status set_target_ms(double target_ms);
  /// Changes the hysteresis band (a fraction of the target in [0, 0.5)); the rest of the state
  /// is kept. A narrower band settles closer to the target (the controller stops wherever the
  /// smoothed frame time enters the band), at the price of reacting to smaller swings.
  Status set_deadband(double deadband);
  /// Changes headroom_gain (finite, >= 0); the state is kept.
  Status set_headroom_gain(double gain);
  /// Changes the threshold range; the current threshold is clamped into it (that is the point),
  /// as is render_scale_from_px when it was set.
  Status set_range(double min_threshold, double max_threshold);
  /// Changes the render-scale lever (min_render_scale in (0, 1], render_scale_from_px 0 or in
  /// the threshold range); the current outputs are moved onto the new ladder.
  Status set_render_scale_range(double min_render_scale, double render_scale_from_px);
  /// Puts the threshold to `threshold` (within the range) and the render scale to
  /// `render_scale` (within [min_render_scale, 1]; below 1 only when the threshold is at the
  /// scale's step, else it is taken as 1), and forgets the history (warm-up starts again).
  Status reset(double threshold, double render_scale = 1.0);

 private:
  explicit BudgetController(const BudgetControllerDesc& desc);
  // The ladder: x in [0, x_max]; outputs from x.
  double knee_px() const noexcept;
  double x_of(double threshold, double render_scale) const noexcept;
  void apply_x() noexcept;
  void keep_exact(double threshold) noexcept;

  BudgetControllerDesc desc_;
  BudgetState state_;
  double x_ = 0;                                  // quality level on the ladder
  BudgetAction direction_ = BudgetAction::kHold;  // last direction moved
  double opposite_s_ = 0;   // seconds spent outside the band opposite to direction_
  bool primed_ = false;     // the average holds at least one frame
  std::uint32_t fed_ = 0;   // frames fed since create() or reset() (saturating)
  double recent_[15] = {};  // ring of the last median_frames frame times
  std::uint32_t recent_count_ = 0, recent_next_ = 0;
};

/// Short name of an action: "hold", "raise", "lower".
const char* to_string(BudgetAction action) noexcept;

}  // namespace ridgeline
