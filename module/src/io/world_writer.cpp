// The bake (world_file.h): samples in memory to a world file (world_format.h). Stages: the
// samples (checked, or quantised to a tolerance), the page summaries, the tessellator's coarse
// bounds (records.h, from every sample), the pages of every level (cut and compressed by workers
// while this thread writes them in order), then the end of the file (world_file_end.cpp: the
// entry chunks, the index, the TIFF directories and the locator); flushed and renamed.

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <cmath>
#include <cstring>
#include <unordered_map>
#include <thread>

#include "format.h"
#include "io/durable_file.h"
#include "io/world_format.h"
#include "io/world_output.h"
#include "ridgeline/world_file.h"
#include "roam/records.h"
#include "surface/hole_mask.h"
#include "world/page.h"

namespace ridgeline::io {

using detail::fmt;
using detail::num;
using namespace world_file;

namespace {

struct Cancelled {};

// Runs fn(k) for k in [0, n) on `threads` threads.
template <class Fn>
void parallel_for(std::size_t n, unsigned threads, const Fn& fn) {
  if (threads <= 1 || n < 2) {
    for (std::size_t k = 0; k < n; ++k) fn(k);
    return;
  }
  std::atomic<std::size_t> next{0};
  std::vector<std::thread> pool;
  for (unsigned t = 0; t < std::min<std::size_t>(threads, n); ++t)
    pool.emplace_back([&] {
      for (std::size_t k; (k = next.fetch_add(1)) < n;) fn(k);
    });
  for (auto& th : pool) th.join();
}

// One compressed page as it goes to the file.
struct CompressedPage {
  std::vector<std::uint8_t> tile, apron, materials, records;
  // TIFF-only tiles past a level's last page (2^k + 1 sizes leave one sample column and row over
  // the pages' 256-sample tiles): the column right of the page (x), the row below it (z) and the
  // corner sample (xz), each as a whole TIFF tile; empty when the page has no such neighbour.
  std::vector<std::uint8_t> edge_x, edge_z, edge_xz;
  std::uint64_t hash = 0;  // the content hash's page hash (level 0)
  // The four parts joined as the file holds them, their sizes and checksum.
  std::vector<std::uint8_t> all;
  std::vector<std::uint32_t> sizes;
  std::uint64_t checksum = 0;
};

}  // namespace

Result<BakeReport> bake_world(const BakeSamples& in, const std::string& path,
                              const BakeOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  WorldInfo info = in.info;
  const std::string what = "bake '" + path + "'";
  // ---- checks --------------------------------------------------------------------------------
  {
    HeightfieldDesc d;
    d.width = info.width, d.height = info.height;
    d.spacing_x = info.spacing_x, d.spacing_z = info.spacing_z;
    d.origin_x = info.origin_x, d.origin_z = info.origin_z;
    d.height_offset = info.height_offset;
    d.height_scale = info.height_scale;
    d.max_samples = ~std::uint64_t{0};
    d.name = what;
    if (auto s = validate_heightfield_desc(d); !s) return Error{s.message()};
  }
  const bool u16_in = info.format == SampleFormat::kU16;
  if ((u16_in && in.u16 == nullptr) || (!u16_in && in.f32 == nullptr))
    return Error{what + ": no samples given for the format"};
  if (o.threads > 256) return Error{fmt("%s: %u threads; need 0..256", what.c_str(), o.threads)};
  if (o.compression_level < 1 || o.compression_level > 12)
    return Error{fmt("%s: compression level %d; need 1..12", what.c_str(), o.compression_level)};
  if (o.tolerance && !(std::isfinite(*o.tolerance) && *o.tolerance > 0))
    return Error{fmt("%s: tolerance %s m; need a finite value > 0 (--tolerance)", what.c_str(),
                     num(o.tolerance.value_or(0)).c_str())};
  // The holes: checked, as runs along rows (what the index stores) and as the mask the bounds
  // are made around.
  std::vector<HoleRun> hole_runs;
  std::shared_ptr<HoleMask> holes;
  if (!in.hole_cells.empty()) {
    const std::uint64_t cx = info.width - 1, cells = cx * std::uint64_t(info.height - 1);
    std::vector<std::uint64_t> sorted(in.hole_cells.begin(), in.hole_cells.end());
    std::sort(sorted.begin(), sorted.end());
    sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
    if (sorted.back() >= cells)
      return Error{fmt("%s: hole cell %llu is outside the %u x %u cells", what.c_str(),
                       static_cast<unsigned long long>(sorted.back()), info.width - 1,
                       info.height - 1)};
    holes = std::make_shared<HoleMask>();
    for (const std::uint64_t c : sorted) {
      const auto i = std::uint32_t(c % cx), j = std::uint32_t(c / cx);
      if (!hole_runs.empty() && hole_runs.back().j == j && hole_runs.back().i1 + 1 == i)
        hole_runs.back().i1 = i;
      else
        hole_runs.push_back({j, i, i});
    }
    for (const HoleRun& r : hole_runs) holes->set_run(r.j, r.i0, r.i1);
  }
  const unsigned threads =
      o.threads ? o.threads : std::max(1u, std::thread::hardware_concurrency());
  const std::size_t n = std::size_t(info.width) * info.height;
  auto report = [&](double f, const char* stage) {
    if (o.progress && !o.progress(std::clamp(f, 0.0, 1.0), stage)) throw Cancelled{};
  };
  BakeReport rep;
  rep.samples = n;
  try {
    report(0.0, "samples");
    // ---- samples: checked, min/max, optionally quantised --------------------------------------
    std::vector<std::uint16_t> quantised;
    const std::uint16_t* u16 = in.u16;
    const float* f32 = in.f32;
    float lo = INFINITY, hi = -INFINITY;
    {
      const std::size_t chunks = std::max<std::size_t>(1, std::min<std::size_t>(256, n / 65536));
      std::vector<float> clo(chunks, INFINITY), chi(chunks, -INFINITY);
      std::vector<std::size_t> bad(chunks, n);
      parallel_for(chunks, threads, [&](std::size_t c) {
        const std::size_t a = n * c / chunks, b = n * (c + 1) / chunks;
        if (u16) {
          // 16-bit values are finite: their extremes give the range (the scale is > 0).
          std::uint16_t vlo = 0xffff, vhi = 0;
          for (std::size_t k = a; k < b; ++k)
            vlo = std::min(vlo, u16[k]), vhi = std::max(vhi, u16[k]);
          clo[c] = static_cast<float>(info.height_scale * double(vlo));
          chi[c] = static_cast<float>(info.height_scale * double(vhi));
          if (!(std::abs(chi[c]) <= float(kMaxRelativeHeight)))
            for (std::size_t k = a; k < b && bad[c] == n; ++k)
              if (u16[k] == vhi) bad[c] = k;
          return;
        }
        for (std::size_t k = a; k < b; ++k) {
          const float v = u16 ? static_cast<float>(info.height_scale * double(u16[k])) : f32[k];
          if (!(std::abs(v) <= float(kMaxRelativeHeight))) {
            bad[c] = std::min(bad[c], k);
            continue;
          }
          clo[c] = std::min(clo[c], v), chi[c] = std::max(chi[c], v);
        }
      });
      for (std::size_t c = 0; c < chunks; ++c) {
        if (bad[c] < n) {
          const std::size_t k = bad[c];
          return Error{fmt("%s: sample (%zu, %zu) is %s; need a finite height within +-%.0f m of "
                           "the offset",
                           what.c_str(), k % info.width, k / info.width,
                           detail::numf(u16 ? float(info.height_scale * double(u16[k])) : f32[k]).c_str(),
                           kMaxRelativeHeight)};
        }
        lo = std::min(lo, clo[c]), hi = std::max(hi, chi[c]);
      }
    }
    info.min_local = lo, info.max_local = hi;
    if (!u16 && o.tolerance) {
      // 16-bit values relative to the lowest height: local = float(step * v), offset moved.
      const double range = double(hi) - double(lo);
      const double step = std::max(range / 65535.0, 1e-12);
      if (step / 2.0 > *o.tolerance)
        return Error{fmt("%s: a tolerance of %s m needs a 16-bit step of at most %s m, but the "
                         "heights span %s m (a step of %s m); raise --tolerance to at least %s "
                         "m, or leave it out to keep the floats",
                         what.c_str(), num(*o.tolerance).c_str(), num(2 * *o.tolerance).c_str(),
                         num(range).c_str(), num(step).c_str(), num(step / 2.0).c_str())};
      quantised.resize(n);
      std::vector<double> worst(threads, 0.0);
      const double new_offset = info.height_offset + double(lo);
      parallel_for(threads, threads, [&](std::size_t t) {
        for (std::size_t k = n * t / threads; k < n * (t + 1) / threads; ++k) {
          const double v = std::nearbyint((double(f32[k]) - double(lo)) / step);
          quantised[k] = std::uint16_t(std::clamp(v, 0.0, 65535.0));
          const double stored = new_offset + double(static_cast<float>(step * quantised[k]));
          worst[t] = std::max(worst[t], std::abs(stored - (info.height_offset + double(f32[k]))));
        }
      });
      rep.max_error_m = *std::max_element(worst.begin(), worst.end());
      if (rep.max_error_m > *o.tolerance)
        return Error{fmt("%s: quantising to 16 bits leaves an error of %s m, above the tolerance "
                         "of %s m (--tolerance)",
                         what.c_str(), num(rep.max_error_m).c_str(), num(*o.tolerance).c_str())};
      info.height_offset = new_offset;
      info.height_scale = step;
      info.format = SampleFormat::kU16;
      info.min_local = 0.0f;
      info.max_local = static_cast<float>(step * 65535.0);
      lo = info.min_local, hi = info.max_local;
      u16 = quantised.data();
      f32 = nullptr;
    }
    rep.format = info.format;
    const bool store_u16 = info.format == SampleFormat::kU16;
    roam::Heights h;
    h.u16 = u16, h.f32 = f32, h.scale = info.height_scale;
    h.stride = info.width, h.last_i = info.width - 1, h.last_j = info.height - 1;
    report(0.05, "summaries");

    // ---- page summaries -----------------------------------------------------------------------
    const world::PageGrid grid = world::PageGrid::of(info.width, info.height);
    std::vector<PageSummary> summaries(grid.count(0));
    parallel_for(summaries.size(), threads, [&](std::size_t k) {
      summaries[k] = world::summarize(grid, std::int32_t(k % std::size_t(grid.px[0])),
                                      std::int32_t(k / std::size_t(grid.px[0])),
                                      [&](std::int64_t i, std::int64_t j) { return h(i, j); });
    });
    report(0.1, "bounds");

    // ---- the tessellator's coarse bounds --------------------------------------------------------
    const auto tb = std::chrono::steady_clock::now();
    std::uint32_t exponent = o.landscape.patch_exponent;
    if (exponent == 0) exponent = roam::default_patch_exponent(info.width, info.height);
    if (exponent < 2 || exponent > 10)
      return Error{
          fmt("%s: patch exponent %u; need 2..10 (--patch-exponent)", what.c_str(), exponent)};
    const double window = o.landscape.morph_window;
    const double delay = window > 0.0 ? o.landscape.morph_delay : 0.0;
    if (!(window >= 0.0 && window <= 4.0) || !(delay >= 0.0 && delay <= 1.0))
      return Error{fmt("%s: morph window %s / delay %s; need 0..4 and 0..1", what.c_str(),
                       num(window).c_str(), num(delay).c_str())};
    roam::RecordConfig rc;
    rc.patch_log2 = int(exponent);
    rc.growth = std::sqrt(1.0 + delay + window);
    rc.last_i = info.width - 1, rc.last_j = info.height - 1;
    const std::int64_t P = std::int64_t{1} << exponent;
    rc.pad_i = ((rc.last_i + P - 1) / P) * P, rc.pad_j = ((rc.last_j + P - 1) / P) * P;
    rc.spacing_x = info.spacing_x, rc.spacing_z = info.spacing_z;
    // Around the holes as a terrain in memory makes them (records.h: the diamonds over a hole's
    // edge split to the finest level).
    if (holes) rc.hole_source = [holes] { return std::shared_ptr<const HoleMask>(holes); };
    std::vector<std::size_t> level_first;
    std::size_t total_pages = 0;
    for (std::uint32_t k = 0; k < grid.levels; ++k) {
      level_first.push_back(total_pages);
      total_pages += grid.count(k);
    }
    std::vector<std::shared_ptr<roam::RecordBlock>> blocks(total_pages);
    roam::build_all(
        rc, grid, h,
        [](const PageKey&) -> const world::Page* { return nullptr; },
        [&](const PageKey& key, std::shared_ptr<roam::RecordBlock> b) {
          blocks[level_first[key.level] + std::size_t(key.px) +
                 std::size_t(key.pz) * std::size_t(grid.px[key.level])] = std::move(b);
        },
        threads, false);
    rep.bounds_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - tb).count();
    rep.patch_exponent = exponent;
    rep.hole_cells = holes ? holes->cells() : 0;
    report(0.35, "pages");

    // ---- pages ------------------------------------------------------------------------------
    const auto tp = std::chrono::steady_clock::now();
    Output out(path);
    if (auto s = out.open(); !s) return Error{s.message()};
    {
      std::vector<std::uint8_t> zero(kDataStart, 0);
      if (auto s = out.write(zero.data(), zero.size()); !s) return Error{s.message()};
    }
    std::vector<PageEntry> entries(total_pages);
    std::vector<std::uint64_t> page_hashes(grid.count(0), 0);
    const bool mats = in.materials != nullptr;
    info.has_materials = mats;
    auto make_page = [&](std::size_t idx, CompressedPage& cp) {
      std::uint32_t k = 0;
      while (k + 1 < grid.levels && idx >= level_first[k + 1]) ++k;
      const std::size_t local = idx - level_first[k];
      const PageKey key{k, std::int32_t(local % std::size_t(grid.px[k])),
                        std::int32_t(local / std::size_t(grid.px[k]))};
      const int ls = world::level_shift(k);
      const std::int64_t i0 = std::int64_t(key.px) << world::page_shift(k);
      const std::int64_t j0 = std::int64_t(key.pz) << world::page_shift(k);
      auto sample = [&](std::int32_t a, std::int32_t b) {
        const std::int64_t i = std::clamp<std::int64_t>(i0 + (std::int64_t(a) << ls), 0, grid.last_i);
        const std::int64_t j = std::clamp<std::int64_t>(j0 + (std::int64_t(b) << ls), 0, grid.last_j);
        return std::size_t(i) + std::size_t(j) * info.width;
      };
      // The page's samples and the tile's buffers are kept per thread (allocations this size
      // would be fresh, zeroed pages from the system for every page).
      thread_local std::shared_ptr<world::PageSamples> keep;
      if (!keep || keep.use_count() != 1) keep = std::make_shared<world::PageSamples>();
      const std::shared_ptr<world::PageSamples>& s = keep;
      s->u16.clear(), s->f32.clear(), s->materials.clear();
      if (store_u16)
        s->u16.resize(kPageEntries);
      else
        s->f32.resize(kPageEntries);
      if (mats) s->materials.resize(kPageEntries);
      // A row of a finest page inside the data: one copy.
      const std::int64_t x0 = i0 - kPageApron, x1 = i0 + kPageCells + kPageApron;
      const bool rows = k == 0 && !mats && x0 >= 0 && x1 <= grid.last_i;
      for (std::int32_t b = -kPageApron; b <= kPageCells + kPageApron; ++b) {
        if (rows) {
          const std::size_t from = sample(-kPageApron, b), e = world::entry_index(-kPageApron, b);
          if (store_u16)
            std::memcpy(s->u16.data() + e, u16 + from, std::size_t(kPageStride) * 2);
          else
            std::memcpy(s->f32.data() + e, f32 + from, std::size_t(kPageStride) * 4);
          continue;
        }
        for (std::int32_t a = -kPageApron; a <= kPageCells + kPageApron; ++a) {
          const std::size_t at = sample(a, b), e = world::entry_index(a, b);
          if (store_u16)
            s->u16[e] = u16[at];
          else
            s->f32[e] = f32[at];
          if (mats) {
            // The stored cell at the entry: sample (i, j)'s id, clamped into the cells.
            const std::int64_t i = std::min<std::int64_t>(std::int64_t(at % info.width), info.width - 2);
            const std::int64_t j = std::min<std::int64_t>(std::int64_t(at / info.width), info.height - 2);
            s->materials[e] = in.materials[std::size_t(i) + std::size_t(j) * info.width];
          }
        }
      }
      world::Page page;
      page.key = key;
      page.set_samples(s, info.height_scale);
      if (k == 0) cp.hash = world::hash_page(page, grid, mats);
      // The tile (its 256 x 256 entries) with TIFF's predictor, and the ring around it.
      if (store_u16) {
        thread_local std::vector<std::uint16_t> tile, ring;
        tile.resize(kTileSamples);
        ring.clear();
        ring.reserve(kApronSamples);
        // Row by row: the tile's part of the row, the rest to the ring in entry order.
        const std::uint16_t* ev = s->u16.data();
        for (std::int32_t b = -kPageApron; b <= kPageCells + kPageApron; ++b) {
          const std::uint16_t* row = ev + world::entry_index(-kPageApron, b);
          if (b < 0 || b >= std::int32_t(kTile)) {
            ring.insert(ring.end(), row, row + kPageStride);
            continue;
          }
          ring.insert(ring.end(), row, row + kPageApron);
          std::memcpy(tile.data() + std::size_t(b) * kTile, row + kPageApron, kTile * 2);
          ring.insert(ring.end(), row + kPageApron + kTile, row + kPageStride);
        }
        encode_u16(tile);
        cp.tile = deflate({reinterpret_cast<const std::uint8_t*>(tile.data()), tile.size() * 2},
                          o.compression_level);
        cp.apron = deflate({reinterpret_cast<const std::uint8_t*>(ring.data()), ring.size() * 2},
                           o.compression_level);
      } else {
        thread_local std::vector<float> tile, ring;
        tile.resize(kTileSamples);
        ring.clear();
        ring.reserve(kApronSamples);
        for (std::int32_t b = -kPageApron; b <= kPageCells + kPageApron; ++b)
          for (std::int32_t a = -kPageApron; a <= kPageCells + kPageApron; ++a) {
            const float v = s->f32[world::entry_index(a, b)];
            if (a >= 0 && b >= 0 && a < std::int32_t(kTile) && b < std::int32_t(kTile))
              tile[std::size_t(a) + std::size_t(b) * kTile] = v;
            else
              ring.push_back(v);
          }
        const std::vector<std::uint8_t> planes = encode_f32(tile);
        cp.tile = deflate(planes, o.compression_level);
        cp.apron = deflate({reinterpret_cast<const std::uint8_t*>(ring.data()), ring.size() * 4},
                           o.compression_level);
      }
      // The TIFF's extra tiles past the last page column / row (readers of the TIFF see the whole
      // image; Ridgeline reads the same samples from the pages' aprons).
      {
        const std::uint32_t iw = std::uint32_t(((info.width - 1) >> ls) + 1);
        const std::uint32_t ih = std::uint32_t(((info.height - 1) >> ls) + 1);
        const bool more_x = (iw + kTile - 1) / kTile > std::uint32_t(grid.px[k]);
        const bool more_z = (ih + kTile - 1) / kTile > std::uint32_t(grid.pz[k]);
        const bool last_x = key.px == grid.px[k] - 1, last_z = key.pz == grid.pz[k] - 1;
        // A tile whose every row repeats entry (fa(b), fb(b)) of this page along the row.
        auto edge = [&](auto entry_of) {
          if (store_u16) {
            std::vector<std::uint16_t> t(kTileSamples);
            for (std::size_t b = 0; b < kTile; ++b)
              for (std::size_t a = 0; a < kTile; ++a)
                t[a + b * kTile] = s->u16[entry_of(std::int32_t(a), std::int32_t(b))];
            encode_u16(t);
            return deflate({reinterpret_cast<const std::uint8_t*>(t.data()), t.size() * 2},
                           o.compression_level);
          }
          std::vector<float> t(kTileSamples);
          for (std::size_t b = 0; b < kTile; ++b)
            for (std::size_t a = 0; a < kTile; ++a)
              t[a + b * kTile] = s->f32[entry_of(std::int32_t(a), std::int32_t(b))];
          return deflate(encode_f32(t), o.compression_level);
        };
        const std::int32_t E = kPageCells;
        if (more_x && last_x)
          cp.edge_x = edge([&](std::int32_t, std::int32_t b) { return world::entry_index(E, b); });
        if (more_z && last_z)
          cp.edge_z = edge([&](std::int32_t a, std::int32_t) { return world::entry_index(a, E); });
        if (more_x && more_z && last_x && last_z)
          cp.edge_xz = edge([&](std::int32_t, std::int32_t) { return world::entry_index(E, E); });
      }
      if (mats) cp.materials = deflate(s->materials, o.compression_level);
      if (blocks[idx]) {
        const std::vector<std::uint8_t> raw = blocks[idx]->encode();
        const std::uint32_t raw_size = std::uint32_t(raw.size());
        std::vector<std::uint8_t> z = deflate(raw, o.compression_level);
        cp.records.resize(4 + z.size());
        std::memcpy(cp.records.data(), &raw_size, 4);
        std::memcpy(cp.records.data() + 4, z.data(), z.size());
        blocks[idx].reset();  // written: memory back
      }
    };
    // Offsets and sizes of the TIFF-only edge tiles, by the page they follow.
    EdgeTiles edge_x, edge_z, edge_xz;
    // `threads` workers make the pages (cut, compressed, joined and checksummed) at most
    // `ahead` pages ahead of this thread, which writes them in order as they come.
    {
      const std::size_t ahead = std::max<std::size_t>(std::size_t(threads) * 4, 8);
      std::vector<CompressedPage> ring(ahead);
      std::vector<std::uint8_t> ready(ahead, 0);
      std::mutex mu;
      std::condition_variable made, freed;
      std::size_t next = 0, written = 0;
      bool stop = false;
      std::vector<std::thread> workers;
      // Stops and joins the workers however this block is left (an error, a cancellation).
      struct Join {
        std::vector<std::thread>& w;
        std::mutex& mu;
        bool& stop;
        std::condition_variable& freed;
        ~Join() {
          {
            std::lock_guard lock(mu);
            stop = true;
          }
          freed.notify_all();
          for (auto& t : w) t.join();
        }
      } join{workers, mu, stop, freed};
      for (unsigned t = 0; t < std::max(1u, threads); ++t)
        workers.emplace_back([&] {
          for (;;) {
            std::size_t k;
            {
              std::unique_lock lock(mu);
              freed.wait(lock, [&] { return stop || next >= total_pages || next < written + ahead; });
              if (stop || next >= total_pages) return;
              k = next++;
            }
            CompressedPage cp;
            make_page(k, cp);
            cp.all.reserve(cp.tile.size() + cp.apron.size() + cp.materials.size() + cp.records.size());
            for (auto* part : {&cp.tile, &cp.apron, &cp.materials, &cp.records}) {
              cp.all.insert(cp.all.end(), part->begin(), part->end());
              cp.sizes.push_back(std::uint32_t(part->size()));
              std::vector<std::uint8_t>().swap(*part);
            }
            cp.checksum = checksum(cp.all.data(), cp.all.size());
            {
              std::lock_guard lock(mu);
              ring[k % ahead] = std::move(cp);
              ready[k % ahead] = 1;
            }
            made.notify_all();
          }
        });
      for (std::size_t k = 0; k < total_pages; ++k) {
        CompressedPage cp;
        {
          std::unique_lock lock(mu);
          made.wait(lock, [&] { return ready[k % ahead] != 0; });
          cp = std::move(ring[k % ahead]);
          ready[k % ahead] = 0;
          written = k + 1;
        }
        freed.notify_all();
        PageEntry& e = entries[k];
        e.offset = out.size();
        e.tile = cp.sizes[0], e.apron = cp.sizes[1], e.materials = cp.sizes[2], e.records = cp.sizes[3];
        e.checksum = cp.checksum;
        if (auto s = out.write(cp.all.data(), cp.all.size()); !s) return Error{s.message()};
        // The TIFF-only edge tiles, after the page's bytes (outside its checksum and the index).
        for (auto [part, sink] : {std::pair{&cp.edge_x, &edge_x}, std::pair{&cp.edge_z, &edge_z},
                                  std::pair{&cp.edge_xz, &edge_xz}}) {
          if (part->empty()) continue;
          (*sink)[k] = {out.size(), part->size()};
          if (auto s = out.write(part->data(), part->size()); !s) return Error{s.message()};
        }
        if (k < grid.count(0)) page_hashes[k] = cp.hash;
        if ((k + 1) % ahead == 0 || k + 1 == total_pages)
          report(0.35 + 0.6 * double(k + 1) / double(total_pages), "pages");
      }
    }
    rep.pages_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - tp).count();
    info.content_hash = world::combine_hashes(world::hash_header(info), page_hashes);
    rep.content_hash = info.content_hash;
    rep.pages = total_pages;
    report(0.95, "index");

    if (auto st = write_file_end(out, {info, store_u16, mats, exponent, window, delay, grid,
                                       level_first, summaries, entries, hole_runs, edge_x, edge_z,
                                       edge_xz});
        !st)
      return Error{st.message()};
    rep.bytes = out.size();
    if (auto s = out.commit(); !s) return Error{s.message()};
    report(1.0, "done");
  } catch (const Cancelled&) {
    return Error{what + ": cancelled; nothing was written"};
  } catch (const std::bad_alloc&) {
    return Error{what + ": out of memory (the bake holds the samples and about 1.6 bytes a "
                        "sample besides; bake a smaller world or use a larger machine)"};
  }
  rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return rep;
}

Result<BakeReport> bake_world(const Heightfield& hf, const std::string& path,
                              const BakeOptions& options) {
  BakeSamples s;
  s.info.width = hf.width(), s.info.height = hf.height();
  s.info.spacing_x = hf.spacing_x(), s.info.spacing_z = hf.spacing_z();
  s.info.origin_x = hf.origin_x(), s.info.origin_z = hf.origin_z();
  s.info.height_offset = hf.height_offset(), s.info.height_scale = hf.height_scale();
  s.info.filled_samples = hf.filled_samples();
  s.info.name = path;
  std::vector<std::uint16_t> values;
  if (world::fits_u16(hf)) {
    s.info.format = SampleFormat::kU16;
    values.resize(hf.local_heights().size());
    for (std::size_t k = 0; k < values.size(); ++k)
      values[k] =
          std::uint16_t(std::nearbyint(double(hf.local_heights()[k]) / hf.height_scale()));
    s.u16 = values.data();
  } else {
    s.info.format = SampleFormat::kF32;
    s.f32 = hf.local_heights().data();
  }
  s.hole_cells = hf.hole_cells();
  std::vector<std::uint8_t> mats;
  if (hf.has_materials()) {
    mats.resize(std::size_t(hf.width()) * hf.height());
    for (std::uint32_t j = 0; j < hf.height(); ++j)
      for (std::uint32_t i = 0; i < hf.width(); ++i)
        mats[i + std::size_t(j) * hf.width()] =
            hf.material(std::min(i, hf.width() - 2), std::min(j, hf.height() - 2));
    s.materials = mats.data();
  }
  return bake_world(s, path, options);
}

}  // namespace ridgeline::io
