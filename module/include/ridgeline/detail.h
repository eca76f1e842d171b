// Procedural detail below the stored resolution (docs/surface.md "Detail and edits";
// docs/detail.md): the detail function, its tiles, a tile cache with worker threads, and
// conservative amplitude bounds. A Terrain created with DetailParams makes a field and a cache
// part of its Surface (surface.h: queries, Landscape, RoamView).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "ridgeline/heightfield.h"
#include "ridgeline/result.h"

namespace ridgeline {

/// Everything that defines the detail function. Changing any field changes the surface: do it
/// only between sessions (docs/surface.md). Defaults are sane for a 1-30 m base spacing.
struct DetailParams {
  /// Number of detail levels L, 0..kMaxDetailLevels. Level l has lattice spacing spacing / 2^l;
  /// the finest lattice is level L. 0 disables detail (the surface is the stored one).
  std::uint32_t levels = 4;
  /// Seed of the integer hash; any value. The same seed gives the same surface everywhere.
  std::uint64_t seed = 1;
  /// Amplitude of level 1's octave in metres where the shape field is 1; finite, 0..1000.
  /// Level l's octave has amplitude `amplitude * gain^(l-1)` (times the shape field).
  double amplitude = 2.0;
  /// Ratio between the amplitudes of successive levels (roughness); finite, in (0, 1].
  /// 0.5 keeps slopes scale-independent (fractal dimension 2); larger is rougher.
  double gain = 0.5;
  /// Shape field (a smooth multiplier on every octave, from the base terrain's slope): value on
  /// flat ground, 0..1.
  double flat_shape = 0.25;
  /// Shape field value on ground at least as steep as `steep_slope`, 0..1.
  double steep_shape = 1.0;
  /// Slope (rise over run, unitless) at or below which ground counts as flat; finite, >= 0.
  double flat_slope = 0.05;
  /// Slope at or above which ground counts as steep; finite, > flat_slope. Between the two the
  /// shape follows a smoothstep of the slope.
  double steep_slope = 0.6;
  /// Radius in base samples of the box blur (three passes, close to a Gaussian of sigma
  /// ~ radius) applied to the slope map before shaping; 0..64.
  std::uint32_t blur_radius = 2;
};

/// Most detail levels allowed: 12 (4096 finest samples per base cell side).
inline constexpr std::uint32_t kMaxDetailLevels = 12;
/// Detail values are fixed-point integers of this many metres (2^-16 m, about 15 micrometres).
inline constexpr double kDetailUnit = 1.0 / 65536.0;

/// Checks every field of `params`; the error names the field and the value, e.g.
/// "detail: gain is 1.5; need a finite value in (0, 1]".
Status validate_detail_params(const DetailParams& params);

/// Identifies a detail tile: level 1..L and tile indices. Tile (tx, tz) at level l covers the
/// level-l lattice indices [tx * kDetailTileCells, (tx + 1) * kDetailTileCells] along x and the
/// same along z (neighbouring tiles share their edge samples).
struct DetailTileKey {
  std::uint32_t level = 1;
  std::int32_t tx = 0, tz = 0;
  bool operator==(const DetailTileKey&) const = default;
  /// The tile at level - 1 whose area contains this one (level must be >= 2).
  DetailTileKey parent() const noexcept { return {level - 1, tx >> 1, tz >> 1}; }
};
struct DetailTileKeyHash {
  std::size_t operator()(const DetailTileKey& k) const noexcept;
};

/// Cells per tile side: a tile holds (kDetailTileCells + 1)^2 = 129 x 129 samples.
inline constexpr std::int32_t kDetailTileCells = 128;
/// Extra samples stored on every side of a tile so that its children can be derived from it
/// alone (the interpolation reads two parent samples beyond an edge).
inline constexpr std::int32_t kDetailTileApron = 3;
/// Samples per stored row: 129 + 2 * 3 = 135.
inline constexpr std::int32_t kDetailTileStride = kDetailTileCells + 1 + 2 * kDetailTileApron;

class DetailField;

/// One generated tile: the detail values of levels-l lattice samples, in fixed point. Immutable;
/// shared as std::shared_ptr<const DetailTile>; every method is safe from any number of threads.
class DetailTile {
 public:
  const DetailTileKey& key() const noexcept { return key_; }
  /// Level-l lattice index of the tile's sample (0, 0).
  std::int64_t first_i() const noexcept { return std::int64_t{key_.tx} * kDetailTileCells; }
  std::int64_t first_j() const noexcept { return std::int64_t{key_.tz} * kDetailTileCells; }
  /// Detail in units of kDetailUnit at tile-local sample (li, lj); -3 <= li, lj <= 131 (the
  /// apron included), asserted. Equals DetailField::detail_raw(level, first_i() + li, ...).
  std::int32_t raw(std::int32_t li, std::int32_t lj) const noexcept;
  /// Detail in metres at tile-local sample (li, lj), same range as raw().
  double detail(std::int32_t li, std::int32_t lj) const noexcept {
    return raw(li, lj) * kDetailUnit;
  }
  /// Smallest and largest detail over the 129 x 129 samples proper, metres (a measured bound,
  /// tighter than DetailField::contribution_bound).
  double min_detail() const noexcept { return min_ * kDetailUnit; }
  double max_detail() const noexcept { return max_ * kDetailUnit; }
  /// Measured bound, metres, on |D_L - P_{from_level - 1}| over the tile's area (P interpolating
  /// the level-(from_level - 1) lattice): the sum over levels l >= from_level of the largest
  /// |D_l - P_{l-1}| at the tile's new level-l vertices. Only for tiles of the finest level L,
  /// and only where every level's cells fit the tile (l >= L - 7); otherwise +infinity (use
  /// DetailField::contribution_bound). Usually well below the analytic bound: it replaces it for
  /// ROAM nodes inside a resident finest tile.
  double measured_contribution(std::uint32_t from_level) const noexcept;
  /// Bytes held by the tile (object and samples).
  std::size_t memory_bytes() const noexcept;

 private:
  friend class DetailField;
  DetailTile() = default;
  DetailTileKey key_;
  std::vector<std::int32_t> samples_;  // kDetailTileStride^2, row-major, apron included
  std::int32_t min_ = 0, max_ = 0;
  // Largest |D_l - P_{l-1}| at the new level-l vertices, kDetailUnit; -1: not measured.
  std::int32_t increment_max_[kMaxDetailLevels + 1] = {};
  std::uint32_t levels_ = 0;  // L of the field (measured only when key_.level == L)
};

/// The detail function over a heightfield's lattice: immutable after create(); shared as
/// std::shared_ptr<const DetailField>; every method may run concurrently from any threads. It
/// keeps what it derived from the heightfield (placement, size, shape field), not the heightfield
/// itself: later edits of the samples change the surface's base, never the detail (whose shape
/// field stays as created), and the field refers to no terrain.
///
/// Definition (docs/detail.md): detail D_0 = 0 on the base lattice. Level l >= 1 keeps the parent
/// values on the even-even samples, D_l(2i, 2j) = D_{l-1}(i, j), and sets every new sample to the
/// linear interpolation of its parents (edge midpoint, or the cell diagonal's midpoint under the
/// diagonal rule) plus a smoothing correction (4-point cubic minus linear, clamped to the
/// previous octave's amplitude) plus that level's octave: a hashed value in [-1, 1] times
/// amplitude * gain^(l-1) * shape(x, z). All of it is integer arithmetic on fixed-point values,
/// so it is bit for bit the same on every platform, compiler and thread (the shape field is
/// computed once at create() in double with correctly rounded operations only, then quantised).
class DetailField {
 public:
  /// Validates `params` and derives the shape field from the slopes of `base`'s samples (once, at
  /// the base resolution: 2 bytes per stored sample); copies its placement and size. `base` is
  /// not referenced after the call. Fails with a precise message on bad params.
  static Result<std::shared_ptr<const DetailField>> create(const Heightfield& base,
                                                           const DetailParams& params);

  const DetailParams& params() const noexcept { return params_; }
  std::uint32_t levels() const noexcept { return params_.levels; }
  /// Stored samples per axis of the heightfield the field was made for: level l's lattice spans
  /// indices 0 .. (width - 1) * 2^l along x, the same along z with height.
  std::uint32_t base_width() const noexcept { return std::uint32_t(shape_w_); }
  std::uint32_t base_height() const noexcept { return std::uint32_t(shape_h_); }
  /// That heightfield's spacing (metres) and world origin.
  double spacing_x() const noexcept { return spacing_x_; }
  double spacing_z() const noexcept { return spacing_z_; }
  double origin_x() const noexcept { return origin_x_; }
  double origin_z() const noexcept { return origin_z_; }

  /// Detail at level-`level` lattice sample (i, j) in units of kDetailUnit, evaluated directly
  /// (no cache, no allocation): reproduces the tile recurrence bit for bit. level <= levels()
  /// (asserted; 0 is returned past it); level 0 gives 0. Any (i, j) is valid (outside the
  /// terrain the shape field repeats its edge); |i|, |j| < 2^40. Cost: at most 7 x 7 samples
  /// per level (about 2.5 us at level 8, 4 us at level 12 on the CI machine).
  std::int32_t detail_raw(std::uint32_t level, std::int64_t i, std::int64_t j) const noexcept;
  /// The same in metres.
  double detail(std::uint32_t level, std::int64_t i, std::int64_t j) const noexcept {
    return detail_raw(level, i, j) * kDetailUnit;
  }
  /// Detail of a w x h window of level-`level` samples starting at (i0, j0), row-major into
  /// `out` (out.size() >= w * h), evaluated directly; identical to detail_raw per sample and
  /// cheaper than calling it w * h times. Allocates scratch of about (w/2 + 4) * (h/2 + 4)
  /// samples. level > levels() (asserted) gives zeros; a short `out` is left untouched.
  void detail_window(std::uint32_t level, std::int64_t i0, std::int64_t j0, std::uint32_t w,
                     std::uint32_t h, std::span<std::int32_t> out) const;

  /// World position (x, z) of level-`level` sample (i, j), metres. (The height there, base plus
  /// detail, is the surface's: Surface::vertex_height() at level L.)
  double lattice_x(std::uint32_t level, std::int64_t i) const noexcept;
  double lattice_z(std::uint32_t level, std::int64_t j) const noexcept;

  /// Generates a tile from its parent tile (the recurrence). `parent` must be the tile
  /// key.parent() for level >= 2 and null for level 1 (whose parent is the zero base detail);
  /// asserted (null is returned past the asserts). 1 <= key.level <= levels(). Thread-safe;
  /// allocates one tile (about 73 KB; finest tiles also measure their per-level increments, about
  /// 0.08 ms).
  std::shared_ptr<const DetailTile> make_tile(const DetailTileKey& key,
                                              const DetailTile* parent) const;
  /// Generates a tile and every ancestor it needs, synchronously (tools and tests).
  std::shared_ptr<const DetailTile> make_tile_chain(const DetailTileKey& key) const;

  /// Conservative bound, metres, on |contribution of levels >= from_level| at every finest
  /// lattice sample whose position lies in the closed rectangle of level-`level` lattice indices
  /// [i0, i1] x [j0, j1]: the largest |D_L(v) - P(v)|, P being the piecewise-linear
  /// interpolation (diagonal rule) of the level-(from_level - 1) lattice. from_level 1 bounds
  /// |detail| itself; from_level > levels() gives 0. Derived from the amplitudes and the shape
  /// field only, so it holds before any tile exists. i0 <= i1, j0 <= j1 (else 0).
  double contribution_bound(std::uint32_t from_level, std::uint32_t level, std::int64_t i0,
                            std::int64_t j0, std::int64_t i1, std::int64_t j1) const noexcept;
  /// The same bound over the whole (infinite) lattice.
  double contribution_bound(std::uint32_t from_level) const noexcept;
  /// The two factors of contribution_bound(): it equals (amplitude_sum(from_level) *
  /// shape_max_q15(level, i0, j0, i1, j1) / 32768 + rounding_terms(from_level)) * kDetailUnit.
  /// What a caller needs that combines the bound of several levels over one rectangle (the
  /// tessellator's morph bounds) without recomputing the shape maximum for each.
  std::int64_t amplitude_sum(std::uint32_t from_level) const noexcept;
  std::int64_t rounding_terms(std::uint32_t from_level) const noexcept;
  /// Largest shape value (Q15: 32768 = 1) that reaches the rectangle, as contribution_bound uses
  /// it; 0 for an empty rectangle.
  std::uint32_t shape_max_q15(std::uint32_t level, std::int64_t i0, std::int64_t j0,
                              std::int64_t i1, std::int64_t j1) const noexcept;

  /// Shape field at level-`level` sample (i, j), in [0, 1] (fixed point 2^-15 internally).
  double shape(std::uint32_t level, std::int64_t i, std::int64_t j) const noexcept;
  /// Bytes held (shape field and its max pyramid).
  std::size_t memory_bytes() const noexcept;

 private:
  DetailField() = default;
  friend struct DetailKernel;

  void measure_increments(DetailTile& tile) const;
  DetailParams params_;
  double spacing_x_ = 1, spacing_z_ = 1, origin_x_ = 0, origin_z_ = 0;  // the base's placement
  std::uint64_t seed_mix_ = 0;
  // Octave amplitude per level in kDetailUnit (index 0 is 0).
  std::int64_t amp_[kMaxDetailLevels + 1] = {};
  // Shape field per base sample, 0..32768 (Q15), and a max pyramid over it for the bound.
  std::vector<std::uint16_t> shape_;
  std::int64_t shape_w_ = 0, shape_h_ = 0;
  std::vector<std::vector<std::uint16_t>> shape_max_;  // [p - 1]: blocks of 2^p x 2^p samples
  std::uint16_t shape_max_all_ = 0;
};

/// Everything a DetailCache needs besides the field.
struct DetailCacheDesc {
  /// Hard cap on the bytes of resident tiles after each update(); >= (levels + 1) tiles
  /// (about 73 KB each). Default 256 MiB.
  std::size_t budget_bytes = std::size_t{256} << 20;
  /// Worker threads of the cache's own pool, 0..64. 0 means synchronous: request() generates
  /// the tile (and its missing ancestors) before returning. Ignored when `executor` is set. On
  /// Linux they run 10 nice levels below the thread that made the cache.
  std::uint32_t worker_threads = 2;
  /// Optional job system of the embedding engine: called from request(), after the cache's lock
  /// is released, with a job to run once on any thread (it may also run it inline). The job is
  /// self-contained and safe to run after the cache is destroyed (it then does nothing). If the
  /// executor throws, request() withdraws the request (as if it had not been made) and lets the
  /// exception propagate; a job the executor accepts but never runs leaves its tile pending.
  std::function<void(std::function<void()>)> executor;
};

/// Streaming statistics of a DetailCache.
struct DetailCacheStats {
  std::size_t resident_tiles = 0;      ///< tiles in the cache (published by update())
  std::size_t resident_bytes = 0;      ///< their bytes, <= budget after each update()
  std::size_t pending = 0;             ///< tiles requested and not yet integrated
  std::uint64_t generated = 0;         ///< tiles generated since creation (ancestors included)
  std::uint64_t evicted = 0;           ///< tiles evicted since creation
  std::uint64_t integrated = 0;        ///< tiles integrated by update() since creation
  double generated_per_second = 0;     ///< over the last >= 1 s window of update() calls
  double generation_seconds = 0;       ///< summed wall time of tile generation, all threads
  std::uint64_t worst_lag_frames = 0;  ///< most update() calls between a request and its tile
  std::uint64_t frame = 0;             ///< update() calls so far
};

/// An immutable view of the resident tiles at one update(). Lookups take no lock and touch no
/// shared counter; the snapshot keeps its tiles alive (an evicted tile is freed when the last
/// snapshot holding it goes), so hold one for a frame or a batch of queries, not longer.
class DetailSnapshot {
 public:
  /// The tile, or null when it was not resident at that update(). Valid while the snapshot lives.
  const DetailTile* find(const DetailTileKey& key) const noexcept;
  std::size_t size() const noexcept { return tiles_.size(); }
  /// Tile k of the snapshot, 0 <= k < size(), in no particular order (to list what arrived).
  const DetailTile& tile(std::size_t k) const noexcept { return *tiles_[k]; }

 private:
  friend class DetailCache;
  std::ptrdiff_t find_index(const DetailTileKey& key) const noexcept;
  // Flat arrays (cheap to build once per update): the tiles, and an open-addressing index of
  // them (power-of-two size, linear probing, -1 for empty).
  std::vector<std::shared_ptr<const DetailTile>> tiles_;
  std::vector<std::int32_t> index_;
};

/// Tiles generated on demand, cached with LRU eviction under a byte budget.
///
/// Threading contract:
/// - request(), update() and stats() may be called from any threads; they serialise on one
///   internal mutex held for O(1) work per request and, per update(), for the tiles integrated
///   and evicted plus, when anything changed, a copy of the resident table into the new
///   snapshot (O(resident tiles)); never during generation. The renderer never waits for
///   generation.
/// - snapshot() may be called from any thread: a shared_ptr copy under a lock of its own, held
///   for that copy only (never behind request(), update() or generation). Lookups in a snapshot
///   take no lock and write no shared memory, so queries on many threads share one snapshot
///   per frame or batch without contention. try_get() is a snapshot() plus a lookup: fine for
///   a one-off, but in a query loop take the snapshot once.
/// - Tiles become visible to snapshot()/try_get() only at update() (the owner calls it once per
///   frame), except in synchronous mode where request() publishes at once.
class DetailCache {
 public:
  static Result<std::unique_ptr<DetailCache>> create(std::shared_ptr<const DetailField> field,
                                                     const DetailCacheDesc& desc = {});
  ~DetailCache();
  DetailCache(const DetailCache&) = delete;
  DetailCache& operator=(const DetailCache&) = delete;

  /// True when the tile is resident (and marks it used this frame for the LRU). Otherwise
  /// queues it (once; `urgent` puts it first) and returns false without waiting, except in
  /// synchronous mode where it generates it and returns true. key.level must be 1..levels()
  /// (asserted; false past the assert).
  bool request(const DetailTileKey& key, bool urgent = false);
  /// request() for each of `count` keys in order, taking the cache's lock once instead of once
  /// per key (a view's ~1,000 requests a frame cost ~0.5 ms one by one, most of it the lock and
  /// the wake-ups); returns how many were resident. The same result as the calls one by one.
  std::size_t request_many(const DetailTileKey* keys, std::size_t count, bool urgent = false);
  /// Starts a frame: integrates generated tiles (at most `max_integrations`, 0 = all), evicts the
  /// least recently used tiles until the bytes are within budget, publishes a new snapshot.
  void update(std::size_t max_integrations = 0);
  /// The tiles resident at the last update().
  std::shared_ptr<const DetailSnapshot> snapshot() const;
  /// The tile if resident at the last update(), else null.
  std::shared_ptr<const DetailTile> try_get(const DetailTileKey& key) const;
  /// Blocks until no request is pending generation or `timeout_seconds` passed; true when idle.
  /// For tests and tools (a frame loop never calls it). Does not integrate: call update().
  bool wait_idle(double timeout_seconds);

  DetailCacheStats stats() const;
  /// Identifies the published snapshot: changes (to a value no cache has used before) whenever
  /// a new snapshot is published. One atomic load: lets a reader keep a snapshot per thread and
  /// refresh it only when this changes (Terrain's queries do).
  std::uint64_t generation() const noexcept;
  const DetailField& field() const noexcept { return *field_; }

 private:
  struct State;
  DetailCache() = default;
  std::shared_ptr<const DetailField> field_;
  std::shared_ptr<State> state_;
};

}  // namespace ridgeline
