// Landscape: the terrain cut into patches of bintree roots, with nested error bounds per node.
// Shared, read-only data that every RoamView (one per camera) reads.
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
};

/// A bintree triangle in global lattice coordinates: apex and the two ends of its hypotenuse,
/// counter-clockwise seen from above (apex, left, right).
struct LatticeTriangle {
  std::int64_t ax, az, lx, lz, rx, rz;
};

/// Patches and error bounds over a Terrain.
///
/// Layout: the sampled area is covered by patches_x() x patches_z() patches; the last row and
/// column of patches may extend past the samples: that padding repeats the edge samples
/// (SPEC.md) and is not terrain (queries there are off-terrain; mesh output flags the triangles
/// whose centre lies in it). Each patch has two roots split along its main diagonal; root ids
/// are patch * 2 + r, patch = px + pz * patches_x(). Node ids inside a root are heap indices:
/// the root is 1, the children of h are 2h and 2h + 1 (child 0 holds the root's left corner).
///
/// Error bounds (SPEC.md): for every node, the largest |surface - triangle plane| over every
/// lattice vertex under the node's triangle (the exact error), then made nested by taking the
/// maximum with the children's bounds. Finest-level nodes (half cells) have bound 0.
///
/// Edits: the bounds are a cache of the terrain's current surface, brought up to date by sync(),
/// which pulls the terrain's change log (Terrain::changes_since) and recomputes the bounds of
/// exactly the nodes whose triangles hold a changed vertex (bottom-up, then nested). Every
/// RoamView calls it at the start of its update(); nothing is pushed from inside an edit.
///
/// Threading: between edits every method may run concurrently, sync() included (it locks
/// internally). Edits need exclusive access (terrain.h): no landscape call during one.
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
  /// Detail levels L of the terrain: lattice coordinates below are on the finest lattice
  /// (spacing / 2^L); a patch spans 2^(patch_exponent + L) of its cells.
  std::uint32_t detail_levels() const noexcept { return detail_; }
  std::int64_t patch_cells() const noexcept { return std::int64_t{1} << (exponent_ + detail_); }
  std::uint32_t patches_x() const noexcept { return patches_x_; }
  std::uint32_t patches_z() const noexcept { return patches_z_; }
  std::uint32_t patch_count() const noexcept { return patches_x_ * patches_z_; }
  std::uint32_t root_count() const noexcept { return 2 * patch_count(); }
  /// Deepest bintree level: 2 * (patch_exponent + L) (half-cell triangles of the finest lattice).
  /// Levels below 2 * patch_exponent refine into procedural detail.
  std::uint32_t max_level() const noexcept { return 2 * (exponent_ + detail_); }
  /// Deepest level of the stored lattice: 2 * patch_exponent.
  std::uint32_t base_level() const noexcept { return 2 * exponent_; }

  /// Geometry of node `heap` of root `root`.
  LatticeTriangle triangle(std::uint32_t root, std::uint64_t heap) const noexcept;
  /// Geometry of node `heap` of root `root` whose apex is (ax, az), in O(1): the direction from
  /// the apex to the hypotenuse midpoint follows from the root and the path bits, its length from
  /// the level.
  LatticeTriangle triangle_at(std::int64_t ax, std::int64_t az, std::uint32_t root,
                              std::uint64_t heap) const noexcept {
    static constexpr int kUx[8] = {1, 1, 0, -1, -1, -1, 0, 1};
    static constexpr int kUz[8] = {0, 1, 1, 1, 0, -1, -1, -1};
    const int level = 63 - __builtin_clzll(heap);
    const int dir = ((root & 1) ? 7 : 3) + 3 * level + 2 * (popcount64(heap) - 1);
    const int k = dir & 7;
    const std::int64_t s2 = patch_cells() >> (level / 2);  // twice the apex-midpoint distance
    const std::int64_t ux = kUx[k], uz = kUz[k], px = -uz, pz = ux;  // p: u turned +90 degrees
    return {ax,
            az,
            ax + (ux + px) * s2 / 2,
            az + (uz + pz) * s2 / 2,
            ax + (ux - px) * s2 / 2,
            az + (uz - pz) * s2 / 2};
  }
  /// Lattice bounding box [i0, i1] x [j0, j1] of node `heap` of root `root` whose apex is
  /// (ax, az): triangle_at()'s corners without forming them (what a priority needs).
  struct LatticeBox {
    std::int64_t i0, i1, j0, j1;
  };
  LatticeBox box_at(std::int64_t ax, std::int64_t az, std::uint32_t root,
                    std::uint64_t heap) const noexcept {
    // Per direction k: the box's extent in units of s2 / 2 from the apex. With u the unit
    // step towards the hypotenuse and p = u turned +90 degrees, the corners are apex,
    // apex + (u + p) s2 / 2 and apex + (u - p) s2 / 2: x spans [min(0, ux - |uz|),
    // max(0, ux + |uz|)] and z [min(0, uz - |ux|), max(0, uz + |ux|)] of those units.
    static constexpr std::int8_t kBox[8][4] = {{0, 1, -1, 1},  {0, 2, 0, 2},  {-1, 1, 0, 1},
                                               {-2, 0, 0, 2},  {-1, 0, -1, 1}, {-2, 0, -2, 0},
                                               {-1, 1, -1, 0}, {0, 2, -2, 0}};
    const int level = 63 - __builtin_clzll(heap);
    const int k = (((root & 1) ? 7 : 3) + 3 * level + 2 * (popcount64(heap) - 1)) & 7;
    const std::int64_t s2 = patch_cells() >> (level / 2);  // as in triangle_at()
    const std::int8_t* b = kBox[k];
    return {ax + b[0] * s2 / 2, ax + b[1] * s2 / 2, az + b[2] * s2 / 2, az + b[3] * s2 / 2};
  }
  /// Bits set in x, inline (without -mpopcnt the builtin is a libgcc call; triangle_at runs
  /// for every priority).
  static constexpr int popcount64(std::uint64_t x) noexcept {
    x -= (x >> 1) & 0x5555555555555555ull;
    x = (x & 0x3333333333333333ull) + ((x >> 2) & 0x3333333333333333ull);
    x = (x + (x >> 4)) & 0x0f0f0f0f0f0f0f0full;
    return int((x * 0x0101010101010101ull) >> 56);
  }
  /// Geometry of a child given its parent's (child 0 or 1).
  static LatticeTriangle child_triangle(const LatticeTriangle& parent, int child) noexcept;

  /// Nested error bound of node `heap` of root `root` whose triangle is `t`, metres. Levels of
  /// the stored lattice: the stored exact nested bound, plus (with detail) the detail field's
  /// amplitude bound over the triangle's box, and at least twice that bound. Levels below: twice
  /// the bound of the contribution of the detail levels the node does not resolve
  /// (docs/detail.md, "Bounds").
  float bound(std::uint32_t root, std::uint64_t heap, const LatticeTriangle& t) const noexcept {
    const float stored = heap < nodes_per_root_plus_one_
                             ? bounds_[root * (nodes_per_root_plus_one_ - 1) + heap - 1]
                             : 0.0f;
    if (detail_ == 0) return stored;
    const int level = 63 - __builtin_clzll(heap);
    const float d = detail_bound(level, t);  // twice the bound of the detail's contribution
    // Stored levels: the plane is the stored surface's, so |detail| (half of d) adds to the
    // stored error; at least d keeps the bound nested over the levels below.
    return level < int(base_level()) ? std::max(stored + 0.5f * d, d) : d;
  }
  float bound(std::uint32_t root, std::uint64_t heap) const noexcept {
    return bound(root, heap, triangle(root, heap));
  }
  /// Exact (not nested) error of a node of the stored levels against the stored lattice (without
  /// detail), metres: used by tests and the minimal-triangulation reference. O(area) per call.
  float exact_error(std::uint32_t root, std::uint64_t heap) const noexcept;

  /// Height of finest-lattice vertex (i, j) relative to the heightfield's offset (base + detail +
  /// edits), with the padding rule (indices clamped into the footprint).
  float lattice_height(std::int64_t i, std::int64_t j) const noexcept {
    if (detail_ != 0) return static_cast<float>(terrain_->fine_local_height(i, j));
    const Heightfield& hf = terrain_->heightfield();
    if (i >= 0 && j >= 0 && i < std::int64_t(hf.width()) && j < std::int64_t(hf.height()))
      return hf.local(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j));
    return hf.local_clamped(i, j);
  }
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
  /// The last finest-lattice index inside the footprint along x and z.
  std::int64_t last_i() const noexcept { return last_i_; }
  std::int64_t last_j() const noexcept { return last_j_; }

  /// Brings the bounds up to date with the terrain's edits: pulls
  /// Terrain::changes_since(synced_version()) and recomputes the bounds over each change's
  /// changed_box(), so that they equal a fresh build's. Logically const: the bounds are a cache
  /// of the terrain's current surface, and the landscape is shared read-only by its views.
  /// Internally locked: views updating on several threads may call it at once; one does the
  /// work while the others wait, and each returns with the bounds at the terrain's current
  /// version (a cheap check when nothing changed). RoamView::update() calls it first; call it
  /// yourself before reading bound() after an edit. Never during an edit.
  void sync() const;
  /// The Terrain::edit_version() the bounds reflect (that of the last sync(), or of creation).
  std::uint64_t synced_version() const noexcept;
  /// The finest-lattice box [i0, i1] x [j0, j1] a change covers in this landscape: its vertex
  /// range, extended over the padding patches when it reaches the terrain's last column or row
  /// (the padding repeats the edge vertices, so it moves with them).
  LatticeBox changed_box(const TerrainChange& change) const noexcept;

  /// Bytes of the bound arrays, and how long building them took.
  std::size_t bound_bytes() const noexcept { return bounds_.size() * sizeof(float); }
  double build_ms() const noexcept { return build_ms_; }

 private:
  Landscape() = default;
  // Exact error against the stored lattice of a triangle in stored-lattice coordinates.
  float compute_exact(const LatticeTriangle& t) const noexcept;
  // Geometry of a stored-level node in stored-lattice coordinates.
  LatticeTriangle base_triangle(std::uint32_t root, std::uint64_t heap) const noexcept;
  float base_height(std::int64_t i, std::int64_t j) const noexcept {
    return terrain_->heightfield().local_clamped(i, j);
  }
  float detail_bound(int level, const LatticeTriangle& t) const noexcept;
  // sync()'s lock and the version the bounds reflect.
  struct Sync;
  std::unique_ptr<Sync> sync_;
  // Recomputes the stored bounds over the stored-lattice samples [i0, i1] x [j0, j1] (under
  // sync()'s lock); returns the entries recomputed.
  std::uint64_t update_bounds(std::int64_t i0, std::int64_t j0, std::int64_t i1,
                              std::int64_t j1) const;

  std::shared_ptr<const Terrain> terrain_;
  std::uint32_t exponent_ = 6, detail_ = 0, patches_x_ = 0, patches_z_ = 0;
  std::int64_t last_i_ = 0, last_j_ = 0;
  std::uint64_t nodes_per_root_plus_one_ = 0;  // 2^(2k): heaps 1 .. 2^(2k) - 1 are stored
  mutable std::vector<float> bounds_;          // written only by create() and sync()
  double origin_x_ = 0, origin_z_ = 0, spacing_x_ = 1, spacing_z_ = 1;
  double build_ms_ = 0;
};

}  // namespace ridgeline
