// Private: what one edit transaction changed (Terrain::commit, module/src/edit/): the stored
// samples it changed and the range of their heights before and after.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

namespace ridgeline {

/// Bookkeeping of one transaction (Terrain::commit): which stored samples changed, and the range
/// of their heights before and after; which cells became holes or solid (the range then covers
/// their corners).
struct SampleChanges {
  std::uint32_t i0 = ~0u, j0 = ~0u, i1 = 0, j1 = 0;
  float lo = INFINITY, hi = -INFINITY;
  std::size_t samples = 0;
  void add(std::uint32_t i, std::uint32_t j, float before, float after) {
    i0 = std::min(i0, i), j0 = std::min(j0, j), i1 = std::max(i1, i), j1 = std::max(j1, j);
    lo = std::min({lo, before, after});
    hi = std::max({hi, before, after});
    ++samples;
  }
  /// Stored cell (i, j) became a hole or solid: its corners' bounds and triangles change.
  std::size_t cells = 0;
  void add_cell(std::uint32_t i, std::uint32_t j) {
    i0 = std::min(i0, i), j0 = std::min(j0, j), i1 = std::max(i1, i + 1), j1 = std::max(j1, j + 1);
    ++cells;
  }
  bool empty() const noexcept { return samples == 0 && cells == 0; }
};

}  // namespace ridgeline
