// An unbudgeted frame's end: converged to the threshold (converge_to_threshold.h).
//
// Breadth first: the changes a wave of changes asks for (parents that became mergeable and
// inactive, children that are active) make the next wave, so each wave's list is known before
// it starts and the next changes' data can be fetched ahead (prefetch_change()); and coarser
// diamonds split before finer ones, so few splits need forcing.
#include "roam/view/converge_to_threshold.h"

#include <bit>

namespace ridgeline::roam {

namespace {

// The changes are memory walks (node, entry, neighbours, the landscape's records, the patch
// buffers) that depend on each other within one change but not across changes. So the next
// changes' data is fetched in stages while this one runs: a node 32 changes ahead, what the
// node points at 16 ahead, what its entry points at 8 ahead; the misses overlap instead of
// stalling one change at a time. (`list`'s back is the next change.)
void prefetch_change(const Refiner& r, const std::vector<std::uint32_t>& list, bool split) {
  constexpr std::size_t kNodeAhead = 32, kLinksAhead = 16, kRecordsAhead = 8;  // 16/8/4: ~10 % slower
  const NodePool& nodes = r.nodes();
  const Front& front = r.front();
  const std::size_t n = list.size();
  if (n > kNodeAhead) nodes.prefetch(list[n - kNodeAhead - 1]);
  if (n > kLinksAhead) {
    const Node& x = nodes[list[n - kLinksAhead - 1]];
    front.prefetch(x.entry());
    nodes.prefetch(linked_node(x.base()));
    nodes.prefetch(x.parent);
    // A leaf's left neighbour, an interior node's children (raw: it may have changed since).
    const std::uint32_t side = x.link[kLeftLink];
    nodes.prefetch(split ? linked_node(side) : side);
    if (split) nodes.prefetch(linked_node(x.link[kRightLink]));
  }
  if (n <= kRecordsAhead) return;
  const Node& x = nodes[list[n - kRecordsAhead - 1]];
  const std::uint32_t e = x.entry();
  if (e >= front.size() || x.leaf() != split) return;  // no longer a candidate
  const std::int64_t i = front.ci(e), j = front.cj(e), hu = front.hu(e), hw = front.hw(e);
  const DiamondSource& source = r.source();
  if (!split) {
    // A merge removes its children's entries and may make a parent mergeable (its partner's
    // children are read, its record too: the parents are centred at the two apexes c +- p).
    front.prefetch(nodes[x.first_child()].entry());
    front.prefetch(nodes[x.first_child() + 1].entry());
    if (x.parent != kNone) nodes.prefetch(linked_node(nodes[x.parent].base()));
    source.prefetch(i - hw, j + hu);
    source.prefetch(i + hw, j - hu);
    return;
  }
  // A split removes its parents' entries (when mergeable), writes its vertex (its record) and
  // adds its children's diamonds (centres c +- (p +- h) / 2, p = (-hw, hu)). A base neighbour
  // that is not its partner is split first (a forced split): its entry and parent next.
  if (x.parent != kNone) front.prefetch(nodes[x.parent].entry());
  if (is_coarser(x.base())) {
    const Node& f = nodes[linked_node(x.base())];
    front.prefetch(f.entry());
    nodes.prefetch(f.parent);
    nodes.prefetch(linked_node(f.link[kLeftLink]));
    nodes.prefetch(linked_node(f.link[kRightLink]));
  }
  source.prefetch(i, j, true);
  if (((hu - hw) | (hu + hw)) & 1) return;  // finest: no child diamonds
  const std::int64_t au = (hu - hw) / 2, aw = (hu + hw) / 2, bu = (hu + hw) / 2, bw = (hw - hu) / 2;
  source.prefetch(i + au, j + aw);
  source.prefetch(i - au, j - aw);
  source.prefetch(i + bu, j + bw);
  source.prefetch(i - bu, j - bw);
}

}  // namespace

void ConvergeToThreshold::collect(const Front& front) {
  merges_.clear();
  splits_.clear();
  const std::uint32_t blocks = front.blocks();
  for (std::uint32_t b = 0; b < blocks; ++b) {
    for (std::uint32_t lanes = front.changed(b); lanes != 0; lanes &= lanes - 1) {
      const std::uint32_t e = b * Front::kLanes + std::uint32_t(std::countr_zero(lanes));
      (front.split(e) ? merges_ : splits_).push_back(front.node(e));
    }
  }
}

void ConvergeToThreshold::run(Refiner& r) {
  for (std::vector<std::uint32_t>* list : {&merges_, &splits_}) {
    const bool split = list == &splits_;
    next_wave_.clear();
    while (!list->empty()) {
      while (!list->empty()) {
        prefetch_change(r, *list, split);
        const std::uint32_t n = list->back();
        list->pop_back();
        if (split) {
          if (r.split_candidate(n) && !r.split(n, false, &next_wave_)) ++r.stats().pending_splits;
        } else if (r.merge_candidate(n)) {
          r.merge(n, &next_wave_);
        }
      }
      list->swap(next_wave_);
    }
  }
}

}  // namespace ridgeline::roam
