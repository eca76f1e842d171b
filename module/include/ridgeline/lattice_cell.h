// The lattice cell (docs/surface.md, "The diagonal rule"): how a cell of any Ridgeline lattice is
// split into two triangles, and which of them holds a point. Defined once, below everything that
// uses it: the surface and its queries (surface.h includes this header), the procedural detail
// field, the tessellator's finest level and the error measurement.
#pragma once

#include <cstdint>

namespace ridgeline {

/// Diagonal rule in global lattice indices: cell (i, j) (between samples i..i+1 and j..j+1) is
/// split along (i, j)-(i+1, j+1) when i + j is even (the "main" diagonal), along
/// (i+1, j)-(i, j+1) when it is odd. This is the finest level of the 4-8 bintree triangulation
/// of patches that start at multiples of their size.
constexpr bool cell_has_main_diagonal(std::int64_t i, std::int64_t j) noexcept {
  return ((i + j) & 1) == 0;
}

/// One of the two triangles of a lattice cell, and the barycentric weights of a point in it.
/// Corners are given as offsets (di, dj) in {0, 1} from the cell's lower corner (i, j), in
/// counter-clockwise order seen from above (+y), i.e. a consistent winding for the mesh.
struct CellTriangle {
  std::uint8_t di[3];
  std::uint8_t dj[3];
  float w[3];          ///< barycentric weights of the point, summing to 1
  std::uint8_t which;  ///< 0 or 1: which of the cell's two triangles (0 is the one holding (0,0)
                       ///< for the main diagonal, the one holding (0,0) for the anti diagonal)
};

/// Locates the point with fractional position (fu, fv) in [0, 1]^2 inside cell (i, j).
/// Points on the cell's diagonal belong to triangle 0. Seen from above with x to the right and z
/// down the page (image rows), the counter-clockwise order about +y is (0,0) -> (0,1) -> (1,1) for
/// a triangle whose normal points up: with y up and the right-handed frame (x, y, z), a triangle
/// (p0, p1, p2) faces +y when (p1 - p0) x (p2 - p0) has positive y.
constexpr CellTriangle locate_in_cell(std::int64_t i, std::int64_t j, float fu, float fv) noexcept {
  if (cell_has_main_diagonal(i, j)) {
    // Diagonal (0,0)-(1,1).
    if (fu >= fv)  // triangle (0,0), (1,1), (1,0)
      return {{0, 1, 1}, {0, 1, 0}, {1.0f - fu, fv, fu - fv}, 0};
    // triangle (0,0), (0,1), (1,1)
    return {{0, 0, 1}, {0, 1, 1}, {1.0f - fv, fv - fu, fu}, 1};
  }
  // Diagonal (1,0)-(0,1).
  if (fu + fv <= 1.0f)  // triangle (0,0), (0,1), (1,0)
    return {{0, 0, 1}, {0, 1, 0}, {1.0f - fu - fv, fv, fu}, 0};
  // triangle (1,0), (0,1), (1,1)
  return {{1, 0, 1}, {0, 1, 1}, {1.0f - fv, 1.0f - fu, fu + fv - 1.0f}, 1};
}

}  // namespace ridgeline
