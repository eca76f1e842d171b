// TerrainSync: keeps a Bullet world in step with a Ridgeline terrain's edits, the way Jolt's
// deformation sample does after HeightFieldShape::SetHeights (docs/engine_integration.md,
// "Bullet"): pull the terrain's change log once per step, then for each changed box drop the
// stale contacts of the bodies resting there and wake them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "ridgeline/bullet/terrain_shape.h"
#include "ridgeline/result.h"

class btCollisionObject;
class btCollisionWorld;

namespace ridgeline::bullet {

/// How a TerrainSync behaves. Plain data with sane defaults.
struct TerrainSyncDesc {
  /// Metres (finite, >= 0) by which each changed box is widened before the overlap test, for
  /// bodies resting just outside it (a wheel on a crater's rim).
  double wake_margin = 0.25;
  /// Lift a woken rigid body whose centre of mass the edit left under the surface (the ground
  /// rose by more than about half the body's height) so that the bottom of its bounding box sits
  /// on the surface under its centre. Bullet's contacts push a shallowly sunk body out along the
  /// triangles' upward normals, but a body buried past its middle may be pushed down through the
  /// ground instead. Velocities are kept.
  bool lift_buried = true;
  /// On a paged terrain (Terrain::paged()): metres (finite, >= 0) around each non-static body's
  /// bounding box whose stored pages are kept resident (Terrain::pin) while the body is there,
  /// so that its contacts and rays never load a page on the stepping thread; the pages within
  /// twice that are prefetched in the background when a body reaches new pages. Nothing is
  /// pinned on a terrain held in memory.
  double residency_margin = 16.0;
};

/// What one TerrainSync::update() did.
struct TerrainSyncStats {
  /// Change-log entries handled (Terrain::changes_since: one per edit, or one merged entry).
  std::size_t changes = 0;
  /// The log no longer reached back to the version last seen: one merged box covered everything.
  bool trimmed = false;
  /// Contact manifolds between the terrain object and a body over a changed box that were
  /// cleared (their points lay on the old surface).
  std::size_t manifolds_cleared = 0;
  /// Non-static collision objects over a changed box that were activated (woken).
  std::size_t bodies_woken = 0;
  /// Of those, rigid bodies lifted out of the ground (TerrainSyncDesc::lift_buried).
  std::size_t bodies_lifted = 0;
  /// Level-0 pages kept resident under the bodies after this update (paged terrains).
  std::size_t pinned_pages = 0;
  /// Whether the set of pages under the bodies changed (new pins, prefetches sent).
  bool residency_changed = false;
};

/// Follows a terrain's edits for one Bullet world: the TerrainShape reads the surface live, so
/// the ground itself never needs a rebuild; what Bullet caches about it does. Each update():
///  1. pulls Terrain::changes_since(the version seen last) (nothing to do, and nothing allocated,
///     when no edit happened);
///  2. refreshes the terrain object's box in the broadphase (an edit may raise or lower the
///     ground beyond the heights it had);
///  3. for every changed box (world metres, converted with the shape's origin and widened by
///     wake_margin), finds through the broadphase the objects whose bounding boxes overlap it,
///     activates the non-static ones (a sleeping body over a new crater falls into it), and
///     clears the contact manifolds between the terrain object and those objects (their points
///     were on the old surface; Bullet makes new ones at the next step);
///  4. lifts the woken rigid bodies the edit buried (TerrainSyncDesc::lift_buried).
/// On a paged terrain it first keeps the pages under the non-static bodies resident
/// (TerrainSyncDesc::residency_margin): one pass over the world's objects, new pins only when a
/// body reaches other pages. Call it once per step, before btDynamicsWorld::stepSimulation, on the thread that steps.
///
/// The helper holds raw pointers to the world and the terrain object: both must outlive it, and
/// the object must stay in that world. Bodies may be added and removed freely between updates.
///
/// Threading: like the world it serves, one thread; never during an edit of the terrain or a
/// step of the world (it reads the log and touches the broadphase and the manifolds).
class TerrainSync {
 public:
  /// A helper for `terrain_object` (a collision object whose shape is a TerrainShape, added to
  /// `world`). It starts at the terrain's current edit_version(): edits made before create() are
  /// part of the surface the shape reads from the start. Errors, naming the problem: a null world
  /// or object, an object whose shape is not a TerrainShape, a bad wake margin.
  static Result<TerrainSync> create(btCollisionWorld* world, btCollisionObject* terrain_object,
                                    const TerrainSyncDesc& desc = {});

  TerrainSync(TerrainSync&&) noexcept = default;
  TerrainSync& operator=(TerrainSync&&) noexcept = default;
  TerrainSync(const TerrainSync&) = delete;
  TerrainSync& operator=(const TerrainSync&) = delete;

  /// Brings the world's contacts and sleeping bodies up to date with every edit since the last
  /// call (see the class comment). Cost: nothing without edits on a terrain held in memory; else
  /// one broadphase box query per change plus one pass over the world's manifolds, and on a
  /// paged terrain one pass over the world's objects.
  TerrainSyncStats update();

  /// The terrain version handled so far (Terrain::edit_version() at the last update()).
  std::uint64_t seen_version() const noexcept { return seen_; }
  const TerrainShape& shape() const noexcept { return *shape_; }

 private:
  TerrainSync(btCollisionWorld* world, btCollisionObject* object, const TerrainShape* shape,
              const TerrainSyncDesc& desc);
  btCollisionWorld* world_;
  btCollisionObject* object_;
  const TerrainShape* shape_;
  TerrainSyncDesc desc_;
  // Lifts `o` out of the ground when it is a rigid body whose centre of mass is under the surface.
  bool lift_if_buried(btCollisionObject& o) const;
  std::uint64_t seen_ = 0;
  std::vector<const btCollisionObject*> touched_;  // reused: the objects over changed boxes
  // Paged terrains: keeps the pages under the bodies pinned (see residency_margin).
  void keep_resident(TerrainSyncStats& stats);
  std::vector<std::uint64_t> page_keys_, next_keys_;  // pages pinned, as (pz << 32 | px)
  std::vector<RegionPin> pins_;
};

}  // namespace ridgeline::bullet
