// ROAM's mesh as a renderer draws it, for the measurement: the patch meshes with their geomorph
// data, captured after an update and drawn later for any camera (the pop metric draws the previous
// frame's mesh with the current camera; docs/report_method.md, "Popping").
//
// The geomorphed height of a vertex is computed in ONE place, roam_drawn_y(): when the core's
// MeshVertex or its shader formula changes, that function is the only one to follow.
#pragma once

#include <cstdint>
#include <vector>

#include "ridgeline/camera.h"
#include "ridgeline/mesh_error.h"
#include "ridgeline/roam_view.h"

namespace ridgeline::bench {

/// World height at which a renderer draws patch vertex `v` of a mesh whose origin is at height
/// `origin_y`, for `camera` at the view's threshold `threshold_px` and the landscape's geomorph
/// parameters: the vertex shader's formula (morphed_height(), docs/roam.md, geomorphs) when `morph`
/// and threshold_px > 0, else the vertex's true height. `world` is the vertex's unmorphed world
/// position.
double roam_drawn_y(const MeshVertex& v, const glm::dvec3& world, const Camera& camera,
                    double threshold_px, const Geomorph& geomorph, bool morph);

/// The patch meshes of a view as captured after one update: each drawn triangle's three vertices
/// (the MeshVertex as the renderer holds it, and its world position). Drawing it for a camera
/// applies roam_drawn_y() to every corner.
class RoamSnapshot {
 public:
  RoamSnapshot() = default;
  /// Captures every patch mesh of `view` (regenerating dirty ones: RoamView::patch_mesh), at the
  /// view's current threshold. Triangles over the padding are kept (the measurement reads only
  /// the sampled area).
  static RoamSnapshot capture(RoamView& view);
  /// The captured mesh drawn for `camera` (geomorphed when `morph`), in lattice units of
  /// `meter` (which must share the view's terrain origin).
  DrawnMesh draw(const MeshErrorMeter& meter, const Camera& camera, bool morph) const;
  std::size_t triangles() const noexcept { return corners_.size() / 3; }

 private:
  struct Corner {
    glm::dvec3 world;  // unmorphed world position
    MeshVertex vertex;
  };
  std::vector<Corner> corners_;
  double threshold_px_ = 0;
  Geomorph geomorph_;
};

}  // namespace ridgeline::bench
