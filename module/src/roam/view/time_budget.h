// Private: the way a frame ends under a time budget (and under a triangle cap when the cap's
// threshold search does not apply): D97's dual split and merge queues (section 5), built afresh
// from this update's test, the most important change first until the clock or the cap says
// stop; and the deadline the whole update keeps.
#pragma once

#include <chrono>
#include <cstdint>
#include <utility>
#include <vector>

#include "roam/view/refiner.h"

namespace ridgeline::roam {

/// An update's time budget: when it ends, and the checks of the clock during the changes.
class Deadline {
 public:
  using Clock = std::chrono::steady_clock;
  /// Operations (splits and merges) an update under a time budget makes before it first reads
  /// the clock (out_of_time()).
  static constexpr std::uint32_t kFreeOperations = 2;

  /// Starts an update at `start` with `budget_ms` milliseconds (0: none).
  void start(Clock::time_point start, double budget_ms);
  bool has_budget() const noexcept { return has_budget_; }
  Clock::time_point start_time() const noexcept { return start_; }
  /// `share` (0..1) of the budget.
  Clock::duration share(double share) const {
    return std::chrono::duration_cast<Clock::duration>((end_ - start_) * share);
  }

  /// Called before each operation: true when the budget is spent. The first kFreeOperations of
  /// an update always run, so the mesh keeps moving however small the budget and however slow
  /// the machine (a pass that used the whole budget left none: under AddressSanitizer a 0.02 ms
  /// budget made no change at all). Then the clock is read at the next check and every eighth
  /// after it. Never true without a budget.
  bool out_of_time() {
    if (!has_budget_) return false;
    const std::uint32_t k = checks_++;
    if (k < kFreeOperations || ((k - kFreeOperations) & 7) != 0) return false;
    return Clock::now() >= end_;
  }

 private:
  bool has_budget_ = false;
  Clock::time_point start_, end_;
  std::uint32_t checks_ = 0;
};

class TimeBudget {
 public:
  /// The share of the budget the front's pass may take.
  static constexpr double kPassShare = 0.4;

  /// The front's test under a time budget: whole chunks from where the last one stopped, for at
  /// most kPassShare of the budget (Front::evaluate_until()); without a cap it lists the changed
  /// entries with their priorities for run()'s queues. Counts the entries tested.
  void test_front(Refiner& refiner, const Deadline& deadline, bool capped);
  /// Splits the highest priority and merges the lowest until the deadline, the cap (0: none)
  /// or convergence stops it (RoamStats::stop); under a cap, trades a merge for a split while
  /// the split matters more. Returns the largest priority in view left unsplit. Under a cap, the
  /// splits that end the mesh on the data's border are made past the cap at the end.
  float run(Refiner& refiner, Deadline& deadline, double threshold, std::uint32_t cap,
            std::vector<std::uint32_t>& scratch);
  /// Bytes of the pass's list of changed entries (RoamStats::memory_bytes).
  std::size_t memory_bytes() const noexcept {
    return changed_entries_.capacity() * sizeof(Front::Keyed);
  }

 private:
  using QueueItem = std::pair<float, std::uint32_t>;  // priority, node
  /// The candidates of a queue not ordered yet: the pass's changed entries (no cap) or the
  /// whole front (a cap); `held_back` receives the largest priority of a split left out.
  void fill_queues(Refiner& refiner, std::uint32_t cap, float& held_back);

  // Members, so that an update allocates nothing once they have grown (an allocation after
  // other code gave memory back to the system faults pages in: ~0.5 ms spikes).
  std::vector<Front::Keyed> changed_entries_;  // the pass's changed entries and priorities
  std::vector<QueueItem> split_queue_, merge_queue_;
  std::vector<float> key_sample_;              // the sample of keep_largest()'s cutoff
  std::vector<std::uint32_t> touched_nodes_;   // nodes a change made or freed: queued again
  std::uint32_t last_operations_ = 0;          // changes the last budgeted update made
  std::uint32_t pass_cursor_ = 0;              // the chunk the next pass starts at
};

}  // namespace ridgeline::roam
