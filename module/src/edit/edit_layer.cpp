// The sparse edit layer (edit_layer.h): the original heights of every chunk an edit touched.
#include "edit/edit_layer.h"

#include <algorithm>

namespace ridgeline {

void EditLayer::touch(const Heightfield& hf, std::uint32_t i, std::uint32_t j) {
  const std::uint64_t k = key(i >> kChunkShift, j >> kChunkShift);
  auto [it, inserted] = originals_.try_emplace(k);
  if (!inserted) return;
  std::vector<float>& o = it->second;
  o.assign(std::size_t{kChunk} * kChunk, 0.0f);
  const std::uint32_t i0 = (i >> kChunkShift) << kChunkShift, j0 = (j >> kChunkShift)
                                                                   << kChunkShift;
  for (std::uint32_t dj = 0; dj < kChunk && j0 + dj < hf.height(); ++dj)
    for (std::uint32_t di = 0; di < kChunk && i0 + di < hf.width(); ++di)
      o[di + dj * kChunk] = hf.local(i0 + di, j0 + dj);
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

void EditLayer::restore_all(Heightfield& hf) {
  for (const auto& [k, o] : originals_) {
    const std::uint32_t i0 = std::uint32_t(k) << kChunkShift, j0 = std::uint32_t(k >> 32)
                                                                   << kChunkShift;
    for (std::uint32_t dj = 0; dj < kChunk && j0 + dj < hf.height(); ++dj)
      for (std::uint32_t di = 0; di < kChunk && i0 + di < hf.width(); ++di)
        write(hf, i0 + di, j0 + dj, o[di + dj * kChunk]);
  }
  originals_.clear();
}

}  // namespace ridgeline
