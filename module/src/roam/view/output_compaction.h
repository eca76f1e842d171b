// Private: the last phase of an update (under a time budget the first, in a share of it):
// patches whose buffers hold many more slots than live triangles are renumbered in tree order
// and shrunk (PatchOutput::compact()), their nodes' slots with them.
#pragma once

#include <chrono>
#include <cstdint>
#include <vector>

#include "roam/view/refiner.h"

namespace ridgeline::roam {

class OutputCompaction {
 public:
  /// Under a time budget: the share of the budget compaction may take (before the changes),
  /// and its estimated cost per live triangle of a patch (measured: ~80 ns on the noise flyover).
  static constexpr double kBudgetShare = 0.1;
  static constexpr std::int64_t kNsPerTriangle = 100;

  /// Compacts the patches listed as oversized (PatchOutput::compact_pending()), renumbering
  /// their leaves' triangle slots and their interior nodes' vertex slots. With `until`, only the
  /// patches whose estimated cost ends before it (the rest stay listed for a later update).
  /// Counts RoamStats::compacted_patches.
  void run(Refiner& refiner, const std::chrono::steady_clock::time_point* until);

 private:
  // Work lists, kept between updates: the walk's stack, the patch's nodes in tree order, its
  // live triangle slots in that order, and the old-to-new vertex slot map.
  std::vector<std::uint32_t> stack_, tree_nodes_, triangle_order_, vertex_map_;
};

}  // namespace ridgeline::roam
