// The report's modes (modes.h): each a Ridgeline::bench technique, run by its frame loop.
#include "report/modes.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "ridgeline/bench/clock.h"
#include "ridgeline/bench/stats.h"
#include "ridgeline/bench/summary.h"
#include "ridgeline/bench/techniques.h"
#include "ridgeline/roam_view.h"

namespace ridgeline::report {

const Cdlod& Scene::cdlod(std::uint32_t grid) {
  auto& p = cdlod_[grid];
  if (!p) p = std::make_unique<Cdlod>(lattice(), grid);
  return *p;
}

const Heightfield& Scene::lattice() {
  if (!fine) fine = std::make_shared<const Heightfield>(bench::finest_lattice(*terrain).value());
  return *fine;
}

const Soar& Scene::soar() {
  if (!soar_) soar_ = std::make_unique<Soar>(lattice());
  return *soar_;
}

const MeshErrorMeter& Scene::meter(std::uint32_t stride) {
  if (!meter_ || meter_->stride() != std::max<std::uint32_t>(stride, 1))
    meter_ = std::make_unique<MeshErrorMeter>(lattice(), stride);
  return *meter_;
}

bench::LoopOptions roam_loop(const Options& o, RoamMode mode, bool detail_cache) {
  bench::LoopOptions lo = o.loop();
  // With detail the rebuild runs every frame: the tiles it requests on a frame arrive for the
  // later ones.
  lo.only_measured_frames = mode == RoamMode::kRebuild && !detail_cache;
  return lo;
}

void add_time_budget(Run& r, const Setting& st) {
  if (st.kind != "time_ms") return;
  bench::append(r.summary, bench::time_budget_figures(r, st.value));
}

Result<Run> run_roam(Scene& sc, const NamedPath& path, const Setting& st, RoamMode mode,
                     const Options& o) {
  std::shared_ptr<const Terrain> terrain = sc.terrain;
  std::shared_ptr<const Landscape> land = sc.landscape;
  if (sc.fresh) {  // a cold tile cache for every run: each pays for its own tiles
    auto f = sc.fresh();
    if (!f) return f.error();
    terrain = f->first;
    land = f->second;
  }
  auto v = RoamView::create(land, st.roam(mode));
  if (!v) return v.error();
  const bool cache = terrain->surface().detail_cache() != nullptr;
  // Converged for the first frame, tiles included (the start a game has after loading; for
  // rebuild only the tiles matter, its next update starts from the roots again).
  bench::RoamTechnique roam(std::move(*v), mode == RoamMode::kCoherent || cache);
  auto r = bench::run_path(roam, path.frames, &sc.meter(o.stride), roam_loop(o, mode, cache));
  if (!r) return r.error();
  add_time_budget(*r, st);
  return r;
}

Result<Run> run_uniform(Scene& sc, const NamedPath& path, double target, const Options& o) {
  bench::GridTechnique grid(sc.lattice(), target);
  auto r = bench::run_path(grid, path.frames, &sc.meter(o.stride), o.loop());
  if (!r) return r.error();
  r->summary["target_triangles"] = target;
  r->summary["matched_ratio"] = bench::median(r->triangles) / std::max(1.0, target);
  return r;
}

CdlodChoice calibrate_cdlod(Scene& sc, const NamedPath& path, double target) {
  CdlodChoice best;
  double best_err = std::numeric_limits<double>::infinity();
  const std::size_t step = std::max<std::size_t>(1, path.frames.size() / 40);
  for (std::uint32_t g : {32u, 16u, 8u, 4u}) {
    const auto m = sc.cdlod(g).match(path.frames, target, step);
    const double e = std::abs(m.median / std::max(1.0, target) - 1.0);
    if (e < best_err) {
      best_err = e;
      best = {g, m.r0, m.median};
    }
    if (best_err <= kMatchTolerance / 2) break;
  }
  return best;
}

Result<Run> run_cdlod(Scene& sc, const NamedPath& path, double target, const Options& o) {
  const auto t_cal = bench::Clock::now();
  const CdlodChoice ch = calibrate_cdlod(sc, path, target);
  const double calibrate_s = bench::ms_since(t_cal) / 1000;
  const Cdlod& cd = sc.cdlod(ch.grid);
  bench::CdlodTechnique cdlod(cd, ch.r0);
  auto r = bench::run_path(cdlod, path.frames, &sc.meter(o.stride), o.loop());
  if (!r) return r.error();
  r->summary["calibrate_s"] = calibrate_s;
  r->summary["target_triangles"] = target;
  r->summary["matched_ratio"] = bench::median(r->triangles) / std::max(1.0, target);
  r->summary["chunk_grid"] = ch.grid;
  r->summary["r0_m"] = ch.r0;
  r->summary["min_r0_m"] = cd.min_r0();
  r->summary["levels"] = cd.levels();
  return r;
}

Result<Run> run_soar(Scene& sc, const NamedPath& path, const Setting& st, const Options& o) {
  const Soar& soar = sc.soar();
  double path_kappa = std::numeric_limits<double>::infinity(), calibrate_s = 0;
  if (st.kind == "triangles") {
    const auto t_cal = bench::Clock::now();
    path_kappa =
        soar.match(path.frames, st.value, std::max<std::size_t>(1, path.frames.size() / 40)).kappa;
    calibrate_s = bench::ms_since(t_cal) / 1000;
  }
  bench::SoarTechnique technique(soar, st.threshold_px(), path_kappa);
  auto r = bench::run_path(technique, path.frames, &sc.meter(o.stride), o.loop());
  if (!r) return r.error();
  if (st.kind == "triangles") r->summary["calibrate_s"] = calibrate_s;
  if (st.kind == "time_ms") r->summary["time_budget"] = "none: SOAR runs unbudgeted at 1 px";
  return r;
}

}  // namespace ridgeline::report
