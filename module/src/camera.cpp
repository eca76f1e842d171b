#include "ridgeline/camera.h"

#include <cmath>
#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "format.h"

namespace ridgeline {

Status validate_camera(const Camera& c) {
  auto finite3 = [](const glm::dvec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
  };
  if (!finite3(c.eye) || !finite3(c.target) || !finite3(c.up))
    return Error{"camera: eye, target and up must be finite"};
  const glm::dvec3 f = c.target - c.eye;
  if (glm::length(f) <= 0.0) return Error{"camera: eye and target are the same point"};
  if (glm::length(c.up) <= 0.0 ||
      glm::length(glm::cross(glm::normalize(f), glm::normalize(c.up))) < 1e-9)
    return Error{"camera: up is zero or parallel to the view direction"};
  if (!(c.fov_y_deg > 0.0 && c.fov_y_deg < 180.0))
    return Error{fmt("camera: fov_y %s degrees; need (0, 180)", num(c.fov_y_deg).c_str())};
  if (c.viewport.x < 1 || c.viewport.y < 1)
    return Error{fmt("camera: viewport %d x %d; need at least 1 x 1", c.viewport.x, c.viewport.y)};
  if (!(c.near_m > 0.0 && c.far_m > c.near_m && std::isfinite(c.far_m)))
    return Error{fmt("camera: near %s, far %s; need 0 < near < far, finite", num(c.near_m).c_str(),
                     num(c.far_m).c_str())};
  return {};
}

Frustum::Frustum(const Camera& c) : eye(c.eye), far_m(c.far_m), scale(projection_scale(c)) {
  forward = glm::normalize(c.target - c.eye);
  right = glm::normalize(glm::cross(forward, c.up));
  up = glm::cross(right, forward);
  tan_v = std::tan(c.fov_y_deg * 3.14159265358979323846 / 360.0);
  tan_h = tan_v * double(c.viewport.x) / double(c.viewport.y);
  planes[0] = glm::normalize(tan_h * forward + right);  // left
  planes[1] = glm::normalize(tan_h * forward - right);  // right
  planes[2] = glm::normalize(tan_v * forward + up);     // bottom
  planes[3] = glm::normalize(tan_v * forward - up);     // top
}

bool Frustum::contains(const glm::dvec3& p, double* distance) const noexcept {
  const glm::dvec3 q = p - eye;
  const double z = glm::dot(q, forward);
  const double d = glm::length(q);
  if (distance != nullptr) *distance = d;
  return z > 0 && std::abs(glm::dot(q, right)) <= tan_h * z &&
         std::abs(glm::dot(q, up)) <= tan_v * z && d <= far_m;
}

Frustum::Cull Frustum::classify_box(const glm::dvec3& lo, const glm::dvec3& hi) const noexcept {
  const glm::dvec3 c = 0.5 * (lo + hi) - eye, he = 0.5 * (hi - lo);
  if (!(glm::length(glm::clamp(eye, lo, hi) - eye) <= far_m)) return Cull::kOut;
  bool all_in = true;
  for (const glm::dvec3& n : planes) {
    const double mid = glm::dot(n, c);
    const double ext = std::abs(n.x) * he.x + std::abs(n.y) * he.y + std::abs(n.z) * he.z;
    if (!(mid + ext >= 0.0)) return Cull::kOut;
    if (mid - ext < 0.0) all_in = false;
  }
  // Wholly within far_m: the farthest corner is.
  const glm::dvec3 far_corner = glm::abs(c) + he;
  if (glm::length(far_corner) > far_m) all_in = false;
  return all_in ? Cull::kIn : Cull::kPartial;
}

Frustum::Cull Frustum::classify_sphere(const glm::dvec3& centre, double radius) const noexcept {
  const glm::dvec3 c = centre - eye;
  const double d = glm::length(c);
  if (!(d - radius <= far_m)) return Cull::kOut;
  bool all_in = d + radius <= far_m;
  for (const glm::dvec3& n : planes) {
    const double s = glm::dot(n, c);
    if (!(s + radius >= 0.0)) return Cull::kOut;
    if (s - radius < 0.0) all_in = false;
  }
  return all_in ? Cull::kIn : Cull::kPartial;
}

double projection_scale(const Camera& c) {
  return c.viewport.y / (2.0 * std::tan(c.fov_y_deg * 3.14159265358979323846 / 360.0));
}

}  // namespace ridgeline
