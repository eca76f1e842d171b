// The tessellator's bounds of the stored diamonds, page by page (records.h).
//
// A diamond's error bound starts from the exact error of its triangles (the RTIN / "martini"
// definition: the largest vertical distance between the surface and the triangle over every
// lattice vertex under it; both are piecewise linear over the finest triangles, so the maximum is
// at a lattice vertex) and is made nested over the diamond hierarchy, as Lindstrom & Pascucci's
// SOAR nests its vertex errors: a diamond's bound is at least each of its four children's. With
// nested bounding spheres the projected bound of a diamond is then never smaller than a
// descendant's, so the set of diamonds to split is closed under the hierarchy for every camera:
// the mesh a threshold asks for is unique.
//
// The sphere of a diamond is centred at its vertex at its true height; its radius is at least
// every child's radius plus the distance to the child's centre, so it holds every lattice vertex
// under the diamond.
#include "roam/records.h"
#include "world/page_store.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <thread>

#include "ridgeline/detail.h"
#include "ridgeline/log.h"

namespace ridgeline::roam {

namespace {

// True when a diamond at v with reach r has every existing descendant within samples [lo, hi]
// along one axis (descendants past the world's first sample or its padded extent do not exist).
bool within(std::int64_t v, std::int64_t r, std::int64_t lo, std::int64_t hi,
            std::int64_t pad) noexcept {
  return (v - r >= lo || lo <= 0) && (v + r <= hi || hi >= pad);
}

std::int64_t floor_div(std::int64_t n, std::int64_t d) noexcept {  // d > 0
  return n >= 0 ? n / d : -((-n + d - 1) / d);
}
// floor_div() by a shift when d is a power of two (the bintree's triangles' edges always are).
std::int64_t floor_div_fast(std::int64_t n, std::int64_t d) noexcept {  // d > 0
  if ((d & (d - 1)) == 0) return n >> __builtin_ctzll(std::uint64_t(d));
  return floor_div(n, d);
}

// Heights of samples lo .. hi of row z into out[0 .. hi - lo]: the accessor's rule, with fast
// paths for dense rows (the values are the accessor's, bit for bit).
template <class H>
void read_row(const H& h, std::int64_t z, std::int64_t lo, std::int64_t hi, float* out) {
  for (std::int64_t x = lo; x <= hi; ++x) out[x - lo] = h(x, z);
}
void read_row(const Heights& h, std::int64_t z, std::int64_t lo, std::int64_t hi, float* out) {
  if ((h.f32 == nullptr && h.u16 == nullptr) || z < 0 || z > h.last_j || lo < 0 ||
      hi > h.last_i) {
    for (std::int64_t x = lo; x <= hi; ++x) out[x - lo] = h(x, z);
    return;
  }
  const std::size_t e = std::size_t(lo) + std::size_t(z) * std::size_t(h.stride);
  const std::size_t n = std::size_t(hi - lo + 1);
  if (h.f32 != nullptr) {
    std::memcpy(out, h.f32 + e, n * sizeof(float));
  } else {
    const std::uint16_t* u = h.u16 + e;
    const double scale = h.scale;
    for (std::size_t k = 0; k < n; ++k) out[k] = static_cast<float>(scale * double(u[k]));
  }
}

// Heights of a square block of samples copied out of an accessor (its values bit for bit): what
// the finest diamonds' bounds read, without the accessor's clamping and branches.
struct DenseBlock {
  const float* p;
  std::int64_t i0, j0, n;
  float operator()(std::int64_t i, std::int64_t j) const noexcept {
    RIDGELINE_ASSERT(i >= i0 && j >= j0 && i < i0 + n && j < j0 + n);
    return p[std::size_t(i - i0) + std::size_t(j - j0) * std::size_t(n)];
  }
};

// The samples inside the small bintree triangles (legs of at most 4 cells: the diamonds of
// t <= 1, most of every world's diamonds), with their edge functions, by the apex's legs: a table
// built once instead of each row's span.
struct SmallTriangles {
  struct Sample {
    std::int8_t dx, dz;        // from the apex
    std::int16_t wa, wl, wr;   // plane * |w| = wa ha + wl hl + wr hr
  };
  static constexpr int kMax = 4;
  static constexpr int kSide = 2 * kMax + 1;
  // Entry (ux, uz, turn): L - A = (ux, uz), R - A = (ux, uz) turned by +-90 degrees.
  std::vector<Sample> samples[kSide * kSide * 2];
  int aw[kSide * kSide * 2] = {};

  static int index(std::int64_t ux, std::int64_t uz, bool left) noexcept {
    return int((ux + kMax) + (uz + kMax) * kSide) * 2 + (left ? 1 : 0);
  }
  SmallTriangles() {
    for (int uz = -kMax; uz <= kMax; ++uz)
      for (int ux = -kMax; ux <= kMax; ++ux)
        for (const bool left : {false, true}) {
          if (ux == 0 && uz == 0) continue;
          const int vx = left ? -uz : uz, vz = left ? ux : -ux;  // R - A
          const int w = ux * vz - uz * vx;
          const int sgn = w > 0 ? 1 : -1;
          const int k = index(ux, uz, left);
          aw[k] = w * sgn;
          const int x0 = std::min({0, ux, vx}), x1 = std::max({0, ux, vx});
          const int z0 = std::min({0, uz, vz}), z1 = std::max({0, uz, vz});
          for (int z = z0; z <= z1; ++z)
            for (int x = x0; x <= x1; ++x) {
              if ((x == 0 && z == 0) || (x == ux && z == uz) || (x == vx && z == vz)) continue;
              const int e_ab = (ux * z - uz * x) * sgn;                         // A -> L
              const int e_lr = ((vx - ux) * (z - uz) - (vz - uz) * (x - ux)) * sgn;  // L -> R
              const int e_ra = ((-vx) * (z - vz) - (-vz) * (x - vx)) * sgn;     // R -> A
              if (e_ab < 0 || e_lr < 0 || e_ra < 0) continue;
              samples[k].push_back({std::int8_t(x), std::int8_t(z), std::int16_t(e_lr),
                                    std::int16_t(e_ra), std::int16_t(e_ab)});
            }
        }
  }
  // The table entry of triangle t, or null when it is not a small right isosceles triangle with
  // its right angle at the apex.
  int find(const LatticeTriangle& t) const noexcept {
    const std::int64_t ux = t.lx - t.ax, uz = t.lz - t.az, vx = t.rx - t.ax, vz = t.rz - t.az;
    if (ux < -kMax || ux > kMax || uz < -kMax || uz > kMax) return -1;
    if (vx == -uz && vz == ux) return index(ux, uz, true);
    if (vx == uz && vz == -ux) return index(ux, uz, false);
    return -1;
  }
};

const SmallTriangles& small_triangles() {
  static const SmallTriangles table;
  return table;
}

// Exact error against the stored lattice of a triangle in stored coordinates: the largest
// |height - plane| over the samples inside it (edge functions in integer arithmetic, the span of
// each row found exactly). Heights past the data repeat the edge (the accessor clamps). The
// plane is evaluated scaled by the triangle's doubled area w (|h w - (S x + T)|, then / |w|):
// the products of heights and integers are exact in doubles.
template <class H>
float exact_triangle(const H& h, const LatticeTriangle& t) {
  const std::int64_t x0 = std::min({t.ax, t.lx, t.rx}), x1 = std::max({t.ax, t.lx, t.rx});
  const std::int64_t z0 = std::min({t.az, t.lz, t.rz}), z1 = std::max({t.az, t.lz, t.rz});
  const double ha = h(t.ax, t.az), hl = h(t.lx, t.lz), hr = h(t.rx, t.rz);
  auto cross = [](std::int64_t ux, std::int64_t uz, std::int64_t vx, std::int64_t vz) {
    return ux * vz - uz * vx;
  };
  const std::int64_t w = cross(t.lx - t.ax, t.lz - t.az, t.rx - t.ax, t.rz - t.az);
  if (w == 0) return 0.0f;
  const std::int64_t sgn = w > 0 ? 1 : -1;
  const double aw = double(w * sgn);
  const SmallTriangles& small = small_triangles();
  if (const int k = small.find(t); k >= 0) {
    double worst = 0.0;
    for (const SmallTriangles::Sample& q : small.samples[k]) {
      const double d = std::abs(double(h(t.ax + q.dx, t.az + q.dz)) * aw -
                                (double(q.wa) * ha + double(q.wl) * hl + double(q.wr) * hr));
      worst = d > worst ? d : worst;
    }
    return round_up(worst / aw);
  }
  thread_local std::vector<float> row;
  if (row.size() < std::size_t(x1 - x0 + 1)) row.resize(std::size_t(x1 - x0 + 1));
  double worst = 0.0;
  const std::int64_t ex[3][2] = {{t.ax, t.az}, {t.lx, t.lz}, {t.rx, t.rz}};
  const int from[3] = {0, 1, 2}, to[3] = {1, 2, 0};
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
        lo = std::max(lo, -floor_div_fast(c, a));  // x >= ceil(-c / a)
      else if (a < 0)
        hi = std::min(hi, floor_div_fast(c, -a));  // x <= floor(c / -a)
      else if (c < 0)
        lo = hi + 1;  // edge parallel to x, row outside
    }
    if (lo > hi) continue;
    // plane(x) * |w| = e_lr(x) ha + e_ra(x) hl + e_ab(x) hr = S x + T, with x relative to lo.
    const double S = double(coef[1]) * ha + double(coef[2]) * hl + double(coef[0]) * hr;
    const double T = double(coef[1] * lo + off[1]) * ha + double(coef[2] * lo + off[2]) * hl +
                     double(coef[0] * lo + off[0]) * hr;
    read_row(h, z, lo, hi, row.data());
    const std::int64_t n = hi - lo + 1;
    double m0 = 0.0, m1 = 0.0;
    std::int64_t x = 0;
    for (; x + 1 < n; x += 2) {
      const double d0 = std::abs(double(row[std::size_t(x)]) * aw - (S * double(x) + T));
      const double d1 = std::abs(double(row[std::size_t(x + 1)]) * aw - (S * double(x + 1) + T));
      m0 = d0 > m0 ? d0 : m0;
      m1 = d1 > m1 ? d1 : m1;
    }
    if (x < n) {
      const double d0 = std::abs(double(row[std::size_t(x)]) * aw - (S * double(x) + T));
      m0 = d0 > m0 ? d0 : m0;
    }
    worst = std::max(worst, std::max(m0, m1));
  }
  return round_up(worst / aw);  // never below the double error
}

// diamond_bound() over any height accessor.
template <class H, class Child>
DiamondBound bound_of(const RecordConfig& c, const H& h, std::int64_t i, std::int64_t j,
                      const Child& child) {
  const int L = int(c.L);
  const Diamond d = diamond_at(i, j, c.K);
  if (L == 0 && d.t == 0 && !d.square) {
    const bool horizontal = (i & 1) != 0;
    return edge_bound_of(c, h(i, j), horizontal ? h(i - 1, j) : h(i, j - 1),
                         horizontal ? h(i + 1, j) : h(i, j + 1), i, j, horizontal);
  }
  const std::int64_t W = c.pad_i, Hh = c.pad_j;
  std::int64_t hx0, hz0, hx1, hz1, ax0, az0, ax1, az1;
  d.hypotenuse(hx0, hz0, hx1, hz1);
  d.apexes(ax0, az0, ax1, az1);
  const std::int64_t wi = c.last_i, hj = c.last_j;
  double err = 0;
  bool any_data = false, straddles = false;
  const std::int64_t apex[2][2] = {{ax0, az0}, {ax1, az1}};
  for (const auto& a : apex) {
    if (a[0] < 0 || a[1] < 0 || a[0] > W || a[1] > Hh) continue;
    const LatticeTriangle t{a[0], a[1], hx0, hz0, hx1, hz1};
    const Landscape::LatticeBox b = Landscape::box_of(t);
    // A triangle over the data's border must split until none does: the mesh then ends on it.
    straddles |= (b.i0 < wi && wi < b.i1) || (b.j0 < hj && hj < b.j1);
    if (b.i0 >= wi || b.j0 >= hj) continue;  // wholly padding: not terrain, never refined
    any_data = true;
    double e = exact_triangle(h, t);
    if (L > 0)
      e += c.detail->contribution_bound(1, std::uint32_t(L), b.i0 << L, b.j0 << L, b.i1 << L,
                                        b.j1 << L);
    err = std::max(err, e);
  }
  if (!any_data) err = 0;
  double morph = err, radius = 0;
  const double hv = h(i, j);
  auto visit = [&](const DiamondBound& cb, double dist) {
    err = std::max(err, double(cb.error));
    morph = std::max(morph, c.growth * double(cb.morph));
    radius = std::max(radius, double(cb.radius) + dist);
    straddles |= cb.radius >= FLT_MAX;
  };
  if (d.has_children()) {
    for (int k = 0; k < 4; ++k) {
      std::int64_t ci, cj;
      d.child(k, ci, cj);
      if (ci < 0 || cj < 0 || ci > W || cj > Hh) continue;
      const double dx = double(ci - i) * c.spacing_x, dz = double(cj - j) * c.spacing_z;
      const double dy = double(h(ci, cj)) - hv;
      visit(child(ci, cj), std::sqrt(dx * dx + dz * dz + dy * dy));
    }
  } else if (L > 0) {
    // The finest stored diamonds' children are detail diamonds at half the stored spacing (in
    // finest coordinates, half of 2^L): their heights are only known within the detail bound.
    const Diamond fd = diamond_at(i << L, j << L, c.K + L);
    const double fsx = std::ldexp(c.spacing_x, -L), fsz = std::ldexp(c.spacing_z, -L);
    for (int k = 0; k < 4; ++k) {
      std::int64_t ci, cj;
      fd.child(k, ci, cj);
      if (ci < 0 || cj < 0 || ci > (W << L) || cj > (Hh << L)) continue;
      const double dx = double(ci - (i << L)) * fsx, dz = double(cj - (j << L)) * fsz;
      // The child's base height: the stored cell's plane at the child (a half-cell midpoint:
      // the mean of the two stored samples at the ends of the edge or diagonal it halves).
      const std::int64_t e0x = (ci - (std::int64_t{1} << (L - 1))) >> L;
      const std::int64_t e1x = (ci + (std::int64_t{1} << (L - 1))) >> L;
      const std::int64_t e0z = (cj - (std::int64_t{1} << (L - 1))) >> L;
      const std::int64_t e1z = (cj + (std::int64_t{1} << (L - 1))) >> L;
      const bool midx = ((ci >> (L - 1)) & 1) != 0, midz = ((cj >> (L - 1)) & 1) != 0;
      double base;
      if (midx && midz) {
        // A cell's centre: the diagonal of the diagonal rule.
        const bool main = cell_has_main_diagonal(e0x, e0z);
        base = main ? 0.5 * (double(h(e0x, e0z)) + double(h(e1x, e1z)))
                    : 0.5 * (double(h(e1x, e0z)) + double(h(e0x, e1z)));
      } else if (midx) {
        base = 0.5 * (double(h(e0x, cj >> L)) + double(h(e1x, cj >> L)));
      } else {
        base = 0.5 * (double(h(ci >> L, e0z)) + double(h(ci >> L, e1z)));
      }
      const double dy = std::abs(base - hv) + double(c.detail_offset(ci, cj));
      visit(c.detail_child(ci, cj), std::sqrt(dx * dx + dz * dz + dy * dy));
    }
  }
  if (straddles) radius = FLT_MAX;
  return quantized(
      {round_up(err), round_up(morph), radius >= FLT_MAX ? FLT_MAX : round_up(radius)});
}

template <class H>
DiamondBound edge_of(const RecordConfig& c, const H& h, std::int64_t i, std::int64_t j) {
  // No children, and no detail: the only vertex under the two triangles but their corners is
  // the centre, on the hypotenuse. bound_of() with no children does exactly this.
  return bound_of(c, h, i, j, [](std::int64_t, std::int64_t) { return DiamondBound{}; });
}

}  // namespace

DiamondBound diamond_bound(const RecordConfig& c, const Heights& h, std::int64_t i, std::int64_t j,
                           const std::function<DiamondBound(std::int64_t, std::int64_t)>& child) {
  return bound_of(c, h, i, j, child);
}

DiamondBound edge_bound(const RecordConfig& c, const Heights& h, std::int64_t i, std::int64_t j) {
  return edge_of(c, h, i, j);
}

// ---- encoding -----------------------------------------------------------------------------------

std::vector<std::uint8_t> RecordBlock::encode() const {
  const std::size_t n =
      values.empty() && encoded ? (encoded->size() - kHeaderBytes) / 4 : values.size();
  std::vector<std::uint8_t> out(kHeaderBytes + n * 4);
  out[0] = 'R', out[1] = 'B', out[2] = std::uint8_t(level), out[3] = edges ? 1 : 0;
  const std::uint32_t n32 = std::uint32_t(n);
  std::memcpy(out.data() + 4, &n32, 4);
  if (!values.empty())
    std::memcpy(out.data() + kHeaderBytes, values.data(), n * 4);
  else if (n > 0)
    std::memcpy(out.data() + kHeaderBytes, encoded->data() + kHeaderBytes, n * 4);
  return out;
}

std::shared_ptr<RecordBlock> RecordBlock::decode(std::uint32_t level,
                                                 std::shared_ptr<const std::vector<std::uint8_t>> in) {
  if (!in || in->size() < kHeaderBytes || (*in)[0] != 'R' || (*in)[1] != 'B' || (*in)[2] != level)
    return nullptr;
  auto b = std::make_shared<RecordBlock>();
  b->level = level;
  b->edges = (*in)[3] != 0;
  std::uint32_t n;
  std::memcpy(&n, in->data() + 4, 4);
  if (n == 0 || n != slots(level, b->edges) || in->size() != kHeaderBytes + std::size_t(n) * 4)
    return nullptr;
  b->encoded = std::move(in);
  return b;
}

void RecordBlock::own() {
  if (!encoded) return;
  const std::size_t n = (encoded->size() - kHeaderBytes) / 4;
  values.resize(n);
  std::memcpy(values.data(), encoded->data() + kHeaderBytes, n * 4);
  encoded.reset();
}

// ---- level 0, from the page alone ---------------------------------------------------------------

namespace {

// The bounds of every t <= 1 diamond whose descendants lie in the block of samples
// [i0, i0 + n) x [j0, j0 + n) (or past the padded extent, where they do not exist), finest
// first, into out[(i - i0) + (j - j0) n]; other entries are left as they are. `h`: the block's
// heights. The level-0 blocks and the bake's t = 1 squares both come from here, so both hold
// the same values.
void small_bounds(const RecordConfig& c, const DenseBlock& h, std::vector<DiamondBound>& out) {
  const std::int64_t i0 = h.i0, j0 = h.j0, n = h.n;
  out.resize(std::size_t(n * n));
  auto at = [&](std::int64_t i, std::int64_t j) -> DiamondBound {
    const std::int64_t a = i - i0, b = j - j0;
    if (a < 0 || b < 0 || a >= n || b >= n) return DiamondBound{};
    return out[std::size_t(a + b * n)];
  };
  // Kinds in order: t = 0 edge, t = 0 square, t = 1 edge, t = 1 square; the residues of their
  // centres (i mod m, j mod m).
  struct Kind {
    int t;
    bool square;
    std::int64_t m;
    int count;
    std::int64_t ri[2], rj[2];
  };
  static constexpr Kind kinds[4] = {{0, false, 2, 2, {1, 0}, {0, 1}},
                                    {0, true, 2, 1, {1, 0}, {1, 0}},
                                    {1, false, 4, 2, {2, 0}, {0, 2}},
                                    {1, true, 4, 1, {2, 0}, {2, 0}}};
  for (const Kind& k : kinds) {
    const std::int64_t r = (k.square ? 3 : 2) << k.t;
    for (int v = 0; v < k.count; ++v) {
      auto first = [&](std::int64_t lo, std::int64_t res) {
        return lo + (((res - lo) % k.m) + k.m) % k.m;
      };
      for (std::int64_t j = first(j0, k.rj[v]); j < j0 + n; j += k.m) {
        if (j < 0 || j > c.pad_j || !within(j, r, j0, j0 + n - 1, c.pad_j)) continue;
        for (std::int64_t i = first(i0, k.ri[v]); i < i0 + n; i += k.m) {
          if (i < 0 || i > c.pad_i || !within(i, r, i0, i0 + n - 1, c.pad_i)) continue;
          // The residues make (i, j) a diamond of this kind (t <= 1 < K: never a corner).
          out[std::size_t((i - i0) + (j - j0) * n)] = bound_of(c, h, i, j, at);
        }
      }
    }
  }
}

}  // namespace

std::shared_ptr<RecordBlock> level0_block(const RecordConfig& c, const world::Page& page) {
  const std::int64_t i0 = std::int64_t(page.key.px) << 8, j0 = std::int64_t(page.key.pz) << 8;
  auto block = std::make_shared<RecordBlock>();
  block->level = 0;
  block->edges = c.L > 0;
  block->values.assign(RecordBlock::slots(0, block->edges), 0);
  // Every t <= 1 diamond of the page and its apron whose descendants lie on the entries. The
  // apron (kPageApron = 6) is the reach of a t = 1 square diamond, so every diamond of the
  // page's own cells is among them.
  thread_local std::vector<float> heights;
  thread_local std::vector<DiamondBound> local;
  heights.resize(kPageEntries);
  for (std::size_t e = 0; e < kPageEntries; ++e) heights[e] = page.local(e);
  const DenseBlock h{heights.data(), i0 - kPageApron, j0 - kPageApron, kPageStride};
  local.assign(kPageEntries, DiamondBound{});
  small_bounds(c, h, local);
  for (std::int32_t b = 0; b <= kPageCells; ++b)
    for (std::int32_t a = 0; a <= kPageCells; ++a) {
      const std::int64_t i = i0 + a, j = j0 + b;
      if (i > c.pad_i || j > c.pad_j) continue;
      const Diamond d = diamond_at(i, j, c.K);
      if (d.corner || d.t >= 2) continue;
      if (d.t == 0 && !d.square && !block->edges) continue;
      block->set(a, b, local[world::entry_index(a, b)]);
    }
  return block;
}

// ---- every block of a whole world ------------------------------------------------------------

namespace {

// Bounds on the grid of stride 4^k (positions (i, j) = (4^k m, 4^k n)), quantised.
struct StrideGrid {
  int shift = 0;  // log2 stride
  std::int64_t nx = 0, nz = 0, off = 0;
  std::vector<std::uint32_t> v;  // one packed bound per position
  void init(int s, std::int64_t pad_i, std::int64_t pad_j, std::int64_t offset) {
    shift = s, off = offset;
    nx = ((pad_i - off) >> s) + 1, nz = ((pad_j - off) >> s) + 1;
    v.assign(std::size_t(nx) * std::size_t(nz), 0);
  }
  bool has(std::int64_t i, std::int64_t j) const noexcept {
    if (i < off || j < off) return false;
    const std::int64_t m = (i - off) >> shift, n = (j - off) >> shift;
    return ((i - off) & ((std::int64_t{1} << shift) - 1)) == 0 &&
           ((j - off) & ((std::int64_t{1} << shift) - 1)) == 0 && m < nx && n < nz;
  }
  DiamondBound get(std::int64_t i, std::int64_t j) const noexcept {
    if (!has(i, j)) return {};
    const std::size_t k = std::size_t((i - off) >> shift) + std::size_t((j - off) >> shift) * std::size_t(nx);
    return packed::unpack(v[k]);
  }
  void set(std::int64_t i, std::int64_t j, const DiamondBound& b) noexcept {
    const std::size_t k = std::size_t((i - off) >> shift) + std::size_t((j - off) >> shift) * std::size_t(nx);
    v[k] = packed::pack(b);
  }
};

// Runs fn(row) for rows [0, n) on `threads` threads.
template <class Fn>
void parallel_rows(std::int64_t n, unsigned threads, const Fn& fn) {
  if (threads <= 1 || n < 16) {
    for (std::int64_t r = 0; r < n; ++r) fn(r);
    return;
  }
  std::atomic<std::int64_t> next{0};
  std::vector<std::thread> pool;
  for (unsigned t = 0; t < threads; ++t)
    pool.emplace_back([&] {
      for (std::int64_t r; (r = next.fetch_add(1)) < n;) fn(r);
    });
  for (auto& th : pool) th.join();
}

// True nested bounds of the t = 1 square diamonds (positions 2 mod 4): what the size-4 edge
// diamonds nest over (the level-0 blocks hold the same values).
// Computed page by page over the page and 8 samples around it.
template <class H, class Out>
void t1_squares(const RecordConfig& c, const world::PageGrid& g, const H& h,
                std::int64_t pi0, std::int64_t pj0, std::int64_t pi1, std::int64_t pj1,
                const Out& out, unsigned threads) {
  const std::int64_t npx = pi1 - pi0 + 1;
  parallel_rows((pj1 - pj0 + 1) * npx, threads, [&](std::int64_t r) {
    const std::int64_t px = pi0 + r % npx, pz = pj0 + r / npx;
    if (px < 0 || pz < 0 || px >= g.px[0] || pz >= g.pz[0]) return;
    // The page's samples and its apron, as a level-0 page holds them.
    const std::int64_t i0 = (px << 8) - kPageApron, j0 = (pz << 8) - kPageApron;
    constexpr std::int64_t n = kPageStride;
    thread_local std::vector<float> heights;
    thread_local std::vector<DiamondBound> local;
    heights.resize(std::size_t(n * n));
    for (std::int64_t b = 0; b < n; ++b)
      read_row(h, j0 + b, i0, i0 + n - 1, heights.data() + b * n);
    local.assign(std::size_t(n * n), DiamondBound{});
    small_bounds(c, DenseBlock{heights.data(), i0, j0, n}, local);
    // The t = 1 squares of this page's cells.
    for (std::int64_t j = (pz << 8) + 2; j < ((pz + 1) << 8) && j <= c.pad_j; j += 4)
      for (std::int64_t i = (px << 8) + 2; i < ((px + 1) << 8) && i <= c.pad_i; i += 4) {
        const Diamond d = diamond_at(i, j, c.K);
        if (d.corner || d.t != 1 || !d.square) continue;
        out(i, j, local[std::size_t((i - i0) + (j - j0) * n)]);
      }
  });
}

// Level k >= 1 (t = 2k, 2k + 1) bounds of the positions of `grid` inside [i0, i1] x [j0, j1]
// whose reach meets it (all of them for a whole world), from the heights and the grids below.
template <class H>
void level_bounds(const RecordConfig& c, const H& h, int k, StrideGrid& grid,
                  const StrideGrid& below_squares, std::int64_t i0, std::int64_t j0,
                  std::int64_t i1, std::int64_t j1, unsigned threads) {
  const std::int64_t stride = std::int64_t{1} << (2 * k);
  for (int kind = 0; kind < 4; ++kind) {
    const int t = 2 * k + kind / 2;
    const bool square = (kind & 1) != 0;
    if (t >= c.K) break;
    const std::int64_t s = std::int64_t{1} << t, reach = (square ? 3 : 2) * s;
    const std::int64_t a0 = std::max<std::int64_t>(0, floor_div(i0 - reach, stride));
    const std::int64_t a1 = std::min<std::int64_t>(c.pad_i / stride, floor_div(i1 + reach, stride) + 1);
    const std::int64_t b0 = std::max<std::int64_t>(0, floor_div(j0 - reach, stride));
    const std::int64_t b1 = std::min<std::int64_t>(c.pad_j / stride, floor_div(j1 + reach, stride) + 1);
    parallel_rows(b1 - b0 + 1, threads, [&](std::int64_t r) {
      const std::int64_t b = b0 + r;
      for (std::int64_t a = a0; a <= a1; ++a) {
        const std::int64_t i = a * stride, j = b * stride;
        const Diamond d = diamond_at(i, j, c.K);
        if (d.corner || d.t != t || d.square != square) continue;
        if (i + reach < i0 || i - reach > i1 || j + reach < j0 || j - reach > j1) continue;
        auto child = [&](std::int64_t ci, std::int64_t cj) -> DiamondBound {
          if (grid.has(ci, cj)) return grid.get(ci, cj);
          return below_squares.get(ci, cj);
        };
        grid.set(i, j, bound_of(c, h, i, j, child));
      }
    });
  }
}

// The block of level-k page `key` (k >= 1) from the grids (entries 0 .. 256): the diamonds whose
// record level (record_level()) is k, each from its own level's grid.
std::shared_ptr<RecordBlock> slice(const RecordConfig& c, const std::vector<StrideGrid>& grids,
                                   std::uint32_t levels, const PageKey& key) {
  auto block = std::make_shared<RecordBlock>();
  block->level = key.level;
  block->values.assign(RecordBlock::kCoarse, 0);
  const int ls = world::level_shift(key.level);
  const std::int64_t i0 = std::int64_t(key.px) << world::page_shift(key.level);
  const std::int64_t j0 = std::int64_t(key.pz) << world::page_shift(key.level);
  for (std::int32_t b = 0; b <= kPageCells; ++b)
    for (std::int32_t a = 0; a <= kPageCells; ++a) {
      const std::int64_t i = i0 + (std::int64_t(a) << ls), j = j0 + (std::int64_t(b) << ls);
      if (i < 0 || j < 0 || i > c.pad_i || j > c.pad_j) continue;
      const Diamond d = diamond_at(i, j, c.K);
      if (d.corner || record_level(d.t, levels) != key.level) continue;
      const std::size_t g = std::size_t(d.t / 2);
      block->set(a, b, g < grids.size() ? grids[g].get(i, j) : DiamondBound{});
    }
  return block;
}


}  // namespace

void build_all(const RecordConfig& c, const world::PageGrid& grid, const Heights& h,
               const std::function<const world::Page*(const PageKey&)>& page,
               const std::function<void(const PageKey&, std::shared_ptr<RecordBlock>)>& out,
               unsigned threads, bool level0) {
  const Heights& dh = h;
  // Grids of every level >= 1, coarsest last; each built from the one below.
  const int top_level = (c.K - 1) / 2;
  std::vector<StrideGrid> grids(std::size_t(std::max(top_level, 0)) + 1);
  StrideGrid squares1;  // t = 1 squares
  squares1.init(2, c.pad_i, c.pad_j, 2);
  t1_squares(c, grid, dh, 0, 0, grid.px[0] - 1, grid.pz[0] - 1,
             [&](std::int64_t i, std::int64_t j, const DiamondBound& v) { squares1.set(i, j, v); },
             threads);
  for (int k = 1; k <= top_level; ++k) {
    grids[std::size_t(k)].init(2 * k, c.pad_i, c.pad_j, 0);
    level_bounds(c, dh, k, grids[std::size_t(k)], k == 1 ? squares1 : grids[std::size_t(k - 1)],
                 0, 0, c.pad_i, c.pad_j, threads);
  }
  // Level >= 1 blocks, then level 0 (from the pages alone).
  for (std::uint32_t k = 1; k < grid.levels; ++k)
    for (std::int32_t pz = 0; pz < grid.pz[k]; ++pz)
      for (std::int32_t px = 0; px < grid.px[k]; ++px) {
        const PageKey key{k, px, pz};
        out(key, slice(c, grids, grid.levels, key));
      }
  if (!level0) return;
  const std::int64_t n0 = std::int64_t(grid.count(0));
  parallel_rows(n0, threads, [&](std::int64_t r) {
    const std::int32_t px = std::int32_t(r % grid.px[0]), pz = std::int32_t(r / grid.px[0]);
    const PageKey key{0, px, pz};
    if (const world::Page* p = page(key)) out(key, level0_block(c, *p));
  });
}

std::vector<std::pair<PageKey, std::shared_ptr<const RecordBlock>>> remake(
    const RecordConfig& c, const world::PageGrid& grid, const Heights& h,
    const std::function<const world::Page*(const PageKey&)>& page,
    const std::function<const RecordBlock*(const PageKey&)>& block, std::int64_t i0,
    std::int64_t j0, std::int64_t i1, std::int64_t j1) {
  const Heights& dh = h;
  // The padding repeats the edge samples: an edited edge sample moves the padding too.
  if (i1 >= c.last_i) i1 = c.pad_i;
  if (j1 >= c.last_j) j1 = c.pad_j;
  std::unordered_map<PageKey, std::shared_ptr<RecordBlock>, world::PageKeyHash> fresh;
  auto writable = [&](const PageKey& k) -> RecordBlock* {
    if (auto it = fresh.find(k); it != fresh.end()) return it->second.get();
    const RecordBlock* b = block(k);
    if (b == nullptr) return nullptr;
    auto copy = std::make_shared<RecordBlock>(*b);
    RecordBlock* raw = copy.get();
    fresh.emplace(k, std::move(copy));
    return raw;
  };
  const int top_level = (c.K - 1) / 2;
  // Level by level: the positions whose reach meets the change, from the current bounds (the
  // blocks) and the heights, then written to every block holding them (aprons included).
  // Read-modify-write through a map keyed by position (the window is small).
  struct Window {
    std::unordered_map<std::uint64_t, DiamondBound> v;
    static std::uint64_t key(std::int64_t i, std::int64_t j) {
      return (std::uint64_t(std::uint32_t(j)) << 32) | std::uint32_t(i);
    }
  };
  // The current bound of a level >= 1 diamond from its block (canonical page).
  auto stored = [&](std::int64_t i, std::int64_t j) -> DiamondBound {
    const Diamond d = diamond_at(i, j, c.K);
    if (d.corner) return {};
    const std::uint32_t k = record_level(d.t, grid.levels);
    const PageKey key = grid.page_of(k, i, j);
    const std::int32_t a = std::int32_t((i >> (2 * k)) - (std::int64_t(key.px) << 8));
    const std::int32_t b = std::int32_t((j >> (2 * k)) - (std::int64_t(key.pz) << 8));
    if (auto it = fresh.find(key); it != fresh.end()) return it->second->get(a, b);
    const RecordBlock* bl = block(key);
    return bl ? bl->get(a, b) : DiamondBound{};
  };
  // Into every block holding it: its page's and, on a page edge, its neighbours' (entries 0 ..
  // 256 of each).
  auto store_everywhere = [&](std::int64_t i, std::int64_t j, std::uint32_t k, const DiamondBound& v) {
    const int ls = world::level_shift(k);
    const std::int64_t x = i >> ls, z = j >> ls;
    for (std::int64_t pz = std::max<std::int64_t>(0, floor_div(z - 1, kPageCells));
         pz <= std::min<std::int64_t>(grid.pz[k] - 1, floor_div(z, kPageCells)); ++pz)
      for (std::int64_t px = std::max<std::int64_t>(0, floor_div(x - 1, kPageCells));
           px <= std::min<std::int64_t>(grid.px[k] - 1, floor_div(x, kPageCells)); ++px) {
        const std::int32_t a = std::int32_t(x - (px << 8)), b = std::int32_t(z - (pz << 8));
        if (!RecordBlock::holds(a, b)) continue;
        if (RecordBlock* bl = writable({k, std::int32_t(px), std::int32_t(pz)})) bl->set(a, b, v);
      }
  };
  // t = 1 squares near the change: true values (runtime radius) from the heights.
  Window t1;
  {
    // The pages near the change (a t = 2 edge diamond reaching the change has its children
    // within 10 samples of it).
    const std::int64_t w = 16;
    t1_squares(c, grid, dh, std::max<std::int64_t>(0, (i0 - w) >> 8),
               std::max<std::int64_t>(0, (j0 - w) >> 8), (i1 + w) >> 8, (j1 + w) >> 8,
               [&](std::int64_t i, std::int64_t j, const DiamondBound& v) {
                 t1.v[Window::key(i, j)] = v;
               },
               1);
  }
  for (int k = 1; k <= top_level; ++k) {
    const std::int64_t stride = std::int64_t{1} << (2 * k);
    for (int kind = 0; kind < 4; ++kind) {
      const int t = 2 * k + kind / 2;
      const bool square = (kind & 1) != 0;
      if (t >= c.K) break;
      const std::int64_t s = std::int64_t{1} << t, reach = (square ? 3 : 2) * s;
      const std::int64_t a0 = std::max<std::int64_t>(0, floor_div(i0 - reach, stride));
      const std::int64_t a1 = std::min<std::int64_t>(c.pad_i / stride, floor_div(i1 + reach, stride) + 1);
      const std::int64_t b0 = std::max<std::int64_t>(0, floor_div(j0 - reach, stride));
      const std::int64_t b1 = std::min<std::int64_t>(c.pad_j / stride, floor_div(j1 + reach, stride) + 1);
      for (std::int64_t b = b0; b <= b1; ++b)
        for (std::int64_t a = a0; a <= a1; ++a) {
          const std::int64_t i = a * stride, j = b * stride;
          const Diamond d = diamond_at(i, j, c.K);
          if (d.corner || d.t != t || d.square != square) continue;
          if (i + reach < i0 || i - reach > i1 || j + reach < j0 || j - reach > j1) continue;
          auto child = [&](std::int64_t ci, std::int64_t cj) -> DiamondBound {
            const Diamond cd = diamond_at(ci, cj, c.K);
            if (cd.t <= 1) {
              auto it = t1.v.find(Window::key(ci, cj));
              return it != t1.v.end() ? it->second : DiamondBound{};
            }
            return stored(ci, cj);
          };
          store_everywhere(i, j, record_level(t, grid.levels), bound_of(c, dh, i, j, child));
        }
    }
  }
  // Level-0 pages near the change (their apron reaches 6 samples past their cells).
  const std::int64_t w = 16;
  for (std::int64_t pz = std::max<std::int64_t>(0, (j0 - w) >> 8);
       pz <= std::min<std::int64_t>(grid.pz[0] - 1, (j1 + w) >> 8); ++pz)
    for (std::int64_t px = std::max<std::int64_t>(0, (i0 - w) >> 8);
         px <= std::min<std::int64_t>(grid.px[0] - 1, (i1 + w) >> 8); ++px) {
      const PageKey key{0, std::int32_t(px), std::int32_t(pz)};
      if (const world::Page* p = page(key)) fresh[key] = level0_block(c, *p);
    }
  std::vector<std::pair<PageKey, std::shared_ptr<const RecordBlock>>> outv;
  outv.reserve(fresh.size());
  for (auto& [k, b] : fresh) outv.emplace_back(k, std::move(b));
  return outv;
}

}  // namespace ridgeline::roam
