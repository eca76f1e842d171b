// Bintree node storage of a RoamView: 24-byte nodes in one array that grows in place, allocated in
// sibling pairs.
#pragma once

#include <cstdint>
#include <new>
#include <type_traits>

#include "platform/memory_hints.h"
#include "ridgeline/log.h"
#include "roam/reserved.h"

namespace ridgeline::roam {

inline constexpr std::uint32_t kNone = 0xffffffffu;

/// The three links of a node, and the values a link word's back field takes.
inline constexpr std::uint32_t kBaseLink = 0, kLeftLink = 1, kRightLink = 2;
/// A link word: the neighbour's index in bits 0-29 and, in bits 30-31, which of the neighbour's
/// links (kBaseLink, kLeftLink, kRightLink) points back, so that relinking a neighbour is a
/// store, not a search. kNone (all ones) for no neighbour.
inline constexpr std::uint32_t kIndexMask = 0x3fffffffu;
inline constexpr std::uint32_t link_word(std::uint32_t node, std::uint32_t back_link) noexcept {
  return node | (back_link << 30);
}
/// The node link word w points at (kNone for none).
inline constexpr std::uint32_t linked_node(std::uint32_t w) noexcept {
  return w == kNone ? kNone : (w & kIndexMask);
}
/// Which link of that node points back (kBaseLink, kLeftLink or kRightLink).
inline constexpr std::uint32_t back_link(std::uint32_t w) noexcept {
  return w >> 30;
}
/// True when base link word w names the node's partner: the other triangle of its diamond,
/// which links back through its own base link.
inline constexpr bool is_partner(std::uint32_t w) noexcept {
  return w != kNone && back_link(w) == kBaseLink;
}
/// True when base link word w names a coarser neighbour: one that must split (a forced split)
/// before the node can.
inline constexpr bool is_coarser(std::uint32_t w) noexcept {
  return w != kNone && back_link(w) != kBaseLink;
}

/// Node::slot() of an interior node.
inline constexpr std::uint32_t kInterior = 0x7fffffffu;
/// Node::entry() when the node's diamond has no front entry.
inline constexpr std::uint32_t kNoEntry = 0xffffffffu;

/// One bintree triangle. Its two side links mean different things for a leaf and for an interior
/// node, so each meaning has its own accessor:
///   leaf:     left(), right(): link words of the neighbours across its left and right edges;
///             slot(): its triangle slot in its patch's buffers
///   interior: first_child(): the first of its two children (the pair c, c + 1);
///             midpoint_slot(): the vertex slot of its hypotenuse's midpoint in its patch's
///             buffers; slot() == kInterior
/// base() is a link word for both (a split diamond's two nodes keep linking each other).
/// entry() is the index of its diamond's front entry (kNoEntry: none; a leaf always has one but
/// at the finest level, an interior node when its diamond is mergeable): a whole word, so that
/// re-pointing a node at a moved entry is a plain store, no read. side() says which of the
/// diamond's two apexes is this triangle's (apex_side()), so a node's geometry follows from the
/// entry's centre without being stored. Geometry, root and heap index are never stored.
struct Node {
  std::uint32_t parent = kNone;
  /// [kBaseLink] the neighbour across the hypotenuse (kNone on the border); [kLeftLink] and
  /// [kRightLink] the leaf's left and right neighbours, or the interior node's first child and
  /// midpoint vertex slot (plain numbers). Read through the accessors below; the raw words only
  /// where a node changes between leaf and interior.
  std::uint32_t link[3] = {kNone, kNone, kNone};
  std::uint32_t entry_index = kNoEntry;
  std::uint32_t slot_and_side = kInterior;  ///< slot (bits 0-30) and side (bit 31)

  std::uint32_t& base() noexcept { return link[kBaseLink]; }
  std::uint32_t base() const noexcept { return link[kBaseLink]; }
  std::uint32_t& left() noexcept {
    RIDGELINE_ASSERT(leaf());
    return link[kLeftLink];
  }
  std::uint32_t left() const noexcept {
    RIDGELINE_ASSERT(leaf());
    return link[kLeftLink];
  }
  std::uint32_t& right() noexcept {
    RIDGELINE_ASSERT(leaf());
    return link[kRightLink];
  }
  std::uint32_t right() const noexcept {
    RIDGELINE_ASSERT(leaf());
    return link[kRightLink];
  }
  std::uint32_t first_child() const noexcept {
    RIDGELINE_ASSERT(!leaf());
    return link[kLeftLink];
  }
  std::uint32_t midpoint_slot() const noexcept {
    RIDGELINE_ASSERT(!leaf());
    return link[kRightLink];
  }
  void set_midpoint_slot(std::uint32_t v) noexcept {
    RIDGELINE_ASSERT(!leaf());
    link[kRightLink] = v;
  }
  /// Turns a leaf into an interior node with children c, c + 1 and midpoint vertex slot v.
  void make_interior(std::uint32_t c, std::uint32_t v) noexcept {
    link[kLeftLink] = c;
    link[kRightLink] = v;
    slot_and_side |= kInterior;
  }
  /// Turns an interior node back into a leaf with triangle slot s and neighbour links l and r.
  void make_leaf(std::uint32_t s, std::uint32_t l, std::uint32_t r) noexcept {
    set_slot(s);
    link[kLeftLink] = l;
    link[kRightLink] = r;
  }
  bool leaf() const noexcept { return (slot_and_side & kInterior) != kInterior; }
  std::uint32_t slot() const noexcept { return slot_and_side & kInterior; }
  void set_slot(std::uint32_t s) noexcept { slot_and_side = (slot_and_side & ~kInterior) | s; }
  std::uint32_t entry() const noexcept { return entry_index; }
  void set_entry(std::uint32_t e) noexcept { entry_index = e; }
  std::uint32_t side() const noexcept { return slot_and_side >> 31; }
  void set_side(std::uint32_t s) noexcept {
    slot_and_side = (slot_and_side & kInterior) | (s << 31);
  }
};
static_assert(sizeof(Node) == 24, "docs/roam.md quotes the node size");
static_assert(std::is_trivially_destructible_v<Node>);

/// Nodes in one reserved range of address space (reserved.h) that never moves: growing copies
/// no node inside an update (a vector's doubling did: 5-15 ms spikes under a time budget), and
/// node i is at base + i (no chunk to look up). Pages are committed 384 KiB at a time as nodes
/// are handed out, in sibling pairs. At most kMaxNodes (2^28, ~134 million triangles' worth);
/// past it, past the RoamMemory's limit, or when the system refuses the pages, alloc_pair()
/// throws OutOfMemory (reserved.h), which RoamView::update() turns into an error. (With
/// RIDGELINE_PORTABLE the array is a plain allocation that moves when it grows: no reference to
/// a node is held across alloc_pair().)
class NodePool {
 public:
  static constexpr std::uint32_t kMaxNodes = 1u << 28;
  static_assert(kMaxNodes <= kIndexMask);

  /// `pool`, when given, must outlive the nodes (reserved.h).
  explicit NodePool(RangePool* pool = nullptr) noexcept : mem_("node array", pool) {}

  Node& operator[](std::uint32_t i) noexcept { return base_[i]; }
  const Node& operator[](std::uint32_t i) const noexcept { return base_[i]; }
  /// Hints the caches to fetch node i (node 0 for kNone or any other index out of range).
  void prefetch(std::uint32_t i) const noexcept { detail::prefetch(base_ + (i < size_ ? i : 0)); }
  /// Nodes handed out so far (live or free).
  std::uint32_t size() const noexcept { return size_; }

  /// The first of two new sibling nodes, default-constructed. Freed pairs are handed out first,
  /// the last freed first: their lines are the likeliest to be in the caches.
  std::uint32_t alloc_pair() {
    std::uint32_t c;
    if (free_ != kNone) {
      c = free_;
      free_ = base_[c].parent;  // a free pair's first node links to the next free pair
      prefetch(free_);          // the next allocation reads it
    } else {
      c = size_;
      if (std::size_t(size_ + 2) * sizeof(Node) > mem_.committed()) grow();
      size_ += 2;
    }
    ::new (&base_[c]) Node{};
    ::new (&base_[c + 1]) Node{};
    return c;
  }
  /// Frees a pair. Freed nodes read as interior nodes without an entry, so that a node index
  /// left in a policy's queue (a split or merge candidate whose parent merged since it was
  /// queued) is never taken for a leaf to split or a diamond to merge.
  void free_pair(std::uint32_t first) {
    base_[first] = base_[first + 1] = Node{};  // interior (slot kInterior), no entry
    base_[first].parent = free_;
    free_ = first;
  }

  /// Forgets every node; the first `count` (an even number) are handed out again,
  /// default-constructed. The pages are kept, so a rebuild faults in no new ones.
  void reset(std::uint32_t count) {
    free_ = kNone;
    size_ = 0;
    while (size_ < count) (void)alloc_pair();
  }

  /// Gives back the pages beyond the nodes handed out plus one spare step (what a range taken
  /// over from a destroyed view had committed beyond this view's needs).
  void trim() noexcept {
    const std::size_t keep = (std::size_t(size_) * sizeof(Node) / kStep + 2) * kStep;
    if (mem_.committed() > keep) {
      mem_.shrink_to(keep);
      base_ = static_cast<Node*>(mem_.data());
    }
  }

  std::size_t memory_bytes() const noexcept { return mem_.committed(); }

 private:
  static constexpr std::size_t kStep = sizeof(Node) << 14;  // 16k nodes, 384 KiB
  void grow() {
    mem_.grow_to(std::size_t(size_ + 2) * sizeof(Node), kStep, std::size_t(kMaxNodes) * sizeof(Node));
    base_ = static_cast<Node*>(mem_.data());
  }
  Reservation mem_;
  Node* base_ = nullptr;
  std::uint32_t free_ = kNone;  // first node of the last freed pair (a list through `parent`)
  std::uint32_t size_ = 0;
};

}  // namespace ridgeline::roam
