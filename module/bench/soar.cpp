// Stateless SOAR refinement after Lindstrom & Pascucci 2001 (section 4: nested errors and
// spheres, the refinement test, view culling, the strip built during the recursion) and 2002
// (the division-free test). See soar.h.
#include "ridgeline/bench/soar.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace ridgeline::bench {

namespace {
constexpr std::uint32_t kAllInside = 0;  // no side plane left to test
constexpr std::uint32_t kUndecided = 0xF;
constexpr std::uint32_t kOutside = 0x10;
}  // namespace

Soar::Soar(const Grid& hf)
    : origin_x_(hf.origin_x()),
      origin_z_(hf.origin_z()),
      offset_(hf.height_offset()),
      spacing_x_(hf.spacing_x()),
      spacing_z_(hf.spacing_z()) {
  std::uint32_t n = 1;
  while ((std::uint64_t{1} << n) < std::max(hf.width(), hf.height()) - 1) ++n;
  size_ = (1u << n) + 1;
  levels_ = 2 * n - 1;  // a root (a quarter of the square) holds 2^levels_ half cells
  vertices_.resize(std::size_t(size_) * size_);
  for (std::uint32_t j = 0; j < size_; ++j)
    for (std::uint32_t i = 0; i < size_; ++i)
      vertices_[i + std::size_t(j) * size_] = {float(double(i) * spacing_x_),
                                               hf.local_clamped(i, j),
                                               float(double(j) * spacing_z_), 0.0f, 0.0f};
  // Bottom-up over the levels: a vertex's children are the split vertices of the triangles it
  // is the apex of, all one level finer, so every child is final before its parent takes the
  // maximum.
  const std::uint32_t c = (size_ - 1) / 2 * (size_ + 1), sw = 0, se = size_ - 1,
                      ne = size_ * size_ - 1, nw = (size_ - 1) * size_;
  for (std::uint32_t level = 1; level <= levels_; ++level)
    for (const auto& root :
         {std::array<std::uint32_t, 3>{c, sw, se}, {c, se, ne}, {c, ne, nw}, {c, nw, sw}})
      nest(levels_, root[0], root[1], root[2], level);
}

// Visits the triangles of level `depth` under triangle (apex, left, right) of level `level` and
// nests the error and radius of each one's split vertex over its two children's.
void Soar::nest(std::uint32_t level, std::uint32_t apex, std::uint32_t left, std::uint32_t right,
                std::uint32_t depth) {
  const std::uint32_t m = (left + right) / 2;
  if (level > depth) {
    nest(level - 1, m, left, apex, depth);
    nest(level - 1, m, apex, right, depth);
    return;
  }
  Vertex& v = vertices_[m];
  // The vertex's own error: its height against the edge it bisects (the error between two
  // consecutive levels of refinement, as in SOAR implementations).
  const float own = std::abs(v.y - 0.5f * (vertices_[left].y + vertices_[right].y));
  v.e = std::max(v.e, own);
  if (level < 2) return;  // the children have no split vertex
  for (const std::uint32_t child : {(left + apex) / 2, (apex + right) / 2}) {
    const Vertex& cv = vertices_[child];
    const float dx = v.x - cv.x, dy = v.y - cv.y, dz = v.z - cv.z;
    v.e = std::max(v.e, cv.e);
    v.r = std::max(v.r, std::sqrt(dx * dx + dy * dy + dz * dz) + cv.r);
  }
}

// One refinement pass: the camera in the vertices' frame, and the strip being built.
struct Soar::Pass {
  const Vertex* v;
  float ex, ey, ez, kappa;
  float planes[4][3];
  std::vector<std::uint32_t>* strip;  // null: count only
  std::uint64_t leaves = 0;
  bool parity = true;

  bool active(const Vertex& p) const {
    const float dx = p.x - ex, dy = p.y - ey, dz = p.z - ez;
    const float f = kappa * p.e + p.r;
    return f * f > dx * dx + dy * dy + dz * dz;
  }
  // Sphere of vertex p against the side planes still undecided in `mask`: kOutside when it is
  // wholly outside one; a plane it is wholly inside of is dropped from the mask (the spheres are
  // nested, so every descendant is inside it too).
  std::uint32_t cull(const Vertex& p, std::uint32_t mask) const {
    const float cx = p.x - ex, cy = p.y - ey, cz = p.z - ez;
    for (std::uint32_t k = 0; k < 4; ++k) {
      if (!(mask >> k & 1)) continue;
      const float s = planes[k][0] * cx + planes[k][1] * cy + planes[k][2] * cz;
      if (s < -p.r) return kOutside;
      if (s > p.r) mask &= ~(1u << k);
    }
    return mask;
  }
  // Appends vertex index i (of a triangle of parity `p`) to the generalised strip: nothing when
  // it is one of the last two; a repeated vertex first ("turning the corner") when the parity
  // did not alternate.
  void append(std::uint32_t i, bool p) {
    std::vector<std::uint32_t>& s = *strip;
    const std::uint32_t tail = s[s.size() - 2], head = s.back();
    if (i == tail || i == head) return;
    if (p == parity) s.push_back(tail);
    s.push_back(i);
    parity = p;
  }

  template <bool Emit>
  void refine(std::uint32_t level, std::uint32_t apex, std::uint32_t left, std::uint32_t right) {
    const std::uint32_t m = (left + right) / 2;
    const bool split = level > 0 && active(v[m]);
    if (split) refine<Emit>(level - 1, m, left, apex);
    leaves += !split;
    if constexpr (Emit) append(apex, level & 1);
    if (split) refine<Emit>(level - 1, m, apex, right);
  }
  template <bool Emit>
  void refine_culled(std::uint32_t level, std::uint32_t apex, std::uint32_t left,
                     std::uint32_t right, std::uint32_t mask) {
    if (mask == kAllInside) return refine<Emit>(level, apex, left, right);
    const std::uint32_t m = (left + right) / 2;
    bool split = false;
    if (level > 0) {
      mask = cull(v[m], mask);
      split = mask != kOutside && active(v[m]);
    }
    if (split) refine_culled<Emit>(level - 1, m, left, apex, mask);
    leaves += !split;
    if constexpr (Emit) append(apex, level & 1);
    if (split) refine_culled<Emit>(level - 1, m, apex, right, mask);
  }
};

double Soar::kappa_for(const Camera& camera, double threshold_px) {
  return threshold_px > 0 ? projection_scale(camera) / threshold_px
                          : std::numeric_limits<double>::infinity();
}

namespace {
template <class P>
void setup(P& pass, const Camera& camera, double kappa, double ox, double oz, double offset) {
  pass.ex = float(camera.eye.x - ox);
  pass.ey = float(camera.eye.y - offset);
  pass.ez = float(camera.eye.z - oz);
  // +infinity would make inf * 0 = NaN for vertices of zero error: a huge finite kappa refines
  // everything with an error and overflows to +inf harmlessly.
  pass.kappa = float(std::min(kappa, 1e30));
  const Frustum f(camera);
  for (int k = 0; k < 4; ++k)
    for (int a = 0; a < 3; ++a) pass.planes[k][a] = float(f.planes[k][a]);
}
}  // namespace

Soar::Frame Soar::refine(const Camera& camera, double kappa, std::vector<std::uint32_t>& strip,
                         bool cull) const {
  Pass p{};
  p.v = vertices_.data();
  setup(p, camera, kappa, origin_x_, origin_z_, offset_);
  p.strip = &strip;
  strip.clear();
  const std::uint32_t c = (size_ - 1) / 2 * (size_ + 1), sw = 0, se = size_ - 1,
                      ne = size_ * size_ - 1, nw = (size_ - 1) * size_;
  const std::uint32_t mask = cull ? kUndecided : kAllInside;
  strip.push_back(sw);
  strip.push_back(sw);
  p.parity = true;
  p.refine_culled<true>(levels_, c, sw, se, mask);
  p.append(se, false);
  p.refine_culled<true>(levels_, c, se, ne, mask);
  p.append(ne, false);
  p.refine_culled<true>(levels_, c, ne, nw, mask);
  p.append(nw, false);
  p.refine_culled<true>(levels_, c, nw, sw, mask);
  strip.push_back(sw);
  return {p.leaves, kappa};
}

std::uint64_t Soar::count(const Camera& camera, double kappa, bool cull) const {
  Pass p{};
  p.v = vertices_.data();
  setup(p, camera, kappa, origin_x_, origin_z_, offset_);
  const std::uint32_t c = (size_ - 1) / 2 * (size_ + 1), sw = 0, se = size_ - 1,
                      ne = size_ * size_ - 1, nw = (size_ - 1) * size_;
  const std::uint32_t mask = cull ? kUndecided : kAllInside;
  p.refine_culled<false>(levels_, c, sw, se, mask);
  p.refine_culled<false>(levels_, c, se, ne, mask);
  p.refine_culled<false>(levels_, c, ne, nw, mask);
  p.refine_culled<false>(levels_, c, nw, sw, mask);
  return p.leaves;
}

Soar::Match Soar::match(const std::vector<Camera>& frames, double target, std::size_t step) const {
  step = std::max<std::size_t>(step, 1);
  auto median = [&](double kappa) {
    std::vector<double> t;
    for (std::size_t k = 0; k < frames.size(); k += step)
      t.push_back(double(count(frames[k], kappa)));
    if (t.empty()) return 0.0;
    std::nth_element(t.begin(), t.begin() + std::ptrdiff_t(t.size() / 2), t.end());
    return t[t.size() / 2];
  };
  // Counts grow with kappa: bracket the target by doubling, then bisect in log kappa.
  double lo = 1.0, hi = 1.0, mlo = median(lo), mhi = mlo;
  while (mlo > target && lo > 1e-9) mlo = median(lo /= 2);
  hi = lo;
  mhi = mlo;
  while (mhi < target && hi < 1e12) {
    lo = hi;
    mlo = mhi;
    mhi = median(hi *= 2);
  }
  Match best = std::abs(mlo - target) <= std::abs(mhi - target) ? Match{lo, mlo} : Match{hi, mhi};
  for (int it = 0; it < 40 && hi / lo > 1.0001; ++it) {
    const double mid = std::sqrt(lo * hi), m = median(mid);
    if (std::abs(m - target) < std::abs(best.median - target)) best = {mid, m};
    (m < target ? lo : hi) = mid;
  }
  return best;
}

DrawnMesh Soar::mesh(const std::vector<std::uint32_t>& strip) const {
  DrawnMesh out;
  auto corner = [&](std::uint32_t i) {
    return glm::dvec3(double(i % size_), offset_ + double(vertices_[i].y), double(i / size_));
  };
  for (std::size_t t = 0; t + 2 < strip.size(); ++t) {
    const std::uint32_t a = strip[t], b = strip[t + 1], c = strip[t + 2];
    if (a == b || b == c || a == c) continue;
    out.add(corner(a), corner(b), corner(c));
  }
  return out;
}

}  // namespace ridgeline::bench
