// The game's Bullet world: Ridgeline::bullet's DynamicsWorld (default collision configuration,
// dynamic AABB tree broadphase, sequential impulse solver); the ground is Ridgeline::bullet's TerrainShape on a static rigid
// body (a rigid body, not a plain collision object, because btRaycastVehicle's raycasters only
// report rigid bodies), followed through TerrainSync.
#include "physics.h"

#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "materials.h"
#include "ridgeline/bullet/dynamics_world.h"

namespace game {

struct Physics::Parts {
  ridgeline::bullet::DynamicsWorld dynamics;
  btDiscreteDynamicsWorld& world = dynamics.world();
  std::unique_ptr<btRigidBody> ground;
  std::optional<ridgeline::bullet::TerrainSync> sync;
};

namespace {

bool is_terrain(const btCollisionObjectWrapper* w) {
  return w->getCollisionObject()->getCollisionShape()->getShapeType() ==
         FAST_CONCAVE_MESH_PROXYTYPE;
}

// Bullet's contact-added hook (the ground carries CF_CUSTOM_MATERIAL_CALLBACK): the terrain's
// triangles report their material id as part id (ridgeline/bullet/terrain_shape.h), so a box
// slides further on snow than on rock, with the same factors the tyres use (materials.cpp).
bool material_friction(btManifoldPoint& cp, const btCollisionObjectWrapper* w0, int part0, int,
                       const btCollisionObjectWrapper* w1, int part1, int) {
  int part = -1;
  if (is_terrain(w0)) part = part0;
  if (is_terrain(w1)) part = part1;
  if (part >= 0 && part < 256)
    cp.m_combinedFriction *= btScalar(material(std::uint8_t(part)).friction);
  return false;
}

}  // namespace

ridgeline::Result<std::unique_ptr<Physics>> Physics::create(
    std::shared_ptr<ridgeline::Terrain> terrain) {
  if (terrain == nullptr) return ridgeline::Error{"physics: the terrain is null"};
  std::unique_ptr<Physics> p(new Physics());
  p->terrain_ = terrain;
  const ridgeline::WorldInfo& hf = terrain->info();
  const glm::dvec3 middle(hf.origin_x + hf.extent_x() / 2, hf.height_offset,
                          hf.origin_z + hf.extent_z() / 2);
  auto shape = ridgeline::bullet::TerrainShape::create(terrain, {.origin = middle});
  if (!shape) return ridgeline::Error{"physics: " + shape.error().message};
  p->shape_ = std::move(*shape);
  p->parts_ = std::make_unique<Parts>();
  Parts& parts = *p->parts_;
  btRigidBody::btRigidBodyConstructionInfo info(0, nullptr, p->shape_.get());
  info.m_friction = 0.9f;
  info.m_rollingFriction = 1.0f;
  info.m_restitution = 0.2f;
  parts.ground = std::make_unique<btRigidBody>(info);
  parts.ground->setCollisionFlags(parts.ground->getCollisionFlags() |
                                  btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK);
  gContactAddedCallback = material_friction;
  parts.world.addRigidBody(parts.ground.get(), kGroupTerrain, kGroupVehicle | kGroupBody);
  auto sync = ridgeline::bullet::TerrainSync::create(&parts.world, parts.ground.get());
  if (!sync) return ridgeline::Error{"physics: " + sync.error().message};
  parts.sync.emplace(std::move(*sync));
  return p;
}

Physics::~Physics() {
  if (parts_ && parts_->ground) parts_->world.removeRigidBody(parts_->ground.get());
}

btDiscreteDynamicsWorld& Physics::world() noexcept {
  return parts_->world;
}

const btCollisionObject* Physics::ground() const noexcept {
  return parts_->ground.get();
}

void Physics::step(double dt) {
  if (!(dt > 0)) return;
  last_sync_ = parts_->sync->update();
  // Fixed internal steps of exactly dt / n seconds (Bullet's own accumulator would sometimes take
  // one more or one fewer, from float rounding): the same game every run.
  const int n = std::max(1, int(std::lround(dt / kPhysicsSubstep)));
  for (int i = 0; i < n; ++i) parts_->world.stepSimulation(btScalar(dt / n), 0);
}

namespace {
template <class F>
void for_pair(btDispatcher& d, const btCollisionObject* a, const btCollisionObject* b, F&& f) {
  for (int k = 0; k < d.getNumManifolds(); ++k) {
    const btPersistentManifold* m = d.getManifoldByIndexInternal(k);
    if ((m->getBody0() == a && m->getBody1() == b) || (m->getBody0() == b && m->getBody1() == a))
      for (int c = 0; c < m->getNumContacts(); ++c) f(m->getContactPoint(c));
  }
}
}  // namespace

double Physics::penetration(const btCollisionObject* a, const btCollisionObject* b) const {
  double deepest = 0;
  for_pair(parts_->dynamics.dispatcher(), a, b, [&](const btManifoldPoint& p) {
    deepest = std::max(deepest, -double(p.getDistance()));
  });
  return deepest;
}

bool Physics::touching(const btCollisionObject* a, const btCollisionObject* b) const {
  bool touch = false;
  for_pair(parts_->dynamics.dispatcher(), a, b,
           [&](const btManifoldPoint& p) { touch = touch || p.getDistance() < 0.01f; });
  return touch;
}

// ---- loose bodies ------------------------------------------------------------------------------

const char* to_string(BodyShape shape) noexcept {
  return shape == BodyShape::kBox ? "box" : "sphere";
}

LooseBody::LooseBody(Physics& physics, int id, const BodySpec& spec)
    : physics_(&physics), id_(id), spec_(spec) {
  const glm::dvec3 s = spec.size;
  double volume = 0;
  if (spec.shape == BodyShape::kBox) {
    shape_ = std::make_unique<btBoxShape>(btVector3(btScalar(s.x), btScalar(s.y), btScalar(s.z)));
    volume = 8 * s.x * s.y * s.z;
  } else {
    shape_ = std::make_unique<btSphereShape>(btScalar(s.x));
    volume = 4.0 / 3.0 * M_PI * s.x * s.x * s.x;
  }
  mass_ = spec.mass > 0 ? spec.mass : 2400 * volume;
  btVector3 inertia(0, 0, 0);
  shape_->calculateLocalInertia(btScalar(mass_), inertia);
  btRigidBody::btRigidBodyConstructionInfo info(btScalar(mass_), nullptr, shape_.get(), inertia);
  info.m_startWorldTransform.setIdentity();
  info.m_startWorldTransform.setOrigin(physics.to_local(spec.position));
  info.m_friction = 0.8f;
  info.m_restitution = 0.15f;
  // Rolling resistance and a little damping: a boulder on flat ground stops; on a slope it rolls.
  info.m_rollingFriction = spec.shape == BodyShape::kSphere ? 0.04f : 0.0f;
  info.m_linearDamping = 0.02f;
  info.m_angularDamping = 0.15f;
  body_ = std::make_unique<btRigidBody>(info);
  body_->setLinearVelocity(
      btVector3(btScalar(spec.velocity.x), btScalar(spec.velocity.y), btScalar(spec.velocity.z)));
  body_->setAngularVelocity(btVector3(btScalar(spec.angular_velocity.x),
                                      btScalar(spec.angular_velocity.y),
                                      btScalar(spec.angular_velocity.z)));
  physics.world().addRigidBody(body_.get(), kGroupBody, kGroupTerrain | kGroupVehicle | kGroupBody);
}

LooseBody::~LooseBody() {
  if (physics_ != nullptr && body_) physics_->world().removeRigidBody(body_.get());
}

LooseBody::LooseBody(LooseBody&& o) noexcept
    : vehicle_hits(o.vehicle_hits),
      spawned_frame(o.spawned_frame),
      physics_(o.physics_),
      id_(o.id_),
      spec_(std::move(o.spec_)),
      mass_(o.mass_),
      shape_(std::move(o.shape_)),
      body_(std::move(o.body_)) {
  o.physics_ = nullptr;
}

LooseBody& LooseBody::operator=(LooseBody&& o) noexcept {
  if (this != &o) {
    if (physics_ != nullptr && body_) physics_->world().removeRigidBody(body_.get());
    vehicle_hits = o.vehicle_hits;
    spawned_frame = o.spawned_frame;
    physics_ = o.physics_;
    id_ = o.id_;
    spec_ = std::move(o.spec_);
    mass_ = o.mass_;
    shape_ = std::move(o.shape_);
    body_ = std::move(o.body_);
    o.physics_ = nullptr;
  }
  return *this;
}

glm::dvec3 LooseBody::position() const noexcept {
  return physics_->to_world(body_->getCenterOfMassPosition());
}

glm::dquat LooseBody::orientation() const noexcept {
  const btQuaternion q = body_->getOrientation();
  return glm::dquat(q.w(), q.x(), q.y(), q.z());
}

glm::dvec3 LooseBody::velocity() const noexcept {
  const btVector3 v = body_->getLinearVelocity();
  return {v.x(), v.y(), v.z()};
}

bool LooseBody::sleeping() const noexcept {
  return !body_->isActive();
}

void LooseBody::push(const glm::dvec3& impulse) noexcept {
  body_->activate(true);
  body_->applyCentralImpulse(
      btVector3(btScalar(impulse.x), btScalar(impulse.y), btScalar(impulse.z)));
}

}  // namespace game
