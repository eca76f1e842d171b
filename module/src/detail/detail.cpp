// The detail layer's core: an interpolating subdivision (midpoint displacement on the 4-8
// lattice, after Fournier, Fussell & Carpenter 1982 and Miller 1986's diamond-square, with the
// 4-point scheme of Dyn, Levin & Gregory 1987 as a clamped smoothing term), in integer
// arithmetic so that tiles and the direct evaluator agree bit for bit on every platform.
#include "ridgeline/detail.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "format.h"
#include "ridgeline/lattice_cell.h"
#include "ridgeline/log.h"

namespace ridgeline {

namespace {

constexpr std::uint64_t kMixA = 0x9E3779B97F4A7C15ull;
constexpr std::uint64_t kMixB = 0xC2B2AE3D27D4EB4Full;

constexpr std::uint64_t fmix64(std::uint64_t h) noexcept {
  h ^= h >> 33;
  h *= 0xff51afd7ed558ccdull;
  h ^= h >> 33;
  h *= 0xc4ceb9fe1a85ec53ull;
  h ^= h >> 33;
  return h;
}

constexpr std::int64_t clamp64(std::int64_t v, std::int64_t lo, std::int64_t hi) noexcept {
  return v < lo ? lo : (v > hi ? hi : v);
}

// Fixed-point bound on |D| (2^30 units = 16384 m) so that sums of a few samples times 9 fit easily
// in int64 and every stored value fits in int32.
constexpr std::int64_t kMaxBoundUnits = std::int64_t{1} << 30;

std::size_t tile_samples() {
  return std::size_t{kDetailTileStride} * kDetailTileStride;
}

}  // namespace

std::size_t DetailTileKeyHash::operator()(const DetailTileKey& k) const noexcept {
  return static_cast<std::size_t>(fmix64(std::uint64_t{k.level} * kMixA ^
                                         std::uint64_t(std::uint32_t(k.tx)) * kMixB ^
                                         (std::uint64_t(std::uint32_t(k.tz)) << 32)));
}

Status validate_detail_params(const DetailParams& p) {
  if (p.levels > kMaxDetailLevels)
    return Error{fmt("detail: levels is %u; need 0..%u", p.levels, kMaxDetailLevels)};
  auto in_range = [](double v, double lo, double hi, const char* what) -> Status {
    if (!std::isfinite(v) || v < lo || v > hi)
      return Error{fmt("detail: %s is %s; need a finite value in [%s, %s]", what, num(v).c_str(),
                       num(lo).c_str(), num(hi).c_str())};
    return {};
  };
  if (auto s = in_range(p.amplitude, 0, 1000, "amplitude (metres)"); !s) return s;
  if (!std::isfinite(p.gain) || p.gain <= 0 || p.gain > 1)
    return Error{fmt("detail: gain is %s; need a finite value in (0, 1]", num(p.gain).c_str())};
  if (auto s = in_range(p.flat_shape, 0, 1, "flat shape"); !s) return s;
  if (auto s = in_range(p.steep_shape, 0, 1, "steep shape"); !s) return s;
  if (auto s = in_range(p.flat_slope, 0, 1e6, "flat slope"); !s) return s;
  if (!std::isfinite(p.steep_slope) || p.steep_slope <= p.flat_slope || p.steep_slope > 1e6)
    return Error{fmt("detail: steep slope is %s; need a finite value in (flat slope %s, 1e6]",
                     num(p.steep_slope).c_str(), num(p.flat_slope).c_str())};
  if (p.blur_radius > 64)
    return Error{fmt("detail: blur radius is %u base samples; need 0..64", p.blur_radius)};
  return {};
}

// ---- the kernel: shape field, noise, one level of the recurrence -------------------------------

struct DetailKernel {
  // Shape at level-l sample (i, j), Q15 (0..32768): the base-resolution field interpolated with
  // smoothstep weights (C1, not piecewise linear), in integers so both paths agree exactly.
  static std::int64_t shape_q15(const DetailField& f, std::uint32_t level, std::int64_t i,
                                std::int64_t j) noexcept {
    const std::int64_t mask = (std::int64_t{1} << level) - 1;
    const std::int64_t k = i >> level, m = j >> level;
    const std::int64_t tu = (i & mask) << (12 - level), tv = (j & mask) << (12 - level);
    const std::int64_t wu = (tu * tu * (3 * 4096 - 2 * tu)) >> 24;
    const std::int64_t wv = (tv * tv * (3 * 4096 - 2 * tv)) >> 24;
    const std::int64_t w1 = f.shape_w_ - 1, h1 = f.shape_h_ - 1;
    const std::int64_t k0 = clamp64(k, 0, w1), k1 = clamp64(k + 1, 0, w1);
    const std::int64_t m0 = clamp64(m, 0, h1), m1 = clamp64(m + 1, 0, h1);
    const std::uint16_t* s = f.shape_.data();
    const std::int64_t s00 = s[k0 + m0 * f.shape_w_], s10 = s[k1 + m0 * f.shape_w_];
    const std::int64_t s01 = s[k0 + m1 * f.shape_w_], s11 = s[k1 + m1 * f.shape_w_];
    const std::int64_t top = s00 * (4096 - wu) + s10 * wu, bottom = s01 * (4096 - wu) + s11 * wu;
    return (top * (4096 - wv) + bottom * wv) >> 24;
  }

  // Octave value in [-32767, 32767]: triangular distribution (sum of two 16-bit uniforms).
  static std::int64_t noise(std::uint64_t level_seed, std::int64_t i, std::int64_t j) noexcept {
    const std::uint64_t h =
        fmix64(level_seed ^ (std::uint64_t(i) * kMixA) ^ (std::uint64_t(j) * kMixB));
    const std::int64_t a = std::int64_t(h & 0xFFFF), b = std::int64_t((h >> 16) & 0xFFFF);
    return (a + b - 65535) / 2;
  }

  static std::uint64_t level_seed(const DetailField& f, std::uint32_t level) noexcept {
    return fmix64(f.seed_mix_ ^ (std::uint64_t{level} * kMixB));
  }

  // One step of the recurrence: child window [ci0, ci0 + cw) x [cj0, cj0 + ch) of level `level`
  // from a parent window (level - 1) starting at (pi0, pj0) that covers
  // [(ci0 >> 1) - 1, ((ci0 + cw - 1) >> 1) + 2] and the same along j. Tiles and the direct
  // evaluator both run exactly this code.
  static void fill_level(const DetailField& f, std::uint32_t level, const std::int32_t* par,
                         std::int64_t pi0, std::int64_t pj0, std::int64_t pstride, std::int64_t ci0,
                         std::int64_t cj0, std::int64_t cw, std::int64_t ch, std::int32_t* out,
                         std::int64_t ostride) noexcept {
    RIDGELINE_ASSERT(level >= 1 && level <= f.params_.levels);
    const std::int64_t amp = f.amp_[level], amp_prev = f.amp_[level - 1];
    const std::uint64_t seed = level_seed(f, level);
    const std::int64_t mask = (std::int64_t{1} << level) - 1, up = 12 - level;
    const std::int64_t sw = f.shape_w_, w1 = f.shape_w_ - 1, h1 = f.shape_h_ - 1;
    for (std::int64_t r = 0; r < ch; ++r) {
      const std::int64_t j = cj0 + r, m = j >> 1;
      const bool jodd = (j & 1) != 0;
      std::int32_t* row = out + r * ostride;
      // Parent rows m - 1 .. m + 2, indexed by the parent column minus pi0.
      const std::int32_t* pr[4];
      for (int d = 0; d < 4; ++d) {
        const std::int64_t rr = std::max(m - 1 + d, pj0);  // rows outside are never read
        pr[d] = par + (rr - pj0) * pstride;
      }
      const std::int32_t* p0 = pr[1];  // row m
      // Shape along this row: the same four products as shape_q15, summed in another order
      // (exact in int64, so the same value).
      const std::int64_t tv = (j & mask) << up, wv = (tv * tv * (3 * 4096 - 2 * tv)) >> 24;
      const std::uint16_t* s0 = f.shape_.data() + clamp64(j >> level, 0, h1) * sw;
      const std::uint16_t* s1 = f.shape_.data() + clamp64((j >> level) + 1, 0, h1) * sw;
      auto new_sample = [&](std::int64_t i, std::int64_t lin2, std::int64_t corr) {
        const std::int64_t tu = (i & mask) << up, wu = (tu * tu * (3 * 4096 - 2 * tu)) >> 24;
        const std::int64_t k0 = clamp64(i >> level, 0, w1), k1 = clamp64((i >> level) + 1, 0, w1);
        const std::int64_t c0 = std::int64_t{s0[k0]} * (4096 - wv) + std::int64_t{s1[k0]} * wv;
        const std::int64_t c1 = std::int64_t{s0[k1]} * (4096 - wv) + std::int64_t{s1[k1]} * wv;
        const std::int64_t s = (c0 * (4096 - wu) + c1 * wu) >> 24;
        const std::int64_t q = (amp * s) >> 15, q_prev = (amp_prev * s) >> 15;
        return static_cast<std::int32_t>((lin2 >> 1) + clamp64(corr, -q_prev, q_prev) +
                                         ((noise(seed, i, j) * q) >> 15));
      };
      if (!jodd) {
        for (std::int64_t c = 0; c < cw; ++c) {
          const std::int64_t i = ci0 + c, x = (i >> 1) - pi0;
          if ((i & 1) == 0) {  // a parent sample keeps its value
            row[c] = p0[x];
            continue;
          }
          // Edge midpoint along x: linear + (4-point cubic - linear), floor.
          const std::int64_t a = p0[x - 1], b = p0[x], cc = p0[x + 1], d = p0[x + 2];
          row[c] = new_sample(i, b + cc, (b + cc - a - d) >> 4);
        }
        continue;
      }
      for (std::int64_t c = 0; c < cw; ++c) {
        const std::int64_t i = ci0 + c, k = i >> 1, x = k - pi0;
        if ((i & 1) == 0) {  // edge midpoint along z
          const std::int64_t a = pr[0][x], b = pr[1][x], cc = pr[2][x], d = pr[3][x];
          row[c] = new_sample(i, b + cc, (b + cc - a - d) >> 4);
          continue;
        }
        // Cell centre: the linear interpolation is the midpoint of the parent cell's diagonal;
        // the cubic one the tensor product of the 4-point weights (-1, 9, 9, -1) / 16.
        const std::int64_t lin2 = cell_has_main_diagonal(k, m)
                                      ? std::int64_t{pr[1][x]} + pr[2][x + 1]
                                      : std::int64_t{pr[1][x + 1]} + pr[2][x];
        std::int64_t h16[4];
        for (int d = 0; d < 4; ++d)
          h16[d] = 9 * (std::int64_t{pr[d][x]} + pr[d][x + 1]) - pr[d][x - 1] - pr[d][x + 2];
        const std::int64_t s256 = 9 * (h16[1] + h16[2]) - h16[0] - h16[3];
        row[c] = new_sample(i, lin2, (s256 - 128 * lin2) >> 8);
      }
    }
  }

  // Parent range needed for a child range [lo, hi].
  static std::int64_t parent_lo(std::int64_t lo) noexcept { return (lo >> 1) - 1; }
  static std::int64_t parent_hi(std::int64_t hi) noexcept { return (hi >> 1) + 2; }

  // Direct evaluation of a window: ranges from the target level down to 0, then the recurrence
  // upwards on small windows. `a` and `b` are scratch buffers of `cap` samples each.
  static void eval_window(const DetailField& f, std::uint32_t level, std::int64_t i0,
                          std::int64_t j0, std::int64_t w, std::int64_t h, std::int32_t* out,
                          std::int64_t ostride, std::int32_t* a, std::int32_t* b,
                          std::size_t cap) noexcept {
    if (level == 0) {
      for (std::int64_t r = 0; r < h; ++r) std::fill_n(out + r * ostride, w, 0);
      return;
    }
    std::int64_t lo_i[kMaxDetailLevels + 1], hi_i[kMaxDetailLevels + 1];
    std::int64_t lo_j[kMaxDetailLevels + 1], hi_j[kMaxDetailLevels + 1];
    lo_i[level] = i0, hi_i[level] = i0 + w - 1, lo_j[level] = j0, hi_j[level] = j0 + h - 1;
    for (std::uint32_t l = level; l >= 1; --l) {
      lo_i[l - 1] = parent_lo(lo_i[l]), hi_i[l - 1] = parent_hi(hi_i[l]);
      lo_j[l - 1] = parent_lo(lo_j[l]), hi_j[l - 1] = parent_hi(hi_j[l]);
    }
    auto width = [&](std::uint32_t l) { return hi_i[l] - lo_i[l] + 1; };
    auto height = [&](std::uint32_t l) { return hi_j[l] - lo_j[l] + 1; };
    (void)cap;  // only read by the asserts
    RIDGELINE_ASSERT(std::size_t(width(0) * height(0)) <= cap);
    std::fill_n(a, width(0) * height(0), 0);  // D_0 = 0
    std::int32_t* par = a;
    std::int32_t* cur = b;
    for (std::uint32_t l = 1; l <= level; ++l) {
      std::int32_t* dst = l == level ? out : cur;
      const std::int64_t dstride = l == level ? ostride : width(l);
      RIDGELINE_ASSERT(l == level || std::size_t(width(l) * height(l)) <= cap);
      fill_level(f, l, par, lo_i[l - 1], lo_j[l - 1], width(l - 1), lo_i[l], lo_j[l], width(l),
                 height(l), dst, dstride);
      std::swap(par, cur);
    }
  }
};

// ---- DetailTile --------------------------------------------------------------------------------

std::int32_t DetailTile::raw(std::int32_t li, std::int32_t lj) const noexcept {
  RIDGELINE_ASSERT(li >= -kDetailTileApron && li <= kDetailTileCells + kDetailTileApron);
  RIDGELINE_ASSERT(lj >= -kDetailTileApron && lj <= kDetailTileCells + kDetailTileApron);
  return samples_[std::size_t(lj + kDetailTileApron) * kDetailTileStride +
                  std::size_t(li + kDetailTileApron)];
}

std::size_t DetailTile::memory_bytes() const noexcept {
  return sizeof(DetailTile) + samples_.capacity() * sizeof(std::int32_t);
}

// ---- DetailField -------------------------------------------------------------------------------

Result<std::shared_ptr<const DetailField>> DetailField::create(const Heightfield& hf,
                                                             const DetailParams& params) {
  if (auto s = validate_detail_params(params); !s) return Error{s.message()};
  std::shared_ptr<DetailField> f(new DetailField());
  f->params_ = params;
  f->spacing_x_ = hf.spacing_x();
  f->spacing_z_ = hf.spacing_z();
  f->origin_x_ = hf.origin_x();
  f->origin_z_ = hf.origin_z();
  f->seed_mix_ = fmix64(params.seed ^ 0x5851F42D4C957F2Dull);

  // Octave amplitudes by repeated multiplication (no pow: its rounding is not specified).
  double a = params.amplitude;
  std::int64_t total = 0;
  for (std::uint32_t l = 1; l <= params.levels; ++l) {
    f->amp_[l] = std::llround(a / kDetailUnit);
    total += f->amp_[l] + f->amp_[l - 1] + 1;
    a *= params.gain;
  }
  if (total > kMaxBoundUnits)
    return Error{
        fmt("detail: amplitude %s m with gain %s over %u levels can reach %s m; need at "
            "most %s m",
            num(params.amplitude).c_str(), num(params.gain).c_str(), params.levels,
            num(double(total) * kDetailUnit).c_str(),
            num(double(kMaxBoundUnits) * kDetailUnit).c_str())};

  // Shape field: slope magnitude (central differences), box-blurred three times, smoothstepped
  // between the flat and steep slopes. Only +, -, *, / and sqrt (correctly rounded in IEEE 754),
  // in a fixed order, so it is the same on every platform; then quantised to Q15.
  const std::int64_t W = hf.width(), H = hf.height();
  f->shape_w_ = W;
  f->shape_h_ = H;
  std::vector<double> slope(std::size_t(W * H)), tmp(std::size_t(W * H));
  for (std::int64_t j = 0; j < H; ++j) {
    for (std::int64_t i = 0; i < W; ++i) {
      const std::int64_t il = std::max<std::int64_t>(i - 1, 0), ir = std::min(i + 1, W - 1);
      const std::int64_t jl = std::max<std::int64_t>(j - 1, 0), jr = std::min(j + 1, H - 1);
      const double gx = (double(hf.local(std::uint32_t(ir), std::uint32_t(j))) -
                         double(hf.local(std::uint32_t(il), std::uint32_t(j)))) /
                        (double(ir - il) * hf.spacing_x());
      const double gz = (double(hf.local(std::uint32_t(i), std::uint32_t(jr))) -
                         double(hf.local(std::uint32_t(i), std::uint32_t(jl)))) /
                        (double(jr - jl) * hf.spacing_z());
      slope[std::size_t(i + j * W)] = std::sqrt(gx * gx + gz * gz);
    }
  }
  const std::int64_t r = params.blur_radius;
  if (r > 0) {
    // One pass along one axis with a running sum, edges clamped (window shrinks at the borders).
    std::vector<double> line;
    auto pass = [&](std::vector<double>& src, std::vector<double>& dst, bool along_x) {
      const std::int64_t n = along_x ? W : H, lines = along_x ? H : W;
      line.assign(std::size_t(n + 1), 0.0);
      for (std::int64_t t = 0; t < lines; ++t) {
        auto at = [&](std::int64_t s) -> std::size_t {
          return along_x ? std::size_t(s + t * W) : std::size_t(t + s * W);
        };
        for (std::int64_t s = 0; s < n; ++s)
          line[std::size_t(s + 1)] = line[std::size_t(s)] + src[at(s)];
        for (std::int64_t s = 0; s < n; ++s) {
          const std::int64_t lo = std::max<std::int64_t>(s - r, 0), hi = std::min(s + r, n - 1);
          dst[at(s)] = (line[std::size_t(hi + 1)] - line[std::size_t(lo)]) / double(hi - lo + 1);
        }
      }
    };
    for (int k = 0; k < 3; ++k) {
      pass(slope, tmp, true);
      pass(tmp, slope, false);
    }
  }
  f->shape_.resize(std::size_t(W * H));
  const double range = params.steep_slope - params.flat_slope;
  for (std::size_t s = 0; s < f->shape_.size(); ++s) {
    double t = (slope[s] - params.flat_slope) / range;
    t = t < 0 ? 0 : (t > 1 ? 1 : t);
    const double shape =
        params.flat_shape + (params.steep_shape - params.flat_shape) * (t * t * (3 - 2 * t));
    f->shape_[s] = static_cast<std::uint16_t>(clamp64(std::llround(shape * 32768.0), 0, 32768));
  }
  // Max pyramid for the bound: level p >= 1 (shape_max_[p - 1]) holds the max over blocks of
  // 2^p x 2^p samples; level 0 is the field itself.
  std::int64_t pw = W, ph = H;
  while (pw > 1 || ph > 1) {
    const std::vector<std::uint16_t>& src =
        f->shape_max_.empty() ? f->shape_ : f->shape_max_.back();
    const std::int64_t nw = (pw + 1) / 2, nh = (ph + 1) / 2;
    std::vector<std::uint16_t> dst(std::size_t(nw * nh));
    for (std::int64_t j = 0; j < nh; ++j)
      for (std::int64_t i = 0; i < nw; ++i) {
        std::uint16_t v = 0;
        for (std::int64_t dj = 0; dj < 2; ++dj)
          for (std::int64_t di = 0; di < 2; ++di) {
            const std::int64_t si = std::min(2 * i + di, pw - 1), sj = std::min(2 * j + dj, ph - 1);
            v = std::max(v, src[std::size_t(si + sj * pw)]);
          }
        dst[std::size_t(i + j * nw)] = v;
      }
    f->shape_max_.push_back(std::move(dst));
    pw = nw;
    ph = nh;
  }
  f->shape_max_all_ = f->shape_max_.back()[0];
  return std::shared_ptr<const DetailField>(std::move(f));
}

std::int32_t DetailField::detail_raw(std::uint32_t level, std::int64_t i,
                                     std::int64_t j) const noexcept {
  RIDGELINE_ASSERT(level <= params_.levels);
  if (level == 0 || level > params_.levels) return 0;  // the fallback after the assert
  // A 1 x 1 window never needs more than 4 x 4 parents and 7 x 7 further up (docs/detail.md).
  std::array<std::int32_t, 64> a, b;
  std::int32_t out = 0;
  DetailKernel::eval_window(*this, level, i, j, 1, 1, &out, 1, a.data(), b.data(), a.size());
  return out;
}

void DetailField::detail_window(std::uint32_t level, std::int64_t i0, std::int64_t j0,
                                std::uint32_t w, std::uint32_t h,
                                std::span<std::int32_t> out) const {
  RIDGELINE_ASSERT(level <= params_.levels);
  RIDGELINE_ASSERT(out.size() >= std::size_t{w} * h);
  if (w == 0 || h == 0 || out.size() < std::size_t{w} * h) return;
  if (level > params_.levels) level = 0;  // the fallback after the assert: zeros
  // The largest window is the one at level 0 or near the top; size scratch for the worst.
  std::int64_t lo_i = i0, hi_i = i0 + w - 1, lo_j = j0, hi_j = j0 + h - 1;
  std::size_t cap = std::size_t{w} * h;
  for (std::uint32_t l = level; l >= 1; --l) {
    lo_i = DetailKernel::parent_lo(lo_i), hi_i = DetailKernel::parent_hi(hi_i);
    lo_j = DetailKernel::parent_lo(lo_j), hi_j = DetailKernel::parent_hi(hi_j);
    cap = std::max(cap, std::size_t((hi_i - lo_i + 1) * (hi_j - lo_j + 1)));
  }
  std::vector<std::int32_t> a(cap), b(cap);
  DetailKernel::eval_window(*this, level, i0, j0, w, h, out.data(), w, a.data(), b.data(), cap);
}

double DetailField::lattice_x(std::uint32_t level, std::int64_t i) const noexcept {
  return origin_x_ + std::ldexp(double(i) * spacing_x_, -int(level));
}

double DetailField::lattice_z(std::uint32_t level, std::int64_t j) const noexcept {
  return origin_z_ + std::ldexp(double(j) * spacing_z_, -int(level));
}

double DetailField::shape(std::uint32_t level, std::int64_t i, std::int64_t j) const noexcept {
  RIDGELINE_ASSERT(level <= kMaxDetailLevels);
  level = std::min(level, kMaxDetailLevels);
  return double(DetailKernel::shape_q15(*this, level, i, j)) / 32768.0;
}

std::size_t DetailField::memory_bytes() const noexcept {
  std::size_t bytes = sizeof(DetailField);
  for (const auto& v : shape_max_) bytes += v.capacity() * sizeof(std::uint16_t);
  return bytes + shape_.capacity() * sizeof(std::uint16_t);
}

std::shared_ptr<const DetailTile> DetailField::make_tile(const DetailTileKey& key,
                                                         const DetailTile* parent) const {
  RIDGELINE_ASSERT(key.level >= 1 && key.level <= params_.levels);
  RIDGELINE_ASSERT((key.level == 1) == (parent == nullptr));
  RIDGELINE_ASSERT(parent == nullptr || parent->key() == key.parent());
  if (key.level < 1 || key.level > params_.levels || (key.level == 1) != (parent == nullptr) ||
      (parent && !(parent->key() == key.parent())))
    return nullptr;  // the fallback after the asserts
  std::shared_ptr<DetailTile> tile(new DetailTile());
  tile->key_ = key;
  tile->samples_.resize(tile_samples());
  const std::int64_t ci0 = std::int64_t{key.tx} * kDetailTileCells - kDetailTileApron;
  const std::int64_t cj0 = std::int64_t{key.tz} * kDetailTileCells - kDetailTileApron;
  const std::int64_t n = kDetailTileStride;
  if (parent) {
    const std::int64_t pi0 = parent->first_i() - kDetailTileApron;
    const std::int64_t pj0 = parent->first_j() - kDetailTileApron;
    // The apron of 3 is what makes the parent tile alone enough (docs/detail.md).
    RIDGELINE_ASSERT(DetailKernel::parent_lo(ci0) >= pi0 &&
                     DetailKernel::parent_hi(ci0 + n - 1) <= pi0 + n - 1);
    RIDGELINE_ASSERT(DetailKernel::parent_lo(cj0) >= pj0 &&
                     DetailKernel::parent_hi(cj0 + n - 1) <= pj0 + n - 1);
    DetailKernel::fill_level(*this, key.level, parent->samples_.data(), pi0, pj0, n, ci0, cj0, n, n,
                             tile->samples_.data(), n);
  } else {
    // Level 1 from the zero base detail.
    const std::int64_t pi0 = DetailKernel::parent_lo(ci0), pj0 = DetailKernel::parent_lo(cj0);
    const std::int64_t pn = DetailKernel::parent_hi(ci0 + n - 1) - pi0 + 1;
    const std::vector<std::int32_t> zeros(std::size_t(pn * pn), 0);
    DetailKernel::fill_level(*this, 1, zeros.data(), pi0, pj0, pn, ci0, cj0, n, n,
                             tile->samples_.data(), n);
  }
  std::int32_t lo = tile->raw(0, 0), hi = lo;
  for (std::int32_t lj = 0; lj <= kDetailTileCells; ++lj)
    for (std::int32_t li = 0; li <= kDetailTileCells; ++li) {
      const std::int32_t v = tile->raw(li, lj);
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  tile->min_ = lo;
  tile->max_ = hi;
  tile->levels_ = params_.levels;
  if (key.level == params_.levels) measure_increments(*tile);
  return tile;
}

// For a finest tile: the largest |D_l - P_{l-1}| at its new level-l vertices, for every level l
// whose cells fit the tile (edge midpoints: the mean of the edge's ends; cell centres: the mean of
// the diagonal's ends, by the diagonal rule of the coarser lattice).
void DetailField::measure_increments(DetailTile& tile) const {
  const int L = int(params_.levels);
  const std::int64_t gx = tile.first_i(), gz = tile.first_j();
  for (int l = 0; l <= L; ++l) tile.increment_max_[l] = -1;
  for (int l = L; l >= 1; --l) {
    const std::int32_t s = std::int32_t{1} << (L - l);  // level-l spacing, finest cells
    if (2 * s > kDetailTileCells) break;                 // level-(l-1) cells exceed the tile
    std::int64_t worst = 0;                              // in half units
    for (std::int32_t lj = 0; lj <= kDetailTileCells; lj += s) {
      const bool odd_j = (lj / s) & 1;
      for (std::int32_t li = (odd_j ? 0 : s); li <= kDetailTileCells; li += odd_j ? s : 2 * s) {
        const bool odd_i = (li / s) & 1;
        std::int64_t a, b;
        if (odd_i && !odd_j) {
          a = tile.raw(li - s, lj), b = tile.raw(li + s, lj);
        } else if (!odd_i && odd_j) {
          a = tile.raw(li, lj - s), b = tile.raw(li, lj + s);
        } else {
          // A level-(l-1) cell centre: that cell's diagonal, in global level-(l-1) indices.
          const std::int64_t ci = (gx + li - s) >> (L - l + 1), cj = (gz + lj - s) >> (L - l + 1);
          if (cell_has_main_diagonal(ci, cj))
            a = tile.raw(li - s, lj - s), b = tile.raw(li + s, lj + s);
          else
            a = tile.raw(li + s, lj - s), b = tile.raw(li - s, lj + s);
        }
        worst = std::max<std::int64_t>(worst, std::abs(2 * std::int64_t(tile.raw(li, lj)) - a - b));
      }
    }
    tile.increment_max_[l] = static_cast<std::int32_t>((worst + 1) / 2);  // rounded up
  }
}

double DetailTile::measured_contribution(std::uint32_t from_level) const noexcept {
  if (key_.level != levels_ || from_level == 0) return INFINITY;
  std::int64_t sum = 0;
  for (std::uint32_t l = from_level; l <= levels_; ++l) {
    if (increment_max_[l] < 0) return INFINITY;
    sum += increment_max_[l];
  }
  return double(sum) * kDetailUnit;
}

std::shared_ptr<const DetailTile> DetailField::make_tile_chain(const DetailTileKey& key) const {
  if (key.level <= 1) return make_tile(key, nullptr);
  const std::shared_ptr<const DetailTile> parent = make_tile_chain(key.parent());
  return make_tile(key, parent.get());
}

std::uint32_t DetailField::shape_max_q15(std::uint32_t level, std::int64_t i0, std::int64_t j0,
                                         std::int64_t i1, std::int64_t j1) const noexcept {
  if (i0 > i1 || j0 > j1 || level > kMaxDetailLevels) return 0;
  // Base samples whose shape can reach a finest sample in the rectangle, or a corner of the
  // level-m triangle around one (one base sample of margin covers both).
  const std::int64_t w1 = shape_w_ - 1, h1 = shape_h_ - 1;
  std::int64_t a0 = clamp64((i0 >> level) - 1, 0, w1), a1 = clamp64((i1 >> level) + 2, 0, w1);
  std::int64_t b0 = clamp64((j0 >> level) - 1, 0, h1), b1 = clamp64((j1 >> level) + 2, 0, h1);
  std::size_t p = 0;
  while (p < shape_max_.size() && ((a1 >> p) - (a0 >> p) > 1 || (b1 >> p) - (b0 >> p) > 1)) ++p;
  const std::vector<std::uint16_t>& blocks = p == 0 ? shape_ : shape_max_[p - 1];
  const std::int64_t pw = ((shape_w_ - 1) >> p) + 1;
  std::uint16_t smax = 0;
  for (std::int64_t bj = b0 >> p; bj <= (b1 >> p); ++bj)
    for (std::int64_t bi = a0 >> p; bi <= (a1 >> p); ++bi)
      smax = std::max(smax, blocks[std::size_t(bi + bj * pw)]);
  return smax;
}

std::int64_t DetailField::amplitude_sum(std::uint32_t from_level) const noexcept {
  std::int64_t amps = 0;
  for (std::uint32_t m = std::max(from_level, 1u); m <= params_.levels; ++m)
    amps += amp_[m] + amp_[m - 1];
  return amps;
}

std::int64_t DetailField::rounding_terms(std::uint32_t from_level) const noexcept {
  const std::uint32_t from = std::max(from_level, 1u);
  return from > params_.levels ? 0 : std::int64_t(params_.levels - from + 1);
}

double DetailField::contribution_bound(std::uint32_t from_level, std::uint32_t level,
                                       std::int64_t i0, std::int64_t j0, std::int64_t i1,
                                       std::int64_t j1) const noexcept {
  if (i0 > i1 || j0 > j1 || level > kMaxDetailLevels) return 0;
  const double smax = shape_max_q15(level, i0, j0, i1, j1);
  return (double(amplitude_sum(from_level)) * smax / 32768.0 +
          double(rounding_terms(from_level))) *
         kDetailUnit;
}

double DetailField::contribution_bound(std::uint32_t from_level) const noexcept {
  return (double(amplitude_sum(from_level)) * double(shape_max_all_) / 32768.0 +
          double(rounding_terms(from_level))) *
         kDetailUnit;
}

}  // namespace ridgeline
