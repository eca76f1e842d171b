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
  /// Patches hold 2^patch_exponent cells per side (2^k + 1 samples). 2..10; 0 (the default)
  /// takes the world's: the exponent a baked world's bounds were made for, else 6 (65 x 65
  /// samples), raised for worlds of more than 64 x 64 such patches (at most 10). Larger patches:
  /// fewer roots, bigger per-patch buffers, longer edits per patch.
  std::uint32_t patch_exponent = 0;
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
  /// vertex under the diamond and every descendant's sphere (nested). FLT_MAX (or infinity)
  /// marks a diamond that straddles the border of the sampled data: always split, so that the
  /// mesh ends exactly on the border.
  float radius = 0;
};

namespace roam {
struct LandscapeAccess;  // the tessellator's reads of the landscape (module/src/roam)
class Reader;
}  // namespace roam

/// The terrain cut into patches of bintree roots, with the tessellator's bounds of every diamond:
/// what every RoamView over it (one per camera) shares. Made once per terrain and tessellator
/// configuration; read-only afterwards.
///
/// Layout: the sampled area is covered by patches_x() x patches_z() patches; the last row and
/// column of patches may extend past the samples: that padding repeats the edge samples and is
/// not terrain (queries there are off-terrain, and a RoamView refines every triangle that
/// straddles the data's border, so its mesh ends exactly on it and drops the padding). Each patch
/// has two roots split along its main diagonal; root ids are patch * 2 + r, patch = px + pz *
/// patches_x(). Node ids inside a root are heap indices: the root is 1, the children of h are 2h
/// and 2h + 1 (child 0 holds the root's left corner).
///
/// Bounds (docs/roam.md, "Error bounds"; docs/worlds.md): per diamond an error bound, a morph
/// bound and a bounding sphere, nested over the diamond hierarchy, held with the terrain's pages
/// (6 bytes per diamond, about 3 bytes per stored sample). On a terrain in memory they are
/// computed here for every page (O(samples log samples), on up to 8 threads); on a baked world
/// the coarse ones come with its pages and the finest are computed as each page arrives, and
/// the configuration must be the one the world was baked for. Edits refresh them inside
/// Terrain::apply_edit(); views pull the terrain's change log.
///
/// Threading: every method may run concurrently with every other. Edits to the terrain need
/// exclusive access (terrain.h).
class Landscape {
 public:
  /// Fails, naming the setting, on a patch exponent outside 2..10, a morph window outside 0..4
  /// or a delay outside 0..1, too many patches, a baked world whose bounds were made for another
  /// configuration, or a terrain whose pages already carry four configurations' bounds.
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
  /// Geometry of a child given its parent's (child 0 or 1): (M, A, L) and (M, R, A), M the
  /// midpoint of the hypotenuse.
  static LatticeTriangle child_triangle(const LatticeTriangle& t, int child) noexcept {
    const std::int64_t mx = (t.lx + t.rx) / 2, mz = (t.lz + t.rz) / 2;
    if (child == 0) return {mx, mz, t.ax, t.az, t.lx, t.lz};
    return {mx, mz, t.rx, t.rz, t.ax, t.az};
  }
  /// Lattice bounding box [i0, i1] x [j0, j1] of a triangle.
  struct LatticeBox {
    std::int64_t i0, i1, j0, j1;
  };
  static LatticeBox box_of(const LatticeTriangle& t) noexcept;

  /// Bounds of the diamond centred at finest-lattice vertex (i, j), which must be a diamond
  /// centre inside the landscape (not a patch corner: zeros). On a baked world the page holding
  /// it is loaded when it is not resident.
  DiamondBound diamond(std::int64_t i, std::int64_t j) const noexcept;
  /// Nested error bound of node `heap` of root `root`: its diamond's DiamondBound::error, metres
  /// (0 for the finest level, whose triangles never split).
  float bound(std::uint32_t root, std::uint64_t heap) const noexcept;

  /// Bytes of the bounds this landscape made (on a terrain in memory; on a baked world they are
  /// counted with the pages: Terrain::world_stats()), and how long making them took.
  std::size_t bound_bytes() const noexcept;
  double build_ms() const noexcept { return build_ms_; }

 private:
  friend struct roam::LandscapeAccess;
  friend class roam::Reader;
  Landscape() = default;
  struct Impl;

  std::shared_ptr<const Terrain> terrain_;
  std::uint32_t exponent_ = 6, detail_ = 0, patches_x_ = 0, patches_z_ = 0;
  Geomorph geomorph_;
  double build_ms_ = 0;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ridgeline
