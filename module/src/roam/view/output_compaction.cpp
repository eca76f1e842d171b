// Output compaction (output_compaction.h). A patch's slots are renumbered in the depth-first
// order of its two trees (child 0 first): the leaves' order is a space-filling curve over the
// patch, so neighbouring triangles sit side by side in the index buffer and share vertices
// nearby, what a GPU's vertex cache likes.
#include "roam/view/output_compaction.h"

namespace ridgeline::roam {

void OutputCompaction::run(Refiner& r, const std::chrono::steady_clock::time_point* until) {
  PatchOutput& output = r.output();
  NodePool& nodes = r.nodes();
  std::vector<std::uint32_t>& pending = output.compact_pending();
  std::size_t kept = 0;  // patches left listed for a later update, moved to the front
  for (std::size_t q = 0; q < pending.size(); ++q) {
    const std::uint32_t p = pending[q];
    if (until != nullptr &&
        std::chrono::steady_clock::now() +
                std::chrono::nanoseconds(kNsPerTriangle * std::int64_t(output.live_triangles(p))) >
            *until) {
      pending[kept++] = p;
      continue;
    }
    output.unlist_compact(p);
    if (!output.oversized(p)) continue;  // grew back since it was listed
    tree_nodes_.clear();
    triangle_order_.clear();
    stack_.assign({2 * p + 1, 2 * p});
    while (!stack_.empty()) {
      const std::uint32_t n = stack_.back();
      stack_.pop_back();
      tree_nodes_.push_back(n);
      const Node& x = nodes[n];
      if (x.leaf()) {
        triangle_order_.push_back(x.slot());
      } else {
        stack_.push_back(x.first_child() + 1);
        stack_.push_back(x.first_child());
      }
    }
    output.compact(p, triangle_order_, vertex_map_);
    std::uint32_t k = 0;
    for (const std::uint32_t n : tree_nodes_) {
      Node& x = nodes[n];
      if (x.leaf())
        x.set_slot(k++);
      else
        x.set_midpoint_slot(vertex_map_[x.midpoint_slot()]);
    }
    ++r.stats().compacted_patches;
  }
  pending.resize(kept);
}

}  // namespace ridgeline::roam
