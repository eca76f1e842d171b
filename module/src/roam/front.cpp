// The front's test, vectorised (compiled with -ffp-contract=off -fno-math-errno: the vector and
// scalar paths make the same IEEE operations in the same order, so a diamond tested alone gets
// the same answer as in the pass). The test is Lindstrom & Pascucci's (SOAR, 2001): active when
// (kappa mu + r)^2 > d^2, with nested bounds and spheres, plus view culling of the sphere against
// the side planes and the far distance.
#include "roam/front.h"
#include "roam/nodes.h"

#include <algorithm>
#include <bit>
#include <cmath>

#include "platform/cpu_features.h"

namespace ridgeline::roam {

namespace {

// One entry's test; `p` receives the priority (projected bound, pixels) with the distance to the
// sphere clamped to the near plane. Every operation here is mirrored, in the same order, by the
// eight-lane pass below.
inline std::uint32_t screen_test(float x, float y, float z, float mu, float r, const FrontCamera& c,
                                 float* p) noexcept {
  const float dx = x - c.ex, dy = y - c.ey, dz = z - c.ez;
  const float d2 = dx * dx + dy * dy + dz * dz;
  // A diamond without error never splits, even with the eye inside its sphere; one over the
  // data's border always does.
  const std::uint32_t may = std::uint32_t(mu > 0.0f) | std::uint32_t(r >= Front::kBorderRadius);
  r = r + c.margin;
  const float m = c.kappa * mu + r;
  const std::uint32_t act = std::uint32_t(m * m > d2) & may;  // 0 * inf (bound 0, threshold 0)
  const float s0 = c.planes[0][0] * dx + c.planes[0][1] * dy + c.planes[0][2] * dz;
  const float s1 = c.planes[1][0] * dx + c.planes[1][1] * dy + c.planes[1][2] * dz;
  const float s2 = c.planes[2][0] * dx + c.planes[2][1] * dy + c.planes[2][2] * dz;
  const float s3 = c.planes[3][0] * dx + c.planes[3][1] * dy + c.planes[3][2] * dz;
  const float nr = -r, fr = c.far_m + r;
  const std::uint32_t in = std::uint32_t(s0 >= nr) & std::uint32_t(s1 >= nr) &
                           std::uint32_t(s2 >= nr) & std::uint32_t(s3 >= nr) &
                           std::uint32_t(d2 <= fr * fr);
  if (p != nullptr) {
    float den = std::sqrt(d2) - r;
    den = den > c.near_m ? den : c.near_m;
    *p = mu * c.scale / den;
  }
  return (act & in) | (in << 1);
}

inline std::uint32_t world_test(float mu, float r, const FrontCamera& c, float* p) noexcept {
  if (p != nullptr) *p = mu;
  const std::uint32_t act =
      std::uint32_t(mu > c.threshold) | std::uint32_t(r >= Front::kBorderRadius);
  return act | kInView;
}

// The pass without vector instructions: the scalar test lane by lane.
// Blocks [0, nb) of one chunk, whose first block is block `first` of the front; `worst` is the
// largest failing priority in view so far (the chunks before).
float screen_pass_scalar(Front::Hot* hot, std::size_t nb, std::uint32_t first, const FrontCamera& c,
                         std::vector<Front::Keyed>* changed, float worst) {
  for (std::size_t b = 0; b < nb; ++b) {
    Front::Hot& h = hot[b];
    std::uint32_t act = 0, view = 0;
    float p[Front::kLanes];
    for (std::uint32_t l = 0; l < Front::kLanes; ++l) {
      const std::uint32_t t = screen_test(h.x[l], h.y[l], h.z[l], h.mu[l], h.r[l], c, &p[l]);
      act |= (t & 1u) << l;
      view |= ((t >> 1) & 1u) << l;
      if (t == kInView && ((h.m.valid >> l) & 1u) && p[l] > worst) worst = p[l];
    }
    h.m.active = std::uint8_t(act & h.m.valid);
    h.m.view = std::uint8_t(view & h.m.valid);
    if (changed == nullptr) continue;
    for (std::uint32_t d = std::uint32_t(h.m.active ^ h.m.split) & h.m.valid; d != 0; d &= d - 1) {
      const std::uint32_t l = std::uint32_t(std::countr_zero(d));
      changed->push_back(
          {(h.m.view >> l) & 1 ? p[l] : -1.0f,
           ((first + std::uint32_t(b)) * Front::kLanes + l) | (((h.m.split >> l) & 1u) << 31)});
    }
  }
  return worst;
}

#if RIDGELINE_HAS_AVX2_DISPATCH
// Eight lanes at a time, the same operations as screen_test() in the same order (no fused
// multiply-adds). Writes only the masks.
RIDGELINE_TARGET_AVX2 float screen_pass_avx2(Front::Hot* hot, std::size_t nb,
                                                       std::uint32_t first, const FrontCamera& c,
                                                       std::vector<Front::Keyed>* changed,
                                                       float w) {
  const __m256 ex = _mm256_set1_ps(c.ex), ey = _mm256_set1_ps(c.ey), ez = _mm256_set1_ps(c.ez);
  const __m256 kappa = _mm256_set1_ps(c.kappa), margin = _mm256_set1_ps(c.margin);
  const __m256 zero = _mm256_setzero_ps(), border = _mm256_set1_ps(Front::kBorderRadius);
  const __m256 far = _mm256_set1_ps(c.far_m), near = _mm256_set1_ps(c.near_m);
  const __m256 scale = _mm256_set1_ps(c.scale);
  __m256 pl[4][3];
  for (int k = 0; k < 4; ++k)
    for (int a = 0; a < 3; ++a) pl[k][a] = _mm256_set1_ps(c.planes[k][a]);
  // The largest priority of a failing lane in view: mu K / max(d - r, near). Computing it for
  // every lane costs a square root and a division; instead a lane is a candidate only when
  // (mu K / w + r)^2 > d^2 (w the largest so far), which every lane whose priority exceeds w
  // passes (for d - r > near directly, and for d - r <= near because then mu K / w > near,
  // so mu K / w + r > d). Only blocks with a candidate compute priorities; w climbs to its
  // final value within the first blocks, so that is rare.
  __m256 kw = _mm256_set1_ps(w > 0.0f ? c.scale / w * (1.0f + 0x1p-20f)
                                      : INFINITY);  // K / w, generous by 2^-20
  for (std::size_t b = 0; b < nb; ++b) {
    Front::Hot& h = hot[b];
    const __m256 dx = _mm256_sub_ps(_mm256_load_ps(h.x), ex);
    const __m256 dy = _mm256_sub_ps(_mm256_load_ps(h.y), ey);
    const __m256 dz = _mm256_sub_ps(_mm256_load_ps(h.z), ez);
    const __m256 d2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)),
                                    _mm256_mul_ps(dz, dz));
    const __m256 mu = _mm256_load_ps(h.mu);
    __m256 r = _mm256_load_ps(h.r);
    const __m256 may =
        _mm256_or_ps(_mm256_cmp_ps(mu, zero, _CMP_GT_OQ), _mm256_cmp_ps(r, border, _CMP_GE_OQ));
    r = _mm256_add_ps(r, margin);
    const __m256 m = _mm256_add_ps(_mm256_mul_ps(kappa, mu), r);
    const __m256 act = _mm256_and_ps(_mm256_cmp_ps(_mm256_mul_ps(m, m), d2, _CMP_GT_OQ), may);
    const __m256 nr = _mm256_sub_ps(zero, r);
    const __m256 fr = _mm256_add_ps(far, r);
    __m256 in = _mm256_cmp_ps(d2, _mm256_mul_ps(fr, fr), _CMP_LE_OQ);
    for (int k = 0; k < 4; ++k) {
      const __m256 s =
          _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(pl[k][0], dx), _mm256_mul_ps(pl[k][1], dy)),
                        _mm256_mul_ps(pl[k][2], dz));
      in = _mm256_and_ps(in, _mm256_cmp_ps(s, nr, _CMP_GE_OQ));
    }
    const std::uint32_t valid = hot[b].m.valid;
    const auto act_bits = std::uint32_t(_mm256_movemask_ps(_mm256_and_ps(act, in))) & valid;
    const auto view_bits = std::uint32_t(_mm256_movemask_ps(in)) & valid;
    hot[b].m.active = std::uint8_t(act_bits);
    hot[b].m.view = std::uint8_t(view_bits);
    // Lanes whose test disagrees with their state (their priorities go to the budgeted update's
    // queues), and whether a failing lane in view may raise the worst priority: the eight
    // priorities (a square root and a division) are computed once, only for a block that needs
    // them.
    const std::uint32_t d = changed != nullptr ? (act_bits ^ hot[b].m.split) & valid : 0u;
    const std::uint32_t q = view_bits & ~act_bits;  // in view, the test failed
    bool candidate = false;
    if (q != 0) {
      const __m256 a = _mm256_add_ps(_mm256_mul_ps(mu, kw), r);
      candidate =
          (std::uint32_t(_mm256_movemask_ps(_mm256_cmp_ps(_mm256_mul_ps(a, a), d2, _CMP_GT_OQ))) &
           q) != 0;
    }
    if (d == 0 && !candidate) continue;
    __m256 den = _mm256_sub_ps(_mm256_sqrt_ps(d2), r);
    den = _mm256_max_ps(den, near);  // den > near ? den : near, as the scalar test
    alignas(32) float p[8];
    _mm256_store_ps(p, _mm256_div_ps(_mm256_mul_ps(mu, scale), den));
    for (std::uint32_t x = d; x != 0; x &= x - 1) {
      const std::uint32_t l = std::uint32_t(std::countr_zero(x));
      changed->push_back(
          {(view_bits >> l) & 1 ? p[l] : -1.0f, ((first + std::uint32_t(b)) * Front::kLanes + l) |
                                                    (((hot[b].m.split >> l) & 1u) << 31)});
    }
    if (!candidate) continue;
    for (std::uint32_t l = 0; l < Front::kLanes; ++l)
      if (((q >> l) & 1) && p[l] > w) w = p[l];
    kw = _mm256_set1_ps(w > 0.0f ? c.scale / w * (1.0f + 0x1p-20f) : INFINITY);
  }
  return w;
}
#endif

}  // namespace

FrontCamera FrontCamera::screen(const Camera& camera, double threshold_px, double ox, double oy,
                                double oz, double extent) {
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

namespace {
// The four masks of a block as one word: byte 0 split, 1 active, 2 view, 3 valid (Masks).
inline std::uint32_t word(const Front::Masks& m) noexcept {
  return std::bit_cast<std::uint32_t>(m);
}
inline void set_word(Front::Masks& m, std::uint32_t w) noexcept {
  m = std::bit_cast<Front::Masks>(w);
}
constexpr std::uint32_t kLaneBits = 0x01010101u;  // lane 0's bit in each of the four masks
}  // namespace

std::uint32_t Front::add(std::int32_t i, std::int32_t j, std::int32_t hu, std::int32_t hw,
                         std::uint32_t t, float x, float y, float z, float mu, float r,
                         std::uint32_t node, bool split, bool provisional) {
  const std::uint32_t e = n_;
  const std::uint32_t l = e & 7;
  if (l == 0) {
    // A new block (zero bound and radius in its free lanes: never active), with room for a
    // chunk more when the last one is full.
    if (e >= capacity_) grow();
    block(e >> 3) = Hot{};
  }
  ++n_;
  Hot& h = block(e >> 3);
  h.x[l] = x, h.y[l] = y, h.z[l] = z, h.mu[l] = mu, h.r[l] = r;
  // The half hypotenuse's kind: (s, 0), (0, -s), (-s, -s), (s, -s) (canonical: diamond.h).
  const std::uint32_t kind = hw == 0 ? 0u : hu == 0 ? 1u : hu < 0 ? 2u : 3u;
  cold(e) = {i, j, node, (t << 8) | (kind << 1) | (provisional ? 1u : 0u)};
  // valid, not active nor in view yet, split as given.
  const std::uint32_t w = word(h.m) & ~(kLaneBits << l);
  set_word(h.m, w | ((0x01000000u | std::uint32_t(split)) << l));
  return e;
}

std::uint32_t Front::remove(std::uint32_t e) noexcept {
  const std::uint32_t last = --n_;
  const std::uint32_t a = e & 7, b = last & 7;
  Hot& sh = block(last >> 3);
  if (e != last) {
    Hot& dh = block(e >> 3);
    dh.x[a] = sh.x[b], dh.y[a] = sh.y[b], dh.z[a] = sh.z[b], dh.mu[a] = sh.mu[b], dh.r[a] = sh.r[b];
    cold(e) = cold(last);
    const std::uint32_t moved = (word(sh.m) >> b) & kLaneBits;
    set_word(dh.m, (word(dh.m) & ~(kLaneBits << a)) | (moved << a));
  }
  // The freed lane: zero bound and radius (never active), outside every mask.
  sh.x[b] = sh.y[b] = sh.z[b] = sh.mu[b] = sh.r[b] = 0.0f;
  set_word(sh.m, word(sh.m) & ~(kLaneBits << b));
  return last;
}

void Front::clear() noexcept {
  n_ = 0;
}

void Front::grow() {
  // Entries never outnumber the nodes: each is a diamond with a node.
  constexpr std::size_t kMaxEntries = NodePool::kMaxNodes;
  const std::size_t n = std::size_t(capacity_) + kChunkEntries;
  // Each pointer read again as soon as its array grew: a plain allocation moves (reserved.h),
  // and the second growth may fail.
  hot_mem_.grow_to(n / kLanes * sizeof(Hot), kChunkBlocks * sizeof(Hot),
                   kMaxEntries / kLanes * sizeof(Hot));
  hot_ = static_cast<Hot*>(hot_mem_.data());
  cold_mem_.grow_to(n * sizeof(Cold), kChunkEntries * sizeof(Cold), kMaxEntries * sizeof(Cold));
  cold_ = static_cast<Cold*>(cold_mem_.data());
  set_capacity();
}

void Front::set_capacity() noexcept {
  // What both arrays hold (more than asked when a destroyed view's range was taken over: trim()
  // gives that back).
  capacity_ = std::uint32_t(std::min(hot_mem_.committed() / sizeof(Hot) * kLanes,
                                     cold_mem_.committed() / sizeof(Cold)));
}

void Front::trim() noexcept {
  // Whole chunks: a chunk's blocks and records are whole pages.
  static_assert(kChunkBlocks * sizeof(Hot) % 4096 == 0 && kChunkEntries * sizeof(Cold) % 4096 == 0);
  const std::size_t keep = ((n_ + kChunkEntries - 1) / kChunkEntries + 1) * kChunkEntries;
  if (keep >= capacity_) return;
  hot_mem_.shrink_to(keep / kLanes * sizeof(Hot));
  cold_mem_.shrink_to(keep * sizeof(Cold));
  hot_ = static_cast<Hot*>(hot_mem_.data());  // a plain allocation moves (reserved.h)
  cold_ = static_cast<Cold*>(cold_mem_.data());
  set_capacity();
}

void Front::set_result(std::uint32_t e, std::uint32_t bits) noexcept {
  Masks& m = block(e >> 3).m;
  const std::uint32_t l = e & 7;
  // bits: kActive (1) -> byte 1, kInView (2) -> byte 2.
  const std::uint32_t set = ((bits & kActive) << 8 | (bits & kInView) << 15) << l;
  set_word(m, (word(m) & ~(0x00010100u << l)) | set);
}

float Front::evaluate(const FrontCamera& c, std::vector<Keyed>* changed) {
  if (changed != nullptr) changed->clear();
  const std::size_t nb = blocks();
  if (c.world) {
    float worst = 0;
    for (std::uint32_t e = 0; e < n_; ++e) {
      float p;
      const std::uint32_t t = world_test(mu(e), radius(e), c, &p);
      set_result(e, t);
      if (!(t & kActive)) worst = std::max(worst, p);
      if (changed != nullptr && bool(t & kActive) != split(e))
        changed->push_back({p, e | (split(e) ? kKeyedSplit : 0u)});
    }
    return worst;
  }
  float worst = 0.0f;
  for (std::uint32_t k = 0; k * kChunkBlocks < nb; ++k) worst = pass_chunk(k, c, changed, worst);
  return worst;
}

float Front::pass_chunk(std::uint32_t k, const FrontCamera& c, std::vector<Keyed>* changed,
                        float worst) {
  const std::uint32_t first = k * kChunkBlocks;
  Hot* hot = hot_ + std::size_t(first);
  const std::size_t n = std::min<std::size_t>(kChunkBlocks, blocks() - first);
#if RIDGELINE_HAS_AVX2_DISPATCH
  if (detail::cpu_has_avx2()) return screen_pass_avx2(hot, n, first, c, changed, worst);
#endif
  return screen_pass_scalar(hot, n, first, c, changed, worst);
}

float Front::evaluate_until(const FrontCamera& c, std::vector<Keyed>* changed,
                            std::chrono::steady_clock::time_point stop_at, std::uint32_t* cursor,
                            std::uint32_t* tested) {
  const std::uint32_t used = (blocks() + kChunkBlocks - 1) / kChunkBlocks;
  if (c.world || used <= 1) {
    *cursor = 0;
    *tested = n_;
    return evaluate(c, changed);
  }
  if (changed != nullptr) changed->clear();
  float worst = 0.0f;
  std::uint32_t k = *cursor % used, count = 0;
  *tested = 0;
  for (;;) {
    worst = pass_chunk(k, c, changed, worst);
    *tested += std::min(n_ - k * kChunkEntries, kChunkEntries);
    k = (k + 1) % used;
    if (++count == used || std::chrono::steady_clock::now() >= stop_at) break;
  }
  *cursor = k;
  return worst;
}

std::uint8_t Front::test_one(std::uint32_t e, const FrontCamera& c, float* priority) noexcept {
  const Hot& h = block(e >> 3);
  const std::uint32_t l = e & 7;
  const std::uint32_t t = c.world
                              ? world_test(h.mu[l], h.r[l], c, priority)
                              : screen_test(h.x[l], h.y[l], h.z[l], h.mu[l], h.r[l], c, priority);
  set_result(e, t);
  return std::uint8_t(t);
}

std::uint8_t Front::test_values(float x, float y, float z, float mu, float r, const FrontCamera& c,
                                float* priority) noexcept {
  return std::uint8_t(c.world ? world_test(mu, r, c, priority)
                              : screen_test(x, y, z, mu, r, c, priority));
}

float Front::priority(std::uint32_t e, const FrontCamera& c) const noexcept {
  const Hot& h = block(e >> 3);
  const std::uint32_t l = e & 7;
  float p = 0;
  if (c.world)
    (void)world_test(h.mu[l], h.r[l], c, &p);
  else
    (void)screen_test(h.x[l], h.y[l], h.z[l], h.mu[l], h.r[l], c, &p);
  return p;
}

float Front::max_unsplit_priority(const FrontCamera& c) const noexcept {
  float m = 0.0f;
  for (std::uint32_t e = 0; e < n_; ++e) {
    const std::uint8_t r = result(e);
    if (split(e) || !(r & kInView) || ((r & kActive) && provisional(e))) continue;
    m = std::max(m, priority(e, c));
  }
  return m;
}

std::size_t Front::memory_bytes() const noexcept {
  return hot_mem_.committed() + cold_mem_.committed();
}

}  // namespace ridgeline::roam
