// DynamicsWorld: the usual Bullet world in one object (the default collision configuration, a
// dynamic AABB tree broadphase, the sequential impulse solver, gravity along -y) and the rigid
// bodies it owns. What the sample game, the benchmark and the tests build around a TerrainShape
// (docs/engine_integration.md, "Bullet"); an engine with a Bullet world of its own needs none of
// it: TerrainShape and TerrainSync take any btCollisionWorld.
#pragma once

#include <btBulletDynamicsCommon.h>

#include <cstddef>
#include <memory>
#include <vector>

namespace ridgeline::bullet {

class DynamicsWorld {
 public:
  /// A world with gravity `g` m/s^2 along -y (finite).
  explicit DynamicsWorld(double g = 9.81);
  /// Removes its bodies from the world before freeing them.
  ~DynamicsWorld();
  DynamicsWorld(const DynamicsWorld&) = delete;
  DynamicsWorld& operator=(const DynamicsWorld&) = delete;

  btDiscreteDynamicsWorld& world() noexcept { return world_; }
  const btDiscreteDynamicsWorld& world() const noexcept { return world_; }
  btCollisionDispatcher& dispatcher() noexcept { return dispatcher_; }

  /// A rigid body of `mass` kg (0: static) with `shape` at `transform` and the given friction,
  /// owned by this world and added to it (to collision `group`, colliding with `mask`, when
  /// group is not 0; Bullet's default filter otherwise).
  btRigidBody* add_body(std::unique_ptr<btCollisionShape> shape, const btTransform& transform,
                        double mass, double friction, int group = 0, int mask = 0);
  /// The bodies add_body() made, in that order.
  const std::vector<btRigidBody*>& bodies() const noexcept { return body_list_; }
  /// Removes every body add_body() made from the world and frees them.
  void remove_bodies();
  /// Contact points in all of the dispatcher's manifolds (after a step).
  std::size_t contact_points() const;

 private:
  btDefaultCollisionConfiguration config_;
  btCollisionDispatcher dispatcher_{&config_};
  btDbvtBroadphase broadphase_;
  btSequentialImpulseConstraintSolver solver_;
  btDiscreteDynamicsWorld world_{&dispatcher_, &broadphase_, &solver_, &config_};
  struct Body {
    std::unique_ptr<btCollisionShape> shape;
    std::unique_ptr<btDefaultMotionState> state;
    std::unique_ptr<btRigidBody> body;
  };
  std::vector<Body> bodies_;
  std::vector<btRigidBody*> body_list_;
};

}  // namespace ridgeline::bullet
