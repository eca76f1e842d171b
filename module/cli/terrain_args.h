// The common terrain flags of every `ridge` subcommand (SPEC.md, "The `ridge` tool's common
// flags"), defined once so that every subcommand (info, query, profile, bench, mesh, ...) reads
// its terrain the same way.
#pragma once

#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "ridgeline/heightfield.h"
#include "ridgeline/result.h"
#include "ridgeline/terrain.h"

namespace ridgeline::cli {

/// Holds the values of the terrain flags after parsing. Add the flags to a subcommand with
/// add_to(), parse, then call load_heightfield() or load_terrain(), which validate every value
/// (finite numbers, positive spacing and scale, one terrain source) and name the bad flag.
class TerrainArgs {
 public:
  /// Adds --heightmap, --default-terrain, --raw-size, --raw-type, --spacing, --height-scale,
  /// --height-offset, --origin, --nodata, --fill, --max-samples, --channel, --materials, --load and
  /// the detail flags (--detail-levels, --detail-seed, --detail-amplitude, --detail-gain,
  /// --detail-budget-mb) to
  /// `app`, in an option group "Terrain". The object must outlive the parse.
  void add_to(CLI::App& app);

  /// The heightfield the flags describe: loaded from --heightmap or generated (--default-terrain),
  /// placed by the placement flags.
  Result<Heightfield> load_heightfield() const;
  /// load_heightfield() wrapped into a Terrain (builds the query structures), with the edit
  /// state of --load STATE.bin applied when given.
  Result<std::shared_ptr<Terrain>> load_terrain() const;

  /// "default terrain" or the heightmap path: for reports.
  std::string source() const;

 private:
  Result<HeightfieldDesc> placement() const;
  bool given(const char* flag) const;

  std::string heightmap_;
  bool default_terrain_ = false;
  std::string raw_size_, raw_type_, spacing_, height_scale_, height_offset_, origin_, nodata_,
      fill_, max_samples_, channel_, materials_, load_;
  // Procedural detail (docs/detail.md): --detail-levels N --detail-seed S and the shape flags.
  std::string detail_levels_, detail_seed_, detail_amplitude_, detail_gain_, detail_budget_mb_;
  CLI::App* app_ = nullptr;
};

}  // namespace ridgeline::cli
