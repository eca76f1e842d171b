// The sparse edit layer (edit_layer.h): the original heights of every chunk an edit touched.
#include "surface/edit_layer.h"

#include <algorithm>

namespace ridgeline {

void EditLayer::touch(world::PageEdit& edit, std::uint32_t i, std::uint32_t j,
                      std::uint32_t width, std::uint32_t height) {
  const std::uint64_t k = key(i >> kChunkShift, j >> kChunkShift);
  auto [it, inserted] = originals_.try_emplace(k);
  if (!inserted) return;
  std::vector<float>& o = it->second;
  o.assign(std::size_t{kChunk} * kChunk, 0.0f);
  const std::uint32_t i0 = (i >> kChunkShift) << kChunkShift, j0 = (j >> kChunkShift)
                                                                   << kChunkShift;
  for (std::uint32_t dj = 0; dj < kChunk && j0 + dj < height; ++dj)
    for (std::uint32_t di = 0; di < kChunk && i0 + di < width; ++di)
      o[di + dj * kChunk] = edit.height(i0 + di, j0 + dj);
}

std::vector<std::uint64_t> EditLayer::sorted_keys() const {
  std::vector<std::uint64_t> keys;
  keys.reserve(originals_.size());
  for (const auto& kv : originals_) keys.push_back(kv.first);
  std::sort(keys.begin(), keys.end());
  return keys;
}

const std::vector<float>* EditLayer::original(std::uint64_t k) const {
  auto it = originals_.find(k);
  return it == originals_.end() ? nullptr : &it->second;
}

void EditLayer::restore_all(world::PageEdit& edit, std::uint32_t width, std::uint32_t height) {
  for (const auto& [k, o] : originals_) {
    const std::uint32_t i0 = std::uint32_t(k) << kChunkShift, j0 = std::uint32_t(k >> 32)
                                                                   << kChunkShift;
    for (std::uint32_t dj = 0; dj < kChunk && j0 + dj < height; ++dj)
      for (std::uint32_t di = 0; di < kChunk && i0 + di < width; ++di)
        if (edit.height(i0 + di, j0 + dj) != o[di + dj * kChunk])
          edit.write(i0 + di, j0 + dj, o[di + dj * kChunk]);
  }
  originals_.clear();
}

}  // namespace ridgeline
