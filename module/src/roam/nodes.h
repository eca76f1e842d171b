// Bintree node storage of a RoamView: 24-byte nodes in fixed chunks, allocated in sibling pairs.
#pragma once

#include <cstdint>
#include <memory>
#include <new>
#include <type_traits>
#include <vector>

namespace ridgeline::roam {

inline constexpr std::uint32_t kNone = 0xffffffffu;
/// Node::tri of an interior node.
inline constexpr std::uint32_t kInterior = 0xffffffffu;
/// Node::front's low 31 bits when the node's diamond has no front entry.
inline constexpr std::uint32_t kNoEntry = 0x7fffffffu;

/// One bintree triangle. A leaf and an interior node use the two middle words differently:
///   leaf:     a = left neighbour, b = right neighbour, tri = triangle slot in its patch's buffers
///   interior: a = first child (the pair a, a + 1), b = vertex slot of its hypotenuse midpoint in
///             its patch's buffers, tri = kInterior
/// `front` holds the index of its diamond's front entry (kNoEntry: none; a leaf always has one,
/// an interior node when its diamond is mergeable) and, in bit 31, which of the diamond's two
/// apexes is this triangle's (Diamond::apexes() order), so a node's geometry follows from the
/// entry's centre without being stored. Geometry, root and heap index are never stored: they
/// follow from the entry (leaves) or from a walk from the roots.
struct Node {
  std::uint32_t parent = kNone;
  std::uint32_t base = kNone;  ///< neighbour across the hypotenuse (kNone on the border)
  std::uint32_t a = kNone, b = kNone;
  std::uint32_t front = kNoEntry;
  std::uint32_t tri = kInterior;

  bool leaf() const noexcept { return tri != kInterior; }
  std::uint32_t entry() const noexcept { return front & kNoEntry; }
  std::uint32_t side() const noexcept { return front >> 31; }
  void set_entry(std::uint32_t e) noexcept { front = (front & 0x80000000u) | e; }
  void set_side(std::uint32_t s) noexcept { front = (front & kNoEntry) | (s << 31); }
};
static_assert(sizeof(Node) == 24, "docs/roam.md quotes the node size");
static_assert(std::is_trivially_destructible_v<Node>);

/// Nodes in fixed chunks that never move (growing never copies nodes inside an update: a
/// vector's doubling did, 5-15 ms spikes under a time budget), handed out and taken back in
/// sibling pairs. A new chunk is raw memory: nodes are constructed as they are handed out, so
/// its pages fault in a few at a time.
class NodePool {
 public:
  Node& operator[](std::uint32_t i) noexcept { return chunks_[i >> kShift].get()[i & kMask]; }
  const Node& operator[](std::uint32_t i) const noexcept {
    return chunks_[i >> kShift].get()[i & kMask];
  }
  /// Nodes handed out so far (live or free).
  std::uint32_t size() const noexcept { return size_; }

  /// The first of two new sibling nodes, default-constructed.
  std::uint32_t alloc_pair() {
    std::uint32_t c;
    if (!free_.empty()) {
      c = free_.back();
      free_.pop_back();
    } else {
      c = size_;
      if (((size_ + 1) >> kShift) >= chunks_.size())
        chunks_.emplace_back(static_cast<Node*>(::operator new(sizeof(Node) << kShift)));
      size_ += 2;
    }
    ::new (&(*this)[c]) Node{};
    ::new (&(*this)[c + 1]) Node{};
    return c;
  }
  void free_pair(std::uint32_t first) { free_.push_back(first); }

  /// Forgets every node; the first `count` (an even number) are handed out again,
  /// default-constructed. Chunks are kept, so a rebuild faults in no new pages.
  void reset(std::uint32_t count) {
    free_.clear();
    size_ = 0;
    while (size_ < count) (void)alloc_pair();
  }

  std::size_t memory_bytes() const noexcept {
    return chunks_.size() * (sizeof(Node) << kShift) + chunks_.capacity() * sizeof(chunks_[0]) +
           free_.capacity() * sizeof(std::uint32_t);
  }

 private:
  static constexpr std::uint32_t kShift = 14;  // 16k nodes, 384 KiB per chunk
  static constexpr std::uint32_t kMask = (1u << kShift) - 1;
  struct FreeChunk {
    void operator()(Node* p) const noexcept { ::operator delete(p); }
  };
  std::vector<std::unique_ptr<Node, FreeChunk>> chunks_;
  std::vector<std::uint32_t> free_;
  std::uint32_t size_ = 0;
};

}  // namespace ridgeline::roam
