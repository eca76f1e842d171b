// Test helper: a Bullet world with Ridgeline's terrain shape as its static ground.
#pragma once

#include <btBulletDynamicsCommon.h>

#include <glm/vec3.hpp>
#include <memory>
#include <vector>

#include "ridgeline/bullet/dynamics_world.h"
#include "ridgeline/bullet/terrain_shape.h"
#include "ridgeline/terrain.h"

namespace ridgeline::bullet::test {

// A Bullet world with one static terrain object (identity transform) and owned bodies.
struct World {
  DynamicsWorld dynamics;
  btDiscreteDynamicsWorld& world = dynamics.world();
  std::unique_ptr<TerrainShape> shape;
  btCollisionObject ground;

  explicit World(std::shared_ptr<const Terrain> terrain, TerrainShapeDesc desc = {}) {
    shape = TerrainShape::create(std::move(terrain), desc).value();
    ground.setCollisionShape(shape.get());
    ground.setFriction(1);
    world.addCollisionObject(&ground, btBroadphaseProxy::StaticFilter,
                             btBroadphaseProxy::AllFilter ^ btBroadphaseProxy::StaticFilter);
  }
  ~World() {
    dynamics.remove_bodies();
    world.removeCollisionObject(&ground);
  }
  const std::vector<btRigidBody*>& bodies() const { return dynamics.bodies(); }
  btRigidBody* add(std::unique_ptr<btCollisionShape> s, const glm::dvec3& world_pos, double mass) {
    btTransform t;
    t.setIdentity();
    t.setOrigin(shape->to_local(world_pos));
    return dynamics.add_body(std::move(s), t, mass, 0.8);
  }
  btRigidBody* sphere(double r, const glm::dvec3& p, double mass = 10) {
    return add(std::make_unique<btSphereShape>(btScalar(r)), p, mass);
  }
  btRigidBody* box(const glm::dvec3& half, const glm::dvec3& p, double mass = 10) {
    return add(std::make_unique<btBoxShape>(
                   btVector3(btScalar(half.x), btScalar(half.y), btScalar(half.z))),
               p, mass);
  }
  void step(int n) {
    for (int i = 0; i < n; ++i) world.stepSimulation(1.0f / 60.0f, 0);
  }
  glm::dvec3 position(const btRigidBody* b) const {
    return shape->to_world(b->getWorldTransform().getOrigin());
  }
};

}  // namespace ridgeline::bullet::test
