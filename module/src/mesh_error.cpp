// Measured error and popping of drawn meshes over a fixed sample of lattice vertices
// (mesh_error.h; definitions in docs/report_method.md). Any drawn mesh: nothing here knows the
// tessellator (a view's leaves become a DrawnMesh in leaves_mesh.cpp).
#include "ridgeline/mesh_error.h"

#include <algorithm>
#include <cmath>
#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <limits>

namespace ridgeline {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::uint32_t sampled(std::int64_t lattice, std::uint32_t stride) {
  return lattice > 0 ? static_cast<std::uint32_t>((lattice - 1) / stride + 1) : 0;
}
}  // namespace

MeshErrorMeter::MeshErrorMeter(const Terrain& terrain, std::uint32_t stride)
    : terrain_(&terrain), stride_(std::max<std::uint32_t>(stride, 1)) {
  const SurfaceLattice& at = terrain.surface().lattice();
  init(at.vertices_x, at.vertices_z, at.spacing_x, at.spacing_z, at.origin_x, at.origin_z,
       at.height_offset);
}

MeshErrorMeter::MeshErrorMeter(const Heightfield& hf, std::uint32_t stride)
    : heightfield_(&hf), stride_(std::max<std::uint32_t>(stride, 1)) {
  init(hf.width(), hf.height(), hf.spacing_x(), hf.spacing_z(), hf.origin_x(), hf.origin_z(),
       hf.height_offset());
}

void MeshErrorMeter::init(std::int64_t width, std::int64_t height, double sx, double sz,
                          double ox, double oz, double offset) {
  width_ = width;
  height_ = height;
  spacing_x_ = sx;
  spacing_z_ = sz;
  origin_x_ = ox;
  origin_z_ = oz;
  offset_ = offset;
  nx_ = sampled(width_, stride_);
  nz_ = sampled(height_, stride_);
  surface_.assign(std::size_t(nx_) * nz_, 0.0);
  if (nx_ && nz_) read(0, 0, nx_ - 1, nz_ - 1);
}

void MeshErrorMeter::read(std::uint32_t k0, std::uint32_t l0, std::uint32_t k1, std::uint32_t l1) {
  for (std::uint32_t l = l0; l <= l1; ++l)
    for (std::uint32_t k = k0; k <= k1; ++k) {
      const std::int64_t i = std::int64_t(k) * stride_, j = std::int64_t(l) * stride_;
      const double local = terrain_ ? terrain_->surface().vertex_height(i, j)
                                    : double(heightfield_->local(static_cast<std::uint32_t>(i),
                                                                 static_cast<std::uint32_t>(j)));
      surface_[k + std::size_t(l) * nx_] = offset_ + local;
    }
}

void MeshErrorMeter::refresh(std::int64_t i0, std::int64_t j0, std::int64_t i1, std::int64_t j1) {
  if (!nx_ || !nz_) return;
  const std::int64_t s = stride_;
  const std::int64_t k0 = std::max<std::int64_t>(0, (std::max<std::int64_t>(i0, 0) + s - 1) / s);
  const std::int64_t l0 = std::max<std::int64_t>(0, (std::max<std::int64_t>(j0, 0) + s - 1) / s);
  const std::int64_t k1 = std::min<std::int64_t>(nx_ - 1, i1 < 0 ? -1 : i1 / s);
  const std::int64_t l1 = std::min<std::int64_t>(nz_ - 1, j1 < 0 ? -1 : j1 / s);
  if (k0 > k1 || l0 > l1) return;
  read(std::uint32_t(k0), std::uint32_t(l0), std::uint32_t(k1), std::uint32_t(l1));
}

glm::dvec3 MeshErrorMeter::position(std::uint32_t k, std::uint32_t l) const noexcept {
  return {origin_x_ + double(std::int64_t(k) * stride_) * spacing_x_,
          surface_[k + std::size_t(l) * nx_],
          origin_z_ + double(std::int64_t(l) * stride_) * spacing_z_};
}

DrawnHeights MeshErrorMeter::rasterize(const DrawnMesh& mesh) const {
  DrawnHeights out;
  rasterize(mesh, out);
  return out;
}

void MeshErrorMeter::rasterize(const DrawnMesh& mesh, DrawnHeights& out) const {
  out.heights.assign(std::size_t(nx_) * nz_, kNaN);
  if (!nx_ || !nz_) return;
  const double s = stride_;
  for (std::size_t t = 0; t + 2 < mesh.corners.size(); t += 3) {
    const glm::dvec3 &a = mesh.corners[t], &b = mesh.corners[t + 1], &c = mesh.corners[t + 2];
    const double area = (b.x - a.x) * (c.z - a.z) - (b.z - a.z) * (c.x - a.x);
    if (!(std::abs(area) >= 1e-12)) continue;  // zero xz area (or NaN): covers nothing
    const double umin = std::min({a.x, b.x, c.x}), umax = std::max({a.x, b.x, c.x});
    const double vmin = std::min({a.z, b.z, c.z}), vmax = std::max({a.z, b.z, c.z});
    if (umax < 0 || vmax < 0) continue;
    const auto k0 = static_cast<std::int64_t>(std::max(0.0, std::ceil(umin / s - 1e-9)));
    const auto k1 = std::min<std::int64_t>(nx_ - 1, std::int64_t(std::floor(umax / s + 1e-9)));
    const auto l0 = static_cast<std::int64_t>(std::max(0.0, std::ceil(vmin / s - 1e-9)));
    const auto l1 = std::min<std::int64_t>(nz_ - 1, std::int64_t(std::floor(vmax / s + 1e-9)));
    // Barycentric weights signed by the winding; a vertex on an edge (within a relative 1e-9 of
    // the area) counts as covered.
    const double sgn = area > 0 ? 1.0 : -1.0, tol = 1e-9 * std::abs(area);
    for (std::int64_t l = l0; l <= l1; ++l) {
      const double v = double(l) * s;
      for (std::int64_t k = k0; k <= k1; ++k) {
        double& h = out.heights[std::size_t(k) + std::size_t(l) * nx_];
        if (!std::isnan(h)) continue;
        const double u = double(k) * s;
        const double wa = (b.x - u) * (c.z - v) - (b.z - v) * (c.x - u);
        const double wb = (c.x - u) * (a.z - v) - (c.z - v) * (a.x - u);
        const double wc = (a.x - u) * (b.z - v) - (a.z - v) * (b.x - u);
        if (wa * sgn < -tol || wb * sgn < -tol || wc * sgn < -tol) continue;
        h = (wa * a.y + wb * b.y + wc * c.y) / area;
      }
    }
  }
}

MeshError MeshErrorMeter::finish(std::vector<float>& px, double sum2, MeshError out) const {
  const std::uint64_t covered = out.vertices - out.uncovered;
  if (covered) out.rms_m = std::sqrt(sum2 / double(covered));
  if (!px.empty()) {
    const std::size_t q = std::min(px.size() - 1, px.size() * 99 / 100);
    std::nth_element(px.begin(), px.begin() + std::ptrdiff_t(q), px.end());
    out.p99_px = px[q];
    out.max_px = *std::max_element(px.begin(), px.end());
  }
  return out;
}

MeshError MeshErrorMeter::measure(const DrawnHeights& drawn, const Camera& camera) const {
  MeshError out;
  if (drawn.heights.size() != surface_.size() || !validate_camera(camera)) return out;
  const Frustum f(camera);
  double sum2 = 0;
  std::vector<float> px;
  for (std::uint32_t l = 0; l < nz_; ++l)
    for (std::uint32_t k = 0; k < nx_; ++k) {
      const glm::dvec3 p = position(k, l);
      double d = 0;
      if (!f.contains(p, &d)) continue;
      ++out.vertices;
      const double h = drawn.heights[k + std::size_t(l) * nx_];
      if (std::isnan(h)) {
        ++out.uncovered;
        continue;
      }
      const double e = std::abs(h - p.y);
      out.max_m = std::max(out.max_m, e);
      sum2 += e * e;
      px.push_back(static_cast<float>(d > 0 ? e * f.scale / d : 0.0));
    }
  return finish(px, sum2, out);
}

MeshError MeshErrorMeter::measure_all(const DrawnHeights& drawn) const {
  MeshError out;
  if (drawn.heights.size() != surface_.size()) return out;
  double sum2 = 0;
  std::vector<float> px;
  for (std::size_t n = 0; n < surface_.size(); ++n) {
    ++out.vertices;
    const double h = drawn.heights[n];
    if (std::isnan(h)) {
      ++out.uncovered;
      continue;
    }
    const double e = std::abs(h - surface_[n]);
    out.max_m = std::max(out.max_m, e);
    sum2 += e * e;
  }
  return finish(px, sum2, out);
}

double MeshErrorMeter::jump_px(const DrawnHeights& before, const DrawnHeights& now,
                               const Camera& camera, const Camera* before_camera) const {
  if (before.heights.size() != surface_.size() || now.heights.size() != surface_.size() ||
      !validate_camera(camera) || (before_camera && !validate_camera(*before_camera)))
    return 0.0;
  const Frustum f(camera);
  const Frustum fb(before_camera ? *before_camera : camera);
  double worst = 0;
  for (std::uint32_t l = 0; l < nz_; ++l)
    for (std::uint32_t k = 0; k < nx_; ++k) {
      const std::size_t at = k + std::size_t(l) * nx_;
      const double a = before.heights[at], b = now.heights[at];
      if (std::isnan(a) || std::isnan(b) || a == b) continue;
      const glm::dvec3 p = position(k, l);
      double d = 0;
      if (!f.contains(p, &d) || !(d > 0) || (before_camera && !fb.contains(p))) continue;
      worst = std::max(worst, std::abs(b - a) * f.scale / d);
    }
  return worst;
}

std::uint64_t MeshErrorMeter::triangles_in_view(const DrawnMesh& mesh, const Camera& camera) const {
  if (!validate_camera(camera)) return 0;
  const Frustum f(camera);
  std::uint64_t n = 0;
  const double last_u = double(width_ - 1), last_v = double(height_ - 1);
  for (std::size_t t = 0; t + 2 < mesh.corners.size(); t += 3) {
    const glm::dvec3 &p = mesh.corners[t], &q = mesh.corners[t + 1], &r = mesh.corners[t + 2];
    // Not drawn: degenerate slots of a renderer's buffers (zero xz area), and triangles over
    // the padding, wholly beyond the lattice's last row or column.
    const double area2 = (q.x - p.x) * (r.z - p.z) - (q.z - p.z) * (r.x - p.x);
    if (area2 == 0.0) continue;
    if (std::min({p.x, q.x, r.x}) >= last_u || std::min({p.z, q.z, r.z}) >= last_v) continue;
    const glm::dvec3 a = to_world(p), b = to_world(q), c = to_world(r);
    n += f.classify_box(glm::min(a, glm::min(b, c)), glm::max(a, glm::max(b, c))) !=
         Frustum::Cull::kOut;
  }
  return n;
}

}  // namespace ridgeline
