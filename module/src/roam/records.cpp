// The tessellator's bounds of the stored diamonds, page by page (records.h).
//
// A diamond's error bound starts from the exact error of its triangles (the RTIN / "martini"
// definition: the largest vertical distance between the surface and the triangle over every
// lattice vertex under it; both are piecewise linear over the finest triangles, so the maximum is
// at a lattice vertex) and is made nested over the diamond hierarchy, as Lindstrom & Pascucci's
// SOAR nests its vertex errors: a diamond's bound is at least each of its four children's. With
// nested bounding spheres the projected bound of a diamond is then never smaller than a
// descendant's, so the set of diamonds to split is closed under the hierarchy for every camera:
// the mesh a threshold asks for is unique.
//
// The sphere of a diamond is centred at its vertex at its true height; its radius is at least
// every child's radius plus the distance to the child's centre, so it holds every lattice vertex
// under the diamond.
#include "roam/records.h"
#include "roam/diamond_bounds.h"
#include "world/page_store.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <thread>

#include "ridgeline/detail.h"
#include "ridgeline/log.h"

namespace ridgeline::roam {

using namespace bounds;  // one diamond's bound (diamond_bounds.h)

DiamondBound diamond_bound(const RecordConfig& c, const Heights& h, std::int64_t i, std::int64_t j,
                           const std::function<DiamondBound(std::int64_t, std::int64_t)>& child) {
  return bound_of(c, h, i, j, child);
}

DiamondBound edge_bound(const RecordConfig& c, const Heights& h, std::int64_t i, std::int64_t j) {
  return edge_of(c, h, i, j);
}

bool straddles_hole(const HoleMask& holes, int patch_log2, std::int64_t pad_i, std::int64_t pad_j,
                    std::int64_t i, std::int64_t j) {
  const Diamond d = diamond_at(i, j, patch_log2);
  std::int64_t hx0, hz0, hx1, hz1, ax0, az0, ax1, az1;
  d.hypotenuse(hx0, hz0, hx1, hz1);
  d.apexes(ax0, az0, ax1, az1);
  for (const auto& [ax, az] : {std::pair{ax0, az0}, std::pair{ax1, az1}}) {
    if (ax < 0 || az < 0 || ax > pad_i || az > pad_j) continue;
    if (holes.cover(ax, az, hx0, hz0, hx1, hz1, 0).mixed()) return true;
  }
  return false;
}

// ---- encoding -----------------------------------------------------------------------------------

std::vector<std::uint8_t> RecordBlock::encode() const {
  const std::size_t n =
      values.empty() && encoded ? (encoded->size() - kHeaderBytes) / 4 : values.size();
  std::vector<std::uint8_t> out(kHeaderBytes + n * 4);
  out[0] = 'R', out[1] = 'B', out[2] = std::uint8_t(level), out[3] = edges ? 1 : 0;
  const std::uint32_t n32 = std::uint32_t(n);
  std::memcpy(out.data() + 4, &n32, 4);
  if (!values.empty())
    std::memcpy(out.data() + kHeaderBytes, values.data(), n * 4);
  else if (n > 0)
    std::memcpy(out.data() + kHeaderBytes, encoded->data() + kHeaderBytes, n * 4);
  return out;
}

std::shared_ptr<RecordBlock> RecordBlock::decode(std::uint32_t level,
                                                 std::shared_ptr<const std::vector<std::uint8_t>> in) {
  if (!in || in->size() < kHeaderBytes || (*in)[0] != 'R' || (*in)[1] != 'B' || (*in)[2] != level)
    return nullptr;
  auto b = std::make_shared<RecordBlock>();
  b->level = level;
  b->edges = (*in)[3] != 0;
  std::uint32_t n;
  std::memcpy(&n, in->data() + 4, 4);
  if (n == 0 || n != slots(level, b->edges) || in->size() != kHeaderBytes + std::size_t(n) * 4)
    return nullptr;
  b->encoded = std::move(in);
  return b;
}

void RecordBlock::own() {
  if (!encoded) return;
  const std::size_t n = (encoded->size() - kHeaderBytes) / 4;
  values.resize(n);
  std::memcpy(values.data(), encoded->data() + kHeaderBytes, n * 4);
  encoded.reset();
}

// ---- level 0, from the page alone ---------------------------------------------------------------

namespace {

// The level-0 block of page (px, pz) from the packed bounds small_bounds() gave over the page and
// its apron (entry_index() order): the t <= 1 diamonds of the page's cells.
std::shared_ptr<RecordBlock> level0_from(const RecordConfig& c, std::int32_t px, std::int32_t pz,
                                         const std::vector<std::uint32_t>& local) {
  const std::int64_t i0 = std::int64_t(px) << 8, j0 = std::int64_t(pz) << 8;
  auto block = std::make_shared<RecordBlock>();
  block->level = 0;
  block->edges = c.L > 0;
  block->values.assign(RecordBlock::slots(0, block->edges), 0);
  // Entries past the padded extent hold no diamond (most of a small world's page).
  const std::int32_t bend = std::int32_t(std::min<std::int64_t>(kPageCells, c.pad_j - j0));
  const std::int32_t aend = std::int32_t(std::min<std::int64_t>(kPageCells, c.pad_i - i0));
  for (std::int32_t b = 0; b <= bend; ++b)
    for (std::int32_t a = 0; a <= aend; ++a) {
      const std::int64_t i = i0 + a, j = j0 + b;
      const Diamond d = diamond_at(i, j, c.patch_log2);
      if (d.corner || d.t >= 2) continue;
      if (d.t == 0 && !d.square && !block->edges) continue;
      block->set_packed(a, b, local[world::entry_index(a, b)]);
    }
  return block;
}

}  // namespace

std::shared_ptr<RecordBlock> level0_block(const RecordConfig& config, const world::Page& page) {
  RecordConfig holed;
  std::shared_ptr<const HoleMask> keep;
  const RecordConfig& c = with_holes(config, holed, keep);
  const std::int64_t i0 = std::int64_t(page.key.px) << 8, j0 = std::int64_t(page.key.pz) << 8;
  // Every t <= 1 diamond of the page and its apron whose descendants lie on the entries. The
  // apron (kPageApron = 6) is the reach of a t = 1 square diamond, so every diamond of the
  // page's own cells is among them.
  thread_local std::vector<float> heights;
  thread_local std::vector<std::uint32_t> local;  // packed bounds
  heights.resize(kPageEntries);
  for (std::size_t e = 0; e < kPageEntries; ++e) heights[e] = page.local(e);
  const DenseBlock h{heights.data(), i0 - kPageApron, j0 - kPageApron, kPageStride};
  local.assign(kPageEntries, 0);
  small_bounds(c, h, local);
  return level0_from(c, page.key.px, page.key.pz, local);
}

// ---- every block of a whole world ------------------------------------------------------------

namespace {

// Bounds on the grid of stride 4^k (positions (i, j) = (4^k m, 4^k n)), quantised.
struct StrideGrid {
  int shift = 0;  // log2 stride
  std::int64_t nx = 0, nz = 0, off = 0;
  std::vector<std::uint32_t> v;  // one packed bound per position
  void init(int s, std::int64_t pad_i, std::int64_t pad_j, std::int64_t offset) {
    shift = s, off = offset;
    nx = ((pad_i - off) >> s) + 1, nz = ((pad_j - off) >> s) + 1;
    v.assign(std::size_t(nx) * std::size_t(nz), 0);
  }
  bool has(std::int64_t i, std::int64_t j) const noexcept {
    if (i < off || j < off) return false;
    const std::int64_t m = (i - off) >> shift, n = (j - off) >> shift;
    return ((i - off) & ((std::int64_t{1} << shift) - 1)) == 0 &&
           ((j - off) & ((std::int64_t{1} << shift) - 1)) == 0 && m < nx && n < nz;
  }
  DiamondBound get(std::int64_t i, std::int64_t j) const noexcept {
    return packed::unpack(get_packed(i, j));
  }
  std::uint32_t get_packed(std::int64_t i, std::int64_t j) const noexcept {
    if (!has(i, j)) return 0;  // unpacks to DiamondBound{}
    const std::size_t k = std::size_t((i - off) >> shift) + std::size_t((j - off) >> shift) * std::size_t(nx);
    return v[k];
  }
  void set(std::int64_t i, std::int64_t j, const DiamondBound& b) noexcept {
    set_packed(i, j, packed::pack(b));
  }
  void set_packed(std::int64_t i, std::int64_t j, std::uint32_t packed_bound) noexcept {
    const std::size_t k = std::size_t((i - off) >> shift) + std::size_t((j - off) >> shift) * std::size_t(nx);
    v[k] = packed_bound;
  }
};

// Runs fn(row) for rows [0, n) on `threads` threads.
template <class Fn>
void parallel_rows(std::int64_t n, unsigned threads, const Fn& fn) {
  if (threads <= 1 || n < 16) {
    for (std::int64_t r = 0; r < n; ++r) fn(r);
    return;
  }
  std::atomic<std::int64_t> next{0};
  std::vector<std::thread> pool;
  for (unsigned t = 0; t < threads; ++t)
    pool.emplace_back([&] {
      for (std::int64_t r; (r = next.fetch_add(1)) < n;) fn(r);
    });
  for (auto& th : pool) th.join();
}

// True nested bounds of the t = 1 square diamonds (positions 2 mod 4): what the size-4 edge
// diamonds nest over (the level-0 blocks hold the same values).
// Computed page by page over the page and 8 samples around it; out(i, j, bound) gets each packed.
// `page_bounds(px, pz, local)`, when given, gets every page's packed bounds too: what
// level0_block() computes from the page's own samples, which these are.
template <class H, class Out>
void t1_squares(const RecordConfig& c, const world::PageGrid& g, const H& h,
                std::int64_t pi0, std::int64_t pj0, std::int64_t pi1, std::int64_t pj1,
                const Out& out, unsigned threads,
                const std::function<void(std::int32_t, std::int32_t, const std::vector<std::uint32_t>&)>&
                    page_bounds = nullptr) {
  const std::int64_t npx = pi1 - pi0 + 1;
  parallel_rows((pj1 - pj0 + 1) * npx, threads, [&](std::int64_t r) {
    const std::int64_t px = pi0 + r % npx, pz = pj0 + r / npx;
    if (px < 0 || pz < 0 || px >= g.px[0] || pz >= g.pz[0]) return;
    // The page's samples and its apron, as a level-0 page holds them.
    const std::int64_t i0 = (px << 8) - kPageApron, j0 = (pz << 8) - kPageApron;
    constexpr std::int64_t n = kPageStride;
    thread_local std::vector<float> heights;
    thread_local std::vector<std::uint32_t> local;  // packed bounds
    heights.resize(std::size_t(n * n));
    for (std::int64_t b = 0; b < n; ++b)
      read_row(h, j0 + b, i0, i0 + n - 1, heights.data() + b * n);
    local.assign(std::size_t(n * n), 0);
    small_bounds(c, DenseBlock{heights.data(), i0, j0, n}, local);
    // The t = 1 squares of this page's cells.
    for (std::int64_t j = (pz << 8) + 2; j < ((pz + 1) << 8) && j <= c.pad_j; j += 4)
      for (std::int64_t i = (px << 8) + 2; i < ((px + 1) << 8) && i <= c.pad_i; i += 4) {
        const Diamond d = diamond_at(i, j, c.patch_log2);
        if (d.corner || d.t != 1 || !d.square) continue;
        out(i, j, local[std::size_t((i - i0) + (j - j0) * n)]);
      }
    if (page_bounds) page_bounds(std::int32_t(px), std::int32_t(pz), local);
  });
}

// Level k >= 1 (t = 2k, 2k + 1) bounds of the positions of `grid` inside [i0, i1] x [j0, j1]
// whose reach meets it (all of them for a whole world), from the heights and the grids below.
// The finer levels (t <= 5: triangles of legs up to 32 cells, most of whose samples the small-
// triangle table reads one by one) go tile by tile, each tile's heights copied once into a dense
// block (the accessor's values bit for bit, so the bounds are the same): the reads are then plain
// array reads without clamping, and a tile's rows stay in cache. The coarser levels read whole
// rows through the accessor.
template <class H>
void level_bounds(const RecordConfig& c, const H& h, int k, StrideGrid& grid,
                  const StrideGrid& below_squares, std::int64_t i0, std::int64_t j0,
                  std::int64_t i1, std::int64_t j1, unsigned threads) {
  const std::int64_t stride = std::int64_t{1} << (2 * k);
  for (int kind = 0; kind < 4; ++kind) {
    const int t = 2 * k + kind / 2;
    const bool square = (kind & 1) != 0;
    if (t >= c.patch_log2) break;
    const std::int64_t s = std::int64_t{1} << t, reach = (square ? 3 : 2) * s;
    const std::int64_t a0 = std::max<std::int64_t>(0, floor_div(i0 - reach, stride));
    const std::int64_t a1 = std::min<std::int64_t>(c.pad_i / stride, floor_div(i1 + reach, stride) + 1);
    const std::int64_t b0 = std::max<std::int64_t>(0, floor_div(j0 - reach, stride));
    const std::int64_t b1 = std::min<std::int64_t>(c.pad_j / stride, floor_div(j1 + reach, stride) + 1);
    if (a1 < a0 || b1 < b0) continue;
    auto child_packed = [&](std::int64_t ci, std::int64_t cj) -> std::uint32_t {
      if (grid.has(ci, cj)) return grid.get_packed(ci, cj);
      return below_squares.get_packed(ci, cj);
    };
    auto child = [&](std::int64_t ci, std::int64_t cj) { return packed::unpack(child_packed(ci, cj)); };
    // The small triangles' stencils serve the size-4 edges too (legs of 4 cells across, the
    // table's largest) without detail or holes, below the patches' top; larger triangles'
    // rows come from their shapes' table (exact_triangle()).
    const bool stencils = c.L == 0 && c.holes == nullptr && t < c.patch_log2 - 1 && t == 2 && !square;
    // The diamond at position (a, b) from heights `hh`, when it is of this kind and meets the box.
    auto one = [&](const auto& hh, std::int64_t a, std::int64_t b) {
      const std::int64_t i = a * stride, j = b * stride;
      const Diamond d = diamond_at(i, j, c.patch_log2);
      if (d.corner || d.t != t || d.square != square) return;
      if (i + reach < i0 || i - reach > i1 || j + reach < j0 || j - reach > j1) return;
      grid.set_packed(i, j, packed::pack(bound_of(c, hh, i, j, child)));
    };
    if (t > 5) {
      parallel_rows(b1 - b0 + 1, threads, [&](std::int64_t r) {
        for (std::int64_t a = a0; a <= a1; ++a) one(h, a, b0 + r);
      });
      continue;
    }
    // Tiles of 128 samples a side (32 or 8 positions); a diamond's triangles and children lie
    // within s samples of its centre.
    const std::int64_t per = std::max<std::int64_t>(1, 128 / stride);
    const std::int64_t ta = (a1 - a0) / per + 1, tb = (b1 - b0) / per + 1;
    parallel_rows(ta * tb, threads, [&](std::int64_t r) {
      const std::int64_t pa0 = a0 + (r % ta) * per, pb0 = b0 + (r / ta) * per;
      const std::int64_t pa1 = std::min(a1, pa0 + per - 1), pb1 = std::min(b1, pb0 + per - 1);
      const std::int64_t x0 = pa0 * stride - s, z0 = pb0 * stride - s;
      const std::int64_t n = std::max(pa1 - pa0, pb1 - pb0) * stride + 2 * s + 1;
      thread_local std::vector<float> heights;
      heights.resize(std::size_t(n * n));
      for (std::int64_t z = 0; z < n; ++z)
        read_row(h, z0 + z, x0, x0 + n - 1, heights.data() + z * n);
      const DenseBlock dense{heights.data(), x0, z0, n};
      if (!stencils) {
        for (std::int64_t b = pb0; b <= pb1; ++b)
          for (std::int64_t a = pa0; a <= pa1; ++a) one(dense, a, b);
        return;
      }
      // Diamonds inside the data through the stencil of their orientation (four at a time where
      // the CPU allows), the others through bound_of().
      const SmallStencils& st = small_stencils(t, square, n);
      StencilBatches batches(st, c, heights.data());
      auto store = [&grid](std::int64_t i, std::int64_t j, std::uint32_t v) { grid.set_packed(i, j, v); };
      for (std::int64_t b = pb0; b <= pb1; ++b)
        for (std::int64_t a = pa0; a <= pa1; ++a) {
          const std::int64_t i = a * stride, j = b * stride;
          if (i - s < 0 || j - s < 0 || i + s > c.last_i || j + s > c.last_j) {
            one(dense, a, b);
            continue;
          }
          const Diamond d = diamond_at(i, j, c.patch_log2);
          if (d.corner || d.t != t || d.square != square) continue;
          if (i + reach < i0 || i - reach > i1 || j + reach < j0 || j - reach > j1) continue;
          const int which = st.which(i, j);
          std::uint32_t cv[4];
          for (int q = 0; q < 4; ++q)
            cv[q] = child_packed(i + st.v[std::size_t(which)].cdi[q], j + st.v[std::size_t(which)].cdj[q]);
          batches.add(which, std::int32_t((i - x0) + (j - z0) * n), cv, i, j, store);
        }
      batches.flush(store);
    });
  }
}

// The block of level-k page `key` (k >= 1) from the grids (entries 0 .. 256): the diamonds whose
// record level (record_level()) is k, each from its own level's grid.
std::shared_ptr<RecordBlock> slice(const RecordConfig& c, const std::vector<StrideGrid>& grids,
                                   std::uint32_t levels, const PageKey& key) {
  auto block = std::make_shared<RecordBlock>();
  block->level = key.level;
  block->values.assign(RecordBlock::kCoarse, 0);
  const int ls = world::level_shift(key.level);
  const std::int64_t i0 = std::int64_t(key.px) << world::page_shift(key.level);
  const std::int64_t j0 = std::int64_t(key.pz) << world::page_shift(key.level);
  for (std::int32_t b = 0; b <= kPageCells; ++b)
    for (std::int32_t a = 0; a <= kPageCells; ++a) {
      const std::int64_t i = i0 + (std::int64_t(a) << ls), j = j0 + (std::int64_t(b) << ls);
      if (i < 0 || j < 0 || i > c.pad_i || j > c.pad_j) continue;
      const Diamond d = diamond_at(i, j, c.patch_log2);
      if (d.corner || record_level(d.t, levels) != key.level) continue;
      const std::size_t g = std::size_t(d.t / 2);
      block->set(a, b, g < grids.size() ? grids[g].get(i, j) : DiamondBound{});
    }
  return block;
}


}  // namespace

void build_all(const RecordConfig& config, const world::PageGrid& grid, const Heights& h,
               const std::function<const world::Page*(const PageKey&)>& page,
               const std::function<void(const PageKey&, std::shared_ptr<RecordBlock>)>& out,
               unsigned threads, bool level0) {
  RecordConfig holed;
  std::shared_ptr<const HoleMask> keep;
  const RecordConfig& c = with_holes(config, holed, keep);
  const Heights& dh = h;
  // Grids of every level >= 1, coarsest last; each built from the one below.
  const int top_level = (c.patch_log2 - 1) / 2;
  std::vector<StrideGrid> grids(std::size_t(std::max(top_level, 0)) + 1);
  StrideGrid squares1;  // t = 1 squares
  squares1.init(2, c.pad_i, c.pad_j, 2);
  // The level-0 blocks come from the same pass: its bounds over each page and its apron are the
  // ones level0_block() would compute again from the page.
  std::vector<std::shared_ptr<RecordBlock>> level0_blocks(level0 ? grid.count(0) : 0);
  t1_squares(c, grid, dh, 0, 0, grid.px[0] - 1, grid.pz[0] - 1,
             [&](std::int64_t i, std::int64_t j, std::uint32_t v) { squares1.set_packed(i, j, v); },
             threads, [&](std::int32_t px, std::int32_t pz, const std::vector<std::uint32_t>& local) {
               if (!level0 || page(PageKey{0, px, pz}) == nullptr) return;
               level0_blocks[std::size_t(px) + std::size_t(pz) * std::size_t(grid.px[0])] =
                   level0_from(c, px, pz, local);
             });
  for (int k = 1; k <= top_level; ++k) {
    grids[std::size_t(k)].init(2 * k, c.pad_i, c.pad_j, 0);
    level_bounds(c, dh, k, grids[std::size_t(k)], k == 1 ? squares1 : grids[std::size_t(k - 1)],
                 0, 0, c.pad_i, c.pad_j, threads);
  }
  // Level >= 1 blocks, then level 0 (from the pages alone).
  std::vector<PageKey> coarse;
  for (std::uint32_t k = 1; k < grid.levels; ++k)
    for (std::int32_t pz = 0; pz < grid.pz[k]; ++pz)
      for (std::int32_t px = 0; px < grid.px[k]; ++px) coarse.push_back({k, px, pz});
  parallel_rows(std::int64_t(coarse.size()), threads, [&](std::int64_t r) {
    const PageKey& key = coarse[std::size_t(r)];
    out(key, slice(c, grids, grid.levels, key));
  });
  for (std::size_t r = 0; r < level0_blocks.size(); ++r)
    if (level0_blocks[r])
      out(PageKey{0, std::int32_t(r % std::size_t(grid.px[0])), std::int32_t(r / std::size_t(grid.px[0]))},
          std::move(level0_blocks[r]));
}

std::vector<std::pair<PageKey, std::shared_ptr<const RecordBlock>>> remake(
    const RecordConfig& config, const world::PageGrid& grid, const Heights& h,
    const std::function<const world::Page*(const PageKey&)>& page,
    const std::function<const RecordBlock*(const PageKey&)>& block, std::int64_t i0,
    std::int64_t j0, std::int64_t i1, std::int64_t j1) {
  RecordConfig holed;
  std::shared_ptr<const HoleMask> keep;
  const RecordConfig& c = with_holes(config, holed, keep);
  const Heights& dh = h;
  // The padding repeats the edge samples: an edited edge sample moves the padding too.
  if (i1 >= c.last_i) i1 = c.pad_i;
  if (j1 >= c.last_j) j1 = c.pad_j;
  std::unordered_map<PageKey, std::shared_ptr<RecordBlock>, world::PageKeyHash> fresh;
  auto writable = [&](const PageKey& k) -> RecordBlock* {
    if (auto it = fresh.find(k); it != fresh.end()) return it->second.get();
    const RecordBlock* b = block(k);
    if (b == nullptr) return nullptr;
    auto copy = std::make_shared<RecordBlock>(*b);
    RecordBlock* raw = copy.get();
    fresh.emplace(k, std::move(copy));
    return raw;
  };
  const int top_level = (c.patch_log2 - 1) / 2;
  // Level by level: the positions whose reach meets the change, from the current bounds (the
  // blocks) and the heights, then written to every block holding them (aprons included).
  // Read-modify-write through a map keyed by position (the window is small).
  struct Window {
    std::unordered_map<std::uint64_t, DiamondBound> v;
    static std::uint64_t key(std::int64_t i, std::int64_t j) {
      return (std::uint64_t(std::uint32_t(j)) << 32) | std::uint32_t(i);
    }
  };
  // The current bound of a level >= 1 diamond from its block (canonical page).
  auto stored = [&](std::int64_t i, std::int64_t j) -> DiamondBound {
    const Diamond d = diamond_at(i, j, c.patch_log2);
    if (d.corner) return {};
    const std::uint32_t k = record_level(d.t, grid.levels);
    const PageKey key = grid.page_of(k, i, j);
    const std::int32_t a = std::int32_t((i >> (2 * k)) - (std::int64_t(key.px) << 8));
    const std::int32_t b = std::int32_t((j >> (2 * k)) - (std::int64_t(key.pz) << 8));
    if (auto it = fresh.find(key); it != fresh.end()) return it->second->get(a, b);
    const RecordBlock* bl = block(key);
    return bl ? bl->get(a, b) : DiamondBound{};
  };
  // Into every block holding it: its page's and, on a page edge, its neighbours' (entries 0 ..
  // 256 of each).
  auto store_everywhere = [&](std::int64_t i, std::int64_t j, std::uint32_t k, const DiamondBound& v) {
    const int ls = world::level_shift(k);
    const std::int64_t x = i >> ls, z = j >> ls;
    for (std::int64_t pz = std::max<std::int64_t>(0, floor_div(z - 1, kPageCells));
         pz <= std::min<std::int64_t>(grid.pz[k] - 1, floor_div(z, kPageCells)); ++pz)
      for (std::int64_t px = std::max<std::int64_t>(0, floor_div(x - 1, kPageCells));
           px <= std::min<std::int64_t>(grid.px[k] - 1, floor_div(x, kPageCells)); ++px) {
        const std::int32_t a = std::int32_t(x - (px << 8)), b = std::int32_t(z - (pz << 8));
        if (!RecordBlock::holds(a, b)) continue;
        if (RecordBlock* bl = writable({k, std::int32_t(px), std::int32_t(pz)})) bl->set(a, b, v);
      }
  };
  // t = 1 squares near the change: true values (runtime radius) from the heights.
  Window t1;
  {
    // The pages near the change (a t = 2 edge diamond reaching the change has its children
    // within 10 samples of it).
    const std::int64_t w = 16;
    t1_squares(c, grid, dh, std::max<std::int64_t>(0, (i0 - w) >> 8),
               std::max<std::int64_t>(0, (j0 - w) >> 8), (i1 + w) >> 8, (j1 + w) >> 8,
               [&](std::int64_t i, std::int64_t j, std::uint32_t v) {
                 t1.v[Window::key(i, j)] = packed::unpack(v);
               },
               1);
  }
  for (int k = 1; k <= top_level; ++k) {
    const std::int64_t stride = std::int64_t{1} << (2 * k);
    for (int kind = 0; kind < 4; ++kind) {
      const int t = 2 * k + kind / 2;
      const bool square = (kind & 1) != 0;
      if (t >= c.patch_log2) break;
      const std::int64_t s = std::int64_t{1} << t, reach = (square ? 3 : 2) * s;
      const std::int64_t a0 = std::max<std::int64_t>(0, floor_div(i0 - reach, stride));
      const std::int64_t a1 = std::min<std::int64_t>(c.pad_i / stride, floor_div(i1 + reach, stride) + 1);
      const std::int64_t b0 = std::max<std::int64_t>(0, floor_div(j0 - reach, stride));
      const std::int64_t b1 = std::min<std::int64_t>(c.pad_j / stride, floor_div(j1 + reach, stride) + 1);
      for (std::int64_t b = b0; b <= b1; ++b)
        for (std::int64_t a = a0; a <= a1; ++a) {
          const std::int64_t i = a * stride, j = b * stride;
          const Diamond d = diamond_at(i, j, c.patch_log2);
          if (d.corner || d.t != t || d.square != square) continue;
          if (i + reach < i0 || i - reach > i1 || j + reach < j0 || j - reach > j1) continue;
          auto child = [&](std::int64_t ci, std::int64_t cj) -> DiamondBound {
            const Diamond cd = diamond_at(ci, cj, c.patch_log2);
            if (cd.t <= 1) {
              auto it = t1.v.find(Window::key(ci, cj));
              return it != t1.v.end() ? it->second : DiamondBound{};
            }
            return stored(ci, cj);
          };
          store_everywhere(i, j, record_level(t, grid.levels), bound_of(c, dh, i, j, child));
        }
    }
  }
  // Level-0 pages near the change (their apron reaches 6 samples past their cells).
  const std::int64_t w = 16;
  for (std::int64_t pz = std::max<std::int64_t>(0, (j0 - w) >> 8);
       pz <= std::min<std::int64_t>(grid.pz[0] - 1, (j1 + w) >> 8); ++pz)
    for (std::int64_t px = std::max<std::int64_t>(0, (i0 - w) >> 8);
         px <= std::min<std::int64_t>(grid.px[0] - 1, (i1 + w) >> 8); ++px) {
      const PageKey key{0, std::int32_t(px), std::int32_t(pz)};
      if (const world::Page* p = page(key)) fresh[key] = level0_block(c, *p);
    }
  std::vector<std::pair<PageKey, std::shared_ptr<const RecordBlock>>> outv;
  outv.reserve(fresh.size());
  for (auto& [k, b] : fresh) outv.emplace_back(k, std::move(b));
  return outv;
}

}  // namespace ridgeline::roam
