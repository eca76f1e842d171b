// Private: a Surface's finest lattice as the queries read it. Two views with one interface, so
// that every query is written once, as a template over the view (point_queries.cpp,
// ray_queries.cpp), and with_lattice() picks the view once per call:
//  - StoredLattice (L = 0): vertex heights are the stored samples, read from their pages;
//  - DetailLattice (L >= 1): vertex heights are the stored surface interpolated at the vertex
//    plus the detail there, in double (docs/surface.md, "Detail and edits").
// A view reads vertices and cells inside the lattice only (the public Surface calls clamp). A view
// lives for one query (or one batch) on one thread: it keeps the page table snapshot it started
// with and the last page it read, and loads a missing page on the spot (a synchronous load).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>

#include "platform/memory_hints.h"
#include "ridgeline/surface.h"
#include "surface/hole_mask.h"
#include "surface/surface_eval.h"
#include "world/page_store.h"

namespace ridgeline::detail {

/// The stored samples as the finest lattice.
struct StoredLattice {
  using Height = float;
  static constexpr int levels = 0;
  static constexpr double scale = 1.0;  ///< 2^L: finest cells per stored cell side
  static constexpr double inv_scale = 1.0;
  const world::PageStore& store;
  const SurfaceLattice& at;
  mutable const world::PageTable* table;
  mutable std::shared_ptr<const world::PageTable> keep;  // a snapshot taken by a synchronous load
  mutable const world::Page* page = nullptr;             // the page read last
  mutable std::int64_t pi0 = 0, pj0 = 0;                 // its sample (0, 0)
  /// A page could not be loaded: what was read from it is 0 and the query answers nothing.
  mutable bool missing = false;
  /// The surface's holes, null without any (one well-predicted branch per query then).
  const HoleMask* holes = nullptr;

  StoredLattice(const world::PageStore& s, const SurfaceLattice& a,
                const HoleMask* h = nullptr) noexcept
      : store(s), at(a), table(&s.current()), holes(h) {}

  /// Whether cell (i, j) of this lattice lies in a hole.
  bool hole(std::int64_t i, std::int64_t j) const noexcept {
    return holes != nullptr && holes->hole(i, j);
  }

  /// A page holding stored sample (i, j) (the last one read when its entries hold it).
  const world::Page* page_at(std::int64_t i, std::int64_t j) const noexcept {
    if (page != nullptr && i - pi0 >= -kPageApron && i - pi0 <= kPageCells + kPageApron &&
        j - pj0 >= -kPageApron && j - pj0 <= kPageCells + kPageApron)
      return page;
    const PageKey k = store.grid().page_of(0, i, j);
    const world::Page* p = table->find(k);
    if (p == nullptr) {
      p = store.require(k, keep);
      if (p == nullptr) return nullptr;
      table = keep.get();
    }
    page = p;
    pi0 = std::int64_t(k.px) << 8, pj0 = std::int64_t(k.pz) << 8;
    return p;
  }
  /// Page `k` itself (found, or loaded on the spot); null when it cannot be loaded.
  const world::Page* page_of_key(const PageKey& k) const noexcept {
    const world::Page* p = table->find(k);
    if (p == nullptr) {
      p = store.require(k, keep);
      if (p == nullptr) {
        missing = true;
        return nullptr;
      }
      table = keep.get();
    }
    return p;
  }
  Height local(std::int64_t i, std::int64_t j) const noexcept {
    const world::Page* p = page_at(i, j);
    if (p == nullptr) {
      missing = true;
      return 0.0f;
    }
    return p->local(std::int32_t(i - pi0), std::int32_t(j - pj0));
  }
  Height base(std::int64_t i, std::int64_t j) const noexcept { return local(i, j); }
  std::uint8_t material(std::int64_t i, std::int64_t j) const noexcept {
    const world::Page* p = page_at(i, j);
    return p ? p->material(std::int32_t(i - pi0), std::int32_t(j - pj0)) : 0;
  }
  /// Starts fetching the samples of cell (i, j) into the cache (the next query's, in a batch):
  /// only when its page is resident.
  void prefetch(std::int64_t i, std::int64_t j) const noexcept {
    const PageKey k = store.grid().page_of(0, i, j);
    if (const world::Page* p = table->find(k)) {
      const std::size_t e = world::entry_index(std::int32_t(i - (std::int64_t(k.px) << 8)),
                                               std::int32_t(j - (std::int64_t(k.pz) << 8)));
      const char* a = p->f32 ? reinterpret_cast<const char*>(p->f32 + e)
                             : reinterpret_cast<const char*>(p->u16 + e);
      detail::prefetch(a);
      detail::prefetch(a + (p->f32 ? 4 : 2) * kPageStride);
    }
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
  StoredLattice stored;
  const SurfaceLattice& at;
  const Surface& surface;  // for the detail (Surface::vertex_detail: the cache or the field)
  mutable bool missing = false;

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
    if (k == stored.store.grid().last_i) --k, fi = mask + 1;
    if (m == stored.store.grid().last_j) --m, fj = mask + 1;
    const float fu = std::ldexp(float(fi), -levels), fv = std::ldexp(float(fj), -levels);
    const CellPlane plane = cell_plane(stored, k, m, locate_in_cell(k, m, fu, fv));
    missing |= stored.missing;
    return plane.at(fu, fv);
  }
  std::uint8_t material(std::int64_t i, std::int64_t j) const noexcept {
    return stored.material(std::min(i >> levels, stored.store.grid().last_i - 1),
                           std::min(j >> levels, stored.store.grid().last_j - 1));
  }
  /// Whether finest cell (i, j) lies in a hole (that of the stored cell holding it).
  bool hole(std::int64_t i, std::int64_t j) const noexcept {
    return stored.holes != nullptr && stored.holes->hole(i >> levels, j >> levels);
  }
  void prefetch(std::int64_t, std::int64_t) const noexcept {}  // detail dominates; nothing to gain
  double spacing_x() const noexcept { return at.spacing_x; }
  double spacing_z() const noexcept { return at.spacing_z; }
  std::int64_t width() const noexcept { return at.vertices_x; }
  std::int64_t height() const noexcept { return at.vertices_z; }
};

/// What the lattice views read of a Surface's private parts.
struct SurfaceAccess {
  static const world::PageStore& store(const Surface& s) noexcept { return *s.store_; }
  static world::PageStore& store(Surface& s) noexcept { return *s.store_; }
  /// The stored samples' placement as a lattice (L = 0).
  static const SurfaceLattice& stored_at(const Surface& s) noexcept { return s.stored_at_; }
  static EditLayer& edits(Surface& s) noexcept { return *s.edits_; }
  static const EditLayer& edits(const Surface& s) noexcept { return *s.edits_; }
  static const HoleMask* holes(const Surface& s) noexcept { return s.holes_; }
  /// Replaces the holes (an edit's transaction: exclusive access).
  static void publish_holes(Surface& s, std::shared_ptr<const HoleMask> m) {
    s.publish_holes(std::move(m));
  }
};

/// The view of `s`'s lattice of each kind (the caller knows which one `s` has).
inline StoredLattice stored_lattice(const Surface& s) noexcept {
  return StoredLattice(SurfaceAccess::store(s), SurfaceAccess::stored_at(s),
                       SurfaceAccess::holes(s));
}
inline DetailLattice detail_lattice(const Surface& s) noexcept {
  const int L = int(s.lattice().levels);
  return {L, std::ldexp(1.0, L), std::ldexp(1.0, -L), stored_lattice(s), s.lattice(), s};
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

/// Lattice position (u, v) lies in hole cell p.(i, j): when it lies on that cell's edge or corner
/// shared with a solid cell, moves p to the solid cell (the boundary is ground: docs/surface.md)
/// and returns true; else false (no ground). Out of line: only points over holes get here.
template <class Lattice>
[[gnu::noinline]] bool leave_hole(const Lattice& g, double u, double v,
                                  LatticePoint<Lattice>& p) noexcept {
  const double fu = u - double(p.i), fv = v - double(p.j);
  const std::int64_t last_i = g.at.vertices_x - 2, last_j = g.at.vertices_z - 2;
  // The neighbours sharing the point: across u = i (or u = i + 1 at the far edge), v likewise.
  const std::int64_t di = fu == 0.0 ? -1 : (fu == 1.0 ? 1 : 0);
  const std::int64_t dj = fv == 0.0 ? -1 : (fv == 1.0 ? 1 : 0);
  for (const auto& [a, b] : {std::pair{di, std::int64_t{0}}, std::pair{std::int64_t{0}, dj},
                             std::pair{di, dj}}) {
    if (a == 0 && b == 0) continue;
    const std::int64_t i = p.i + a, j = p.j + b;
    if (i < 0 || j < 0 || i > last_i || j > last_j || g.hole(i, j)) continue;
    p.i = i, p.j = j;
    p.tri = locate_in_cell(i, j, static_cast<float>(u - double(i)), static_cast<float>(v - double(j)));
    return true;
  }
  return false;
}

/// Finds the cell and triangle under world (x, z) and reads its corners; false off the footprint
/// and over a hole (NaN fails the range test too).
template <class Lattice>
[[gnu::always_inline]] inline bool locate(const Lattice& g, double x, double z,
                                          LatticePoint<Lattice>& p) noexcept {
  const SurfaceLattice& at = g.at;
  const double u = (x - at.origin_x) * at.inv_spacing_x;
  const double v = (z - at.origin_z) * at.inv_spacing_z;
  const double max_u = double(at.vertices_x - 1), max_v = double(at.vertices_z - 1);
  if (!(u >= 0.0 && u <= max_u && v >= 0.0 && v <= max_v)) return false;
  p.tri = cell_at(g, u, v, p.i, p.j);
  if (g.hole(p.i, p.j) && !leave_hole(g, u, v, p)) return false;
  // Written out: as a loop, -O3 versions it for a unit row stride and spills the heights.
  p.h[0] = g.local(p.i + p.tri.di[0], p.j + p.tri.dj[0]);
  p.h[1] = g.local(p.i + p.tri.di[1], p.j + p.tri.dj[1]);
  p.h[2] = g.local(p.i + p.tri.di[2], p.j + p.tri.dj[2]);
  return true;
}

}  // namespace ridgeline::detail
