// Private: the pages a terrain's stored samples live in (world.h), the immutable snapshot of
// the resident ones that readers look pages up in, and the geometry that maps a sample to its
// page.
//
// A page of level k holds kPageStride x kPageStride entries at stride 4^k: its 256 x 256 cells,
// the shared edges and a six-entry apron of its neighbours' samples, so that a vertex's height,
// normal, geomorph offset and bounds are all read from the one page that holds it. A page is
// immutable once published; an edit publishes a copy (copy on write), so a snapshot taken before
// keeps seeing the old one.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "ridgeline/world.h"

namespace ridgeline {
class Heightfield;
namespace roam {
struct RecordBlock;  // the tessellator's bounds of one page's diamonds (roam/records.h)
}
}  // namespace ridgeline

namespace ridgeline::world {

/// n / d rounded towards minus infinity (d > 0).
inline std::int64_t floor_div(std::int64_t n, std::int64_t d) noexcept {
  return n >= 0 ? n / d : -((-n + d - 1) / d);
}

/// Record slots a page carries: one per tessellator configuration in use (Landscape).
inline constexpr std::size_t kRecordSlots = 4;
/// Levels of the pyramid at most (4^15 * 256 cells is far beyond any world).
inline constexpr std::uint32_t kMaxLevels = 16;
/// Ray pyramid inside a level-0 page: blocks of 4 x 4 cells (64 per page side), then 32, 16, 8,
/// 4 and 2 nodes per side; the node of a whole page is the page's summary (PageSummary).
inline constexpr int kRayLevels = 6;
inline constexpr int kRayLeafShift = 2;

/// log2 of the stride of level k.
constexpr int level_shift(std::uint32_t level) noexcept { return int(2 * level); }
/// log2 of the stored cells a page of level k covers per side.
constexpr int page_shift(std::uint32_t level) noexcept { return 8 + level_shift(level); }
/// Index of entry (a, b) of a page (a, b in -6 .. 262).
constexpr std::size_t entry_index(std::int32_t a, std::int32_t b) noexcept {
  return std::size_t(a + kPageApron) + std::size_t(b + kPageApron) * std::size_t(kPageStride);
}

/// The geometry of a world's pyramid: how many pages each level has.
struct PageGrid {
  std::uint32_t levels = 0;                   ///< levels 0 .. levels - 1
  std::array<std::int32_t, kMaxLevels> px{};  ///< pages along x per level
  std::array<std::int32_t, kMaxLevels> pz{};
  std::int64_t last_i = 0, last_j = 0;  ///< the last sample index (width - 1, height - 1)

  /// Pages of every level for a world of width x height samples: up to the first level with a
  /// single page, and at least two levels (a level-0 page's tessellator bounds read the level-1
  /// page above it).
  static PageGrid of(std::uint32_t width, std::uint32_t height, std::uint32_t min_levels = 2);
  /// The page of level k that holds sample (i, j) (inside the data; clamped into the grid): the
  /// one whose cells hold it, the last one for the far edge.
  PageKey page_of(std::uint32_t level, std::int64_t i, std::int64_t j) const noexcept {
    const int s = page_shift(level);
    return {level, std::int32_t(std::clamp<std::int64_t>(i >> s, 0, px[level] - 1)),
            std::int32_t(std::clamp<std::int64_t>(j >> s, 0, pz[level] - 1))};
  }
  std::size_t count(std::uint32_t level) const noexcept {
    return std::size_t(px[level]) * std::size_t(pz[level]);
  }
};

/// Heights (and materials) of one page: shared by the versions of a page that differ only in
/// their bounds.
struct PageSamples {
  std::vector<std::uint16_t> u16;  ///< kPageEntries, or empty
  std::vector<float> f32;          ///< kPageEntries, or empty
  std::vector<std::uint8_t> materials;
};

/// Nodes of the ray pyramid of a level-0 page before level `level` (64^2 + 32^2 + ...).
constexpr std::size_t ray_offset(int level) noexcept {
  std::size_t o = 0;
  for (int l = 0; l < level; ++l) o += std::size_t(64 >> l) * std::size_t(64 >> l);
  return o;
}

/// Min/max of local heights over blocks of a level-0 page (the ray pyramid's levels 0 .. 5).
struct PageRays {
  static constexpr std::size_t offset(int level) noexcept { return ray_offset(level); }
  static constexpr std::size_t kNodes = ray_offset(kRayLevels);
  std::array<float, kNodes> max, min;
  /// Node (x, z) of ray level l (0 .. 5; 64 >> l nodes per side).
  std::size_t index(int level, std::int32_t x, std::int32_t z) const noexcept {
    return offset(level) + std::size_t(x) + std::size_t(z) * std::size_t(64 >> level);
  }
};

/// One resident page. Immutable once published.
class Page {
 public:
  PageKey key;
  std::shared_ptr<const PageSamples> samples;
  std::shared_ptr<const PageRays> rays;  ///< level 0 only
  /// The tessellator's bounds per record slot (null: not computed for that configuration).
  std::array<std::shared_ptr<const roam::RecordBlock>, kRecordSlots> records;
  /// Baked bounds as the source delivered them (levels >= 1 of a baked world), for the slot of
  /// the baked configuration to decode.
  std::shared_ptr<const std::vector<std::uint8_t>> baked;
  bool edited = false;  ///< an edit changed it: never evicted

  /// Raw pointers into `samples` (set by set_samples()).
  const std::uint16_t* u16 = nullptr;
  const float* f32 = nullptr;
  const std::uint8_t* materials = nullptr;
  double scale = 1.0;  ///< kU16: metres per unit

  void set_samples(std::shared_ptr<const PageSamples> s, double height_scale) noexcept {
    samples = std::move(s);
    u16 = samples->u16.empty() ? nullptr : samples->u16.data();
    f32 = samples->f32.empty() ? nullptr : samples->f32.data();
    materials = samples->materials.empty() ? nullptr : samples->materials.data();
    scale = height_scale;
  }
  /// Local height of entry e (entry_index()).
  float local(std::size_t e) const noexcept {
    return f32 != nullptr ? f32[e] : static_cast<float>(scale * double(u16[e]));
  }
  float local(std::int32_t a, std::int32_t b) const noexcept { return local(entry_index(a, b)); }
  std::uint8_t material(std::int32_t a, std::int32_t b) const noexcept {
    return materials != nullptr ? materials[entry_index(a, b)] : 0;
  }
  /// Bytes held by this page (its samples, ray pyramid and bounds).
  std::size_t memory_bytes() const noexcept;
  /// A copy sharing everything (to change one part and publish it).
  std::shared_ptr<Page> copy() const { return std::make_shared<Page>(*this); }
};

/// The resident pages at one moment: readers look pages up without a lock; the snapshot keeps
/// its pages alive. Pages are found through chunks of 32 x 32 page pointers, so a new snapshot
/// copies only the chunks whose pages changed.
class PageTable {
 public:
  static constexpr int kChunkShift = 5;
  static constexpr std::int32_t kChunk = 1 << kChunkShift;
  struct Chunk {
    std::array<const Page*, std::size_t(kChunk) * kChunk> pages{};
  };

  PageTable() = default;
  explicit PageTable(const PageGrid& grid);

  /// The page, or null when it is not resident.
  const Page* find(std::uint32_t level, std::int32_t px, std::int32_t pz) const noexcept {
    const Level& l = levels_[level];
    if (px < 0 || pz < 0 || px >= l.px || pz >= l.pz) return nullptr;
    const Chunk* c =
        l.chunks[std::size_t(px >> kChunkShift) + std::size_t(pz >> kChunkShift) * l.cx].get();
    return c ? c->pages[std::size_t(px & (kChunk - 1)) + std::size_t(pz & (kChunk - 1)) * kChunk]
             : nullptr;
  }
  const Page* find(const PageKey& k) const noexcept { return find(k.level, k.px, k.pz); }
  /// Identifies the snapshot: different for every snapshot a store publishes.
  std::uint64_t generation() const noexcept { return generation_; }
  std::size_t size() const noexcept { return keep_.size(); }
  /// Page k of the snapshot, 0 <= k < size(), in no particular order.
  const Page& page(std::size_t k) const noexcept { return *keep_[k]; }

  /// The next snapshot: this one with `changed` pages put in (replacing the page of the same
  /// key) and `removed` keys taken out; `all` is every page resident afterwards.
  std::shared_ptr<const PageTable> with(const std::vector<std::shared_ptr<const Page>>& changed,
                                        const std::vector<PageKey>& removed,
                                        std::vector<std::shared_ptr<const Page>> all,
                                        std::uint64_t generation) const;

 private:
  struct Level {
    std::int32_t px = 0, pz = 0, cx = 0, cz = 0;
    std::vector<std::shared_ptr<const Chunk>> chunks;
  };
  Chunk& writable(Level& l, std::int32_t px, std::int32_t pz,
                  std::vector<std::shared_ptr<Chunk>>& fresh) const;
  std::vector<Level> levels_;
  std::vector<std::shared_ptr<const Page>> keep_;
  std::uint64_t generation_ = 0;
};

/// The samples of every page of a world held as one Heightfield (a terrain made in memory):
/// entry (a, b) of page `key` from the field, clamped into it (the padding's rule). Heights are
/// stored as 16-bit values when every sample is float(scale * v) for an integer v in 0..65535,
/// as floats otherwise.
std::shared_ptr<PageSamples> samples_from(const Heightfield& hf, const PageKey& key,
                                          bool as_u16);
/// True when every sample of `hf` is float(height_scale * v) for an integer v in 0..65535.
bool fits_u16(const Heightfield& hf);
/// The ray pyramid of a level-0 page from its samples.
std::shared_ptr<PageRays> make_rays(const Page& page);
/// Recomputes the ray nodes of `rays` over the page's entries [a0, a1] x [b0, b1] (cells whose
/// corners changed).
void update_rays(PageRays& rays, const Page& page, std::int32_t a0, std::int32_t b0,
                 std::int32_t a1, std::int32_t b1);
/// The summary of level-0 page (px, pz) from a function giving the local height of any sample
/// (clamped into the data by the caller).
template <class Height>
PageSummary summarize(const PageGrid& g, std::int32_t px, std::int32_t pz, Height&& h) {
  PageSummary s{INFINITY, -INFINITY, INFINITY, -INFINITY};
  const std::int64_t i0 = std::int64_t(px) << 8, j0 = std::int64_t(pz) << 8;
  // Indices past the data are clamped into it, which only repeats samples: the ranges are those
  // of the samples in the clamped boxes, each read once (a small world's page is mostly repeats).
  const auto clamp_i = [&](std::int64_t i) { return std::clamp<std::int64_t>(i, 0, g.last_i); };
  const auto clamp_j = [&](std::int64_t j) { return std::clamp<std::int64_t>(j, 0, g.last_j); };
  const std::int64_t ia = clamp_i(i0), ib = clamp_i(i0 + kPageCells);
  const std::int64_t ja = clamp_j(j0), jb = clamp_j(j0 + kPageCells);
  for (std::int64_t j = clamp_j(j0 - 8); j <= clamp_j(j0 + kPageCells + 8); ++j)
    for (std::int64_t i = clamp_i(i0 - 8); i <= clamp_i(i0 + kPageCells + 8); ++i) {
      const float v = h(i, j);
      s.lo8 = std::min(s.lo8, v), s.hi8 = std::max(s.hi8, v);
      if (i >= ia && i <= ib && j >= ja && j <= jb) s.lo = std::min(s.lo, v), s.hi = std::max(s.hi, v);
    }
  return s;
}

/// 64-bit hash of a world's size, placement, heights and materials, page by page (level-0
/// pages' 256 x 256 cells' samples in row-major page order): the same for the same samples
/// whether they are held in memory or baked (WorldInfo::content_hash).
std::uint64_t hash_header(const WorldInfo& info);
/// Folds one page's samples (its canonical (257 - edge) x (257 - edge) block, local heights as
/// float bits, then materials) into a page hash.
std::uint64_t hash_page(const Page& page, const PageGrid& grid, bool materials);
/// Combines the header hash and the page hashes (row-major) into the content hash.
std::uint64_t combine_hashes(std::uint64_t header, const std::vector<std::uint64_t>& pages);

}  // namespace ridgeline::world
