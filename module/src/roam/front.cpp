// The front's test, vectorised (compiled with -O3 -ffp-contract=off -fno-math-errno: the
// vector and scalar paths make the same IEEE operations in the same order, so a diamond tested
// alone gets the same answer as in the pass). The test is Lindstrom & Pascucci's (SOAR, 2001):
// active when (kappa mu + r)^2 > d^2, with nested bounds and spheres, plus view culling of the
// sphere against the side planes and the far distance.
#include "roam/front.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <glm/geometric.hpp>

namespace ridgeline::roam {

namespace {

// One entry's test. Branch free, so the pass vectorises; `p` receives the priority (projected
// bound, pixels) with the distance to the sphere clamped to the near plane.
inline std::uint32_t screen_test(std::int32_t i, std::int32_t j, float y, float mu, float r,
                                 const FrontCamera& c, float& p) noexcept {
  const float dx = float(i) * c.sx - c.ex, dy = y - c.ey, dz = float(j) * c.sz - c.ez;
  const float d2 = dx * dx + dy * dy + dz * dz;
  // A diamond without error never splits, even with the eye inside its sphere; one over the
  // data's border always does (radius FLT_MAX).
  const std::uint32_t may = (mu > 0.0f) | (r >= 3.0e38f);
  r += c.margin;
  const float m = c.kappa * mu + r;
  const std::uint32_t act = (m * m > d2) & may;  // 0 * inf (zero bound, threshold 0) is NaN
  const float s0 = c.planes[0][0] * dx + c.planes[0][1] * dy + c.planes[0][2] * dz;
  const float s1 = c.planes[1][0] * dx + c.planes[1][1] * dy + c.planes[1][2] * dz;
  const float s2 = c.planes[2][0] * dx + c.planes[2][1] * dy + c.planes[2][2] * dz;
  const float s3 = c.planes[3][0] * dx + c.planes[3][1] * dy + c.planes[3][2] * dz;
  const float nr = -r, fr = c.far_m + r;
  const std::uint32_t in = (s0 >= nr) & (s1 >= nr) & (s2 >= nr) & (s3 >= nr) & (d2 <= fr * fr);
  float den = std::sqrt(d2) - r;
  den = den > c.near_m ? den : c.near_m;
  p = mu * c.scale / den;
  return (act & in) | (in << 1);
}

inline std::uint32_t world_test(float mu, float r, const FrontCamera& c, float& p) noexcept {
  p = mu;
  const std::uint32_t act = (mu > c.threshold) | (r >= 3.0e38f);  // the data border is forced
  return act | kInView;
}

// The new state word of a lane from its old one and the test's result.
inline std::uint32_t with_result(std::uint32_t state, std::uint32_t t) noexcept {
  const std::uint32_t changed = ((t & kActive) ^ (state & Front::kSplit)) << 2;
  return (state & ~(0xffu << Front::kResultShift)) | ((t | changed) << Front::kResultShift);
}

#if defined(__x86_64__) && !defined(__clang__)
#define RIDGELINE_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define RIDGELINE_CLONES
#endif

// The pass, one block of four lanes at a time: the results, and the largest priority of an entry
// in view whose test fails (what stays unsplit once the changes are made), as the bits of a
// non-negative float (integer order: the reduction vectorises). Lanes past the last entry hold
// zeros and test inactive, out of view.
RIDGELINE_CLONES
std::uint32_t screen_pass(Front::Block* __restrict blocks, std::size_t nblocks,
                          const FrontCamera& c, std::uint8_t* __restrict changed) {
  const FrontCamera cc = c;  // a local copy: no aliasing with the blocks
  std::uint32_t worst = 0;
  for (std::size_t b = 0; b < nblocks; ++b) {
    const std::int32_t* __restrict bi = blocks[b].i;
    const std::int32_t* __restrict bj = blocks[b].j;
    const float* __restrict y = blocks[b].y;
    const float* __restrict mu = blocks[b].mu;
    const float* __restrict r = blocks[b].r;
    std::uint32_t* __restrict st = blocks[b].state;
    for (std::uint32_t l = 0; l < Front::kLanes; ++l) {
      float pk;
      const std::uint32_t t = screen_test(bi[l], bj[l], y[l], mu[l], r[l], cc, pk);
      st[l] = with_result(st[l], t);
      // In view and the test failed: keep the priority's bits (a mask, so that it vectorises).
      const std::uint32_t q = std::bit_cast<std::uint32_t>(pk) & -std::uint32_t(t == kInView);
      worst = q > worst ? q : worst;
    }
    // Whether any lane of the block changed: the view's scan skips the others.
    changed[b] = std::uint8_t(((st[0] | st[1] | st[2] | st[3]) >> (Front::kResultShift + 2)) & 1);
  }
  return worst;
}

}  // namespace

FrontCamera FrontCamera::screen(const Camera& camera, double threshold_px, double ox, double oy,
                                double oz, double sx, double sz, double extent) {
  FrontCamera c;
  const Frustum f(camera);
  c.ex = float(camera.eye.x - ox);
  c.ey = float(camera.eye.y - oy);
  c.ez = float(camera.eye.z - oz);
  c.scale = float(f.scale);
  c.kappa = threshold_px > 0 ? float(f.scale / threshold_px) : INFINITY;
  for (int k = 0; k < 4; ++k)
    for (int a = 0; a < 3; ++a) c.planes[k][a] = float(f.planes[k][a]);
  c.far_m = float(camera.far_m);
  c.near_m = float(camera.near_m);
  c.threshold = float(threshold_px);
  c.sx = float(sx);
  c.sz = float(sz);
  // Positions are floats of magnitude up to the extent (and the eye's): their rounding, a few
  // units in the last place, is what the test must not lose: 2^-17 of the magnitude, ~64 ulps.
  const double mag =
      extent + std::abs(double(c.ex)) + std::abs(double(c.ey)) + std::abs(double(c.ez));
  c.margin = float(std::ldexp(mag, -17));
  return c;
}

FrontCamera FrontCamera::world_metres(double threshold_m) {
  FrontCamera c;
  c.world = true;
  c.threshold = float(threshold_m);
  return c;
}

std::uint32_t Front::add(std::int32_t i, std::int32_t j, std::uint32_t t, float y, float mu,
                         float r, std::uint32_t node, bool split, bool provisional) {
  const std::uint32_t e = n_++;
  if ((e & 3) == 0 && (e >> 2) >= blocks_.size()) {
    // Grow by a quarter, not double: the front is most of a view's memory after the nodes.
    if (blocks_.size() == blocks_.capacity())
      blocks_.reserve(std::max<std::size_t>(256, blocks_.size() + blocks_.size() / 4));
    blocks_.emplace_back();
  }
  Block& k = blk(e);
  const std::uint32_t l = e & 3;
  k.i[l] = i, k.j[l] = j, k.y[l] = y, k.mu[l] = mu, k.r[l] = r, k.node[l] = node;
  k.state[l] = (t << kLevelShift) | (split ? kSplit : 0u) | (provisional ? kProvisional : 0u);
  return e;
}

void Front::set_data(std::uint32_t e, float y, float mu, float r) noexcept {
  Block& k = blk(e);
  const std::uint32_t l = e & 3;
  k.y[l] = y, k.mu[l] = mu, k.r[l] = r;
}

std::uint32_t Front::remove(std::uint32_t e) {
  const std::uint32_t last = --n_;
  Block& d = blk(e);
  Block& s = blk(last);
  const std::uint32_t a = e & 3, b = last & 3;
  if (e != last) {
    d.i[a] = s.i[b], d.j[a] = s.j[b], d.y[a] = s.y[b], d.mu[a] = s.mu[b], d.r[a] = s.r[b];
    d.state[a] = s.state[b], d.node[a] = s.node[b];
  }
  // The freed lane tests inactive and out of view (zero bound and radius, far from the eye is
  // not needed: a zero sphere at the origin with a zero bound never passes; changed never set).
  s.i[b] = s.j[b] = 0;
  s.y[b] = s.mu[b] = s.r[b] = 0.0f;
  s.state[b] = s.node[b] = 0;
  return last;
}

float Front::evaluate(const FrontCamera& c) {
  const std::size_t nb = (n_ + kLanes - 1) / kLanes;
  if (c.world) {
    float worst = 0;
    for (std::uint32_t e = 0; e < n_; ++e) {
      Block& k = blk(e);
      const std::uint32_t l = e & 3;
      float p;
      const std::uint32_t t = world_test(k.mu[l], k.r[l], c, p);
      k.state[l] = with_result(k.state[l], t);
      if (!(t & kActive)) worst = std::max(worst, p);
    }
    changed_.assign(blocks_.size(), 1);
    return worst;
  }
  changed_.resize(blocks_.size());
  const float worst = std::bit_cast<float>(screen_pass(blocks_.data(), nb, c, changed_.data()));
  // A lane past the last entry (zeros: a sphere of radius 0 at the lattice origin, bound 0)
  // never tests active or changed, but tests in view when the origin is: keep it all zeros.
  for (std::uint32_t e = n_; e < nb * kLanes; ++e) blk(e).state[e & 3] = 0;
  return worst;
}

std::uint8_t Front::test_one(std::uint32_t e, const FrontCamera& c) noexcept {
  Block& k = blk(e);
  const std::uint32_t l = e & 3;
  float p;
  const std::uint32_t t = c.world ? world_test(k.mu[l], k.r[l], c, p)
                                  : screen_test(k.i[l], k.j[l], k.y[l], k.mu[l], k.r[l], c, p);
  k.state[l] = with_result(k.state[l], t);
  return std::uint8_t(t);
}

float Front::priority(std::uint32_t e, const FrontCamera& c) const noexcept {
  const Block& k = blk(e);
  const std::uint32_t l = e & 3;
  float p;
  if (c.world)
    (void)world_test(k.mu[l], k.r[l], c, p);
  else
    (void)screen_test(k.i[l], k.j[l], k.y[l], k.mu[l], k.r[l], c, p);
  return p;
}

float Front::max_unsplit_priority(const FrontCamera& c) const noexcept {
  float m = 0.0f;
  for (std::uint32_t e = 0; e < n_; ++e) {
    const std::uint32_t s = st(e), f = s & 0xffu, r = (s >> kResultShift) & 0xffu;
    if ((f & kSplit) || !(r & kInView) || ((r & kActive) && (f & kProvisional))) continue;
    m = std::max(m, priority(e, c));
  }
  return m;
}

std::size_t Front::memory_bytes() const noexcept {
  return blocks_.capacity() * sizeof(Block) + changed_.capacity();
}

}  // namespace ridgeline::roam
