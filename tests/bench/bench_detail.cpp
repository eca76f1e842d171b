// Detail tile generation speed (docs/detail.md, "Speed"): one 129 x 129 tile from its parent on
// one core, and the direct evaluator per sample. Prints JSON; medians over repetitions.
//   bench_detail [repetitions]
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "ridgeline/bench/clock.h"
#include "ridgeline/bench/stats.h"
#include "ridgeline/detail.h"
#include "ridgeline/terrain.h"

using namespace ridgeline;
using bench::Clock;
using bench::median;
using bench::ms_since;

int main(int argc, char** argv) {
  const int reps = argc > 1 ? std::max(3, std::atoi(argv[1])) : 31;
  auto hf = make_default_heightfield();
  if (!hf) return 1;
  auto terrain = Terrain::create(std::move(hf).value()).value();
  DetailParams params;
  params.levels = 12;
  auto field = DetailField::create(terrain->surface().to_heightfield().value(), params);
  if (!field) {
    std::fprintf(stderr, "%s\n", field.error().message.c_str());
    return 1;
  }
  const DetailField& f = **field;
  std::printf("{\n  \"terrain\": \"default\",\n  \"levels\": %u,\n  \"tiles\": [\n", f.levels());
  volatile std::int32_t sink = 0;
  const std::uint32_t shown[] = {1, 4, 8, 12};
  for (std::uint32_t level : shown) {
    // A tile over the middle of the default terrain.
    const DetailTileKey key{level, 4 << (level - 1), 4 << (level - 1)};
    const auto parent = level > 1 ? f.make_tile_chain(key.parent()) : nullptr;
    std::vector<double> ms;
    std::size_t bytes = 0;
    for (int r = 0; r < reps; ++r) {
      constexpr int kBatch = 20;
      const auto t0 = Clock::now();
      for (int b = 0; b < kBatch; ++b) {
        const auto tile = f.make_tile(key, parent.get());
        sink = sink + tile->raw(64, 64);
        bytes = tile->memory_bytes();
      }
      ms.push_back(ms_since(t0) / kBatch);
    }
    std::printf("    {\"level\": %u, \"median_ms\": %.4f, \"min_ms\": %.4f, \"bytes\": %zu}%s\n",
                level, median(ms), *std::min_element(ms.begin(), ms.end()), bytes,
                level == shown[3] ? "" : ",");
  }
  std::printf("  ],\n  \"direct\": [\n");
  for (std::uint32_t level : shown) {
    std::vector<double> us;
    for (int r = 0; r < reps; ++r) {
      constexpr int kPoints = 2000;
      const auto t0 = Clock::now();
      for (int k = 0; k < kPoints; ++k)
        sink = sink + f.detail_raw(level, (std::int64_t{300} << level) + k * 37,
                                   (std::int64_t{500} << level) + k * 13);
      us.push_back(ms_since(t0) * 1e3 / kPoints);
    }
    std::printf("    {\"level\": %u, \"median_us_per_sample\": %.3f}%s\n", level, median(us),
                level == shown[3] ? "" : ",");
  }
  std::printf("  ]\n}\n");
  return 0;
}
