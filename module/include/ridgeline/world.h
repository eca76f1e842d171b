// Stored worlds as pages (docs/worlds.md): what a terrain's stored samples are made of, the
// interface through which an engine (or Ridgeline::io's reader of baked worlds) serves them, and
// the cache that keeps the pages a scene needs under a byte budget.
//
// Every terrain keeps its stored samples in pages: squares of 256 x 256 cells at each level of a
// pyramid whose level k holds every 4^k-th sample. A terrain made from a Heightfield has every
// page resident from the start; a terrain opened from a PageSource (a baked world) holds only
// the coarse levels at first and pages the rest in where views, queries and pins need them.
// Both read the same pages, so both give the same surface, the same bounds and the same meshes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "ridgeline/result.h"

namespace ridgeline {

/// How stored heights are encoded. kU16: height = height_offset + float(height_scale * value)
/// for a 16-bit value (exact for 16-bit input, 2 bytes per sample); kF32: the local height as a
/// float (4 bytes per sample). Edited pages always hold floats.
enum class SampleFormat : std::uint8_t { kU16 = 0, kF32 = 1 };

/// Cells per page side at the page's own stride; pages of level k cover 256 * 4^k stored cells.
inline constexpr std::int32_t kPageCells = 256;
/// Entries of apron around a page on each side (copies of the neighbours' samples, so that
/// everything about a vertex, the tessellator's bounds of its diamond included, is read from one
/// page: the descendants of a size-2 diamond reach 6 samples from its centre).
inline constexpr std::int32_t kPageApron = 6;
/// Entries per page row (and rows per page): 256 + 1 + 2 * 6.
inline constexpr std::int32_t kPageStride = kPageCells + 1 + 2 * kPageApron;
/// Entries per page.
inline constexpr std::size_t kPageEntries = std::size_t(kPageStride) * std::size_t(kPageStride);

/// Where a world's stored samples lie and how they are encoded: the header of a baked world, and
/// what a terrain made from a Heightfield describes itself with (Terrain::info()).
struct WorldInfo {
  std::uint32_t width = 0;     ///< samples along x, >= 2
  std::uint32_t height = 0;    ///< samples along z, >= 2
  double spacing_x = 1.0;      ///< metres between samples along x, > 0
  double spacing_z = 1.0;      ///< metres between samples along z, > 0
  double origin_x = 0.0;       ///< world x of sample (0, 0), metres
  double origin_z = 0.0;       ///< world z of sample (0, 0), metres
  double height_offset = 0.0;  ///< world height of local height 0, metres
  double height_scale = 1.0;   ///< kU16: metres per unit of the stored value
  SampleFormat format = SampleFormat::kF32;
  /// Lowest and highest local height (relative to height_offset); after edits, a range that
  /// holds every height (edits only widen it).
  float min_local = 0.0f, max_local = 0.0f;
  /// The stored data carries a material id per cell (otherwise every material is 0).
  bool has_materials = false;
  /// Samples replaced by a fill policy when the data was made (no-data), for information.
  std::uint64_t filled_samples = 0;
  /// Hash of size, placement, heights and materials as created (WorldInfo::content_hash() of
  /// the same samples gives the same value in memory and baked): what edit files record.
  std::uint64_t content_hash = 0;
  /// A name for messages (the file, "default terrain", ...).
  std::string name;

  /// World extent along x and z, metres: (width - 1) * spacing_x, (height - 1) * spacing_z.
  double extent_x() const noexcept { return double(width - 1) * spacing_x; }
  double extent_z() const noexcept { return double(height - 1) * spacing_z; }
};

/// A page of the stored pyramid: level k >= 0 holds every 4^k-th sample; page (px, pz) of level k
/// covers the samples (i, j) with i = (256 px + a) 4^k, j = (256 pz + b) 4^k, a and b in
/// -6 .. 262 (its 256 x 256 cells and a six-entry apron; entries past the data repeat the
/// nearest sample, as the padding of docs/surface.md does).
struct PageKey {
  std::uint32_t level = 0;
  std::int32_t px = 0, pz = 0;
  friend bool operator==(const PageKey&, const PageKey&) = default;
};

/// Per level-0 page, kept resident for the whole world: the range of local heights over the
/// page's samples (lo, hi), and over them widened by 8 samples on every side (lo8, hi8).
struct PageSummary {
  float lo = 0.0f, hi = 0.0f;
  float lo8 = 0.0f, hi8 = 0.0f;
};

/// The tessellator's settings a world's coarse bounds were baked for (docs/worlds.md): a
/// Landscape over that world uses them (LandscapeDesc 0 = from the world) and refuses others.
struct BakedRecords {
  std::uint32_t patch_exponent = 0;  ///< 0: the world carries no baked bounds
  double morph_window = 0.2;
  double morph_delay = 0.1;
};

/// Cells i0 .. i1 (inclusive) of row j of stored cells (cell (i, j) lies between samples i, i + 1
/// and j, j + 1) without ground: a world's holes (docs/deformation.md, "Holes").
struct HoleRun {
  std::uint32_t j = 0, i0 = 0, i1 = 0;
  friend bool operator==(const HoleRun&, const HoleRun&) = default;
};

/// One page as a PageSource delivers it.
struct PageData {
  /// kPageEntries heights, row-major (entry (a, b) at (a + 6) + (b + 6) * kPageStride): u16 for
  /// SampleFormat::kU16, f32 for kF32 (the other stays empty).
  std::vector<std::uint16_t> u16;
  std::vector<float> f32;
  /// Empty, or kPageEntries material ids (the stored cell at each entry, clamped into the data).
  std::vector<std::uint8_t> materials;
  /// The tessellator's baked bounds of the page's diamonds (levels >= 1; opaque bytes written by
  /// the bake, checked by the tessellator). Empty for level 0 and for worlds without them.
  std::vector<std::uint8_t> records;
};

/// What serves a world's pages: Ridgeline::io's reader of baked worlds (io::open_world), or an
/// engine's own asset system. load() runs on the page cache's worker threads or the engine's
/// executor (WorldCacheDesc), possibly on several at once, and on the thread of a query that
/// needs a page nobody loaded (a synchronous load): it must be safe to call concurrently.
class PageSource {
 public:
  virtual ~PageSource() = default;
  /// The world's header; constant.
  virtual const WorldInfo& info() const noexcept = 0;
  /// The settings of the baked bounds the pages of level >= 1 carry (patch_exponent 0: none).
  virtual BakedRecords baked_records() const noexcept { return {}; }
  /// One summary per level-0 page, row-major (pages_x * pages_z of them, pages_x = ceil((width -
  /// 1) / 256)): read once when the world is opened.
  virtual Status summaries(std::vector<PageSummary>& out) const = 0;
  /// Fills `out` with page `key`. An error (unreadable, corrupt: named in the message) leaves the
  /// page missing: views keep their coarser mesh there and queries answer "no data".
  virtual Status load(const PageKey& key, PageData& out) const = 0;
  /// The world's own holes (cells without ground from its input: no-data values, an alpha
  /// channel), read once when the world is opened; Terrain::open makes them its first hole mask,
  /// as Terrain::create does with a Heightfield's. Resident for the whole world: one bit per hole
  /// cell in blocks of 32 x 32 cells. Default: none.
  virtual Status holes(std::vector<HoleRun>& out) const {
    out.clear();
    return {};
  }
};

/// How a terrain opened from a PageSource keeps its pages.
struct WorldCacheDesc {
  /// Bytes of resident pages the cache keeps after each update() (LRU eviction beyond it). The
  /// coarse levels (always resident), pinned and edited pages count but are never evicted, so a
  /// budget below them is exceeded by them. >= 4 MiB; default 192 MiB.
  std::size_t budget_bytes = std::size_t{192} << 20;
  /// Worker threads of the cache's own pool, 0..64. 0: synchronous (a request loads at once).
  /// Ignored when `executor` is set. On Linux they run 10 nice levels below the thread that
  /// opened the terrain, so that streaming never takes a core from the frame.
  std::uint32_t worker_threads = 2;
  /// Optional job system of the embedding engine: called with a job to run once on any thread
  /// (as DetailCacheDesc::executor).
  std::function<void(std::function<void()>)> executor;
  /// Levels from the top of the pyramid held resident from the open on: every page of the
  /// coarsest `resident_levels` levels (at most 16 MiB worth; the rest of them page in).
  std::uint32_t resident_levels = 2;
};

/// Streaming statistics of a terrain's pages (Terrain::world_stats()).
struct WorldStats {
  std::size_t resident_pages = 0;    ///< pages held
  std::size_t resident_bytes = 0;    ///< their bytes (heights, bounds, ray pyramids, materials)
  std::size_t resident_samples = 0;  ///< stored samples those pages hold (level 0 and coarser)
  std::size_t budget_bytes = 0;      ///< WorldCacheDesc::budget_bytes (0: everything resident)
  std::size_t pinned_pages = 0;      ///< pages that cannot be evicted (coarse, pinned, edited)
  std::size_t pending = 0;           ///< pages requested and not yet resident
  std::uint64_t loaded = 0;          ///< pages loaded since the terrain was made
  std::uint64_t sync_loads = 0;      ///< of which a query or pin loaded on its own thread
  std::uint64_t evicted = 0;         ///< pages evicted since the terrain was made
  std::uint64_t failed = 0;          ///< loads that failed (the source's error, logged once)
  double load_seconds = 0;           ///< summed wall time of loads and their bound computation
};

}  // namespace ridgeline
