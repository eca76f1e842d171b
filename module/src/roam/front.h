// The split and merge front of a RoamView: every diamond that could change in the next update,
// in blocks of eight lanes that one vectorised pass tests each update.
//
// The front holds each unsplit diamond with at least one triangle in the mesh (a split
// candidate) and each split diamond whose four children are unsplit (a merge candidate). Every
// update tests all of them against the camera (evaluate()), the same function for both: a
// diamond is active when its projected bound exceeds the threshold and its sphere meets the
// frustum. Only entries whose activity disagrees with their state are split or merged, so no
// priority is kept between frames and nothing expires: the cost of frame coherence is one pass
// over ~0.85 entries per triangle (well under a nanosecond each) plus the changes.
//
// Layout: what the pass reads (the centre's position, the bound and the radius) is in blocks of
// eight entries, five rows of eight floats, with the block's masks in the padding; what only
// the changes read (lattice indices, geometry, node, flags) is one 16-byte record per entry.
// The pass writes nothing per entry: its results are two bytes per block (which lanes are
// active, which in view), beside a byte of which lanes are split. So a pass streams 20 bytes per
// entry, and an entry costs 40 bytes in all. Blocks and records are two arrays
// that grow in place, a chunk of 1,024 entries (40 KiB) at a time, in address space reserved once
// (reserved.h): growing copies nothing (a vector's growth copied the whole front inside an update
// and faulted in a new copy), an entry's address is base + index, and the unused capacity is
// under one chunk plus one spare.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <vector>

#include "platform/memory_hints.h"
#include "roam/reserved.h"
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
  /// Metres added to every radius: more than the float rounding of the positions and the eye
  /// (so that the test stays conservative against the exact distances).
  float margin = 0;
  bool world = false;  ///< ErrorMetric::kWorldMetres: active when mu > threshold; no culling
  float threshold = 0;

  /// The camera in the frame whose origin is (ox, oy, oz) in world coordinates, over a lattice
  /// whose coordinates and heights stay within `extent` metres of it.
  static FrontCamera screen(const Camera& camera, double threshold_px, double ox, double oy,
                            double oz, double extent);
  static FrontCamera world_metres(double threshold_m);
};

/// Result of the test of one entry: active, in view.
inline constexpr std::uint8_t kActive = 1, kInView = 2;

class Front {
 public:
  static constexpr std::uint32_t kLanes = 8;
  /// Bound of a diamond over the data's border: always active (FrontCamera's test).
  static constexpr float kBorderRadius = 3.0e38f;

  /// Per block: which lanes are split (kept by set_split()), and the last test's active and
  /// in-view lanes (bit l = lane l), and which lanes hold entries.
  struct Masks {
    std::uint8_t split = 0, active = 0, view = 0, valid = 0;
  };
  static_assert(sizeof(Masks) == 4);
  /// What the pass reads (rows of eight lanes), and the block's masks in the padding of the
  /// third line.
  struct alignas(64) Hot {
    float x[kLanes], y[kLanes], z[kLanes], mu[kLanes], r[kLanes];
    Masks m;
  };
  static_assert(sizeof(Hot) == 192);
  /// What only the changes read of one entry: a quarter of a cache line.
  struct alignas(16) Cold {
    std::int32_t i, j;  // centre, finest-lattice indices
    std::uint32_t node;
    std::uint32_t code;  // bit 0 provisional; bits 1-2 half hypotenuse kind; bits 8..: log2 size
  };
  static_assert(sizeof(Cold) == 16);

  /// Blocks per chunk (a power of two).
  static constexpr std::uint32_t kChunkBlocks = 128;

  /// `pool`, when given, must outlive the front (reserved.h).
  explicit Front(RangePool* pool = nullptr) noexcept
      : hot_mem_("front's blocks", pool), cold_mem_("front's records", pool) {}

  std::uint32_t size() const noexcept { return n_; }
  std::uint32_t blocks() const noexcept { return (n_ + kLanes - 1) / kLanes; }
  bool split(std::uint32_t e) const noexcept { return (mask(e).split >> (e & 7)) & 1; }
  void set_split(std::uint32_t e, bool s) noexcept {
    std::uint8_t& m = block(e >> 3).m.split;
    m = s ? std::uint8_t(m | (1u << (e & 7))) : std::uint8_t(m & ~(1u << (e & 7)));
  }
  /// A detail vertex whose height is not known yet (its tile not resident): its sphere is
  /// widened to hold every height it may take.
  bool provisional(std::uint32_t e) const noexcept { return (cold(e).code & 1u) != 0; }
  void set_provisional(std::uint32_t e, bool p) noexcept {
    std::uint32_t& f = cold(e).code;
    f = p ? (f | 1u) : (f & ~1u);
  }
  /// One node of the diamond (a leaf, or an interior node when split); the other one, when it
  /// is in the mesh, is the partner its base link names.
  std::uint32_t node(std::uint32_t e) const noexcept { return cold(e).node; }
  void set_node(std::uint32_t e, std::uint32_t n) noexcept { cold(e).node = n; }
  /// The diamond's centre (finest-lattice indices), its canonical half hypotenuse (diamond.h)
  /// and log2 of its size (Diamond::t).
  std::int32_t ci(std::uint32_t e) const noexcept { return cold(e).i; }
  std::int32_t cj(std::uint32_t e) const noexcept { return cold(e).j; }
  std::uint32_t t(std::uint32_t e) const noexcept { return cold(e).code >> 8; }
  std::int32_t hu(std::uint32_t e) const noexcept {
    static constexpr std::int32_t kU[4] = {1, 0, -1, 1};
    return kU[(cold(e).code >> 1) & 3] << t(e);
  }
  std::int32_t hw(std::uint32_t e) const noexcept {
    return ((cold(e).code >> 1) & 3) == 0 ? 0 : -(std::int32_t{1} << t(e));
  }
  float y(std::uint32_t e) const noexcept { return block(e >> 3).y[e & 7]; }
  float mu(std::uint32_t e) const noexcept { return block(e >> 3).mu[e & 7]; }
  float radius(std::uint32_t e) const noexcept { return block(e >> 3).r[e & 7]; }
  /// kActive, kInView of the last evaluate() or test_one().
  std::uint8_t result(std::uint32_t e) const noexcept {
    const Masks& m = mask(e);
    const unsigned l = e & 7;
    return std::uint8_t(((m.active >> l) & 1) | (((m.view >> l) & 1) << 1));
  }
  /// Priority: the projected bound (pixels; metres with kWorldMetres), distances clamped to the
  /// near plane. Computed, not stored.
  float priority(std::uint32_t e, const FrontCamera& c) const noexcept;

  /// Appends an entry; returns its index. (hu, hw) is the canonical half hypotenuse, t = log2
  /// of the diamond's size; (x, z) the centre in metres (i and j times the lattice spacing, as floats), y its
  /// height.
  std::uint32_t add(std::int32_t i, std::int32_t j, std::int32_t hu, std::int32_t hw,
                    std::uint32_t t, float x, float y, float z, float mu, float r,
                    std::uint32_t node, bool split, bool provisional);
  /// Rewrites an entry's sphere and bound (after an edit, or a page's or tile's arrival).
  void set_data(std::uint32_t e, float x, float y, float z, float mu, float r) noexcept {
    Hot& h = block(e >> 3);
    h.x[e & 7] = x, h.y[e & 7] = y, h.z[e & 7] = z, h.mu[e & 7] = mu, h.r[e & 7] = r;
  }
  /// Removes entry `e` by moving the last entry into its place; returns the old index of the
  /// moved entry (== e when `e` was the last), whose nodes the caller re-points.
  std::uint32_t remove(std::uint32_t e) noexcept;
  /// Empties the front; keeps the memory.
  void clear() noexcept;
  /// Gives back the pages of the chunks beyond the one spare after those in use (the capacity a
  /// rebuild's peak left).
  void trim() noexcept;

  /// An entry whose test disagrees with its state, and its priority (-1 for a merge candidate
  /// out of view). `entry` carries kKeyedSplit when the entry is split (a merge candidate), so
  /// the queues can be chosen without reading the entry's record.
  struct Keyed {
    float key;
    std::uint32_t entry;
  };
  static constexpr std::uint32_t kKeyedSplit = 1u << 31;
  /// Tests every entry for `c` (result() of each). Returns the largest priority of an entry in
  /// view whose test fails (0 when none). With `changed`, also lists the entries whose test
  /// disagrees with their state with their priorities, computed in the same pass.
  float evaluate(const FrontCamera& c, std::vector<Keyed>* changed = nullptr);
  /// The same pass under a time budget: tests whole chunks, starting at chunk `*cursor` (taken
  /// modulo the chunks in use) and wrapping around, and stops after the chunk during which
  /// `stop_at` passed. The untested entries keep their last results. `*cursor` becomes the chunk
  /// to start at next time; `*tested` the entries tested. Returns the largest failing priority
  /// in view among the tested entries.
  float evaluate_until(const FrontCamera& c, std::vector<Keyed>* changed,
                       std::chrono::steady_clock::time_point stop_at, std::uint32_t* cursor,
                       std::uint32_t* tested);
  /// Tests one entry (a new one, or one whose data changed) the same way, bit for bit; returns
  /// kActive | kInView bits. `priority`, when given, receives its priority.
  std::uint8_t test_one(std::uint32_t e, const FrontCamera& c, float* priority = nullptr) noexcept;
  /// The same test of a diamond that has no entry (yet): centre (x, y, z), bound mu, radius r,
  /// as add() takes them. Bit for bit test_one()'s answer for the entry add() would make.
  static std::uint8_t test_values(float x, float y, float z, float mu, float r,
                                  const FrontCamera& c, float* priority = nullptr) noexcept;
  /// Largest priority of an entry in view that is left unsplit, not counting those that wait
  /// for a detail tile (active and provisional).
  float max_unsplit_priority(const FrontCamera& c) const noexcept;

  /// Lanes of block b whose last test disagrees with their state (active and unsplit, or split
  /// and inactive).
  std::uint32_t changed(std::uint32_t b) const noexcept {
    const Masks& m = block(b).m;
    return std::uint32_t((m.active ^ m.split) & m.valid);
  }
  /// Hints the caches to fetch entry e's record (what node() and the geometry read).
  void prefetch_record(std::uint32_t e) const noexcept { detail::prefetch(&cold(e < n_ ? e : 0)); }
  /// Hints the caches to fetch what a change of entry e reads: its cold record and its lane
  /// of the block (three lines: height, bound, radius and the masks).
  void prefetch(std::uint32_t e) const noexcept {
    e = e < n_ ? e : 0;
    detail::prefetch(&cold(e));
    const char* h = reinterpret_cast<const char*>(&block(e >> 3));
    detail::prefetch(h);
    detail::prefetch(h + 64);
    detail::prefetch(h + 128);
  }

  /// Bytes held (capacity).
  std::size_t memory_bytes() const noexcept;

 private:
  static constexpr std::uint32_t kChunkShift = 7;  // log2 kChunkBlocks
  static_assert(kChunkBlocks == 1u << kChunkShift);
  static constexpr std::uint32_t kChunkEntries = kChunkBlocks * kLanes;
  const Hot& block(std::uint32_t b) const noexcept { return hot_[b]; }
  Hot& block(std::uint32_t b) noexcept { return hot_[b]; }
  const Cold& cold(std::uint32_t e) const noexcept { return cold_[e]; }
  Cold& cold(std::uint32_t e) noexcept { return cold_[e]; }
  const Masks& mask(std::uint32_t e) const noexcept { return block(e >> 3).m; }
  void set_result(std::uint32_t e, std::uint32_t bits) noexcept;
  /// The screen pass over the blocks of chunk k in use.
  float pass_chunk(std::uint32_t k, const FrontCamera& c, std::vector<Keyed>* changed, float worst);

  /// Room for one more chunk of entries.
  void grow();
  void set_capacity() noexcept;

  std::uint32_t n_ = 0;
  std::uint32_t capacity_ = 0;  // entries with committed room (whole chunks)
  // What the pass streams (blocks), and the records, each one array that grows in place.
  Reservation hot_mem_, cold_mem_;
  Hot* hot_ = nullptr;
  Cold* cold_ = nullptr;
};

}  // namespace ridgeline::roam
