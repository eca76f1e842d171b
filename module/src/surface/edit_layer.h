// Private: the sparse edit layer of a terrain's Surface (docs/deformation.md). The surface's
// stored samples are edited in their pages (copies of the pages they lie in, so queries cost the
// same edited or not); the layer keeps, for every 32 x 32 chunk an edit touched, the chunk's
// original heights, so that the edits can be saved (the current values of the touched chunks)
// and undone (load_edits restores the originals first). Part of the surface: it knows pages, not
// brushes, transactions or limits (module/src/edit/ writes through it).
//
// It also owns the hole mask (hole_mask.h): holes are edits too, so they are cloned, saved,
// loaded and undone with the heights.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <unordered_map>
#include <vector>

#include "surface/hole_mask.h"
#include "world/page_store.h"

namespace ridgeline {

class EditLayer {
 public:
  EditLayer() = default;
  EditLayer(const EditLayer& o)
      : originals_(o.originals_), holes_(o.hole_snapshot()), baked_holes_(o.baked_holes_) {}
  EditLayer& operator=(const EditLayer&) = delete;

  static constexpr std::uint32_t kChunkShift = 5;
  static constexpr std::uint32_t kChunk = 1u << kChunkShift;  ///< samples per chunk side

  /// Records the original heights of the chunk holding sample (i, j) if not yet recorded,
  /// reading them through `edit` (before it writes them) from a field of width x height samples.
  void touch(world::PageEdit& edit, std::uint32_t i, std::uint32_t j, std::uint32_t width,
             std::uint32_t height);
  std::size_t chunks() const noexcept { return originals_.size(); }
  /// Chunk keys in ascending order (cz, cx): the save order.
  std::vector<std::uint64_t> sorted_keys() const;
  static std::uint64_t key(std::uint32_t cx, std::uint32_t cz) noexcept {
    return (std::uint64_t{cz} << 32) | cx;
  }
  /// Original heights of a touched chunk (kChunk * kChunk, row-major; samples past the field's
  /// edge hold 0), or null.
  const std::vector<float>* original(std::uint64_t key) const;
  /// Writes every touched chunk's original heights back through `edit` and forgets them.
  void restore_all(world::PageEdit& edit, std::uint32_t width, std::uint32_t height);
  /// Bytes held by the originals.
  std::size_t memory_bytes() const noexcept {
    return originals_.size() * (sizeof(float) * kChunk * kChunk + 48) +
           (holes_ ? holes_->memory_bytes() : 0);
  }

  /// The hole mask, or null when no cell is a hole. Read by queries (never during an edit).
  const HoleMask* holes() const noexcept { return holes_.get(); }
  /// The same as a snapshot that stays valid across later edits, for threads that may run
  /// while an edit publishes a new mask (pages loading and making their bounds).
  std::shared_ptr<const HoleMask> hole_snapshot() const {
    std::lock_guard lock(holes_mu_);
    return holes_;
  }
  /// The holes a baked world's bounds were made around (its own, from the open), or null: a
  /// Landscape remakes bounds only where the mask differs from them.
  const std::shared_ptr<const HoleMask>& baked_holes() const noexcept { return baked_holes_; }
  void set_baked_holes(std::shared_ptr<const HoleMask> m) { baked_holes_ = std::move(m); }
  /// Publishes a new mask (null or empty: no holes). Exclusive access (an edit).
  void set_holes(std::shared_ptr<const HoleMask> m) {
    if (m != nullptr && m->empty()) m.reset();
    std::lock_guard lock(holes_mu_);
    holes_ = std::move(m);
  }

 private:
  std::unordered_map<std::uint64_t, std::vector<float>> originals_;
  mutable std::mutex holes_mu_;
  std::shared_ptr<const HoleMask> holes_;
  std::shared_ptr<const HoleMask> baked_holes_;
};

}  // namespace ridgeline
