// Physics: the game's Bullet world on the Ridgeline shape (Ridgeline::bullet): the terrain as a
// static body whose contacts and rays are the terrain's own queries (procedural detail and
// craters included, nothing rebuilt), the helper that follows edits, and the loose bodies
// (boulders and debris) scripts throw around. Vehicles (vehicle.h) live in the same world.
#pragma once

#include <cstdint>
#include <glm/gtc/quaternion.hpp>
#include <glm/vec3.hpp>
#include <memory>
#include <string>

#include "ridgeline/bullet/terrain_shape.h"
#include "ridgeline/bullet/terrain_sync.h"
#include "ridgeline/result.h"
#include "ridgeline/terrain.h"

class btDiscreteDynamicsWorld;
class btCollisionObject;
class btCollisionShape;
class btRigidBody;

namespace game {

/// Bullet collision groups of the game's objects (masks: everything collides with everything,
/// except that wheel rays see only the terrain and vehicles: a boulder under a wheel is pushed by
/// the chassis, not driven over).
enum CollisionGroup : int {
  kGroupTerrain = 1 << 6,
  kGroupVehicle = 1 << 7,
  kGroupBody = 1 << 8,
};

/// Seconds per internal Bullet step: the game's 1/60 s step is taken in two (120 Hz), which keeps
/// stiff truck suspensions stable.
inline constexpr double kPhysicsSubstep = 1.0 / 120.0;

/// The game's Bullet world. Positions cross it through the shape's origin (the middle of the
/// terrain): Bullet's floats stay within about 1.5 km of it. Friction follows the terrain's
/// material: the terrain's triangles carry their material id as Bullet's part id, and create()
/// installs Bullet's process-wide contact hook (gContactAddedCallback, a stateless function
/// every Physics shares) that scales a terrain contact's friction by it. Threading: the game's
/// thread.
class Physics {
 public:
  /// A world over `terrain` (kept alive). Errors: a null terrain.
  static ridgeline::Result<std::unique_ptr<Physics>> create(
      std::shared_ptr<ridgeline::Terrain> terrain);
  ~Physics();
  Physics(const Physics&) = delete;
  Physics& operator=(const Physics&) = delete;

  /// One game step of `dt` seconds (> 0): TerrainSync::update() (edits since the last step wake
  /// the bodies over them and drop their stale contacts), then Bullet in kPhysicsSubstep steps.
  void step(double dt);
  /// What the last step's sync did.
  const ridgeline::bullet::TerrainSyncStats& last_sync() const noexcept { return last_sync_; }

  btDiscreteDynamicsWorld& world() noexcept;
  const btCollisionObject* ground() const noexcept;
  const ridgeline::bullet::TerrainShape& shape() const noexcept { return *shape_; }
  const ridgeline::Terrain& terrain() const noexcept { return *terrain_; }
  /// World metres (double) to Bullet's local floats and back, through the shape's origin.
  btVector3 to_local(const glm::dvec3& world) const noexcept { return shape_->to_local(world); }
  glm::dvec3 to_world(const btVector3& local) const noexcept { return shape_->to_world(local); }

  /// Deepest penetration (metres, >= 0) between `a` and `b` among the contact points of the last
  /// step (0 when they do not touch).
  double penetration(const btCollisionObject* a, const btCollisionObject* b) const;
  /// Whether the last step left contact points between `a` and `b`.
  bool touching(const btCollisionObject* a, const btCollisionObject* b) const;

 private:
  Physics() = default;
  struct Parts;
  std::unique_ptr<Parts> parts_;
  std::shared_ptr<ridgeline::Terrain> terrain_;
  std::unique_ptr<ridgeline::bullet::TerrainShape> shape_;
  ridgeline::bullet::TerrainSyncStats last_sync_;
};

/// What a loose body is.
enum class BodyShape : std::uint8_t { kSphere, kBox };
/// "sphere" or "box".
const char* to_string(BodyShape shape) noexcept;

/// A loose body to spawn (game.spawn_body in Lua). Units: metres, kilograms, m/s, rad/s.
struct BodySpec {
  BodyShape shape = BodyShape::kSphere;
  /// Sphere: the radius (in x); box: half extents. Each 0.05 .. 5 m.
  glm::dvec3 size{0.6};
  glm::dvec3 position{0};          ///< world metres (centre of mass)
  glm::dvec3 velocity{0};          ///< m/s
  glm::dvec3 angular_velocity{0};  ///< rad/s
  /// Kilograms; 0: from the volume at 2,400 kg/m^3 (rock).
  double mass = 0;
  std::string name;
};

/// A boulder or a piece of debris: a Bullet rigid body in a Physics world, removed from it when
/// destroyed. Move-only.
class LooseBody {
 public:
  /// Adds the body to `physics` (spec checked by the caller: finite, sizes in range).
  LooseBody(Physics& physics, int id, const BodySpec& spec);
  ~LooseBody();
  LooseBody(LooseBody&&) noexcept;
  LooseBody& operator=(LooseBody&&) noexcept;

  int id() const noexcept { return id_; }
  const BodySpec& spec() const noexcept { return spec_; }
  double mass() const noexcept { return mass_; }
  glm::dvec3 position() const noexcept;  ///< centre of mass, world metres
  glm::dquat orientation() const noexcept;
  glm::dvec3 velocity() const noexcept;  ///< m/s
  /// Bullet put it to sleep (at rest; TerrainSync wakes it when the ground changes under it).
  bool sleeping() const noexcept;
  /// Applies an impulse (N s) at the centre of mass and wakes it.
  void push(const glm::dvec3& impulse) noexcept;
  const btRigidBody* rigid_body() const noexcept { return body_.get(); }
  /// Contacts with vehicles so far (counted by the game at the start of each touch).
  std::uint64_t vehicle_hits = 0;
  /// The game step it was spawned at.
  std::uint64_t spawned_frame = 0;

 private:
  Physics* physics_ = nullptr;
  int id_ = 0;
  BodySpec spec_;
  double mass_ = 0;
  std::unique_ptr<btCollisionShape> shape_;
  std::unique_ptr<btRigidBody> body_;
};

}  // namespace game
