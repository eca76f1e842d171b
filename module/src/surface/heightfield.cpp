// Heightfield validation, no-data filling and the built-in default terrain.
#include "ridgeline/heightfield.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <deque>
#include <limits>
#include <sstream>
#include <utility>

#include "format.h"

namespace ridgeline {

Status validate_heightfield_desc(const HeightfieldDesc& d) {
  const std::string& n = d.name;
  if (d.width < 2 || d.height < 2)
    return Error{fmt("%s: %u x %u samples; need at least 2 x 2", n.c_str(), d.width, d.height)};
  const std::uint64_t count = std::uint64_t{d.width} * d.height;
  if (count > d.max_samples)
    return Error{fmt("%s: %u x %u = %llu samples exceeds the limit of %llu samples "
                     "(HeightfieldDesc::max_samples)",
                     n.c_str(), d.width, d.height, static_cast<unsigned long long>(count),
                     static_cast<unsigned long long>(d.max_samples))};
  auto positive = [&](double v, const char* what) -> Status {
    if (!std::isfinite(v) || v <= 0.0)
      return Error{fmt("%s: %s is %s; need a finite value > 0", n.c_str(), what, num(v).c_str())};
    return {};
  };
  auto finite = [&](double v, const char* what) -> Status {
    if (!std::isfinite(v))
      return Error{fmt("%s: %s is %s; need a finite value", n.c_str(), what, num(v).c_str())};
    return {};
  };
  if (auto s = positive(d.spacing_x, "spacing x"); !s) return s;
  if (auto s = positive(d.spacing_z, "spacing z"); !s) return s;
  for (const auto& [v, what] : {std::pair{d.spacing_x, "x"}, std::pair{d.spacing_z, "z"}})
    if (v < kMinSpacing || v > kMaxSpacing)
      return Error{fmt("%s: spacing %s is %s m; need %s .. %s m (HeightfieldDesc::spacing_%s)",
                       n.c_str(), what, num(v).c_str(), num(kMinSpacing).c_str(),
                       num(kMaxSpacing).c_str(), what)};
  if (auto s = positive(d.height_scale, "height scale"); !s) return s;
  if (auto s = finite(d.height_offset, "height offset"); !s) return s;
  if (auto s = finite(d.origin_x, "origin x"); !s) return s;
  if (auto s = finite(d.origin_z, "origin z"); !s) return s;
  if (d.fill == FillPolicy::kConstant)
    if (auto s = finite(d.fill_constant, "fill constant"); !s) return s;
  if (d.nodata && std::isnan(*d.nodata))
    return Error{fmt("%s: no-data value is NaN; non-finite samples are always treated as missing",
                     n.c_str())};
  // Keep world coordinates representable: the far corner must stay finite and the spacing must
  // not vanish next to the origin in double precision.
  const double far_x = d.origin_x + (d.width - 1) * d.spacing_x;
  const double far_z = d.origin_z + (d.height - 1) * d.spacing_z;
  if (!std::isfinite(far_x) || !std::isfinite(far_z) || std::abs(far_x) > 1e12 ||
      std::abs(far_z) > 1e12)
    return Error{fmt("%s: terrain extends to (%s, %s) m; world coordinates must stay within 1e12 m",
                     n.c_str(), num(far_x).c_str(), num(far_z).c_str())};
  return {};
}

Result<Heightfield> Heightfield::create(const HeightfieldDesc& d, std::span<const float> values,
                                        std::span<const std::uint8_t> materials) {
  if (auto s = validate_heightfield_desc(d); !s) return Error{s.message()};
  const std::size_t count = std::size_t{d.width} * d.height;
  if (values.size() != count)
    return Error{fmt("%s: %zu sample values given for %u x %u samples", d.name.c_str(),
                     values.size(), d.width, d.height)};
  const std::size_t cells = std::size_t{d.width - 1} * (d.height - 1);
  if (!materials.empty() && materials.size() != cells && materials.size() != count)
    return Error{fmt("%s: %zu material ids given; need %zu (one per cell) or %zu (one per sample)",
                     d.name.c_str(), materials.size(), cells, count)};

  auto bad = [&](float v) { return !std::isfinite(v) || (d.nodata && double(v) == *d.nodata); };

  Heightfield hf;
  hf.width_ = d.width;
  hf.height_ = d.height;
  hf.spacing_x_ = d.spacing_x;
  hf.spacing_z_ = d.spacing_z;
  hf.origin_x_ = d.origin_x;
  hf.origin_z_ = d.origin_z;
  hf.height_offset_ = d.height_offset;
  hf.height_scale_ = d.height_scale;
  hf.heights_.resize(count);

  std::vector<std::uint8_t> missing;
  std::size_t first_bad = count;
  for (std::size_t k = 0; k < count; ++k) {
    if (bad(values[k])) {
      if (first_bad == count) first_bad = k;
      if (missing.empty()) missing.assign(count, 0);
      missing[k] = 1;
    }
  }
  if (first_bad != count) {
    if (d.fill == FillPolicy::kRefuse) {
      const float v = values[first_bad];
      return Error{
          fmt("%s: sample (%zu, %zu) is %s%s; refuse (choose a fill policy to replace "
              "missing samples)",
              d.name.c_str(), first_bad % d.width, first_bad / d.width, num(v).c_str(),
              std::isfinite(v) ? " (the no-data value)" : "")};
    }
  }

  // Scale, then fill. Values are scaled in double and stored as float relative to the offset.
  const float fill_scaled = static_cast<float>(d.height_scale * d.fill_constant);
  if (!missing.empty() && d.fill == FillPolicy::kConstant &&
      !(std::abs(double(fill_scaled)) <= kMaxRelativeHeight))
    return Error{
        fmt("%s: fill constant %s gives a height of %s m relative to the offset, beyond "
            "the +-%.0f m limit",
            d.name.c_str(), num(d.fill_constant).c_str(),
            num(d.height_scale * d.fill_constant).c_str(), kMaxRelativeHeight)};
  for (std::size_t k = 0; k < count; ++k) {
    if (!missing.empty() && missing[k]) {
      hf.heights_[k] = fill_scaled;
      continue;
    }
    const double h = d.height_scale * double(values[k]);
    if (!std::isfinite(static_cast<float>(h)))
      return Error{fmt("%s: sample (%zu, %zu) = %s times height scale %s overflows float",
                       d.name.c_str(), k % d.width, k / d.width, num(values[k]).c_str(),
                       num(d.height_scale).c_str())};
    if (std::abs(h) > kMaxRelativeHeight)
      return Error{
          fmt("%s: sample (%zu, %zu) = %s gives a height of %s m relative to the offset, "
              "beyond the +-%.0f m limit (if it marks missing data, give it as the "
              "no-data value with a fill policy)",
              d.name.c_str(), k % d.width, k / d.width, detail::numf(values[k]).c_str(),
              num(h).c_str(), kMaxRelativeHeight)};
    hf.heights_[k] = static_cast<float>(h);
  }
  if (!missing.empty()) {
    std::size_t filled = 0;
    for (auto m : missing) filled += m;
    hf.filled_samples_ = filled;
    if (filled == count)
      return Error{fmt("%s: every sample is missing; nothing to fill from", d.name.c_str())};
    if (d.fill == FillPolicy::kHole)
      // A cell is ground only where its four corners are measured.
      for (std::size_t j = 0; j + 1 < d.height; ++j)
        for (std::size_t i = 0; i + 1 < d.width; ++i) {
          const std::size_t k = i + j * d.width;
          if (missing[k] | missing[k + 1] | missing[k + d.width] | missing[k + d.width + 1])
            hf.hole_cells_.push_back(i + j * (d.width - 1));
        }
    if (d.fill == FillPolicy::kNearest || d.fill == FillPolicy::kHole) {
      // Multi-source breadth-first search from every valid sample: each missing sample takes the
      // height of the valid sample that reached it first (4-neighbour distance).
      std::deque<std::size_t> queue;
      for (std::size_t k = 0; k < count; ++k)
        if (!missing[k]) queue.push_back(k);
      while (!queue.empty()) {
        const std::size_t k = queue.front();
        queue.pop_front();
        const std::size_t i = k % d.width, j = k / d.width;
        auto visit = [&](std::size_t nk) {
          if (missing[nk]) {
            missing[nk] = 0;
            hf.heights_[nk] = hf.heights_[k];
            queue.push_back(nk);
          }
        };
        if (i > 0) visit(k - 1);
        if (i + 1 < d.width) visit(k + 1);
        if (j > 0) visit(k - d.width);
        if (j + 1 < d.height) visit(k + d.width);
      }
    }
  }

  auto [lo, hi] = std::minmax_element(hf.heights_.begin(), hf.heights_.end());
  hf.min_local_ = *lo;
  hf.max_local_ = *hi;

  if (!materials.empty()) {
    hf.materials_.resize(cells);
    if (materials.size() == cells) {
      std::memcpy(hf.materials_.data(), materials.data(), cells);
    } else {
      for (std::uint32_t j = 0; j + 1 < d.height; ++j)
        for (std::uint32_t i = 0; i + 1 < d.width; ++i)
          hf.materials_[i + std::size_t{j} * (d.width - 1)] =
              materials[i + std::size_t{j} * d.width];
    }
  }
  return hf;
}

float Heightfield::local_clamped(std::int64_t i, std::int64_t j) const noexcept {
  i = std::clamp<std::int64_t>(i, 0, width_ - 1);
  j = std::clamp<std::int64_t>(j, 0, height_ - 1);
  return local(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j));
}

std::uint64_t Heightfield::content_hash() const noexcept {
  std::uint64_t h = 1469598103934665603ull;
  auto mix = [&](const void* p, std::size_t n) {
    const auto* b = static_cast<const unsigned char*>(p);
    for (std::size_t k = 0; k < n; ++k) {
      h ^= b[k];
      h *= 1099511628211ull;
    }
  };
  mix(&width_, sizeof width_);
  mix(&height_, sizeof height_);
  for (double v : {spacing_x_, spacing_z_, origin_x_, origin_z_, height_offset_, height_scale_})
    mix(&v, sizeof v);
  mix(heights_.data(), heights_.size() * sizeof(float));
  mix(materials_.data(), materials_.size());
  return h;
}

// ---------------------------------------------------------------------------------------------
// Default terrain: value-noise fBm with a ridged component. Integer hashing only, so the bytes do
// not depend on the platform's libm beyond IEEE float arithmetic.

namespace {

float hash01(std::int32_t x, std::int32_t y, std::uint32_t seed) {
  std::uint32_t h = static_cast<std::uint32_t>(x) * 374761393u +
                    static_cast<std::uint32_t>(y) * 668265263u + seed * 2246822519u;
  h = (h ^ (h >> 13)) * 1274126177u;
  h ^= h >> 16;
  return static_cast<float>(h & 0xffffffu) / float(0xffffff);
}

double value_noise(double x, double y, std::uint32_t seed) {
  const double fx = std::floor(x), fy = std::floor(y);
  const auto ix = static_cast<std::int32_t>(fx), iy = static_cast<std::int32_t>(fy);
  const double tx = x - fx, ty = y - fy;
  const double sx = tx * tx * (3 - 2 * tx), sy = ty * ty * (3 - 2 * ty);
  const double a = hash01(ix, iy, seed), b = hash01(ix + 1, iy, seed);
  const double c = hash01(ix, iy + 1, seed), e = hash01(ix + 1, iy + 1, seed);
  const double top = a + (b - a) * sx, bottom = c + (e - c) * sx;
  return top + (bottom - top) * sy;
}

}  // namespace

Result<Heightfield> make_default_heightfield(const DefaultTerrainParams& p) {
  HeightfieldDesc d;
  d.width = d.height = p.size;
  d.spacing_x = d.spacing_z = p.spacing;
  d.name = "default terrain";
  if (auto s = validate_heightfield_desc(d); !s) return Error{s.message()};
  const std::size_t n = p.size;
  std::vector<float> values(n * n);
  for (std::size_t j = 0; j < n; ++j) {
    for (std::size_t i = 0; i < n; ++i) {
      // Features scaled to a 1025-sample grid so other sizes show the same landscape, stretched.
      const double u = double(i) * 1024.0 / double(n - 1), v = double(j) * 1024.0 / double(n - 1);
      double h = 0, amp = 120, f = 1.0 / 256;
      for (std::uint32_t o = 0; o < 7; ++o) {
        h += amp * value_noise(u * f, v * f, p.seed + o);
        f *= 2;
        amp *= 0.5;
      }
      // Ridges: folded noise adds sharp crests that stress the error bounds.
      const double r = 1.0 - std::abs(2.0 * value_noise(u / 128.0, v / 128.0, p.seed + 100) - 1.0);
      h += 60.0 * r * r;
      values[i + j * n] = static_cast<float>(h - 40.0);
    }
  }
  // The material map, per cell, from slope, height and two noise fields (ids listed in
  // heightfield.h): rock on cliffs, gravel (scree) on steep slopes below them, snow on the
  // highest ground, sand in the lowest valleys, mud in patches of flat low ground, grass
  // elsewhere. Heights are compared as fractions of the terrain's range so that other sizes and
  // seeds get the same mix.
  float lo = values[0], hi = values[0];
  for (float v : values) lo = std::min(lo, v), hi = std::max(hi, v);
  const double range = std::max(1.0, double(hi) - double(lo));
  std::vector<std::uint8_t> mats((n - 1) * (n - 1));
  for (std::size_t j = 0; j + 1 < n; ++j) {
    for (std::size_t i = 0; i + 1 < n; ++i) {
      const float h00 = values[i + j * n], h10 = values[i + 1 + j * n];
      const float h01 = values[i + (j + 1) * n];
      const double slope = std::max(std::abs(h10 - h00), std::abs(h01 - h00)) / p.spacing;
      const double t = (double(h00) - lo) / range;  // 0 lowest .. 1 highest
      const double u = double(i) * 1024.0 / double(n - 1), v = double(j) * 1024.0 / double(n - 1);
      // Patchiness: low-frequency noise (about 60 m features) for mud, and a little
      // higher-frequency noise to fray the borders of sand and snow.
      const double patch = value_noise(u / 30.0, v / 30.0, p.seed + 200);
      const double fray = 0.04 * (value_noise(u / 6.0, v / 6.0, p.seed + 300) - 0.5);
      std::uint8_t m = 0;                                             // grass
      if (t + fray < 0.12) m = 2;                                     // sand
      if (t + fray > 0.80) m = 3;                                     // snow
      if (m == 0 && slope < 0.15 && t < 0.45 && patch > 0.66) m = 4;  // mud
      if (slope > 0.55) m = 5;                                        // gravel
      if (slope > 0.8) m = 1;                                         // rock
      mats[i + j * (n - 1)] = m;
    }
  }
  return Heightfield::create(d, values, mats);
}

}  // namespace ridgeline
