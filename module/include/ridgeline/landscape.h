// Landscape: the terrain cut into patches of bintree roots, with nested error bounds and bounding
// spheres per diamond. Shared, read-only data that every RoamView (one per camera) reads.
#pragma once

#include <cstdint>
#include <glm/vec3.hpp>
#include <memory>
#include <vector>

#include "ridgeline/result.h"
#include "ridgeline/terrain.h"

namespace ridgeline {

struct LandscapeDesc {
  /// Patches hold 2^patch_exponent cells per side (2^k + 1 samples). 2..10; default 6 (65 x 65
  /// samples). Larger patches: fewer roots, bigger per-patch buffers, longer edits per patch.
  std::uint32_t patch_exponent = 6;
  /// Geomorph window w (docs/roam.md, "Geomorphs"): a vertex morphs from its edge to its true
  /// height while its projected bound grows from (1 + morph_delay) times the threshold to
  /// (1 + morph_delay + w) times it. To let every vertex finish before a finer one can start,
  /// the morph bounds grow by a factor sqrt(1 + morph_delay + w) per level up the hierarchy,
  /// which costs some triangles on smooth ground. 0 turns geomorphs and that growth off (the
  /// morph bound is the error bound; vertices appear at their true heights). 0..4.
  double morph_window = 0.2;
  /// Geomorph delay delta: a new vertex stays on the edge it splits until its projected bound
  /// exceeds (1 + delta) times the threshold. A diamond splits at the first update where its
  /// ratio exceeds 1, which camera motion puts anywhere up to one frame's change of the ratio
  /// beyond 1: the delay absorbs that step, so the vertex is born at t = 0 and does not pop.
  /// The drawn mesh's error bound grows with it (docs/roam.md). 0..1; ignored when the window
  /// is 0.
  double morph_delay = 0.1;
};

/// What a vertex shader needs besides a MeshVertex to draw its geomorph (morph_factor() in
/// roam_view.h; docs/roam.md, "Geomorphs"): the landscape's window and delay.
struct Geomorph {
  double window = 0.2;
  double delay = 0.1;
};

/// A bintree triangle in global lattice coordinates: apex and the two ends of its hypotenuse,
/// counter-clockwise seen from above (apex, left, right).
struct LatticeTriangle {
  std::int64_t ax, az, lx, lz, rx, rz;
};

/// What the tessellator knows of one diamond, metres. Every lattice vertex that is not a patch
/// corner is the centre of one diamond: the bintree triangles whose hypotenuse it halves.
struct DiamondBound {
  /// Error bound: the largest vertical distance between the surface and either triangle of the
  /// diamond over every lattice vertex under it, made nested (at least every descendant
  /// diamond's). What ErrorMetric::kWorldMetres compares with the tolerance.
  float error = 0;
  /// Morph bound: the error bound grown by sqrt(1 + morph_delay + morph_window) per level up the
  /// hierarchy (LandscapeDesc). What the screen-pixel metric and geomorphs use.
  float morph = 0;
  /// Radius of a sphere about the centre vertex at its true height that holds every lattice
  /// vertex under the diamond and every descendant's sphere (nested). FLT_MAX marks a diamond
  /// that straddles the border of the sampled data: always split, so that the mesh ends exactly
  /// on the border.
  float radius = 0;
};

/// What a mesh vertex needs besides its position: the smooth (area-weighted) normal of the
/// finest surface at the vertex and, for a diamond centre, the height of the midpoint of the
/// hypotenuse it splits relative to its own (the geomorph offset; 0 for patch corners).
struct VertexShading {
  glm::vec3 normal{0, 1, 0};
  float morph_dy = 0;
  std::uint8_t material = 0;  ///< material id of the stored cell at the vertex (clamped in)
};

/// Patches and error bounds over a Terrain.
///
/// Layout: the sampled area is covered by patches_x() x patches_z() patches; the last row and
/// column of patches may extend past the samples: that padding repeats the edge samples and is
/// not terrain (queries there are off-terrain, and a RoamView refines every triangle that
/// straddles the data's border, so its mesh ends exactly on it and drops the padding). Each patch
/// has two roots split along its main diagonal; root ids are patch * 2 + r, patch = px + pz *
/// patches_x(). Node ids inside a root are heap indices: the root is 1, the children of h are 2h
/// and 2h + 1 (child 0 holds the root's left corner).
///
/// Bounds (docs/roam.md, "Error bounds"): for every diamond the exact error of its triangles
/// (the largest |surface - triangle plane| over every lattice vertex under them), made nested
/// over the diamond hierarchy, plus a nested bounding sphere. Stored per vertex of the stored
/// lattice (12 bytes of a 28-byte record per sample); below the stored resolution (procedural
/// detail) derived from the detail field's amplitude bounds, or from a resident tile's measured
/// bounds.
///
/// Edits: after Terrain::apply_edit() the bounds over the changed region are out of date until
/// sync() (RoamView::update() calls it first) recomputes exactly the diamonds whose bounds the
/// changed samples reach. changes_since() lists the changed regions for views.
///
/// Threading: every method may run concurrently with every other, except that sync() after an
/// edit must not overlap other readers of this landscape (views calling it concurrently
/// serialise on an internal lock). Edits to the terrain need exclusive access (terrain.h).
namespace roam {
struct LandscapeAccess;  // the tessellator's inline reads of the records (module/src/roam)
}

class Landscape {
 public:
  static Result<std::shared_ptr<const Landscape>> create(std::shared_ptr<const Terrain> terrain,
                                                         const LandscapeDesc& desc = {});
  ~Landscape();
  Landscape(const Landscape&) = delete;
  Landscape& operator=(const Landscape&) = delete;

  const Terrain& terrain() const noexcept { return *terrain_; }
  const std::shared_ptr<const Terrain>& terrain_ptr() const noexcept { return terrain_; }

  std::uint32_t patch_exponent() const noexcept { return exponent_; }
  /// The geomorph parameters of LandscapeDesc (window and delay), for morph_factor().
  Geomorph geomorph() const noexcept { return geomorph_; }
  /// Detail levels L of the terrain: lattice coordinates below are on the finest lattice
  /// (spacing / 2^L); a patch spans 2^(patch_exponent + L) of its cells.
  std::uint32_t detail_levels() const noexcept { return detail_; }
  std::int64_t patch_cells() const noexcept { return std::int64_t{1} << (exponent_ + detail_); }
  /// log2 of patch_cells().
  int patch_log2() const noexcept { return int(exponent_ + detail_); }
  std::uint32_t patches_x() const noexcept { return patches_x_; }
  std::uint32_t patches_z() const noexcept { return patches_z_; }
  std::uint32_t patch_count() const noexcept { return patches_x_ * patches_z_; }
  std::uint32_t root_count() const noexcept { return 2 * patch_count(); }
  /// Deepest bintree level: 2 * (patch_exponent + L) (half-cell triangles of the finest lattice).
  /// Levels from 2 * patch_exponent on refine into procedural detail.
  std::uint32_t max_level() const noexcept { return 2 * (exponent_ + detail_); }
  /// Deepest level of the stored lattice's triangles: 2 * patch_exponent.
  std::uint32_t base_level() const noexcept { return 2 * exponent_; }

  /// Geometry of node `heap` of root `root` (walks the path: O(level)).
  LatticeTriangle triangle(std::uint32_t root, std::uint64_t heap) const noexcept;
  /// Geometry of node `heap` of root `root` whose apex is (ax, az), in O(1): the direction from
  /// the apex to the hypotenuse midpoint follows from the root and the path bits, its length from
  /// the level.
  LatticeTriangle triangle_at(std::int64_t ax, std::int64_t az, std::uint32_t root,
                              std::uint64_t heap) const noexcept;
  /// Lattice bounding box [i0, i1] x [j0, j1] of a triangle.
  struct LatticeBox {
    std::int64_t i0, i1, j0, j1;
  };
  static LatticeBox box_of(const LatticeTriangle& t) noexcept;
  /// Geometry of a child given its parent's (child 0 or 1): (M, A, L) and (M, R, A), M the
  /// midpoint of the hypotenuse.
  static LatticeTriangle child_triangle(const LatticeTriangle& t, int child) noexcept {
    const std::int64_t mx = (t.lx + t.rx) / 2, mz = (t.lz + t.rz) / 2;
    if (child == 0) return {mx, mz, t.ax, t.az, t.lx, t.lz};
    return {mx, mz, t.rx, t.rz, t.ax, t.az};
  }

  /// Bounds of the diamond centred at finest-lattice vertex (i, j), which must be a diamond
  /// centre inside the landscape (0 <= i <= patches_x() * patch_cells(), same for j; not a patch
  /// corner: asserted, zeros returned past the assert).
  DiamondBound diamond(std::int64_t i, std::int64_t j) const noexcept;
  /// Shading data of finest-lattice vertex (i, j), inside the landscape (padding included).
  /// Stored once per sample without procedural detail (in the bounds' 28-byte record), computed
  /// otherwise.
  VertexShading shading(std::int64_t i, std::int64_t j) const noexcept;
  /// For vertices below the stored resolution: the bound of |detail| over the diamond's reach,
  /// metres (what a sphere about a vertex whose detail is not known yet must add). 0 for stored
  /// vertices or without detail.
  float detail_offset_bound(std::int64_t i, std::int64_t j) const noexcept;

  /// Nested error bound of node `heap` of root `root`: its diamond's DiamondBound::error, metres
  /// (0 for the finest level, whose triangles never split).
  float bound(std::uint32_t root, std::uint64_t heap) const noexcept;
  float bound(std::uint32_t root, std::uint64_t heap, const LatticeTriangle& t) const noexcept;
  /// Exact (not nested) error of a node of the stored levels against the stored lattice (without
  /// detail), metres: used by tests and the minimal-triangulation reference. O(area) per call.
  float exact_error(std::uint32_t root, std::uint64_t heap) const noexcept;

  /// Height of finest-lattice vertex (i, j) relative to the heightfield's offset (base + detail +
  /// edits), with the padding rule (indices clamped into the footprint).
  float lattice_height(std::int64_t i, std::int64_t j) const noexcept;
  /// Height relative to the offset of the stored surface (no detail) at finest-lattice vertex
  /// (i, j): what a vertex's height is known to be within detail_offset_bound() of before its
  /// detail tile is resident.
  float base_lattice_height(std::int64_t i, std::int64_t j) const noexcept;
  /// World x / z of a lattice index.
  double world_x(std::int64_t i) const noexcept { return origin_x_ + double(i) * spacing_x_; }
  double world_z(std::int64_t j) const noexcept { return origin_z_ + double(j) * spacing_z_; }
  /// Metres between finest-lattice vertices along x and z.
  double spacing_x() const noexcept { return spacing_x_; }
  double spacing_z() const noexcept { return spacing_z_; }
  /// True when lattice vertex (i, j) is inside the sampled area (not padding).
  bool is_sampled(std::int64_t i, std::int64_t j) const noexcept {
    return i >= 0 && j >= 0 && i <= last_i_ && j <= last_j_;
  }
  /// Largest magnitude, metres, of a lattice position or height relative to the landscape's
  /// origin and the height offset (padding included).
  double local_extent() const noexcept;
  /// The last finest-lattice index inside the footprint along x and z.
  std::int64_t last_i() const noexcept { return last_i_; }
  std::int64_t last_j() const noexcept { return last_j_; }

  /// An edited region of the finest lattice: every vertex whose height, or whose diamond's bound,
  /// may have changed lies inside the inclusive rectangle, widened by the diamond's reach for
  /// ancestors (RoamView handles that).
  struct Change {
    std::uint64_t version = 0;  ///< the landscape's change version this region produced
    std::int64_t i0 = 0, j0 = 0, i1 = 0, j1 = 0;
  };
  /// Brings the bounds up to date with the terrain's edits (no-op when they are): pulls
  /// Terrain::changes_since(synced_version()) and recomputes the bounds each change reaches.
  /// Logically const: the bounds always describe the terrain's current surface once it returns.
  void sync() const;
  /// The Terrain::edit_version() the bounds reflect (that of the last sync(), or of creation).
  std::uint64_t synced_version() const noexcept;
  /// Version counter of the bounds: increases with every synced edit.
  std::uint64_t version() const noexcept;
  /// Changes after `version` (call after sync()). `trimmed` is set when the bounded log (1,024
  /// regions) no longer reaches back that far: the one region returned then covers the whole
  /// landscape.
  std::vector<Change> changes_since(std::uint64_t version, bool* trimmed = nullptr) const;

  /// Bytes of the bound and shading arrays, and how long building them took.
  std::size_t bound_bytes() const noexcept { return records_.size() * sizeof(VertexRecord); }
  double build_ms() const noexcept { return build_ms_; }

 private:
  friend struct roam::LandscapeAccess;
  Landscape() = default;
  struct Impl;
  // Exact error against the stored lattice of a triangle in stored-lattice coordinates.
  float compute_exact(const LatticeTriangle& t) const noexcept;
  float base_height(std::int64_t i, std::int64_t j) const noexcept {
    return terrain_->heightfield().local_clamped(i, j);
  }
  // Bounds of one stored diamond from its triangles and its children (stored coordinates).
  DiamondBound compute_stored(std::int64_t i, std::int64_t j) const noexcept;
  DiamondBound diamond_slow(std::int64_t i, std::int64_t j) const noexcept;
  // Bounds of a diamond below the stored resolution (finest coordinates).
  DiamondBound compute_detail(std::int64_t i, std::int64_t j) const noexcept;
  // Recomputes the stored bounds reached by a change of samples [i0, i1] x [j0, j1] (stored
  // coordinates, inclusive); returns the diamonds recomputed.
  std::uint64_t update_region(std::int64_t i0, std::int64_t j0, std::int64_t i1, std::int64_t j1);
  // Records in tiles of 4 x 4 vertices (448 bytes), tiles row by row: a diamond's neighbours and
  // children at the fine levels share cache lines with it.
  std::size_t stored_index(std::int64_t i, std::int64_t j) const noexcept {
    return ((std::size_t(j) >> 2) * std::size_t(tiles_x_) + (std::size_t(i) >> 2)) * 16 +
           ((std::size_t(j) & 3) << 2) + (std::size_t(i) & 3);
  }

  std::shared_ptr<const Terrain> terrain_;
  std::uint32_t exponent_ = 6, detail_ = 0, patches_x_ = 0, patches_z_ = 0;
  Geomorph geomorph_;
  double morph_growth_ = 1.0;  // sqrt(1 + delay + window) per level; 1 without geomorphs
  std::int64_t last_i_ = 0, last_j_ = 0;
  std::int64_t stored_w_ = 0, stored_h_ = 0;  // stored lattice vertices per row / column (padded)
  // Per stored vertex: its diamond's bounds (unused for patch corners), and without detail its
  // height (a copy of the terrain's, refreshed by sync()), its geomorph offset and its normal's
  // x and z in 1/32767 units (y > 0 follows).
  struct VertexRecord {
    DiamondBound bound;
    float height = 0, morph_dy = 0;
    std::int16_t nx = 0, nz = 0;
    std::uint8_t material = 0;
  };
  std::vector<VertexRecord> records_;
  std::int64_t tiles_x_ = 0;
  static VertexShading unpack(const VertexRecord& p) noexcept;
  VertexShading compute_shading(std::int64_t i, std::int64_t j) const noexcept;
  void store_shading(std::int64_t i, std::int64_t j) noexcept;
  // Per depth below the stored lattice (procedural detail): the growth factors the morph bound's
  // closed form needs (landscape.cpp, compute_detail()).
  std::vector<double> detail_amp_growth_, detail_round_growth_;
  double origin_x_ = 0, origin_z_ = 0, spacing_x_ = 1, spacing_z_ = 1;
  double build_ms_ = 0;
  std::unique_ptr<Impl> impl_;  // edit log, sync lock
};

}  // namespace ridgeline
