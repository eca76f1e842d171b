// Private: the min/max-height pyramid over a surface's stored samples that raycasts descend and
// box queries cull with, and those two queries, written once over the surface's finest lattice
// (see ray_hierarchy.cpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <glm/vec3.hpp>
#include <optional>
#include <string>
#include <vector>

#include "ridgeline/heightfield.h"
#include "ridgeline/surface.h"

namespace ridgeline {

/// Min/max pyramid over the heightfield. Level 0 holds one node per block of kLeafCells x
/// kLeafCells cells (the block's samples including its borders); each level above halves the node
/// count per axis, up to a single root. Immutable after construction; const calls are thread-safe.
class RayHierarchy {
 public:
  static constexpr std::uint32_t kLeafShift = 2;  ///< log2 of the leaf block size in cells
  static constexpr std::uint32_t kLeafCells = 1u << kLeafShift;

  explicit RayHierarchy(const Heightfield& hf);
  RayHierarchy(const RayHierarchy&) = default;

  /// Recomputes the pyramid over the cells [i0, i1] x [j0, j1] (inclusive cell indices) after
  /// their heights changed: the leaf blocks holding them, then their ancestors, and the touch
  /// tolerance from the field's (widened) height range. Cost: the blocks' samples plus the
  /// ancestors, about the edited area.
  void update_cells(const Heightfield& hf, std::uint32_t i0, std::uint32_t j0, std::uint32_t i1,
                    std::uint32_t j1);

  /// Bytes held by the pyramid.
  std::size_t memory_bytes() const noexcept;

  /// Compares two pyramids node by node (levels, sizes, every minimum and maximum, the touch
  /// tolerance). Empty when equal, else the first difference.
  std::string compare(const RayHierarchy& other) const;

  /// See Terrain::raycast: the ray against `surface`'s finest lattice, descending this pyramid
  /// (built over `surface`'s stored samples) widened by the surface's detail bound.
  std::optional<RayHit> raycast(const Surface& surface, const glm::dvec3& origin,
                                const glm::dvec3& direction, double max_distance) const noexcept;

  /// See Terrain::triangles_in_box: `surface`'s finest triangles, blocks culled by this pyramid.
  std::size_t triangles_in_box(const Surface& surface, const Box& box,
                               std::vector<SurfaceTriangle>& out, std::size_t max_triangles) const;

  /// Number of levels (level 0 = leaf blocks).
  std::size_t levels() const noexcept { return levels_.size(); }

  /// A ray "touches" the surface where its height above it is at most this (metres): about a
  /// million units of double rounding of the field's largest local height, far below anything
  /// physical (1e-9 * (1 + max |local height|)).
  double touch_tolerance() const noexcept { return touch_; }

 private:
  struct Level {
    std::uint32_t nx = 0, nz = 0;  ///< nodes per axis
    // Row-major, index = x + z * nx; local heights (relative to the offset), metres. Kept apart
    // so that rays, which only read maxima, touch half the memory.
    std::vector<float> max, min;
    std::size_t index(std::int64_t x, std::int64_t z) const noexcept {
      return std::size_t(x) + std::size_t(z) * nx;
    }
  };
  struct Ray;
  void leaf_block(const Heightfield& hf, std::uint32_t bx, std::uint32_t bz);
  void parent_node(std::size_t level, std::uint32_t x, std::uint32_t z);

  // The queries over a lattice view of surface/lattice.h (one per view).
  template <class Lattice>
  std::optional<RayHit> raycast_impl(const Lattice& g, double widen, const glm::dvec3& origin,
                                     const glm::dvec3& direction,
                                     double max_distance) const noexcept;
  template <class Lattice>
  bool walk_leaf(const Lattice& g, const Ray& r, std::uint32_t bx, std::uint32_t bz, double ta,
                 double tb, RayHit& hit) const noexcept;
  template <class Lattice>
  std::size_t boxes_impl(const Lattice& g, double widen, const Box& box,
                         std::vector<SurfaceTriangle>& out, std::size_t max_triangles) const;

  std::vector<Level> levels_;
  double inv_sx_ = 1, inv_sz_ = 1;  // 1 / spacing
  double touch_ = 1e-9;
};

}  // namespace ridgeline
