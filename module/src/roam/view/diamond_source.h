// Private: where a view reads its diamonds from, once per update: the landscape's records in the
// terrain's resident pages, the procedural detail's tiles, and, for what is not resident yet,
// a conservative stand-in and a request for it.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "ridgeline/landscape.h"
#include "roam/diamond.h"
#include "roam/front.h"
#include "roam/landscape_access.h"

namespace ridgeline {
class DetailCache;
class DetailSnapshot;
struct DetailTileKey;
}  // namespace ridgeline

namespace ridgeline::roam {

/// What the front's test reads of a diamond: the centre of its sphere in metres from the
/// landscape's origin (its vertex, or for a provisional diamond one whose sphere holds every
/// position the vertex may take), its bound (morph, or error in the tolerance mode) and radius.
struct EntryData {
  float x, y, z;
  float bound, radius;
  /// Its detail tile or its page is not resident: the sphere and bound are a stand-in that
  /// holds the true ones (nested), and a split waits for the data (Refiner::chain_ready()).
  bool provisional;
};

/// One update's view of the data under the mesh. Made once per view; begin_update() takes this
/// update's snapshots (tiles integrated and pages loaded since the last one).
class DiamondSource {
 public:
  explicit DiamondSource(const Landscape& landscape);

  /// Integrates the detail tiles and the pages loaded since the last update (DetailCache::update,
  /// Terrain::update_pages) and reads through their snapshots until the next call. `world_metric`:
  /// the tolerance mode (the error bound instead of the morph bound).
  void begin_update(bool world_metric);
  /// Reads the terrain's resident pages as they are, integrating nothing, without the detail
  /// tiles (a view's creation: its first update begins with begin_update()).
  void open_pages();

  /// The diamond centred at finest-lattice vertex (i, j) (not a patch corner).
  EntryData read(std::int64_t i, std::int64_t j) const {
    DiamondBound b;
    float y;
    if (reader_.stored(i, j, b, y) == Reader::Vertex::kResident)  // stored: one page
      return {float(i) * step_x_m_, y, float(j) * step_z_m_, world_metric_ ? b.error : b.morph,
              b.radius, false};
    return read_not_resident(i, j);
  }

  /// True when the vertex (i, j) a split creates has its data: its detail tile (a detail
  /// vertex) or its page (a stored one). Otherwise requests it (urgent) and returns false.
  bool request_vertex(std::int64_t i, std::int64_t j);
  /// True when the shading of stored vertex (i, j) can be read from a resident page: a page
  /// evicted since the diamond's entry was made is requested again (false then).
  bool request_shading(std::int64_t i, std::int64_t j);
  /// Sends the pages this update's splits wait for to the terrain's loaders, urgent, each once;
  /// returns how many (RoamStats::requested_pages).
  std::uint32_t send_page_requests();

  const Reader& reader() const noexcept { return reader_; }
  /// The detail cache (null without procedural detail) and this update's snapshot of it.
  DetailCache* detail_cache() const noexcept { return cache_; }
  const DetailSnapshot* detail_snapshot() const noexcept { return snapshot_.get(); }
  /// Hints the caches to fetch what read(i, j) reads (with `shading`: what a split writing the
  /// vertex reads too).
  void prefetch(std::int64_t i, std::int64_t j, bool shading = false) const noexcept {
    reader_.prefetch(i, j, shading);
  }

 private:
  /// read() of a vertex without a resident page: procedural detail, or a page to load.
  EntryData read_not_resident(std::int64_t i, std::int64_t j) const;
  /// The key of the detail tile holding detail vertex (i, j); false for a stored vertex.
  bool detail_tile_of(std::int64_t i, std::int64_t j, DetailTileKey& key) const noexcept;

  const Landscape& landscape_;
  const int patch_log2_;
  const float step_x_m_, step_z_m_;  // metres per finest-lattice step, as the front's test has them
  DetailCache* const cache_;          // procedural detail's tiles (null without detail)
  std::shared_ptr<const DetailSnapshot> snapshot_;  // the cache's tiles for this update
  Reader reader_;                                   // the terrain's pages for this update
  std::vector<PageKey> page_requests_;              // pages this update's splits wait for
  bool world_metric_ = false;
};

}  // namespace ridgeline::roam
