// TerrainShape: a Bullet Physics collision shape backed by a Ridgeline terrain's surface
// (docs/engine_integration.md, "Bullet"). Bodies collide with the finest triangles under their
// bounding box, read from the terrain when Bullet asks (Terrain::triangles_in_box); rays go
// through Ridgeline's own raycast. Nothing is copied per body or per edit: an edit, procedural
// detail and (later) holes are seen by the next query, without a rebuild.
#pragma once

#include <BulletCollision/CollisionShapes/btConcaveShape.h>
#include <LinearMath/btVector3.h>

#include <cstdint>
#include <glm/vec3.hpp>
#include <memory>
#include <optional>

#include "ridgeline/result.h"
#include "ridgeline/terrain.h"

class btTriangleRaycastCallback;

namespace ridgeline::bullet {

/// How a TerrainShape is made. Plain data with sane defaults.
struct TerrainShapeDesc {
  /// The Ridgeline world position (metres, double precision) of the shape's local origin: a
  /// point of the terrain at world position w is at local position w - origin. With the terrain's
  /// collision object at the identity transform (the recommended set-up), local positions are
  /// Bullet's world positions, so Bullet's float coordinates are measured from `origin`, not from
  /// Ridgeline's (0, 0, 0). Put it near where the bodies are (the centre of the play area): see
  /// "Precision" in TerrainShape. Every component finite; the default is Ridgeline's origin.
  glm::dvec3 origin{0.0};
  /// Bullet's collision margin of each terrain triangle, metres: finite, >= 0. 0 (the default,
  /// as for Bullet's own btHeightfieldTerrainShape) puts contacts on the surface itself; a few
  /// centimetres make boxes and hulls (GJK/EPA against triangles) more robust at the price of
  /// resting that far above the surface.
  double margin = 0.0;
};

/// Which finest-lattice triangle a Bullet triangle index names (TerrainShape::triangle_id).
struct TriangleId {
  /// Finest-lattice cell (i, j): the square between lattice vertices i..i+1 and j..j+1
  /// (surface.h, SurfaceLattice; the stored samples when the terrain has no detail).
  std::int64_t i = 0, j = 0;
  /// Which of the cell's two triangles, as surface.h's CellTriangle::which (locate_in_cell).
  int which = 0;
};

/// A static Bullet concave shape whose triangles are a Ridgeline terrain's finest triangles
/// (the surface every query, ray and full-detail mesh shares: docs/surface.md). Put it on one
/// static btCollisionObject (mass 0); any number of rigid bodies, vehicles and queries may then
/// touch it.
///
/// **Contacts.** Bullet's convex-concave algorithm asks processAllTriangles() for the triangles
/// under a body's bounding box once per step and pair; the shape answers with
/// Terrain::triangles_in_box() over that box (exact triangle/box overlap, the box's height range
/// included), converted to shape-local floats in a per-thread scratch buffer that is reused, so
/// nothing is copied per body, per step or per edit. A box larger than 32 x 32 finest cells is
/// split into 32-cell tiles, each triangle reported once, so that a huge box (a debug drawer's
/// whole world) costs time, not memory. Each reported triangle carries its cell's material id as
/// its part id (Bullet's `partId`, btManifoldPoint::m_partId0/1, LocalShapeInfo::m_shapePart:
/// what a contact callback needs to tell mud from rock) and its lattice cell and half as its
/// triangle index (triangle_id() decodes it; -1 when the lattice has 2^30 cells or more).
/// Triangles are counter-clockwise seen from above, so Bullet's face normals point up (+y).
///
/// **Rays.** btCollisionWorld::rayTest (and so btRaycastVehicle's default raycaster) hands a
/// concave shape that is neither a triangle mesh nor a btHeightfieldTerrainShape to
/// processAllTriangles() with a btTriangleRaycastCallback and the ray's bounding box. The shape
/// recognises that callback and reports only the one triangle Ridgeline's Terrain::raycast()
/// hits (pyramid descent in double precision, not Bullet's per-triangle tests over the ray's
/// box): its fraction is distance / |to - from|, its normal the terrain's face normal (unit,
/// pointing up, never flipped), its part id the material and its triangle index as above. As
/// terrain.h defines: a ray starting below the surface hits at fraction 0 (the ground is solid),
/// unless the callback asks to filter back faces (btTriangleRaycastCallback::kF_FilterBackfaces),
/// which then reports nothing; a ray entering the footprint's side below the surface hits there;
/// nothing beyond the footprint's edge is hit. A hit no closer than the callback's current
/// m_hitFraction is not reported. Bullet's broadphase sees the shape's bounding box first, so
/// the solid ground ends 1 km under the lowest surface point (getAabb): a ray wholly below that
/// never reaches the shape.
///
/// **Holes and edits.** What triangles_in_box() does not return and what raycast() does not hit
/// is simply absent: bodies and rays pass through it. Edits change both at once; TerrainSync
/// (terrain_sync.h) wakes the bodies over a changed box and drops their stale contacts.
///
/// **Precision.** Ridgeline works in double-precision world metres, Bullet (the float build
/// btScalar) in float. Positions are exchanged relative to origin(): a triangle vertex is
/// computed in double, has origin() subtracted in double and is rounded once to float; a ray's
/// ends are added to origin() in double before Ridgeline traces it. A float local coordinate of
/// magnitude d is resolved to about d x 6e-8: 0.06 mm at 1 km from the origin, 0.6 mm at 10 km,
/// 6 mm at 100 km. Keep the bodies within a few kilometres of origin(); a game whose play area
/// moves further re-centres with set_origin() and shifts its bodies by the returned offset. A
/// world 1,000 km from Ridgeline's (0, 0, 0) is as precise as one at it when the origin is near.
///
/// **Units and frame.** Metres, Y up, the terrain spanning x and z (Ridgeline's frame); the
/// shape's local frame has the same axes. Bullet's gravity should point along -y.
///
/// **Threading.** processAllTriangles(), getAabb() and the other const methods may run from any
/// number of threads at once (a multithreaded Bullet world's parallel narrow phase): each thread
/// has its own scratch buffer, and the terrain's const queries are thread-safe. An edit of the
/// terrain (Terrain::apply_edit, load_edits) needs exclusive access: no Bullet step, ray test or
/// query on this shape may run during it (terrain.h). set_origin(), setMargin() and
/// setLocalScaling() change the shape: not while Bullet uses it.
///
/// **Not supported.** Collisions with other concave shapes (Bullet has no concave-concave
/// algorithm, as for its own heightfield), moving the shape (it is static: zero inertia), and
/// local scaling (setLocalScaling() is ignored: the terrain's own spacing and height scale
/// apply).
class TerrainShape final : public btConcaveShape {
 public:
  BT_DECLARE_ALIGNED_ALLOCATOR();

  /// A shape over `terrain`, which it keeps alive (shared, read only). Errors, naming the value:
  /// a null terrain, a non-finite origin component, a margin that is negative or not finite.
  static Result<std::unique_ptr<TerrainShape>> create(std::shared_ptr<const Terrain> terrain,
                                                      const TerrainShapeDesc& desc = {});

  ~TerrainShape() override;
  TerrainShape(const TerrainShape&) = delete;
  TerrainShape& operator=(const TerrainShape&) = delete;

  // ---- what Bullet calls ----------------------------------------------------------------------

  /// Reports to `callback` every finest triangle overlapping the local box [aabb_min, aabb_max]
  /// (closed; touching counts), in shape-local coordinates, each once; or, for a
  /// btTriangleRaycastCallback, the one triangle Ridgeline's raycast hits (see the class
  /// comment). A null callback, a box with a non-finite coordinate or min > max on an axis, and
  /// a box off the terrain report nothing.
  void processAllTriangles(btTriangleCallback* callback, const btVector3& aabb_min,
                           const btVector3& aabb_max) const override;
  /// The bounding box of the whole terrain under transform `t`: its footprint in x and z, and in
  /// y the stored heights' range (edits included: it widens as edits go beyond it) widened by
  /// the procedural detail's bound and the margin, reaching 1 km further down (the solid ground
  /// under the surface, for rays that start below it). TerrainSync refreshes the collision object's
  /// box in Bullet's broadphase after edits.
  void getAabb(const btTransform& t, btVector3& aabb_min, btVector3& aabb_max) const override;
  /// Ignored (the shape cannot be scaled); getLocalScaling() stays (1, 1, 1).
  void setLocalScaling(const btVector3& scaling) override;
  const btVector3& getLocalScaling() const override { return scaling_; }
  /// Zero: the shape is static.
  void calculateLocalInertia(btScalar mass, btVector3& inertia) const override;
  const char* getName() const override { return "RidgelineTerrain"; }
  /// Sets the triangles' collision margin, metres. A negative or non-finite value is ignored
  /// (the margin stays as it was).
  void setMargin(btScalar margin) override;

  // ---- coordinates ----------------------------------------------------------------------------

  /// World position (metres) of the local origin.
  const glm::dvec3& origin() const noexcept { return origin_; }
  /// Moves the local origin to `origin` (every component finite; otherwise nothing changes and
  /// the result is (0, 0, 0)). Returns the offset, new - old in float, by which the ground moved
  /// in local coordinates the other way: a caller keeps its bodies where they are on the ground
  /// by subtracting it from each body's position (and from anything else held in local
  /// coordinates), then refreshes the broadphase (btCollisionWorld::updateAabbs). Not while
  /// Bullet uses the shape.
  btVector3 set_origin(const glm::dvec3& origin) noexcept;
  /// World position (double) of local position `local`: origin() + local.
  glm::dvec3 to_world(const btVector3& local) const noexcept;
  /// Local position (float) of world position `world`: world - origin(), rounded once.
  btVector3 to_local(const glm::dvec3& world) const noexcept;

  // ---- what the shape reads and reports -------------------------------------------------------

  /// The terrain this shape reads.
  const Terrain& terrain() const noexcept { return *terrain_; }
  const std::shared_ptr<const Terrain>& terrain_ptr() const noexcept { return terrain_; }
  /// The lattice cell and half named by a triangle index this shape reported (contacts' m_index,
  /// rays' LocalShapeInfo::m_triangleIndex); empty for -1 or an index outside the lattice.
  std::optional<TriangleId> triangle_id(int triangle_index) const noexcept;

  /// The raycast callback's hit, as processAllTriangles() reports it (exposed for tests and for
  /// engines with their own callbacks): traces callback.m_from -> m_to (shape-local) through
  /// Terrain::raycast and calls reportHit() when it hits closer than callback.m_hitFraction.
  /// Returns whether it reported.
  bool report_ray(btTriangleRaycastCallback& callback) const;

 private:
  TerrainShape(std::shared_ptr<const Terrain> terrain, const TerrainShapeDesc& desc);
  // Reports the triangles of `box` (world metres) whose centroid lies in the half-open tile
  // [tx0, tx1) x [tz0, tz1) (world metres, infinite at the box's outer edges).
  void report_box(btTriangleCallback& callback, const Box& box, double tx0, double tx1, double tz0,
                  double tz1, bool filter) const;
  int triangle_index(const SurfaceTriangle& t) const noexcept;

  std::shared_ptr<const Terrain> terrain_;
  glm::dvec3 origin_{0.0};
  btVector3 scaling_{1, 1, 1};
  // The finest lattice (from the heightfield and the detail levels): origin, spacing, cells.
  double lattice_x0_ = 0, lattice_z0_ = 0, cell_x_ = 1, cell_z_ = 1;
  double inv_cell_x_ = 1, inv_cell_z_ = 1;
  std::int64_t cells_x_ = 0, cells_z_ = 0;
};

}  // namespace ridgeline::bullet
