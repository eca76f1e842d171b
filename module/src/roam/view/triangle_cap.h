// Private: the way a frame ends under a triangle cap alone (no time budget, the screen metric,
// the coherent mode): a search for the threshold whose converged mesh fills the cap, carried
// from one update to the next.
#pragma once

#include <cstdint>

#include "ridgeline/camera.h"
#include "roam/view/converge_to_threshold.h"
#include "roam/view/refiner.h"
#include "roam/view/time_budget.h"

namespace ridgeline::roam {

/// Splitting the highest priority first until the cap is reached (the dual queues) ends in the
/// mesh of one threshold: the priority of the last split. So the search looks for that
/// threshold instead of ordering every change: it converges at the last update's threshold (the
/// unbudgeted path: a pass over the front and only the changes), raises the threshold while the
/// mesh exceeds the cap (merges, the cheap direction), and when the mesh ends well under the
/// cap, starts the next update lower. The mesh then follows the camera at the cost of an
/// unbudgeted update, where ordering the whole front by priority each update cost ~2x. The first
/// update (and any that does not fit after a few raises) uses the queues, which hit the cap
/// exactly; their remaining priority seeds the search.
class TriangleCap {
 public:
  /// True once an update has found a threshold to start from (the first uses the queues).
  bool searching() const noexcept { return next_threshold_ > 0.0; }
  /// The threshold this update's test starts at (pixels): the last update's, never below
  /// `threshold`.
  double start_threshold(double threshold) const noexcept {
    return next_threshold_ > threshold ? next_threshold_ : threshold;
  }
  /// Forgets the search (the cap changed).
  void forget() noexcept { next_threshold_ = 0.0; }

  /// After the front's test at start_threshold() and converge.collect(): converges at the
  /// smallest threshold found (>= `threshold`) whose mesh fits `cap`; returns it (the
  /// RoamStats::morph_threshold) and sets RoamStats::stop.
  double run(Refiner& refiner, ConvergeToThreshold& converge, TimeBudget& queues,
             Deadline& deadline, const Camera& camera, double threshold, std::uint32_t cap);

 private:
  double next_threshold_ = 0.0;  // where the next update's search starts (0: none yet)
};

}  // namespace ridgeline::roam
