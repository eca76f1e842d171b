// The split and merge front of a RoamView: every diamond that could change in the next update,
// in blocks of four lanes that one vectorised pass tests each update.
//
// The front holds each unsplit diamond with at least one triangle in the mesh (a split
// candidate) and each split diamond whose four children are unsplit (a merge candidate). Every
// update tests all of them against the camera (evaluate()), the same function for both: a
// diamond is active when its projected bound exceeds the threshold and its sphere meets the
// frustum. Only entries whose activity disagrees with their state are split or merged, so no
// priority is kept between frames and nothing expires: the cost of frame coherence is one pass
// over ~0.85 entries per triangle (about a nanosecond each) plus the changes.
//
// Layout: blocks of four entries, each field four consecutive 32-bit values (structure of arrays
// inside a block, array of blocks; 128 bytes, two cache lines per block). The pass reads whole
// vectors; adding, removing or testing one entry touches two cache lines, not one per field.
#pragma once

#include <cstdint>
#include <vector>

#include "ridgeline/camera.h"

namespace ridgeline::roam {

/// The camera as the front's test sees it: eye and planes in the landscape-local frame (metres
/// from the landscape's origin, heights relative to the height offset: small numbers, so floats
/// keep their precision however far the world is from its origin).
struct FrontCamera {
  float ex = 0, ey = 0, ez = 0;
  /// kappa = projection scale / threshold: a diamond is active when kappa * bound + radius >
  /// distance, i.e. (kappa mu + r)^2 > d^2 (Lindstrom & Pascucci's test, no division). Infinite
  /// for threshold 0 (every diamond with a nonzero bound is active).
  float kappa = 1;
  float planes[4][3] = {};  ///< inward unit normals of the side planes (through the eye)
  float far_m = 1e30f;
  float scale = 1;       ///< projection scale K: pixels per metre at 1 m
  float near_m = 0.5f;   ///< distances below this count as this in priorities
  float sx = 1, sz = 1;  ///< metres per finest-lattice step (a centre's x is i * sx)
  /// Metres added to every radius: more than the float rounding of the positions and the eye
  /// (so that the test stays conservative against the exact distances).
  float margin = 0;
  bool world = false;  ///< ErrorMetric::kWorldMetres: active when mu > threshold; no culling
  float threshold = 0;

  /// The camera in the frame whose origin is (ox, oy, oz) in world coordinates, over a lattice
  /// of spacing (sx, sz) whose coordinates and heights stay within `extent` metres of it.
  static FrontCamera screen(const Camera& camera, double threshold_px, double ox, double oy,
                            double oz, double sx, double sz, double extent);
  static FrontCamera world_metres(double threshold_m);
};

/// Result of the test of one entry: active, in view, and whether the test disagrees with the
/// entry's split state.
inline constexpr std::uint8_t kActive = 1, kInView = 2, kChanged = 4;

class Front {
 public:
  static constexpr std::uint32_t kLanes = 4;
  /// Per entry flags: kSplit (a merge candidate), kProvisional (a detail vertex whose height is
  /// not known yet, its tile not resident: its sphere is widened to hold every height it may
  /// take).
  static constexpr std::uint8_t kSplit = 1, kProvisional = 2;
  /// State word of a lane: flags in bits 0-7, the last test's result in bits 8-15, the
  /// diamond's log2 size (Diamond::t) in bits 16-23.
  static constexpr int kResultShift = 8, kLevelShift = 16;

  std::uint32_t size() const noexcept { return n_; }
  bool split(std::uint32_t e) const noexcept { return (st(e) & kSplit) != 0; }
  void set_split(std::uint32_t e, bool s) noexcept { set_flag(e, kSplit, s); }
  bool provisional(std::uint32_t e) const noexcept { return (st(e) & kProvisional) != 0; }
  void set_provisional(std::uint32_t e, bool p) noexcept { set_flag(e, kProvisional, p); }
  /// One node of the diamond (a leaf, or an interior node when split).
  std::uint32_t node(std::uint32_t e) const noexcept { return blk(e).node[e & 3]; }
  void set_node(std::uint32_t e, std::uint32_t n) noexcept { blk(e).node[e & 3] = n; }
  /// The diamond's centre (finest-lattice indices) and log2 of its size.
  std::int32_t ci(std::uint32_t e) const noexcept { return blk(e).i[e & 3]; }
  std::int32_t cj(std::uint32_t e) const noexcept { return blk(e).j[e & 3]; }
  std::uint32_t t(std::uint32_t e) const noexcept { return (st(e) >> kLevelShift) & 0xffu; }
  float y(std::uint32_t e) const noexcept { return blk(e).y[e & 3]; }
  float mu(std::uint32_t e) const noexcept { return blk(e).mu[e & 3]; }
  float radius(std::uint32_t e) const noexcept { return blk(e).r[e & 3]; }
  /// Result (kActive, kInView, kChanged) of the last evaluate() or test_one().
  std::uint8_t result(std::uint32_t e) const noexcept {
    return std::uint8_t(st(e) >> kResultShift);
  }
  /// Priority: the projected bound (pixels; metres with kWorldMetres), distances clamped to the
  /// near plane. Computed, not stored.
  float priority(std::uint32_t e, const FrontCamera& c) const noexcept;

  /// Appends an entry; returns its index.
  std::uint32_t add(std::int32_t i, std::int32_t j, std::uint32_t t, float y, float mu, float r,
                    std::uint32_t node, bool split, bool provisional);
  /// Rewrites an entry's data (after an edit or a tile's arrival).
  void set_data(std::uint32_t e, float y, float mu, float r) noexcept;
  /// Removes entry `e` by moving the last entry into its place; returns the old index of the
  /// moved entry (== e when `e` was the last), whose nodes the caller re-points.
  std::uint32_t remove(std::uint32_t e);
  /// Empties the front; keeps the memory. (Lanes past size() must read as zeros: the pass tests
  /// whole blocks.)
  void clear() noexcept {
    n_ = 0;
    blocks_.clear();
  }

  /// Tests every entry for `c`: result() of each. Returns the largest priority of an entry in
  /// view whose test fails (0 when none).
  float evaluate(const FrontCamera& c);
  /// Tests one entry (a new one, or one whose data changed) the same way, bit for bit; returns
  /// kActive | kInView bits.
  std::uint8_t test_one(std::uint32_t e, const FrontCamera& c) noexcept;
  /// Largest priority of an entry in view that is left unsplit, not counting those that wait
  /// for a detail tile (active and provisional).
  float max_unsplit_priority(const FrontCamera& c) const noexcept;

  /// Hints the caches to fetch entry e (both lines of its block).
  void prefetch(std::uint32_t e) const noexcept {
    if (e < n_) __builtin_prefetch(&blocks_[e >> 2]), __builtin_prefetch(&blocks_[e >> 2].state);
  }
  /// Whether a lane of block b may have changed in the last evaluate() (a quick skip for scans).
  bool block_changed(std::uint32_t b) const noexcept { return changed_[b] != 0; }
  /// The state words of block b (lanes past size() are 0), for scanning.
  const std::uint32_t* block_state(std::uint32_t b) const noexcept { return blocks_[b].state; }

  /// Bytes held (capacity).
  std::size_t memory_bytes() const noexcept;

  struct alignas(64) Block {
    std::int32_t i[kLanes], j[kLanes];
    float y[kLanes], mu[kLanes], r[kLanes];
    std::uint32_t state[kLanes], node[kLanes], spare[kLanes];
  };
  static_assert(sizeof(Block) == 128);

 private:
  const Block& blk(std::uint32_t e) const noexcept { return blocks_[e >> 2]; }
  Block& blk(std::uint32_t e) noexcept { return blocks_[e >> 2]; }
  std::uint32_t st(std::uint32_t e) const noexcept { return blk(e).state[e & 3]; }
  void set_flag(std::uint32_t e, std::uint8_t bit, bool on) noexcept {
    std::uint32_t& f = blk(e).state[e & 3];
    f = on ? (f | bit) : (f & ~std::uint32_t(bit));
  }
  std::uint32_t n_ = 0;
  std::vector<Block> blocks_;
  std::vector<std::uint8_t> changed_;  // per block, from the last evaluate()
};

}  // namespace ridgeline::roam
