// The hole mask (hole_mask.h): per-cell bits in blocks, and how much of a lattice triangle they
// cover.
#include "surface/hole_mask.h"

#include <algorithm>
#include <bit>

namespace ridgeline {

bool HoleMask::set(std::int64_t i, std::int64_t j, bool hole) {
  const std::uint64_t k = key(i >> kShift, j >> kShift);
  const std::size_t b = bit(i, j);
  const std::uint64_t m = std::uint64_t{1} << (b & 63);
  if (!hole) {
    const auto it = blocks_.find(k);
    if (it == blocks_.end() || !(it->second.bits[b >> 6] & m)) return false;
    it->second.bits[b >> 6] &= ~m;
    --cells_;
    if (--it->second.count == 0) blocks_.erase(it);  // memory follows the holes left
    return true;
  }
  Block& blk = blocks_[k];
  if (blk.bits[b >> 6] & m) return false;
  blk.bits[b >> 6] |= m;
  ++blk.count;
  ++cells_;
  return true;
}

void HoleMask::set_run(std::int64_t j, std::int64_t i0, std::int64_t i1) {
  const std::int64_t row = j & (kBlock - 1);
  for (std::int64_t bx = i0 >> kShift; bx <= (i1 >> kShift); ++bx) {
    const std::int64_t a = std::max(i0, bx << kShift) & (kBlock - 1);
    const std::int64_t b = std::min(i1, (bx << kShift) + kBlock - 1) & (kBlock - 1);
    // The row's 32 bits are one half of word row / 2 (kBlock = 32).
    const std::uint64_t run = ((std::uint64_t{1} << (b - a + 1)) - 1) << a;
    const std::uint64_t m = run << (32 * (row & 1));
    Block& blk = blocks_[key(bx, j >> kShift)];
    std::uint64_t& w = blk.bits[std::size_t(row >> 1)];
    const auto added = std::uint32_t(std::popcount(m & ~w));
    w |= m;
    blk.count += added;
    cells_ += added;
  }
}

bool HoleMask::any_in(std::int64_t i0, std::int64_t j0, std::int64_t i1, std::int64_t j1) const {
  bool any = false;
  // Visits at most the held blocks; the cells are few wherever holes are rare.
  for_each_in(i0, j0, i1, j1, [&](std::int64_t, std::int64_t) { any = true; });
  return any;
}

HoleCover HoleMask::cover(std::int64_t ax, std::int64_t az, std::int64_t lx, std::int64_t lz,
                          std::int64_t rx, std::int64_t rz, int levels) const {
  HoleCover c;
  const std::int64_t w = (lx - ax) * (rz - az) - (lz - az) * (rx - ax);
  const std::uint64_t aw = std::uint64_t(w < 0 ? -w : w);
  if (aw == 0) return c;
  const std::uint64_t unit = std::uint64_t{1} << (2 * levels);  // a stored half-cell, doubled
  if (aw < unit) {
    // Below the stored resolution: the triangle lies in one stored half-cell, its centroid's.
    c.total = 1;
    c.holes = hole((ax + lx + rx) / (std::int64_t{3} << levels),
                   (az + lz + rz) / (std::int64_t{3} << levels))
                  ? 1
                  : 0;
    return c;
  }
  // A union of stored half-cells (its corners lie on the stored lattice): count those of hole
  // cells whose centroid lies strictly inside, in exact integer arithmetic (3 x coordinates).
  c.total = aw >> (2 * levels);
  const std::int64_t i0 = std::min({ax, lx, rx}) >> levels, i1 = (std::max({ax, lx, rx}) >> levels) - 1;
  const std::int64_t j0 = std::min({az, lz, rz}) >> levels, j1 = (std::max({az, lz, rz}) >> levels) - 1;
  using Wide = __int128;
  const Wide sgn = w > 0 ? 1 : -1;
  const Wide px[3] = {Wide(ax) * 3, Wide(lx) * 3, Wide(rx) * 3};
  const Wide pz[3] = {Wide(az) * 3, Wide(lz) * 3, Wide(rz) * 3};
  auto inside = [&](Wide x, Wide z) {
    for (int e = 0; e < 3; ++e) {
      const int f = (e + 1) % 3;
      const Wide side = (px[f] - px[e]) * (z - pz[e]) - (pz[f] - pz[e]) * (x - px[e]);
      if (side * sgn <= 0) return false;
    }
    return true;
  };
  for_each_in(i0, j0, i1, j1, [&](std::int64_t i, std::int64_t j) {
    // Centroids of the cell's two triangles (diagonal rule, lattice_cell.h), times 3.
    const bool main = ((i + j) & 1) == 0;
    const int cu[2] = {main ? 2 : 1, main ? 1 : 2}, cv[2] = {main ? 1 : 1, main ? 2 : 2};
    for (int k = 0; k < 2; ++k)
      c.holes += inside(Wide(3 * i + cu[k]) << levels, Wide(3 * j + cv[k]) << levels) ? 1 : 0;
  });
  return c;
}

bool HoleMask::all_holes(std::int64_t ax, std::int64_t az, std::int64_t lx, std::int64_t lz,
                         std::int64_t rx, std::int64_t rz, int levels) const {
  // The centroid is strictly inside the triangle, so the half-cells around it are in it: a
  // solid cell there settles it.
  if (!hole((ax + lx + rx) / (std::int64_t{3} << levels),
            (az + lz + rz) / (std::int64_t{3} << levels)))
    return false;
  return cover(ax, az, lx, lz, rx, rz, levels).all();
}

std::vector<std::pair<std::uint64_t, HoleMask::Bits>> HoleMask::sorted_blocks() const {
  std::vector<std::pair<std::uint64_t, Bits>> out;
  out.reserve(blocks_.size());
  for (const auto& [k, b] : blocks_) out.emplace_back(k, b.bits);
  std::sort(out.begin(), out.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  return out;
}

void HoleMask::set_block(std::uint64_t k, const Bits& bits) {
  std::uint32_t n = 0;
  for (const std::uint64_t w : bits) n += std::uint32_t(std::popcount(w));
  if (const auto it = blocks_.find(k); it != blocks_.end()) {
    cells_ -= it->second.count;
    blocks_.erase(it);
  }
  if (n == 0) return;
  blocks_[k] = Block{bits, n};
  cells_ += n;
}

}  // namespace ridgeline
