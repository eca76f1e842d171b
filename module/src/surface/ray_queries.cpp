// Raycasts and box queries against the surface of surface.h.
//
// Raycasts descend a min/max pyramid front to back, after the octree ray traversal of Revelles,
// Urena and Lastra (2000) and the maximum mipmaps of Tevs, Ihrke and Seidel (2008): a node is
// skipped when the ray stays above the node's highest sample over the node's footprint. A leaf
// block is walked cell by cell with a 2D DDA (Amanatides and Woo 1987); in each cell the ray's
// height above the surface is linear in t over each of the two triangles, so the first touching
// point follows from the values at the ends of the ray's piece over each triangle.
//
// Everything runs in double precision in lattice-local coordinates (grid units from sample (0, 0)
// along x and z, metres above the height offset along y), so terrains far from the world origin
// lose nothing.
#include "surface/ray_queries.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <limits>

#include "format.h"
#include "surface/lattice.h"
#include "surface/surface_eval.h"
#include "world/page_store.h"

namespace ridgeline {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Direction components below this (after normalisation) are zero: over any representable ray
// length they move the ray by far less than a nanometre, and they would overflow 1 / d.
constexpr double kTinyDirection = 1e-150;

// Narrows [t0, t1] to the part where o + d * t lies in [a, b]. False when empty.
inline bool clip_axis(double o, double d, double inv, double a, double b, double& t0,
                      double& t1) noexcept {
  if (d == 0.0) return o >= a && o <= b;
  double ta = (a - o) * inv, tb = (b - o) * inv;
  if (ta > tb) std::swap(ta, tb);
  t0 = std::max(t0, ta);
  t1 = std::min(t1, tb);
  return t0 <= t1;
}

}  // namespace

struct RayQueries::Ray {
  double u0, v0, y0;       // origin: grid units along x and z, metres above the height offset
  double du, dv, dy;       // change per metre along the ray
  double inv_du, inv_dv;   // 1 / du, 1 / dv (unused when zero)
  double t_enter, t_exit;  // the part of [0, max_distance] above the footprint
  glm::dvec3 origin, dir;  // world origin and unit direction
};

namespace {

// The pyramid as a ray walks it: levels 0 .. 5 inside level-0 pages (blocks of 4 << l cells),
// levels 6 and up above them (the store's pyramid over pages). Pages are read through the
// lattice view, which loads a missing one (a synchronous load).
struct Pyramid {
  const detail::StoredLattice& g;
  const world::PageStore& store;
  int levels() const noexcept { return world::kRayLevels + int(store.upper_rays().size()); }
  std::int64_t nx(int l) const noexcept {
    return l < world::kRayLevels ? std::int64_t(store.grid().px[0]) * (64 >> l)
                                 : store.upper_rays()[std::size_t(l - world::kRayLevels)].nx;
  }
  std::int64_t nz(int l) const noexcept {
    return l < world::kRayLevels ? std::int64_t(store.grid().pz[0]) * (64 >> l)
                                 : store.upper_rays()[std::size_t(l - world::kRayLevels)].nz;
  }
  // Min and max of node (x, z) of level l; false when its page could not be loaded.
  bool node(int l, std::int64_t x, std::int64_t z, float& lo, float& hi) const noexcept {
    if (l >= world::kRayLevels) {
      const auto& u = store.upper_rays()[std::size_t(l - world::kRayLevels)];
      const std::size_t k = std::size_t(x) + std::size_t(z) * std::size_t(u.nx);
      lo = u.min[k], hi = u.max[k];
      return true;
    }
    const int s = world::kRayLevels - l;
    const world::Page* p = g.page_of_key({0, std::int32_t(x >> s), std::int32_t(z >> s)});
    if (p == nullptr) return false;
    const std::int32_t m = (64 >> l) - 1;
    const std::size_t k = p->rays->index(l, std::int32_t(x) & m, std::int32_t(z) & m);
    lo = p->rays->min[k], hi = p->rays->max[k];
    return true;
  }
};

const detail::StoredLattice& stored_of(const detail::StoredLattice& g) { return g; }
const detail::StoredLattice& stored_of(const detail::DetailLattice& g) { return g.stored; }

}  // namespace

double RayQueries::touch_tolerance(const Surface& s) noexcept {
  const WorldInfo& hf = s.info();
  return 1e-9 * (1.0 + std::max(std::abs(double(hf.min_local)), std::abs(double(hf.max_local))));
}

std::string RayQueries::check(const world::PageStore& store) {
  using detail::fmt;
  const std::shared_ptr<const world::PageTable> t = store.snapshot();
  for (std::size_t k = 0; k < t->size(); ++k) {
    const world::Page& p = t->page(k);
    if (p.key.level != 0) continue;
    const auto fresh = world::make_rays(p);
    for (std::size_t n = 0; n < world::PageRays::kNodes; ++n)
      if (fresh->min[n] != p.rays->min[n] || fresh->max[n] != p.rays->max[n])
        return fmt("ray pyramid: page (%d, %d) node %zu holds [%g, %g], rebuilt [%g, %g]", p.key.px,
                   p.key.pz, n, double(p.rays->min[n]), double(p.rays->max[n]),
                   double(fresh->min[n]), double(fresh->max[n]));
  }
  const world::PageGrid& g = store.grid();
  const detail::StoredLattice lat(store, SurfaceLattice{});
  for (std::int32_t pz = 0; pz < g.pz[0]; ++pz)
    for (std::int32_t px = 0; px < g.px[0]; ++px) {
      const PageSummary s = world::summarize(
          g, px, pz, [&](std::int64_t i, std::int64_t j) { return lat.local(i, j); });
      const PageSummary& have = store.summary(px, pz);
      // lo and hi exactly (a baked world's page is refused when it loads otherwise); the ring
      // around, which a loaded page cannot check alone, must hold the rebuilt one.
      if (s.lo != have.lo || s.hi != have.hi || !(have.lo8 <= s.lo8) || !(have.hi8 >= s.hi8))
        return fmt("page summary (%d, %d) holds [%g, %g] / [%g, %g], rebuilt [%g, %g] / [%g, %g]",
                   px, pz, double(have.lo), double(have.hi), double(have.lo8), double(have.hi8),
                   double(s.lo), double(s.hi), double(s.lo8), double(s.hi8));
      const auto& u = store.upper_rays()[0];
      const std::size_t k = std::size_t(px) + std::size_t(pz) * std::size_t(u.nx);
      if (u.min[k] != s.lo || u.max[k] != s.hi)
        return fmt("ray pyramid above pages: node (%d, %d) differs from its page", px, pz);
    }
  const auto& up = store.upper_rays();
  for (std::size_t l = 1; l < up.size(); ++l)
    for (std::int32_t z = 0; z < up[l].nz; ++z)
      for (std::int32_t x = 0; x < up[l].nx; ++x) {
        float lo = INFINITY, hi = -INFINITY;
        for (int c = 0; c < 4; ++c) {
          const std::int32_t cx = 2 * x + (c & 1), cz = 2 * z + (c >> 1);
          if (cx >= up[l - 1].nx || cz >= up[l - 1].nz) continue;
          const std::size_t k = std::size_t(cx) + std::size_t(cz) * std::size_t(up[l - 1].nx);
          lo = std::min(lo, up[l - 1].min[k]), hi = std::max(hi, up[l - 1].max[k]);
        }
        const std::size_t k = std::size_t(x) + std::size_t(z) * std::size_t(up[l].nx);
        if (up[l].min[k] != lo || up[l].max[k] != hi)
          return fmt("ray pyramid above pages: level %zu node (%d, %d) differs from its children",
                     l, x, z);
      }
  return {};
}

namespace {

// Fills a hit at distance t on the triangle with plane `plane` in cell (i, j) of lattice `g`.
template <class Lattice>
void fill_hit(const Lattice& g, const glm::dvec3& origin, const glm::dvec3& dir, std::int64_t i,
              std::int64_t j, const detail::CellPlane& plane, double t, bool started_below,
              RayHit& hit) noexcept {
  hit.distance = t;
  hit.point = t == 0.0 ? origin : origin + dir * t;
  hit.normal = detail::plane_normal(plane, g.at.inv_spacing_x, g.at.inv_spacing_z);
  hit.material = g.material(i, j);
  hit.started_below = started_below;
}

// The surface under a point: its finest cell, the point's fractions in it, the triangle's plane;
// `hole` when there is no ground there (the boundary of a hole is ground, as for the point
// queries).
struct PointPlane {
  std::int64_t i = 0, j = 0;
  double fu = 0, fv = 0;
  detail::CellPlane plane{};
  bool hole = false;
};

// (u, v) in stored-lattice units, inside the footprint.
template <class Lattice>
PointPlane point_plane(const Lattice& g, double u, double v) noexcept {
  u *= g.scale, v *= g.scale;  // finest-lattice units (exact: a power of two)
  PointPlane p;
  detail::LatticePoint<Lattice> lp;
  lp.tri = detail::cell_at(g, u, v, lp.i, lp.j);
  if (g.hole(lp.i, lp.j) && !detail::leave_hole(g, u, v, lp)) p.hole = true;
  p.i = lp.i, p.j = lp.j;
  p.fu = u - double(p.i);
  p.fv = v - double(p.j);
  p.plane = detail::cell_plane(g, p.i, p.j, lp.tri);
  return p;
}

}  // namespace

// Tests the finest cells of leaf block (bx, bz) that the ray crosses during [ta, tb], in ray
// order (a 2D DDA over the block's 2^L x 2^L finest cells per stored cell).
template <class Lattice>
bool RayQueries::walk_leaf(const Lattice& g, double touch_, const Ray& stored, std::uint32_t bx,
                           std::uint32_t bz, double ta, double tb, RayHit& hit) noexcept {
  const int L = g.levels;
  Ray r = stored;  // the same ray in finest-lattice units (exact: powers of two)
  r.u0 *= g.scale, r.v0 *= g.scale, r.du *= g.scale, r.dv *= g.scale;
  r.inv_du *= g.inv_scale, r.inv_dv *= g.inv_scale;
  const std::int64_t cells_x = g.at.vertices_x - 1, cells_z = g.at.vertices_z - 1;
  const std::int64_t ci0 = std::int64_t{bx} << (kLeafShift + L);
  const std::int64_t cj0 = std::int64_t{bz} << (kLeafShift + L);
  const std::int64_t ci1 = std::min<std::int64_t>(ci0 + (kLeafCells << L), cells_x) - 1;
  const std::int64_t cj1 = std::min<std::int64_t>(cj0 + (kLeafCells << L), cells_z) - 1;
  // Truncation acts as floor here: anything below 0 is clamped up to ci0 >= 0 anyway.
  std::int64_t ci = std::clamp<std::int64_t>(
      static_cast<std::int64_t>(std::max(r.u0 + r.du * ta, -1.0)), ci0, ci1);
  std::int64_t cj = std::clamp<std::int64_t>(
      static_cast<std::int64_t>(std::max(r.v0 + r.dv * ta, -1.0)), cj0, cj1);
  const int step_u = r.du > 0 ? 1 : -1, step_v = r.dv > 0 ? 1 : -1;
  double t = ta;
  for (;;) {
    // Leave this cell where the ray crosses its far u or v boundary. With both at once (through a
    // vertex) the DDA steps one axis first: the side cell gets an empty interval and is tested at
    // the vertex alone, which is harmless.
    const double tnu = r.du > 0   ? (double(ci + 1) - r.u0) * r.inv_du
                       : r.du < 0 ? (double(ci) - r.u0) * r.inv_du
                                  : kInf;
    const double tnv = r.dv > 0   ? (double(cj + 1) - r.v0) * r.inv_dv
                       : r.dv < 0 ? (double(cj) - r.v0) * r.inv_dv
                                  : kInf;
    const double tc = std::max(t, std::min({tnu, tnv, tb}));

    // The cell: skip it when the ray stays above its highest corner, or when it is a hole (the
    // ray passes through, on to the cells beyond).
    const bool solid = !g.hole(ci, cj);
    const double h00 = g.local(ci, cj), h10 = g.local(ci + 1, cj);
    const double h01 = g.local(ci, cj + 1), h11 = g.local(ci + 1, cj + 1);
    const double cmax = std::max(std::max(h00, h10), std::max(h01, h11));
    const double ylow = r.y0 + r.dy * (r.dy < 0 ? tc : t);
    if (solid && ylow <= cmax + touch_) {
      // Split [t, tc] where the ray crosses the cell's diagonal (surface.h decides which one).
      const double ou = r.u0 - double(ci), ov = r.v0 - double(cj);
      const bool main = cell_has_main_diagonal(ci, cj);
      auto side = [&](double s) {
        const double fu = ou + r.du * s, fv = ov + r.dv * s;
        return main ? fu - fv : fu + fv - 1.0;
      };
      const double sa = side(t), sb = side(tc);
      double piece[3] = {t, tc, tc};
      int pieces = 1;
      if ((sa < 0 && sb > 0) || (sa > 0 && sb < 0)) {
        piece[1] = std::clamp(t + (tc - t) * (sa / (sa - sb)), t, tc);
        pieces = 2;
      }
      for (int k = 0; k < pieces; ++k) {
        const double pa = piece[k], pb = piece[k + 1];
        const double pm = 0.5 * (pa + pb);
        const CellTriangle tri =
            locate_in_cell(ci, cj, static_cast<float>(std::clamp(ou + r.du * pm, 0.0, 1.0)),
                           static_cast<float>(std::clamp(ov + r.dv * pm, 0.0, 1.0)));
        const detail::CellPlane plane = detail::cell_plane(g, ci, cj, tri);
        const double ha = plane.at(ou + r.du * pa, ov + r.dv * pa);
        const double fa = (r.y0 + r.dy * pa) - ha;
        double th;
        if (fa <= touch_) {
          th = pa;
        } else {
          const double hb = plane.at(ou + r.du * pb, ov + r.dv * pb);
          const double fb = (r.y0 + r.dy * pb) - hb;
          if (fb > touch_) continue;
          th = fb <= 0 ? std::clamp(pa + (pb - pa) * (fa / (fa - fb)), pa, pb) : pb;
        }
        fill_hit(g, r.origin, r.dir, ci, cj, plane, th, false, hit);
        return true;
      }
    }

    if (tc >= tb) return false;
    if (tnu <= tnv) {
      ci += step_u;
      if (ci < ci0 || ci > ci1) return false;
    } else {
      cj += step_v;
      if (cj < cj0 || cj > cj1) return false;
    }
    t = tc;
  }
}

// `widen`: the detail bound, metres, by which the pyramid's stored maxima are raised.
template <class Lattice>
std::optional<RayHit> RayQueries::raycast_impl(const Lattice& g, const Surface& s, double widen,
                                               const glm::dvec3& origin,
                                               const glm::dvec3& direction,
                                               double max_distance) noexcept {
  const WorldInfo& hf = s.info();
  const double touch_ = touch_tolerance(s);
  const double inv_sx_ = 1.0 / hf.spacing_x, inv_sz_ = 1.0 / hf.spacing_z;
  const Pyramid pyr{stored_of(g), detail::SurfaceAccess::store(s)};
  if (!(max_distance > 0.0)) return std::nullopt;  // also NaN
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(origin[a]) || !std::isfinite(direction[a])) return std::nullopt;
  // Normalise without overflow: scale by the largest component first.
  const double m = std::max({std::abs(direction.x), std::abs(direction.y), std::abs(direction.z)});
  if (!(m > 0.0)) return std::nullopt;  // zero direction
  glm::dvec3 d(0.0, direction.y > 0.0 ? 1.0 : -1.0, 0.0);
  if (direction.x != 0.0 || direction.z != 0.0) {
    d = direction / m;
    d /= std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    if (std::abs(d.x) < kTinyDirection) d.x = 0.0;
    if (std::abs(d.z) < kTinyDirection) d.z = 0.0;
  }

  Ray r;
  r.origin = origin;
  r.dir = d;
  // Multiplied by 1 / spacing like Terrain's point queries, so both locate the same cell.
  r.u0 = (origin.x - hf.origin_x) * inv_sx_;
  r.v0 = (origin.z - hf.origin_z) * inv_sz_;
  r.y0 = origin.y - hf.height_offset;
  r.du = d.x * inv_sx_;
  r.dv = d.z * inv_sz_;
  r.dy = d.y;
  const double umax = hf.width - 1.0, vmax = hf.height - 1.0;
  RayHit hit;

  if (r.du == 0.0 && r.dv == 0.0) {
    // Vertical: only the surface under the origin can be hit.
    if (!(r.u0 >= 0.0 && r.u0 <= umax && r.v0 >= 0.0 && r.v0 <= vmax)) return std::nullopt;
    const PointPlane p = point_plane(g, r.u0, r.v0);
    if (p.hole) return std::nullopt;  // straight down a hole: nothing below
    const double f = r.y0 - p.plane.at(p.fu, p.fv);  // height above the surface
    if (f <= touch_) {
      fill_hit(g, origin, d, p.i, p.j, p.plane, 0.0, f < 0.0, hit);
      return hit;
    }
    if (r.dy > 0.0 || f > max_distance) return std::nullopt;
    fill_hit(g, origin, d, p.i, p.j, p.plane, f, false, hit);
    return hit;
  }

  // The part of the ray above the footprint (exact bounds: the footprint is the terrain).
  r.inv_du = r.du != 0.0 ? 1.0 / r.du : 0.0;
  r.inv_dv = r.dv != 0.0 ? 1.0 / r.dv : 0.0;
  r.t_enter = 0.0;
  r.t_exit = max_distance;
  if (!clip_axis(r.u0, r.du, r.inv_du, 0.0, umax, r.t_enter, r.t_exit)) return std::nullopt;
  if (!clip_axis(r.v0, r.dv, r.inv_dv, 0.0, vmax, r.t_enter, r.t_exit)) return std::nullopt;

  // Where the ray starts over the terrain: at or below the surface there, it hits there.
  {
    const double t = r.t_enter;
    const double u = std::clamp(r.u0 + r.du * t, 0.0, umax);
    const double v = std::clamp(r.v0 + r.dv * t, 0.0, vmax);
    const PointPlane p = point_plane(g, u, v);
    const double f = (r.y0 + r.dy * t) - p.plane.at(p.fu, p.fv);
    if (!p.hole && f <= touch_) {
      fill_hit(g, origin, d, p.i, p.j, p.plane, t, t == 0.0 && f < 0.0, hit);
      return hit;
    }
  }

  // Hierarchical DDA (after Tevs et al. 2008): walk the nodes of level L along the ray; a node
  // the ray passes above is skipped, stepping to its neighbour and climbing a level when that
  // crosses the parent's boundary; otherwise descend into the child holding the ray, down to the
  // leaf blocks, whose cells are tested in ray order. Stepping is in integer node coordinates,
  // one axis at a time, so every node the ray touches is visited (through a corner, the side node
  // gets an empty interval) and the walk always advances.
  const int top = pyr.levels() - 1;
  double t = r.t_enter;
  // Start at the lowest level whose nodes are at least as long as the ray's footprint (fewer
  // descents for short rays); the walk climbs from there if the ray crosses into another node.
  int l = top;
  const double cells = (r.t_exit - t) * std::max(std::abs(r.du), std::abs(r.dv));
  while (l > 0 && double(std::int64_t{kLeafCells} << (l - 1)) >= cells) --l;
  std::int64_t x = 0, z = 0;
  if (l < top) {
    const int shift = l + static_cast<int>(kLeafShift);
    x = std::clamp<std::int64_t>(
        static_cast<std::int64_t>(std::clamp(r.u0 + r.du * t, 0.0, umax)) >> shift, 0,
        pyr.nx(l) - 1);
    z = std::clamp<std::int64_t>(
        static_cast<std::int64_t>(std::clamp(r.v0 + r.dv * t, 0.0, vmax)) >> shift, 0,
        pyr.nz(l) - 1);
  }
  const int step_u = r.du > 0 ? 1 : -1, step_v = r.dv > 0 ? 1 : -1;
  for (;;) {
    const double size = double(std::int64_t{1} << (l + kLeafShift));
    const double ua = double(x) * size, va = double(z) * size;
    // The far edges of the last nodes may lie past the footprint: t_exit stops the ray first.
    const double ub = ua + size, vb = va + size;
    const double tnu = r.du > 0 ? (ub - r.u0) * r.inv_du : r.du < 0 ? (ua - r.u0) * r.inv_du : kInf;
    const double tnv = r.dv > 0 ? (vb - r.v0) * r.inv_dv : r.dv < 0 ? (va - r.v0) * r.inv_dv : kInf;
    const double t_out = std::max(t, std::min(std::min(tnu, tnv), r.t_exit));
    float node_min, node_max;
    if (!pyr.node(l, x, z, node_min, node_max)) return std::nullopt;
    const double ylow = r.y0 + r.dy * (r.dy < 0 ? t_out : t);
    if (ylow <= double(node_max) + widen + touch_) {
      if (l > 0) {
        // Descend into the child that holds the ray at t (ties go the way the ray moves).
        --l;
        const double mu = ua + 0.5 * size, mv = va + 0.5 * size;
        const double u = r.u0 + r.du * t, v = r.v0 + r.dv * t;
        x = 2 * x + ((u > mu || (u == mu && r.du > 0)) ? 1 : 0);
        z = 2 * z + ((v > mv || (v == mv && r.dv > 0)) ? 1 : 0);
        x = std::min<std::int64_t>(x, pyr.nx(l) - 1);
        z = std::min<std::int64_t>(z, pyr.nz(l) - 1);
        continue;
      }
      if (walk_leaf(g, touch_, r, std::uint32_t(x), std::uint32_t(z), t, t_out, hit)) return hit;
    }
    // Step to the next node along the ray.
    if (t_out >= r.t_exit) return std::nullopt;
    bool climb;
    if (tnu <= tnv) {
      x += step_u;
      if (x < 0 || x >= pyr.nx(l)) return std::nullopt;
      climb = (x & 1) == (step_u > 0 ? 0 : 1);  // crossed into another parent
    } else {
      z += step_v;
      if (z < 0 || z >= pyr.nz(l)) return std::nullopt;
      climb = (z & 1) == (step_v > 0 ? 0 : 1);
    }
    t = t_out;
    if (climb && l < top) {
      ++l;
      x >>= 1;
      z >>= 1;
    }
  }
}

// `widen` as for raycast_impl.
template <class Lattice>
std::size_t RayQueries::boxes_impl(const Lattice& g, double widen, const Box& box,
                                   std::vector<SurfaceTriangle>& out,
                                   std::size_t max_triangles) {
  const SurfaceLattice& at = g.at;
  const int L = g.levels;
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(box.min[a]) || !std::isfinite(box.max[a]) || !(box.min[a] <= box.max[a]))
      return 0;
  // Finest cells (2^L per stored cell side).
  const double sx = at.spacing_x, sz = at.spacing_z;
  const double ua = (box.min.x - at.origin_x) / sx, ub = (box.max.x - at.origin_x) / sx;
  const double va = (box.min.z - at.origin_z) / sz, vb = (box.max.z - at.origin_z) / sz;
  const double ylo = box.min.y - at.height_offset, yhi = box.max.y - at.height_offset;
  const double umax = double(at.vertices_x - 1), vmax = double(at.vertices_z - 1);
  if (ub < 0.0 || vb < 0.0 || ua > umax || va > vmax) return 0;
  // Closed cell ranges: a box touching a cell's edge overlaps that cell.
  const auto cell_lo = [](double a, double cells) {
    return static_cast<std::int64_t>(std::clamp(std::ceil(a) - 1.0, 0.0, cells - 1.0));
  };
  const auto cell_hi = [](double b, double cells) {
    return static_cast<std::int64_t>(std::clamp(std::floor(b), 0.0, cells - 1.0));
  };
  const std::int64_t i0 = cell_lo(ua, umax), i1 = cell_hi(ub, umax);
  const std::int64_t j0 = cell_lo(va, vmax), j1 = cell_hi(vb, vmax);

  const Pyramid pyr{stored_of(g), stored_of(g).store};
  const int shift = L + int(kLeafShift);  // cell -> leaf block of the pyramid
  std::size_t added = 0;
  for (std::int64_t cj = j0; cj <= j1; ++cj) {
    for (std::int64_t ci = i0; ci <= i1; ++ci) {
      // Blocks whose height range (widened by the detail bound) misses the box are skipped.
      float block_min, block_max;
      if (!pyr.node(0, ci >> shift, cj >> shift, block_min, block_max)) return added;
      if (double(block_max) + widen < ylo || double(block_min) - widen > yhi) {
        ci |= (std::int64_t{1} << shift) - 1;  // to the block's last cell
        continue;
      }
      if (g.hole(ci, cj)) continue;  // no ground: no triangles
      // The box in this cell's fractional coordinates.
      const double bu0 = ua - double(ci), bu1 = ub - double(ci);
      const double bv0 = va - double(cj), bv1 = vb - double(cj);
      for (int which = 0; which < 2; ++which) {
        const CellTriangle t = detail::cell_triangle(ci, cj, which);
        double h[3];
        for (int k = 0; k < 3; ++k) h[k] = g.local(ci + t.di[k], cj + t.dj[k]);
        const double hmin = std::min({h[0], h[1], h[2]}), hmax = std::max({h[0], h[1], h[2]});
        if (hmax < ylo || hmin > yhi) continue;
        // Separating axes: the box's axes hold (the cell overlaps the box and the triangle
        // spans the cell); test the triangle's edge normals.
        bool separated = false;
        for (int e = 0; e < 3 && !separated; ++e) {
          const int a = e, b = (e + 1) % 3, c = (e + 2) % 3;
          // Normal of edge a-b, turned towards the opposite corner c.
          double nx = -(double(t.dj[b]) - t.dj[a]), nz = double(t.di[b]) - t.di[a];
          if (nx * (t.di[c] - t.di[a]) + nz * (t.dj[c] - t.dj[a]) < 0) nx = -nx, nz = -nz;
          // Separated when even the box corner furthest along the normal lies strictly
          // behind the edge.
          const double box_max = nx * (nx >= 0 ? bu1 : bu0) + nz * (nz >= 0 ? bv1 : bv0);
          separated = box_max < nx * t.di[a] + nz * t.dj[a];
        }
        if (separated) continue;
        if (max_triangles != 0 && added == max_triangles) return added;
        SurfaceTriangle st;
        for (int k = 0; k < 3; ++k)
          st.v[k] = {at.origin_x + double(ci + t.di[k]) * sx, at.height_offset + h[k],
                     at.origin_z + double(cj + t.dj[k]) * sz};
        st.material = g.material(ci, cj);
        out.push_back(st);
        ++added;
      }
    }
  }
  return added;
}

std::optional<RayHit> RayQueries::raycast(const Surface& s, const glm::dvec3& origin,
                                          const glm::dvec3& direction,
                                          double max_distance) noexcept {
  return detail::with_lattice(s, [&](const auto& g) -> std::optional<RayHit> {
    auto hit = raycast_impl(g, s, s.detail_bound(), origin, direction, max_distance);
    if (g.missing || stored_of(g).missing) return std::nullopt;  // a page could not be loaded
    return hit;
  });
}

std::size_t RayQueries::triangles_in_box(const Surface& s, const Box& box,
                                         std::vector<SurfaceTriangle>& out,
                                         std::size_t max_triangles) {
  return detail::with_lattice(
      s, [&](const auto& g) { return boxes_impl(g, s.detail_bound(), box, out, max_triangles); });
}

}  // namespace ridgeline
