// VehicleModel: a vehicle's meshes and wheel layout read from a glTF 2.0 file (tinygltf).
#pragma once

#include <array>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "ridgeline/result.h"

namespace game {

/// One vertex of a vehicle mesh in the vehicle's frame (metres; +y up, +z forward).
struct ModelVertex {
  float px, py, pz;
  float nx, ny, nz;
  float r, g, b;  ///< material base colour
};

struct ModelMesh {
  std::vector<ModelVertex> vertices;
  std::vector<std::uint32_t> indices;
};

/// What the game needs from a vehicle file (conventions in docs/game.md and
/// sample_game/tools/make_vehicles.cpp): the body mesh (every node that is not a wheel, with its
/// transform applied), the wheel mesh (in the wheel's own frame) and the four wheel centres.
struct VehicleModel {
  std::string name;
  ModelMesh body;
  ModelMesh wheel;
  /// Wheel centres at rest in the vehicle frame: front left, front right, rear left, rear right.
  std::array<glm::vec3, 4> wheel_centres{};
  float wheel_radius = 0.5f;  ///< metres, from the wheel mesh's extent around its axle (x)
  glm::vec3 body_min{0}, body_max{0};  ///< bounding box of the body mesh
};

/// Loads a .glb or .gltf. Errors name the file and the problem: unreadable, not glTF, no node
/// named wheel_fl/wheel_fr/wheel_rl/wheel_rr, a primitive that is not triangles, a POSITION or
/// NORMAL accessor that is not float VEC3, indices out of range.
ridgeline::Result<VehicleModel> load_vehicle_model(const std::string& path);

}  // namespace game
