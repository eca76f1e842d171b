// The game's terrain materials: what a material id of the surface (Terrain queries return it per
// stored cell) looks like and how much grip it gives. The default terrain's ids are listed in
// ridgeline/heightfield.h (make_default_heightfield).
#pragma once

#include <cstdint>

namespace game {

struct Material {
  const char* name;
  float albedo[3];  ///< linear RGB, 0..1, before lighting
  /// Multiplies a tyre's friction coefficient (VehicleParams::friction): 1 on grass, where the
  /// vehicles were tuned; below 1 slips earlier (sand, mud, snow).
  double friction;
};

/// Ids 0 .. kMaterialCount - 1 are known: 0 grass, 1 rock, 2 sand, 3 snow, 4 mud, 5 gravel.
inline constexpr int kMaterialCount = 6;

/// The material of `id`; an unknown id gets a neutral grey with friction 1 ("unknown").
const Material& material(std::uint8_t id) noexcept;

}  // namespace game
