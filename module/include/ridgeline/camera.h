// Camera: what a view is tessellated for (one frame of a camera path, docs/cli.md).
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

/// The view frustum of a camera, as every part of Ridgeline culls and measures with it: in front
/// of the eye, inside the four side planes through the eye, and within `far_m` of the eye. There
/// is no near plane: terrain between the eye and the near plane counts as in view (the level of
/// detail must not drop there, and a measurement must not skip it).
///
/// Plain data, built once per camera; every method is const and safe from any thread.
struct Frustum {
  /// Builds the frustum of a camera that passed validate_camera() (otherwise the planes are NaN
  /// and every test answers false).
  explicit Frustum(const Camera& camera);

  glm::dvec3 eye{0};      ///< world position of the eye, metres
  glm::dvec3 forward{0};  ///< unit view direction
  glm::dvec3 right{0};    ///< unit, forward x up
  glm::dvec3 up{0};       ///< unit, right x forward
  double tan_v = 1;       ///< tan(fov_y / 2)
  double tan_h = 1;       ///< tan_v * viewport width / height
  double far_m = 0;       ///< far distance, metres (a sphere around the eye, not a plane)
  double scale = 1;       ///< projection_scale(camera): pixels per metre at 1 m
  /// Inward unit normals of the side planes, all through the eye: left, right, bottom, top.
  glm::dvec3 planes[4];

  /// True when world point `p` lies inside (borders included). `distance`, when given, receives
  /// |p - eye| in metres.
  bool contains(const glm::dvec3& p, double* distance = nullptr) const noexcept;

  /// How a volume lies against the frustum.
  enum class Cull { kOut, kPartial, kIn };
  /// Classifies the world box [lo, hi]: kOut only when it is certainly outside (a side plane
  /// leaves it wholly behind, or its nearest point is beyond far_m); kIn when it is wholly inside
  /// the side planes and within far_m; kPartial otherwise. Conservative: kOut is never wrong.
  Cull classify_box(const glm::dvec3& lo, const glm::dvec3& hi) const noexcept;
  /// Classifies the sphere (world centre, radius in metres), as classify_box().
  Cull classify_sphere(const glm::dvec3& centre, double radius) const noexcept;
};

/// Pixels per metre at unit distance: viewport_height / (2 tan(fov_y / 2)). A world-space error e
/// at distance d projects to e * projection_scale / d pixels (docs/surface.md, "Error and
/// budgets": the projected bound).
double projection_scale(const Camera& camera);

}  // namespace ridgeline
