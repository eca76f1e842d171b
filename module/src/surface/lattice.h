// Private: a Surface's finest lattice as the queries read it. Two views with one interface, so
// that every query is written once, as a template over the view (point_queries.cpp,
// ray_hierarchy.cpp), and with_lattice() picks the view once per call:
//  - StoredLattice (L = 0): vertex heights are the stored float samples, read directly;
//  - DetailLattice (L >= 1): vertex heights are the stored surface interpolated at the vertex
//    plus the detail there, in double (docs/surface.md, "Detail and edits").
// A view reads vertices and cells inside the lattice only (the public Surface calls clamp).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "ridgeline/heightfield.h"
#include "ridgeline/surface.h"
#include "surface/surface_eval.h"

namespace ridgeline::detail {

/// The stored samples as the finest lattice.
struct StoredLattice {
  using Height = float;
  static constexpr int levels = 0;
  static constexpr double scale = 1.0;  ///< 2^L: finest cells per stored cell side
  static constexpr double inv_scale = 1.0;
  const Heightfield& hf;
  const SurfaceLattice& at;

  Height local(std::int64_t i, std::int64_t j) const noexcept {
    return hf.local(std::uint32_t(i), std::uint32_t(j));
  }
  Height base(std::int64_t i, std::int64_t j) const noexcept { return local(i, j); }
  std::uint8_t material(std::int64_t i, std::int64_t j) const noexcept {
    return hf.material(std::uint32_t(i), std::uint32_t(j));
  }
  /// Starts fetching the samples of cell (i, j) into the cache (the next query's, in a batch).
  void prefetch(std::int64_t i, std::int64_t j) const noexcept {
    const float* row = hf.local_heights().data() + std::size_t(i) + std::size_t(j) * hf.width();
    __builtin_prefetch(row);
    __builtin_prefetch(row + hf.width());
  }
  // What vertex_normal() (surface_eval.h) reads.
  double spacing_x() const noexcept { return at.spacing_x; }
  double spacing_z() const noexcept { return at.spacing_z; }
  std::int64_t width() const noexcept { return at.vertices_x; }
  std::int64_t height() const noexcept { return at.vertices_z; }
};

/// The finest lattice of a surface with detail. (DetailLattice::local is base + detail; the
/// vertex's own detail comes from the surface: its cache or its field.)
struct DetailLattice {
  using Height = double;
  int levels;        ///< L >= 1
  double scale;      ///< 2^L
  double inv_scale;  ///< 2^-L
  const Heightfield& hf;
  const SurfaceLattice& at;
  const Surface& surface;  // for the detail (Surface::vertex_detail: the cache or the field)

  /// The stored surface at the vertex (its cell's triangle plane, evaluated exactly: the
  /// vertex's fractions are multiples of 2^-L) plus the detail there.
  Height local(std::int64_t i, std::int64_t j) const noexcept {
    return base(i, j) + surface.vertex_detail(i, j);
  }
  /// The stored surface alone at the vertex.
  Height base(std::int64_t i, std::int64_t j) const noexcept {
    const std::int64_t mask = (std::int64_t{1} << levels) - 1;
    std::int64_t k = i >> levels, m = j >> levels, fi = i & mask, fj = j & mask;
    // The far edge belongs to the last cell (fraction 1), as in the point queries.
    if (k == std::int64_t(hf.width()) - 1) --k, fi = mask + 1;
    if (m == std::int64_t(hf.height()) - 1) --m, fj = mask + 1;
    const float fu = std::ldexp(float(fi), -levels), fv = std::ldexp(float(fj), -levels);
    const CellPlane plane = cell_plane(hf, k, m, locate_in_cell(k, m, fu, fv));
    return plane.at(fu, fv);
  }
  std::uint8_t material(std::int64_t i, std::int64_t j) const noexcept {
    return hf.material(std::min(std::uint32_t(i >> levels), hf.width() - 2),
                       std::min(std::uint32_t(j >> levels), hf.height() - 2));
  }
  void prefetch(std::int64_t, std::int64_t) const noexcept {}  // detail dominates; nothing to gain
  double spacing_x() const noexcept { return at.spacing_x; }
  double spacing_z() const noexcept { return at.spacing_z; }
  std::int64_t width() const noexcept { return at.vertices_x; }
  std::int64_t height() const noexcept { return at.vertices_z; }
};

/// The view of `s`'s lattice of each kind (the caller knows which one `s` has).
inline StoredLattice stored_lattice(const Surface& s) noexcept {
  return {s.heightfield(), s.lattice()};
}
inline DetailLattice detail_lattice(const Surface& s) noexcept {
  const int L = int(s.lattice().levels);
  return {L, std::ldexp(1.0, L), std::ldexp(1.0, -L), s.heightfield(), s.lattice(), s};
}

/// Calls f(view) with the view of `s`'s lattice and returns what it returns.
template <class F>
decltype(auto) with_lattice(const Surface& s, F&& f) {
  if (s.lattice().levels == 0) return f(stored_lattice(s));
  return f(detail_lattice(s));
}

/// A point located on a lattice: its finest cell (i, j), the triangle under it and the local
/// heights of that triangle's corners (locate_in_cell's order).
template <class Lattice>
struct LatticePoint {
  std::int64_t i = 0, j = 0;
  CellTriangle tri;
  typename Lattice::Height h[3];
};

/// The finest cell (i, j) holding lattice position (u, v) (finest-lattice units from vertex
/// (0, 0), inside the lattice: a point on the far edges belongs to the last cell) and the
/// triangle under it: the one rule by which every query finds its triangle.
template <class Lattice>
[[gnu::always_inline]] inline CellTriangle cell_at(const Lattice& g, double u, double v,
                                                   std::int64_t& i, std::int64_t& j) noexcept {
  i = std::min(static_cast<std::int64_t>(u), g.at.vertices_x - 2);
  j = std::min(static_cast<std::int64_t>(v), g.at.vertices_z - 2);
  return locate_in_cell(i, j, static_cast<float>(u - double(i)), static_cast<float>(v - double(j)));
}

/// Finds the cell and triangle under world (x, z) and reads its corners; false off the footprint
/// (NaN fails the range test too).
template <class Lattice>
[[gnu::always_inline]] inline bool locate(const Lattice& g, double x, double z,
                                          LatticePoint<Lattice>& p) noexcept {
  const SurfaceLattice& at = g.at;
  const double u = (x - at.origin_x) * at.inv_spacing_x;
  const double v = (z - at.origin_z) * at.inv_spacing_z;
  const double max_u = double(at.vertices_x - 1), max_v = double(at.vertices_z - 1);
  if (!(u >= 0.0 && u <= max_u && v >= 0.0 && v <= max_v)) return false;
  p.tri = cell_at(g, u, v, p.i, p.j);
  // Written out: as a loop, -O3 versions it for a unit row stride and spills the heights.
  p.h[0] = g.local(p.i + p.tri.di[0], p.j + p.tri.dj[0]);
  p.h[1] = g.local(p.i + p.tri.di[1], p.j + p.tri.dj[1]);
  p.h[2] = g.local(p.i + p.tri.di[2], p.j + p.tri.dj[2]);
  return true;
}

}  // namespace ridgeline::detail
