#include "ridgeline/camera.h"

#include <cmath>
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

double projection_scale(const Camera& c) {
  return c.viewport.y / (2.0 * std::tan(c.fov_y_deg * 3.14159265358979323846 / 360.0));
}

}  // namespace ridgeline
