// Terrain: shared, read-mostly terrain data (heightfield, procedural detail, edits, ray hierarchy),
// the physics queries on its surface (surface.h, docs/surface.md) and the change log through which
// views, physics and engines learn what edits changed.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "ridgeline/heightfield.h"
#include "ridgeline/result.h"

namespace ridgeline {

class RayHierarchy;
class EditLayer;
class DetailField;
class DetailCache;
struct DetailParams;
struct DetailCacheDesc;
struct Edit;
struct EditLimits;
struct EditResult;
class ChangeLog;

/// Height, both normals and the material at a point of the surface.
struct SurfaceSample {
  double height = 0;             ///< world height, metres
  glm::vec3 face_normal{0, 1, 0};    ///< unit normal of the triangle under the point (physics)
  glm::vec3 smooth_normal{0, 1, 0};  ///< unit normal interpolated from vertex normals (shading)
  std::uint8_t material = 0;     ///< material id of the cell under the point
};

/// Height, face normal and material at a point: what a physics contact needs, cheaper than
/// SurfaceSample (no smooth normal).
struct HeightNormal {
  double height = 0;                ///< world height, metres
  glm::vec3 face_normal{0, 1, 0};   ///< unit normal of the triangle under the point
  std::uint8_t material = 0;        ///< material id of the cell under the point
};

/// The first intersection of a ray with the surface.
struct RayHit {
  double distance = 0;        ///< metres along the (normalised) direction from the origin
  glm::dvec3 point{0};        ///< world position of the hit
  glm::vec3 normal{0, 1, 0};  ///< face normal of the triangle hit (unit, points up)
  std::uint8_t material = 0;
  bool started_below = false;  ///< the origin was below the surface: distance 0, point = origin
};

/// A full-detail surface triangle in world coordinates, counter-clockwise seen from above.
struct SurfaceTriangle {
  glm::dvec3 v[3];
  std::uint8_t material = 0;
};

/// Axis-aligned box in world coordinates (metres). min <= max per axis.
struct Box {
  glm::dvec3 min{0};
  glm::dvec3 max{0};
};

/// An inclusive range of finest-lattice vertex indices, [i0, i1] x [j0, j1]: vertex (i, j) sits
/// at world (origin_x + i * spacing_x / 2^L, origin_z + j * spacing_z / 2^L), L being
/// Terrain::detail_levels() (the stored samples when L = 0). Empty when i1 < i0 or j1 < j0.
struct LatticeRange {
  std::int64_t i0 = 0, j0 = 0, i1 = -1, j1 = -1;
  bool empty() const noexcept { return i1 < i0 || j1 < j0; }
};

/// What one edit (or one loaded edit state) changed: an entry of the terrain's change log.
struct TerrainChange {
  /// The Terrain::edit_version() this change produced (for a merged entry: the newest one).
  std::uint64_t version = 0;
  /// Where the surface changed, world metres: x and z span every finest-lattice cell touching a
  /// changed vertex (the triangles whose shape or normals changed), clamped to the footprint;
  /// y spans the surface over that region before and after the change. What an engine refreshes
  /// its physics shape over and wakes the bodies in.
  Box box;
  /// The finest-lattice vertices whose height may have changed (every changed one is inside;
  /// some inside may be unchanged), within the footprint: what a tessellator refreshes. An edit
  /// of stored samples moves the interpolated detail-lattice vertices in the cells around them.
  LatticeRange vertices;
};

/// The answer of Terrain::changes_since().
struct TerrainChanges {
  /// The terrain's edit_version() now: what to pass to the next changes_since() call.
  std::uint64_t version = 0;
  /// The changes after the version asked for, oldest first; or, when `trimmed`, a single entry
  /// covering all of them. Empty when nothing changed.
  std::vector<TerrainChange> changes;
  /// The log no longer reaches back to the version asked for (more than kChangeLogCapacity
  /// changes ago), or that version is not one this terrain had: `changes` holds one merged
  /// entry covering everything that may differ (the whole footprint for an unknown version).
  bool trimmed = false;
  bool empty() const noexcept { return changes.empty(); }
};

/// Changes a Terrain's log holds one by one (about 90 bytes each). Older ones are merged into a
/// single summary entry, so changes_since() always answers, with coarser boxes past this many.
inline constexpr std::size_t kChangeLogCapacity = 1024;

/// The terrain shared by every view and every physics query. Created once from a Heightfield;
/// changed afterwards only by edits (apply_edit, load_edits in edit.h).
///
/// Edits are pulled, not pushed: every edit that changes the surface bumps edit_version() and
/// records what it changed in a bounded change log; whoever caches something derived from the
/// surface (a Landscape's bounds, a RoamView's mesh, a physics engine's shape, a game's sleeping
/// bodies) keeps the version it has seen and asks changes_since(it) when it next runs, as Jolt's
/// HeightFieldShape::SetHeights is followed by NotifyShapeChanged and waking the bodies in the
/// box. Nothing is called back from inside an edit.
///
/// Threading: every const method may run concurrently from any number of threads. An edit
/// (apply_edit(), load_edits(), set_edit_limits()) needs exclusive access, as in Jolt's
/// HeightFieldShape: one thread edits, and no other call on this terrain, on a Landscape or
/// RoamView built on it, or on its change log may run meanwhile (querying while modifying is a
/// race). Between edits any number of threads may query, pull changes_since() and update views.
/// An engine whose physics thread must keep querying during edits queries a clone() (a
/// snapshot) and swaps it after the edit.
///
/// Queries take world coordinates in double precision. Points outside the sampled area (including
/// the padding that patches add), and NaN or infinite input, give an empty optional or no hit;
/// they never have undefined behaviour. A point exactly on the far edge (x = origin_x + extent_x)
/// is on the terrain.
class Terrain {
 public:
  /// Builds the query acceleration structures (a max-height pyramid for rays). Never fails for a
  /// valid Heightfield.
  static std::shared_ptr<Terrain> create(Heightfield heightfield);
  /// A terrain whose surface includes procedural detail with L = detail.levels levels
  /// (docs/detail.md, docs/surface.md): every query, Landscape and RoamView then works on the
  /// finest lattice (spacing / 2^L), whose vertex heights are base + detail (+ edits). The terrain
  /// owns the detail field and a tile cache made from `cache`; detail values come from the cache's
  /// tiles when resident and from the direct evaluator otherwise (bit-identical). Fails, naming the
  /// field, on invalid parameters. detail.levels == 0 gives a terrain without detail.
  static Result<std::shared_ptr<Terrain>> create(Heightfield heightfield, const DetailParams& detail,
                                                 const DetailCacheDesc& cache);

  ~Terrain();
  Terrain(const Terrain&) = delete;
  Terrain& operator=(const Terrain&) = delete;

  const Heightfield& heightfield() const noexcept { return heightfield_; }

  /// World height of the surface at (x, z), metres; empty off-terrain or for non-finite input.
  std::optional<double> height(double x, double z) const noexcept;
  /// Face normal (unit, y > 0) of the triangle under (x, z). Points on an edge shared by two
  /// triangles take the triangle that locate_in_cell() picks.
  std::optional<glm::vec3> face_normal(double x, double z) const noexcept;
  /// Smooth normal (unit, y > 0): barycentric blend of the vertex normals of the triangle under
  /// (x, z); a vertex normal is the area-weighted mean of the face normals of the triangles
  /// around the vertex.
  std::optional<glm::vec3> smooth_normal(double x, double z) const noexcept;
  /// Height, face normal and material in one call (one lookup instead of two); empty off-terrain
  /// or for non-finite input.
  std::optional<HeightNormal> height_normal(double x, double z) const noexcept;
  /// Height, both normals and the material in one call.
  std::optional<SurfaceSample> sample(double x, double z) const noexcept;

  /// Batched heights: out[k] = height(xz[k]) or NaN off-terrain. out.size() must be >= xz.size().
  void heights(std::span<const glm::dvec2> xz, std::span<double> out) const noexcept;
  /// Batched samples: valid[k] says whether out[k] is meaningful. Sizes as for heights().
  void samples(std::span<const glm::dvec2> xz, std::span<SurfaceSample> out,
               std::span<std::uint8_t> valid) const noexcept;

  /// First intersection of the ray origin + t * normalize(direction), 0 <= t <= max_distance,
  /// with the surface: the smallest such t at which the ray is over the footprint and at or below
  /// the surface. max_distance may be +infinity.
  /// - Starting below the surface (inside the solid under it): a hit at distance 0 with
  ///   started_below = true, point = origin, the normal of the triangle under the origin.
  /// - Starting outside the footprint: the ray is clipped to it; if it enters below the surface
  ///   level it hits at the entry point (the side of the solid), started_below = false.
  /// - Touching counts: a ray that grazes the surface at a point, runs along it, starts exactly
  ///   on it, or passes within the touch tolerance of it (1e-9 * (1 + the largest |height -
  ///   height_offset|) metres: rounding, not geometry) hits at the first touching point.
  /// - Vertical rays, rays exactly along cell edges or diagonals and rays through vertices are
  ///   ordinary rays; they take the same answers as above (tested against a brute-force reference).
  /// - Empty when the ray misses, leaves the footprint before meeting the surface (nothing beyond
  ///   the edge is hit), direction is zero, max_distance <= 0 or NaN, or any origin or direction
  ///   component is non-finite. Direction need not be normalised; its length is irrelevant.
  /// Cost: the ray descends a min/max pyramid, so a long ray costs about the number of pyramid
  /// nodes it crosses at the level where it clears the terrain, not the number of cells.
  std::optional<RayHit> raycast(const glm::dvec3& origin, const glm::dvec3& direction,
                                double max_distance) const noexcept;

  /// Appends to `out` every full-detail triangle whose xz footprint overlaps the box's xz range
  /// (closed: touching counts; exact triangle/rectangle test, not bounding boxes) and whose
  /// height range (min..max of its corners) overlaps [box.min.y, box.max.y]: what a physics
  /// mid-phase asks for. Triangles are in world coordinates, counter-clockwise seen from above
  /// (locate_in_cell's corner order), with their cell's material; padding is never returned.
  /// Returns the number appended. `max_triangles` caps the work (0 = no cap); when the cap is
  /// hit the result is truncated and the return value equals the cap. A box with a non-finite
  /// coordinate or min > max on any axis appends nothing and returns 0.
  std::size_t triangles_in_box(const Box& box, std::vector<SurfaceTriangle>& out,
                               std::size_t max_triangles = 0) const;

  // ---- procedural detail (detail.h, docs/detail.md) ----------------------------------------

  /// Detail levels L of the surface (0: the stored lattice is the finest).
  std::uint32_t detail_levels() const noexcept { return detail_levels_; }
  /// The detail field, or null without detail.
  const DetailField* detail() const noexcept { return detail_.get(); }
  /// The tile cache, or null without detail. Its owner (the engine's frame loop, once per frame)
  /// calls update(); views request tiles through it. Thread-safe (detail.h).
  DetailCache* detail_cache() const noexcept { return cache_.get(); }
  /// Finest-lattice samples per axis: (width - 1) * 2^L + 1 and (height - 1) * 2^L + 1.
  std::int64_t fine_width() const noexcept;
  std::int64_t fine_height() const noexcept;
  /// Height relative to the offset of finest-lattice vertex (i, j) (base + detail + edits);
  /// indices outside the footprint are clamped to it (the padding rule). Detail comes from the
  /// cache's current snapshot (kept per thread, refreshed when the cache publishes: no lock per
  /// call) or is evaluated directly. Without detail this is the stored height.
  double fine_local_height(std::int64_t i, std::int64_t j) const noexcept;
  /// Vertex normal (area-weighted, unit, y > 0) at finest-lattice vertex (i, j), which must lie
  /// in the footprint: what shading wants at a mesh vertex.
  glm::vec3 lattice_vertex_normal(std::int64_t i, std::int64_t j) const noexcept;
  /// Measured bound (metres) on |D_L - P_{from_level - 1}| over the finest-lattice rectangle
  /// [i0, i1] x [j0, j1] when it lies inside one resident finest tile (its
  /// DetailTile::measured_contribution), else +infinity. Through the per-thread snapshot.
  double measured_detail_bound(std::uint32_t from_level, std::int64_t i0, std::int64_t j0,
                               std::int64_t i1, std::int64_t j1) const noexcept;
  /// Detail (metres) at finest-lattice vertex (i, j) alone; 0 without detail.
  double detail_at(std::int64_t i, std::int64_t j) const noexcept;
  /// 64-bit hash of the detail parameters (0 without detail): save files record it.
  std::uint64_t detail_hash() const noexcept { return detail_hash_; }

  // ---- deformation (edit.h, docs/deformation.md) -------------------------------------------

  /// Applies one brush as one transaction: changes the heights (clamped to the edit limits),
  /// refreshes the ray pyramid over the changed blocks, bumps edit_version() and records the
  /// change in the log (changes_since()). Every query sees the new surface when it returns;
  /// Landscapes and RoamViews catch up at their next sync() / update(). Cost follows the edited
  /// area, never the terrain size.
  /// Errors (nothing changes): a field fails validate_edit(), the radius exceeds the terrain's
  /// larger extent, the area cap is exceeded with EditLimits::refuse_oversize, or keep_detail is
  /// false on a terrain with detail (edit.h). A brush wholly outside the terrain, or one that
  /// changes no height, is a no-op with an empty result (no version, no log entry). Exclusive
  /// access (see above).
  Result<EditResult> apply_edit(const Edit& edit);
  /// Limits for later edits (validated: finite, area > 0, min < max; else an error and no change).
  Status set_edit_limits(const EditLimits& limits);
  const EditLimits& edit_limits() const noexcept;
  /// Number of 32 x 32-sample chunks the edit layer holds (0 when unedited).
  std::size_t edited_chunks() const noexcept;
  /// Hash of the heightfield as created, before any edit (what save files record).
  std::uint64_t base_hash() const noexcept { return base_hash_; }
  /// Hash of the current heights (base + edits): equal hashes, equal surfaces.
  std::uint64_t heights_hash() const noexcept { return heightfield_.content_hash(); }
  /// The surface's version: 0 as created, one more with every edit or load that changed a
  /// height (one change-log entry each).
  std::uint64_t edit_version() const noexcept { return edit_version_; }
  /// What changed after version `version` (an edit_version() value seen earlier), and the
  /// current version. A consumer keeps `result.version` and asks again with it next time:
  ///   auto c = terrain.changes_since(seen);  // nothing new: c.empty()
  ///   for (const TerrainChange& ch : c.changes) refresh(ch.box);
  ///   seen = c.version;
  /// Within the last kChangeLogCapacity changes the answer lists them one by one; further back
  /// it is one merged entry and `trimmed` (correct, coarser). A version above edit_version() is
  /// not this terrain's: one entry covering the whole footprint, `trimmed`. Cost: O(entries
  /// returned); allocates only when something changed. Any thread, concurrently with queries
  /// and other pulls, never during an edit.
  TerrainChanges changes_since(std::uint64_t version) const;
  /// A deep copy (heights, ray pyramid, edit layer, limits, version and change log), not
  /// attached to any Landscape: a snapshot a physics thread can query while this terrain is
  /// being edited.
  std::shared_ptr<Terrain> clone() const;

  /// Checks the query structures against the surface: the ray pyramid equals, node by node, one
  /// rebuilt from the current heights. Returns an empty string when it holds, else the first
  /// difference. O(samples): for tests and debugging after edits.
  std::string check_invariants() const;

  /// Bytes held: heights, materials, ray hierarchy.
  std::size_t memory_bytes() const noexcept;
  /// Bytes held by the ray hierarchy alone (the min/max pyramid over 4 x 4-cell blocks, about
  /// 0.67 bytes per sample).
  std::size_t ray_hierarchy_bytes() const noexcept;

 private:
  explicit Terrain(Heightfield heightfield);

  Heightfield heightfield_;
  std::unique_ptr<RayHierarchy> rays_;
  std::unique_ptr<EditLayer> edits_;
  std::unique_ptr<ChangeLog> log_;
  std::uint64_t base_hash_ = 0;
  std::uint64_t edit_version_ = 0;
  std::uint32_t detail_levels_ = 0;
  std::shared_ptr<const DetailField> detail_;
  std::unique_ptr<DetailCache> cache_;
  std::uint64_t detail_hash_ = 0;
  // Detail versions of the point queries (terrain_detail.cpp).
  struct FineLocated;
  bool locate_fine(double x, double z, FineLocated& p) const noexcept;
  double fine_height_at(const FineLocated& p) const noexcept;
  glm::vec3 fine_face_normal(const FineLocated& p) const noexcept;
  glm::vec3 fine_smooth_normal(const FineLocated& p) const noexcept;
  std::uint8_t fine_material(const FineLocated& p) const noexcept;
  // Cached for the query fast path.
  double inv_spacing_x_ = 1, inv_spacing_z_ = 1;

  // The edit file's reader and writer (edit.cpp) reach the edit layer and the transaction.
  friend Result<EditResult> load_edits_from_memory(Terrain&, std::string_view);
  friend Status save_edits(const Terrain&, const std::string&);
};

}  // namespace ridgeline
