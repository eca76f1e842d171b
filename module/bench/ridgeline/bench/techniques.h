// The techniques the frame loop runs (technique.h): ROAM (a RoamView, coherent or rebuilt from
// the roots every update), the stateless SOAR refinement, the CDLOD-like quadtree and the static
// uniform grid. Every one reports the same figures, so `ridge bench lod`, `ridge report`,
// bench_roam_core and game_pop compare them like for like (docs/benchmarks.md, docs/report.md).
//
// Ownership: a technique keeps references to what it is built over (a view's landscape, a Soar,
// a Cdlod, a Grid's heightfield or terrain), which must outlive it. Threading: one thread at a
// time.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "ridgeline/bench/meshes.h"
#include "ridgeline/bench/soar.h"
#include "ridgeline/bench/technique.h"
#include "ridgeline/roam_view.h"

namespace ridgeline::bench {

/// ROAM: one RoamView updated every frame (RoamSettings::mode: coherent or rebuild). The update
/// is timed apart from its output (take_dirty_patches(): the ranges an engine re-uploads). On a
/// terrain with a detail tile cache, the cache's once-per-frame update runs before each update
/// (untimed by the loop; its own time is in the summary as cache_update_ms_median), and the
/// figures add pending splits, resident tiles and detail memory.
class RoamTechnique final : public Technique {
 public:
  /// `converge_first`: start() converges the view for the first camera (with a detail cache:
  /// repeatedly, until no split waits for a tile), the state a game has after loading.
  explicit RoamTechnique(std::unique_ptr<RoamView> view, bool converge_first = false);

  RoamView& view() noexcept { return *view_; }

  std::string name() const override;
  Status start(const Camera& first) override;
  void before_update() override;
  Status update(const Camera& camera) override;
  bool has_output() const override { return true; }
  void output() override;
  FrameFigures figures() const override;
  /// The patch meshes as a renderer draws them (report's RoamSnapshot), geomorphs included.
  Drawable capture(const MeshErrorMeter& meter) override;
  Json summary() const override;
  /// A pixel threshold above 0 (a triangle cap alone has no geomorph factors).
  bool geomorphs() const override;
  bool view_independent() const override;

 private:
  std::unique_ptr<RoamView> view_;
  DetailCache* cache_ = nullptr;
  double field_bytes_ = 0;
  bool converge_first_ = false;
  RoamStats last_;
  std::size_t dirty_ = 0;
  std::uint64_t time_stops_ = 0, rebuilds_ = 0, compactions_ = 0;
  std::vector<double> cache_ms_;
};

/// SOAR: one refinement with the emission of its whole strip per frame (the timed update), with
/// kappa = min(Soar::kappa_for(camera, threshold_px), path_kappa): a pixel threshold, a kappa
/// fixed for the whole path (a triangle target: Soar::match), or both. On measured frames its
/// diagnostics run the refinement again without emission (refine_only_ms).
class SoarTechnique final : public Technique {
 public:
  /// `threshold_px` 0: no pixel threshold; `path_kappa` +infinity: none (not both).
  SoarTechnique(const Soar& soar, double threshold_px, double path_kappa);

  std::string name() const override { return "soar"; }
  Status update(const Camera& camera) override;
  FrameFigures figures() const override;
  Drawable capture(const MeshErrorMeter& meter) override;
  Json diagnose(const Camera& camera) override;
  Json summary() const override;

 private:
  double kappa_of(const Camera& camera) const;

  const Soar& soar_;
  double threshold_px_ = 0, path_kappa_ = 0, kappa_ = 0;
  Soar::Frame last_;
  std::vector<std::uint32_t> strip_;
  std::vector<double> refine_only_ms_;
};

/// The CDLOD-like quadtree at range r0 (Cdlod::match picks it for a triangle target): the
/// timed update is the chunk selection (its morph runs in a vertex shader and is not timed).
/// Changes are the quadrants that enter or leave the selection. Over a terrain that changes (the
/// storm) it owns its quadtree and refreshes the min/max nodes over each change in the update.
class CdlodTechnique final : public Technique {
 public:
  /// Over a shared quadtree (no terrain_changed()).
  CdlodTechnique(const Cdlod& cdlod, double r0);
  /// Over its own quadtree, which terrain_changed() refreshes.
  CdlodTechnique(std::unique_ptr<Cdlod> cdlod, double r0);

  std::string name() const override { return "cdlod"; }
  Status update(const Camera& camera) override;
  FrameFigures figures() const override;
  Drawable capture(const MeshErrorMeter& meter) override;
  bool geomorphs() const override { return true; }
  void terrain_changed(const CellBox& box) override;

 private:
  std::unique_ptr<Cdlod> owned_;
  const Cdlod* cdlod_;
  double r0_;
  Cdlod::Selection sel_;
  std::vector<std::uint64_t> keys_;
  double changes_ = 0;
  bool first_ = true;
  std::vector<CellBox> pending_;
};

/// A static uniform grid of about `target` triangles over `grid` (UniformGrid::for_triangles):
/// no per-frame work (idle) until the terrain changes, when its update re-samples the vertices
/// inside the changed box.
class GridTechnique final : public Technique {
 public:
  GridTechnique(const Grid& grid, double target);

  std::string name() const override { return "uniform_grid"; }
  Status update(const Camera& camera) override;
  bool idle() const override { return pending_.empty(); }
  FrameFigures figures() const override;
  Drawable capture(const MeshErrorMeter& meter) override;
  Json summary() const override;
  void terrain_changed(const CellBox& box) override;

 private:
  Grid grid_;
  UniformGrid g_;
  std::vector<glm::dvec3> vertices_;
  std::vector<CellBox> pending_;
  std::size_t resampled_ = 0;
  bool changed_ever_ = false;
};

}  // namespace ridgeline::bench
