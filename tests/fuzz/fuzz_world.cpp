// Fuzz target: the baked world reader (io::open_world, docs/worlds.md "The world file") and
// everything that reads its pages: Terrain::open under a 4 MiB cache with loads on this thread,
// heights over the whole footprint and past it, rays across it, the triangles of a box, and a
// view converged over it (the coarse levels' baked bounds). The input is written to a file (the
// reader takes a path). A refused file must be refused at open with a message; a damaged page
// is found when it loads and reads as "no data"; the terrain's invariants must hold whatever the
// file holds. Seeds: small worlds made by `ridge bake` (16-bit and float).
//
// Every part of a world file is checksummed, so a mutated byte almost always stops at "checksum
// mismatch". Two inputs in three (by size) get their checksums recomputed before the file is
// written (every page's, the index's, the locator's: fix_checksums()), so that mutations reach
// the index and page decoding; the others are written as they are.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "ridgeline/camera.h"
#include "ridgeline/landscape.h"
#include "ridgeline/roam_view.h"
#include "ridgeline/terrain.h"
#include "ridgeline/world_file.h"
#include "io/world_format.h"
#include "world/page.h"

namespace {

template <class T>
T get(const std::string& b, std::size_t at) {
  T v{};
  std::memcpy(&v, b.data() + at, sizeof v);
  return v;
}
template <class T>
void put(std::string& b, std::size_t at, T v) {
  std::memcpy(b.data() + at, &v, sizeof v);
}

// Recomputes the checksums the reader checks, where the layout can be followed: each page's (in
// its entry: offset, four part sizes, checksum), each chunk of entries' (version 5: the chunks
// lie before the index, their offsets in the index after the summaries; versions 3 and 4: the
// entries lie in the index after the summaries), then the index's and the locator's
// (world_format.h).
void fix_checksums(std::string& b) {
  namespace wf = ridgeline::io::world_file;
  const std::size_t loc = wf::kLocatorAt;
  if (b.size() < wf::kDataStart || std::memcmp(b.data() + loc, wf::kMagic, 8) != 0) return;
  const auto version = get<std::uint32_t>(b, loc + 8);
  const auto index_at = get<std::uint64_t>(b, loc + 16), index_bytes = get<std::uint64_t>(b, loc + 24);
  if (index_at > b.size() || index_bytes > b.size() - index_at || index_bytes < 16) return;
  auto fix_entry = [&](std::size_t e) {  // the page checksum of the entry at byte e
    const auto off = get<std::uint64_t>(b, e);
    const std::uint64_t n = std::uint64_t(get<std::uint32_t>(b, e + 8)) +
                            get<std::uint32_t>(b, e + 12) + get<std::uint32_t>(b, e + 16) +
                            get<std::uint32_t>(b, e + 20);
    if (off <= b.size() && n <= b.size() - off)
      put(b, e + 24, wf::checksum(b.data() + off, std::size_t(n)));
  };
  const auto width = get<std::uint32_t>(b, index_at + 8), height = get<std::uint32_t>(b, index_at + 12);
  // The header's fixed part (world_writer.cpp): magic, size, six doubles, format, range,
  // materials, filled, hash; then the name, the baked settings, the levels.
  std::size_t at = index_at + 8 + 8 + 48 + 1 + 8 + 1 + 8 + 8;
  const std::size_t end = index_at + index_bytes;
  if (width >= 2 && height >= 2 && width <= (1u << 20) && height <= (1u << 20) && at + 4 <= end) {
    at += 4 + std::size_t(get<std::uint32_t>(b, at));
    at += 4 + 8 + 8;
    const auto grid = ridgeline::world::PageGrid::of(width, height);
    std::size_t pages = 0;
    for (std::uint32_t k = 0; k < grid.levels; ++k) pages += grid.count(k);
    at += 4 + 8 * std::size_t(grid.levels) + 16 * grid.count(0);  // levels, summaries
    if (version >= 5) {
      const std::size_t chunks = (pages + wf::kChunkEntries - 1) / wf::kChunkEntries;
      for (std::size_t c = 0; c < chunks && at + 16 * (c + 1) <= end; ++c) {
        const auto chunk_at = get<std::uint64_t>(b, at + 16 * c);
        const std::size_t n = wf::kEntryBytes * std::min(wf::kChunkEntries, pages - c * wf::kChunkEntries);
        if (chunk_at > b.size() || n > b.size() - chunk_at) continue;
        for (std::size_t e = chunk_at; e < chunk_at + n; e += wf::kEntryBytes) fix_entry(e);
        put(b, at + 16 * c + 8, wf::checksum(b.data() + chunk_at, n));
      }
    } else if (at <= end && pages * wf::kEntryBytes <= end - at) {
      for (std::size_t e = at; e < at + pages * wf::kEntryBytes; e += wf::kEntryBytes) fix_entry(e);
    }
  }
  put(b, loc + 32, wf::checksum(b.data() + index_at, std::size_t(index_bytes)));
  put(b, loc + 48, wf::checksum(b.data() + loc, 48));
}

const std::string& scratch_path() {
  static const std::string path = "/tmp/ridgeline_fuzz_world_" + std::to_string(::getpid()) + ".tif";
  return path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace ridgeline;
  const std::string& path = scratch_path();
  std::string bytes(reinterpret_cast<const char*>(data), size);
  if (size % 3 != 0) fix_checksums(bytes);
  if (std::FILE* f = std::fopen(path.c_str(), "wb")) {
    const bool written = std::fwrite(bytes.data(), 1, size, f) == size;
    if (std::fclose(f) != 0 || !written) return 0;
  } else {
    return 0;
  }
  auto source = io::open_world(path);
  if (!source) {
    if (source.error().message.empty()) __builtin_trap();  // a refusal names its cause
    return 0;
  }
  WorldCacheDesc cache;
  cache.budget_bytes = std::size_t{4} << 20;
  cache.worker_threads = 0;
  auto opened = Terrain::open(*source, cache);
  if (!opened) return 0;
  const std::shared_ptr<Terrain>& t = *opened;
  const WorldInfo& w = t->info();
  for (int j = -1; j <= 9; ++j)
    for (int i = -1; i <= 9; ++i) {
      const auto h = t->height(w.origin_x + w.extent_x() * i / 8.0, w.origin_z + w.extent_z() * j / 8.0);
      if (h && !std::isfinite(*h)) __builtin_trap();
    }
  const glm::dvec3 o(w.origin_x - 1.0, w.height_offset + w.max_local + 5.0, w.origin_z - 1.0);
  (void)t->raycast(o, glm::dvec3(w.extent_x(), -(w.max_local - w.min_local) - 10.0, w.extent_z()),
                   INFINITY);
  std::vector<SurfaceTriangle> tris;
  (void)t->triangles_in_box(
      Box{{w.origin_x, -1e9, w.origin_z},
          {w.origin_x + 0.3 * w.extent_x(), 1e9, w.origin_z + 0.3 * w.extent_z()}},
      tris, 4096);
  if (auto land = Landscape::create(t)) {
    RoamSettings s;
    s.threshold = 4;
    if (auto view = RoamView::create(*land, s)) {
      Camera cam;
      cam.eye = {w.origin_x + 0.5 * w.extent_x(), w.height_offset + w.max_local + 20.0,
                 w.origin_z - 0.2 * w.extent_z()};
      cam.target = {w.origin_x + 0.5 * w.extent_x(), w.height_offset, w.origin_z + 0.5 * w.extent_z()};
      (void)(*view)->converge(cam);
      if (const std::string m = (*view)->check_invariants(); !m.empty()) {
        std::fprintf(stderr, "view invariant: %s\n", m.c_str());
        __builtin_trap();
      }
    }
  }
  if (const std::string m = t->check_invariants(); !m.empty()) {
    std::fprintf(stderr, "terrain invariant: %s\n", m.c_str());
    __builtin_trap();
  }
  return 0;
}
