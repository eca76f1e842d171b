// A frame's end under a triangle cap alone: the threshold search (triangle_cap.h).
#include "roam/view/triangle_cap.h"

#include <algorithm>
#include <cmath>

namespace ridgeline::roam {

double TriangleCap::run(Refiner& r, ConvergeToThreshold& converge, TimeBudget& queues,
                        Deadline& deadline, const Camera& camera, double threshold,
                        std::uint32_t cap) {
  RoamStats& stats = r.stats();
  if (!searching()) {
    // The first update: the queues fill the cap exactly; what they leave seeds the search.
    r.set_worst_failing(queues.run(r, deadline, threshold, cap, converge.scratch()));
    const double reached = stats.stop == StopReason::kTriangleBudget
                               ? std::max(threshold, double(r.worst_failing()))
                               : threshold;
    next_threshold_ = reached;
    return reached;
  }
  // N(tau) falls roughly as tau^-1.5 on terrain: steps of the ratio^(2/3), at least 1 %.
  constexpr double kExponent = 2.0 / 3.0, kTarget = 0.99, kLowerBelow = 0.985;
  constexpr int kRaises = 4;
  double tau = start_threshold(threshold);
  for (int pass = 0;; ++pass) {
    if (pass > 0) {
      r.set_camera(screen_camera(r.landscape(), camera, tau));
      r.test_front();
      converge.collect(r.front());
    }
    converge.run(r);
    if (r.triangles() <= cap) break;
    if (pass == kRaises) {
      // Still over: let the queues trade down to the cap at this threshold.
      r.set_worst_failing(queues.run(r, deadline, tau, cap, converge.scratch()));
      tau = std::max(tau, double(r.worst_failing()));
      break;
    }
    tau *= std::clamp(std::pow(double(r.triangles()) / (kTarget * cap), kExponent), 1.01, 4.0);
  }
  // Where the next update starts: lower when this mesh ended well under the cap.
  double next = tau;
  if (r.triangles() < kLowerBelow * cap && tau > threshold)
    next = std::max(threshold,
                    tau * std::clamp(std::pow(double(r.triangles()) / (kTarget * cap), kExponent),
                                     0.25, 0.99));
  next_threshold_ = next;
  stats.stop = tau > threshold ? StopReason::kTriangleBudget : StopReason::kConverged;
  return tau;
}

}  // namespace ridgeline::roam
