// Test helper: a Bullet world with Ridgeline's terrain shape as its static ground.
#pragma once

#include <btBulletDynamicsCommon.h>

#include <glm/vec3.hpp>
#include <memory>
#include <vector>

#include "ridgeline/bullet/terrain_shape.h"
#include "ridgeline/terrain.h"

namespace ridgeline::bullet::test {

// A Bullet world with one static terrain object (identity transform) and owned bodies.
struct World {
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &config};
  std::unique_ptr<TerrainShape> shape;
  btCollisionObject ground;
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  std::vector<std::unique_ptr<btDefaultMotionState>> states;
  std::vector<std::unique_ptr<btRigidBody>> bodies;

  explicit World(std::shared_ptr<const Terrain> terrain, TerrainShapeDesc desc = {}) {
    world.setGravity(btVector3(0, -9.81f, 0));
    shape = TerrainShape::create(std::move(terrain), desc).value();
    ground.setCollisionShape(shape.get());
    ground.setFriction(1);
    world.addCollisionObject(&ground, btBroadphaseProxy::StaticFilter,
                             btBroadphaseProxy::AllFilter ^ btBroadphaseProxy::StaticFilter);
  }
  ~World() {
    for (auto& b : bodies) world.removeRigidBody(b.get());
    world.removeCollisionObject(&ground);
  }
  btRigidBody* add(std::unique_ptr<btCollisionShape> s, const glm::dvec3& world_pos, double mass) {
    btVector3 inertia(0, 0, 0);
    s->calculateLocalInertia(btScalar(mass), inertia);
    btTransform t;
    t.setIdentity();
    t.setOrigin(shape->to_local(world_pos));
    states.push_back(std::make_unique<btDefaultMotionState>(t));
    btRigidBody::btRigidBodyConstructionInfo info(btScalar(mass), states.back().get(), s.get(),
                                                  inertia);
    info.m_friction = 0.8f;
    bodies.push_back(std::make_unique<btRigidBody>(info));
    shapes.push_back(std::move(s));
    world.addRigidBody(bodies.back().get());
    return bodies.back().get();
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
