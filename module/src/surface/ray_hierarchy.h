// Private: the min/max-height pyramid that raycasts descend and box queries cull with, and the
// exact per-cell surface evaluation they share (see ray_hierarchy.cpp).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <optional>
#include <string>
#include <vector>

#include "ridgeline/heightfield.h"
#include "ridgeline/surface.h"
#include "ridgeline/terrain.h"
#include "surface/surface_eval.h"

namespace ridgeline {

namespace detail {

/// Height (metres, relative to the heightfield's offset) of the plane of lattice triangle `t` of
/// cell (i, j) at fractional position (fu, fv) of the cell, in double precision. (fu, fv) may lie
/// slightly outside the triangle: the plane is extrapolated. The plane is derived from the
/// triangle's corners as locate_in_cell() gives them, so the diagonal rule lives in surface.h only.
struct CellPlane {
  double h0;   ///< height at the first corner
  double c0u;  ///< first corner, cell fractions
  double c0v;
  double gu, gv;  ///< height gradient per cell fraction along u (x) and v (z)
  double at(double fu, double fv) const noexcept { return h0 + gu * (fu - c0u) + gv * (fv - c0v); }
};

/// The plane of lattice triangle `t` whose corners have heights h0, h1, h2 (corner order of t).
inline CellPlane plane_of(const CellTriangle& t, double h0, double h1, double h2) noexcept {
  const double e1u = double(t.di[1]) - t.di[0], e1v = double(t.dj[1]) - t.dj[0];
  const double e2u = double(t.di[2]) - t.di[0], e2v = double(t.dj[2]) - t.dj[0];
  // The corners of a lattice triangle span a unit-area parallelogram: det is +-1.
  const double det = e1u * e2v - e1v * e2u;
  const double gu = ((h1 - h0) * e2v - (h2 - h0) * e1v) * det;  // 1 / det == det
  const double gv = ((h2 - h0) * e1u - (h1 - h0) * e2u) * det;
  return {h0, double(t.di[0]), double(t.dj[0]), gu, gv};
}

/// `Grid` is a Heightfield or a finest-lattice view with the same local(i, j).
template <class Grid>
inline CellPlane cell_plane(const Grid& hf, std::uint32_t i, std::uint32_t j,
                            const CellTriangle& t) noexcept {
  return plane_of(t, hf.local(i + t.di[0], j + t.dj[0]), hf.local(i + t.di[1], j + t.dj[1]),
                  hf.local(i + t.di[2], j + t.dj[2]));
}

/// v / |v|. Unlike glm::normalize (v * inversesqrt), a vector along an axis comes out exactly
/// unit (sqrt(c * c) == |c| in IEEE arithmetic): a flat field's normal is exactly (0, 1, 0).
template <class V>
inline V unit(const V& v) noexcept {
  return v / std::sqrt(glm::dot(v, v));
}

/// Unit upward normal of a triangle's plane: (-dh/dx, 1, -dh/dz) normalised. `inv_sx`, `inv_sz`
/// are 1 / spacing. A flat triangle gives exactly (0, 1, 0).
inline glm::vec3 plane_normal(const CellPlane& p, double inv_sx, double inv_sz) noexcept {
  const double nx = -p.gu * inv_sx, nz = -p.gv * inv_sz;
  const double inv_len = 1.0 / std::sqrt(nx * nx + 1.0 + nz * nz);
  return {float(nx * inv_len), float(inv_len), float(nz * inv_len)};
}

/// Unit upward face normal of lattice triangle `t` of cell (i, j).
inline glm::vec3 face_normal(const Heightfield& hf, double inv_sx, double inv_sz, std::uint32_t i,
                             std::uint32_t j, const CellTriangle& t) noexcept {
  return plane_normal(cell_plane(hf, i, j, t), inv_sx, inv_sz);
}

/// Triangle `which` (0 or 1, as CellTriangle::which) of cell (i, j), located through
/// locate_in_cell() at a point strictly inside it.
inline CellTriangle cell_triangle(std::int64_t i, std::int64_t j, int which) noexcept {
  // Probe points: one inside each triangle for either diagonal, tried in turn.
  constexpr float kProbe[4][2] = {{0.75f, 0.25f}, {0.25f, 0.75f}, {0.25f, 0.25f}, {0.75f, 0.75f}};
  CellTriangle t = locate_in_cell(i, j, kProbe[0][0], kProbe[0][1]);
  for (int k = 1; k < 4 && t.which != which; ++k)
    t = locate_in_cell(i, j, kProbe[k][0], kProbe[k][1]);
  return t;
}

}  // namespace detail

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

  /// See Terrain::raycast.
  std::optional<RayHit> raycast(const Heightfield& hf, const glm::dvec3& origin,
                                const glm::dvec3& direction, double max_distance) const noexcept;

  /// See Terrain::raycast, on a terrain with procedural detail: the pyramid of the stored heights
  /// is widened by the detail field's amplitude bound, and leaf blocks are walked cell by cell on
  /// the finest lattice (heights from Terrain::fine_local_height).
  std::optional<RayHit> raycast_fine(const Terrain& terrain, const glm::dvec3& origin,
                                     const glm::dvec3& direction, double max_distance) const noexcept;

  /// See Terrain::triangles_in_box, on a terrain with detail (finest triangles).
  std::size_t triangles_in_box_fine(const Terrain& terrain, const Box& box,
                                    std::vector<SurfaceTriangle>& out,
                                    std::size_t max_triangles) const;

  /// See Terrain::triangles_in_box.
  std::size_t triangles_in_box(const Heightfield& hf, const Box& box,
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

  // The ray walk shared by both surfaces; `Mode` (BaseMode, FineMode in ray_hierarchy.cpp)
  // evaluates the surface under a point, widens node maxima and walks leaf blocks.
  struct BaseMode;
  struct FineMode;
  template <class Mode>
  std::optional<RayHit> raycast_impl(const Mode& mode, const Heightfield& hf,
                                     const glm::dvec3& origin, const glm::dvec3& direction,
                                     double max_distance) const noexcept;
  template <class Grid>
  std::size_t boxes_impl(const Grid& g, const Heightfield& hf, int L, double widen,
                         const Box& box, std::vector<SurfaceTriangle>& out,
                         std::size_t max_triangles) const;
  // Tests the cells [ci0, ci1] x [cj0, cj1] of `grid` that the ray (in grid units) crosses
  // during [ta, tb], in ray order.
  template <class Grid>
  bool walk_cells(const Grid& grid, const Ray& r, std::int64_t ci0, std::int64_t cj0,
                  std::int64_t ci1, std::int64_t cj1, double ta, double tb,
                  RayHit& hit) const noexcept;

  std::vector<Level> levels_;
  double inv_sx_ = 1, inv_sz_ = 1;  // 1 / spacing
  double touch_ = 1e-9;
};

}  // namespace ridgeline
