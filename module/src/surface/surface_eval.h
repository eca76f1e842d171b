// Private: evaluation of the surface of surface.h on the stored lattice (heights relative to the
// heightfield's offset). Shared by queries, the mesh output and the error measurement.
#pragma once

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "ridgeline/heightfield.h"
#include "ridgeline/surface.h"

namespace ridgeline::detail {

/// Unnormalised upward normal of the lattice triangle with corners (i + di[k], j + dj[k]), i.e.
/// (p1 - p0) x (p2 - p0) in metres^2 (its length is twice the triangle's area).
/// `Grid` is a Heightfield or any lattice with the same accessors (spacing_x/z(), width(),
/// height(), local(i, j)): the terrain's finest lattice with detail (terrain.cpp).
template <class Grid>
inline glm::dvec3 cell_triangle_cross(const Grid& hf, std::uint32_t i, std::uint32_t j,
                                      const CellTriangle& t) {
  const double sx = hf.spacing_x(), sz = hf.spacing_z();
  glm::dvec3 p[3];
  for (int k = 0; k < 3; ++k)
    p[k] = {t.di[k] * sx, double(hf.local(i + t.di[k], j + t.dj[k])), t.dj[k] * sz};
  return glm::cross(p[1] - p[0], p[2] - p[0]);
}

/// Area-weighted vertex normal at lattice vertex (i, j): the normalised sum of the cross products
/// of every finest triangle that has (i, j) as a corner.
template <class Grid>
inline glm::vec3 vertex_normal(const Grid& hf, std::uint32_t i, std::uint32_t j) {
  glm::dvec3 sum(0.0);
  const std::int64_t w = std::int64_t(hf.width()), h = std::int64_t(hf.height());
  for (int cj = -1; cj <= 0; ++cj) {
    for (int ci = -1; ci <= 0; ++ci) {
      const std::int64_t ii = std::int64_t(i) + ci, jj = std::int64_t(j) + cj;
      if (ii < 0 || jj < 0 || ii + 1 >= w || jj + 1 >= h) continue;
      // The vertex's position inside this cell, as fractions.
      const int du = -ci, dv = -cj;  // 0 or 1
      // Both triangles of the cell; keep those with the vertex as a corner.
      for (int which = 0; which < 2; ++which) {
        // Pick a point strictly inside each triangle to get it from locate_in_cell.
        const bool main = cell_has_main_diagonal(ii, jj);
        const float fu = main ? (which == 0 ? 0.75f : 0.25f) : (which == 0 ? 0.25f : 0.75f);
        const float fv = main ? (which == 0 ? 0.25f : 0.75f) : (which == 0 ? 0.25f : 0.75f);
        const CellTriangle t = locate_in_cell(ii, jj, fu, fv);
        bool has = false;
        for (int k = 0; k < 3; ++k) has |= (t.di[k] == du && t.dj[k] == dv);
        if (has)
          sum += cell_triangle_cross(hf, static_cast<std::uint32_t>(ii),
                                     static_cast<std::uint32_t>(jj), t);
      }
    }
  }
  return glm::vec3(glm::normalize(sum));
}

}  // namespace ridgeline::detail
