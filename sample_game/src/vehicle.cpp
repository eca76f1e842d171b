// Raycast-suspension vehicle on Bullet: a btRaycastVehicle (one ray per wheel along the body's
// down axis, a spring-damper on the hit distance, a friction impulse per tyre limited by the
// suspension load) whose rays go through btCollisionWorld::rayTest, i.e. through Ridgeline's
// raycast on the terrain (ridgeline/bullet/terrain_shape.h), and a box chassis that collides
// with the terrain's finest triangles, the other vehicles and the loose bodies. The tyres' grip
// follows the material under them (materials.cpp).
#include "vehicle.h"

#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/mat3x3.hpp>

#include "materials.h"

namespace game {
namespace {

constexpr double kGravity = 9.81;

btVector3 bt(const glm::dvec3& v) {
  return btVector3(btScalar(v.x), btScalar(v.y), btScalar(v.z));
}
glm::dvec3 dv(const btVector3& v) {
  return {v.x(), v.y(), v.z()};
}

// Wheel rays see the terrain alone: the chassis hulls meet other vehicles and push the loose
// bodies (a wheel ray that found another vehicle's hull after a crash would drive the vehicle up
// onto it, and a boulder under a wheel would carry the truck without being pushed down).
struct Raycaster final : btVehicleRaycaster {
  btDynamicsWorld* world = nullptr;
  const btCollisionObject* self = nullptr;
  void* castRay(const btVector3& from, const btVector3& to,
                btVehicleRaycasterResult& result) override {
    struct Closest final : btCollisionWorld::ClosestRayResultCallback {
      using ClosestRayResultCallback::ClosestRayResultCallback;
      const btCollisionObject* self = nullptr;
      bool needsCollision(btBroadphaseProxy* proxy) const override {
        return proxy->m_clientObject != self && ClosestRayResultCallback::needsCollision(proxy);
      }
    } cb(from, to);
    cb.self = self;
    cb.m_collisionFilterGroup = kGroupVehicle;
    cb.m_collisionFilterMask = kGroupTerrain;
    world->rayTest(from, to, cb);
    if (!cb.hasHit()) return nullptr;
    result.m_hitPointInWorld = cb.m_hitPointWorld;
    result.m_hitNormalInWorld = cb.m_hitNormalWorld.normalized();
    result.m_distFraction = cb.m_closestHitFraction;
    return const_cast<btCollisionObject*>(cb.m_collisionObject);
  }
};

}  // namespace

// The Bullet side of a vehicle. It is also the world's action for the vehicle: at each internal
// step it turns the controls into engine force, brakes, steering and grip, then runs the raycast
// vehicle.
struct Vehicle::Parts final : btActionInterface {
  Vehicle* owner = nullptr;
  btDynamicsWorld* world = nullptr;
  std::unique_ptr<btConvexHullShape> hull;
  std::unique_ptr<btRigidBody> body;
  Raycaster raycaster;
  std::unique_ptr<btRaycastVehicle> vehicle;

  void updateAction(btCollisionWorld* w, btScalar dt) override {
    const double steer = std::clamp(owner->controls.steer, -1.0, 1.0) * owner->params_.max_steer;
    vehicle->setSteeringValue(btScalar(steer), 0);
    vehicle->setSteeringValue(btScalar(steer), 1);
    // Bullet's raycast vehicle: the suspension rays (Ridgeline's raycast on the terrain), the
    // springs, the wheel transforms. Its own tyre impulses are switched off (zero friction slip):
    // they only cancel a fifth of the side slip per step (resolveSingleBilateral's damping), so a
    // braked truck creeps down any slope; the tyres below cancel all of it within the friction
    // circle.
    vehicle->updateAction(w, dt);
    tyres(double(dt));
  }

  // Engine, brakes, rolling resistance and side grip at each wheel in contact, as impulses on the
  // chassis at the contact point, each limited by the friction circle: the suspension load times
  // the tyre's friction times the ground's material factor (materials.cpp). Applied wheel by
  // wheel, each seeing the velocity the previous ones left (sequential impulses).
  void tyres(double dt) {
    const VehicleParams& p = owner->params_;
    const Controls& c = owner->controls;
    const double throttle = std::clamp(c.throttle, -1.0, 1.0);
    const double brake = std::clamp(c.brake, 0.0, 1.0);
    const double fwd_speed = owner->speed();
    btRigidBody& chassis = *body;
    const btVector3 com = chassis.getCenterOfMassPosition();
    const btMatrix3x3& basis = chassis.getWorldTransform().getBasis();
    const btVector3 fwd = basis.getColumn(2), up = basis.getColumn(1);
    for (int i = 0; i < 4; ++i) {
      const btWheelInfo& wi = vehicle->getWheelInfo(i);
      if (!wi.m_raycastInfo.m_isInContact) continue;
      const btVector3 n = wi.m_raycastInfo.m_contactNormalWS;
      const btVector3 r = wi.m_raycastInfo.m_contactPointWS - com;
      const btVector3 wheel_fwd = fwd.rotate(up, wi.m_steering);
      btVector3 tf = wheel_fwd - n * n.dot(wheel_fwd);
      if (tf.length2() < 1e-8f) continue;
      tf.normalize();
      const btVector3 ts = n.cross(tf);
      // Effective mass of the chassis at the contact along a direction.
      const auto mass_along = [&](const btVector3& d) {
        const btVector3 rd = r.cross(d);
        const double k =
            double(chassis.getInvMass()) + double(rd.dot(chassis.getInvInertiaTensorWorld() * rd));
        return k > 0 ? 1.0 / k : 0.0;
      };
      const btVector3 vp = chassis.getVelocityInLocalPoint(r);
      const double vf = vp.dot(tf), vs = vp.dot(ts);
      // Side: cancel the slip. Along: the engine (none above the top speed), else brakes and
      // rolling resistance, which stop the wheel's rolling at most.
      double js = -vs * mass_along(ts);
      double jf = 0;
      if (throttle != 0 && !(throttle > 0 && fwd_speed > p.max_speed) &&
          !(throttle < 0 && fwd_speed < -p.max_speed / 3)) {
        jf = throttle * p.engine_force / 4 * dt;
      } else {
        const double stop = (brake * p.brake_force + 0.015 * p.mass * kGravity) / 4 * dt;
        jf = std::clamp(-vf * mass_along(tf), -stop, stop);
      }
      const double limit = p.friction * material(owner->wheels_[std::size_t(i)].material).friction *
                           double(std::min(wi.m_wheelsSuspensionForce, wi.m_maxSuspensionForce)) *
                           dt;
      const double mag = std::hypot(jf, js);
      if (mag > limit && mag > 0) {
        jf *= limit / mag;
        js *= limit / mag;
      }
      chassis.applyImpulse(tf * btScalar(jf) + ts * btScalar(js), r);
    }
  }
  void debugDraw(btIDebugDraw*) override {}
};

VehicleParams params_from_model(const VehicleModel& model, double mass_kg) {
  VehicleParams p;
  p.mass = mass_kg;
  p.wheel_radius = model.wheel_radius;
  // Centre of mass a little above the wheel centres.
  const float wheel_y = model.wheel_centres[0].y;
  p.com_in_model = {0, wheel_y + 0.35, 0};
  p.rest_length = 0.45;
  for (int i = 0; i < 4; ++i) {
    // Suspension tops sit rest_length above the wheel centres at rest (the model shows the
    // wheels hanging at full extension).
    const glm::dvec3 c(model.wheel_centres[i]);
    p.attach[i] = c + glm::dvec3(0, p.rest_length, 0) - p.com_in_model;
  }
  const glm::vec3 e = model.body_max - model.body_min;
  p.inertia_extent = {e.x, e.y, e.z};
  // The chassis box: the body's box, its bottom at the wheel centres (the frame; the wheels
  // below it are rays).
  p.chassis_min = glm::dvec3(model.body_min) - p.com_in_model;
  p.chassis_max = glm::dvec3(model.body_max) - p.com_in_model;
  p.chassis_min.y = std::max(p.chassis_min.y, double(wheel_y) - p.com_in_model.y);
  // Static sag of about rest_length / 3, damping ratio about 0.5.
  const double per_wheel = mass_kg * kGravity / 4;
  p.spring_k = per_wheel / (p.rest_length / 3);
  p.damper_c = 2 * 0.5 * std::sqrt(p.spring_k * mass_kg / 4);
  p.engine_force = mass_kg * 7.0;
  p.friction = 1.1;
  p.brake_force = mass_kg * 7.0;
  return p;
}

Vehicle::Vehicle(Physics& physics, const VehicleParams& params, glm::dvec3 position,
                 double heading_rad)
    : physics_(&physics), params_(params), parts_(std::make_unique<Parts>()) {
  Parts& b = *parts_;
  b.owner = this;
  b.world = &physics.world();
  // The chassis: a hull of the body's box above a third of its height, narrowing below to the
  // four points where the wheels' bottoms are at full compression. A wheel that bottoms out (a
  // hard landing in a crater) then rests on the hull instead of sinking into the ground, and a
  // crest or a crater's rim lifts the bevelled nose instead of stopping the vehicle dead.
  const glm::dvec3 lo = params.chassis_min, hi = params.chassis_max;
  b.hull = std::make_unique<btConvexHullShape>();
  const double mid = lo.y + (hi.y - lo.y) / 3;
  for (int i = 0; i < 8; ++i)
    b.hull->addPoint(bt({i & 1 ? hi.x : lo.x, i & 4 ? hi.y : mid, i & 2 ? hi.z : lo.z}), false);
  for (const glm::dvec3& a : params.attach)
    b.hull->addPoint(bt(a - glm::dvec3(0, params.wheel_radius, 0)), false);
  b.hull->recalcLocalAabb();
  b.hull->setMargin(0.02f);
  const glm::dvec3 e = params.inertia_extent;
  const double m = params.mass;
  const btVector3 inertia(btScalar(m / 12 * (e.y * e.y + e.z * e.z)),
                          btScalar(m / 12 * (e.x * e.x + e.z * e.z)),
                          btScalar(m / 12 * (e.x * e.x + e.y * e.y)));
  btRigidBody::btRigidBodyConstructionInfo info(btScalar(m), nullptr, b.hull.get(), inertia);
  info.m_friction = 0.3f;
  info.m_restitution = 0.2f;
  info.m_linearDamping = 0.02f;
  info.m_angularDamping = 0.4f;
  b.body = std::make_unique<btRigidBody>(info);
  b.body->setActivationState(DISABLE_DEACTIVATION);
  physics.world().addRigidBody(b.body.get(), kGroupVehicle,
                               kGroupTerrain | kGroupVehicle | kGroupBody);
  b.raycaster.world = &physics.world();
  b.raycaster.self = b.body.get();
  // Bullet's suspension force is stiffness x chassis mass x compression: per-kilogram figures.
  btRaycastVehicle::btVehicleTuning tuning;
  tuning.m_suspensionStiffness = btScalar(params.spring_k / m);
  tuning.m_suspensionCompression = btScalar(params.damper_c / m);
  tuning.m_suspensionDamping = btScalar(params.damper_c / m);
  tuning.m_maxSuspensionTravelCm = btScalar(params.rest_length * 100);
  tuning.m_frictionSlip = 0;  // the tyres are ours (Parts::tyres)
  tuning.m_maxSuspensionForce = btScalar(m * kGravity * 8);
  b.vehicle = std::make_unique<btRaycastVehicle>(tuning, b.body.get(), &b.raycaster);
  b.vehicle->setCoordinateSystem(0, 1, 2);  // right (the body's +x is left: axles point -x), up,
                                            // forward
  for (int i = 0; i < 4; ++i) {
    btWheelInfo& w = b.vehicle->addWheel(bt(params.attach[i]), btVector3(0, -1, 0),
                                         btVector3(-1, 0, 0), btScalar(params.rest_length),
                                         btScalar(params.wheel_radius), tuning, i < 2);
    w.m_rollInfluence = 0.2f;
  }
  physics.world().addAction(&b);
  place(position, heading_rad);
}

Vehicle::~Vehicle() {
  if (parts_ && physics_ != nullptr) {
    physics_->world().removeAction(parts_.get());
    physics_->world().removeRigidBody(parts_->body.get());
  }
}

Vehicle::Vehicle(Vehicle&& o) noexcept
    : controls(o.controls),
      collisions(o.collisions),
      body_hits(o.body_hits),
      physics_(o.physics_),
      params_(o.params_),
      parts_(std::move(o.parts_)),
      wheels_(o.wheels_),
      ground_material_(o.ground_material_),
      ground_(o.ground_) {
  if (parts_) parts_->owner = this;
  o.physics_ = nullptr;
}

Vehicle& Vehicle::operator=(Vehicle&& o) noexcept {
  if (this != &o) {
    if (parts_ && physics_ != nullptr) {
      physics_->world().removeAction(parts_.get());
      physics_->world().removeRigidBody(parts_->body.get());
    }
    controls = o.controls;
    collisions = o.collisions;
    body_hits = o.body_hits;
    physics_ = o.physics_;
    params_ = o.params_;
    parts_ = std::move(o.parts_);
    wheels_ = o.wheels_;
    ground_material_ = o.ground_material_;
    ground_ = o.ground_;
    if (parts_) parts_->owner = this;
    o.physics_ = nullptr;
  }
  return *this;
}

const btRigidBody* Vehicle::chassis() const noexcept {
  return parts_->body.get();
}

btRigidBody* Vehicle::chassis() noexcept {
  return parts_->body.get();
}

glm::dvec3 Vehicle::position() const noexcept {
  return physics_->to_world(parts_->body->getCenterOfMassPosition());
}

glm::dquat Vehicle::orientation() const noexcept {
  const btQuaternion q = parts_->body->getOrientation();
  return glm::dquat(q.w(), q.x(), q.y(), q.z());
}

glm::dvec3 Vehicle::velocity() const noexcept {
  return dv(parts_->body->getLinearVelocity());
}

double Vehicle::heading() const noexcept {
  const glm::dvec3 f = forward();
  return std::atan2(f.x, f.z);
}

double Vehicle::speed() const noexcept {
  return glm::dot(velocity(), forward());
}

void Vehicle::place(glm::dvec3 position, double heading_rad) {
  const glm::dquat q = glm::angleAxis(heading_rad, glm::dvec3(0, 1, 0));
  btRigidBody& body = *parts_->body;
  body.setCenterOfMassTransform(
      btTransform(btQuaternion(btScalar(q.x), btScalar(q.y), btScalar(q.z), btScalar(q.w)),
                  physics_->to_local(position)));
  body.setLinearVelocity(btVector3(0, 0, 0));
  body.setAngularVelocity(btVector3(0, 0, 0));
  body.clearForces();
  parts_->vehicle->resetSuspension();
  // Contacts made at the old place are meaningless at the new one.
  btDiscreteDynamicsWorld& w = physics_->world();
  w.getBroadphase()->getOverlappingPairCache()->cleanProxyFromPairs(body.getBroadphaseHandle(),
                                                                    w.getDispatcher());
  w.updateSingleAabb(&body);
  measure_contacts();
}

bool Vehicle::place_on_surface(double x, double z, double heading_rad) {
  const ridgeline::Terrain& terrain = physics_->terrain();
  const auto hn = terrain.height_normal(x, z);
  if (!hn) return false;
  // The mean face normal under the wheels' footprint gives the tilt.
  glm::dvec3 n(0);
  const glm::dquat yaw = glm::angleAxis(heading_rad, glm::dvec3(0, 1, 0));
  for (const glm::dvec3& at : params_.attach) {
    const glm::dvec3 p = glm::dvec3(x, 0, z) + yaw * at;
    if (auto h = terrain.height_normal(p.x, p.z)) n += glm::dvec3(h->face_normal);
  }
  if (glm::length(n) < 1e-6) n = glm::dvec3(hn->face_normal);
  n = glm::normalize(n);
  glm::dquat q = yaw;
  const glm::dvec3 axis = glm::cross(glm::dvec3(0, 1, 0), n);
  const double s = glm::length(axis);
  if (s > 1e-9) q = glm::angleAxis(std::asin(std::min(1.0, s)), axis / s) * yaw;
  // Lowest height at which every wheel at full compression clears the ground by its radius and
  // no corner of the chassis' bottom is under it; then the suspension a little extended.
  glm::dvec3 pos(x, hn->height, z);
  double lift = -1e300;
  for (const glm::dvec3& at : params_.attach) {
    const glm::dvec3 a = pos + q * at;
    if (auto h = terrain.height_normal(a.x, a.z))
      lift = std::max(
          lift, h->height + params_.wheel_radius / std::max(0.2, double(h->face_normal.y)) - a.y);
  }
  const glm::dvec3 lo = params_.chassis_min, hi = params_.chassis_max;
  for (int i = 0; i < 4; ++i) {
    const glm::dvec3 c = pos + q * glm::dvec3(i & 1 ? hi.x : lo.x, lo.y, i & 2 ? hi.z : lo.z);
    if (auto h = terrain.height(c.x, c.z)) lift = std::max(lift, *h - c.y);
  }
  if (lift > -1e300) pos.y += lift;
  pos += q * glm::dvec3(0, params_.rest_length * 0.6, 0);
  place(pos, heading_rad);
  // place() took the heading alone: set the tilt too.
  btRigidBody& body = *parts_->body;
  btTransform t = body.getCenterOfMassTransform();
  t.setRotation(btQuaternion(btScalar(q.x), btScalar(q.y), btScalar(q.z), btScalar(q.w)));
  body.setCenterOfMassTransform(t);
  physics_->world().updateSingleAabb(&body);
  measure_contacts();
  return true;
}

void Vehicle::measure_contacts() {
  // The wheel state for the final pose of the step (what is drawn and what the tests check),
  // from the terrain's own queries: each wheel's suspension ray again, the gap under its lowest
  // point, the material under it. Bullet's wheel info gives the load, the steering and the spin.
  const ridgeline::Terrain& terrain = physics_->terrain();
  const glm::dquat q = orientation();
  const glm::dvec3 up = q * glm::dvec3(0, 1, 0), pos = position();
  const double reach = params_.rest_length + params_.wheel_radius;
  for (int i = 0; i < 4; ++i) {
    WheelState& w = wheels_[std::size_t(i)];
    const btWheelInfo& wi = parts_->vehicle->getWheelInfo(i);
    const glm::dvec3 a = pos + q * params_.attach[std::size_t(i)];
    const auto hit = terrain.raycast(a, -up, reach);
    const double dist = hit ? (hit->started_below ? 0.0 : hit->distance) : reach;
    w.contact = hit.has_value();
    w.suspension_length = std::clamp(dist - params_.wheel_radius, 0.0, params_.rest_length);
    w.centre = a - up * w.suspension_length;
    w.contact_point = hit ? hit->point : w.centre - up * params_.wheel_radius;
    w.contact_normal = hit ? glm::dvec3(hit->normal) : glm::dvec3(0, 1, 0);
    const glm::dvec3 bottom = w.centre - up * params_.wheel_radius;
    const auto h = terrain.height(bottom.x, bottom.z);
    w.surface_gap = h ? bottom.y - *h : 0.0;
    w.material = hit ? hit->material : 0;
    w.load_n = wi.m_raycastInfo.m_isInContact ? double(wi.m_wheelsSuspensionForce) : 0.0;
    w.steer = wi.m_steering;
    w.spin = wi.m_rotation;
    ground_[std::size_t(i)] = {a.x, a.z, terrain.height(a.x, a.z).value_or(std::nan(""))};
  }
  // The ground's material: the one under most wheels in contact (ties: the lowest id).
  int votes[256] = {};
  for (const WheelState& w : wheels_)
    if (w.contact) ++votes[w.material];
  int best = 0;
  for (int m = 1; m < 256; ++m)
    if (votes[m] > votes[best]) best = m;
  ground_material_ = static_cast<std::uint8_t>(best);
}

double Vehicle::follow_ground() {
  // The wheels carry the body: it rises with the ground under them.
  const ridgeline::Terrain& terrain = physics_->terrain();
  double rise = 0;
  for (const GroundPoint& g : ground_) {
    const auto h = terrain.height(g.x, g.z);
    if (h && std::isfinite(g.height)) rise = std::max(rise, *h - g.height);
  }
  if (rise > 0) {
    btRigidBody& body = *parts_->body;
    btTransform t = body.getCenterOfMassTransform();
    t.setOrigin(t.getOrigin() + btVector3(0, btScalar(rise), 0));
    body.setCenterOfMassTransform(t);
    physics_->world().updateSingleAabb(&body);
  }
  measure_contacts();
  return rise;
}

bool Autopilot::drive(Vehicle& v) {
  if (!active || waypoints.empty()) return false;
  bool reached_one = false;
  const glm::dvec3 p = v.position();
  glm::dvec2 here(p.x, p.z);
  if (next < waypoints.size() && glm::length(waypoints[next] - here) < reach) {
    ++reached;
    reached_one = true;
    ++next;
    if (next >= waypoints.size()) {
      if (loop) {
        next = 0;
      } else {
        active = false;
        v.controls = {0, 0, 1};
        return true;
      }
    }
  }
  const glm::dvec2 target = waypoints[next];
  const glm::dvec2 to = target - here;
  const double want = std::atan2(to.x, to.y);
  double err = want - v.heading();
  while (err > M_PI) err -= 2 * M_PI;
  while (err < -M_PI) err += 2 * M_PI;
  // Heading grows towards +x; steering positive turns left (towards +x when facing +z).
  v.controls.steer = std::clamp(err * 1.5, -1.0, 1.0);
  const double want_speed = speed * (std::abs(err) > 0.8 ? 0.4 : 1.0);
  const double s = v.speed();
  v.controls.throttle = std::clamp((want_speed - s) * 0.4, -0.2, 1.0);
  v.controls.brake = s > want_speed + 3 ? 0.5 : 0.0;
  return reached_one;
}

}  // namespace game
