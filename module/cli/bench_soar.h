// `ridge bench lod --mode soar`: the stateless SOAR comparator along a camera path, with the same
// JSON fields as the ROAM modes so that their figures compare like for like (docs/cli.md).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "ridgeline/camera_path.h"
#include "terrain_args.h"

namespace ridgeline::cli {

/// What the SOAR mode of `ridge bench lod` reads: the path and counts bench lod parsed already,
/// the LOD flags as given (validated here).
struct SoarBenchArgs {
  const TerrainArgs* terrain = nullptr;
  const std::vector<io::PathFrame>* frames = nullptr;
  std::string threshold, triangles, budget_ms;
  std::uint64_t error_every = 1, error_stride = 1, warmup = 0, repeat = 1;
  double flush_mb = 0;  ///< --flush-mb: other memory touched before each refinement
  std::string json_path;
};

/// Runs it; returns the exit code (errors go to stderr naming the flag).
int run_bench_lod_soar(const SoarBenchArgs& a);

}  // namespace ridgeline::cli
