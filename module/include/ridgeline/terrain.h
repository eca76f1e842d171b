// Terrain: shared, read-mostly terrain data (heightfield, ray hierarchy) and the physics queries on
// the surface of surface.h.
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
namespace detail {
class EditListener;
}

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

/// The terrain shared by every view and every physics query. Created once from a Heightfield;
/// changed afterwards only by edits (apply_edit, load_edits in edit.h).
///
/// Threading: every const method may run concurrently from any number of threads. An edit needs
/// exclusive access, as in Jolt's HeightFieldShape: no query, Landscape or RoamView call on this
/// terrain may run during apply_edit() or load_edits() (querying while modifying is a race). An
/// engine whose physics thread must keep querying during edits queries a clone() (a snapshot)
/// and swaps it after the edit.
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
  /// A terrain whose surface includes procedural detail (SPEC.md "The surface" with L =
  /// detail.levels levels; docs/detail.md): every query, Landscape and RoamView then works on the
  /// finest lattice (spacing / 2^L), whose vertex heights are base + detail. The terrain owns the
  /// detail field and a tile cache made from `cache`; detail values come from the cache's tiles
  /// when resident and from the direct evaluator otherwise (bit-identical). Fails, naming the
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
  /// refreshes the ray pyramid over the changed blocks, recomputes the error bounds of exactly
  /// the bintree nodes of every attached Landscape whose triangles hold a changed sample
  /// (bottom-up), and in every RoamView on those landscapes refreshes the nodes over the changed
  /// region, requeues the queued ones with fresh priorities and marks the patches dirty. Queries
  /// see the new surface when it returns. Cost follows the edited area (plus a rescan of the
  /// top levels of the touched patches), never the terrain size.
  /// Errors (nothing changes): a field fails validate_edit(), the radius exceeds the terrain's
  /// larger extent, or the area cap is exceeded with EditLimits::refuse_oversize. A brush wholly
  /// outside the terrain is a no-op with an empty result. Exclusive access (see above).
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
  /// Increases by one with every edit or load that changed something.
  std::uint64_t edit_version() const noexcept { return edit_version_; }
  /// A deep copy (heights, ray pyramid, edit layer, limits), not attached to any Landscape: a
  /// snapshot a physics thread can query while this terrain is being edited.
  std::shared_ptr<Terrain> clone() const;

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

  // Landscapes register here to hear of edits (internal; Landscape and edit.cpp only).
  friend class Landscape;
  friend class EditLayer;
  friend Result<EditResult> load_edits_from_memory(Terrain&, std::string_view);
  friend Status save_edits(const Terrain&, const std::string&);
  void add_listener(detail::EditListener* l) const;
  void remove_listener(detail::EditListener* l) const;
  struct Listeners;
  std::unique_ptr<Listeners> listeners_;
};

}  // namespace ridgeline
