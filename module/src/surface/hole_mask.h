// Private: the hole mask of a terrain's surface (docs/deformation.md, "Holes"): one bit per
// stored cell (cell (i, j) lies between samples i..i+1 and j..j+1), set where the ground has been
// removed. Held in blocks of 32 x 32 cells allocated on the first hole in them, so a terrain
// without holes holds none and memory follows the cells that ever had a hole. Immutable once
// published: an edit builds a changed copy (the blocks are small) and publishes it, so readers on
// other threads (pages loading) never see a mask half written.
#pragma once

#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace ridgeline {

/// How much of a lattice triangle lies over hole cells, in stored half-cells (the triangles of
/// the diagonal rule). A triangle smaller than a stored half-cell (procedural detail) counts as
/// the one half-cell holding it.
struct HoleCover {
  std::uint64_t holes = 0;  ///< half-cells of hole cells inside the triangle
  std::uint64_t total = 0;  ///< half-cells inside the triangle
  bool any() const noexcept { return holes != 0; }
  bool all() const noexcept { return total != 0 && holes == total; }
  bool mixed() const noexcept { return holes != 0 && holes < total; }
};

class HoleMask {
 public:
  static constexpr int kShift = 5;
  static constexpr std::int64_t kBlock = std::int64_t{1} << kShift;  ///< cells per block side
  static constexpr std::size_t kWords = std::size_t(kBlock * kBlock / 64);
  using Bits = std::array<std::uint64_t, kWords>;  ///< bit (i & 31) + 32 (j & 31)

  /// Whether stored cell (i, j) is a hole (false for cells outside the data).
  bool hole(std::int64_t i, std::int64_t j) const noexcept {
    if (i < 0 || j < 0) return false;
    const auto it = blocks_.find(key(i >> kShift, j >> kShift));
    if (it == blocks_.end()) return false;
    const std::size_t b = bit(i, j);
    return (it->second.bits[b >> 6] >> (b & 63)) & 1u;
  }
  /// Hole cells in all.
  std::uint64_t cells() const noexcept { return cells_; }
  bool empty() const noexcept { return cells_ == 0; }
  /// Makes cell (i, j) (i, j >= 0) a hole or solid; true when that changed it.
  bool set(std::int64_t i, std::int64_t j, bool hole);
  /// Makes cells i0 .. i1 of row j holes (0 <= i0 <= i1, j >= 0): a block's row at a time (a
  /// baked world's holes at its open).
  void set_run(std::int64_t j, std::int64_t i0, std::int64_t i1);
  /// Calls f(i, j) for every hole cell in [i0, i1] x [j0, j1] (inclusive), block by block.
  template <class F>
  void for_each_in(std::int64_t i0, std::int64_t j0, std::int64_t i1, std::int64_t j1,
                   F&& f) const;
  /// Whether any cell of [i0, i1] x [j0, j1] is a hole.
  bool any_in(std::int64_t i0, std::int64_t j0, std::int64_t i1, std::int64_t j1) const;

  /// The cover of the lattice triangle (a, l, r) given in the finest lattice's indices of a
  /// surface with `levels` detail levels (0: stored indices): a triangle of the 4-8 hierarchy,
  /// so a union of stored half-cells when it is at least one. O(hole cells under its box).
  HoleCover cover(std::int64_t ax, std::int64_t az, std::int64_t lx, std::int64_t lz,
                  std::int64_t rx, std::int64_t rz, int levels) const;
  /// cover(...).all(), answered from the centroid's cell alone when that cell is solid (what
  /// nearly every triangle of a mesh beside a hole is).
  bool all_holes(std::int64_t ax, std::int64_t az, std::int64_t lx, std::int64_t lz,
                 std::int64_t rx, std::int64_t rz, int levels) const;

  /// The blocks holding a hole, as (key, bits) in ascending key order (cz, cx): what the edit
  /// file saves. key = block (bx, bz) as (bz << 32) | bx.
  std::vector<std::pair<std::uint64_t, Bits>> sorted_blocks() const;
  /// Sets a whole block (the edit file's load); an all-zero block is dropped.
  void set_block(std::uint64_t key, const Bits& bits);
  static std::uint64_t key(std::int64_t bx, std::int64_t bz) noexcept {
    return (std::uint64_t(bz) << 32) | std::uint64_t(bx);
  }
  std::size_t memory_bytes() const noexcept { return blocks_.size() * (sizeof(Block) + 32); }

 private:
  struct Block {
    Bits bits{};
    std::uint32_t count = 0;
  };
  static std::size_t bit(std::int64_t i, std::int64_t j) noexcept {
    return std::size_t(i & (kBlock - 1)) + std::size_t(j & (kBlock - 1)) * std::size_t(kBlock);
  }
  std::unordered_map<std::uint64_t, Block> blocks_;
  std::uint64_t cells_ = 0;
};

template <class F>
void HoleMask::for_each_in(std::int64_t i0, std::int64_t j0, std::int64_t i1, std::int64_t j1,
                           F&& f) const {
  if (blocks_.empty()) return;
  i0 = i0 < 0 ? 0 : i0, j0 = j0 < 0 ? 0 : j0;
  if (i1 < i0 || j1 < j0) return;
  const std::int64_t bx0 = i0 >> kShift, bx1 = i1 >> kShift, bz0 = j0 >> kShift,
                     bz1 = j1 >> kShift;
  auto visit = [&](std::int64_t bx, std::int64_t bz, const Block& b) {
    const std::int64_t ci0 = bx << kShift, cj0 = bz << kShift;
    for (std::size_t w = 0; w < kWords; ++w) {
      std::uint64_t word = b.bits[w];
      while (word != 0) {
        const std::size_t k = w * 64 + std::size_t(std::countr_zero(word));
        word &= word - 1;
        const std::int64_t i = ci0 + std::int64_t(k & std::size_t(kBlock - 1));
        const std::int64_t j = cj0 + std::int64_t(k >> kShift);
        if (i >= i0 && i <= i1 && j >= j0 && j <= j1) f(i, j);
      }
    }
  };
  // Look the range's blocks up one by one, or walk the held blocks when they are fewer.
  if (double(bx1 - bx0 + 1) * double(bz1 - bz0 + 1) <= double(blocks_.size())) {
    for (std::int64_t bz = bz0; bz <= bz1; ++bz)
      for (std::int64_t bx = bx0; bx <= bx1; ++bx)
        if (const auto it = blocks_.find(key(bx, bz)); it != blocks_.end()) visit(bx, bz, it->second);
  } else {
    for (const auto& [k, b] : blocks_) {
      const auto bx = std::int64_t(k & 0xffffffffu), bz = std::int64_t(k >> 32);
      if (bx >= bx0 && bx <= bx1 && bz >= bz0 && bz <= bz1) visit(bx, bz, b);
    }
  }
}

}  // namespace ridgeline
