// The modes `ridge report` runs along a camera path, and the one measurement loop they share
// (docs/report.md, "Modes" and "What is measured"): ROAM coherent and rebuild, the uniform grid,
// the CDLOD-like quadtree and the SOAR refinement.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "report/meshes.h"
#include "report/paths.h"
#include "report/soar.h"
#include "report/stats.h"
#include "ridgeline/landscape.h"
#include "ridgeline/mesh_error.h"
#include "ridgeline/terrain.h"

namespace ridgeline::report {

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

/// The finest lattice of `terrain` (base + detail + edits, Surface::vertex_height) baked into a
/// heightfield (spacing / 2^L): what the comparators draw from.
Result<Heightfield> finest_lattice(const Terrain& terrain);

/// A mode's mesh as captured after one frame's update, drawable later for any camera (geomorphed
/// or not): the pop compares the previous frame's mesh and the current one drawn for the
/// current camera.
using Drawable = std::function<DrawnMesh(const Camera& camera, bool morph)>;

/// Runs one mode along `frames`: `update(k)` does frame k's work and records its cost into `r`;
/// `capture()` returns the mesh as it stands. On the frames measured_frame() names, the loop
/// measures with `meter`: the error of the mesh (and of the morphed mesh with r.has_morph), the
/// per-vertex jump and the pop (docs/report.md). `after_update(k)`, if set, runs before the
/// measurement of frame k (the storm refreshes the meter's surface there).
void run_mode(const MeshErrorMeter& meter, const std::vector<Camera>& frames, const Options& o,
              const std::function<void(std::size_t)>& update,
              const std::function<Drawable()>& capture, ModeResult& r);

/// ROAM (coherent or rebuild) on `scene` at `setting`, converged for the first frame first.
Result<ModeResult> run_roam(Scene& scene, const NamedPath& path, const Setting& setting,
                            RoamMode mode, const Options& o);
/// The static uniform grid closest to `target` triangles.
ModeResult run_uniform(Scene& scene, const NamedPath& path, double target, const Options& o);

/// The CDLOD chunk grid and range that match `target` triangles over a path.
struct CdlodChoice {
  std::uint32_t grid = 32;
  double r0 = 0, median = 0;
};
CdlodChoice calibrate_cdlod(Scene& scene, const NamedPath& path, double target);
/// CDLOD at the range matching `target` triangles (geomorphed and not).
ModeResult run_cdlod(Scene& scene, const NamedPath& path, double target, const Options& o);
/// SOAR at `setting`: a threshold in pixels as kappa = projection_scale / threshold per frame; a
/// triangle cap as the one kappa whose median count over the path matches it; a time budget at
/// its 1 px threshold (SOAR has no budget).
ModeResult run_soar(Scene& scene, const NamedPath& path, const Setting& setting, const Options& o);

/// Thread CPU milliseconds and wall milliseconds of `work()`.
struct Timing {
  double wall_ms = 0, cpu_ms = 0;
};
Timing timed(const std::function<void()>& work);

}  // namespace ridgeline::report
