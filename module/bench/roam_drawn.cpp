// ROAM's mesh as drawn (roam_drawn.h).
#include "ridgeline/bench/roam_drawn.h"

#include <glm/geometric.hpp>

namespace ridgeline::bench {

double roam_drawn_y(const MeshVertex& v, const glm::dvec3& world, const Camera& camera,
                    double threshold_px, const Geomorph& geomorph, bool morph) {
  if (!morph || !(threshold_px > 0)) return world.y;
  // The vertex shader's formula, morphed_height() of roam_view.h, with the eye in the patch's
  // local frame (the vertex's world position minus its local one is the patch origin).
  const glm::dvec3 origin = world - glm::dvec3(v.x, v.y, v.z);
  const glm::vec3 eye_local(camera.eye - origin);
  return origin.y + double(morphed_height(v, eye_local, projection_scale(camera), threshold_px,
                                          geomorph));
}

RoamSnapshot RoamSnapshot::capture(RoamView& view) {
  RoamSnapshot s;
  s.threshold_px_ =
      view.settings().metric == ErrorMetric::kScreenPixels ? view.settings().threshold : 0.0;
  s.geomorph_ = view.landscape().geomorph();
  s.corners_.reserve(std::size_t(view.triangle_count()) * 3);
  const Landscape& l = view.landscape();
  for (std::uint32_t p = 0; p < l.patch_count(); ++p) {
    const PatchMesh& m = view.patch_mesh(p);
    for (std::uint32_t index : m.indices) {
      const MeshVertex& v = m.vertices[index];
      s.corners_.push_back({{m.origin_x + v.x, m.origin_y + v.y, m.origin_z + v.z}, v});
    }
  }
  return s;
}

DrawnMesh RoamSnapshot::draw(const MeshErrorMeter& meter, const Camera& camera, bool morph) const {
  DrawnMesh out;
  out.corners.reserve(corners_.size());
  for (const Corner& c : corners_)
    out.corners.emplace_back((c.world.x - meter.origin_x()) / meter.spacing_x(),
                             roam_drawn_y(c.vertex, c.world, camera, threshold_px_, geomorph_, morph),
                             (c.world.z - meter.origin_z()) / meter.spacing_z());
  return out;
}

}  // namespace ridgeline::bench
