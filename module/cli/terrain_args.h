// The common terrain flags of every `ridge` subcommand (docs/cli.md, "Terrain flags"), defined
// once so that every subcommand (info, query, profile, bench, mesh, ...) reads its terrain the
// same way.
#pragma once

#include <CLI/CLI.hpp>
#include <memory>
#include <string>
#include <vector>

#include "ridgeline/detail.h"
#include "ridgeline/heightfield.h"
#include "ridgeline/io.h"
#include "ridgeline/result.h"
#include "ridgeline/terrain.h"

namespace ridgeline::cli {

/// Holds the values of the terrain flags after parsing. Add the flags to a subcommand with
/// add_to(), parse, then call load_heightfield() or load_terrain(), which validate every value
/// (finite numbers, positive spacing and scale, one terrain source) and name the bad flag.
class TerrainArgs {
 public:
  /// Adds --heightmap (repeatable: a world of several files, with --layout and --unshared-edges),
  /// --world (a baked world, with --cache-mb and --cache-workers), --default-terrain, --raw-size,
  /// --raw-type, --spacing, --height-scale,
  /// --height-offset, --origin, --nodata, --fill, --max-samples, --channel, --materials, --load and
  /// --default-size and the detail flags (--detail-levels, --detail-seed, --detail-amplitude,
  /// --detail-gain, --detail-flat-shape, --detail-steep-shape, --detail-flat-slope,
  /// --detail-steep-slope, --detail-blur-radius, --detail-budget-mb) to
  /// `app`, in an option group "Terrain". The object must outlive the parse. Sets the app's
  /// parse_complete_callback: a missing terrain source (none of --heightmap, --world and
  /// --default-terrain) is a usage error (CLI::RequiredError, exit 2).
  void add_to(CLI::App& app);

  /// The heightfield the flags describe: loaded from --heightmap (one file, or several joined by
  /// --layout or their georeferencing) or generated (--default-terrain), placed by the placement
  /// flags; without --spacing (--origin) a GeoTIFF's own placement is used. `report`, when
  /// given, receives what the loader found (pixel type, file placement, warnings). Refused for
  /// --world (a baked world is not held as one heightfield).
  Result<Heightfield> load_heightfield(io::LoadReport* report = nullptr) const;
  /// The terrain the flags describe: load_heightfield() in memory, or the baked world of --world
  /// paged in (Terrain::open), with the edit state of --load STATE.bin applied when given.
  Result<std::shared_ptr<Terrain>> load_terrain(io::LoadReport* report = nullptr) const;
  /// True when the terrain is a baked world (--world).
  bool world() const { return given("--world"); }

  /// The DetailParams of the detail flags (levels 0 without --detail-levels), validated; the
  /// other detail flags without --detail-levels N >= 1 are refused.
  Result<DetailParams> detail_params() const;

  /// "default terrain" or the heightmap path: for reports.
  std::string source() const;
  /// True when `flag` (e.g. "--detail-budget-mb") was given.
  bool given(const char* flag) const;

 private:
  Result<HeightfieldDesc> placement() const;
  Result<Heightfield> load_heightfield_uncapped(io::LoadReport* report) const;

  std::vector<std::string> heightmaps_;
  std::string world_, layout_, cache_mb_, cache_workers_;
  bool unshared_edges_ = false;
  bool default_terrain_ = false;
  bool alpha_nodata_ = false;
  std::string raw_size_, raw_type_, spacing_, height_scale_, height_offset_, origin_, nodata_,
      fill_, max_samples_, channel_, materials_, load_, default_size_;
  // Procedural detail (docs/detail.md): --detail-levels N --detail-seed S and the shape flags.
  std::string detail_levels_, detail_seed_, detail_amplitude_, detail_gain_, detail_budget_mb_,
      detail_flat_shape_, detail_steep_shape_, detail_flat_slope_, detail_steep_slope_,
      detail_blur_radius_;
  CLI::App* app_ = nullptr;
};

}  // namespace ridgeline::cli
