// TerrainSync: the pull side of the terrain's change log for a Bullet world (terrain.h's
// changes_since, as Jolt's deformation sample wakes the bodies in a changed box).
#include "ridgeline/bullet/terrain_sync.h"

#include <BulletCollision/BroadphaseCollision/btBroadphaseInterface.h>
#include <BulletCollision/BroadphaseCollision/btDispatcher.h>
#include <BulletCollision/CollisionDispatch/btCollisionObject.h>
#include <BulletCollision/CollisionDispatch/btCollisionWorld.h>
#include <BulletCollision/NarrowPhaseCollision/btPersistentManifold.h>
#include <BulletDynamics/Dynamics/btRigidBody.h>
#include <LinearMath/btAabbUtil2.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace ridgeline::bullet {
namespace {

// Collects the objects whose broadphase boxes overlap a query box.
struct Collect final : btBroadphaseAabbCallback {
  std::vector<const btCollisionObject*>* out = nullptr;
  const btCollisionObject* skip = nullptr;
  bool process(const btBroadphaseProxy* proxy) override {
    const auto* o = static_cast<const btCollisionObject*>(proxy->m_clientObject);
    if (o != nullptr && o != skip) out->push_back(o);
    return true;
  }
};

}  // namespace

bool TerrainSync::lift_if_buried(btCollisionObject& o) const {
  btRigidBody* body = btRigidBody::upcast(&o);
  if (body == nullptr) return false;
  // The centre of mass against the surface under it, in the terrain's frame.
  const btTransform& ground = object_->getWorldTransform();
  const btTransform to_shape = ground.inverse() * body->getCenterOfMassTransform();
  const glm::dvec3 c = shape_->to_world(to_shape.getOrigin());
  const std::optional<double> h = shape_->terrain().height(c.x, c.z);
  if (!h || c.y >= *h) return false;
  btVector3 lo, hi;
  o.getCollisionShape()->getAabb(to_shape, lo, hi);
  const double bottom = shape_->to_world(lo).y;
  const btVector3 up = ground.getBasis() * btVector3(0, btScalar(*h - bottom + 1e-3), 0);
  btTransform t = body->getCenterOfMassTransform();
  t.setOrigin(t.getOrigin() + up);
  body->setCenterOfMassTransform(t);
  if (btMotionState* ms = body->getMotionState()) ms->setWorldTransform(t);
  world_->updateSingleAabb(body);
  return true;
}

Result<TerrainSync> TerrainSync::create(btCollisionWorld* world, btCollisionObject* terrain_object,
                                        const TerrainSyncDesc& desc) {
  if (world == nullptr) return Error{"bullet terrain sync: the world is null"};
  if (terrain_object == nullptr) return Error{"bullet terrain sync: the terrain object is null"};
  const auto* shape = dynamic_cast<const TerrainShape*>(terrain_object->getCollisionShape());
  if (shape == nullptr)
    return Error{std::string("bullet terrain sync: the terrain object's shape is ") +
                 (terrain_object->getCollisionShape() == nullptr
                      ? "null"
                      : "a " + std::string(terrain_object->getCollisionShape()->getName())) +
                 ", not a ridgeline::bullet::TerrainShape"};
  if (!(std::isfinite(desc.wake_margin) && desc.wake_margin >= 0))
    return Error{"bullet terrain sync: wake margin is " + std::to_string(desc.wake_margin) +
                 "; need a finite value >= 0 metres"};
  if (!(std::isfinite(desc.residency_margin) && desc.residency_margin >= 0))
    return Error{"bullet terrain sync: residency margin is " +
                 std::to_string(desc.residency_margin) + "; need a finite value >= 0 metres"};
  return TerrainSync(world, terrain_object, shape, desc);
}

TerrainSync::TerrainSync(btCollisionWorld* world, btCollisionObject* object,
                         const TerrainShape* shape, const TerrainSyncDesc& desc)
    : world_(world),
      object_(object),
      shape_(shape),
      desc_(desc),
      seen_(shape->terrain().edit_version()) {}

void TerrainSync::keep_resident(TerrainSyncStats& stats) {
  const Terrain& terrain = shape_->terrain();
  const WorldInfo& w = terrain.info();
  const double page_x = w.spacing_x * kPageCells, page_z = w.spacing_z * kPageCells;
  const std::int64_t last_px = std::int64_t(w.width - 2) / kPageCells;
  const std::int64_t last_pz = std::int64_t(w.height - 2) / kPageCells;
  auto page = [](double v, double size, std::int64_t last) {
    const double p = std::floor(v / size);
    return std::int64_t(std::clamp(p, 0.0, double(last)));
  };
  // Every body's box in the terrain's frame (in world metres), widened by the margin, as the
  // level-0 pages it covers.
  const btTransform to_shape = object_->getWorldTransform().inverse();
  const btCollisionObjectArray& objects = world_->getCollisionObjectArray();
  next_keys_.clear();
  for (int k = 0; k < objects.size(); ++k) {
    const btCollisionObject* o = objects[k];
    if (o == object_ || o->isStaticObject() || o->getCollisionShape() == nullptr) continue;
    btVector3 lo, hi;
    o->getCollisionShape()->getAabb(to_shape * o->getWorldTransform(), lo, hi);
    const glm::dvec3 a = shape_->to_world(lo), b = shape_->to_world(hi);
    if (!std::isfinite(a.x + a.z + b.x + b.z)) continue;
    const double m = desc_.residency_margin;
    const std::int64_t x0 = page(a.x - m - w.origin_x, page_x, last_px),
                       x1 = page(b.x + m - w.origin_x, page_x, last_px),
                       z0 = page(a.z - m - w.origin_z, page_z, last_pz),
                       z1 = page(b.z + m - w.origin_z, page_z, last_pz);
    for (std::int64_t pz = z0; pz <= z1; ++pz)
      for (std::int64_t px = x0; px <= x1; ++px)
        next_keys_.push_back(std::uint64_t(pz) << 32 | std::uint64_t(px));
  }
  std::sort(next_keys_.begin(), next_keys_.end());
  next_keys_.erase(std::unique(next_keys_.begin(), next_keys_.end()), next_keys_.end());
  stats.pinned_pages = next_keys_.size();
  if (next_keys_ == page_keys_) return;
  stats.residency_changed = true;
  // The new pins first, then the old ones released: a page under a body in both sets stays.
  std::vector<RegionPin> pins;
  pins.reserve(next_keys_.size());
  for (const std::uint64_t key : next_keys_) {
    const double px = double(key & 0xffffffffu), pz = double(key >> 32);
    // The page's inside, half a cell from its edges: it lies on no other page.
    // (pin() and prefetch() read the xz range only.)
    const Box inside{{w.origin_x + (px * kPageCells + 0.5) * w.spacing_x, 0.0,
                      w.origin_z + (pz * kPageCells + 0.5) * w.spacing_z},
                     {w.origin_x + ((px + 1) * kPageCells - 0.5) * w.spacing_x, 0.0,
                      w.origin_z + ((pz + 1) * kPageCells - 0.5) * w.spacing_z}};
    pins.push_back(terrain.pin(inside));
    const glm::dvec3 around(desc_.residency_margin + 0.5 * page_x, 0.0,
                            desc_.residency_margin + 0.5 * page_z);
    terrain.prefetch(Box{inside.min - around, inside.max + around});
  }
  pins_ = std::move(pins);
  page_keys_.swap(next_keys_);
}

TerrainSyncStats TerrainSync::update() {
  TerrainSyncStats stats;
  if (shape_->terrain().paged()) keep_resident(stats);
  const TerrainChanges c = shape_->terrain().changes_since(seen_);
  seen_ = c.version;
  if (c.empty()) return stats;
  stats.changes = c.changes.size();
  stats.trimmed = c.trimmed;
  // The ground may now reach beyond the heights the broadphase knew.
  if (object_->getBroadphaseHandle() != nullptr) world_->updateSingleAabb(object_);

  touched_.clear();
  Collect collect;
  collect.out = &touched_;
  collect.skip = object_;
  for (const TerrainChange& ch : c.changes) {
    const glm::dvec3 m(desc_.wake_margin);
    const btVector3 lo = shape_->to_local(ch.box.min - m), hi = shape_->to_local(ch.box.max + m);
    // The terrain object's transform is normally the identity; with another, the box moves with
    // it (its bounding box under that transform).
    btVector3 wlo, whi;
    btTransformAabb(lo, hi, 0, object_->getWorldTransform(), wlo, whi);
    world_->getBroadphase()->aabbTest(wlo, whi, collect);
  }
  std::sort(touched_.begin(), touched_.end());
  touched_.erase(std::unique(touched_.begin(), touched_.end()), touched_.end());
  for (const btCollisionObject* c_o : touched_) {
    if (c_o->isStaticObject()) continue;
    // Bullet's broadphase hands out const objects; they are the world's, which we were given.
    auto* o = const_cast<btCollisionObject*>(c_o);
    o->activate(true);
    ++stats.bodies_woken;
    if (desc_.lift_buried && !o->isKinematicObject()) stats.bodies_lifted += lift_if_buried(*o);
  }
  btDispatcher* dispatcher = world_->getDispatcher();
  for (int k = 0; k < dispatcher->getNumManifolds(); ++k) {
    btPersistentManifold* m = dispatcher->getManifoldByIndexInternal(k);
    const btCollisionObject* other = m->getBody0() == object_   ? m->getBody1()
                                     : m->getBody1() == object_ ? m->getBody0()
                                                                : nullptr;
    if (other == nullptr || !std::binary_search(touched_.begin(), touched_.end(), other)) continue;
    dispatcher->clearManifold(m);
    ++stats.manifolds_cleared;
  }
  return stats;
}

}  // namespace ridgeline::bullet
