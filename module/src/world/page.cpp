// Pages of stored samples (world/page.h): the geometry of the pyramid, the snapshot table, pages
// made from a Heightfield, their ray pyramids and the content hash.
#include "world/page.h"

#include <cmath>
#include <cstring>

#include "ridgeline/heightfield.h"

namespace ridgeline::world {

// ---- geometry ----------------------------------------------------------------------------------

PageGrid PageGrid::of(std::uint32_t width, std::uint32_t height, std::uint32_t min_levels) {
  PageGrid g;
  g.last_i = std::int64_t(width) - 1;
  g.last_j = std::int64_t(height) - 1;
  for (std::uint32_t k = 0; k < kMaxLevels; ++k) {
    const int s = page_shift(k);
    g.px[k] = std::int32_t(std::max<std::int64_t>(1, (g.last_i + (std::int64_t{1} << s) - 1) >> s));
    g.pz[k] = std::int32_t(std::max<std::int64_t>(1, (g.last_j + (std::int64_t{1} << s) - 1) >> s));
    g.levels = k + 1;
    if (g.px[k] == 1 && g.pz[k] == 1 && g.levels >= min_levels) break;
  }
  return g;
}

std::size_t Page::memory_bytes() const noexcept {
  std::size_t b = sizeof(Page);
  if (samples)
    b += samples->u16.capacity() * 2 + samples->f32.capacity() * 4 + samples->materials.capacity();
  if (rays) b += sizeof(PageRays);
  if (baked) b += baked->capacity();
  return b;
}

// ---- the snapshot table ------------------------------------------------------------------------

PageTable::PageTable(const PageGrid& grid) {
  levels_.resize(grid.levels);
  for (std::uint32_t k = 0; k < grid.levels; ++k) {
    Level& l = levels_[k];
    l.px = grid.px[k], l.pz = grid.pz[k];
    l.cx = (l.px + kChunk - 1) >> kChunkShift;
    l.cz = (l.pz + kChunk - 1) >> kChunkShift;
    l.chunks.assign(std::size_t(l.cx) * std::size_t(l.cz), nullptr);
  }
}

PageTable::Chunk& PageTable::writable(Level& l, std::int32_t px, std::int32_t pz,
                                      std::vector<std::shared_ptr<Chunk>>& fresh) const {
  std::shared_ptr<const Chunk>& slot =
      l.chunks[std::size_t(px >> kChunkShift) + std::size_t(pz >> kChunkShift) * l.cx];
  // A chunk made for this snapshot is written in place; one shared with the old snapshot is
  // copied first.
  for (const auto& f : fresh)
    if (f.get() == slot.get()) return *f;
  auto c = slot ? std::make_shared<Chunk>(*slot) : std::make_shared<Chunk>();
  fresh.push_back(c);
  slot = c;
  return *c;
}

std::shared_ptr<const PageTable> PageTable::with(
    const std::vector<std::shared_ptr<const Page>>& changed, const std::vector<PageKey>& removed,
    std::vector<std::shared_ptr<const Page>> all, std::uint64_t generation) const {
  auto t = std::make_shared<PageTable>(*this);
  t->generation_ = generation;
  t->keep_ = std::move(all);
  std::vector<std::shared_ptr<Chunk>> fresh;
  auto put = [&](const PageKey& k, const Page* p) {
    Level& l = t->levels_[k.level];
    Chunk& c = t->writable(l, k.px, k.pz, fresh);
    c.pages[std::size_t(k.px & (kChunk - 1)) + std::size_t(k.pz & (kChunk - 1)) * kChunk] = p;
  };
  for (const PageKey& k : removed) put(k, nullptr);
  for (const auto& p : changed) put(p->key, p.get());
  return t;
}

// ---- pages from a Heightfield -----------------------------------------------------------------

bool fits_u16(const Heightfield& hf) {
  const double scale = hf.height_scale();
  for (float h : hf.local_heights()) {
    const double v = std::nearbyint(double(h) / scale);
    if (!(v >= 0.0 && v <= 65535.0) || static_cast<float>(scale * v) != h) return false;
  }
  return true;
}

std::shared_ptr<PageSamples> samples_from(const Heightfield& hf, const PageKey& key, bool as_u16) {
  auto s = std::make_shared<PageSamples>();
  const int shift = level_shift(key.level);
  const std::int64_t i0 = std::int64_t(key.px) << page_shift(key.level);
  const std::int64_t j0 = std::int64_t(key.pz) << page_shift(key.level);
  const std::int64_t wi = hf.width() - 1, hj = hf.height() - 1;
  if (as_u16)
    s->u16.resize(kPageEntries);
  else
    s->f32.resize(kPageEntries);
  if (hf.has_materials()) s->materials.resize(kPageEntries);
  const double scale = hf.height_scale();
  // Row by row: the entries past the data repeat its edge (clamped indices), so a row whose
  // clamped source row is the previous row's is a copy of it, and each row's entries left and
  // right of the data repeat its first and last sample (a small world's page is mostly these).
  constexpr std::size_t kRow = std::size_t(kPageStride);
  std::int64_t last_j = -1;
  for (std::int32_t b = -kPageApron; b <= kPageCells + kPageApron; ++b) {
    const auto j = std::uint32_t(std::clamp<std::int64_t>(j0 + (std::int64_t(b) << shift), 0, hj));
    const std::size_t row = entry_index(-kPageApron, b);
    if (std::int64_t(j) == last_j) {
      const std::size_t prev = row - kRow;
      if (as_u16)
        std::copy_n(s->u16.begin() + std::ptrdiff_t(prev), kRow, s->u16.begin() + std::ptrdiff_t(row));
      else
        std::copy_n(s->f32.begin() + std::ptrdiff_t(prev), kRow, s->f32.begin() + std::ptrdiff_t(row));
      if (!s->materials.empty())
        std::copy_n(s->materials.begin() + std::ptrdiff_t(prev), kRow,
                    s->materials.begin() + std::ptrdiff_t(row));
      continue;
    }
    last_j = j;
    std::int64_t last_i = -1;
    for (std::int32_t a = -kPageApron; a <= kPageCells + kPageApron; ++a) {
      const auto i =
          std::uint32_t(std::clamp<std::int64_t>(i0 + (std::int64_t(a) << shift), 0, wi));
      const std::size_t e = entry_index(a, b);
      if (std::int64_t(i) == last_i) {  // clamped: the entry before it holds the same sample
        if (as_u16)
          s->u16[e] = s->u16[e - 1];
        else
          s->f32[e] = s->f32[e - 1];
        if (!s->materials.empty()) s->materials[e] = s->materials[e - 1];
        continue;
      }
      last_i = i;
      const float h = hf.local(i, j);
      if (as_u16)
        s->u16[e] = static_cast<std::uint16_t>(std::nearbyint(double(h) / scale));
      else
        s->f32[e] = h;
      if (!s->materials.empty())
        s->materials[e] = hf.material(std::min(i, hf.width() - 2), std::min(j, hf.height() - 2));
    }
  }
  return s;
}

// ---- ray pyramid --------------------------------------------------------------------------------

namespace {

// Min and max of the samples of leaf block (x, z) of a page (its 4 x 4 cells' corners).
void leaf_node(PageRays& r, const Page& p, std::int32_t x, std::int32_t z) {
  const std::int32_t a0 = x << kRayLeafShift, b0 = z << kRayLeafShift;
  float lo = INFINITY, hi = -INFINITY;
  for (std::int32_t b = b0; b <= b0 + (1 << kRayLeafShift); ++b)
    for (std::int32_t a = a0; a <= a0 + (1 << kRayLeafShift); ++a) {
      const float h = p.local(a, b);
      lo = std::min(lo, h), hi = std::max(hi, h);
    }
  const std::size_t k = r.index(0, x, z);
  r.min[k] = lo, r.max[k] = hi;
}

void parent_node(PageRays& r, int level, std::int32_t x, std::int32_t z) {
  float lo = INFINITY, hi = -INFINITY;
  for (int c = 0; c < 4; ++c) {
    const std::size_t k = r.index(level - 1, 2 * x + (c & 1), 2 * z + (c >> 1));
    lo = std::min(lo, r.min[k]), hi = std::max(hi, r.max[k]);
  }
  const std::size_t k = r.index(level, x, z);
  r.min[k] = lo, r.max[k] = hi;
}

}  // namespace

std::shared_ptr<PageRays> make_rays(const Page& page) {
  auto r = std::make_shared<PageRays>();
  update_rays(*r, page, -kPageApron, -kPageApron, kPageCells + kPageApron,
              kPageCells + kPageApron);
  return r;
}

void update_rays(PageRays& r, const Page& page, std::int32_t a0, std::int32_t b0, std::int32_t a1,
                 std::int32_t b1) {
  // Blocks whose corners include a changed entry: a sample on a block border is in both.
  std::int32_t x0 = std::clamp((a0 - 1) >> kRayLeafShift, 0, 63);
  std::int32_t x1 = std::clamp(a1 >> kRayLeafShift, 0, 63);
  std::int32_t z0 = std::clamp((b0 - 1) >> kRayLeafShift, 0, 63);
  std::int32_t z1 = std::clamp(b1 >> kRayLeafShift, 0, 63);
  for (std::int32_t z = z0; z <= z1; ++z)
    for (std::int32_t x = x0; x <= x1; ++x) leaf_node(r, page, x, z);
  for (int l = 1; l < kRayLevels; ++l) {
    x0 >>= 1, x1 >>= 1, z0 >>= 1, z1 >>= 1;
    for (std::int32_t z = z0; z <= z1; ++z)
      for (std::int32_t x = x0; x <= x1; ++x) parent_node(r, l, x, z);
  }
}

// ---- content hash -------------------------------------------------------------------------------

namespace {

// A 64-bit mix over 8-byte words (the multiply-xorshift of splitmix64 applied per word): fast,
// and page hashes are independent, so a world hashes on every thread at once.
constexpr std::uint64_t kSeed = 0x9e3779b97f4a7c15ull;
inline std::uint64_t mix(std::uint64_t h, std::uint64_t v) noexcept {
  h ^= v + kSeed + (h << 6) + (h >> 2);
  h ^= h >> 30;
  h *= 0xbf58476d1ce4e5b9ull;
  h ^= h >> 27;
  h *= 0x94d049bb133111ebull;
  return h ^ (h >> 31);
}

}  // namespace

std::uint64_t hash_header(const WorldInfo& info) {
  std::uint64_t h = mix(kSeed, (std::uint64_t(info.width) << 32) | info.height);
  for (double v : {info.spacing_x, info.spacing_z, info.origin_x, info.origin_z,
                   info.height_offset, info.height_scale}) {
    std::uint64_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    h = mix(h, bits);
  }
  return mix(h, info.has_materials ? 1 : 0);
}

std::uint64_t hash_page(const Page& page, const PageGrid& grid, bool materials) {
  const std::int64_t i0 = std::int64_t(page.key.px) << 8, j0 = std::int64_t(page.key.pz) << 8;
  const bool last_x = page.key.px == grid.px[0] - 1, last_z = page.key.pz == grid.pz[0] - 1;
  const std::int32_t na = std::int32_t(last_x ? grid.last_i - i0 : kPageCells - 1);
  const std::int32_t nb = std::int32_t(last_z ? grid.last_j - j0 : kPageCells - 1);
  std::uint64_t h = mix(kSeed, (std::uint64_t(std::uint32_t(page.key.px)) << 32) |
                                   std::uint32_t(page.key.pz));
  for (std::int32_t b = 0; b <= nb; ++b) {
    std::uint64_t word = 0;
    int n = 0;
    for (std::int32_t a = 0; a <= na; ++a) {
      const float v = page.local(a, b);
      std::uint32_t bits;
      std::memcpy(&bits, &v, sizeof bits);
      word = (word << 32) | bits;
      if (++n == 2) h = mix(h, word), word = 0, n = 0;
    }
    if (n) h = mix(h, word);
  }
  if (materials && page.materials != nullptr) {
    // Cells: one fewer along each axis on the last pages.
    const std::int32_t ca = std::int32_t(last_x ? grid.last_i - 1 - i0 : kPageCells - 1);
    const std::int32_t cb = std::int32_t(last_z ? grid.last_j - 1 - j0 : kPageCells - 1);
    for (std::int32_t b = 0; b <= cb; ++b) {
      std::uint64_t word = 0;
      int n = 0;
      for (std::int32_t a = 0; a <= ca; ++a) {
        word = (word << 8) | page.material(a, b);
        if (++n == 8) h = mix(h, word), word = 0, n = 0;
      }
      if (n) h = mix(h, word);
    }
  }
  return h;
}

std::uint64_t combine_hashes(std::uint64_t header, const std::vector<std::uint64_t>& pages) {
  std::uint64_t h = header;
  for (std::uint64_t p : pages) h = mix(h, p);
  return h;
}

}  // namespace ridgeline::world
