// Private: the sparse edit layer of a terrain's Surface (docs/deformation.md), and the record of
// what one edit transaction changed. The surface's stored samples are edited in place (so
// queries cost the same edited or not); the layer keeps, for every 32 x 32 chunk an edit
// touched, the chunk's original heights, so that the edits can be saved (the current values of
// the touched chunks) and undone (load_edits restores the originals first).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "ridgeline/edit.h"
#include "ridgeline/heightfield.h"

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

class EditLayer {
 public:
  static constexpr std::uint32_t kChunkShift = 5;
  static constexpr std::uint32_t kChunk = 1u << kChunkShift;  ///< samples per chunk side

  EditLimits limits;

  /// Records the original heights of the chunk holding sample (i, j) if not yet recorded.
  void touch(const Heightfield& hf, std::uint32_t i, std::uint32_t j);
  /// Writes local height `h` at sample (i, j) (the chunk must be touched).
  static void write(Heightfield& hf, std::uint32_t i, std::uint32_t j, float h) noexcept {
    hf.heights_[i + std::size_t{j} * hf.width_] = h;
    hf.min_local_ = std::min(hf.min_local_, h);
    hf.max_local_ = std::max(hf.max_local_, h);
  }
  std::size_t chunks() const noexcept { return originals_.size(); }
  /// Chunk keys in ascending order (cz, cx): the save order.
  std::vector<std::uint64_t> sorted_keys() const;
  static std::uint64_t key(std::uint32_t cx, std::uint32_t cz) noexcept {
    return (std::uint64_t{cz} << 32) | cx;
  }
  /// Original heights of a touched chunk (kChunk * kChunk, row-major; samples past the field's
  /// edge hold 0), or null.
  const std::vector<float>* original(std::uint64_t key) const;
  /// Restores every touched chunk's original heights and forgets them.
  void restore_all(Heightfield& hf);

 private:
  std::unordered_map<std::uint64_t, std::vector<float>> originals_;
};

}  // namespace ridgeline
