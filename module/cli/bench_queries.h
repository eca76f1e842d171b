// `ridge bench queries`: query speed on a terrain (owned by the queries work).
#pragma once

#include <cstddef>
#include <cstdint>

#include <nlohmann/json.hpp>

#include "ridgeline/terrain.h"

namespace ridgeline::cli {

struct BenchQueriesOptions {
  std::size_t points = 1000000;  ///< random points (and rays) per repetition
  int repetitions = 5;           ///< medians are taken over repetitions
  std::uint64_t seed = 1;
};

/// Measures ns per height query (one call per point, and batched: one Terrain::heights call for
/// all points), per height+normal, per vertical ray and per slanted ray crossing 256 cells (see
/// docs/benchmarks.md for the definitions) and returns {"height_ns":..,"batched_height_ns":..,
/// "height_normal_ns":..,"vertical_ray_ns":..,"slanted_ray_ns":..,
///  "bytes_per_sample":.., "points":.., "repetitions":.., ...} with medians.
nlohmann::json bench_queries(const Terrain& terrain, const BenchQueriesOptions& options);

}  // namespace ridgeline::cli
