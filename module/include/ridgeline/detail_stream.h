// Streaming detail tiles for a camera (docs/detail.md, "Streaming"): which detail tiles a view
// needs (the request rule), and a per-frame driver that requests them from a DetailCache,
// updates it and measures what arrived. Used by `ridge bench detail`, the flight tests and the
// streaming picture; an engine can use it as is or as a model for its own frame loop.
#pragma once

#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "ridgeline/camera.h"
#include "ridgeline/detail.h"
#include "ridgeline/result.h"
#include "ridgeline/surface.h"

namespace ridgeline {

/// The request rule: level l is **needed** wherever its lattice spacing projects to at least
/// `pixels` pixels, i.e. within the radius R_l = spacing_l * projection_scale(camera) / pixels of
/// the eye (spacing_l = max(spacing_x, spacing_z) / 2^l, metres). A tile of level l is needed when
/// the distance from the eye to its footprint is <= R_l, and **requested** (needed or prefetched)
/// when it is <= (1 + prefetch) * R_l. R_l halves from one level to the next, so every level
/// needs about the same number of tiles: (R_l / tile side)^2 * pi with tile side = 128
/// spacing_l, i.e. about pi * (projection_scale / (128 pixels))^2 tiles per level. A parent tile
/// contains its children and R_{l-1} = 2 R_l, so a needed tile's ancestors are needed too.
struct DetailViewRule {
  /// Projected size, in pixels, of a level's spacing at which the level stops being needed;
  /// finite, > 0. 1 = detail down to about one pixel.
  double pixels = 1.0;
  /// Extra radius, as a fraction of R_l, within which tiles are requested before they are needed
  /// (they arrive while the camera approaches); finite, 0..4.
  double prefetch = 0.25;
  /// Most tiles the rule may list for one view (all levels), >= 1. A view that asks for more (a
  /// tiny `pixels`, a huge viewport) is refused rather than flooding the cache.
  std::size_t max_tiles = 65536;
};

/// Checks the rule's fields; the error names the field and the value.
Status validate_detail_view_rule(const DetailViewRule& rule);

/// One tile a view asks for.
struct DetailTileNeed {
  DetailTileKey key;
  /// Distance from the eye to the tile, metres: sqrt(dxz^2 + dy^2), dxz the horizontal distance
  /// to the tile's xz rectangle and dy the vertical distance from the eye to the height range the
  /// surface can reach over the tile: for a tile spanning at most 16 stored cells per side (level
  /// >= 3), the range of the stored samples of the cells it overlaps widened by the detail's
  /// amplitude bound there (DetailField::contribution_bound); for coarser tiles, the whole
  /// terrain's range widened by the global bound. So it never exceeds the distance to any surface
  /// point of the tile.
  double distance_m = 0;
  /// Within R_l (false: requested for prefetch only).
  bool needed = false;
};

/// R_l for `camera`, metres (see DetailViewRule); 0 for level 0 or level > field.levels().
double detail_level_radius(const DetailField& field, const Camera& camera, std::uint32_t level,
                           const DetailViewRule& rule) noexcept;

/// Replaces `out` by the tiles of levels 1..L of `surface`'s detail that `camera` requests under
/// `rule`, coarsest level first, nearest first within a level (no tiles without detail). Only
/// tiles whose rectangle overlaps the footprint are listed. Fails (and leaves `out` empty) on an
/// invalid camera or rule, or when more than rule.max_tiles tiles would be listed. Reads the
/// surface's detail field and stored samples: any thread, like the surface's queries.
Status detail_tiles_for_view(const Surface& surface, const Camera& camera,
                             const DetailViewRule& rule, std::vector<DetailTileNeed>& out);

/// What one DetailStream::frame() did and saw.
struct DetailFrameStats {
  std::size_t requested = 0;        ///< tiles the rule listed (needed + prefetch)
  std::size_t needed = 0;           ///< of which needed
  std::size_t needed_resident = 0;  ///< needed tiles in the snapshot published by this update()
  /// Frames the longest-missing currently needed tile has been missing, this one included (0 when
  /// every needed tile is resident).
  std::uint64_t late_frames = 0;
  double request_ms = 0;   ///< wall time of the requests on the calling thread, milliseconds
  double update_ms = 0;    ///< wall time of DetailCache::update() on the calling thread
  DetailCacheStats cache;  ///< the cache's statistics after update()
};

/// Drives a DetailCache from a camera, once per frame: lists the tiles (detail_tiles_for_view),
/// requests them (needed tiles urgent, nearest last so that it is generated first; prefetched
/// tiles in distance order), calls update(), and checks the new snapshot for the needed tiles.
/// Never waits for generation. Holds references to the surface (its terrain must outlive the
/// stream) and to the cache, which must outlive it too. One thread at a time (it is the cache's
/// owner's frame loop).
class DetailStream {
 public:
  /// Streams `surface`'s detail through `cache`: the surface's own (*Surface::detail_cache()) or
  /// another cache of the same detail field (DetailCache::field() is *surface.detail(), e.g. one
  /// with other budgets made from std::shared_ptr<const DetailField>(terrain,
  /// terrain->detail())). Fails on an invalid rule or a cache of another field.
  static Result<DetailStream> create(const Surface& surface, DetailCache& cache,
                                     const DetailViewRule& rule = {});

  /// One frame for `camera`. Fails on an invalid camera or too many tiles (the cache is then
  /// neither asked nor updated).
  Result<DetailFrameStats> frame(const Camera& camera);

  /// The tiles listed by the last successful frame().
  const std::vector<DetailTileNeed>& tiles() const noexcept { return tiles_; }
  /// Most frames any needed tile has been missing so far (the worst `late_frames`).
  std::uint64_t worst_late_frames() const noexcept { return worst_late_; }
  const DetailViewRule& rule() const noexcept { return rule_; }

 private:
  DetailStream(const Surface& surface, DetailCache& cache, const DetailViewRule& rule)
      : surface_(&surface), cache_(&cache), rule_(rule) {}
  const Surface* surface_;
  DetailCache* cache_;
  DetailViewRule rule_;
  std::vector<DetailTileNeed> tiles_;
  std::vector<DetailTileKey> keys_;  // frame()'s request lists (kept memory)
  // Needed tiles missing at the end of the previous frame -> frames missing so far.
  std::unordered_map<DetailTileKey, std::uint64_t, DetailTileKeyHash> late_, next_late_;
  std::uint64_t worst_late_ = 0;
};

}  // namespace ridgeline
