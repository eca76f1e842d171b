// Vehicle: a Bullet rigid body (the chassis box) on four raycast-suspension wheels
// (btRaycastVehicle), in the game's Physics world on the Ridgeline shape: the wheels' rays are
// Ridgeline's raycast, the chassis collides with the terrain's finest triangles, with the other
// vehicles and with the loose bodies.
#pragma once

#include <array>
#include <cstdint>
#include <glm/gtc/quaternion.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <memory>
#include <vector>

#include "physics.h"
#include "ridgeline/terrain.h"
#include "vehicle_model.h"

class btRigidBody;

namespace game {

/// Physical constants of a vehicle kind. Units: kg, metres, newtons, seconds, radians.
struct VehicleParams {
  double mass = 1500;
  glm::dvec3 inertia_extent{2, 1.5, 4};  ///< box whose inertia the body takes (w, h, length)
  std::array<glm::dvec3, 4> attach{};    ///< suspension tops in the body frame (from the COM)
  double wheel_radius = 0.5;
  double rest_length = 0.35;         ///< suspension length (attach -> wheel centre) with no load
  double spring_k = 40000;           ///< N/m per wheel
  double damper_c = 4000;            ///< N s/m per wheel
  double friction = 1.0;             ///< tyre friction coefficient (friction circle radius / load)
  double engine_force = 9000;        ///< N at full throttle, shared by the four wheels
  double brake_force = 14000;        ///< N at full brake, shared by the four wheels
  double max_steer = 0.55;           ///< radians at steer = +-1
  double max_speed = 25;             ///< m/s; the engine gives no force above it
  glm::dvec3 com_in_model{0, 1, 0};  ///< centre of mass in the model frame (the body origin)
  /// The chassis' collision box in the body frame (from the COM): the frame down to the wheel
  /// centres (the wheels below it are rays).
  glm::dvec3 chassis_min{-1, -0.5, -2}, chassis_max{1, 0.5, 2};
};

/// Derives parameters from a model: wheels from its wheel nodes, inertia and chassis box from its
/// body box, mass from `mass_kg`; suspension sized so the static sag is about a third of the
/// travel.
VehicleParams params_from_model(const VehicleModel& model, double mass_kg);

/// Driver input. throttle -1..1 (negative: reverse), steer -1..1 (positive: left), brake 0..1.
struct Controls {
  double throttle = 0, steer = 0, brake = 0;
};

/// State of one wheel after a step.
struct WheelState {
  glm::dvec3 centre{0};         ///< world position of the wheel centre
  glm::dvec3 contact_point{0};  ///< where the suspension ray met the ground (valid with contact)
  glm::dvec3 contact_normal{0, 1, 0};
  bool contact = false;
  double suspension_length = 0;  ///< metres, 0 .. rest_length
  double load_n = 0;             ///< suspension force, newtons
  double steer = 0;              ///< radians
  double spin = 0;               ///< accumulated rotation, radians (for drawing)
  /// Height of the wheel's lowest point (centre - up * radius) above the surface at that point's
  /// xz, measured with Terrain::height after the step: about 0 in contact, positive in the air,
  /// negative when the wheel sinks in. Set by Vehicle::measure_contacts().
  double surface_gap = 0;
  std::uint8_t material = 0;  ///< material id under the wheel (valid with contact)
};

/// A vehicle in a Physics world. Positions in world metres (double precision); the body frame is
/// +y up, +z forward, +x to the left. Removed from the world when destroyed; move-only. Not
/// thread-safe (the game's thread).
class Vehicle {
 public:
  /// Adds the chassis and its raycast vehicle to `physics` at `position` (the centre of mass),
  /// facing `heading_rad`. `physics` must outlive the vehicle.
  Vehicle(Physics& physics, const VehicleParams& params, glm::dvec3 position, double heading_rad);
  ~Vehicle();
  Vehicle(Vehicle&&) noexcept;
  Vehicle& operator=(Vehicle&&) noexcept;

  /// Read by the vehicle at each Bullet step (engine, brakes, steering).
  Controls controls;
  const VehicleParams& params() const noexcept { return params_; }
  glm::dvec3 position() const noexcept;  ///< centre of mass
  glm::dquat orientation() const noexcept;
  glm::dvec3 velocity() const noexcept;
  glm::dvec3 forward() const noexcept { return orientation() * glm::dvec3(0, 0, 1); }
  glm::dvec3 up() const noexcept { return orientation() * glm::dvec3(0, 1, 0); }
  double heading() const noexcept;  ///< radians, 0 = +z, positive towards +x
  double speed() const noexcept;    ///< signed forward speed, m/s
  const std::array<WheelState, 4>& wheels() const noexcept { return wheels_; }
  /// Moves the body (teleport): velocities cleared, suspension reset, contacts dropped.
  void place(glm::dvec3 position, double heading_rad);
  /// Teleports to (x, z) with the given heading, tilted to the surface normal there and lifted
  /// so that the wheels just touch: how vehicles are spawned on slopes. False off-terrain.
  bool place_on_surface(double x, double z, double heading_rad);
  /// Updates every wheel's state (WheelState, surface_gap and material from the terrain's
  /// queries) and the ground under the suspension tops for follow_ground(): after each step.
  void measure_contacts();
  /// The terrain was edited under the body since the last measure_contacts(): where the ground
  /// under its suspension tops rose, the chassis rises by the largest rise (velocity and tilt
  /// kept, so it keeps resting instead of being launched by fully compressed springs); where it
  /// fell, the body is left to fall. Returns the lift, metres.
  double follow_ground();

  /// Material id under most of the wheels in contact at the last measure_contacts() (0 when no
  /// wheel touches).
  std::uint8_t ground_material() const noexcept { return ground_material_; }
  /// The chassis rigid body (for contact queries; the game tags it with the vehicle's id).
  const btRigidBody* chassis() const noexcept;
  btRigidBody* chassis() noexcept;
  /// Contacts with other vehicles so far (counted by the game at the start of each touch).
  std::uint64_t collisions = 0;
  /// Loose bodies (boulders, debris) that hit it so far (likewise).
  std::uint64_t body_hits = 0;

 private:
  struct Parts;
  Physics* physics_ = nullptr;
  VehicleParams params_;
  std::unique_ptr<Parts> parts_;
  std::array<WheelState, 4> wheels_{};
  std::uint8_t ground_material_ = 0;
  // Ground under the four suspension tops at the last measure_contacts() (height NaN
  // off-terrain).
  struct GroundPoint {
    double x = 0, z = 0, height = 0;
  };
  std::array<GroundPoint, 4> ground_{};
};

/// Steers a vehicle along waypoints (pure pursuit on the xz plane).
struct Autopilot {
  std::vector<glm::dvec2> waypoints;  ///< x, z
  std::size_t next = 0;               ///< index of the waypoint being approached
  double speed = 10;                  ///< m/s wanted
  double reach = 10;                  ///< metres: a waypoint within this is reached
  bool loop = false;
  bool active = false;
  std::uint64_t reached = 0;  ///< waypoints reached so far (counts laps when looping)
  /// Sets the vehicle's controls for this step. Returns true when a waypoint was reached.
  bool drive(Vehicle& v);
};

}  // namespace game
