// The shared synthetic scenes (scenes.h). The noise field follows the definition the peers'
// figures were measured on, operation for operation, so that its samples are identical.
#include "ridgeline/scenes.h"

#include <algorithm>
#include <cmath>

namespace ridgeline::scenes {

Result<Heightfield> field(const FieldDesc& desc, const std::function<double(int, int)>& height,
                          const std::vector<std::uint8_t>& materials) {
  HeightfieldDesc d;
  d.width = desc.width;
  d.height = desc.height;
  d.spacing_x = desc.spacing_x;
  d.spacing_z = desc.spacing_z;
  d.origin_x = desc.origin_x;
  d.origin_z = desc.origin_z;
  d.height_offset = desc.height_offset;
  d.name = desc.name;
  std::vector<float> v(std::size_t(desc.width) * desc.height);
  for (std::uint32_t j = 0; j < desc.height; ++j)
    for (std::uint32_t i = 0; i < desc.width; ++i)
      v[i + std::size_t(j) * desc.width] = static_cast<float>(height(int(i), int(j)));
  return Heightfield::create(d, v, materials);
}

double shape_height(Shape shape, std::uint32_t n, int i, int j) {
  if (shape == Shape::kFlat) return 0.0;
  const double x = double(i) / (n - 1), z = double(j) / (n - 1);
  const double hills = 60 * std::sin(6.1 * x) * std::cos(4.3 * z) + 25 * std::sin(23 * x + 17 * z) +
                       8 * std::sin(71 * x) * std::sin(53 * z) + 100;
  if (shape == Shape::kCliff) return (std::uint32_t(i) >= n / 2 ? 1000.0 : 0.0) + 0.05 * hills;
  return hills;
}

Result<Heightfield> shaped(Shape shape, std::uint32_t n, double spacing, double origin,
                           const std::string& name) {
  FieldDesc d;
  d.width = d.height = n;
  d.spacing_x = d.spacing_z = spacing;
  d.origin_x = d.origin_z = origin;
  d.name = name;
  return field(d, [&](int i, int j) { return shape_height(shape, n, i, j); });
}

Result<Heightfield> flight_world() {
  DefaultTerrainParams p;
  p.size = 3126;
  auto base = make_default_heightfield(p);
  if (!base) return base.error();
  std::vector<std::uint8_t> mats;
  mats.reserve(std::size_t{p.size - 1} * (p.size - 1));
  for (std::uint32_t j = 0; j + 1 < p.size; ++j)
    for (std::uint32_t i = 0; i + 1 < p.size; ++i) mats.push_back(base->material(i, j));
  const Heightfield& b = *base;
  return field(
      {.width = p.size,
       .height = p.size,
       .spacing_x = 32,
       .spacing_z = 32,
       .name = "default terrain"},
      [&](int i, int j) { return 4.0 * double(b.local(std::uint32_t(i), std::uint32_t(j))); },
      mats);
}

namespace {
constexpr std::uint64_t kMask = 0xffffffffu;

// A hash of a lattice point and an octave to [0, 1], in 32-bit arithmetic.
double hash2(std::int64_t x, std::int64_t y, std::int64_t o) {
  std::uint64_t h = (std::uint64_t(x) * 374761393u + std::uint64_t(y) * 668265263u +
                     std::uint64_t(o) * 2246822519u) &
                    kMask;
  h = ((h ^ (h >> 13)) * 1274126177u) & kMask;
  return double((h ^ (h >> 16)) & 0xffffff) / double(0xffffff);
}

// Value noise of one octave: smoothstep-interpolated hashes of the lattice at frequency f.
double value_noise(int x, int y, int o, double f) {
  const double fx = x * f, fy = y * f;
  const auto ix = static_cast<std::int64_t>(std::floor(fx)),
             iy = static_cast<std::int64_t>(std::floor(fy));
  const double tx = fx - double(ix), ty = fy - double(iy);
  const double sx = tx * tx * (3 - 2 * tx), sy = ty * ty * (3 - 2 * ty);
  const double a = hash2(ix, iy, o), b = hash2(ix + 1, iy, o);
  const double c = hash2(ix, iy + 1, o), d = hash2(ix + 1, iy + 1, o);
  const double top = a + (b - a) * sx;
  return top + ((c + (d - c) * sx) - top) * sy;
}
}  // namespace

double noise_height(int x, int y) {
  double h = 0.0, f = 1.0 / 256, amp = 160.0;
  for (int o = 0; o < 8; ++o) {
    h += amp * value_noise(x, y, o, f);
    f *= 2;
    amp *= 0.5;
  }
  return h;
}

std::vector<std::uint16_t> noise_samples() {
  std::vector<std::uint16_t> v(std::size_t(kNoiseSize) * kNoiseSize);
  for (std::uint32_t y = 0; y < kNoiseSize; ++y)
    for (std::uint32_t x = 0; x < kNoiseSize; ++x)  // nearbyint: ties to even, as the definition
      v[x + std::size_t(y) * kNoiseSize] = static_cast<std::uint16_t>(
          std::nearbyint(noise_height(int(x), int(y)) / kNoiseHeightScale));
  return v;
}

Result<Heightfield> noise_field() {
  HeightfieldDesc d;
  d.width = d.height = kNoiseSize;
  d.spacing_x = d.spacing_z = 1.0;
  d.height_scale = kNoiseHeightScale;
  d.name = "noise1025";
  const std::vector<std::uint16_t> s = noise_samples();
  std::vector<float> v(s.begin(), s.end());
  return Heightfield::create(d, v);
}

std::vector<Camera> noise_circle() {
  double hi = 0.0;
  for (std::uint32_t y = 0; y < kNoiseSize; ++y)
    for (std::uint32_t x = 0; x < kNoiseSize; ++x) hi = std::max(hi, noise_height(int(x), int(y)));
  hi = std::nearbyint(hi / kNoiseHeightScale) * kNoiseHeightScale;
  constexpr double kPi = 3.141592653589793;
  std::vector<Camera> frames;
  for (int k = 0; k < 360; ++k) {
    const double a = 2 * kPi * k / 360;
    const double ex = 512 + 300 * std::cos(a), ez = 512 + 300 * std::sin(a);
    const double hx = -std::sin(a), hz = std::cos(a), p = -0.35;
    Camera c;
    c.eye = {ex, hi + 25, ez};
    c.target = {ex + std::cos(p) * hx, hi + 25 + std::sin(p), ez + std::cos(p) * hz};
    c.up = {0, 1, 0};
    c.fov_y_deg = 90;
    c.viewport = {1024, 1024};
    c.near_m = 0.5;
    c.far_m = 50000;
    frames.push_back(c);
  }
  return frames;
}

// ---- generated worlds ------------------------------------------------------------------------

namespace {

// A value in [-1, 1) per lattice point of octave o.
inline float lattice_value(std::int64_t x, std::int64_t y, std::uint32_t seed) {
  std::uint64_t h = std::uint64_t(x) * 0x9e3779b97f4a7c15ull ^ std::uint64_t(y) * 0xc2b2ae3d27d4eb4full ^
                    std::uint64_t(seed) * 0x165667b19e3779f9ull;
  h ^= h >> 29;
  h *= 0xbf58476d1ce4e5b9ull;
  h ^= h >> 32;
  return float(std::int32_t(std::uint32_t(h) >> 8) - (1 << 23)) * (1.0f / float(1 << 23));
}

}  // namespace

void generated_world_rows(std::uint32_t width, std::uint32_t j0, std::uint32_t j1,
                          std::uint32_t seed, std::uint16_t* out) {
  constexpr int kOctaves = 12;
  std::vector<float> row(width);
  for (std::uint32_t j = j0; j < j1; ++j) {
    std::fill(row.begin(), row.end(), 600.0f);
    float amp = 550.0f;
    for (int o = 0; o < kOctaves; ++o) {
      const int shift = 13 - o;  // wavelength 2^shift samples
      const std::int64_t lj = std::int64_t(j) >> shift;
      const float fy = float(j & ((1u << shift) - 1)) / float(1u << shift);
      const float ty = fy * fy * (3.0f - 2.0f * fy);
      const std::uint32_t s = seed * 131u + std::uint32_t(o);
      // The two lattice rows around j blended at j, one value per lattice column, then along
      // the row.
      const std::int64_t cols = (std::int64_t(width) >> shift) + 2;
      std::vector<float> col(static_cast<std::size_t>(cols));
      for (std::int64_t c = 0; c < cols; ++c) {
        const float v0 = lattice_value(c, lj, s), v1 = lattice_value(c, lj + 1, s);
        col[std::size_t(c)] = v0 + (v1 - v0) * ty;
      }
      for (std::uint32_t i = 0; i < width; ++i) {
        const std::int64_t c = std::int64_t(i) >> shift;
        const float fx = float(i & ((1u << shift) - 1)) / float(1u << shift);
        const float tx = fx * fx * (3.0f - 2.0f * fx);
        const float v = col[std::size_t(c)] + (col[std::size_t(c + 1)] - col[std::size_t(c)]) * tx;
        row[i] += amp * (o == 3 ? (1.0f - 2.0f * std::abs(v)) : v);
      }
      amp *= o < 2 ? 0.5f : 0.55f;
    }
    for (std::uint32_t i = 0; i < width; ++i) {
      const float v = std::nearbyint(row[i] / float(kWorldHeightScale));
      out[std::size_t(j - j0) * width + i] = std::uint16_t(std::clamp(v, 0.0f, 65535.0f));
    }
  }
}

}  // namespace ridgeline::scenes
