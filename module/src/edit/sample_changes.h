// Private: what one edit transaction changed (Terrain::commit, module/src/edit/): the stored
// samples it changed and the range of their heights before and after.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

namespace ridgeline {

/// Bookkeeping of one transaction (Terrain::commit): which stored samples changed, and the range
/// of their heights before and after.
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
};

}  // namespace ridgeline
