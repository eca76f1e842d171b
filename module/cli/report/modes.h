// The modes `ridge report` runs along a camera path (docs/report_method.md, "Modes"): ROAM coherent and
// rebuild, the uniform grid, the CDLOD-like quadtree and the SOAR refinement, each a technique of
// Ridgeline::bench run by its frame loop over a scene's lattice.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "report/stats.h"
#include "ridgeline/bench/meshes.h"
#include "ridgeline/bench/paths.h"
#include "ridgeline/bench/soar.h"
#include "ridgeline/landscape.h"
#include "ridgeline/mesh_error.h"
#include "ridgeline/terrain.h"

namespace ridgeline::report {

using bench::Cdlod;
using bench::NamedPath;
using bench::Run;
using bench::Soar;

/// The comparators' median triangle count is matched to ROAM's within this fraction.
inline constexpr double kMatchTolerance = 0.10;

/// A scene of the report: a terrain, its landscape, and what the comparators build from it once.
struct Scene {
  std::string name, source;
  std::shared_ptr<const Terrain> terrain;
  std::shared_ptr<const Landscape> landscape;
  std::vector<std::string> messages;  ///< the loader's messages, as a user would see them
  Json loader = Json::object();
  /// Procedural detail: the full-detail surface baked into a heightfield of the finest lattice
  /// (what the comparators draw from and the error is measured against), and a fresh terrain
  /// with a cold tile cache and its landscape for every ROAM run.
  std::shared_ptr<const Heightfield> fine;
  std::function<
      Result<std::pair<std::shared_ptr<const Terrain>, std::shared_ptr<const Landscape>>>()>
      fresh;
  Json detail = nullptr;

  /// The lattice everything is measured on: the finest one (the stored samples without detail),
  /// as a heightfield, made on first use.
  const Heightfield& lattice();
  /// The comparators and the measurement over lattice(), built on first use.
  const Cdlod& cdlod(std::uint32_t grid);
  const Soar& soar();
  const MeshErrorMeter& meter(std::uint32_t stride);

 private:
  std::map<std::uint32_t, std::unique_ptr<Cdlod>> cdlod_;  // by chunk grid
  std::unique_ptr<Soar> soar_;
  std::unique_ptr<MeshErrorMeter> meter_;
};

/// ROAM (coherent or rebuild) on `scene` at `setting`, converged for the first frame first.
Result<Run> run_roam(Scene& scene, const NamedPath& path, const Setting& setting, RoamMode mode,
                     const Options& o);
/// The static uniform grid closest to `target` triangles.
Result<Run> run_uniform(Scene& scene, const NamedPath& path, double target, const Options& o);

/// The CDLOD chunk grid and range that match `target` triangles over a path.
struct CdlodChoice {
  std::uint32_t grid = 32;
  double r0 = 0, median = 0;
};
CdlodChoice calibrate_cdlod(Scene& scene, const NamedPath& path, double target);
/// CDLOD at the range matching `target` triangles (geomorphed and not).
Result<Run> run_cdlod(Scene& scene, const NamedPath& path, double target, const Options& o);
/// SOAR at `setting`: a threshold in pixels as kappa = projection_scale / threshold per frame; a
/// triangle cap as the one kappa whose median count over the path matches it; a time budget at
/// its 1 px threshold (SOAR has no budget).
Result<Run> run_soar(Scene& scene, const NamedPath& path, const Setting& setting,
                     const Options& o);

/// ROAM's loop options for a setting: a rebuild from the roots without a tile cache is updated
/// only on the frames the measurement reads (its mesh depends on the current camera alone).
bench::LoopOptions roam_loop(const Options& o, RoamMode mode, bool detail_cache);
/// ROAM's time-budget fields for a "time_ms" setting (none otherwise), into run.summary.
void add_time_budget(Run& run, const Setting& setting);

}  // namespace ridgeline::report
