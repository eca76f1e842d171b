// The usual Bullet world and the bodies it owns (dynamics_world.h).
#include "ridgeline/bullet/dynamics_world.h"

namespace ridgeline::bullet {

DynamicsWorld::DynamicsWorld(double g) {
  world_.setGravity(btVector3(0, -btScalar(g), 0));
}

DynamicsWorld::~DynamicsWorld() {
  remove_bodies();
}

btRigidBody* DynamicsWorld::add_body(std::unique_ptr<btCollisionShape> shape,
                                     const btTransform& transform, double mass, double friction,
                                     int group, int mask) {
  btVector3 inertia(0, 0, 0);
  if (mass > 0) shape->calculateLocalInertia(btScalar(mass), inertia);
  Body b;
  b.state = std::make_unique<btDefaultMotionState>(transform);
  btRigidBody::btRigidBodyConstructionInfo info(btScalar(mass), b.state.get(), shape.get(),
                                                inertia);
  info.m_friction = btScalar(friction);
  b.body = std::make_unique<btRigidBody>(info);
  b.shape = std::move(shape);
  if (group != 0)
    world_.addRigidBody(b.body.get(), group, mask);
  else
    world_.addRigidBody(b.body.get());
  body_list_.push_back(b.body.get());
  bodies_.push_back(std::move(b));
  return body_list_.back();
}

void DynamicsWorld::remove_bodies() {
  for (btRigidBody* b : body_list_) world_.removeRigidBody(b);
  body_list_.clear();
  bodies_.clear();
}

std::size_t DynamicsWorld::contact_points() const {
  std::size_t n = 0;
  for (int k = 0; k < dispatcher_.getNumManifolds(); ++k)
    n += std::size_t(dispatcher_.getManifoldByIndexInternal(k)->getNumContacts());
  return n;
}

}  // namespace ridgeline::bullet
