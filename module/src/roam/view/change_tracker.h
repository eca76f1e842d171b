// Private: the first phase of an update: what changed under the view since its last update,
// pulled, never pushed (nothing runs inside an edit): the terrain's edits (its change log),
// the pages of a paged world that became resident, and the procedural detail tiles that
// arrived. The front entries and mesh vertices they reach are refreshed, so that the front's
// test that follows sees the new bounds.
#pragma once

#include <cstdint>
#include <unordered_set>

#include "roam/view/refiner.h"

namespace ridgeline::roam {

class ChangeTracker {
 public:
  /// The mesh was rebuilt from the terrain as of `edit_version` (with holes or not): older edits
  /// need no pulling.
  void mark_synced(std::uint64_t edit_version, bool holes) noexcept {
    synced_version_ = edit_version;
    had_holes_ = holes;
  }
  /// Edits since the last update (Terrain::changes_since()): refreshes the front's diamonds
  /// (bounds, positions) and the output vertices (heights, normals, bounds) they reach.
  void pull_edits(Refiner& refiner);
  /// Detail tiles that became resident since the last update: the diamonds whose vertex waited
  /// for one get their true position, and the diamonds and vertices inside a new finest tile
  /// its measured bounds (RoamStats::rebounded counts the tightened ones).
  void pull_tiles(Refiner& refiner);
  /// Pages that became resident since the last update: the provisional stored diamonds over
  /// them get their true data (RoamStats::rebounded counts the tightened ones).
  void pull_pages(Refiner& refiner);

 private:
  std::uint64_t synced_version_ = 0;                     // the terrain's edit_version() applied
  std::uint64_t tiles_generation_ = ~std::uint64_t{0};   // the detail cache's snapshot last seen
  std::uint64_t pages_generation_ = 0;                   // the page table last seen
  bool had_holes_ = false;                               // the terrain had holes last update
  std::unordered_set<std::uint64_t> known_tiles_;        // finest tiles resident at the last look
};

}  // namespace ridgeline::roam
