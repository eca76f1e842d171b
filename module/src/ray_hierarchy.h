// Private: the max-height pyramid that raycasts descend (see ray_hierarchy.cpp).
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include <glm/vec3.hpp>

#include "ridgeline/heightfield.h"
#include "ridgeline/terrain.h"

namespace ridgeline {

class RayHierarchy {
 public:
  explicit RayHierarchy(const Heightfield& hf);
  std::size_t memory_bytes() const noexcept;
  std::optional<RayHit> raycast(const Heightfield& hf, const glm::dvec3& origin,
                                const glm::dvec3& direction, double max_distance) const noexcept;

 private:
  std::vector<std::vector<float>> levels_;
};

}  // namespace ridgeline
