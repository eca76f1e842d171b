// What changed under a view since its last update: edits, pages, detail tiles
// (change_tracker.h).
#include "roam/view/change_tracker.h"

#include <algorithm>
#include <vector>

#include "ridgeline/detail.h"
#include "ridgeline/terrain.h"

namespace ridgeline::roam {

namespace {

// True when the range of lattice vertices, widened by `grow`, holds (i, j).
bool reaches(const LatticeRange& c, std::int64_t i, std::int64_t j, std::int64_t grow) {
  return i >= c.i0 - grow && i <= c.i1 + grow && j >= c.j0 - grow && j <= c.j1 + grow;
}

}  // namespace

// A diamond's bound depends on everything within its reach, a vertex's normal and geomorph
// offset on the vertices of its level around it.
void ChangeTracker::pull_edits(Refiner& r) {
  const Landscape& land = r.landscape();
  const TerrainChanges pulled = land.terrain().changes_since(synced_version_);
  synced_version_ = pulled.version;
  // Holes drawn or hidden by the leaves over a change follow the holes now (a hole edit leaves
  // the heights alone; any edit may dig or fill while holes exist or existed).
  const bool now_holes = r.source().reader().holes() != nullptr;
  const bool holes = now_holes || had_holes_;
  had_holes_ = now_holes;
  if (pulled.empty()) return;
  Front& front = r.front();
  PatchOutput& output = r.output();
  const int patch_log2 = land.patch_log2();
  for (const TerrainChange& change : pulled.changes) {
    const LatticeRange& c = change.vertices;
    if (c.empty()) continue;
    if (holes) r.rehide(c.i0, c.j0, c.i1, c.j1);
    for (std::uint32_t e = 0; e < front.size(); ++e) {
      const std::int64_t size = std::int64_t{1} << front.t(e);
      if (reaches(c, front.ci(e), front.cj(e), 3 * size + 1)) r.refresh_entry(e);
    }
    const std::int64_t cells = land.patch_cells();
    const std::int64_t px0 = std::max<std::int64_t>(0, (c.i0 - 2 * cells) / cells),
                       px1 = std::min<std::int64_t>(land.patches_x() - 1, (c.i1 + 2 * cells) / cells),
                       pz0 = std::max<std::int64_t>(0, (c.j0 - 2 * cells) / cells),
                       pz1 = std::min<std::int64_t>(land.patches_z() - 1, (c.j1 + 2 * cells) / cells);
    for (std::int64_t pz = pz0; pz <= pz1; ++pz)
      for (std::int64_t px = px0; px <= px1; ++px) {
        const auto p = std::uint32_t(px + pz * land.patches_x());
        for (std::uint32_t v = 0; v < output.vertex_slots(p); ++v) {
          if (!output.vertex_live(p, v)) continue;
          const auto q = output.coord(p, v);
          const Diamond d = diamond_at(q[0], q[1], patch_log2);
          const std::int64_t grow =
              d.corner ? cells + 1 : std::max<std::int64_t>(1, d.reach()) + 1;
          if (reaches(c, q[0], q[1], grow)) output.refresh_vertex(p, v);
        }
      }
  }
}

void ChangeTracker::pull_pages(Refiner& r) {
  const Reader& reader = r.source().reader();
  const std::uint64_t generation = reader.table().generation();
  if (generation == pages_generation_) return;
  pages_generation_ = generation;
  if (!r.landscape().terrain().paged()) return;
  Front& front = r.front();
  for (std::uint32_t e = 0; e < front.size(); ++e) {
    if (!front.provisional(e)) continue;
    DiamondBound b;
    float y;
    if (reader.stored(front.ci(e), front.cj(e), b, y) == Reader::Vertex::kResident) {
      const float before = front.mu(e);
      r.refresh_entry(e);
      if (front.mu(e) < before) ++r.stats().rebounded;
    }
  }
}

void ChangeTracker::pull_tiles(Refiner& r) {
  const DetailCache* cache = r.source().detail_cache();
  if (cache == nullptr) return;
  const std::uint64_t generation = cache->generation();
  if (generation == tiles_generation_) return;
  tiles_generation_ = generation;
  const DetailSnapshot& snapshot = *r.source().detail_snapshot();
  const std::uint32_t levels = r.landscape().detail_levels();
  // Finest tiles new since the last look (their areas: measured bounds apply inside).
  std::vector<DetailTileKey> arrived;
  std::unordered_set<std::uint64_t> now;
  now.reserve(snapshot.size());
  for (std::size_t k = 0; k < snapshot.size(); ++k) {
    const DetailTileKey& key = snapshot.tile(k).key();
    if (key.level != levels) continue;
    const std::uint64_t id = (std::uint64_t(std::uint32_t(key.tx)) << 32) | std::uint32_t(key.tz);
    now.insert(id);
    if (!known_tiles_.count(id)) arrived.push_back(key);
  }
  known_tiles_.swap(now);
  const std::int64_t cells = kDetailTileCells;
  Front& front = r.front();
  for (std::uint32_t e = 0; e < front.size(); ++e) {
    const std::uint32_t t = front.t(e);
    const std::int64_t ci = front.ci(e), cj = front.cj(e);
    if (t >= levels) continue;  // stored vertices: no detail
    bool refresh = front.provisional(e);
    if (!refresh) {
      const std::int64_t reach = std::int64_t{3} << t;  // Diamond::reach(), at most
      for (const DetailTileKey& key : arrived) {
        const std::int64_t i0 = std::int64_t(key.tx) * cells, j0 = std::int64_t(key.tz) * cells;
        if (ci - reach >= i0 && ci + reach <= i0 + cells && cj - reach >= j0 &&
            cj + reach <= j0 + cells) {
          refresh = true;
          break;
        }
      }
    }
    if (!refresh) continue;
    const float before = front.mu(e);
    r.refresh_entry(e);
    if (front.mu(e) < before) ++r.stats().rebounded;
  }
  if (arrived.empty()) return;
  // The mesh's vertices over the new tiles carry the measured bounds too.
  PatchOutput& output = r.output();
  const int patch_log2 = r.landscape().patch_log2();
  for (std::uint32_t p = 0; p < output.patch_count(); ++p)
    for (std::uint32_t v = 0; v < output.vertex_slots(p); ++v) {
      if (!output.vertex_live(p, v)) continue;
      const auto q = output.coord(p, v);
      const Diamond d = diamond_at(q[0], q[1], patch_log2);
      if (d.corner || d.t >= int(levels)) continue;
      for (const DetailTileKey& key : arrived) {
        const std::int64_t i0 = std::int64_t(key.tx) * cells, j0 = std::int64_t(key.tz) * cells;
        if (q[0] >= i0 && q[0] <= i0 + cells && q[1] >= j0 && q[1] <= j0 + cells) {
          output.refresh_vertex(p, v);
          break;
        }
      }
    }
}

}  // namespace ridgeline::roam
