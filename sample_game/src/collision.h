// Contacts between vehicles: each body is its chassis box (Vehicle::chassis_min/max), tested as
// an oriented rectangle on the ground plane (separating axes) with an overlap of the boxes'
// height ranges; a contact gets an impulse (restitution and Coulomb friction at the contact
// point, with the bodies' masses and inertias) and a position correction along the normal.
#pragma once

#include <cstddef>
#include <map>

#include "game_api.h"

namespace game {

/// One contact found between two vehicles.
struct VehicleContact {
  int a = 0, b = 0;      ///< vehicle ids
  glm::dvec3 normal{0};  ///< unit, horizontal, from a to b
  glm::dvec3 point{0};   ///< world position of the contact
  double depth = 0;      ///< overlap along the normal, metres
};

/// Finds the overlapping pairs among `vehicles` and resolves them (velocities and positions);
/// counts a collision on both bodies of a pair that was not touching in `touching` (the set of
/// pairs touching after the previous call, updated). Returns the number of contacts this call.
std::size_t resolve_vehicle_contacts(std::map<int, VehicleEntry>& vehicles,
                                     std::map<std::pair<int, int>, bool>& touching);

/// The contact between two bodies, if their boxes overlap (exposed for tests).
bool find_contact(const Vehicle& a, const Vehicle& b, VehicleContact& out);

}  // namespace game
