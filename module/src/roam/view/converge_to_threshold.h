// Private: the way an unbudgeted frame ends: converged to the threshold. After the front's test,
// every merge the test asks for, cascading up, then every split, cascading down, breadth first.
#pragma once

#include <cstdint>
#include <vector>

#include "roam/view/refiner.h"

namespace ridgeline::roam {

class ConvergeToThreshold {
 public:
  /// Lists the front's entries whose last test disagrees with their state: merges due (split
  /// and failing) and splits due (unsplit and passing). Few entries change per update: the
  /// blocks' masks say which.
  void collect(const Front& front);
  /// Merges due listed by collect(): a teleport or a snap turn has many (RoamView::update()
  /// rebuilds from the roots then).
  std::size_t merges_due() const noexcept { return merges_.size(); }
  /// Makes every change listed, and every change those ask for, until none is left: the mesh is
  /// then the one the threshold asks for (or waits for data: RoamStats::pending_splits).
  void run(Refiner& refiner);
  /// Bytes of the work lists (RoamStats::memory_bytes).
  std::size_t memory_bytes() const noexcept {
    return (merges_.capacity() + splits_.capacity() + next_wave_.capacity()) *
           sizeof(std::uint32_t);
  }
  /// A work list for others between runs (its contents are lost at the next collect()).
  std::vector<std::uint32_t>& scratch() noexcept { return next_wave_; }

 private:
  std::vector<std::uint32_t> merges_, splits_;  // nodes; the next change at the back
  std::vector<std::uint32_t> next_wave_;        // the changes this wave asks for
};

}  // namespace ridgeline::roam
