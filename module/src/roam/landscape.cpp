// Patches, bintree geometry and per-diamond bounds.
//
// A diamond's error bound starts from the exact error of its triangles (the RTIN / "martini"
// definition: the largest vertical distance between the surface and the triangle over every
// lattice vertex under it; both are piecewise linear over the finest triangles, so the maximum is
// at a lattice vertex) and is made nested over the diamond hierarchy, as Lindstrom & Pascucci's
// SOAR nests its vertex errors: a diamond's bound is at least each of its four children's. With
// the nested bounding spheres below, the projected bound of a diamond is then never smaller than
// a descendant's, so the set of diamonds to split is closed under the hierarchy for every camera:
// the mesh a threshold asks for is unique, and a refinement that follows the bound never needs a
// forced split (the views keep them for budgets and edits).
//
// The sphere of a diamond is centred at its vertex at its true height; its radius is at least
// every child's radius plus the distance to the child's centre, so it holds every lattice vertex
// under the diamond (all of them are descendants' centres or its corners, which the mesh draws
// exactly).
//
// Cost: exact errors touch every sample about once per level, O(N log N); nesting is one pass
// per level, O(N). Below the stored resolution (procedural detail) the same quantities come from
// closed forms over the detail field's amplitude bounds (compute_detail()).
#include "ridgeline/landscape.h"

#include <algorithm>
#include <atomic>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <deque>
#include <mutex>
#include <thread>

#include "format.h"
#include "ridgeline/detail.h"
#include "ridgeline/log.h"
#include "ridgeline/surface.h"
#include "roam/diamond.h"
#include "roam/landscape_access.h"

namespace ridgeline {

using roam::Diamond;
using roam::diamond_at;

namespace {

constexpr std::size_t kLogCapacity = 1024;

// Radius of a sphere centred at a diamond's vertex that holds its descendants' xz positions, in
// units of s * hypot(spacing): 3 for square diamonds, 2 for edge diamonds (each at least its
// children's plus the distance to them: 3 >= 2 + 1, 2 >= 3/2 + 1/2).
double xz_radius_units(const Diamond& d) noexcept {
  return d.square ? 3.0 : 2.0;
}

// Bits set in x, inline (without -mpopcnt the builtin is a libgcc call).
constexpr int popcount64(std::uint64_t x) noexcept {
  x -= (x >> 1) & 0x5555555555555555ull;
  x = (x & 0x3333333333333333ull) + ((x >> 2) & 0x3333333333333333ull);
  x = (x + (x >> 4)) & 0x0f0f0f0f0f0f0f0full;
  return int((x * 0x0101010101010101ull) >> 56);
}

float round_up(double v) noexcept {
  float f = static_cast<float>(v);
  if (double(f) < v) f = std::nextafter(f, INFINITY);
  return f;
}

}  // namespace

struct Landscape::Impl {
  std::mutex sync_mutex;                 // one sync() at a time
  std::atomic<std::uint64_t> synced{0};  // the terrain edit_version() the bounds describe
  mutable std::mutex mutex;              // the landscape's own change log
  std::deque<Change> log;
  std::uint64_t version = 0;
  std::uint64_t trimmed_before = 0;  // changes up to this version are no longer in the log
};

Landscape::~Landscape() = default;

// ---- geometry -------------------------------------------------------------------------------

LatticeTriangle Landscape::triangle(std::uint32_t root, std::uint64_t heap) const noexcept {
  const std::uint32_t patch = root / 2;
  const std::int64_t p = patch_cells();
  const std::int64_t ox = std::int64_t(patch % patches_x_) * p;
  const std::int64_t oz = std::int64_t(patch / patches_x_) * p;
  LatticeTriangle t = (root & 1) == 0 ? LatticeTriangle{ox + p, oz, ox, oz, ox + p, oz + p}
                                      : LatticeTriangle{ox, oz + p, ox + p, oz + p, ox, oz};
  const int depth = 63 - __builtin_clzll(heap);
  for (int bit = depth - 1; bit >= 0; --bit) t = child_triangle(t, int((heap >> bit) & 1));
  return t;
}

LatticeTriangle Landscape::triangle_at(std::int64_t ax, std::int64_t az, std::uint32_t root,
                                       std::uint64_t heap) const noexcept {
  // The direction from the apex to the hypotenuse midpoint turns by 135 degrees per level and
  // back by 90 for every child 1 on the path: an index into eight compass directions.
  static constexpr int kUx[8] = {1, 1, 0, -1, -1, -1, 0, 1};
  static constexpr int kUz[8] = {0, 1, 1, 1, 0, -1, -1, -1};
  const int level = 63 - __builtin_clzll(heap);
  const int k = (((root & 1) ? 7 : 3) + 3 * level + 2 * (popcount64(heap) - 1)) & 7;
  const std::int64_t s2 = patch_cells() >> (level / 2);  // twice the apex-midpoint distance
  const std::int64_t ux = kUx[k], uz = kUz[k], px = -uz, pz = ux;  // p: u turned +90 degrees
  return {ax,
          az,
          ax + (ux + px) * s2 / 2,
          az + (uz + pz) * s2 / 2,
          ax + (ux - px) * s2 / 2,
          az + (uz - pz) * s2 / 2};
}

Landscape::LatticeBox Landscape::box_of(const LatticeTriangle& t) noexcept {
  return {std::min({t.ax, t.lx, t.rx}), std::max({t.ax, t.lx, t.rx}), std::min({t.az, t.lz, t.rz}),
          std::max({t.az, t.lz, t.rz})};
}

float Landscape::base_lattice_height(std::int64_t i, std::int64_t j) const noexcept {
  return static_cast<float>(terrain_->surface().vertex_base_height(i, j));
}

double Landscape::local_extent() const noexcept {
  const Heightfield& hf = terrain_->heightfield();
  const double h = std::max(std::abs(double(hf.min_local())), std::abs(double(hf.max_local()))) +
                   (detail_ > 0 ? terrain_->detail()->contribution_bound(1) : 0.0);
  return std::max({double(patches_x_ * patch_cells()) * spacing_x_,
                   double(patches_z_ * patch_cells()) * spacing_z_, h});
}

// ---- shading -------------------------------------------------------------------------------

// Area-weighted normal at finest-lattice vertex (i, j) of the surface (the smooth normal the
// queries interpolate): every finest triangle has the same area, so it is the normalised sum of
// the up normals (-dh/dx, 1, -dh/dz) of the triangles around the vertex, 4 or 8 of them by the
// diagonal rule. A closed form over the 3 x 3 heights around the vertex; cells outside the
// sampled area do not count, as in the queries.
VertexShading Landscape::compute_shading(std::int64_t i, std::int64_t j) const noexcept {
  VertexShading out;
  const std::int64_t ci0 = std::clamp<std::int64_t>(i, 0, last_i_),
                     cj0 = std::clamp<std::int64_t>(j, 0, last_j_);
  float h[3][3];  // h[dz + 1][dx + 1]
  for (int dz = -1; dz <= 1; ++dz)
    for (int dx = -1; dx <= 1; ++dx) h[dz + 1][dx + 1] = lattice_height(ci0 + dx, cj0 + dz);
  const double isx = 1.0 / spacing_x_, isz = 1.0 / spacing_z_;
  double gx = 0, gz = 0;
  int count = 0;
  for (int cz = -1; cz <= 0; ++cz)
    for (int cx = -1; cx <= 0; ++cx) {
      const std::int64_t ci = ci0 + cx, cj = cj0 + cz;
      if (ci < 0 || cj < 0 || ci >= last_i_ || cj >= last_j_) continue;
      const double h00 = h[cz + 1][cx + 1], h10 = h[cz + 1][cx + 2], h01 = h[cz + 2][cx + 1],
                   h11 = h[cz + 2][cx + 2];
      const int du = -cx, dv = -cz;  // the vertex's corner in the cell
      if (cell_has_main_diagonal(ci, cj)) {
        // (00, 10, 11) and (00, 11, 01): the vertex is in both when on the diagonal.
        if (!(du == 0 && dv == 1)) gx += (h10 - h00) * isx, gz += (h11 - h10) * isz, ++count;
        if (!(du == 1 && dv == 0)) gx += (h11 - h01) * isx, gz += (h01 - h00) * isz, ++count;
      } else {
        // (00, 10, 01) and (10, 11, 01).
        if (!(du == 1 && dv == 1)) gx += (h10 - h00) * isx, gz += (h01 - h00) * isz, ++count;
        if (!(du == 0 && dv == 0)) gx += (h11 - h01) * isx, gz += (h11 - h10) * isz, ++count;
      }
    }
  if (count > 0) {
    const double len = std::sqrt(gx * gx + double(count) * double(count) + gz * gz);
    out.normal = glm::vec3(float(-gx / len), float(double(count) / len), float(-gz / len));
  }
  const Diamond d = diamond_at(i, j, patch_log2());
  if (!d.corner) {
    std::int64_t ax, az, bx, bz;
    d.hypotenuse(ax, az, bx, bz);
    out.morph_dy = 0.5f * (lattice_height(ax, az) + lattice_height(bx, bz)) - lattice_height(i, j);
  }
  const Heightfield& hf = terrain_->heightfield();
  const int L = int(detail_);
  out.material =
      hf.material(std::min(std::uint32_t(std::max<std::int64_t>(i, 0) >> L), hf.width() - 2),
                  std::min(std::uint32_t(std::max<std::int64_t>(j, 0) >> L), hf.height() - 2));
  return out;
}

VertexShading Landscape::unpack(const VertexRecord& p) noexcept {
  VertexShading out;
  const float nx = float(p.nx) * (1.0f / 32767.0f), nz = float(p.nz) * (1.0f / 32767.0f);
  out.normal = glm::vec3(nx, std::sqrt(std::max(0.0f, 1.0f - nx * nx - nz * nz)), nz);
  out.morph_dy = p.morph_dy;
  out.material = p.material;
  return out;
}

void Landscape::store_shading(std::int64_t i, std::int64_t j) noexcept {
  const VertexShading v = compute_shading(i, j);
  VertexRecord& r = records_[stored_index(i, j)];
  r.nx = std::int16_t(std::lround(v.normal.x * 32767.0f));
  r.nz = std::int16_t(std::lround(v.normal.z * 32767.0f));
  r.morph_dy = v.morph_dy;
  r.material = v.material;
}

// ---- exact error of a stored triangle ---------------------------------------------------------

float Landscape::compute_exact(const LatticeTriangle& t) const noexcept {
  const std::int64_t x0 = std::min({t.ax, t.lx, t.rx}), x1 = std::max({t.ax, t.lx, t.rx});
  const std::int64_t z0 = std::min({t.az, t.lz, t.rz}), z1 = std::max({t.az, t.lz, t.rz});
  const double ha = base_height(t.ax, t.az), hl = base_height(t.lx, t.lz),
               hr = base_height(t.rx, t.rz);
  // Edge functions in integer arithmetic; w is twice the signed area.
  auto cross = [](std::int64_t ux, std::int64_t uz, std::int64_t vx, std::int64_t vz) {
    return ux * vz - uz * vx;
  };
  const std::int64_t w = cross(t.lx - t.ax, t.lz - t.az, t.rx - t.ax, t.rz - t.az);
  if (w == 0) return 0.0f;
  const double inv_w = 1.0 / double(w);
  double worst = 0.0;
  const Heightfield& hf = terrain_->heightfield();
  const std::int64_t wmax = hf.width() - 1, hmax = hf.height() - 1;
  // The three edge functions e(x, z) = a * x + c(z) (weights of R, A and L); inside means all
  // share w's sign. Per row, each edge bounds x from one side: the span is found exactly in
  // integer arithmetic, so only the samples inside are visited.
  const std::int64_t sgn = w > 0 ? 1 : -1;
  const std::int64_t ex[3][2] = {{t.ax, t.az}, {t.lx, t.lz}, {t.rx, t.rz}};
  const int from[3] = {0, 1, 2}, to[3] = {1, 2, 0};
  auto floor_div = [](std::int64_t n, std::int64_t d) {  // d > 0
    return n >= 0 ? n / d : -((-n + d - 1) / d);
  };
  for (std::int64_t z = z0; z <= z1; ++z) {
    std::int64_t lo = x0, hi = x1;
    std::int64_t coef[3], off[3];
    for (int k = 0; k < 3; ++k) {
      const std::int64_t px = ex[from[k]][0], pz = ex[from[k]][1];
      const std::int64_t ux = ex[to[k]][0] - px, uz = ex[to[k]][1] - pz;
      // e(x) = ux * (z - pz) - uz * (x - px) = a * x + c, made >= 0 inside by the sign.
      const std::int64_t a = -uz * sgn, c = (ux * (z - pz) + uz * px) * sgn;
      coef[k] = a, off[k] = c;
      if (a > 0)
        lo = std::max(lo, -floor_div(c, a));  // x >= ceil(-c / a)
      else if (a < 0)
        hi = std::min(hi, floor_div(c, -a));  // x <= floor(c / -a)
      else if (c < 0)
        lo = hi + 1;  // edge parallel to x, row outside
    }
    if (lo > hi) continue;
    const std::uint32_t zc = static_cast<std::uint32_t>(std::clamp<std::int64_t>(z, 0, hmax));
    for (std::int64_t x = lo; x <= hi; ++x) {
      // Barycentric weights from the edge functions (e_k is opposite the vertex after edge k).
      const std::int64_t e_ab = coef[0] * x + off[0];  // edge A->L: weight of R
      const std::int64_t e_lr = coef[1] * x + off[1];  // edge L->R: weight of A
      const std::int64_t e_ra = coef[2] * x + off[2];  // edge R->A: weight of L
      const double plane =
          (double(e_lr) * ha + double(e_ra) * hl + double(e_ab) * hr) * inv_w * double(sgn);
      const double h =
          hf.local(static_cast<std::uint32_t>(std::clamp<std::int64_t>(x, 0, wmax)), zc);
      worst = std::max(worst, std::abs(h - plane));
    }
  }
  return round_up(worst);  // never below the double error
}

float Landscape::exact_error(std::uint32_t root, std::uint64_t heap) const noexcept {
  const int level = 63 - __builtin_clzll(heap);
  if (level >= int(base_level())) return 0.0f;
  LatticeTriangle t = triangle(root, heap);
  const int d = int(detail_);
  t = {t.ax >> d, t.az >> d, t.lx >> d, t.lz >> d, t.rx >> d, t.rz >> d};
  return compute_exact(t);
}

// ---- bounds of one diamond ------------------------------------------------------------------

DiamondBound Landscape::compute_detail(std::int64_t i, std::int64_t j) const noexcept {
  const int K = patch_log2(), L = int(detail_);
  const Diamond d = diamond_at(i, j, K);
  const int depth = d.depth(K);
  const int from = (depth - int(base_level())) / 2 + 1;  // the first detail level not resolved
  const DetailField& f = *terrain_->detail();
  const std::int64_t r = d.reach();
  const std::int64_t i0 = std::max<std::int64_t>(i - r, 0), i1 = i + r;
  const std::int64_t j0 = std::max<std::int64_t>(j - r, 0), j1 = j + r;
  const double smax = f.shape_max_q15(std::uint32_t(L), i0, j0, i1, j1);
  const std::size_t k = std::size_t(depth) - base_level();
  auto analytic = [&](std::uint32_t m) {
    return (double(f.amplitude_sum(m)) * smax / 32768.0 + double(f.rounding_terms(m))) *
           kDetailUnit;
  };
  // Error: twice the bound of the contribution of the levels not resolved (docs/detail.md,
  // "Bounds"), over the diamond's reach (which nests); a resident finest tile's measured
  // contribution replaces the analytic one where it is smaller.
  double err = 2.0 * analytic(std::uint32_t(from));
  double morph =
      2.0 * (smax * detail_amp_growth_[k] / 32768.0 + detail_round_growth_[k]) * kDetailUnit;
  const double measured = terrain_->measured_detail_bound(std::uint32_t(from), i0, j0, i1, j1);
  if (measured < err / 2.0) {
    err = 2.0 * measured;
    // The morph bound's growth over the levels below, from the same tile's measurements.
    double m = 0, g = 1;
    for (int dd = depth; dd <= int(max_level()) - 1; ++dd, g *= morph_growth_) {
      const int fr = (dd - int(base_level())) / 2 + 1;
      m = std::max(m, g * terrain_->measured_detail_bound(std::uint32_t(fr), i0, j0, i1, j1));
    }
    morph = std::min(morph, 2.0 * m);
  }
  // Radius: the xz part nests by construction; the height part bounds |y_child - y_parent| by
  // the height range H of the reach (stored range plus twice the detail amplitude) once per
  // level below, so a parent's radius exceeds a child's by at least their distance.
  const Heightfield& hf = terrain_->heightfield();
  const std::int64_t si0 = std::clamp<std::int64_t>(i0 >> L, 0, hf.width() - 1),
                     si1 = std::clamp<std::int64_t>((i1 >> L) + 1, 0, hf.width() - 1),
                     sj0 = std::clamp<std::int64_t>(j0 >> L, 0, hf.height() - 1),
                     sj1 = std::clamp<std::int64_t>((j1 >> L) + 1, 0, hf.height() - 1);
  float lo = INFINITY, hi = -INFINITY;
  for (std::int64_t sj = sj0; sj <= sj1; ++sj)
    for (std::int64_t si = si0; si <= si1; ++si) {
      const float h = hf.local(std::uint32_t(si), std::uint32_t(sj));
      lo = std::min(lo, h), hi = std::max(hi, h);
    }
  const double height_range = double(hi - lo) + 2.0 * analytic(1);
  const int below = int(max_level()) - 1 - depth;  // levels of diamonds under this one
  const double unit = double(d.s) * std::hypot(spacing_x_, spacing_z_);
  const double radius = xz_radius_units(d) * unit + double(below + 1) * height_range;
  return {round_up(err), round_up(std::max(morph, err)), round_up(radius)};
}

float Landscape::detail_offset_bound(std::int64_t i, std::int64_t j) const noexcept {
  if (detail_ == 0) return 0.0f;
  const int L = int(detail_);
  const std::int64_t mask = (std::int64_t{1} << L) - 1;
  if ((i & mask) == 0 && (j & mask) == 0) return 0.0f;  // stored vertices carry no detail
  return round_up(terrain_->detail()->contribution_bound(1, std::uint32_t(L), i, j, i, j));
}

DiamondBound Landscape::compute_stored(std::int64_t i, std::int64_t j) const noexcept {
  const int Ks = int(exponent_), L = int(detail_);
  const Diamond d = diamond_at(i, j, Ks);
  const std::int64_t W = stored_w_ - 1, H = stored_h_ - 1;  // padded extent
  std::int64_t hx0, hz0, hx1, hz1, ax0, az0, ax1, az1;
  d.hypotenuse(hx0, hz0, hx1, hz1);
  d.apexes(ax0, az0, ax1, az1);
  const Heightfield& hf = terrain_->heightfield();
  const std::int64_t wi = hf.width() - 1, hj = hf.height() - 1;  // last stored sample
  // Exact error of each triangle that exists (one on the landscape's border), plus the detail
  // amplitude over it: the plane through stored corners (whose detail is 0) against stored
  // surface plus detail.
  double err = 0;
  bool any_data = false;
  bool straddles = false;
  const std::int64_t apex[2][2] = {{ax0, az0}, {ax1, az1}};
  for (const auto& a : apex) {
    if (a[0] < 0 || a[1] < 0 || a[0] > W || a[1] > H) continue;
    const LatticeTriangle t{a[0], a[1], hx0, hz0, hx1, hz1};
    const LatticeBox b = box_of(t);
    // A triangle over the data's border must split until none does: the mesh then ends on it.
    straddles |= (b.i0 < wi && wi < b.i1) || (b.j0 < hj && hj < b.j1);
    if (b.i0 >= wi || b.j0 >= hj) continue;  // wholly padding: not terrain, never refined
    any_data = true;
    double e = compute_exact(t);
    if (L > 0)
      e += terrain_->detail()->contribution_bound(1, std::uint32_t(L), b.i0 << L, b.j0 << L,
                                                  b.i1 << L, b.j1 << L);
    err = std::max(err, e);
  }
  if (!any_data) err = 0;
  double morph = err, radius = 0;
  const double hv = hf.local_clamped(i, j);
  auto visit = [&](const DiamondBound& c, double dist) {
    err = std::max(err, double(c.error));
    morph = std::max(morph, morph_growth_ * double(c.morph));
    radius = std::max(radius, double(c.radius) + dist);
    straddles |= c.radius >= FLT_MAX;
  };
  if (d.has_children()) {
    for (int k = 0; k < 4; ++k) {
      std::int64_t ci, cj;
      d.child(k, ci, cj);
      if (ci < 0 || cj < 0 || ci > W || cj > H) continue;
      const double dx = double(ci - i) * hf.spacing_x(), dz = double(cj - j) * hf.spacing_z();
      visit(records_[stored_index(ci, cj)].bound,
            std::sqrt(dx * dx + dz * dz + std::pow(double(hf.local_clamped(ci, cj)) - hv, 2)));
    }
  } else if (L > 0) {
    // The finest stored diamonds' children are detail diamonds at half the stored spacing (in
    // finest coordinates, half of 2^L): their heights are only known within the detail bound.
    const Diamond fd = diamond_at(i << L, j << L, patch_log2());
    for (int k = 0; k < 4; ++k) {
      std::int64_t ci, cj;
      fd.child(k, ci, cj);
      if (ci < 0 || cj < 0 || ci > (W << L) || cj > (H << L)) continue;
      const double dx = double(ci - (i << L)) * spacing_x_, dz = double(cj - (j << L)) * spacing_z_;
      const double dy =
          std::abs(double(base_lattice_height(ci, cj)) - hv) + double(detail_offset_bound(ci, cj));
      visit(compute_detail(ci, cj), std::sqrt(dx * dx + dz * dz + dy * dy));
    }
  }
  if (straddles) radius = FLT_MAX;
  return {round_up(err), round_up(morph), radius >= FLT_MAX ? FLT_MAX : round_up(radius)};
}

DiamondBound Landscape::diamond(std::int64_t i, std::int64_t j) const noexcept {
  return roam::LandscapeAccess::diamond(*this, i, j);
}

VertexShading Landscape::shading(std::int64_t i, std::int64_t j) const noexcept {
  return roam::LandscapeAccess::shading(*this, i, j);
}

float Landscape::lattice_height(std::int64_t i, std::int64_t j) const noexcept {
  return roam::LandscapeAccess::height(*this, i, j);
}

DiamondBound Landscape::diamond_slow(std::int64_t i, std::int64_t j) const noexcept {
  const int L = int(detail_);
  const std::int64_t mask = (std::int64_t{1} << L) - 1;
  if ((i & mask) != 0 || (j & mask) != 0) return compute_detail(i, j);
  const std::int64_t si = i >> L, sj = j >> L;
  RIDGELINE_ASSERT(si >= 0 && sj >= 0 && si < stored_w_ && sj < stored_h_);
  if (si < 0 || sj < 0 || si >= stored_w_ || sj >= stored_h_) return {};
  return records_[stored_index(si, sj)].bound;
}

float Landscape::bound(std::uint32_t root, std::uint64_t heap) const noexcept {
  return bound(root, heap, triangle(root, heap));
}

float Landscape::bound(std::uint32_t, std::uint64_t heap, const LatticeTriangle& t) const noexcept {
  const int level = 63 - __builtin_clzll(heap);
  if (level >= int(max_level())) return 0.0f;
  return diamond((t.lx + t.rx) / 2, (t.lz + t.rz) / 2).error;
}

// ---- building and edits ---------------------------------------------------------------------

// Recomputes the stored diamonds whose bounds the samples [i0, i1] x [j0, j1] reach, deepest
// first, so every diamond reads fresh children.
std::uint64_t Landscape::update_region(std::int64_t i0, std::int64_t j0, std::int64_t i1,
                                       std::int64_t j1) {
  const int Ks = int(exponent_);
  const std::int64_t W = stored_w_ - 1, H = stored_h_ - 1;
  const Heightfield& hf = terrain_->heightfield();
  // The padding repeats the edge samples: an edited edge sample moves the padding too.
  if (i1 >= std::int64_t(hf.width()) - 1) i1 = W;
  if (j1 >= std::int64_t(hf.height()) - 1) j1 = H;
  std::uint64_t n = 0;
  for (int depth = 2 * Ks - 1; depth >= 0; --depth) {
    const int t = Ks - 1 - depth / 2;
    const bool square = (depth & 1) == 0;
    const std::int64_t s = std::int64_t{1} << t;
    const std::int64_t reach = square ? 3 * s : 2 * s;
    // Centres on the lattice of step s whose reach meets the region.
    const std::int64_t a0 = std::max<std::int64_t>(0, (i0 - reach) / s - 1);
    const std::int64_t a1 = std::min<std::int64_t>(W / s, (i1 + reach) / s + 1);
    const std::int64_t b0 = std::max<std::int64_t>(0, (j0 - reach) / s - 1);
    const std::int64_t b1 = std::min<std::int64_t>(H / s, (j1 + reach) / s + 1);
    for (std::int64_t b = b0; b <= b1; ++b)
      for (std::int64_t a = a0; a <= a1; ++a) {
        const bool oa = (a & 1) != 0, ob = (b & 1) != 0;
        if (square ? !(oa && ob) : (oa == ob)) continue;
        const std::int64_t i = a * s, j = b * s;
        if (i + reach < i0 || i - reach > i1 || j + reach < j0 || j - reach > j1) continue;
        records_[stored_index(i, j)].bound = compute_stored(i, j);
        ++n;
      }
  }
  if (detail_ == 0) {
    // The height copies first: the shading reads them.
    const Heightfield& h = terrain_->heightfield();
    for (std::int64_t j = std::max<std::int64_t>(0, j0); j <= std::min(j1, H); ++j)
      for (std::int64_t i = std::max<std::int64_t>(0, i0); i <= std::min(i1, W); ++i)
        records_[stored_index(i, j)].height = h.local_clamped(i, j);
    // Normals read the heights one sample around; a vertex's morph offset its hypotenuse's ends,
    // up to half a patch away (the coarsest diamonds): refresh what the change reaches.
    const std::int64_t half = std::int64_t{1} << (exponent_ - 1);
    for (std::int64_t j = std::max<std::int64_t>(0, j0 - half);
         j <= std::min<std::int64_t>(stored_h_ - 1, j1 + half); ++j) {
      const std::int64_t dj = j < j0 ? j0 - j : (j > j1 ? j - j1 : 0);
      for (std::int64_t i = std::max<std::int64_t>(0, i0 - half);
           i <= std::min<std::int64_t>(stored_w_ - 1, i1 + half); ++i) {
        const std::int64_t di = i < i0 ? i0 - i : (i > i1 ? i - i1 : 0);
        const std::int64_t reach = std::max(di, dj);
        if (reach > 1) {
          const Diamond d = diamond_at(i, j, int(exponent_));
          if (d.corner || reach > d.s) continue;
        }
        store_shading(i, j);
      }
    }
  }
  Impl& m = *impl_;
  std::lock_guard lock(m.mutex);
  const int L = int(detail_);
  // Finest vertices inside the cells around the changed samples moved too (the stored surface
  // is interpolated there).
  Change c{++m.version, std::max<std::int64_t>(i0 - 1, 0) << L,
           std::max<std::int64_t>(j0 - 1, 0) << L, std::min(i1 + 1, W) << L,
           std::min(j1 + 1, H) << L};
  m.log.push_back(c);
  while (m.log.size() > kLogCapacity) {
    m.trimmed_before = m.log.front().version;
    m.log.pop_front();
  }
  return n;
}

void Landscape::sync() const {
  // Pull the terrain's change log: nothing is pushed from inside an edit.
  Impl& m = *impl_;
  const std::uint64_t now = terrain_->edit_version();
  if (m.synced.load(std::memory_order_acquire) == now) return;
  std::lock_guard lock(m.sync_mutex);
  const std::uint64_t have = m.synced.load(std::memory_order_relaxed);
  if (have == now) return;
  const TerrainChanges pulled = terrain_->changes_since(have);
  // The bounds are a cache of the terrain's surface; refreshing them is logically const (the
  // landscape is always created non-const, in create()).
  auto& self = const_cast<Landscape&>(*this);
  const int L = int(detail_);
  const std::int64_t f = std::int64_t{1} << L;
  for (const TerrainChange& c : pulled.changes) {
    if (c.vertices.empty()) continue;
    // Finest-lattice vertices to the stored samples whose cells hold them (rounded outwards).
    self.update_region(c.vertices.i0 >> L, c.vertices.j0 >> L, (c.vertices.i1 + f - 1) >> L,
                       (c.vertices.j1 + f - 1) >> L);
  }
  m.synced.store(pulled.version, std::memory_order_release);
}

std::uint64_t Landscape::synced_version() const noexcept {
  return impl_->synced.load(std::memory_order_acquire);
}

std::uint64_t Landscape::version() const noexcept {
  std::lock_guard lock(impl_->mutex);
  return impl_->version;
}

std::vector<Landscape::Change> Landscape::changes_since(std::uint64_t version,
                                                        bool* trimmed) const {
  const Impl& m = *impl_;
  std::lock_guard lock(m.mutex);
  std::vector<Change> out;
  if (trimmed) *trimmed = false;
  if (version >= m.version) return out;
  if (version < m.trimmed_before) {
    if (trimmed) *trimmed = true;
    out.push_back({m.version, 0, 0, (stored_w_ - 1) << detail_, (stored_h_ - 1) << detail_});
    return out;
  }
  for (const Change& c : m.log)
    if (c.version > version) out.push_back(c);
  return out;
}

Result<std::shared_ptr<const Landscape>> Landscape::create(std::shared_ptr<const Terrain> terrain,
                                                           const LandscapeDesc& desc) {
  if (!terrain) return Error{"landscape: no terrain given"};
  if (desc.patch_exponent < 2 || desc.patch_exponent > 10)
    return Error{fmt("landscape: patch exponent %u; need 2..10 (patches of 5 .. 1025 samples)",
                     desc.patch_exponent)};
  if (!(desc.morph_window >= 0.0 && desc.morph_window <= 4.0))
    return Error{fmt("landscape: morph window %s; need 0..4", num(desc.morph_window).c_str())};
  if (!(desc.morph_delay >= 0.0 && desc.morph_delay <= 1.0))
    return Error{fmt("landscape: morph delay %s; need 0..1", num(desc.morph_delay).c_str())};
  const auto t0 = std::chrono::steady_clock::now();
  std::shared_ptr<Landscape> l(new Landscape());
  const Heightfield& hf = terrain->heightfield();
  l->terrain_ = std::move(terrain);
  l->exponent_ = desc.patch_exponent;
  l->detail_ = l->terrain_->detail_levels();
  l->geomorph_ = {desc.morph_window, desc.morph_window > 0.0 ? desc.morph_delay : 0.0};
  l->morph_growth_ = std::sqrt(1.0 + l->geomorph_.delay + l->geomorph_.window);
  const std::int64_t p = std::int64_t{1} << l->exponent_;  // stored cells per patch
  l->patches_x_ = static_cast<std::uint32_t>((hf.width() - 1 + p - 1) / p);
  l->patches_z_ = static_cast<std::uint32_t>((hf.height() - 1 + p - 1) / p);
  if (std::uint64_t{l->patches_x_} * l->patches_z_ > (std::uint64_t{1} << 26))
    return Error{fmt("landscape: %u x %u patches; too many (use a larger patch exponent)",
                     l->patches_x_, l->patches_z_)};
  l->stored_w_ = std::int64_t(l->patches_x_) * p + 1;
  l->stored_h_ = std::int64_t(l->patches_z_) * p + 1;
  l->origin_x_ = hf.origin_x();
  l->origin_z_ = hf.origin_z();
  l->spacing_x_ = std::ldexp(hf.spacing_x(), -int(l->detail_));
  l->spacing_z_ = std::ldexp(hf.spacing_z(), -int(l->detail_));
  l->last_i_ = std::int64_t(hf.width() - 1) << l->detail_;
  l->last_j_ = std::int64_t(hf.height() - 1) << l->detail_;
  l->tiles_x_ = (l->stored_w_ + 3) / 4;
  l->records_.assign(std::size_t(l->tiles_x_) * std::size_t((l->stored_h_ + 3) / 4) * 16,
                     VertexRecord{});
  if (l->detail_ == 0)
    for (std::int64_t j = 0; j < l->stored_h_; ++j)
      for (std::int64_t i = 0; i < l->stored_w_; ++i)
        l->records_[l->stored_index(i, j)].height = hf.local_clamped(i, j);
  // Growth of the morph bound's closed form below the stored resolution, per depth: the largest
  // g^n times the amplitude sum (and rounding terms) of the first level not resolved n levels
  // further down.
  if (l->detail_ > 0) {
    const DetailField& f = *l->terrain_->detail();
    const int base = int(l->base_level()), top = int(l->max_level());
    l->detail_amp_growth_.assign(std::size_t(top - base), 0.0);
    l->detail_round_growth_.assign(std::size_t(top - base), 0.0);
    for (int d = base; d < top; ++d) {
      double ga = 0, gr = 0, g = 1;
      for (int dd = d; dd < top; ++dd, g *= l->morph_growth_) {
        const auto from = std::uint32_t((dd - base) / 2 + 1);
        ga = std::max(ga, g * double(f.amplitude_sum(from)));
        gr = std::max(gr, g * double(f.rounding_terms(from)));
      }
      l->detail_amp_growth_[std::size_t(d - base)] = ga;
      l->detail_round_growth_[std::size_t(d - base)] = gr;
    }
  }

  // Deepest level first; within a level every diamond reads only its (finished) children, so a
  // level's rows split over the hardware threads.
  const int Ks = int(l->exponent_);
  const unsigned threads = std::max(1u, std::min(8u, std::thread::hardware_concurrency()));
  for (int depth = 2 * Ks - 1; depth >= 0; --depth) {
    const int t = Ks - 1 - depth / 2;
    const bool square = (depth & 1) == 0;
    const std::int64_t s = std::int64_t{1} << t;
    const std::int64_t rows = (l->stored_h_ - 1) / s + 1;
    auto work = [&](std::int64_t b0, std::int64_t b1) {
      for (std::int64_t b = b0; b < b1; ++b)
        for (std::int64_t a = 0; a * s < l->stored_w_; ++a) {
          const bool oa = (a & 1) != 0, ob = (b & 1) != 0;
          if (square ? !(oa && ob) : (oa == ob)) continue;
          l->records_[l->stored_index(a * s, b * s)].bound = l->compute_stored(a * s, b * s);
        }
    };
    if (threads <= 1 || rows < 64) {
      work(0, rows);
    } else {
      std::vector<std::thread> pool;
      for (unsigned k = 0; k < threads; ++k)
        pool.emplace_back(work, rows * k / threads, rows * (k + 1) / threads);
      for (auto& th : pool) th.join();
    }
  }
  if (l->detail_ == 0) {
    auto shade = [&](std::int64_t j0, std::int64_t j1) {
      for (std::int64_t j = j0; j < j1; ++j)
        for (std::int64_t i = 0; i < l->stored_w_; ++i) l->store_shading(i, j);
    };
    if (threads <= 1 || l->stored_h_ < 64) {
      shade(0, l->stored_h_);
    } else {
      std::vector<std::thread> pool;
      for (unsigned k = 0; k < threads; ++k)
        pool.emplace_back(shade, l->stored_h_ * k / threads, l->stored_h_ * (k + 1) / threads);
      for (auto& th : pool) th.join();
    }
  }
  l->build_ms_ =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  l->impl_ = std::make_unique<Impl>();
  l->impl_->synced.store(l->terrain_->edit_version(), std::memory_order_relaxed);
  return std::shared_ptr<const Landscape>(std::move(l));
}

}  // namespace ridgeline
