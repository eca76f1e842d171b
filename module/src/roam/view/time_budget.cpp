// A frame's end under a time budget: D97's dual queues (section 5) over this update's test only
// (time_budget.h). Split the highest priority, merge the lowest; under a triangle cap, trade a
// merge for a split while the split matters more. Keys are this update's priorities; out-of-view
// diamonds merge first.
#include "roam/view/time_budget.h"

#include <algorithm>
#include <cmath>
#include <functional>

namespace ridgeline::roam {

void Deadline::start(Clock::time_point start, double budget_ms) {
  has_budget_ = budget_ms > 0.0;
  start_ = start;
  end_ = start + std::chrono::duration_cast<Clock::duration>(
                     std::chrono::duration<double, std::milli>(budget_ms));
  checks_ = 0;
}

namespace {

using QueueItem = std::pair<float, std::uint32_t>;

// Keeps `keep` of the items with the largest keys (all of them when there are no more), in any
// order; returns the largest key dropped (0 when none). nth_element over all of them cost
// ~30 ns an item (a mispredicted branch per comparison of random keys; and the out-of-view
// merges, thousands of them, share one key): 0.1-0.4 ms for 5,000-15,000 candidates, most of
// a 0.5 ms budget. Instead a cutoff comes from a sample of 256 keys, the items above it are
// moved to the front (a branch nearly always taken the same way), then those equal to it, and
// only when more than `keep` are above it are those selected exactly (by key alone).
float keep_largest(std::vector<QueueItem>& v, std::size_t keep, std::vector<float>& sample) {
  const std::size_t n = v.size();
  if (n <= keep) return 0.0f;
  const std::size_t stride = std::max<std::size_t>(1, n / 256);
  sample.clear();
  for (std::size_t i = 0; i < n; i += stride) sample.push_back(v[i].first);
  // The sample's key with keep's share of the sample above it, and a little more.
  const std::size_t rank = std::min(sample.size() - 1, (keep * sample.size() + n - 1) / n + 2);
  std::nth_element(sample.begin(), sample.begin() + std::ptrdiff_t(rank), sample.end(),
                   std::greater<>());
  const float cut = sample[rank];
  auto above =
      std::partition(v.begin(), v.end(), [cut](const QueueItem& x) { return x.first > cut; });
  auto end = above;
  if (std::size_t(above - v.begin()) < keep)  // then the ties, as many as fit
    end = std::partition(above, v.end(), [cut](const QueueItem& x) { return x.first == cut; });
  end = v.begin() + std::ptrdiff_t(std::min<std::size_t>(keep, std::size_t(end - v.begin())));
  if (std::size_t(above - v.begin()) > keep)  // a skewed sample: select among those above
    std::nth_element(v.begin(), end, above,
                     [](const QueueItem& a, const QueueItem& b) { return a.first > b.first; });
  float dropped = 0.0f;
  for (auto it = end; it != v.end(); ++it) dropped = std::max(dropped, it->first);
  v.erase(end, v.end());
  return dropped;
}

}  // namespace

// Under a time budget the pass takes about 40 % of it at most, in whole chunks, and the next
// update goes on where it stopped: on a large front far from convergence a whole pass with its
// change list took 0.3-0.4 ms of a 0.5 ms budget, leaving time for a few changes a frame, so the
// mesh fell further behind (more changes to list, a slower pass).
void TimeBudget::test_front(Refiner& r, const Deadline& deadline, bool capped) {
  std::uint32_t tested = 0;
  r.set_worst_failing(r.front().evaluate_until(
      r.camera(), capped ? nullptr : &changed_entries_,
      deadline.start_time() + deadline.share(kPassShare), &pass_cursor_, &tested));
  r.stats().priority_updates += tested;
}

void TimeBudget::fill_queues(Refiner& r, std::uint32_t cap, float& held_back) {
  const Front& front = r.front();
  split_queue_.clear();
  merge_queue_.clear();
  if (cap == 0) {
    // Without a cap the candidates are the entries whose test disagrees with their state, with
    // the priorities the pass computed. Far from convergence there are thousands while the
    // budget allows a few hundred changes: only the most important go in the queues (the rest
    // is found again by the next update's pass), so building them costs little.
    // The pass marked which entries are split, so the lists are sorted out by entry and only
    // the kept ones' nodes are read (a record each, which the pass did not touch, fetched
    // ahead: reading them for all the candidates cost up to 0.5 ms for 20,000 of them on a
    // front the rest of the frame had evicted).
    const std::size_t keep = std::max<std::size_t>(1024, 4 * std::size_t(last_operations_));
    for (const Front::Keyed& k : changed_entries_) {
      if (k.entry & Front::kKeyedSplit)
        merge_queue_.push_back({-k.key, k.entry & ~Front::kKeyedSplit});
      else
        split_queue_.push_back({k.key, k.entry});
    }
    auto trim = [&](std::vector<QueueItem>& v, bool is_split) {
      const float dropped = keep_largest(v, keep, key_sample_);
      if (is_split) held_back = std::max(held_back, dropped);
      constexpr std::size_t kAhead = 16;
      for (std::size_t i = 0; i < v.size(); ++i) {  // entry -> node
        if (i + kAhead < v.size()) front.prefetch_record(v[i + kAhead].second);
        v[i].second = front.node(v[i].second);
      }
    };
    trim(split_queue_, true);
    trim(merge_queue_, false);
    return;
  }
  const FrontCamera& camera = r.camera();
  for (std::uint32_t e = 0; e < front.size(); ++e) {
    if (front.split(e)) {
      // Under a cap every mergeable diamond may be traded, except those that keep the mesh
      // on the data's border (forced, like the splits that keep it crack-free).
      if (front.radius(e) < Front::kBorderRadius) {
        const float key = (front.result(e) & kInView) ? front.priority(e, camera) : -1.0f;
        merge_queue_.push_back({-key, front.node(e)});
      }
    } else if (front.result(e) & kActive) {
      split_queue_.push_back({front.priority(e, camera), front.node(e)});
    }
  }
}

float TimeBudget::run(Refiner& r, Deadline& deadline, double threshold, std::uint32_t cap,
                      std::vector<std::uint32_t>& scratch) {
  const Front& front = r.front();
  const NodePool& nodes = r.nodes();
  RoamStats& stats = r.stats();
  const FrontCamera& camera = r.camera();
  float held_back = 0;  // the largest priority of a split candidate left out of the queue
  fill_queues(r, cap, held_back);
  std::vector<QueueItem>& splits = split_queue_;
  std::vector<QueueItem>& merges = merge_queue_;  // keys negated: the lowest priority on top
  std::make_heap(splits.begin(), splits.end());
  std::make_heap(merges.begin(), merges.end());
  auto split_key = [&](std::uint32_t e) { return front.priority(e, camera); };
  auto merge_key = [&](std::uint32_t e) {
    return (front.result(e) & kInView) ? front.priority(e, camera) : -1.0f;
  };
  // The nodes a change made or freed go (back) in the queues they now belong to.
  touched_nodes_.clear();
  auto queue_touched = [&] {
    for (const std::uint32_t n : touched_nodes_) {
      const std::uint32_t e = nodes[n].entry();
      if (e == kNoEntry) continue;
      if (nodes[n].leaf()) {
        if (!front.split(e) && (front.result(e) & kActive)) {
          splits.push_back({split_key(e), n});
          std::push_heap(splits.begin(), splits.end());
        }
      } else if (front.split(e) && (cap == 0 || front.radius(e) < Front::kBorderRadius)) {
        merges.push_back({-merge_key(e), n});
        std::push_heap(merges.begin(), merges.end());
      }
    }
    touched_nodes_.clear();
  };
  // The queues' tops, once stale items (changed since they were queued) are dropped.
  auto top_split = [&]() -> const QueueItem* {
    while (!splits.empty() && !r.split_candidate(splits.front().second)) {
      std::pop_heap(splits.begin(), splits.end());
      splits.pop_back();
    }
    return splits.empty() ? nullptr : &splits.front();
  };
  auto top_merge = [&]() -> const QueueItem* {
    while (!merges.empty()) {
      const std::uint32_t n = merges.front().second;
      if (!nodes[n].leaf() && nodes[n].entry() != kNoEntry && front.split(nodes[n].entry()) &&
          r.mergeable(n))
        break;
      std::pop_heap(merges.begin(), merges.end());
      merges.pop_back();
    }
    return merges.empty() ? nullptr : &merges.front();
  };
  auto merge_top = [&] {
    const std::uint32_t n = merges.front().second;
    std::pop_heap(merges.begin(), merges.end());
    merges.pop_back();
    r.merge(n, nullptr);
    // The merged diamond may split again later (a trade back); its parents may merge next.
    touched_nodes_.push_back(n);
    const std::uint32_t w = nodes[n].base();
    for (const std::uint32_t p : {nodes[n].parent, w != kNone ? nodes[linked_node(w)].parent : kNone})
      if (p != kNone) touched_nodes_.push_back(p);
    queue_touched();
  };
  auto split_top = [&](std::uint32_t n) {
    std::pop_heap(splits.begin(), splits.end());
    splits.pop_back();
    if (!r.split(n, false, &touched_nodes_)) {
      ++stats.pending_splits;
    } else {
      // The split diamond is mergeable now; its children may split next.
      touched_nodes_.push_back(n);
      for (std::uint32_t k = 0; k < 2; ++k) touched_nodes_.push_back(nodes[n].first_child() + k);
      if (nodes[n].base() != kNone)
        for (std::uint32_t k = 0; k < 2; ++k)
          touched_nodes_.push_back(nodes[linked_node(nodes[n].base())].first_child() + k);
    }
    queue_touched();
  };
  // A merge the test asks for: the lowest-priority mergeable diamond, failing its test.
  auto merge_due = [&](const QueueItem* m) {
    return m != nullptr && -m->first <= threshold &&
           !(front.result(nodes[m->second].entry()) & kActive);
  };

  std::uint64_t operations = 0;
  bool merge_turn = false;
  const std::uint32_t splits_before = stats.splits, merges_before = stats.merges;
  for (;;) {
    if (++operations > 16ull * (r.triangles() + 4096)) break;  // a safety net against a trade cycle
    if (deadline.out_of_time()) {
      stats.stop = StopReason::kTimeBudget;
      break;
    }
    const QueueItem* s = top_split();
    const QueueItem* m = top_merge();
    if (cap != 0 && r.triangles() > cap) {  // a mesh above a lowered cap: merge down first
      if (m == nullptr) break;
      merge_top();
      continue;
    }
    // Under a time budget a merge the test asks for goes first every other operation: splits
    // alone would take the whole budget while the camera moves, and the mesh would keep every
    // triangle it no longer needs. Under a cap it always goes first.
    merge_turn = !merge_turn;
    if (merge_due(m) && (s == nullptr || merge_turn || cap != 0)) {
      merge_top();
      continue;
    }
    if (s != nullptr) {
      const std::uint32_t n = s->second;
      // A split on the data's border is forced: it goes past the cap (docs/roam.md).
      const bool border = front.radius(nodes[n].entry()) >= Front::kBorderRadius;
      if (cap != 0 && !border && r.triangles() + r.split_cost(n) > cap) {
        // Trade a lower-priority diamond for this split, unless it is the leaf's own parent.
        if (m != nullptr && -m->first < s->first && m->second != nodes[n].parent &&
            linked_node(nodes[m->second].base()) != nodes[n].parent) {
          merge_top();
          continue;
        }
        stats.stop = StopReason::kTriangleBudget;
        break;
      }
      split_top(n);
      continue;
    }
    if (merge_due(m)) {
      merge_top();
      continue;
    }
    break;
  }
  // What stays unsplit in view: the splits left in the queue (active), and the tests that failed
  // (worst_failing(): this update's pass and every diamond tested since).
  const QueueItem* s = top_split();
  const float left = std::max({r.worst_failing(), s ? s->first : 0.0f, held_back});
  last_operations_ = (stats.splits - splits_before) + (stats.merges - merges_before);
  // Under a cap, the splits that end the mesh on the data's border or a hole's edge are forced, as crack fixes
  // are: every one the cap held back is made now, past the cap (docs/roam.md).
  if (cap != 0 && r.may_hide() && !deadline.out_of_time()) r.split_border_diamonds(scratch);
  return left;
}

}  // namespace ridgeline::roam
