// Private: evaluation of the surface of surface.h on a lattice (heights relative to the height
// offset): triangle planes, face and vertex normals. Shared by the point queries, the ray and box
// queries (through lattice.h) and the edit transaction.
#pragma once

#include <cmath>
#include <cstdint>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "ridgeline/surface.h"

namespace ridgeline::detail {

/// Height (metres, relative to the height offset) of the plane of lattice triangle `t` of a cell
/// at fractional position (fu, fv) of the cell, in double precision. (fu, fv) may lie slightly
/// outside the triangle: the plane is extrapolated. The plane is derived from the triangle's
/// corners as locate_in_cell() gives them, so the diagonal rule lives in surface.h only.
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

/// The plane of triangle `t` of cell (i, j) of `grid`: a Heightfield or a lattice of lattice.h
/// (anything with local(i, j)).
template <class Grid>
inline CellPlane cell_plane(const Grid& grid, std::int64_t i, std::int64_t j,
                            const CellTriangle& t) noexcept {
  return plane_of(t, grid.local(i + t.di[0], j + t.dj[0]), grid.local(i + t.di[1], j + t.dj[1]),
                  grid.local(i + t.di[2], j + t.dj[2]));
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

/// Triangle `which` (0 or 1, as CellTriangle::which) of cell (i, j), located through
/// locate_in_cell() at a point strictly inside it.
inline CellTriangle cell_triangle(std::int64_t i, std::int64_t j, int which) noexcept {
  // Main diagonal: (0.75, 0.25) lies in triangle 0, (0.25, 0.75) in 1. Anti diagonal: (0.25,
  // 0.25) in 0, (0.75, 0.75) in 1.
  const bool main = cell_has_main_diagonal(i, j);
  const float fu = main ? (which == 0 ? 0.75f : 0.25f) : (which == 0 ? 0.25f : 0.75f);
  const float fv = which == 0 ? 0.25f : 0.75f;
  return locate_in_cell(i, j, fu, fv);
}

/// Unnormalised upward normal of the lattice triangle with corners (i + di[k], j + dj[k]), i.e.
/// (p1 - p0) x (p2 - p0) in metres^2 (its length is twice the triangle's area). `Grid` has
/// spacing_x(), spacing_z() and local(i, j).
template <class Grid>
inline glm::dvec3 cell_triangle_cross(const Grid& grid, std::int64_t i, std::int64_t j,
                                      const CellTriangle& t) {
  const double sx = grid.spacing_x(), sz = grid.spacing_z();
  glm::dvec3 p[3];
  for (int k = 0; k < 3; ++k)
    p[k] = {t.di[k] * sx, double(grid.local(i + t.di[k], j + t.dj[k])), t.dj[k] * sz};
  return glm::cross(p[1] - p[0], p[2] - p[0]);
}

/// Area-weighted vertex normal at lattice vertex (i, j), which must lie in the lattice: the
/// normalised sum of the cross products of every triangle that has (i, j) as a corner. `Grid`
/// has width() and height() (vertices per axis) besides cell_triangle_cross()'s accessors.
template <class Grid>
inline glm::vec3 vertex_normal(const Grid& grid, std::int64_t i, std::int64_t j) {
  glm::dvec3 sum(0.0);
  const std::int64_t w = std::int64_t(grid.width()), h = std::int64_t(grid.height());
  for (int cj = -1; cj <= 0; ++cj) {
    for (int ci = -1; ci <= 0; ++ci) {
      const std::int64_t ii = i + ci, jj = j + cj;
      if (ii < 0 || jj < 0 || ii + 1 >= w || jj + 1 >= h) continue;
      // The vertex's position inside this cell, as fractions.
      const int du = -ci, dv = -cj;  // 0 or 1
      // Both triangles of the cell; keep those with the vertex as a corner.
      for (int which = 0; which < 2; ++which) {
        const CellTriangle t = cell_triangle(ii, jj, which);
        bool has = false;
        for (int k = 0; k < 3; ++k) has |= (t.di[k] == du && t.dj[k] == dv);
        if (has) sum += cell_triangle_cross(grid, ii, jj, t);
      }
    }
  }
  return glm::vec3(glm::normalize(sum));
}

}  // namespace ridgeline::detail
