// `ridge bench lod --mode soar`: the stateless SOAR comparator along a camera path, with the same
// JSON fields as the ROAM modes so that their figures compare like for like (docs/cli.md).
#pragma once

#include <string>

#include "terrain_args.h"

namespace ridgeline::cli {

/// The flags of `ridge bench lod` that the SOAR mode reads (strings as given; validated here).
struct SoarBenchArgs {
  const TerrainArgs* terrain = nullptr;
  std::string path, threshold, triangles, budget_ms, error_every, error_stride, warmup, repeat,
      json_path;
};

/// Runs it; returns the exit code (errors go to stderr naming the flag).
int run_bench_lod_soar(const SoarBenchArgs& a);

}  // namespace ridgeline::cli
