// Camera: what a view is tessellated for (SPEC.md, camera paths).
#pragma once

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "ridgeline/result.h"

namespace ridgeline {

/// A perspective camera in world coordinates (double precision, metres).
struct Camera {
  glm::dvec3 eye{0, 100, 0};
  glm::dvec3 target{0, 0, 100};
  glm::dvec3 up{0, 1, 0};          ///< must not be parallel to target - eye
  double fov_y_deg = 60.0;         ///< vertical field of view, degrees, in (0, 180)
  glm::ivec2 viewport{1280, 720};  ///< pixels, both >= 1
  double near_m = 0.5;     ///< near plane distance (metres, > 0); not used for culling terrain
  double far_m = 50000.0;  ///< far plane distance (metres, > near)
};

/// Checks a camera: finite values, eye != target, up not parallel to the view direction, a field
/// of view in (0, 180) degrees, a viewport of at least 1 x 1, 0 < near < far.
Status validate_camera(const Camera& camera);

/// Pixels per metre at unit distance: viewport_height / (2 tan(fov_y / 2)). A world-space error e
/// at distance d projects to e * projection_scale / d pixels (SPEC.md, projected bound).
double projection_scale(const Camera& camera);

}  // namespace ridgeline
