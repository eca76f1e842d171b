// Terrain: the shared terrain an engine builds once: its surface (surface.h: stored samples,
// edits and procedural detail, with the point queries), the ray hierarchy that rays and box
// queries descend, and the edit transaction with the change log through which views, physics
// and engines learn what edits changed.
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

#include "ridgeline/edit_limits.h"
#include "ridgeline/heightfield.h"
#include "ridgeline/result.h"
#include "ridgeline/surface.h"
#include "ridgeline/world.h"

namespace ridgeline {

class EditLayer;
class DetailField;
class DetailCache;
struct DetailParams;
struct DetailCacheDesc;
struct Edit;
struct EditResult;
class EditSink;
class ChangeLog;
struct SampleChanges;
namespace detail {
struct SurfaceAccess;
struct TerrainAccess;
}  // namespace detail
namespace world {
class PageEdit;
}  // namespace world

/// An inclusive range of finest-lattice vertex indices, [i0, i1] x [j0, j1]: vertex (i, j) sits
/// at world (origin_x + i * spacing_x / 2^L, origin_z + j * spacing_z / 2^L), L being the
/// surface's detail levels (SurfaceLattice; the stored samples when L = 0). Empty when i1 < i0 or
/// j1 < j0.
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

/// A region kept resident (Terrain::pin): while it lives, the pages under it are never evicted,
/// so queries there never load. Move-only; releases the pages when destroyed or reset.
class RegionPin {
 public:
  RegionPin() = default;
  RegionPin(RegionPin&& o) noexcept : store_(std::move(o.store_)), keys_(std::move(o.keys_)) {}
  RegionPin& operator=(RegionPin&& o) noexcept;
  RegionPin(const RegionPin&) = delete;
  RegionPin& operator=(const RegionPin&) = delete;
  ~RegionPin() { reset(); }
  /// Releases the pages (the region may be evicted again).
  void reset() noexcept;
  /// Level-0 pages held.
  std::size_t pages() const noexcept { return keys_.size(); }

 private:
  friend class Terrain;
  std::shared_ptr<const world::PageStore> store_;
  std::vector<PageKey> keys_;
};

/// The terrain shared by every view and every physics query. Made once, from a Heightfield
/// (every page in memory) or from a PageSource (a baked world, paged in: docs/worlds.md); changed
/// afterwards only by edits (apply_edit, load_edits in edit.h). It composes the Surface
/// (surface(): the finest lattice and every point query on it), the ray and box queries (which
/// descend the min/max pyramid of its pages before reading the surface's lattice), and the edit
/// transaction (apply_edit(): the surface's pages, the version and the change log, changed
/// together).
///
/// Edits are pulled, not pushed: every edit that changes the surface bumps edit_version() and
/// records what it changed in a bounded change log; whoever caches something derived from the
/// surface (a RoamView's mesh, a physics engine's shape, a game's sleeping bodies) keeps the
/// version it has seen and asks changes_since(it) when it next runs, as Jolt's
/// HeightFieldShape::SetHeights is followed by NotifyShapeChanged and waking the bodies in the
/// box. Nothing is called back from inside an edit.
///
/// Threading: every const method may run concurrently from any number of threads. An edit
/// (apply_edit(), load_edits(), set_edit_limits()) needs exclusive access, as in Jolt's
/// HeightFieldShape: one thread edits, and no other call on this terrain, on a Landscape or
/// RoamView built on it, or on its change log may run meanwhile (querying while modifying is a
/// race). Between edits any number of threads may query, pull changes_since() and update views.
/// An engine whose physics thread must keep querying during edits queries a clone() (a
/// snapshot: it shares every page, so it costs about a pointer per page) and swaps it after the
/// edit.
///
/// Queries take world coordinates in double precision. Points outside the sampled area (including
/// the padding that patches add), and NaN or infinite input, give an empty optional or no hit;
/// they never have undefined behaviour. A point exactly on the far edge (x = origin_x + extent_x)
/// is on the terrain. On a paged world a query over a page that is not resident loads it on the
/// calling thread (surface.h); pin() and prefetch() keep that off the hot path.
class Terrain {
 public:
  /// A terrain holding `heightfield`'s samples in memory (every page resident; 16-bit when every
  /// sample is an integer times height_scale, so 16-bit input takes 2 bytes a sample). Never
  /// fails for a valid Heightfield (the Result is for symmetry with the other makers).
  static Result<std::shared_ptr<Terrain>> create(Heightfield heightfield);
  /// A terrain whose surface includes procedural detail with L = detail.levels levels
  /// (docs/detail.md, docs/surface.md): every query, Landscape and RoamView then works on the
  /// finest lattice (spacing / 2^L), whose vertex heights are base + detail (+ edits). The
  /// surface owns the detail field and a tile cache made from `cache`; detail values come from
  /// the cache's tiles when resident and from the direct evaluator otherwise (bit-identical).
  /// Fails, naming the field, on invalid parameters, or when the finest lattice would have 2^30
  /// cells or more per side. detail.levels == 0 gives a terrain without detail.
  static Result<std::shared_ptr<Terrain>> create(Heightfield heightfield, const DetailParams& detail,
                                                 const DetailCacheDesc& cache);
  /// A terrain over a world served by `source` (io::open_world for a baked world, or an engine's
  /// own PageSource), paged in under `cache`'s budget: reads the world's page summaries and its
  /// coarse levels, nothing proportional to the world. Fails (naming the world) when the source
  /// does, or when `cache` is invalid.
  static Result<std::shared_ptr<Terrain>> open(std::shared_ptr<const PageSource> source,
                                               const WorldCacheDesc& cache = {});

  ~Terrain();
  Terrain(const Terrain&) = delete;
  Terrain& operator=(const Terrain&) = delete;

  /// The surface: stored samples (with edits), detail, the finest lattice and the point queries.
  const Surface& surface() const noexcept { return surface_; }
  /// The stored samples' size, placement and encoding: surface().info().
  const WorldInfo& info() const noexcept { return surface_.info(); }

  // ---- queries ---------------------------------------------------------------------------------
  // The point queries are the surface's (surface.h documents them); these forward to it.

  /// Surface::height(): world height at (x, z), metres; empty off-terrain or for non-finite input.
  std::optional<double> height(double x, double z) const noexcept { return surface_.height(x, z); }
  /// Surface::face_normal(): unit normal of the finest triangle under (x, z).
  std::optional<glm::vec3> face_normal(double x, double z) const noexcept {
    return surface_.face_normal(x, z);
  }
  /// Surface::smooth_normal(): blend of the vertex normals of the triangle under (x, z).
  std::optional<glm::vec3> smooth_normal(double x, double z) const noexcept {
    return surface_.smooth_normal(x, z);
  }
  /// Surface::height_normal(): height, face normal and material in one lookup.
  std::optional<HeightNormal> height_normal(double x, double z) const noexcept {
    return surface_.height_normal(x, z);
  }
  /// Surface::sample(): height, both normals and the material in one lookup.
  std::optional<SurfaceSample> sample(double x, double z) const noexcept {
    return surface_.sample(x, z);
  }
  /// Surface::heights(): batched heights, NaN off-terrain.
  void heights(std::span<const glm::dvec2> xz, std::span<double> out) const noexcept {
    surface_.heights(xz, out);
  }
  /// Surface::samples(): batched samples; valid[k] says whether out[k] is meaningful.
  void samples(std::span<const glm::dvec2> xz, std::span<SurfaceSample> out,
               std::span<std::uint8_t> valid) const noexcept {
    surface_.samples(xz, out, valid);
  }

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
  /// Cost: the ray descends the min/max pyramid (widened by the detail bound), so a long ray
  /// costs about the number of pyramid nodes it crosses at the level where it clears the
  /// terrain, not the number of cells; it meets the surface's finest cells only in the leaf
  /// blocks it cannot skip. On a paged world the pages of those blocks are loaded when missing.
  std::optional<RayHit> raycast(const glm::dvec3& origin, const glm::dvec3& direction,
                                double max_distance) const noexcept;

  /// Appends to `out` every finest-lattice triangle whose xz footprint overlaps the box's xz range
  /// (closed: touching counts; exact triangle/rectangle test, not bounding boxes) and whose
  /// height range (min..max of its corners) overlaps [box.min.y, box.max.y]: what a physics
  /// mid-phase asks for. Triangles are in world coordinates, counter-clockwise seen from above
  /// (locate_in_cell's corner order), with their cell's material; padding is never returned.
  /// Returns the number appended. `max_triangles` caps the work (0 = no cap); when the cap is
  /// hit the result is truncated and the return value equals the cap. A box with a non-finite
  /// coordinate or min > max on any axis appends nothing and returns 0.
  std::size_t triangles_in_box(const Box& box, std::vector<SurfaceTriangle>& out,
                               std::size_t max_triangles = 0) const;

  // ---- residency (docs/worlds.md) ------------------------------------------------------------

  /// Keeps the stored pages under the xz range of `region` resident until the returned pin is
  /// destroyed, loading the missing ones now on this thread: what a physics engine holds around
  /// each body (a residency radius) so that its queries never load. Empty for an invalid box
  /// (non-finite, min > max) or one off the footprint. On a terrain held in memory it holds
  /// nothing (every page is resident anyway).
  RegionPin pin(const Box& region) const;
  /// Asks for the pages under `region` to be loaded in the background (never waits); they are
  /// resident after a later update_pages() once loaded.
  void prefetch(const Box& region) const;
  /// Integrates the pages loaded since the last call, evicts least recently used ones beyond the
  /// cache's budget and publishes the new set to readers. RoamView::update() calls it; an engine
  /// that only queries calls it once per frame. Any thread; cheap when nothing changed.
  void update_pages() const;
  /// The pages' streaming statistics (for a terrain held in memory: everything resident).
  WorldStats world_stats() const;
  /// True when the stored samples are paged in from a source (Terrain::open()).
  bool paged() const noexcept;

  // ---- deformation (edit.h, docs/deformation.md) -------------------------------------------

  /// Applies one brush as one transaction: changes the surface's stored samples (clamped to the
  /// edit limits; the edit layer keeps the originals), refreshes the pages' ray pyramids and the
  /// tessellator's bounds over the changed region, bumps edit_version() and records the change
  /// in the log (changes_since()). Every query sees the new surface when it returns; RoamViews
  /// catch up at their next update(). Cost follows the edited area and the patch size, never the
  /// terrain size; on a paged world the pages it touches are loaded first and stay resident
  /// (an edited page is never evicted).
  /// Errors (nothing changes): a field fails validate_edit(), the radius exceeds the terrain's
  /// larger extent, the area cap is exceeded with EditLimits::refuse_oversize, or keep_detail is
  /// false on a terrain with detail (edit.h). A brush wholly outside the terrain, or one that
  /// changes no height, is a no-op with an empty result (no version, no log entry). Exclusive
  /// access (see above).
  Result<EditResult> apply_edit(const Edit& edit);
  /// Stored heights over a rectangle of samples, for editors and engines that stream their own
  /// formats (as Jolt's HeightFieldShape::GetHeights / SetHeights): columns i0 .. i0 + width - 1
  /// and rows j0 .. j0 + height - 1 of the stored lattice, row r of the rectangle at
  /// heights[r * stride] (stride >= width, in floats). World heights in metres, edits included,
  /// procedural detail not (it rides on top of the stored heights). Errors (nothing read or
  /// changed): an empty rectangle or one past the stored samples, a stride below the width, a
  /// span too short for the rectangle.
  Status get_heights(std::uint32_t i0, std::uint32_t j0, std::uint32_t width,
                     std::uint32_t height, std::span<float> heights, std::size_t stride) const;
  /// Sets them: one edit (one version, one change-log entry, views and queries follow, saved with
  /// the edits), clamped to EditLimits' height range as brushes are. Errors, besides
  /// get_heights' (nothing changes): a non-finite height (naming the sample), a rectangle whose
  /// area passes EditLimits::max_area_m2. Exclusive access (see above).
  Result<EditResult> set_heights(std::uint32_t i0, std::uint32_t j0, std::uint32_t width,
                                 std::uint32_t height, std::span<const float> heights,
                                 std::size_t stride);
  /// Limits for later edits (validated: finite, area > 0, min < max; else an error and no change).
  Status set_edit_limits(const EditLimits& limits);
  const EditLimits& edit_limits() const noexcept { return edit_limits_; }
  /// Hash of the stored samples as created, before any edit (info().content_hash: what save
  /// files record; a baked world and the map it was baked from have the same one).
  std::uint64_t base_hash() const noexcept { return base_hash_; }
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
  /// and other pulls, never during an edit. docs/engine_integration.md shows a physics engine's
  /// collider kept up to date this way.
  TerrainChanges changes_since(std::uint64_t version) const;
  /// A snapshot (pages shared, copy on write: about a pointer per page; the edit layer, limits,
  /// version and change log copied; the detail field shared, immutable, with a tile cache of its
  /// own), not attached to any Landscape: a physics thread can query it while this terrain is
  /// being edited. A clone of a paged world loads what it misses synchronously.
  std::shared_ptr<Terrain> clone() const;

  /// Checks the query structures against the surface: every resident page's ray pyramid, the
  /// page summaries and the pyramid above pages equal ones rebuilt from the current samples.
  /// Returns an empty string when they hold, else the first difference. O(resident samples):
  /// for tests and debugging after edits.
  std::string check_invariants() const;

  /// Bytes held: the surface (resident pages, detail field) and the edit layer.
  std::size_t memory_bytes() const noexcept;

 private:
  Terrain(std::shared_ptr<world::PageStore> store, std::shared_ptr<const DetailField> detail,
          std::unique_ptr<DetailCache> cache);
  Terrain(const Terrain& other, Surface::CloneTag);
  friend struct detail::SurfaceAccess;
  friend struct detail::TerrainAccess;

  // The edit transaction (module/src/edit/): after the surface's samples changed, refreshes the
  // tessellator's bounds over them, bumps the version, records the change and fills the result's
  // box.
  void commit(const SampleChanges& changes, EditResult& result);
  // The hole brushes (edit/hole_edit.cpp), after apply_edit's checks: `result` holds the radius.
  EditResult edit_holes(const Edit& edit, EditResult result);
  // The holes of a field made with FillPolicy::kHole, at creation.
  void take_holes(const Heightfield& heightfield);
  void write_sample(world::PageEdit& edit, EditLayer& layer, SampleChanges& changes,
                    EditResult& result, std::uint32_t i, std::uint32_t j, float old, double h);
  EditLayer& edit_layer() noexcept;
  const EditLayer& edit_layer() const noexcept;

  Surface surface_;
  std::unique_ptr<ChangeLog> log_;
  std::uint64_t base_hash_ = 0;
  std::uint64_t edit_version_ = 0;
  EditLimits edit_limits_;

  // The edit file's reader and writer (edit/edit_file.cpp) reach the edit layer and the
  // transaction.
  friend Result<EditResult> load_edits_from_memory(Terrain&, std::string_view);
  friend Status save_edits(const Terrain&, EditSink&);
};

}  // namespace ridgeline
