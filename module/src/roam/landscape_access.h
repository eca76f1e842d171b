// Private: the tessellator's inline reads of a Landscape's per-vertex records (the public
// accessors Landscape::diamond(), shading() and lattice_height() are the same reads out of line).
#pragma once

#include "ridgeline/landscape.h"
#include "ridgeline/terrain.h"

namespace ridgeline::roam {

struct LandscapeAccess {
  /// True when vertex (i, j) has a stored record (no procedural detail, inside the stored
  /// lattice with its padding).
  static bool stored(const Landscape& l, std::int64_t i, std::int64_t j) noexcept {
    return l.detail_ == 0 && i >= 0 && j >= 0 && i < l.stored_w_ && j < l.stored_h_;
  }
  static const Landscape::VertexRecord& record(const Landscape& l, std::int64_t i,
                                               std::int64_t j) noexcept {
    return l.records_[l.stored_index(i, j)];
  }
  static DiamondBound diamond(const Landscape& l, std::int64_t i, std::int64_t j) noexcept {
    return stored(l, i, j) ? record(l, i, j).bound : l.diamond_slow(i, j);
  }
  static VertexShading shading(const Landscape& l, std::int64_t i, std::int64_t j) noexcept {
    return stored(l, i, j) ? Landscape::unpack(record(l, i, j)) : l.compute_shading(i, j);
  }
  static float height(const Landscape& l, std::int64_t i, std::int64_t j) noexcept {
    if (l.detail_ != 0) return static_cast<float>(l.terrain_->fine_local_height(i, j));
    // The copy kept beside the bounds (one cache line for everything about a vertex).
    if (i >= 0 && j >= 0 && i < l.stored_w_ && j < l.stored_h_) return record(l, i, j).height;
    return l.terrain_->heightfield().local_clamped(i, j);
  }
  /// The bounds and height of a stored vertex in one read; false (nothing written) when the
  /// vertex has no stored record.
  static bool bound_and_height(const Landscape& l, std::int64_t i, std::int64_t j, DiamondBound& b,
                               float& y) noexcept {
    if (!stored(l, i, j)) return false;
    const Landscape::VertexRecord& r = record(l, i, j);
    b = r.bound;
    y = r.height;
    return true;
  }
  /// The address of what the reads above touch for vertex (i, j) (a prefetch hint; some valid
  /// address when it has no record).
  static const void* address(const Landscape& l, std::int64_t i, std::int64_t j) noexcept {
    return l.records_.data() + (stored(l, i, j) ? l.stored_index(i, j) : 0);
  }
};

}  // namespace ridgeline::roam
