// Private (records.cpp): the bound and sphere of one stored diamond from the heights: the exact
// error of its triangles (a table of the small ones), made nested over its children, and the
// t <= 1 diamonds of a block of samples that the level-0 blocks and the bake share. Templates
// over the height accessor, so that the dense paths read plain arrays.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <utility>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#if !defined(RIDGELINE_PORTABLE) && (defined(__SSE2__) || defined(_M_X64))
#include <emmintrin.h>
#endif

#include "ridgeline/detail.h"
#include "platform/cpu_features.h"
#include "ridgeline/log.h"
#include "roam/diamond.h"
#include "roam/records.h"

namespace ridgeline::roam::bounds {

// True when a diamond at v with reach r has every existing descendant within samples [lo, hi]
// along one axis (descendants past the world's first sample or its padded extent do not exist).
inline bool within(std::int64_t v, std::int64_t r, std::int64_t lo, std::int64_t hi,
            std::int64_t pad) noexcept {
  return (v - r >= lo || lo <= 0) && (v + r <= hi || hi >= pad);
}

using world::floor_div;
// floor_div() by a shift when d is a power of two (the bintree's triangles' edges always are).
inline std::int64_t floor_div_fast(std::int64_t n, std::int64_t d) noexcept {  // d > 0
  if ((d & (d - 1)) == 0) return n >> std::countr_zero(std::uint64_t(d));
  return floor_div(n, d);
}

// Heights of samples lo .. hi of row z into out[0 .. hi - lo]: the accessor's rule, with fast
// paths for dense rows (the values are the accessor's, bit for bit).
template <class H>
void read_row(const H& h, std::int64_t z, std::int64_t lo, std::int64_t hi, float* out) {
  for (std::int64_t x = lo; x <= hi; ++x) out[x - lo] = h(x, z);
}
[[gnu::always_inline]] inline void read_row(const Heights& h, std::int64_t z, std::int64_t lo, std::int64_t hi, float* out) {
  if (h.f32 == nullptr && h.u16 == nullptr) {
    for (std::int64_t x = lo; x <= hi; ++x) out[x - lo] = h(x, z);
    return;
  }
  // Past the data the accessor repeats the edge: the row's clamped row, its ends repeated.
  z = z < 0 ? 0 : (z > h.last_j ? h.last_j : z);
  if (lo < 0 || hi > h.last_i) {
    const std::int64_t a = std::max<std::int64_t>(lo, 0), b = std::min(hi, h.last_i);
    if (a > b) {  // wholly past one side
      const float v = h(lo < 0 ? 0 : h.last_i, z);
      for (std::int64_t x = lo; x <= hi; ++x) out[x - lo] = v;
      return;
    }
    const float first = h(0, z), last = h(h.last_i, z);
    for (std::int64_t x = lo; x < a; ++x) out[x - lo] = first;
    for (std::int64_t x = b + 1; x <= hi; ++x) out[x - lo] = last;
    out += a - lo, lo = a, hi = b;
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
[[gnu::always_inline]] inline void read_row(const DenseBlock& h, std::int64_t z, std::int64_t lo, std::int64_t hi, float* out) {
  RIDGELINE_ASSERT(lo >= h.i0 && hi < h.i0 + h.n && z >= h.j0 && z < h.j0 + h.n);
  std::memcpy(out, h.p + std::size_t(lo - h.i0) + std::size_t(z - h.j0) * std::size_t(h.n),
              std::size_t(hi - lo + 1) * sizeof(float));
}

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

inline const SmallTriangles& small_triangles() {
  static const SmallTriangles table;
  return table;
}

// The samples [lo, hi] of row z inside the triangle with corners ex (A, L, R), and its three edge
// functions e_k(x) = coef[k] x + off[k] on that row (k = 0 A -> L, 1 L -> R, 2 R -> A; made >= 0
// inside by sgn, the sign of the doubled area): [lo, hi] narrows to each edge's inner side, and
// comes back empty (lo > hi) for a row outside. exact_triangle() and RowShapes both use it.
inline void row_span(const std::int64_t (&ex)[3][2], std::int64_t sgn, std::int64_t z,
                     std::int64_t& lo, std::int64_t& hi, std::int64_t (&coef)[3],
                     std::int64_t (&off)[3]) noexcept {
  static constexpr int from[3] = {0, 1, 2}, to[3] = {1, 2, 0};
  for (int k = 0; k < 3; ++k) {
    const std::int64_t px = ex[from[k]][0], pz = ex[from[k]][1];
    const std::int64_t ux = ex[to[k]][0] - px, uz = ex[to[k]][1] - pz;
    // e(x) = ux * (z - pz) - uz * (x - px) = a * x + c.
    const std::int64_t a = -uz * sgn, c = (ux * (z - pz) + uz * px) * sgn;
    coef[k] = a, off[k] = c;
    if (a > 0)
      lo = std::max(lo, -floor_div_fast(c, a));  // x >= ceil(-c / a)
    else if (a < 0)
      hi = std::min(hi, floor_div_fast(c, -a));  // x <= floor(c / -a)
    else if (c < 0)
      lo = hi + 1;  // edge parallel to x, row outside
  }
}

// The rows of the bintree's triangles of legs up to 64 cells (axis-aligned or diagonal, the
// right angle at the apex), relative to the apex: each row's first sample and count, and the
// three edge functions at its first sample; exact_triangle()'s spans and integers, found once per
// shape instead of per row (the edge functions do not change when the triangle moves).
struct RowShapes {
  struct Row {
    std::int32_t dz, dlo, n;
    std::int64_t e0, e1, e2;  // A -> L, L -> R, R -> A at (lo, z), made >= 0 inside
  };
  struct Shape {
    std::int64_t c0 = 0, c1 = 0, c2 = 0;  // the edge functions' x coefficients
    double aw = 1;
    std::vector<Row> rows;
  };
  static constexpr int kSizes = 7;  // legs 1 .. 64
  Shape shapes[kSizes][8][2];

  // The shape's slot for legs L - A = (ux, uz) and R - A = (ux, uz) turned (left: by +90
  // degrees), or null when the legs are not an axis or a diagonal of a power of two <= 64.
  static bool slot(std::int64_t ux, std::int64_t uz, int& size, int& dir) noexcept {
    const std::int64_t ax = ux < 0 ? -ux : ux, az = uz < 0 ? -uz : uz;
    const std::int64_t m = std::max(ax, az);
    if (m == 0 || m > 64 || (m & (m - 1)) != 0 || (ax != 0 && ax != m) || (az != 0 && az != m))
      return false;
    size = std::countr_zero(std::uint64_t(m));
    dir = (ux > 0 ? 2 : ux < 0 ? 0 : 1) + 3 * (uz > 0 ? 2 : uz < 0 ? 0 : 1);  // 0 .. 8 but 4
    dir = dir > 4 ? dir - 1 : dir;
    return true;
  }
  RowShapes() {
    for (int a = 0; a < kSizes; ++a)
      for (int sx = -1; sx <= 1; ++sx)
        for (int sz = -1; sz <= 1; ++sz)
          for (const bool left : {false, true}) {
            if (sx == 0 && sz == 0) continue;
            const std::int64_t ux = std::int64_t(sx) << a, uz = std::int64_t(sz) << a;
            const std::int64_t vx = left ? -uz : uz, vz = left ? ux : -ux;  // R - A
            int size = 0, dir = 0;
            slot(ux, uz, size, dir);
            Shape& sh = shapes[size][dir][left ? 1 : 0];
            const std::int64_t w = ux * vz - uz * vx;
            const std::int64_t sgn = w > 0 ? 1 : -1;
            sh.aw = double(w * sgn);
            // Edges as exact_triangle() takes them: k = 0 A -> L, 1 L -> R, 2 R -> A.
            const std::int64_t ex[3][2] = {{0, 0}, {ux, uz}, {vx, vz}};
            const std::int64_t x0 = std::min({std::int64_t{0}, ux, vx}), x1 = std::max({std::int64_t{0}, ux, vx});
            const std::int64_t z0 = std::min({std::int64_t{0}, uz, vz}), z1 = std::max({std::int64_t{0}, uz, vz});
            std::int64_t coef[3] = {};
            for (std::int64_t z = z0; z <= z1; ++z) {
              std::int64_t lo = x0, hi = x1, off[3];
              row_span(ex, sgn, z, lo, hi, coef, off);
              if (lo > hi) continue;
              sh.rows.push_back({std::int32_t(z), std::int32_t(lo), std::int32_t(hi - lo + 1),
                                 coef[0] * lo + off[0], coef[1] * lo + off[1], coef[2] * lo + off[2]});
            }
            sh.c0 = coef[0], sh.c1 = coef[1], sh.c2 = coef[2];
          }
  }
};

inline const RowShapes& row_shapes() {
  static const RowShapes table;
  return table;
}

#if RIDGELINE_HAS_AVX2_DISPATCH
// row_worst() for rows of 8 samples or more, eight at a time in two four-lane halves (AVX2).
RIDGELINE_TARGET_AVX2 inline double row_worst_avx2(const float* row, std::int64_t n, double aw,
                                                   double S, double T) noexcept {
  const __m256d sign = _mm256_set1_pd(-0.0), vaw = _mm256_set1_pd(aw), vS = _mm256_set1_pd(S),
                vT = _mm256_set1_pd(T), step = _mm256_set1_pd(8.0);
  __m256d x0 = _mm256_setr_pd(0.0, 1.0, 2.0, 3.0), x1 = _mm256_setr_pd(4.0, 5.0, 6.0, 7.0);
  __m256d m0 = _mm256_setzero_pd(), m1 = _mm256_setzero_pd();
  std::int64_t x = 0;
  for (; x + 7 < n; x += 8) {
    const __m256d h0 = _mm256_cvtps_pd(_mm_loadu_ps(row + x)), h1 = _mm256_cvtps_pd(_mm_loadu_ps(row + x + 4));
    const __m256d d0 = _mm256_sub_pd(_mm256_mul_pd(h0, vaw), _mm256_add_pd(_mm256_mul_pd(vS, x0), vT));
    const __m256d d1 = _mm256_sub_pd(_mm256_mul_pd(h1, vaw), _mm256_add_pd(_mm256_mul_pd(vS, x1), vT));
    m0 = _mm256_max_pd(m0, _mm256_andnot_pd(sign, d0));
    m1 = _mm256_max_pd(m1, _mm256_andnot_pd(sign, d1));
    x0 = _mm256_add_pd(x0, step), x1 = _mm256_add_pd(x1, step);
  }
  alignas(32) double lanes[4];
  _mm256_store_pd(lanes, _mm256_max_pd(m0, m1));
  double worst = std::max({lanes[0], lanes[1], lanes[2], lanes[3]});
  for (; x < n; ++x) {
    const double d = std::abs(double(row[x]) * aw - (S * double(x) + T));
    worst = d > worst ? d : worst;
  }
  return worst;
}
#endif

// max |row[x] aw - (S x + T)| over x in [0, n): four lanes of AVX2 for long rows where the CPU
// has it, else two lanes of SSE2 where there is SSE2 (every x86-64; not with RIDGELINE_PORTABLE),
// one elsewhere; the same values every way (each lane rounds as the scalar code does, and the
// largest of them does not depend on the order).
[[gnu::always_inline]] inline double row_worst(const float* row, std::int64_t n, double aw, double S, double T) noexcept {
#if RIDGELINE_HAS_AVX2_DISPATCH
  if (n >= 8 && detail::cpu_has_avx2()) return row_worst_avx2(row, n, aw, S, T);
#endif
  std::int64_t x = 0;
  double worst = 0.0;
#if !defined(RIDGELINE_PORTABLE) && (defined(__SSE2__) || defined(_M_X64))
  const __m128d sign = _mm_set1_pd(-0.0), vaw = _mm_set1_pd(aw), vS = _mm_set1_pd(S),
                vT = _mm_set1_pd(T), step = _mm_set1_pd(4.0);
  __m128d x01 = _mm_set_pd(1.0, 0.0), x23 = _mm_set_pd(3.0, 2.0);
  __m128d m01 = _mm_setzero_pd(), m23 = _mm_setzero_pd();
  for (; x + 3 < n; x += 4) {
    const __m128 r = _mm_loadu_ps(row + x);
    const __m128d h01 = _mm_cvtps_pd(r), h23 = _mm_cvtps_pd(_mm_movehl_ps(r, r));
    const __m128d d01 = _mm_sub_pd(_mm_mul_pd(h01, vaw), _mm_add_pd(_mm_mul_pd(vS, x01), vT));
    const __m128d d23 = _mm_sub_pd(_mm_mul_pd(h23, vaw), _mm_add_pd(_mm_mul_pd(vS, x23), vT));
    m01 = _mm_max_pd(m01, _mm_andnot_pd(sign, d01));
    m23 = _mm_max_pd(m23, _mm_andnot_pd(sign, d23));
    x01 = _mm_add_pd(x01, step), x23 = _mm_add_pd(x23, step);
  }
  double lanes[4];
  _mm_storeu_pd(lanes, m01);
  _mm_storeu_pd(lanes + 2, m23);
  worst = std::max({lanes[0], lanes[1], lanes[2], lanes[3]});
#endif
  for (; x < n; ++x) {
    const double d = std::abs(double(row[x]) * aw - (S * double(x) + T));
    worst = d > worst ? d : worst;
  }
  return worst;
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
  int size = 0, dir = 0;
  if (RowShapes::slot(t.lx - t.ax, t.lz - t.az, size, dir)) {
    const std::int64_t ux = t.lx - t.ax, uz = t.lz - t.az;
    const bool left = t.rx - t.ax == -uz && t.rz - t.az == ux;
    if (left || (t.rx - t.ax == uz && t.rz - t.az == -ux)) {
      // The same spans and values as the rows below give, from the shape's table.
      const RowShapes::Shape& sh = row_shapes().shapes[size][dir][left ? 1 : 0];
      const double S = double(sh.c1) * ha + double(sh.c2) * hl + double(sh.c0) * hr;
      for (const RowShapes::Row& r : sh.rows) {
        const double T = double(r.e1) * ha + double(r.e2) * hl + double(r.e0) * hr;
        const std::int64_t lo = t.ax + r.dlo;
        read_row(h, t.az + r.dz, lo, lo + r.n - 1, row.data());
        worst = std::max(worst, row_worst(row.data(), r.n, sh.aw, S, T));
      }
      return round_up(worst / aw);
    }
  }
  const std::int64_t ex[3][2] = {{t.ax, t.az}, {t.lx, t.lz}, {t.rx, t.rz}};
  for (std::int64_t z = z0; z <= z1; ++z) {
    std::int64_t lo = x0, hi = x1;
    std::int64_t coef[3], off[3];
    row_span(ex, sgn, z, lo, hi, coef, off);
    if (lo > hi) continue;
    // plane(x) * |w| = e_lr(x) ha + e_ra(x) hl + e_ab(x) hr = S x + T, with x relative to lo.
    const double S = double(coef[1]) * ha + double(coef[2]) * hl + double(coef[0]) * hr;
    const double T = double(coef[1] * lo + off[1]) * ha + double(coef[2] * lo + off[2]) * hl +
                     double(coef[0] * lo + off[0]) * hr;
    read_row(h, z, lo, hi, row.data());
    const std::int64_t n = hi - lo + 1;
    worst = std::max(worst, row_worst(row.data(), n, aw, S, T));
  }
  return round_up(worst / aw);  // never below the double error
}

// diamond_bound() over any height accessor.
template <class H, class Child>
DiamondBound bound_of(const RecordConfig& c, const H& h, std::int64_t i, std::int64_t j,
                      const Child& child) {
  const int L = int(c.L);
  const Diamond d = diamond_at(i, j, c.patch_log2);
  if (L == 0 && d.t == 0 && !d.square) {
    const bool horizontal = (i & 1) != 0;
    DiamondBound b = edge_bound_of(c, h(i, j), horizontal ? h(i - 1, j) : h(i, j - 1),
                                   horizontal ? h(i + 1, j) : h(i, j + 1), i, j, horizontal);
    if (c.holes != nullptr && straddles_hole(*c.holes, c.patch_log2, c.pad_i, c.pad_j, i, j))
      b.radius = std::numeric_limits<float>::infinity();  // what FLT_MAX quantises to
    return b;
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
  // Over a hole's edge as over the data's border: split until the mesh ends on it.
  if (c.holes != nullptr && !straddles)
    straddles = straddles_hole(*c.holes, c.patch_log2, c.pad_i, c.pad_j, i, j);
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
    const Diamond fd = diamond_at(i << L, j << L, c.patch_log2 + L);
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


// The fixed shape of the t <= 1 diamonds of one kind and orientation, as offsets from the centre
// in a dense block of stride n: the samples of its two triangles with their edge functions (the
// small-triangle table's, so the arithmetic is exact_triangle()'s), and its four children. For a
// diamond wholly inside the data, its bound is then bound_of()'s, bit for bit, without the
// per-diamond classification and table lookups (most of every world's diamonds are these).
struct SmallStencil {
  struct Tri {
    std::ptrdiff_t a = 0, l = 0, r = 0;  // apex, left, right
    double aw = 1;
    std::vector<std::ptrdiff_t> at;
    std::vector<std::array<double, 3>> w;  // wa, wl, wr
  };
  Tri tri[2];
  std::ptrdiff_t child[4] = {};
  double cdx[4] = {}, cdz[4] = {};
  std::int64_t cdi[4] = {}, cdj[4] = {};  // the children's positions from the centre
  int children = 0;

  // From the representative diamond (ri, rj) of the kind (a patch exponent of 10: never a top).
  SmallStencil(std::int64_t ri, std::int64_t rj, std::int64_t n) {
    const Diamond d = diamond_at(ri, rj, 10);
    std::int64_t hx0, hz0, hx1, hz1, ax0, az0, ax1, az1;
    d.hypotenuse(hx0, hz0, hx1, hz1);
    d.apexes(ax0, az0, ax1, az1);
    const std::int64_t apex[2][2] = {{ax0, az0}, {ax1, az1}};
    auto off = [&](std::int64_t x, std::int64_t z) { return std::ptrdiff_t((x - ri) + (z - rj) * n); };
    const SmallTriangles& small = small_triangles();
    for (int k = 0; k < 2; ++k) {
      const LatticeTriangle t{apex[k][0], apex[k][1], hx0, hz0, hx1, hz1};
      const int e = small.find(t);
      RIDGELINE_ASSERT(e >= 0);
      const std::int64_t w = (t.lx - t.ax) * (t.rz - t.az) - (t.lz - t.az) * (t.rx - t.ax);
      Tri& q = tri[k];
      q.a = off(t.ax, t.az), q.l = off(t.lx, t.lz), q.r = off(t.rx, t.rz);
      q.aw = double(w > 0 ? w : -w);
      for (const SmallTriangles::Sample& sm : small.samples[e]) {
        q.at.push_back(off(t.ax + sm.dx, t.az + sm.dz));
        q.w.push_back({double(sm.wa), double(sm.wl), double(sm.wr)});
      }
    }
    if (d.has_children())
      for (int k = 0; k < 4; ++k, ++children) {
        std::int64_t ci, cj;
        d.child(k, ci, cj);
        child[k] = off(ci, cj), cdx[k] = double(ci - ri), cdz[k] = double(cj - rj);
        cdi[k] = ci - ri, cdj[k] = cj - rj;
      }
  }

  // bound_of() of the diamond whose centre is entry `c0` of `p` (its triangles and children
  // inside the data and the block), packed; children's packed bounds read from `out` at the same
  // entries.
  std::uint32_t bound(const RecordConfig& c, const float* p, const std::uint32_t* out,
                      std::ptrdiff_t c0) const noexcept {
    std::uint32_t cv[4] = {};
    for (int k = 0; k < children; ++k) cv[k] = out[c0 + child[k]];
    return bound(c, p, c0, cv);
  }
  // The same with the children's packed bounds given (cv[k]: child k's).
  std::uint32_t bound(const RecordConfig& c, const float* p, std::ptrdiff_t c0,
                      const std::uint32_t* cv) const noexcept {
    double err = 0;
    for (const Tri& q : tri) {
      const double ha = p[c0 + q.a], hl = p[c0 + q.l], hr = p[c0 + q.r];
      double worst = 0.0;
      for (std::size_t k = 0; k < q.at.size(); ++k) {
        const double d = std::abs(double(p[c0 + q.at[k]]) * q.aw -
                                  (q.w[k][0] * ha + q.w[k][1] * hl + q.w[k][2] * hr));
        worst = d > worst ? d : worst;
      }
      err = std::max(err, double(round_up(worst / q.aw)));
    }
    double morph = err, radius = 0;
    bool straddles = false;
    const double hv = p[c0];
    for (int k = 0; k < children; ++k) {
      const DiamondBound cb = packed::unpack(cv[k]);
      const double dx = cdx[k] * c.spacing_x, dz = cdz[k] * c.spacing_z;
      const double dy = double(p[c0 + child[k]]) - hv;
      const double dist = std::sqrt(dx * dx + dz * dz + dy * dy);
      err = std::max(err, double(cb.error));
      morph = std::max(morph, c.growth * double(cb.morph));
      radius = std::max(radius, double(cb.radius) + dist);
      straddles |= cb.radius >= FLT_MAX;
    }
    if (straddles) radius = FLT_MAX;
    return packed::pack(
        {round_up(err), round_up(morph), radius >= FLT_MAX ? FLT_MAX : round_up(radius)});
  }
};

#if RIDGELINE_HAS_AVX2_DISPATCH
// The stencil diamonds (t <= 1 and the t = 2 edges) four at a time (AVX2, chosen at run time):
// the scalar arithmetic of SmallStencil::bound() and the edge rule in four lanes, the same
// operations in the same order (doubles, no fused multiply-adds), so every lane's packed bound is
// the scalar one bit for bit (Records.SmallDiamondStencilsGiveTheGeneralBoundsBitForBit,
// Records.CoarseLevelsAreTheGeneralBoundsOfTheirStoredChildren). `lanes`: the centres' entries.
namespace x4 {

// packed::up12() of four floats.
RIDGELINE_TARGET_AVX2 inline __m128i up12(__m128 v) noexcept {
  const __m128i bits = _mm_castps_si128(v);
  const __m128i e = _mm_sub_epi32(_mm_srli_epi32(bits, 23), _mm_set1_epi32(127 - packed::kBias));
  __m128i m = _mm_srli_epi32(_mm_and_si128(bits, _mm_set1_epi32(0x7fffff)), 17);
  // + 1 when any of the 17 bits below is set (round up); a carry into the exponent is the add's.
  const __m128i exact = _mm_cmpeq_epi32(_mm_and_si128(bits, _mm_set1_epi32(0x1ffff)), _mm_setzero_si128());
  m = _mm_add_epi32(m, _mm_andnot_si128(exact, _mm_set1_epi32(1)));
  __m128i c = _mm_add_epi32(_mm_slli_epi32(e, 6), m);
  c = _mm_min_epi32(_mm_max_epi32(c, _mm_set1_epi32(1 << 6)), _mm_set1_epi32(int(packed::kInfinity)));
  const __m128 big = _mm_cmpnlt_ps(v, _mm_set1_ps(1.0e30f));  // !(v < 1e30), NaN included
  c = _mm_blendv_epi8(c, _mm_set1_epi32(int(packed::kInfinity)), _mm_castps_si128(big));
  return _mm_and_si128(c, _mm_castps_si128(_mm_cmpgt_ps(v, _mm_setzero_ps())));  // !(v > 0): 0
}

// packed::down12() of four codes (0 .. kInfinity).
RIDGELINE_TARGET_AVX2 inline __m128 down12(__m128i c) noexcept {
  const __m128i ex = _mm_add_epi32(_mm_and_si128(_mm_srli_epi32(c, 6), _mm_set1_epi32(63)),
                                   _mm_set1_epi32(127 - packed::kBias));
  const __m128i bits = _mm_or_si128(_mm_slli_epi32(ex, 23),
                                    _mm_slli_epi32(_mm_and_si128(c, _mm_set1_epi32(63)), 17));
  __m128 f = _mm_castsi128_ps(bits);
  f = _mm_blendv_ps(f, _mm_setzero_ps(), _mm_castsi128_ps(_mm_cmpeq_epi32(c, _mm_setzero_si128())));
  const __m128i inf = _mm_cmpgt_epi32(c, _mm_set1_epi32(int(packed::kInfinity) - 1));
  return _mm_blendv_ps(f, _mm_set1_ps(std::numeric_limits<float>::infinity()), _mm_castsi128_ps(inf));
}

// round_up() of four doubles >= 0, as floats.
RIDGELINE_TARGET_AVX2 inline __m128 round_up(__m256d v) noexcept {
  const __m128 f = _mm256_cvtpd_ps(v);
  const __m256i lt = _mm256_castpd_si256(_mm256_cmp_pd(_mm256_cvtps_pd(f), v, _CMP_LT_OQ));
  const __m128i below = _mm256_castsi256_si128(
      _mm256_permutevar8x32_epi32(lt, _mm256_setr_epi32(0, 2, 4, 6, 1, 3, 5, 7)));
  return _mm_castsi128_ps(_mm_sub_epi32(_mm_castps_si128(f), below));  // the next float up
}

// A 64-bit lane mask as four 32-bit lanes.
RIDGELINE_TARGET_AVX2 inline __m128 narrow(__m256d mask) noexcept {
  return _mm_castsi128_ps(_mm256_castsi256_si128(_mm256_permutevar8x32_epi32(
      _mm256_castpd_si256(mask), _mm256_setr_epi32(0, 2, 4, 6, 1, 3, 5, 7))));
}

// Four lanes' values at `off` from their entries (plain loads: gathers are slower on some CPUs).
struct Lanes {
  std::ptrdiff_t e[4];
  explicit Lanes(const std::int32_t* lanes) noexcept {
    for (int l = 0; l < 4; ++l) e[l] = lanes[l];
  }
};
RIDGELINE_TARGET_AVX2 inline __m256d heights(const float* p, std::ptrdiff_t off, const Lanes& x) noexcept {
  return _mm256_cvtps_pd(_mm_setr_ps(p[x.e[0] + off], p[x.e[1] + off], p[x.e[2] + off], p[x.e[3] + off]));
}

// Size-1 edge diamonds inside the data: the centre's offset from the midpoint of its neighbours
// `o` entries away, packed as pack({err, err, 0}) packs it (up12 of the error).
RIDGELINE_TARGET_AVX2 inline void edges(const float* p, std::uint32_t* out, const std::int32_t* lanes,
                                        std::ptrdiff_t o) noexcept {
  const Lanes idx(lanes);
  const __m256d mid = _mm256_mul_pd(_mm256_set1_pd(0.5), _mm256_add_pd(heights(p, -o, idx), heights(p, o, idx)));
  const __m256d d = _mm256_andnot_pd(_mm256_set1_pd(-0.0), _mm256_sub_pd(heights(p, 0, idx), mid));
  alignas(16) std::uint32_t v[4];
  _mm_store_si128(reinterpret_cast<__m128i*>(v), up12(round_up(d)));
  for (int l = 0; l < 4; ++l) out[lanes[l]] = v[l];
}

// SmallStencil::bound() of four diamonds of one stencil.
// `cv[k][l]`: lane l's child k's packed bound; the four packed bounds into `result`.
RIDGELINE_TARGET_AVX2 inline void stencil(const SmallStencil& st, const RecordConfig& c, const float* p,
                                          const std::int32_t* lanes, const std::uint32_t (*cv)[4],
                                          std::uint32_t* result) noexcept {
  const Lanes idx(lanes);
  const __m256d sign = _mm256_set1_pd(-0.0);
  __m256d err = _mm256_setzero_pd();
  for (const SmallStencil::Tri& q : st.tri) {
    const __m256d ha = heights(p, q.a, idx), hl = heights(p, q.l, idx), hr = heights(p, q.r, idx);
    const __m256d aw = _mm256_set1_pd(q.aw);
    __m256d worst = _mm256_setzero_pd();
    for (std::size_t k = 0; k < q.at.size(); ++k) {
      const __m256d plane = _mm256_add_pd(
          _mm256_add_pd(_mm256_mul_pd(_mm256_set1_pd(q.w[k][0]), ha), _mm256_mul_pd(_mm256_set1_pd(q.w[k][1]), hl)),
          _mm256_mul_pd(_mm256_set1_pd(q.w[k][2]), hr));
      const __m256d d = _mm256_andnot_pd(sign, _mm256_sub_pd(_mm256_mul_pd(heights(p, q.at[k], idx), aw), plane));
      worst = _mm256_max_pd(d, worst);
    }
    err = _mm256_max_pd(_mm256_cvtps_pd(round_up(_mm256_div_pd(worst, aw))), err);
  }
  __m256d morph = err, radius = _mm256_setzero_pd();
  __m128 straddles = _mm_setzero_ps();
  const __m256d hv = heights(p, 0, idx), growth = _mm256_set1_pd(c.growth);
  for (int k = 0; k < st.children; ++k) {
    const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(cv[k]));
    alignas(16) std::uint32_t mc[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(mc), _mm_srli_epi32(v, 24));
    const __m128 ce = down12(_mm_and_si128(v, _mm_set1_epi32(0xfff)));
    const __m128 cr = down12(_mm_and_si128(_mm_srli_epi32(v, 12), _mm_set1_epi32(0xfff)));
    const __m128 cm = _mm_mul_ps(ce, _mm_setr_ps(packed::kRatio[mc[0]], packed::kRatio[mc[1]],
                                                     packed::kRatio[mc[2]], packed::kRatio[mc[3]]));
    const double dx = st.cdx[k] * c.spacing_x, dz = st.cdz[k] * c.spacing_z;
    const __m256d dy = _mm256_sub_pd(heights(p, st.child[k], idx), hv);
    const __m256d dist = _mm256_sqrt_pd(_mm256_add_pd(_mm256_set1_pd(dx * dx + dz * dz), _mm256_mul_pd(dy, dy)));
    err = _mm256_max_pd(_mm256_cvtps_pd(ce), err);
    morph = _mm256_max_pd(_mm256_mul_pd(growth, _mm256_cvtps_pd(cm)), morph);
    radius = _mm256_max_pd(_mm256_add_pd(_mm256_cvtps_pd(cr), dist), radius);
    straddles = _mm_or_ps(straddles, _mm_cmpge_ps(cr, _mm_set1_ps(FLT_MAX)));
  }
  const __m128 e = round_up(err), m = round_up(morph);
  const __m128 far = _mm_or_ps(straddles, narrow(_mm256_cmp_pd(radius, _mm256_set1_pd(FLT_MAX), _CMP_GE_OQ)));
  const __m128 r = _mm_blendv_ps(round_up(radius), _mm_set1_ps(FLT_MAX), far);
  // packed::pack(): the error and radius codes here, the morph code lane by lane.
  alignas(16) std::uint32_t ce[4], cr[4];
  alignas(16) float mm[4];
  _mm_store_si128(reinterpret_cast<__m128i*>(ce), up12(e));
  _mm_store_si128(reinterpret_cast<__m128i*>(cr), up12(r));
  _mm_store_ps(mm, _mm_max_ps(e, m));  // std::max(morph, error)
  for (int l = 0; l < 4; ++l) result[l] = packed::with_morph(ce[l], mm[l]) | (cr[l] << 12);
}

// stencil() of four diamonds of a dense block whose children's bounds are in the block's `out`.
RIDGELINE_TARGET_AVX2 inline void stencil(const SmallStencil& st, const RecordConfig& c, const float* p,
                                          std::uint32_t* out, const std::int32_t* lanes) noexcept {
  std::uint32_t cv[4][4] = {}, result[4];
  for (int k = 0; k < st.children; ++k)
    for (int l = 0; l < 4; ++l) cv[k][l] = out[lanes[l] + st.child[k]];
  stencil(st, c, p, lanes, cv, result);
  for (int l = 0; l < 4; ++l) out[lanes[l]] = result[l];
}

}  // namespace x4
#endif

// The two stencils (orientations) of the diamonds of size 2^t and one kind whose triangles the
// small-triangle table holds (t <= 1, and the t = 2 edges: legs of at most 4 cells along each
// axis), in a dense block of stride n.
struct SmallStencils {
  int t = -1;
  bool square = false;
  std::int64_t n = -1;
  std::vector<SmallStencil> v;
  // Which of the two a diamond of this kind centred at (i, j) takes: the diagonal rule of
  // squares (diamond.h), the hypotenuse's direction of edges.
  int which(std::int64_t i, std::int64_t j) const noexcept {
    const std::int64_t s = std::int64_t{1} << t;
    return square ? int((((i - s) >> (t + 1)) + ((j - s) >> (t + 1))) & 1) : int(((i >> t) & 1) == 0);
  }
};
// This thread's stencils of a kind for blocks of stride n (made again when n changes).
inline const SmallStencils& small_stencils(int t, bool square, std::int64_t n) {
  thread_local SmallStencils cache[8];
  SmallStencils& k = cache[t * 2 + (square ? 1 : 0)];
  if (k.n != n) {
    const std::int64_t s = std::int64_t{1} << t;
    k.t = t, k.square = square, k.n = n;
    k.v.clear();
    k.v.emplace_back(s, square ? s : 2 * s, n);
    k.v.emplace_back(square ? 3 * s : 2 * s, s, n);
  }
  return k;
}

// Diamonds of one kind waiting for their stencil four at a time (AVX2 where the CPU has it, else
// one by one; the same bounds bit for bit), each with its children's packed bounds; `sink(i, j,
// packed)` gets every result.
struct StencilBatches {
  const SmallStencils& st;
  const RecordConfig& c;
  const float* p;
  struct Batch {
    std::int32_t lanes[4];
    std::uint32_t cv[4][4];  // [child][lane]
    std::int64_t i[4], j[4];
    int size = 0;
  };
  Batch b[2];
  StencilBatches(const SmallStencils& s, const RecordConfig& config, const float* heights)
      : st(s), c(config), p(heights) {}
  template <class Sink>
  void add(int which, std::int32_t e, const std::uint32_t* cv, std::int64_t i, std::int64_t j,
           const Sink& sink) {
    Batch& q = b[which];
    q.lanes[q.size] = e, q.i[q.size] = i, q.j[q.size] = j;
    for (int k = 0; k < 4; ++k) q.cv[k][q.size] = cv[k];
    if (++q.size == 4) run(which, sink);
  }
  template <class Sink>
  void flush(const Sink& sink) {
    for (int w = 0; w < 2; ++w)
      if (b[w].size > 0) run(w, sink);
  }

 private:
  template <class Sink>
  void run(int which, const Sink& sink);
};

template <class Sink>
void StencilBatches::run(int which, const Sink& sink) {
  Batch& q = b[which];
  const SmallStencil& sv = st.v[std::size_t(which)];
  std::uint32_t result[4];
#if RIDGELINE_HAS_AVX2_DISPATCH
  if (q.size == 4 && detail::cpu_has_avx2()) {
    x4::stencil(sv, c, p, q.lanes, q.cv, result);
  } else
#endif
  {
    for (int l = 0; l < q.size; ++l) {
      const std::uint32_t cv[4] = {q.cv[0][l], q.cv[1][l], q.cv[2][l], q.cv[3][l]};
      result[l] = sv.bound(c, p, q.lanes[l], cv);
    }
  }
  for (int l = 0; l < q.size; ++l) sink(q.i[l], q.j[l], result[l]);
  q.size = 0;
}

// The bounds of every t <= 1 diamond whose descendants lie in the block of samples
// [i0, i0 + n) x [j0, j0 + n) (or past the padded extent, where they do not exist), finest
// first, packed (packed::pack: what the records hold, a quarter of a DiamondBound's bytes) into
// out[(i - i0) + (j - j0) n]; other entries are left as they are. `h`: the block's heights. The
// level-0 blocks and the bake's t = 1 squares both come from here, so both hold the same values.
// `stencils` false computes every diamond with bound_of() (what the tests compare against).
inline void small_bounds(const RecordConfig& c, const DenseBlock& h, std::vector<std::uint32_t>& out,
                         bool stencils = true) {
  const std::int64_t i0 = h.i0, j0 = h.j0, n = h.n;
  out.resize(std::size_t(n * n));
  auto at = [&](std::int64_t i, std::int64_t j) -> DiamondBound {
    const std::int64_t a = i - i0, b = j - j0;
    if (a < 0 || b < 0 || a >= n || b >= n) return DiamondBound{};
    return packed::unpack(out[std::size_t(a + b * n)]);
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
  // The stencils of this block's stride: t = 0 square (main, other diagonal), t = 1 edge
  // (horizontal, vertical), t = 1 square (main, other).
  struct Stencils {
    std::int64_t n = -1;
    std::vector<SmallStencil> v;
  };
  thread_local Stencils st;
  if (st.n != n) {
    st.v.clear();
    for (const auto& [ri, rj] : {std::pair{1, 1}, std::pair{3, 1}, std::pair{2, 4}, std::pair{4, 2},
                                 std::pair{2, 2}, std::pair{6, 2}})
      st.v.emplace_back(ri, rj, n);
    st.n = n;
  }
  // The fast path: no detail, no holes, and the diamond's triangles inside the data (so none
  // straddles its border) and its top never reached (t <= 1 < patch_log2 - 1).
  const bool fast = stencils && c.L == 0 && c.holes == nullptr && c.patch_log2 > 2;
  auto edge_entry = [&](std::size_t e, std::ptrdiff_t o) {
    const float err = round_up(std::abs(double(h.p[e]) - 0.5 * (double(h.p[e - o]) + double(h.p[e + o]))));
    return packed::pack({err, err, 0.0f});
  };
#if RIDGELINE_HAS_AVX2_DISPATCH
  // Diamonds of the fast path wait in batches of four of one stencil (or, for the size-1 edges,
  // one direction); a kind's diamonds depend only on finer kinds, so a kind's leftovers are
  // computed one by one before the next kind starts.
  const bool wide = fast && detail::cpu_has_avx2() && n * n < (std::int64_t{1} << 31);
  struct Batch {
    std::int32_t lanes[4];
    int size = 0;
  };
  Batch batches[8];
#endif
  for (const Kind& k : kinds) {
    const std::int64_t r = (k.square ? 3 : 2) << k.t;
    for (int v = 0; v < k.count; ++v) {
      auto first = [&](std::int64_t lo, std::int64_t res) {
        return lo + (((res - lo) % k.m) + k.m) % k.m;
      };
      // Only the block's part of the padded extent (a small world's page is mostly past it).
      const std::int64_t jend = std::min(j0 + n - 1, c.pad_j), iend = std::min(i0 + n - 1, c.pad_i);
      for (std::int64_t j = first(std::max<std::int64_t>(j0, 0), k.rj[v]); j <= jend; j += k.m) {
        if (!within(j, r, j0, j0 + n - 1, c.pad_j)) continue;
        for (std::int64_t i = first(std::max<std::int64_t>(i0, 0), k.ri[v]); i <= iend; i += k.m) {
          if (!within(i, r, i0, i0 + n - 1, c.pad_i)) continue;
          // The residues make (i, j) a diamond of this kind (t <= 1 < patch_log2: never a corner).
          const std::size_t e = std::size_t((i - i0) + (j - j0) * n);
          const std::int64_t s = std::int64_t{1} << k.t;
          if (fast && i - s >= std::max<std::int64_t>(0, i0) && j - s >= std::max<std::int64_t>(0, j0) &&
              i + s <= std::min(c.last_i, i0 + n - 1) && j + s <= std::min(c.last_j, j0 + n - 1)) {
            if (k.t == 0 && !k.square) {
              // edge_bound_of() inside the data: the centre's offset from the hypotenuse's
              // midpoint as error and morph bound, no sphere.
              const bool horizontal = (i & 1) != 0;
#if RIDGELINE_HAS_AVX2_DISPATCH
              if (wide) {
                Batch& b = batches[6 + (horizontal ? 0 : 1)];
                b.lanes[b.size++] = std::int32_t(e);
                if (b.size == 4)
                  x4::edges(h.p, out.data(), b.lanes, horizontal ? 1 : std::ptrdiff_t(n)), b.size = 0;
                continue;
              }
#endif
              out[e] = edge_entry(e, horizontal ? 1 : std::ptrdiff_t(n));
            } else {
              // Which stencil: the diagonal rule of squares (diamond.h), the hypotenuse's
              // direction of edges.
              const bool other = k.square ? ((((i - s) >> (k.t + 1)) + ((j - s) >> (k.t + 1))) & 1) != 0
                                          : ((i >> k.t) & 1) == 0;
              const int which = (k.t == 0 ? 0 : (k.square ? 4 : 2)) + (other ? 1 : 0);
#if RIDGELINE_HAS_AVX2_DISPATCH
              if (wide) {
                Batch& b = batches[which];
                b.lanes[b.size++] = std::int32_t(e);
                if (b.size == 4)
                  x4::stencil(st.v[std::size_t(which)], c, h.p, out.data(), b.lanes), b.size = 0;
                continue;
              }
#endif
              out[e] = st.v[std::size_t(which)].bound(c, h.p, out.data(), std::ptrdiff_t(e));
            }
            continue;
          }
          out[e] = packed::pack(bound_of(c, h, i, j, at));
        }
      }
    }
#if RIDGELINE_HAS_AVX2_DISPATCH
    // This kind's leftovers, one by one.
    for (int w = 0; w < 8; ++w) {
      Batch& b = batches[w];
      for (int l = 0; l < b.size; ++l) {
        const std::size_t e = std::size_t(b.lanes[l]);
        out[e] = w >= 6 ? edge_entry(e, w == 6 ? 1 : std::ptrdiff_t(n))
                        : st.v[std::size_t(w)].bound(c, h.p, out.data(), std::ptrdiff_t(e));
      }
      b.size = 0;
    }
#endif
  }
}

}  // namespace ridgeline::roam::bounds
