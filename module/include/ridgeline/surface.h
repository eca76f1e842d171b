// The surface (docs/surface.md): the contract every consumer shares (the diagonal rule and the
// triangle lookup inside a cell, defined once), the answers of the queries on it, and the
// Surface: the finest lattice of a terrain (stored samples with their edits, plus procedural
// detail) with every point query written once over it.
//
// Every consumer (the full-detail mesh, height/normal/ray queries, error measurement, the
// detail field, tests) locates triangles through cell_has_main_diagonal() and locate_in_cell()
// (lattice_cell.h, included here), so what physics sees and what the finest level of the
// tessellation draws cannot drift apart.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "ridgeline/heightfield.h"
#include "ridgeline/lattice_cell.h"
#include "ridgeline/world.h"

namespace ridgeline {

class DetailField;
class DetailCache;
class EditLayer;
class HoleMask;
class Terrain;
namespace world {
class PageStore;
}
namespace detail {
struct SurfaceAccess;
}

// ---- what the queries answer ------------------------------------------------------------------

/// Height, both normals and the material at a point of the surface.
struct SurfaceSample {
  double height = 0;                 ///< world height, metres
  glm::vec3 face_normal{0, 1, 0};    ///< unit normal of the triangle under the point (physics)
  glm::vec3 smooth_normal{0, 1, 0};  ///< unit normal interpolated from vertex normals (shading)
  std::uint8_t material = 0;         ///< material id of the cell under the point
};

/// Height, face normal and material at a point: what a physics contact needs, cheaper than
/// SurfaceSample (no smooth normal).
struct HeightNormal {
  double height = 0;               ///< world height, metres
  glm::vec3 face_normal{0, 1, 0};  ///< unit normal of the triangle under the point
  std::uint8_t material = 0;       ///< material id of the cell under the point
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

// ---- the surface -------------------------------------------------------------------------------

/// Where the finest lattice lies. Vertex (i, j), 0 <= i < vertices_x, 0 <= j < vertices_z, sits at
/// world (origin_x + i * spacing_x, origin_z + j * spacing_z); its height is height_offset plus
/// its local height (Surface::vertex_height). Cell (i, j) is the square between vertices i..i+1
/// and j..j+1, split by the diagonal rule in these (finest) indices.
struct SurfaceLattice {
  /// Detail levels L: the finest lattice is the stored one subdivided 2^L times per cell side
  /// (0: the stored samples are the finest lattice).
  std::uint32_t levels = 0;
  /// Vertices per axis: (stored samples - 1) * 2^L + 1; below 2^30 + 1.
  std::int64_t vertices_x = 0, vertices_z = 0;
  /// Metres between neighbouring vertices: the stored spacing / 2^L.
  double spacing_x = 1, spacing_z = 1;
  /// 2^L / stored spacing: what the queries multiply world offsets by to find a cell (exactly
  /// 1 / spacing when that is representable), so a caller doing the same finds the same cell.
  double inv_spacing_x = 1, inv_spacing_z = 1;
  /// World position of vertex (0, 0), metres (the stored sample (0, 0)).
  double origin_x = 0, origin_z = 0;
  /// World height of local height 0, metres (Heightfield::height_offset()).
  double height_offset = 0;
};

/// The surface of a Terrain (docs/surface.md): the finest lattice, whose vertex heights are the
/// stored samples (edits included) interpolated over the diagonal rule plus, with L > 0 detail
/// levels, the procedural detail (detail.h); with L = 0 it is the stored lattice itself. Every
/// point query is defined here once, over that lattice: the height is the barycentric blend of
/// the three finest vertices of the triangle under the point, the face normal that triangle's,
/// the smooth normal the blend of the area-weighted vertex normals, the material the stored
/// cell's. Rays and box queries read the same lattice (Terrain::raycast,
/// Terrain::triangles_in_box).
///
/// The stored samples live in pages (world.h). A terrain made from a Heightfield holds every page;
/// a terrain opened from a baked world pages them in: a query whose page is not resident loads
/// it on the calling thread first (a synchronous load, about 0.2-1 ms a page: docs/worlds.md),
/// unless an engine pinned or prefetched the region (Terrain::pin, Terrain::prefetch). A page
/// that cannot be loaded (the source's error is logged) answers as off-terrain.
///
/// Owned by a Terrain (Terrain::surface()), which also owns the sparse edit layer inside it and
/// is the only writer: an edit changes the surface inside Terrain::apply_edit() or load_edits()
/// (edit.h). Threading: every method may run concurrently from any number of threads, never
/// during an edit (terrain.h). Pages and detail tiles come from snapshots kept per thread and
/// refreshed when their caches publish: no lock per call.
///
/// Queries take world coordinates in double precision. Points outside the footprint (including
/// the padding that patches add), and NaN or infinite input, give an empty optional; they never
/// have undefined behaviour. A point exactly on the far edge (x = origin_x + extent_x) is on the
/// surface.
class Surface {
 public:
  ~Surface();
  Surface(const Surface&) = delete;
  Surface& operator=(const Surface&) = delete;

  // ---- what the surface is made of -----------------------------------------------------------

  /// The stored samples' size, placement and encoding (edits widen min_local / max_local).
  const WorldInfo& info() const noexcept;
  /// The finest lattice's size and placement.
  const SurfaceLattice& lattice() const noexcept { return lattice_; }
  /// Detail levels L (0: no procedural detail).
  std::uint32_t detail_levels() const noexcept { return lattice_.levels; }
  /// The detail field, or null without detail.
  const DetailField* detail() const noexcept { return detail_.get(); }
  /// The detail tile cache, or null without detail. Its owner (the engine's frame loop, once per
  /// frame) calls update(); views and DetailStream request tiles through it. Thread-safe
  /// (detail.h).
  DetailCache* detail_cache() const noexcept { return cache_.get(); }
  /// 64-bit hash of the detail parameters (0 without detail): save files record it.
  std::uint64_t detail_hash() const noexcept { return detail_hash_; }
  /// Bound (metres) on |detail| at every vertex (DetailField::contribution_bound(1)); 0 without
  /// detail. The surface lies within this of the stored samples' interpolation.
  double detail_bound() const noexcept { return detail_bound_; }
  /// Hash of the current stored samples (base + edits), computed like WorldInfo::content_hash:
  /// equal hashes, equal surfaces (for the same detail parameters). O(samples); on a paged world
  /// it loads every page.
  std::uint64_t heights_hash() const;
  /// Number of 32 x 32-sample chunks of stored samples that edits have changed (0 when unedited).
  std::size_t edited_chunks() const noexcept;
  /// Bytes held: resident pages (heights, materials, ray pyramids; the tessellator's bounds are
  /// counted by its Landscape) and the detail field (not the detail cache's tiles: see
  /// DetailCache::stats()).
  std::size_t memory_bytes() const noexcept;

  // ---- the stored samples and the finest lattice, vertex by vertex ----------------------------

  /// Local height (metres, relative to info().height_offset) of stored sample (i, j), edits
  /// included, with (i, j) clamped into the data (the edge-repeating padding).
  float stored_height(std::int64_t i, std::int64_t j) const noexcept;
  /// The stored samples (edits included) and materials as one Heightfield: the same local
  /// heights bit for bit, with height_scale 1 (what tools and comparators that need the whole
  /// field at once read). O(samples) memory; on a paged world it loads every page. Fails only
  /// when the field exceeds `max_samples`.
  Result<Heightfield> to_heightfield(std::uint64_t max_samples = std::uint64_t{1} << 31) const;
  /// Local height (metres, relative to lattice().height_offset) of finest-lattice vertex (i, j):
  /// base + detail, edits included. Indices outside the lattice are clamped into it (the
  /// edge-repeating padding of docs/surface.md). Without detail this is the stored sample.
  double vertex_height(std::int64_t i, std::int64_t j) const noexcept;
  /// Vertex normal (area-weighted mean of the face normals of the finest triangles around the
  /// vertex; unit, y > 0) at finest-lattice vertex (i, j), clamped into the lattice: what
  /// shading wants at a mesh vertex.
  glm::vec3 vertex_normal(std::int64_t i, std::int64_t j) const noexcept;
  /// Detail alone (metres) at finest-lattice vertex (i, j), clamped into the lattice; 0 without
  /// detail and at stored samples.
  double vertex_detail(std::int64_t i, std::int64_t j) const noexcept;
  /// The stored surface alone (edits included, no detail) at finest-lattice vertex (i, j),
  /// clamped into the lattice: vertex_height() - vertex_detail(), what a vertex's height is
  /// known to be before its detail is.
  double vertex_base_height(std::int64_t i, std::int64_t j) const noexcept;
  /// Material id of finest-lattice cell (i, j) (that of the stored cell holding it), clamped into
  /// the lattice's cells; 0 when the data has no material layer.
  std::uint8_t cell_material(std::int64_t i, std::int64_t j) const noexcept;
  /// Measured bound (metres) on |D_L - P_{from_level - 1}| over the finest-lattice rectangle
  /// [i0, i1] x [j0, j1] when it lies inside one resident finest tile (its
  /// DetailTile::measured_contribution), else +infinity (also without detail).
  double measured_detail_bound(std::uint32_t from_level, std::int64_t i0, std::int64_t j0,
                               std::int64_t i1, std::int64_t j1) const noexcept;

  // ---- holes (docs/deformation.md, "Holes") -----------------------------------------------------

  /// Whether stored cell (i, j) (between samples i..i+1 and j..j+1) is a hole: no ground there,
  /// so every point query over it is empty, rays and bodies pass through and no mesh triangle
  /// covers it. False outside the cells. Holes come from the `hole` brush and from no-data or
  /// alpha at load (io.h); `fill_hole` gives the ground back. Cost: one branch on a terrain
  /// without holes, a hash lookup with them.
  bool hole(std::int64_t i, std::int64_t j) const noexcept;
  /// Stored cells that are holes (0 on a terrain without holes).
  std::uint64_t hole_cells() const noexcept;

  // ---- point queries ---------------------------------------------------------------------------
  // Over a hole every query is empty (batched heights: NaN). A point on the boundary between a
  // hole cell and a solid one belongs to the solid one: the ground ends exactly at the hole's
  // edge, as the mesh does.

  /// World height of the surface at (x, z), metres; empty off the footprint, over a hole or for
  /// non-finite input.
  std::optional<double> height(double x, double z) const noexcept;
  /// Face normal (unit, y > 0) of the finest triangle under (x, z). Points on an edge shared by
  /// two triangles take the triangle that locate_in_cell() picks. Empty as for height().
  std::optional<glm::vec3> face_normal(double x, double z) const noexcept;
  /// Smooth normal (unit, y > 0): barycentric blend of the vertex normals of the triangle under
  /// (x, z). Empty as for height().
  std::optional<glm::vec3> smooth_normal(double x, double z) const noexcept;
  /// Material id of the stored cell under (x, z) (edge points as for face_normal()); 0 when the
  /// data has no material layer. Empty as for height().
  std::optional<std::uint8_t> material(double x, double z) const noexcept;
  /// Height, face normal and material in one lookup. Empty as for height().
  std::optional<HeightNormal> height_normal(double x, double z) const noexcept;
  /// Height, both normals and the material in one lookup. Empty as for height().
  std::optional<SurfaceSample> sample(double x, double z) const noexcept;

  /// Batched heights: out[k] = height(xz[k]) or NaN off the footprint, for k < min(xz.size(),
  /// out.size()), bit for bit. Fetches the cell of the point a few places ahead while
  /// evaluating the current one, which pays on scattered points over large worlds.
  void heights(std::span<const glm::dvec2> xz, std::span<double> out) const noexcept;
  /// Batched samples: valid[k] says whether out[k] is meaningful (out[k] is SurfaceSample{} when
  /// not), for k below the smallest of the three sizes.
  void samples(std::span<const glm::dvec2> xz, std::span<SurfaceSample> out,
               std::span<std::uint8_t> valid) const noexcept;

 private:
  friend class Terrain;  // creates and clones it; its edits are the only writer of the pages
  friend struct detail::SurfaceAccess;  // the lattice views of module/src/surface/lattice.h
  struct CloneTag {};
  Surface(std::shared_ptr<world::PageStore> store, std::shared_ptr<const DetailField> detail,
          std::unique_ptr<DetailCache> cache);
  Surface(const Surface& other, CloneTag);

  std::shared_ptr<world::PageStore> store_;
  std::unique_ptr<EditLayer> edits_;  // the original heights of every edited chunk, the holes
  const HoleMask* holes_ = nullptr;   // edits_->holes(), read by every query: null without holes
  void publish_holes(std::shared_ptr<const HoleMask> mask);
  SurfaceLattice lattice_;
  SurfaceLattice stored_at_;  // the stored samples as a lattice (L = 0)
  std::shared_ptr<const DetailField> detail_;
  std::unique_ptr<DetailCache> cache_;
  std::uint64_t detail_hash_ = 0;
  double detail_bound_ = 0;
};

}  // namespace ridgeline
