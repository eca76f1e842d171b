// Bintree node storage of a RoamView: 24-byte nodes in one array that grows in place, allocated in
// sibling pairs.
#pragma once

#include <cstdint>
#include <new>
#include <type_traits>

#include "memory_hints.h"
#include "roam/reserved.h"

namespace ridgeline::roam {

inline constexpr std::uint32_t kNone = 0xffffffffu;
/// A link word: the neighbour's index in bits 0-29 and, in bits 30-31, which of the neighbour's
/// links (0 base, 1 a, 2 b) points back, so that relinking a neighbour is a store, not a search.
/// kNone (all ones) for no neighbour.
inline constexpr std::uint32_t kIndexMask = 0x3fffffffu;
inline constexpr std::uint32_t link_word(std::uint32_t node, std::uint32_t back) noexcept {
  return node | (back << 30);
}
/// The node a link word points at (kNone for none).
inline constexpr std::uint32_t to(std::uint32_t w) noexcept {
  return w == kNone ? kNone : (w & kIndexMask);
}
/// Which link of that node points back.
inline constexpr std::uint32_t back(std::uint32_t w) noexcept {
  return w >> 30;
}

/// Node::slot() of an interior node.
inline constexpr std::uint32_t kInterior = 0x7fffffffu;
/// Node::entry() when the node's diamond has no front entry.
inline constexpr std::uint32_t kNoEntry = 0xffffffffu;

/// One bintree triangle. A leaf and an interior node use the links a and b differently:
///   leaf:     a = left neighbour, b = right neighbour (link words), slot() = triangle slot in
///             its patch's buffers
///   interior: a = first child (the pair a, a + 1), b = vertex slot of its hypotenuse midpoint in
///             its patch's buffers, slot() = kInterior
/// base is a link word for both (a split diamond's two nodes keep linking each other).
/// `front` is the index of its diamond's front entry (kNoEntry: none; a leaf always has one, an
/// interior node when its diamond is mergeable): a whole word, so that re-pointing a node at a
/// moved entry is a plain store, no read. side() says which of the diamond's two apexes is this
/// triangle's (Diamond::apexes() order), so a node's geometry follows from the entry's centre
/// without being stored. Geometry, root and heap index are never stored: they follow from the
/// entry (leaves) or from a walk from the roots.
struct Node {
  std::uint32_t parent = kNone;
  /// base (neighbour across the hypotenuse; kNone on the border), a, b: link words for a leaf
  /// (link_word()), child and vertex slot for an interior node (plain numbers).
  std::uint32_t link[3] = {kNone, kNone, kNone};
  std::uint32_t front = kNoEntry;
  std::uint32_t tri = kInterior;  ///< slot (bits 0-30) and side (bit 31)

  std::uint32_t& base() noexcept { return link[0]; }
  std::uint32_t& a() noexcept { return link[1]; }
  std::uint32_t& b() noexcept { return link[2]; }
  std::uint32_t base() const noexcept { return link[0]; }
  std::uint32_t a() const noexcept { return link[1]; }
  std::uint32_t b() const noexcept { return link[2]; }
  bool leaf() const noexcept { return (tri & kInterior) != kInterior; }
  std::uint32_t slot() const noexcept { return tri & kInterior; }
  void set_slot(std::uint32_t s) noexcept { tri = (tri & ~kInterior) | s; }
  void set_interior() noexcept { tri |= kInterior; }
  std::uint32_t entry() const noexcept { return front; }
  void set_entry(std::uint32_t e) noexcept { front = e; }
  std::uint32_t side() const noexcept { return tri >> 31; }
  void set_side(std::uint32_t s) noexcept { tri = (tri & kInterior) | (s << 31); }
};
static_assert(sizeof(Node) == 24, "docs/roam.md quotes the node size");
static_assert(std::is_trivially_destructible_v<Node>);

/// Nodes in one reserved range of address space (reserved.h) that never moves: growing copies
/// no node inside an update (a vector's doubling did: 5-15 ms spikes under a time budget), and
/// node i is at base + i (no chunk to look up). Pages are committed 384 KiB at a time as nodes
/// are handed out, in sibling pairs. At most kMaxNodes (2^28, ~134 million triangles' worth);
/// past it, or when the system refuses the pages, alloc_pair() throws std::bad_alloc like any
/// allocation.
class NodePool {
 public:
  static constexpr std::uint32_t kMaxNodes = 1u << 28;
  static_assert(kMaxNodes <= kIndexMask);

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
  void free_pair(std::uint32_t first) {
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
    if (mem_.committed() > keep) mem_.shrink_to(keep);
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
