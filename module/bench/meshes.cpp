// The uniform grid and the CDLOD-like quadtree the benchmarks measure ROAM against (meshes.h).
#include "ridgeline/bench/meshes.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <limits>
#include <map>
#include <sstream>
#include <tuple>

namespace ridgeline::bench {

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kMorphStartRatio = 0.66;  // Strugar's default

double sq(double x) {
  return x * x;
}

// Appends the two triangles of every quad of a row-major (nx + 1) x (nz + 1) vertex grid, split
// along (0,0)-(1,1).
void triangulate_grid(const std::vector<glm::dvec3>& v, std::uint32_t nx, std::uint32_t nz,
                      DrawnMesh& out) {
  for (std::uint32_t b = 0; b < nz; ++b)
    for (std::uint32_t a = 0; a < nx; ++a) {
      const std::size_t r0 = std::size_t(b) * (nx + 1), r1 = r0 + nx + 1;
      const glm::dvec3 &p00 = v[a + r0], &p10 = v[a + 1 + r0], &p01 = v[a + r1],
                       &p11 = v[a + 1 + r1];
      out.add(p00, p11, p10);
      out.add(p00, p01, p11);
    }
}

glm::dvec3 to_world(const Grid& hf, const glm::dvec3& c) {
  return {hf.origin_x() + c.x * hf.spacing_x(), c.y, hf.origin_z() + c.z * hf.spacing_z()};
}
}  // namespace

double surface_height(const Grid& hf, double u, double v) {
  const double W = hf.width() - 1, H = hf.height() - 1;
  u = std::clamp(u, 0.0, W);
  v = std::clamp(v, 0.0, H);
  if (u == std::floor(u) && v == std::floor(v))
    return hf.world(static_cast<std::uint32_t>(u), static_cast<std::uint32_t>(v));
  const auto i = static_cast<std::uint32_t>(std::min(std::floor(u), W - 1));
  const auto j = static_cast<std::uint32_t>(std::min(std::floor(v), H - 1));
  const double fu = u - i, fv = v - j;
  const double h00 = hf.local(i, j), h10 = hf.local(i + 1, j), h01 = hf.local(i, j + 1),
               h11 = hf.local(i + 1, j + 1);
  double h;
  if (((i + j) & 1) == 0) {  // diagonal (0,0)-(1,1)
    h = fu >= fv ? h00 + fu * (h10 - h00) + fv * (h11 - h10)
                 : h00 + fv * (h01 - h00) + fu * (h11 - h01);
  } else {  // diagonal (1,0)-(0,1)
    h = fu + fv <= 1.0 ? h00 + fu * (h10 - h00) + fv * (h01 - h00)
                       : h11 + (1.0 - fu) * (h01 - h11) + (1.0 - fv) * (h10 - h11);
  }
  return hf.height_offset() + h;
}

// ---- uniform grid -----------------------------------------------------------------------

UniformGrid UniformGrid::for_triangles(const Grid& hf, double triangles) {
  const double ex = hf.extent_x(), ez = hf.extent_z();
  const double quads = std::max(1.0, triangles / 2.0);
  // nx / nz = ex / ez (square quads), nx * nz = quads; then the best integer pair near it.
  const double fx = std::sqrt(quads * ex / ez);
  UniformGrid best;
  double best_err = std::numeric_limits<double>::infinity();
  for (double cx : {std::floor(fx), std::ceil(fx)}) {
    const double nx = std::max(1.0, cx);
    for (double nz :
         {std::max(1.0, std::floor(quads / nx)), std::max(1.0, std::ceil(quads / nx))}) {
      const double err = std::abs(2.0 * nx * nz - triangles);
      if (err < best_err) {
        best_err = err;
        best.nx = static_cast<std::uint32_t>(nx);
        best.nz = static_cast<std::uint32_t>(nz);
      }
    }
  }
  return best;
}

std::vector<glm::dvec3> UniformGrid::vertices(const Grid& hf) const {
  const double W = hf.width() - 1, H = hf.height() - 1;
  std::vector<glm::dvec3> v(std::size_t(nx + 1) * (nz + 1));
  for (std::uint32_t b = 0; b <= nz; ++b)
    for (std::uint32_t a = 0; a <= nx; ++a) {
      const double u = a == nx ? W : W * a / nx, w = b == nz ? H : H * b / nz;
      v[a + std::size_t(b) * (nx + 1)] = {u, surface_height(hf, u, w), w};
    }
  return v;
}

std::size_t UniformGrid::resample(const Grid& hf, std::vector<glm::dvec3>& v, double u0,
                                  double v0, double u1, double v1) const {
  const double W = hf.width() - 1, H = hf.height() - 1;
  const auto a0 = static_cast<std::int64_t>(std::max(0.0, std::floor(u0 * nx / W)));
  const auto a1 = std::min<std::int64_t>(nx, std::int64_t(std::ceil(u1 * nx / W)));
  const auto b0 = static_cast<std::int64_t>(std::max(0.0, std::floor(v0 * nz / H)));
  const auto b1 = std::min<std::int64_t>(nz, std::int64_t(std::ceil(v1 * nz / H)));
  std::size_t n = 0;
  for (std::int64_t b = b0; b <= b1; ++b)
    for (std::int64_t a = a0; a <= a1; ++a, ++n) {
      glm::dvec3& p = v[std::size_t(a) + std::size_t(b) * (nx + 1)];
      p.y = surface_height(hf, p.x, p.z);
    }
  return n;
}

DrawnMesh UniformGrid::mesh_of(const std::vector<glm::dvec3>& v) const {
  DrawnMesh out;
  out.corners.reserve(std::size_t(triangles()) * 3);
  triangulate_grid(v, nx, nz, out);
  return out;
}

// ---- CDLOD ------------------------------------------------------------------------------

Cdlod::Cdlod(const Grid& hf, std::uint32_t grid)
    : hf_(hf), grid_(std::max<std::uint32_t>(2, grid & ~1u)) {
  cells_x_ = hf.width() - 1;
  cells_z_ = hf.height() - 1;
  levels_ = 1;
  while ((std::int64_t(grid_) << (levels_ - 1)) < std::max(cells_x_, cells_z_)) ++levels_;
  nodes_.resize(levels_);
  per_row_.resize(levels_);
  for (std::uint32_t L = 0; L < levels_; ++L) {
    const std::int64_t size = std::int64_t(grid_) << L;
    const std::int64_t nx = (cells_x_ + size - 1) / size, nz = (cells_z_ + size - 1) / size;
    per_row_[L] = nx;
    nodes_[L].resize(std::size_t(nx * nz));
    for (std::int64_t b = 0; b < nz; ++b)
      for (std::int64_t a = 0; a < nx; ++a) nodes_[L][std::size_t(a + b * nx)] = compute(L, a, b);
  }
  compute_min_r0();
}

Cdlod::Node Cdlod::compute(std::uint32_t L, std::int64_t a, std::int64_t b) const {
  const Grid& hf = hf_;
  const std::int64_t size = std::int64_t(grid_) << L;
  Node n{std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity()};
  if (L == 0) {
    for (std::int64_t j = b * size; j <= std::min((b + 1) * size, cells_z_); ++j)
      for (std::int64_t i = a * size; i <= std::min((a + 1) * size, cells_x_); ++i) {
        const float h = hf.local(std::uint32_t(i), std::uint32_t(j));
        n.lo = std::min(n.lo, h);
        n.hi = std::max(n.hi, h);
      }
    return n;
  }
  const std::int64_t rows = std::int64_t(nodes_[L - 1].size()) / per_row_[L - 1];
  for (int q = 0; q < 4; ++q) {
    const std::int64_t ca = 2 * a + (q & 1), cb = 2 * b + (q >> 1);
    if (ca >= per_row_[L - 1] || cb >= rows) continue;
    const Node& c = nodes_[L - 1][std::size_t(ca + cb * per_row_[L - 1])];
    n.lo = std::min(n.lo, c.lo);
    n.hi = std::max(n.hi, c.hi);
  }
  return n;
}

void Cdlod::refresh(std::int64_t i0, std::int64_t j0, std::int64_t i1, std::int64_t j1) {
  i0 = std::clamp<std::int64_t>(i0, 0, cells_x_);
  i1 = std::clamp<std::int64_t>(i1, 0, cells_x_);
  j0 = std::clamp<std::int64_t>(j0, 0, cells_z_);
  j1 = std::clamp<std::int64_t>(j1, 0, cells_z_);
  for (std::uint32_t L = 0; L < levels_; ++L) {
    const std::int64_t size = std::int64_t(grid_) << L;
    const std::int64_t rows = std::int64_t(nodes_[L].size()) / per_row_[L];
    // Closed footprints: a sample on a node border belongs to both nodes.
    for (std::int64_t b = std::max<std::int64_t>(0, (j0 - 1) / size);
         b <= std::min(rows - 1, j1 / size); ++b)
      for (std::int64_t a = std::max<std::int64_t>(0, (i0 - 1) / size);
           a <= std::min(per_row_[L] - 1, i1 / size); ++a)
        nodes_[L][std::size_t(a + b * per_row_[L])] = compute(L, a, b);
  }
  compute_min_r0();
}

void Cdlod::compute_min_r0() {
  // Smallest r0 for which a coarser neighbour's vertices are unmorphed where a finer chunk meets
  // it: the diagonal of every level-(L+1) node must fit in the band [range_L, start_{L+1}].
  min_r0_ = 0;
  for (std::uint32_t L = 0; L + 2 < levels_; ++L) {
    const std::int64_t size = std::int64_t(grid_) << (L + 1);
    for (std::size_t n = 0; n < nodes_[L + 1].size(); ++n) {
      const std::int64_t a = std::int64_t(n) % per_row_[L + 1],
                         b = std::int64_t(n) / per_row_[L + 1];
      glm::dvec3 lo, hi;
      box(L + 1, a * size, b * size, &lo, &hi);
      const double diag = glm::length(hi - lo);
      min_r0_ = std::max(min_r0_, diag / (kMorphStartRatio * double(1ull << L)));
    }
  }
}

const Cdlod::Node& Cdlod::node(std::uint32_t level, std::int64_t i0, std::int64_t j0) const {
  const std::int64_t size = std::int64_t(grid_) << level;
  return nodes_[level][std::size_t(i0 / size + (j0 / size) * per_row_[level])];
}

void Cdlod::box(std::uint32_t level, std::int64_t i0, std::int64_t j0, glm::dvec3* lo,
                glm::dvec3* hi) const {
  const std::int64_t size = std::int64_t(grid_) << level;
  const Node& n = node(level, i0, j0);
  const Grid& hf = hf_;
  *lo = {hf.origin_x() + double(i0) * hf.spacing_x(), hf.height_offset() + n.lo,
         hf.origin_z() + double(j0) * hf.spacing_z()};
  *hi = {hf.origin_x() + double(std::min(i0 + size, cells_x_)) * hf.spacing_x(),
         hf.height_offset() + n.hi,
         hf.origin_z() + double(std::min(j0 + size, cells_z_)) * hf.spacing_z()};
}

namespace {
bool sphere_meets_box(const glm::dvec3& c, double r, const glm::dvec3& lo, const glm::dvec3& hi) {
  const glm::dvec3 p = glm::clamp(c, lo, hi);
  return sq(p.x - c.x) + sq(p.y - c.y) + sq(p.z - c.z) <= r * r;
}
}  // namespace

bool Cdlod::select_node(std::uint32_t L, std::int64_t i0, std::int64_t j0, const Frustum& f,
                        const std::vector<double>& range, bool cull, Selection& out) const {
  if (i0 >= cells_x_ || j0 >= cells_z_) return true;  // nothing there
  glm::dvec3 lo, hi;
  box(L, i0, j0, &lo, &hi);
  if (L + 1 < levels_ && !sphere_meets_box(f.eye, range[L], lo, hi)) return false;
  if (cull && f.classify_box(lo, hi) == Frustum::Cull::kOut) return true;
  const std::int64_t half = (std::int64_t(grid_) << L) / 2;
  auto add = [&](std::uint8_t mask) {
    std::uint8_t m = 0;
    for (int q = 0; q < 4; ++q)
      if ((mask >> q & 1) && i0 + (q & 1) * half < cells_x_ && j0 + (q >> 1) * half < cells_z_)
        m |= std::uint8_t(1 << q);
    if (!m) return;
    out.chunks.push_back({L, i0, j0, m});
    out.triangles += std::uint64_t(__builtin_popcount(m)) * grid_ * grid_ / 2;
  };
  if (L == 0 || !sphere_meets_box(f.eye, range[L - 1], lo, hi)) {
    add(0xF);
    return true;
  }
  std::uint8_t mask = 0;
  for (int q = 0; q < 4; ++q)
    if (!select_node(L - 1, i0 + (q & 1) * half, j0 + (q >> 1) * half, f, range, cull, out))
      mask |= std::uint8_t(1 << q);
  add(mask);
  return true;
}

namespace {
std::vector<double> ranges(double r0, std::uint32_t levels) {
  std::vector<double> r(levels);
  for (std::uint32_t L = 0; L < levels; ++L) r[L] = r0 * double(1ull << L);
  return r;
}
}  // namespace

Cdlod::Selection Cdlod::select(const Camera& camera, double r0, bool cull) const {
  const Frustum f(camera);
  Selection s;
  s.r0 = std::max(r0, min_r0_);
  select_node(levels_ - 1, 0, 0, f, ranges(s.r0, levels_), cull, s);
  return s;
}

Cdlod::Match Cdlod::match(const std::vector<Camera>& frames, double target,
                          std::size_t step) const {
  step = std::max<std::size_t>(step, 1);
  auto median = [&](double r0) {
    std::vector<double> t;
    for (std::size_t k = 0; k < frames.size(); k += step)
      t.push_back(double(select(frames[k], r0).triangles));
    if (t.empty()) return 0.0;
    std::nth_element(t.begin(), t.begin() + std::ptrdiff_t(t.size() / 2), t.end());
    return t[t.size() / 2];
  };
  Match best{min_r0_, median(min_r0_)};
  auto consider = [&](double r0, double m) {
    if (std::abs(m - target) < std::abs(best.median - target)) best = {r0, m};
  };
  if (best.median >= target) return best;  // even the shortest ranges draw too much
  double lo = min_r0_, hi = std::max(min_r0_, 1e-3) * 2;
  double mhi = median(hi);
  while (mhi < target && hi < std::max(min_r0_, 1e-3) * 1e9) mhi = median(hi *= 2);
  consider(hi, mhi);
  for (int it = 0; it < 40 && hi / lo > 1.0001; ++it) {
    const double mid = std::sqrt(std::max(lo, 1e-6) * hi), m = median(mid);
    consider(mid, m);
    (m < target ? lo : hi) = mid;
  }
  return best;
}

void Cdlod::emit_quadrant(const Chunk& c, int q, const Frustum& f, bool morph,
                          const std::vector<double>& range, DrawnMesh& out) const {
  const Grid& hf = hf_;
  const std::uint32_t L = c.level, g = grid_ / 2;
  const std::int64_t s = std::int64_t(1) << L;
  const std::uint32_t gx0 = std::uint32_t(q & 1) * g, gz0 = std::uint32_t(q >> 1) * g;
  const double end = range[L], start = (L ? range[L - 1] : 0.0) +
                                       kMorphStartRatio * (range[L] - (L ? range[L - 1] : 0.0));
  std::vector<glm::dvec3> v(std::size_t(g + 1) * (g + 1));
  for (std::uint32_t b = 0; b <= g; ++b)
    for (std::uint32_t a = 0; a <= g; ++a) {
      const std::uint32_t gx = gx0 + a, gz = gz0 + b;
      const double u = double(c.i0 + std::int64_t(gx) * s), w = double(c.j0 + std::int64_t(gz) * s);
      double m = 0;
      if (morph && L + 1 < levels_) {
        const double uc = std::min(u, double(cells_x_)), wc = std::min(w, double(cells_z_));
        const glm::dvec3 p = to_world(hf, {uc, surface_height(hf, uc, wc), wc});
        m = std::clamp((glm::length(p - f.eye) - start) / (end - start), 0.0, 1.0);
      }
      const double mu = std::min(u - double(gx & 1) * double(s) * m, double(cells_x_));
      const double mw = std::min(w - double(gz & 1) * double(s) * m, double(cells_z_));
      v[a + std::size_t(b) * (g + 1)] = {mu, surface_height(hf, mu, mw), mw};
    }
  triangulate_grid(v, g, g, out);
}

DrawnMesh Cdlod::mesh(const Selection& s, const Camera& camera, bool morph) const {
  const Frustum f(camera);
  const auto r = ranges(s.r0, levels_);
  DrawnMesh out;
  out.corners.reserve(std::size_t(s.triangles) * 3);
  for (const Chunk& c : s.chunks)
    for (int q = 0; q < 4; ++q)
      if (c.quadrants >> q & 1) emit_quadrant(c, q, f, morph, r, out);
  return out;
}

std::uint64_t Cdlod::memory_bytes() const noexcept {
  std::uint64_t n = 0;
  for (const auto& l : nodes_) n += l.size() * sizeof(Node);
  return n + std::uint64_t(grid_ + 1) * (grid_ + 1) * 8 + std::uint64_t(grid_) * grid_ * 6 * 4 +
         std::uint64_t(hf_.width()) * hf_.height() * 4;
}

// ---- watertightness ---------------------------------------------------------------------

std::string check_watertight(const Grid& hf, const DrawnMesh& mesh) {
  using P = std::tuple<double, double, double>;
  std::map<std::pair<P, P>, int> edges;
  const double W = hf.width() - 1, H = hf.height() - 1;
  double area = 0;
  for (std::size_t t = 0; t + 2 < mesh.corners.size(); t += 3) {
    const glm::dvec3* c = &mesh.corners[t];
    // Triangles with two coincident corners are collapsed: nothing to match. Triangles of zero
    // xz area but distinct corners (a morphing column squeezed onto a line: vertical "skirts")
    // do join their neighbours' edges and are kept; they add no area.
    if (c[0] == c[1] || c[1] == c[2] || c[2] == c[0]) continue;
    const double a2 = (c[1].x - c[0].x) * (c[2].z - c[0].z) - (c[1].z - c[0].z) * (c[2].x - c[0].x);
    area += std::abs(a2) / 2;
    for (int e = 0; e < 3; ++e) {
      P p{c[e].x, c[e].y, c[e].z}, q{c[(e + 1) % 3].x, c[(e + 1) % 3].y, c[(e + 1) % 3].z};
      if (q < p) std::swap(p, q);
      ++edges[{p, q}];
    }
  }
  auto on_border = [&](const P& p, const P& q) {
    const double pu = std::get<0>(p), pv = std::get<2>(p), qu = std::get<0>(q), qv = std::get<2>(q);
    return (pu == qu && (pu == 0 || pu == W)) || (pv == qv && (pv == 0 || pv == H));
  };
  for (const auto& [e, n] : edges) {
    // Inside, an edge joins exactly two triangles; on the border the area sum below checks.
    const bool border = on_border(e.first, e.second);
    if (border ? n < 1 : n != 2) {
      std::ostringstream s;
      s.precision(17);
      s << "edge (" << std::get<0>(e.first) << ", " << std::get<1>(e.first) << ", "
        << std::get<2>(e.first) << ")-(" << std::get<0>(e.second) << ", " << std::get<1>(e.second)
        << ", " << std::get<2>(e.second) << ") is used by " << n << " triangles, expected 2";
      return s.str();
    }
  }
  if (std::abs(area - W * H) > 1e-9 * W * H) {
    std::ostringstream s;
    s.precision(17);
    s << "triangles cover " << area << " square cells, the area has " << W * H;
    return s.str();
  }
  return {};
}

}  // namespace ridgeline::bench
