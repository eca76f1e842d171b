// Private: the ray and box queries of a surface (Terrain::raycast, Terrain::triangles_in_box),
// written once over the surface's finest lattice, descending the min/max pyramid of its pages:
// inside a level-0 page its ray pyramid (world/page.h: blocks of 4 x 4 cells up to 2 x 2 nodes),
// above it the store's pyramid over pages (one node per page, halving up to one node).
#pragma once

#include <cstddef>
#include <cstdint>
#include <glm/vec3.hpp>
#include <optional>
#include <string>
#include <vector>

#include "ridgeline/surface.h"

namespace ridgeline {

namespace world {
class PageStore;
}

/// The queries; stateless (everything lives in the surface's pages). Const calls are
/// thread-safe as the surface's are.
class RayQueries {
 public:
  static constexpr std::uint32_t kLeafShift = 2;  ///< log2 of the leaf block size in cells
  static constexpr std::uint32_t kLeafCells = 1u << kLeafShift;

  /// See Terrain::raycast: the ray against `surface`'s finest lattice, descending the pyramid
  /// (built over the stored samples) widened by the surface's detail bound.
  static std::optional<RayHit> raycast(const Surface& surface, const glm::dvec3& origin,
                                       const glm::dvec3& direction,
                                       double max_distance) noexcept;

  /// See Terrain::triangles_in_box: `surface`'s finest triangles, blocks culled by the pyramid.
  static std::size_t triangles_in_box(const Surface& surface, const Box& box,
                                      std::vector<SurfaceTriangle>& out,
                                      std::size_t max_triangles);

  /// A ray "touches" the surface where its height above it is at most this (metres): about a
  /// million units of double rounding of the field's largest local height, far below anything
  /// physical (1e-9 * (1 + max |local height|)).
  static double touch_tolerance(const Surface& surface) noexcept;

  /// Compares every resident page's ray pyramid, every page summary and the pyramid above pages
  /// with ones rebuilt from the samples. Empty when equal, else the first difference.
  static std::string check(const world::PageStore& store);

 private:
  struct Ray;
  template <class Lattice>
  static std::optional<RayHit> raycast_impl(const Lattice& g, const Surface& s, double widen,
                                            const glm::dvec3& origin, const glm::dvec3& direction,
                                            double max_distance) noexcept;
  template <class Lattice>
  static bool walk_leaf(const Lattice& g, double touch, const Ray& r, std::uint32_t bx,
                        std::uint32_t bz, double ta, double tb, RayHit& hit) noexcept;
  template <class Lattice>
  static std::size_t boxes_impl(const Lattice& g, double widen, const Box& box,
                                std::vector<SurfaceTriangle>& out, std::size_t max_triangles);
};

}  // namespace ridgeline
