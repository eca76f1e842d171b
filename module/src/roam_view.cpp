// Frame-coherent ROAM after Duchaineau et al. 1997 ("ROAMing Terrain"): bintree forest with
// diamonds and forced splits (section 4), split and merge queues (section 5), deferred priority
// recomputation (section 6). The split-only rebuild mode is Turner 2000.
//
// Lazy priorities. A queued node's key is the LARGEST priority it can take while the eye stays
// within a window w of the point where it was computed (d: distance to the node's bounding box):
// bound * K / (d - w), w = max(slack * d, half the way to where the priority would equal the
// threshold). Both queues are keyed by this upper bound and decisions compare it with the
// threshold, so split and merge use one function (no oscillation) and every triangle left
// unsplit truly meets the threshold for any eye position in its window. The key is recomputed
// when the eye's odometer has advanced by w (conservative for any path). A node classified
// outside the frustum gets priority 0 (it is merged back towards its root), valid while
// translation and rotation cannot bring it inside: it carries an angular expiry too. Nodes near
// the frustum border count as inside (conservative); visible nodes are re-checked once the view
// may have turned enough to lose them. A change of field of view, viewport or far plane makes
// every key due, a threshold rise makes the merge keys due (their windows were sized for the
// lower threshold); due keys are recomputed within the time budget, the rest next update.
#include "ridgeline/roam_view.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <deque>
#include <glm/geometric.hpp>
#include <limits>
#include <new>
#include <queue>
#include <type_traits>
#include <unordered_map>

#include "format.h"
#include "ridgeline/detail.h"
#include "ridgeline/mesh_error.h"
#include "ridgeline/log.h"
#include "surface_eval.h"

namespace ridgeline {

namespace {

constexpr std::uint32_t kNone = 0xffffffffu;
constexpr float kInf = std::numeric_limits<float>::infinity();
// How much of the way to the threshold crossing a priority window spans (see priority()): for
// a node below the threshold (the key stays below it for any fraction < 1: the larger, the
// fewer recomputations as the eye approaches; 0.9 needs ~log10 instead of ~log2 of them), and
// for a node above it (split soon anyway; a smaller window keeps the keys that order splits
// under a budget finite and meaningful).
constexpr double kWindowBelow = 0.9;
constexpr double kWindowAbove = 0.5;
// Deepest level the hierarchical culling pass tracks (see refresh_culling()).
constexpr std::uint32_t kCullDepth = 4;

struct Node {
  std::uint32_t parent = kNone;
  std::uint32_t child = kNone;  // first of the pair (child, child + 1); kNone for a leaf
  std::uint32_t base = kNone, left = kNone, right = kNone;
  std::uint32_t qslot = kNone;  // position in the split heap (leaf) or merge heap (internal)
  std::uint32_t root : 31 = 0;
  std::uint32_t visible : 1 = 1;  // in view at the last culling pass (levels <= kCullDepth)
  // When the node's key must be recomputed: eye odometer (metres) and accumulated rotation
  // (radians), rounded down to float; infinity when it never expires that way. An expiry record
  // whose key rounds to a different value is stale.
  float due_d = std::numeric_limits<float>::infinity();
  std::uint64_t heap = 1;  // path from the root, one bit per level (64 bits: detail levels)
  float due_a = std::numeric_limits<float>::infinity();
  std::int32_t ax = 0, az = 0;  // apex in global finest-lattice coordinates (geometry in O(1))
  // Cached at creation so a priority reads no height or bound arrays (cache misses dominated):
  float bound = 0;         // nested error bound, metres
  float ylo = 0, yhi = 0;  // bounding box y range relative to the height offset, metres
};

static_assert(sizeof(Node) == 64, "docs/architecture.md and docs/roam.md quote the node size");

// Node storage in fixed chunks: growing never moves nodes. A contiguous vector doubled by
// copying the whole pool (10+ MB at 60k triangles) inside one update, with fresh pages to
// fault in: 5-15 ms spikes under a 0.5-2 ms time budget (`ridge bench lod --budget-ms`).
class NodePool {
 public:
  Node& operator[](std::uint32_t i) noexcept { return chunks_[i >> kShift].get()[i & kMask]; }
  const Node& operator[](std::uint32_t i) const noexcept {
    return chunks_[i >> kShift].get()[i & kMask];
  }
  std::uint32_t size() const noexcept { return size_; }
  // Appends `count` default nodes (count divides the chunk size). A new chunk is raw memory:
  // nodes are constructed as they are handed out, so its pages are faulted in a few at a time
  // (value-initialising all 16k nodes at once cost ~0.3 ms inside one update: the spikes over
  // a 0.5 ms budget every 16k nodes on the zoom and fast-pass paths).
  void grow(std::uint32_t count) {
    if (((size_ + count - 1) >> kShift) >= chunks_.size())
      chunks_.emplace_back(static_cast<Node*>(::operator new(sizeof(Node) << kShift)));
    for (std::uint32_t k = 0; k < count; ++k) ::new (&(*this)[size_ + k]) Node{};
    size_ += count;
  }
  // `count` default nodes; keeps the chunks (a rebuild reuses them without faulting pages in).
  void assign(std::uint32_t count) {
    size_ = 0;
    while (size_ < count) grow(std::min<std::uint32_t>(2, count - size_));
  }
  std::size_t memory_bytes() const noexcept {
    return chunks_.size() * (sizeof(Node) << kShift) +
           chunks_.capacity() * sizeof(chunks_[0]);
  }

 private:
  static constexpr std::uint32_t kShift = 14;  // 16k nodes, 1 MiB per chunk
  static constexpr std::uint32_t kMask = (1u << kShift) - 1;
  static_assert(std::is_trivially_destructible_v<Node>, "chunks are freed without destructors");
  struct FreeChunk {
    void operator()(Node* p) const noexcept { ::operator delete(p); }
  };
  std::vector<std::unique_ptr<Node, FreeChunk>> chunks_;
  std::uint32_t size_ = 0;
};

struct HeapEntry {
  float key;
  std::uint32_t node;
};

// Binary heap of nodes with positions written back into Node::qslot, so keys can change and
// entries can leave from the middle in O(log n). Max-heap when kMax.
template <bool kMax>
class IndexedHeap {
 public:
  explicit IndexedHeap(NodePool& nodes) : nodes_(&nodes) {}
  bool empty() const { return a_.empty(); }
  std::size_t size() const { return a_.size(); }
  const HeapEntry& top() const { return a_.front(); }
  void clear() {
    for (auto& e : a_) leave(e.node);
    a_.clear();
  }
  void push(std::uint32_t node, float key) {
    a_.push_back({key, node});
    (*nodes_)[node].qslot = static_cast<std::uint32_t>(a_.size() - 1);
    up(a_.size() - 1);
  }
  void remove(std::uint32_t node) {
    const std::uint32_t i = (*nodes_)[node].qslot;
    if (i == kNone) return;
    leave(node);
    const std::size_t last = a_.size() - 1;
    if (i != last) {
      a_[i] = a_[last];
      (*nodes_)[a_[i].node].qslot = i;
      a_.pop_back();
      if (!up(i)) down(i);
    } else {
      a_.pop_back();
    }
  }
  void update(std::uint32_t node, float key) {
    const std::uint32_t i = (*nodes_)[node].qslot;
    a_[i].key = key;
    if (!up(i)) down(i);
  }
  const std::vector<HeapEntry>& entries() const { return a_; }
  // Multiplies every key by r > 0: the order is kept, so no entry moves.
  void scale_keys(float r) {
    for (auto& e : a_) e.key *= r;
  }
  float key_of(std::uint32_t node) const { return a_[(*nodes_)[node].qslot].key; }
  std::size_t memory_bytes() const { return a_.capacity() * sizeof(HeapEntry); }

 private:
  static bool before(float a, float b) { return kMax ? a > b : a < b; }
  // A node leaving its queue forgets its expiry: its records turn stale, and when it is queued
  // again it gets new ones.
  void leave(std::uint32_t node) {
    Node& n = (*nodes_)[node];
    n.qslot = kNone;
    n.due_d = n.due_a = std::numeric_limits<float>::infinity();
  }
  bool up(std::size_t i) {
    bool moved = false;
    while (i > 0) {
      const std::size_t p = (i - 1) / 2;
      if (!before(a_[i].key, a_[p].key)) break;
      swap(i, p);
      i = p;
      moved = true;
    }
    return moved;
  }
  void down(std::size_t i) {
    const std::size_t n = a_.size();
    for (;;) {
      std::size_t best = i;
      const std::size_t l = 2 * i + 1, r = l + 1;
      if (l < n && before(a_[l].key, a_[best].key)) best = l;
      if (r < n && before(a_[r].key, a_[best].key)) best = r;
      if (best == i) return;
      swap(i, best);
      i = best;
    }
  }
  void swap(std::size_t i, std::size_t j) {
    std::swap(a_[i], a_[j]);
    (*nodes_)[a_[i].node].qslot = static_cast<std::uint32_t>(i);
    (*nodes_)[a_[j].node].qslot = static_cast<std::uint32_t>(j);
  }
  NodePool* nodes_;
  std::vector<HeapEntry> a_;
};

struct Expiry {
  double key;
  std::uint32_t node;
  bool operator>(const Expiry& o) const { return key > o.key; }
};

// Expiry records on a timing wheel over a monotone "clock" (the eye's odometer in metres, or its
// accumulated rotation in radians): O(1) push and pop, where a binary heap cost ~16 levels per
// record. Keys beyond the wheel's horizon wait in a small heap until the wheel reaches them.
class ExpiryWheel {
 public:
  explicit ExpiryWheel(double width) : inv_width_(1.0 / width), ring_(kBuckets) {}
  // Empties the wheel and sets its clock to `now`.
  void clear(double now) {
    for (auto& b : ring_) b.clear();
    overflow_ = {};
    size_ = 0;
    cursor_ = bucket(now);
    sweep_pos_ = 0;
  }
  std::size_t size() const { return size_; }
  void push(double key, std::uint32_t node) {
    const std::uint64_t b = bucket(key);
    ++size_;
    if (b < cursor_ + kBuckets)
      ring_[std::max(b, cursor_) % kBuckets].push_back({key, node});
    else
      overflow_.push({key, node});
  }
  // Calls fn(node, key) for every record with key <= now; stops early when fn returns false.
  template <class Fn>
  bool drain(double now, Fn&& fn) {
    const std::uint64_t target = bucket(now);
    const std::uint64_t last = std::min(target, cursor_ + kBuckets - 1);
    for (std::uint64_t b = cursor_; b <= last; ++b) {
      std::vector<Expiry>& v = ring_[b % kBuckets];
      if (!drain_bucket(v, now, fn)) return false;
      trim(v);
    }
    cursor_ = std::max(cursor_, target > cursor_ + kBuckets - 1 ? target : last);
    // Records whose buckets the ring now reaches come in from the overflow heap.
    while (!overflow_.empty() && bucket(overflow_.top().key) < cursor_ + kBuckets) {
      const Expiry e = overflow_.top();
      overflow_.pop();
      ring_[std::max(bucket(e.key), cursor_) % kBuckets].push_back(e);
    }
    // A jump past the horizon (teleport) may leave due records in the ring's current bucket.
    if (target >= cursor_) return drain_bucket(ring_[cursor_ % kBuckets], now, fn);
    return true;
  }

  // Drops the records for which live(node, key) is false (stale ones), in O(records).
  template <class Live>
  void compact(Live&& live) {
    size_ = 0;
    for (auto& v : ring_) {
      std::size_t keep = 0;
      for (const Expiry& e : v)
        if (live(e.node, e.key)) v[keep++] = e;
      v.resize(keep);
      size_ += keep;
    }
    std::vector<Expiry> rest;
    while (!overflow_.empty()) {
      if (live(overflow_.top().node, overflow_.top().key)) rest.push_back(overflow_.top());
      overflow_.pop();
    }
    for (const Expiry& e : rest) overflow_.push(e);
    size_ += rest.size();
  }

  // Drops stale records, looking at no more than `budget` records per call, round robin over the
  // ring: spreads the clean-up over updates so that no single update pays for it.
  template <class Live>
  void compact_some(Live&& live, std::size_t budget) {
    for (std::size_t visited = 0; budget > 0 && visited <= kBuckets; ++visited) {
      std::vector<Expiry>& v = ring_[sweep_bucket_ % kBuckets];
      sweep_pos_ = std::min(sweep_pos_, v.size());  // the bucket may have shrunk since
      const std::size_t end = std::min(v.size(), sweep_pos_ + budget);
      std::size_t w = sweep_pos_;
      for (std::size_t k = sweep_pos_; k < end; ++k)
        if (live(v[k].node, v[k].key)) v[w++] = v[k];
      v.erase(v.begin() + static_cast<std::ptrdiff_t>(w),
              v.begin() + static_cast<std::ptrdiff_t>(end));
      size_ -= end - w;
      budget -= end - sweep_pos_;
      sweep_pos_ = w;
      if (sweep_pos_ >= v.size()) {
        trim(v);
        ++sweep_bucket_;
        sweep_pos_ = 0;
      }
    }
  }

  std::size_t memory_bytes() const {
    std::size_t b = ring_.capacity() * sizeof(std::vector<Expiry>);
    for (const auto& v : ring_) b += v.capacity() * sizeof(Expiry);
    return b + overflow_.size() * sizeof(Expiry);
  }

 private:
  static constexpr std::uint64_t kBuckets = 2048;
  // Gives back a bucket's spare capacity once it is mostly empty, so memory follows the records
  // held rather than the largest burst a bucket ever saw.
  static void trim(std::vector<Expiry>& v) {
    if (v.capacity() > 64 && v.capacity() > 4 * v.size()) std::vector<Expiry>(v).swap(v);
  }
  // Consumes the due records of one bucket, keeping the others in order; on an early stop keeps
  // the records not yet looked at and drops the ones consumed.
  template <class Fn>
  bool drain_bucket(std::vector<Expiry>& v, double now, Fn&& fn) {
    std::size_t keep = 0;
    for (std::size_t k = 0; k < v.size(); ++k) {
      if (v[k].key <= now) {
        --size_;
        if (!fn(v[k].node, v[k].key)) {
          v.erase(v.begin() + static_cast<std::ptrdiff_t>(keep),
                  v.begin() + static_cast<std::ptrdiff_t>(k + 1));
          return false;
        }
      } else {
        v[keep++] = v[k];
      }
    }
    v.resize(keep);
    return true;
  }
  std::uint64_t bucket(double key) const {
    // Keys beyond 2^63 buckets (heights near FLT_MAX give such expiry times) clamp instead of
    // overflowing the conversion (undefined behaviour, caught by UBSan); NaN goes to bucket 0.
    const double b = key * inv_width_;  // monotone in key, like the division it replaces
    if (!(b > 0.0)) return 0;
    return b >= 9.2e18 ? std::uint64_t{1} << 63 : static_cast<std::uint64_t>(b);
  }
  double inv_width_;
  std::vector<std::vector<Expiry>> ring_;
  std::priority_queue<Expiry, std::vector<Expiry>, std::greater<Expiry>> overflow_;
  std::size_t size_ = 0;
  std::uint64_t cursor_ = 0;
  std::uint64_t sweep_bucket_ = 0;
  std::size_t sweep_pos_ = 0;
};

struct Validity {
  double distance = std::numeric_limits<double>::infinity();  // eye travel allowed, metres
  double angle = std::numeric_limits<double>::infinity();     // view rotation allowed, radians
};

// Orthonormal camera frame.
struct Frame {
  glm::dvec3 f, r, u;
};

Frame frame_of(const Camera& c) {
  Frame fr;
  fr.f = glm::normalize(c.target - c.eye);
  fr.r = glm::normalize(glm::cross(fr.f, c.up));
  fr.u = glm::cross(fr.r, fr.f);
  return fr;
}

// Rotation angle between two orthonormal frames.
double frame_angle(const Frame& a, const Frame& b) {
  const double tr = glm::dot(a.f, b.f) + glm::dot(a.r, b.r) + glm::dot(a.u, b.u);
  return std::acos(std::clamp((tr - 1.0) / 2.0, -1.0, 1.0));
}

}  // namespace

struct RoamView::Impl {
  explicit Impl(const Landscape& l) : land(l), split(nodes), merge(nodes) {}

  const Landscape& land;
  NodePool nodes;
  std::vector<std::uint32_t> free_pairs;
  IndexedHeap<true> split;
  IndexedHeap<false> merge;
  ExpiryWheel by_distance{0.25}, by_angle{0.001};

  // Camera state.
  bool have_camera = false;
  Camera cam;
  Frame frame{};
  double K = 1;
  glm::dvec3 planes[4];  // inward normals of the side planes, through the eye
  double odometer = 0, angometer = 0;
  bool zoomed = false;  // the field of view or viewport changed in this update

  // Settings snapshot used by priorities.
  ErrorMetric metric = ErrorMetric::kScreenPixels;
  double slack = 0.05;
  double threshold = 2.0;        // used only to size priority windows
  double window_below = kWindowBelow;  // window fraction below it (see kWindowBelow)
  // Under a triangle cap: the priority level at which the last capped update stopped (the
  // largest key left in the split queue); windows are sized around it instead of the threshold.
  double capped_level = 0.0;
  double keyed_threshold = 0.0;  // threshold of the previous update
  double height_offset = land.terrain().heightfield().height_offset();
  bool reset_pending = true;
  std::uint64_t seen_version = 0;  // the terrain edit version this view's nodes reflect

  // Output.
  std::vector<std::uint64_t> patch_version;
  std::vector<std::uint8_t> patch_dirty;  // listed in dirty_list since last take
  std::vector<std::uint32_t> dirty_list;
  std::vector<PatchMesh> meshes;
  std::vector<std::uint64_t> mesh_built_version;
  std::vector<std::uint32_t> scratch_index;

  // Procedural detail: the terrain's tile cache (null without detail), and the leaves whose
  // split waits for a tile (held at the coarser level; re-queued at the next update).
  DetailCache* cache = land.terrain().detail_cache();
  std::vector<std::uint32_t> waiting;

  // Keys due whose recomputation did not fit in a time budget (see refresh_expired()).
  enum class Clock : std::uint8_t { kDistance, kAngle, kForced };
  struct Due {
    std::uint32_t node;
    float key;    // the due time of the record (stale when the node's due time differs)
    Clock clock;  // kForced: made due by a threshold or far-plane change (live while queued)
  };
  bool live(const Due& b) const {
    switch (b.clock) {
      case Clock::kDistance: return live_distance(b.node, b.key);
      case Clock::kAngle: return live_angle(b.node, b.key);
      case Clock::kForced: break;
    }
    return nodes[b.node].qslot != kNone;
  }
  std::deque<Due> backlog;
  // Round-robin position and scratch of the culling pass (see refresh_culling()).
  std::uint32_t cull_cursor = 0;
  std::vector<std::uint32_t> cull_stack;

  // Per-update counters and the time budget.
  RoamStats st;
  bool has_deadline = false;
  std::chrono::steady_clock::time_point deadline;
  std::uint32_t time_checks = 0;
  std::uint32_t triangles = 0;

  // ---- structure ---------------------------------------------------------------------------

  bool is_leaf(std::uint32_t n) const { return nodes[n].child == kNone; }
  std::uint32_t level(std::uint32_t n) const { return 63 - __builtin_clzll(nodes[n].heap); }
  bool splittable(std::uint32_t n) const { return level(n) < land.max_level(); }

  void mark_dirty(std::uint32_t n) {
    const std::uint32_t p = nodes[n].root / 2;
    ++patch_version[p];
    if (!patch_dirty[p]) {
      patch_dirty[p] = 1;
      dirty_list.push_back(p);
    }
  }

  std::uint32_t alloc_pair() {
    if (!free_pairs.empty()) {
      const std::uint32_t c = free_pairs.back();
      free_pairs.pop_back();
      return c;
    }
    const std::uint32_t c = nodes.size();
    nodes.grow(2);
    return c;
  }

  void replace_link(std::uint32_t n, std::uint32_t from, std::uint32_t to) {
    if (n == kNone) return;
    Node& x = nodes[n];
    if (x.base == from)
      x.base = to;
    else if (x.left == from)
      x.left = to;
    else if (x.right == from)
      x.right = to;
    else
      RIDGELINE_ASSERT(false && "neighbour link not found");
  }

  void reset_to_roots() {
    waiting.clear();
    backlog.clear();
    split.clear();
    merge.clear();
    by_distance.clear(odometer);
    by_angle.clear(angometer);
    free_pairs.clear();
    const std::uint32_t px = land.patches_x(), pz = land.patches_z();
    nodes.assign(land.root_count());
    for (std::uint32_t z = 0; z < pz; ++z) {
      for (std::uint32_t x = 0; x < px; ++x) {
        const std::uint32_t p = x + z * px;
        Node& r0 = nodes[2 * p];
        Node& r1 = nodes[2 * p + 1];
        r0.root = 2 * p;
        r1.root = 2 * p + 1;
        const LatticeTriangle t0 = land.triangle(2 * p, 1), t1 = land.triangle(2 * p + 1, 1);
        r0.ax = static_cast<std::int32_t>(t0.ax);
        r0.az = static_cast<std::int32_t>(t0.az);
        r1.ax = static_cast<std::int32_t>(t1.ax);
        r1.az = static_cast<std::int32_t>(t1.az);
        cache_box(2 * p);
        cache_box(2 * p + 1);
        r0.base = 2 * p + 1;
        r1.base = 2 * p;
        // root 0: apex (P, 0), left edge z = 0 (towards -z), right edge x = P (towards +x)
        r0.left = z > 0 ? 2 * (p - px) + 1 : kNone;
        r0.right = x + 1 < px ? 2 * (p + 1) + 1 : kNone;
        // root 1: apex (0, P), left edge z = P (towards +z), right edge x = 0 (towards -x)
        r1.left = z + 1 < pz ? 2 * (p + px) : kNone;
        r1.right = x > 0 ? 2 * (p - 1) : kNone;
      }
    }
    triangles = land.root_count();
    for (std::uint32_t n = 0; n < land.root_count(); ++n) push_split(n);
    for (std::uint32_t p = 0; p < land.patch_count(); ++p) mark_dirty(2 * p);
    st.rebuilt = true;
  }

  // ---- priorities ---------------------------------------------------------------------------

  float priority(std::uint32_t n, Validity& v) {
    ++st.priority_updates;
    const Node& nd = nodes[n];
    const float b = nd.bound;
    v = Validity{};
    if (metric == ErrorMetric::kWorldMetres || b == 0.0f) return b;
    const Landscape::LatticeBox bx = land.box_at(nd.ax, nd.az, nd.root, nd.heap);
    const double off = height_offset;
    const glm::dvec3 lo(land.world_x(bx.i0), off + double(nd.ylo), land.world_z(bx.j0));
    const glm::dvec3 hi(land.world_x(bx.i1), off + double(nd.yhi), land.world_z(bx.j1));
    const glm::dvec3 e = cam.eye;
    const glm::dvec3 nearest = glm::clamp(e, lo, hi);
    const double d = glm::length(nearest - e);
    const double r = slack * d;
    // Far plane, as a sphere: outside while the eye cannot get within far of the box.
    if (d - r > cam.far_m) {
      v.distance = d - cam.far_m;
      return 0.0f;
    }
    // Window: at least slack * d; wider when the node is far from the threshold either way
    // (a fraction of the way to the distance at which its priority would equal the threshold),
    // so nodes that are clearly fine or clearly too coarse are not recomputed every frame. The
    // key stays below the threshold if the node was below it (and above if above), so decisions
    // only ever err on the side of more detail.
    double window = r;
    if (threshold > 0.0) {
      const double gap = d - double(b) * K / threshold;  // > 0: below the threshold
      window = std::max(window, (gap > 0.0 ? window_below : kWindowAbove) * std::abs(gap));
    }
    const double dd = d - window;
    const float key = dd <= 0.0 ? kInf : static_cast<float>(double(b) * K / dd);
    // Lazy culling: a key at or below the threshold decides the same in view or out of it (no
    // split; mergeable), so the frustum is tested only for nodes that would split in view. Their
    // out-of-view key (0) then holds while translation and rotation cannot bring them inside.
    if (key > threshold) {
      // Side planes. The box is outside a plane by margin m (metres) when its most inward
      // corner is m behind it; the classification holds while translation + rotation * reach
      // < m.
      const glm::dvec3 c = 0.5 * (lo + hi) - e, he = 0.5 * (hi - lo);
      double margin = 0.0;
      for (const glm::dvec3& pn : planes) {
        const double s_max = glm::dot(pn, c) + std::abs(pn.x) * he.x + std::abs(pn.y) * he.y +
                             std::abs(pn.z) * he.z;
        margin = std::max(margin, -s_max);
      }
      if (margin > r && margin > 0.0) {
        const double reach = std::max(glm::length(c) + glm::length(he), 1e-9);
        v.distance = 0.5 * margin;
        v.angle = 0.5 * margin / reach;
        return 0.0f;
      }
    }
    // Counting a node as visible is always conservative; nodes that turn out of view are
    // re-keyed when an ancestor leaves the view (refresh_culling()).
    v.distance = window;
    return key;
  }

  // Largest float not above x: due times round down, so a key is recomputed early, never late.
  static float floor_float(double x) {
    float f = static_cast<float>(x);
    if (double(f) > x) {  // one float step down (the bit pattern's neighbour; no libm call)
      if (f > 0.0f && std::isfinite(f))
        f = std::bit_cast<float>(std::bit_cast<std::uint32_t>(f) - 1u);
      else
        f = std::nextafter(f, -std::numeric_limits<float>::infinity());
    }
    return f;
  }

  // Schedules the recomputation of n's key. A record already due no later is kept (the node is
  // then recomputed early, which is safe); otherwise a new record replaces it, and the old one
  // turns stale.
  void push_records(std::uint32_t n, const Validity& v) {
    Node& nd = nodes[n];
    if (std::isfinite(v.distance)) {
      const float due = floor_float(odometer + v.distance);
      if (!(nd.due_d <= due)) {
        nd.due_d = due;
        by_distance.push(due, n);
      }
    }
    if (std::isfinite(v.angle)) {
      const float due = floor_float(angometer + v.angle);
      if (!(nd.due_a <= due)) {
        nd.due_a = due;
        by_angle.push(due, n);
      }
    }
  }

  bool live_distance(std::uint32_t n, double key) const {
    return nodes[n].qslot != kNone && float(key) == nodes[n].due_d;
  }
  bool live_angle(std::uint32_t n, double key) const {
    return nodes[n].qslot != kNone && float(key) == nodes[n].due_a;
  }

  void push_split(std::uint32_t n) {
    if (!splittable(n)) return;
    Validity v;
    const float p = priority(n, v);
    split.push(n, p);
    push_records(n, v);
  }

  // Representative node of the diamond of internal node n.
  std::uint32_t rep_of(std::uint32_t n) const {
    const std::uint32_t b = nodes[n].base;
    return (b == kNone || n < b) ? n : b;
  }

  bool children_are_leaves(std::uint32_t n) const {
    const std::uint32_t c = nodes[n].child;
    return c != kNone && is_leaf(c) && is_leaf(c + 1);
  }

  bool mergeable(std::uint32_t n) const {
    if (!children_are_leaves(n)) return false;
    const std::uint32_t b = nodes[n].base;
    return b == kNone || (nodes[b].base == n && children_are_leaves(b));
  }

  float diamond_priority(std::uint32_t rep, Validity& v) {
    float p = priority(rep, v);
    const std::uint32_t b = nodes[rep].base;
    if (b != kNone) {
      Validity vb;
      p = std::max(p, priority(b, vb));
      v.distance = std::min(v.distance, vb.distance);
      v.angle = std::min(v.angle, vb.angle);
    }
    return p;
  }

  // Puts the diamond of internal node n in the merge queue if it is mergeable, takes it out if
  // it is not.
  void refresh_merge(std::uint32_t n) {
    if (n == kNone || is_leaf(n)) return;
    const std::uint32_t rep = rep_of(n);
    const bool in = nodes[rep].qslot != kNone;
    if (mergeable(n)) {
      if (!in) {
        Validity v;
        const float p = diamond_priority(rep, v);
        merge.push(rep, p);
        push_records(rep, v);
      }
    } else if (in) {
      merge.remove(rep);
    }
  }

  // Recomputes the key of a queued node (split leaf or merge representative).
  void requeue(std::uint32_t n) {
    Validity v;
    if (is_leaf(n)) {
      const float p = priority(n, v);
      split.update(n, p);
    } else {
      const float p = diamond_priority(n, v);
      merge.update(n, p);
    }
    push_records(n, v);
  }

  // ---- split and merge ---------------------------------------------------------------------

  // Triangles a split of leaf n adds, counting the forced splits it needs.
  std::uint32_t split_cost(std::uint32_t n) const {
    std::uint32_t cost = 0;
    std::uint32_t x = n;
    for (;;) {
      const std::uint32_t b = nodes[x].base;
      if (b == kNone) return cost + 1;
      if (nodes[b].base == x) return cost + 2;
      cost += 2;
      x = b;
    }
  }

  // Caches a node's bound and bounding-box height range (the surface under the triangle lies
  // within [lowest corner - bound, highest corner + bound]).
  void cache_box(std::uint32_t n) {
    Node& nd = nodes[n];
    const LatticeTriangle t = land.triangle_at(nd.ax, nd.az, nd.root, nd.heap);
    nd.bound = land.bound(nd.root, nd.heap, t);
    const float ha = land.lattice_height(t.ax, t.az), hl = land.lattice_height(t.lx, t.lz),
                hr = land.lattice_height(t.rx, t.rz);
    nd.ylo = std::min({ha, hl, hr}) - nd.bound;
    nd.yhi = std::max({ha, hl, hr}) + nd.bound;
    // The culling pass tracks the upper levels; a new node starts with its current visibility.
    if (have_camera && level(n) <= kCullDepth) nd.visible = classify_node(n) != Cull::kOut;
  }

  void make_children(std::uint32_t n) {
    const std::uint32_t c = alloc_pair();
    Node& p = nodes[n];
    Node& c0 = nodes[c];
    Node& c1 = nodes[c + 1];
    c0 = Node{};
    c1 = Node{};
    c0.parent = c1.parent = n;
    c0.root = c1.root = p.root;
    c0.heap = 2 * p.heap;
    c1.heap = 2 * p.heap + 1;
    const LatticeTriangle t = land.triangle_at(p.ax, p.az, p.root, p.heap);
    c0.ax = c1.ax = static_cast<std::int32_t>((t.lx + t.rx) / 2);
    c0.az = c1.az = static_cast<std::int32_t>((t.lz + t.rz) / 2);
    p.child = c;
    cache_box(c);
    cache_box(c + 1);
  }

  // Links the children (c0, c1) of n among themselves, to n's outer neighbours (their bases,
  // updating those neighbours' links) and across n's hypotenuse: c0's right edge borders
  // `right_of_c0`, c1's left edge `left_of_c1` (the base partner's children, or kNone).
  void link_children(std::uint32_t n, std::uint32_t c0, std::uint32_t c1, std::uint32_t right_of_c0,
                     std::uint32_t left_of_c1) {
    const Node& p = nodes[n];
    nodes[c0].base = p.left;
    nodes[c0].left = c1;
    nodes[c0].right = right_of_c0;
    nodes[c1].base = p.right;
    nodes[c1].left = left_of_c1;
    nodes[c1].right = c0;
    replace_link(p.left, n, c0);
    replace_link(p.right, n, c1);
  }

  // True when the vertex a split of n creates (its hypotenuse midpoint) has its detail: a vertex
  // of the stored lattice, or one whose tile is resident (requested otherwise: no waiting).
  bool midpoint_ready(std::uint32_t n) {
    if (level(n) < land.base_level()) return true;
    const Node& nd = nodes[n];
    const LatticeTriangle t = land.triangle_at(nd.ax, nd.az, nd.root, nd.heap);
    const std::int64_t mx = std::clamp<std::int64_t>((t.lx + t.rx) / 2, 0, land.last_i());
    const std::int64_t mz = std::clamp<std::int64_t>((t.lz + t.rz) / 2, 0, land.last_j());
    const int L = int(land.detail_levels());
    const int z = std::min({mx ? __builtin_ctzll(std::uint64_t(mx)) : 64,
                            mz ? __builtin_ctzll(std::uint64_t(mz)) : 64, L});
    if (z == L) return true;  // a stored vertex
    const DetailTileKey key{std::uint32_t(L - z), std::int32_t((mx >> z) / kDetailTileCells),
                            std::int32_t((mz >> z) / kDetailTileCells)};
    return cache->request(key);
  }

  // True when every vertex that splitting leaf n (with its forced splits) creates has its detail.
  bool chain_ready(std::uint32_t n) {
    if (cache == nullptr) return true;
    bool ready = true;
    for (std::uint32_t x = n;;) {
      ready = midpoint_ready(x) && ready;  // request every missing tile of the chain at once
      const std::uint32_t b = nodes[x].base;
      if (b == kNone || nodes[b].base == x) break;
      x = b;
    }
    return ready;
  }

  // Takes leaf n out of the split queue until its tiles arrive.
  void park(std::uint32_t n) {
    split.remove(n);
    waiting.push_back(n);
  }

  // Re-queues the parked leaves that are still leaves (their tiles may have arrived).
  void unpark() {
    std::vector<std::uint32_t> w;
    w.swap(waiting);
    for (std::uint32_t n : w)
      if (n < nodes.size() && is_leaf(n) && nodes[n].qslot == kNone) push_split(n);
  }

  void split_leaf(std::uint32_t t, bool forced) {
    // Make the base neighbour a diamond partner first (forced splits), then split both.
    while (nodes[t].base != kNone && nodes[nodes[t].base].base != t)
      split_leaf(nodes[t].base, true);
    if (forced)
      ++st.forced_splits;
    else
      ++st.splits;
    const std::uint32_t b = nodes[t].base;
    // The leaves' keys become the new diamond's key (the same function, max over both nodes),
    // with the earlier of their expiries: no recomputation.
    float key = split.key_of(t);
    Validity v = due_validity(t);
    if (b != kNone) {
      key = std::max(key, split.key_of(b));
      const Validity vb = due_validity(b);
      v.distance = std::min(v.distance, vb.distance);
      v.angle = std::min(v.angle, vb.angle);
    }
    split.remove(t);
    make_children(t);
    const std::uint32_t t0 = nodes[t].child, t1 = t0 + 1;
    std::uint32_t b0 = kNone, b1 = kNone;
    if (b != kNone) {
      split.remove(b);
      make_children(b);
      b0 = nodes[b].child;
      b1 = b0 + 1;
    }
    link_children(t, t0, t1, b1, b0);
    if (b != kNone) link_children(b, b0, b1, t1, t0);
    triangles += b != kNone ? 2 : 1;
    mark_dirty(t);
    if (b != kNone) mark_dirty(b);
    // Queues: new leaves, the new diamond, and the parents' diamonds that stopped being mergeable.
    push_split(t0);
    push_split(t1);
    if (b != kNone) {
      push_split(b0);
      push_split(b1);
    }
    {
      const std::uint32_t rep = rep_of(t);
      merge.push(rep, key);
      push_records(rep, v);
    }
    if (nodes[t].parent != kNone) refresh_merge(nodes[t].parent);
    if (b != kNone && nodes[b].parent != kNone) refresh_merge(nodes[b].parent);
  }

  // The remaining validity of a queued node's key, from its due times.
  Validity due_validity(std::uint32_t n) const {
    Validity v;
    v.distance = std::max(0.0, double(nodes[n].due_d) - odometer);
    v.angle = std::max(0.0, double(nodes[n].due_a) - angometer);
    return v;
  }

  void merge_diamond(std::uint32_t rep) {
    ++st.merges;
    merge.remove(rep);
    const std::uint32_t t = rep, b = nodes[rep].base;
    auto collapse = [&](std::uint32_t n) {
      const std::uint32_t c0 = nodes[n].child, c1 = c0 + 1;
      nodes[n].left = nodes[c0].base;
      nodes[n].right = nodes[c1].base;
      replace_link(nodes[c0].base, c0, n);
      replace_link(nodes[c1].base, c1, n);
      split.remove(c0);
      split.remove(c1);
      nodes[n].child = kNone;
      free_pairs.push_back(c0);
      mark_dirty(n);
    };
    collapse(t);
    if (b != kNone) collapse(b);
    triangles -= b != kNone ? 2 : 1;
    push_split(t);
    if (b != kNone) push_split(b);
    if (nodes[t].parent != kNone) refresh_merge(nodes[t].parent);
    if (b != kNone && nodes[b].parent != kNone) refresh_merge(nodes[b].parent);
  }

  // ---- camera -------------------------------------------------------------------------------

  // Returns true when every key must be recomputed (projection or far plane changed).
  bool set_camera(const Camera& c) {
    const Frame fr = frame_of(c);
    bool all = !have_camera;
    if (have_camera) {
      odometer += glm::length(c.eye - cam.eye);
      angometer += frame_angle(frame, fr);
      all = c.far_m != cam.far_m;
      zoomed = !all && (c.fov_y_deg != cam.fov_y_deg || c.viewport != cam.viewport);
      if (zoomed) {
        // A zoom or a viewport change scales every priority by K'/K: every key (the largest
        // priority over its window) scales alike and stays an upper bound, and the queues keep
        // their order. A wider frustum can bring culled nodes into view: it counts as that much
        // rotation, so the culled keys whose angular margin it uses up come due.
        const float r = static_cast<float>(projection_scale(c) / K);
        split.scale_keys(r);
        merge.scale_keys(r);
        auto half_angles = [](const Camera& x) {
          const double tv = std::tan(x.fov_y_deg * 3.14159265358979323846 / 360.0);
          return std::pair{std::atan(tv), std::atan(tv * double(x.viewport.x) / x.viewport.y)};
        };
        const auto [v0, h0] = half_angles(cam);
        const auto [v1, h1] = half_angles(c);
        angometer += std::max({0.0, v1 - v0, h1 - h0});
      }
    }
    cam = c;
    frame = fr;
    have_camera = true;
    K = projection_scale(c);
    const double tv = std::tan(c.fov_y_deg * 3.14159265358979323846 / 360.0);
    const double th = tv * double(c.viewport.x) / double(c.viewport.y);
    planes[0] = glm::normalize(th * fr.f + fr.r);  // left
    planes[1] = glm::normalize(th * fr.f - fr.r);  // right
    planes[2] = glm::normalize(tv * fr.f + fr.u);  // bottom
    planes[3] = glm::normalize(tv * fr.f - fr.u);  // top
    return all;
  }

  // Makes every queued key due now (a projection change, or too many stale expiry records). The
  // keys are recomputed by refresh_expired(), within the time budget: what does not fit waits
  // for the next update, and the mesh keeps its shape meanwhile.
  void mark_all_due() {
    backlog.clear();
    for (const auto& e : split.entries()) backlog.push_back({e.node, 0.0f, Clock::kForced});
    for (const auto& e : merge.entries()) backlog.push_back({e.node, 0.0f, Clock::kForced});
  }

  enum class Cull : std::uint8_t { kOut, kPartial, kIn };

  // Classifies the box [lo, hi] (world) against the frustum's side planes and far distance.
  Cull classify_box(const glm::dvec3& lo, const glm::dvec3& hi) const {
    const glm::dvec3 c = 0.5 * (lo + hi) - cam.eye, he = 0.5 * (hi - lo);
    if (glm::length(glm::clamp(cam.eye, lo, hi) - cam.eye) > cam.far_m) return Cull::kOut;
    bool all_in = true;
    for (const glm::dvec3& pn : planes) {
      const double mid = glm::dot(pn, c);
      const double ext = std::abs(pn.x) * he.x + std::abs(pn.y) * he.y + std::abs(pn.z) * he.z;
      if (mid + ext < 0.0) return Cull::kOut;
      if (mid - ext < 0.0) all_in = false;
    }
    return all_in ? Cull::kIn : Cull::kPartial;
  }

  Cull classify_node(std::uint32_t n) const {
    const Node& nd = nodes[n];
    const Landscape::LatticeBox bx = land.box_at(nd.ax, nd.az, nd.root, nd.heap);
    const glm::dvec3 lo(land.world_x(bx.i0), height_offset + double(nd.ylo), land.world_z(bx.j0));
    const glm::dvec3 hi(land.world_x(bx.i1), height_offset + double(nd.yhi), land.world_z(bx.j1));
    return classify_box(lo, hi);
  }

  // Makes every queued key in n's subtree due.
  void rekey_subtree(std::uint32_t n, std::vector<std::uint32_t>& stack) {
    stack.push_back(n);
    while (!stack.empty()) {
      const std::uint32_t x = stack.back();
      stack.pop_back();
      Node& nd = nodes[x];
      if (nd.qslot != kNone) {
        nd.due_d = floor_float(odometer);
        by_distance.push(nd.due_d, x);
      }
      if (nd.child != kNone) {
        stack.push_back(nd.child);
        stack.push_back(nd.child + 1);
      }
    }
  }

  // Hierarchical culling (D97's IN / OUT / PARTIAL flags) over the upper levels of the trees:
  // nodes wholly in or out of view end the descent, so the cost follows the frustum's border.
  // A node that left the view has every queued key below it made due, so what turned out of
  // view is merged back (keys computed as visible stay conservative but would keep the detail).
  // Under a time budget the pass goes round robin over the roots and stops at `until`; the
  // next update resumes where it stopped. A root not yet re-checked keeps its old flags, which
  // only delays merging what left the view (more detail for a moment, never less).
  void refresh_culling(bool rekey = true, bool budgeted = false,
                       std::chrono::steady_clock::time_point until = {}) {
    std::vector<std::uint32_t>& stack = cull_stack;
    std::vector<std::uint32_t> sub;
    const std::uint32_t roots = land.root_count();
    if (cull_cursor >= roots) cull_cursor = 0;
    for (std::uint32_t k = 0; k < roots; ++k) {
      if (budgeted && (k & 7) == 7 && std::chrono::steady_clock::now() >= until) return;
      const std::uint32_t r = cull_cursor;
      cull_cursor = cull_cursor + 1 < roots ? cull_cursor + 1 : 0;
      stack.push_back(r);
      while (!stack.empty()) {
        const std::uint32_t n = stack.back();
        stack.pop_back();
        Node& nd = nodes[n];
        const Cull c = classify_node(n);
        const bool was = nd.visible != 0, now = c != Cull::kOut;
        nd.visible = now;
        if (was && !now && rekey) rekey_subtree(n, sub);
        if (c == Cull::kPartial && nd.child != kNone && level(n) < kCullDepth) {
          stack.push_back(nd.child);
          stack.push_back(nd.child + 1);
        }
      }
    }
  }

  void mark_merges_due() {
    for (const auto& e : merge.entries()) backlog.push_back({e.node, 0.0f, Clock::kForced});
  }

  // Time budget: true once the update's deadline has passed (the clock is read every 4th call:
  // a call is one split, merge or key recomputation, about a microsecond).
  bool out_of_time() {
    if (!has_deadline || (++time_checks & 3) != 0) return false;
    return std::chrono::steady_clock::now() >= deadline;
  }

  // An edit changed the lattice vertices in [i0, i1] x [j0, j1] (padding-extended by the
  // landscape): refresh every node whose triangle's box meets the region (bound, box, visibility),
  // requeue the queued ones, mark the patches whose vertices or vertex normals changed dirty.
  std::uint64_t on_edit(std::int64_t i0, std::int64_t j0, std::int64_t i1, std::int64_t j1) {
    const std::int64_t p = land.patch_cells();
    // Vertex normals read the samples one step around a vertex: one more sample for dirtiness.
    const std::int64_t di0 = i0 - 1, dj0 = j0 - 1, di1 = i1 + 1, dj1 = j1 + 1;
    auto patch_range = [&](std::int64_t a0, std::int64_t a1, std::uint32_t n, std::int64_t& lo,
                           std::int64_t& hi) {
      lo = std::max<std::int64_t>(0, (a0 + p - 1) / p - 1);
      if (a0 < 0) lo = 0;
      hi = std::min<std::int64_t>(std::int64_t(n) - 1, a1 / p);
    };
    std::int64_t px0, px1, pz0, pz1;
    patch_range(di0, di1, land.patches_x(), px0, px1);
    patch_range(dj0, dj1, land.patches_z(), pz0, pz1);
    for (std::int64_t pz = pz0; pz <= pz1; ++pz)
      for (std::int64_t px = px0; px <= px1; ++px)
        mark_dirty(static_cast<std::uint32_t>(2 * (px + pz * land.patches_x())));
    if (reset_pending) return 0;  // the next update starts from the roots with fresh data
    std::uint64_t refreshed = 0;
    std::vector<std::uint32_t> stack;
    patch_range(i0, i1, land.patches_x(), px0, px1);
    patch_range(j0, j1, land.patches_z(), pz0, pz1);
    for (std::int64_t pz = pz0; pz <= pz1; ++pz) {
      for (std::int64_t px = px0; px <= px1; ++px) {
        for (std::uint32_t r = 0; r < 2; ++r) {
          stack.push_back(static_cast<std::uint32_t>(2 * (px + pz * land.patches_x()) + r));
          while (!stack.empty()) {
            const std::uint32_t n = stack.back();
            stack.pop_back();
            const Node& nd = nodes[n];
            const Landscape::LatticeBox bx = land.box_at(nd.ax, nd.az, nd.root, nd.heap);
            if (bx.i1 < i0 || bx.i0 > i1 || bx.j1 < j0 || bx.j0 > j1) continue;
            cache_box(n);
            ++refreshed;
            if (is_leaf(n)) {
              if (nodes[n].qslot != kNone) requeue(n);
            } else {
              const std::uint32_t rep = rep_of(n);
              if (nodes[rep].qslot != kNone) requeue(rep);
              stack.push_back(nodes[n].child);
              stack.push_back(nodes[n].child + 1);
            }
          }
        }
      }
    }
    return refreshed;
  }

  // Refreshes the nodes over every change since the last pull (the landscape synced first).
  void pull_edits() {
    const TerrainChanges c = land.terrain().changes_since(seen_version);
    for (const TerrainChange& ch : c.changes) {
      const Landscape::LatticeBox b = land.changed_box(ch);
      on_edit(b.i0, b.j0, b.i1, b.j1);
    }
    seen_version = c.version;
  }

  enum class Refresh { kDone, kRebuild, kOutOfTime };

  // Recomputes expired keys. Stops with kRebuild when more than `rebuild_above` keys are due
  // (coherence lost: rebuilding costs less), with kOutOfTime when the time budget ran out.
  // Records due when the budget has run out move to the backlog, which the next update takes
  // first (oldest first). The wheels are always drained up to the current clocks, so their
  // cursors never lag behind the camera: a lagging cursor sent every new record to the
  // overflow heap and later paid for moving them all back at once (frames of 100+ ms under a
  // 2 ms budget, found with `ridge bench lod --budget-ms 2`).
  Refresh refresh_expired(std::size_t rebuild_above) {
    std::size_t done = 0;
    Refresh why = Refresh::kDone;
    bool out = false;
    // false: stop (rebuild).
    auto visit = [&](const Due& b, bool from_backlog) {
      ++st.expiry_records;
      if (out) {
        // Out of time: set aside without touching the node (a cache miss per record would cost
        // more than the budget), staleness is checked when it is taken.
        if (!from_backlog) backlog.push_back(b);
        return true;
      }
      if (!live(b)) return true;  // stale
      if (out_of_time()) {
        out = true;
        why = Refresh::kOutOfTime;
        if (!from_backlog) backlog.push_back(b);
        return true;
      }
      ++st.expired;
      // Only the clock that fired is spent; the other record stays valid and is kept when it is
      // due no later than the new key's window (push_records).
      // A forced recomputation replaces both records.
      if (b.clock != Clock::kDistance) nodes[b.node].due_a = std::numeric_limits<float>::infinity();
      if (b.clock != Clock::kAngle) nodes[b.node].due_d = std::numeric_limits<float>::infinity();
      requeue(b.node);
      if (++done > rebuild_above) {
        why = Refresh::kRebuild;
        return false;
      }
      return true;
    };
    // The backlog first (oldest first); once out of time the rest of it stays.
    while (!backlog.empty() && !out) {
      const Due b = backlog.front();
      if (!visit(b, true)) return why;
      if (!out) backlog.pop_front();
    }
    auto visit_angle = [&](std::uint32_t node, double key) {
      return visit(Due{node, float(key), Clock::kAngle}, false);
    };
    auto visit_distance = [&](std::uint32_t node, double key) {
      return visit(Due{node, float(key), Clock::kDistance}, false);
    };
    if (by_angle.drain(angometer, visit_angle)) by_distance.drain(odometer, visit_distance);
    // Stale entries pile up in a backlog that never empties (a budget far too small for the
    // camera): drop them (rare; O(backlog)).
    if (backlog.size() > 4 * (split.size() + merge.size()) + 65536) {
      std::deque<Due> keep;
      for (const Due& b : backlog)
        if (live(b)) keep.push_back(b);
      backlog.swap(keep);
    }
    return why;
  }
};

// -------------------------------------------------------------------------------------------

float morph_factor(float morph_bound, double distance_m, double k, double threshold_px) {
  if (morph_bound <= 0.0f) return 1.0f;
  if (!(threshold_px > 0.0)) return 1.0f;
  const double p = distance_m > 0.0 ? double(morph_bound) * k / distance_m : 1e30;
  return static_cast<float>(std::clamp(p / threshold_px - 1.0, 0.0, 1.0));
}

Result<std::unique_ptr<RoamView>> RoamView::create(std::shared_ptr<const Landscape> landscape,
                                                   const RoamSettings& settings) {
  if (!landscape) return Error{"roam view: no landscape given"};
  std::unique_ptr<RoamView> v(new RoamView());
  v->landscape_ = std::move(landscape);
  v->landscape_->sync();  // the roots below take current bounds
  v->impl_ = std::make_unique<Impl>(*v->landscape_);
  v->impl_->seen_version = v->landscape_->synced_version();
  if (auto s = v->set_settings(settings); !s) return Error{s.message()};
  Impl& m = *v->impl_;
  const std::uint32_t np = v->landscape_->patch_count();
  m.patch_version.assign(np, 0);
  m.patch_dirty.assign(np, 0);
  m.meshes.resize(np);
  m.mesh_built_version.assign(np, ~std::uint64_t{0});
  m.reset_to_roots();
  v->triangles_ = m.triangles;
  return v;
}

RoamView::~RoamView() = default;

Status RoamView::set_settings(const RoamSettings& s) {
  if (!std::isfinite(s.threshold) || s.threshold < 0.0)
    return Error{
        fmt("roam view: threshold %s; need a finite value >= 0", num(s.threshold).c_str())};
  if (!std::isfinite(s.budget_ms) || s.budget_ms < 0.0)
    return Error{
        fmt("roam view: time budget %s ms; need a finite value >= 0", num(s.budget_ms).c_str())};
  if (!(s.slack >= 0.005 && s.slack <= 0.5))
    return Error{fmt("roam view: slack %s; need 0.005 .. 0.5", num(s.slack).c_str())};
  if (s.max_triangles != 0 && s.max_triangles < landscape_->root_count())
    return Error{fmt("roam view: triangle budget %u is below the %u root triangles",
                     s.max_triangles, landscape_->root_count())};
  if (impl_ &&
      (s.mode != settings_.mode || s.metric != settings_.metric || s.slack != settings_.slack))
    impl_->reset_pending = true;
  settings_ = s;
  return {};
}

Result<RoamStats> RoamView::converge(const Camera& camera) {
  RoamSettings saved = settings_;
  RoamSettings s = settings_;
  s.budget_ms = 0;
  (void)set_settings(s);
  auto r = update(camera);
  (void)set_settings(saved);
  return r;
}

Result<RoamStats> RoamView::update(const Camera& camera) {
  if (settings_.metric == ErrorMetric::kScreenPixels)
    if (auto s = validate_camera(camera); !s) return Error{s.message()};
  const auto t0 = std::chrono::steady_clock::now();
  Impl& m = *impl_;
  // Edits since the last update: the shared bounds first, then this view's nodes.
  landscape_->sync();
  m.pull_edits();
  m.st = RoamStats{};
  m.metric = settings_.metric;
  m.slack = settings_.slack;
  const double threshold = settings_.threshold;
  const std::uint32_t cap = settings_.max_triangles;
  m.threshold = settings_.metric == ErrorMetric::kScreenPixels ? threshold : 0.0;
  m.window_below = kWindowBelow;
  if (cap != 0 && m.capped_level > m.threshold && settings_.metric == ErrorMetric::kScreenPixels) {
    // The cap, not the threshold, decides: keys matter near the level where the last update
    // stopped. Size windows around that level (any level gives valid upper-bound keys; this one
    // makes them tight where splits and merges trade), with the half-way window that keeps the
    // keys just below it in order.
    m.threshold = m.capped_level;
    m.window_below = kWindowAbove;
  }
  const double budget = settings_.budget_ms;
  auto elapsed_ms = [&] {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  };

  if (m.cache != nullptr) m.cache->update();  // integrate tiles generated since the last frame
  m.has_deadline = budget > 0.0;
  auto deadline_at = [&](double fraction) {
    return t0 + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                    std::chrono::duration<double, std::milli>(budget * fraction));
  };
  // Recomputing expired keys may take at most this share of a time budget: the rest is kept for
  // splits and merges, else a camera that outruns the budget starves them and the mesh freezes
  // (what `ridge report` found: 0 changes per frame under 0.5 and 2 ms budgets). Keys left due
  // are recomputed first on the next update.
  constexpr double kRefreshShare = 0.5;
  m.deadline = deadline_at(kRefreshShare);
  bool all = false, refresh_ran_out = false;
  if (settings_.metric == ErrorMetric::kScreenPixels) all = m.set_camera(camera);
  if (m.reset_pending || settings_.mode == RoamMode::kRebuild) {
    m.reset_pending = false;
    m.reset_to_roots();
    if (settings_.metric == ErrorMetric::kScreenPixels) m.refresh_culling(false);
  } else if (settings_.metric == ErrorMetric::kScreenPixels) {
    const std::size_t queued = m.split.size() + m.merge.size();
    // Stale records piling up (nodes re-keyed, split or merged before their records came due)
    // are dropped; a projection change makes every key due.
    auto live_d = [&](std::uint32_t n, double key) { return m.live_distance(n, key); };
    auto live_a = [&](std::uint32_t n, double key) { return m.live_angle(n, key); };
    const bool behind = m.by_distance.size() + m.by_angle.size() > 8 * queued + 65536;
    if (behind && !m.has_deadline) {
      m.by_distance.compact(live_d);  // rare: the round-robin sweep below fell behind
      m.by_angle.compact(live_a);
    } else if (!m.has_deadline) {
      m.by_distance.compact_some(live_d, 4096);
      m.by_angle.compact_some(live_a, 4096);
    } else {
      // Under a time budget a full compaction (milliseconds) would break it, and even the
      // regular sweep reads a node per record (a cache miss each: 4,096 of them cost ~0.2 ms):
      // sweep in slices until 5 % of the budget is spent (more records when behind).
      const auto until = deadline_at(0.05);
      const std::size_t quota = behind ? 32768 : 4096;
      for (std::size_t done = 0; done < quota; done += 512) {
        m.by_distance.compact_some(live_d, 384);
        m.by_angle.compact_some(live_a, 128);
        if (std::chrono::steady_clock::now() >= until) break;
      }
    }
    // Culling gets a small share of a time budget (it resumes where it stopped next update).
    constexpr double kCullShare = 0.15;
    m.refresh_culling(true, m.has_deadline, deadline_at(kCullShare));
    const bool everything = all;
    if (everything) {
      m.mark_all_due();
    } else if (threshold > m.keyed_threshold * 1.01) {
      // Merge keys were windowed for a lower threshold and may sit above the new one although
      // the diamond now qualifies: recompute them (within the time budget).
      m.mark_merges_due();
    }
    // Coherence loses when most keys expire at once (a teleport, a snap turn): rebuilding
    // top-down then costs less than requeueing everything and merging most of the mesh away.
    // Not after a projection change (a zoom): the mesh keeps its shape while keys catch up.
    const auto r = m.refresh_expired(everything || m.zoomed ? std::numeric_limits<std::size_t>::max()
                                                : std::max<std::size_t>(2048, queued / 2));
    if (r == Impl::Refresh::kRebuild) m.reset_to_roots();
    // Out of time (kOutOfTime): the rest stays due; splits and merges get the remaining budget.
    refresh_ran_out = r == Impl::Refresh::kOutOfTime;
  }

  m.keyed_threshold = threshold;
  m.deadline = deadline_at(1.0);
  if (!m.waiting.empty()) m.unpark();

  // Greedy split/merge (D97 section 5): split the worst leaf while it exceeds the threshold,
  // merge the best diamond while it is within it; under a triangle cap, trade merges of
  // low-priority diamonds for splits of higher-priority leaves.
  std::uint64_t ops = 0;
  for (;;) {
    // A safety net against a trade cycle under a triangle cap; never reached in practice.
    if (++ops > 16ull * (m.triangles + 4096)) break;
    if (m.st.stop == StopReason::kTimeBudget || m.out_of_time()) {
      m.st.stop = StopReason::kTimeBudget;
      break;
    }
    const float s = m.split.empty() ? -1.0f : m.split.top().key;
    const float g = m.merge.empty() ? kInf : m.merge.top().key;
    if (cap != 0 && m.triangles > cap) {
      if (m.merge.empty()) break;
      m.merge_diamond(m.merge.top().node);
      continue;
    }
    // Under a time budget, a merge that is due goes first every other operation: splits alone
    // would take the whole budget while the camera moves, and the mesh would keep every
    // triangle it no longer needs (2.7x the unbudgeted count at 1 px, 2 ms on the noise
    // flyover) at the cost of the draw calls.
    if (m.has_deadline && g <= threshold && s > threshold && (ops & 1) == 0) {
      m.merge_diamond(m.merge.top().node);
      continue;
    }
    if (s > threshold) {
      const std::uint32_t n = m.split.top().node;
      if (!m.chain_ready(n)) {
        m.park(n);
        continue;
      }
      if (cap != 0 && m.triangles + m.split_cost(n) > cap) {
        // Trade only a diamond that is not the leaf's own parent pair.
        if (g < s && m.nodes[n].parent != m.merge.top().node &&
            m.nodes[n].parent != m.nodes[m.merge.top().node].base) {
          m.merge_diamond(m.merge.top().node);
          continue;
        }
        m.st.stop = StopReason::kTriangleBudget;
        break;
      }
      m.split_leaf(n, false);
      continue;
    }
    if (g <= threshold) {
      m.merge_diamond(m.merge.top().node);
      continue;
    }
    break;
  }

  if (refresh_ran_out) m.st.stop = StopReason::kTimeBudget;  // keys are still due: not converged
  triangles_ = m.triangles;
  m.st.triangles = m.triangles;
  m.st.max_remaining_error = m.split.empty() ? 0.0 : std::max(0.0f, m.split.top().key);
  m.capped_level = m.st.stop == StopReason::kTriangleBudget && std::isfinite(m.st.max_remaining_error)
                       ? m.st.max_remaining_error
                       : 0.0;
  m.st.pending_splits = static_cast<std::uint32_t>(m.waiting.size());
  m.st.dirty_patches = static_cast<std::uint32_t>(m.dirty_list.size());
  m.st.memory_bytes = m.nodes.memory_bytes() + m.split.memory_bytes() +
                      m.merge.memory_bytes() + m.by_distance.memory_bytes() +
                      m.by_angle.memory_bytes() + m.free_pairs.capacity() * sizeof(std::uint32_t);
  for (const PatchMesh& pm : m.meshes)
    m.st.memory_bytes += pm.vertices.capacity() * sizeof(MeshVertex) +
                         pm.indices.capacity() * sizeof(std::uint32_t) + pm.padding.capacity();
  m.st.update_ms = elapsed_ms();
  return m.st;
}

std::vector<std::uint32_t> RoamView::take_dirty_patches() {
  Impl& m = *impl_;
  std::vector<std::uint32_t> out;
  out.swap(m.dirty_list);
  for (std::uint32_t p : out) m.patch_dirty[p] = 0;
  std::sort(out.begin(), out.end());
  return out;
}

void RoamView::for_each_leaf(
    const std::function<void(std::uint32_t, std::uint64_t, const LatticeTriangle&)>& fn) const {
  const Impl& m = *impl_;
  struct Item {
    std::uint32_t n;
    LatticeTriangle t;
  };
  std::vector<Item> stack;
  for (std::uint32_t r = 0; r < landscape_->root_count(); ++r) {
    stack.push_back({r, landscape_->triangle(r, 1)});
    while (!stack.empty()) {
      const Item it = stack.back();
      stack.pop_back();
      const Node& nd = m.nodes[it.n];
      if (nd.child == kNone) {
        fn(nd.root, nd.heap, it.t);
        continue;
      }
      stack.push_back({nd.child + 1, Landscape::child_triangle(it.t, 1)});
      stack.push_back({nd.child, Landscape::child_triangle(it.t, 0)});
    }
  }
}

std::uint64_t RoamView::mesh_hash() const {
  std::uint64_t h = 1469598103934665603ull;
  for_each_leaf([&](std::uint32_t root, std::uint64_t heap, const LatticeTriangle&) {
    for (std::uint64_t v : {std::uint64_t(root), heap}) {
      h ^= v;
      h *= 1099511628211ull;
    }
  });
  return h;
}

std::string RoamView::check_invariants() const {
  const Impl& m = *impl_;
  std::string err;
  std::uint32_t leaves = 0;
  // Pointer symmetry: every leaf's neighbours are leaves that point back.
  std::vector<std::uint32_t> stack;
  for (std::uint32_t r = 0; r < landscape_->root_count() && err.empty(); ++r) {
    stack.push_back(r);
    while (!stack.empty() && err.empty()) {
      const std::uint32_t n = stack.back();
      stack.pop_back();
      const Node& nd = m.nodes[n];
      if (nd.child != kNone) {
        stack.push_back(nd.child);
        stack.push_back(nd.child + 1);
        continue;
      }
      ++leaves;
      for (std::uint32_t nb : {nd.base, nd.left, nd.right}) {
        if (nb == kNone) continue;
        const Node& o = m.nodes[nb];
        if (o.child != kNone)
          err = fmt("leaf %u (root %u heap %llu) links to internal node %u", n, unsigned(nd.root),
                    static_cast<unsigned long long>(nd.heap), nb);
        else if (o.base != n && o.left != n && o.right != n)
          err = fmt("leaf %u links to %u which does not link back", n, nb);
      }
      if (nd.base != kNone) {
        const Node& o = m.nodes[nd.base];
        const std::uint32_t lo = 63 - __builtin_clzll(o.heap), ln = 63 - __builtin_clzll(nd.heap);
        if (o.base == n ? lo != ln : lo + 1 != ln)
          err = fmt("leaf %u and its base neighbour %u differ by more than one level", n, nd.base);
      }
    }
  }
  if (err.empty() && leaves != m.triangles)
    err = fmt("leaf count %u differs from the triangle counter %u", leaves, m.triangles);
  return err;
}

const PatchMesh& RoamView::patch_mesh(std::uint32_t patch) {
  Impl& m = *impl_;
  RIDGELINE_ASSERT(patch < landscape_->patch_count());
  PatchMesh& pm = m.meshes[patch];
  if (m.mesh_built_version[patch] == m.patch_version[patch]) return pm;
  const Landscape& l = *landscape_;
  const Heightfield& hf = l.terrain().heightfield();
  const std::int64_t P = l.patch_cells();
  const std::int64_t i0 = std::int64_t(patch % l.patches_x()) * P;
  const std::int64_t j0 = std::int64_t(patch / l.patches_x()) * P;
  pm.origin_x = l.world_x(i0);
  pm.origin_z = l.world_z(j0);
  pm.origin_y = hf.height_offset();
  pm.vertices.clear();
  pm.indices.clear();
  pm.padding.clear();
  pm.version = m.patch_version[patch];
  // Vertex slots and geomorph data by lattice position: a dense table for patches of up to
  // 2^18 vertices, a hash map beyond (patches refined into detail are sparse).
  const std::size_t cells = std::size_t(P + 1) * std::size_t(P + 1);
  const bool dense = cells <= (std::size_t{1} << 18);
  m.scratch_index.assign(dense ? cells : 0, kNone);
  std::unordered_map<std::size_t, std::uint32_t> sparse_index;
  std::unordered_map<std::size_t, std::pair<float, float>> sparse_morph;
  const std::int64_t wmax = l.last_i(), hmax = l.last_j();

  // Depth-first over the patch's two roots; a vertex's geomorph data comes from the diamond
  // whose split introduced it (the first time the traversal meets it as a midpoint).
  struct Item {
    std::uint32_t n;
    LatticeTriangle t;
  };
  std::vector<Item> stack;
  std::vector<std::pair<float, float>> morph(dense ? cells : 0, {0.0f, 0.0f});
  auto slot_of = [&](std::size_t key) -> std::uint32_t& {
    return dense ? m.scratch_index[key] : sparse_index.try_emplace(key, kNone).first->second;
  };
  auto morph_of = [&](std::size_t key) -> std::pair<float, float>& {
    return dense ? morph[key] : sparse_morph[key];
  };
  auto vertex = [&](std::int64_t i, std::int64_t j) -> std::uint32_t {
    const std::size_t key = std::size_t(i - i0) + std::size_t(j - j0) * std::size_t(P + 1);
    std::uint32_t& slot = slot_of(key);
    if (slot != kNone) return slot;
    slot = static_cast<std::uint32_t>(pm.vertices.size());
    const glm::vec3 n = l.terrain().lattice_vertex_normal(std::clamp<std::int64_t>(i, 0, wmax),
                                                          std::clamp<std::int64_t>(j, 0, hmax));
    MeshVertex v;
    v.x = static_cast<float>(double(i - i0) * l.spacing_x());
    v.z = static_cast<float>(double(j - j0) * l.spacing_z());
    v.y = l.lattice_height(i, j);
    v.nx = n.x;
    v.ny = n.y;
    v.nz = n.z;
    const std::pair<float, float> mo = morph_of(key);
    v.morph_dy = mo.first;
    v.morph_bound = mo.second;
    pm.vertices.push_back(v);
    return slot;
  };
  for (std::uint32_t r = 2 * patch; r < 2 * patch + 2; ++r) {
    stack.push_back({r, l.triangle(r, 1)});
    while (!stack.empty()) {
      const Item it = stack.back();
      stack.pop_back();
      const Node& nd = m.nodes[it.n];
      if (nd.child == kNone) {
        const LatticeTriangle& t = it.t;
        pm.indices.push_back(vertex(t.ax, t.az));
        pm.indices.push_back(vertex(t.lx, t.lz));
        pm.indices.push_back(vertex(t.rx, t.rz));
        const double cx = double(t.ax + t.lx + t.rx) / 3.0, cz = double(t.az + t.lz + t.rz) / 3.0;
        pm.padding.push_back(cx > double(wmax) || cz > double(hmax));
        continue;
      }
      // The midpoint this split introduced: record its geomorph data before any leaf uses it.
      const LatticeTriangle& t = it.t;
      const std::int64_t mx = (t.lx + t.rx) / 2, mz = (t.lz + t.rz) / 2;
      const std::size_t key = std::size_t(mx - i0) + std::size_t(mz - j0) * std::size_t(P + 1);
      if (slot_of(key) == kNone && morph_of(key).second == 0.0f) {
        float b = nd.bound;
        if (nd.base != kNone) b = std::max(b, m.nodes[nd.base].bound);
        const float interp = 0.5f * (l.lattice_height(t.lx, t.lz) + l.lattice_height(t.rx, t.rz));
        morph_of(key) = {interp - l.lattice_height(mx, mz), std::max(b, 1e-30f)};
      }
      stack.push_back({nd.child + 1, Landscape::child_triangle(it.t, 1)});
      stack.push_back({nd.child, Landscape::child_triangle(it.t, 0)});
    }
  }
  m.mesh_built_version[patch] = m.patch_version[patch];
  return pm;
}

}  // namespace ridgeline

namespace ridgeline {

RoamView::MeasuredError RoamView::measure_error(const Camera& camera, std::uint32_t stride) const {
  // One measurement for tests, `bench lod` and `ridge report` (mesh_error.h).
  const MeshErrorMeter meter(landscape_->terrain(), stride);
  const DrawnHeights drawn = meter.rasterize(leaves_mesh(*this));
  const MeshError e = settings_.metric == ErrorMetric::kScreenPixels ? meter.measure(drawn, camera)
                                                                      : meter.measure_all(drawn);
  return {e.max_m, e.rms_m, e.max_px, e.p99_px, e.vertices - e.uncovered};
}

}  // namespace ridgeline
