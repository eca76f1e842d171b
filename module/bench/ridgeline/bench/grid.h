// The lattice the comparators read (meshes.h, soar.h), and a terrain's finest lattice baked into a
// heightfield for them.
#pragma once

#include <cstdint>

#include "ridgeline/heightfield.h"
#include "ridgeline/result.h"
#include "ridgeline/terrain.h"

namespace ridgeline::bench {

/// The lattice the comparators read: a heightfield's samples, or a terrain's stored samples read
/// through its surface (so that its edits show). Holds a pointer to either, which must outlive
/// it. The accessors mirror Heightfield's.
class Grid {
 public:
  Grid(const Heightfield& hf)  // NOLINT: implicit, a heightfield is a grid
      : hf_(&hf),
        w_(hf.width()), h_(hf.height()),
        sx_(hf.spacing_x()), sz_(hf.spacing_z()), ox_(hf.origin_x()), oz_(hf.origin_z()),
        offset_(hf.height_offset()) {}
  explicit Grid(const Terrain& t)
      : t_(&t),
        w_(t.info().width), h_(t.info().height),
        sx_(t.info().spacing_x), sz_(t.info().spacing_z), ox_(t.info().origin_x),
        oz_(t.info().origin_z), offset_(t.info().height_offset) {}
  std::uint32_t width() const noexcept { return w_; }
  std::uint32_t height() const noexcept { return h_; }
  double spacing_x() const noexcept { return sx_; }
  double spacing_z() const noexcept { return sz_; }
  double origin_x() const noexcept { return ox_; }
  double origin_z() const noexcept { return oz_; }
  double height_offset() const noexcept { return offset_; }
  double extent_x() const noexcept { return double(w_ - 1) * sx_; }
  double extent_z() const noexcept { return double(h_ - 1) * sz_; }
  float local(std::int64_t i, std::int64_t j) const noexcept {
    return hf_ ? hf_->local(std::uint32_t(i), std::uint32_t(j))
               : t_->surface().stored_height(i, j);
  }
  float local_clamped(std::int64_t i, std::int64_t j) const noexcept {
    return hf_ ? hf_->local_clamped(i, j) : t_->surface().stored_height(i, j);
  }
  double world(std::int64_t i, std::int64_t j) const noexcept {
    return offset_ + double(local(i, j));
  }

 private:
  const Heightfield* hf_ = nullptr;
  const Terrain* t_ = nullptr;
  std::uint32_t w_ = 0, h_ = 0;
  double sx_ = 1, sz_ = 1, ox_ = 0, oz_ = 0, offset_ = 0;
};

/// The finest lattice of `terrain` (base + detail + edits, Surface::vertex_height) baked into a
/// heightfield (spacing / 2^L with L detail levels): what the comparators draw from and what the
/// error is measured against. Fails when the lattice exceeds 2^31 samples.
Result<Heightfield> finest_lattice(const Terrain& terrain);

}  // namespace ridgeline::bench
