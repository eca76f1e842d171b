// Raycasts against the surface (placeholder: being written).
#include "ray_hierarchy.h"

namespace ridgeline {

RayHierarchy::RayHierarchy(const Heightfield&) {}
std::size_t RayHierarchy::memory_bytes() const noexcept { return 0; }
std::optional<RayHit> RayHierarchy::raycast(const Heightfield&, const glm::dvec3&,
                                            const glm::dvec3&, double) const noexcept {
  return std::nullopt;
}

std::optional<RayHit> Terrain::raycast(const glm::dvec3& origin, const glm::dvec3& direction,
                                       double max_distance) const noexcept {
  return rays_->raycast(heightfield_, origin, direction, max_distance);
}

std::size_t Terrain::triangles_in_box(const Box&, std::vector<SurfaceTriangle>&,
                                      std::size_t) const {
  return 0;
}

}  // namespace ridgeline
