// The deformation storm (storm.h).
#include "report/storm.h"

#include <cmath>
#include <cstdio>

#include "cli_util.h"
#include "ridgeline/bench/clock.h"
#include "ridgeline/bench/stats.h"
#include "ridgeline/bench/techniques.h"
#include "ridgeline/edit.h"
#include "ridgeline/roam_view.h"

namespace ridgeline::report {

namespace {

// The stored heights of a scene, to make a fresh mutable terrain for each mode.
struct Pristine {
  HeightfieldDesc desc;
  std::vector<float> local;
  std::shared_ptr<Terrain> fresh() const {
    auto hf = Heightfield::create(desc, local);
    return hf ? Terrain::create(std::move(*hf)).value() : nullptr;
  }
};

Pristine pristine_of(const Heightfield& hf) {
  Pristine p;
  p.desc.width = hf.width();
  p.desc.height = hf.height();
  p.desc.spacing_x = hf.spacing_x();
  p.desc.spacing_z = hf.spacing_z();
  p.desc.origin_x = hf.origin_x();
  p.desc.origin_z = hf.origin_z();
  p.desc.height_offset = hf.height_offset();
  p.desc.name = "storm";
  p.local.assign(hf.local_heights().begin(), hf.local_heights().end());
  return p;
}

// Frame k's crater: where the view ray meets the ground (in view), jittered, 6..12 m radius.
Edit crater_for(const Terrain& t, const Camera& c, std::size_t k) {
  const glm::dvec3 dir = c.target - c.eye;
  glm::dvec3 at = c.target;
  if (auto hit = t.raycast(c.eye, dir, c.far_m)) at = hit->point;
  std::uint32_t h = static_cast<std::uint32_t>(k + 1) * 2654435761u;
  auto jitter = [&] {
    h ^= h >> 13;
    h *= 1274126177u;
    return (double(h >> 8) / double(1u << 24) - 0.5) * 20.0;
  };
  Edit e;
  e.brush = Brush::kCrater;
  e.x = at.x + jitter();
  e.z = at.z + jitter();
  e.radius = 6.0 + 3.0 * double(k % 3);
  e.depth = 2.0;
  e.rim = 0.2;
  return e;
}

// Lattice cells an edit's changed box covers (one cell of margin).
bench::CellBox cells_of(const WorldInfo& hf, const Box& b) {
  return {std::int64_t(std::floor((b.min.x - hf.origin_x) / hf.spacing_x)) - 1,
          std::int64_t(std::floor((b.min.z - hf.origin_z) / hf.spacing_z)) - 1,
          std::int64_t(std::ceil((b.max.x - hf.origin_x) / hf.spacing_x)) + 1,
          std::int64_t(std::ceil((b.max.z - hf.origin_z) / hf.spacing_z)) + 1};
}

// Runs one technique on its own terrain `t` with the frame loop, the crater of every frame
// applied before the frame's update (timed into the series edit_ms), the meter's surface
// refreshed over it and the technique told.
Result<Run> run_storm_mode(Terrain& t, MeshErrorMeter& meter, const NamedPath& path,
                           bench::LoopOptions lo, bench::Technique& technique) {
  std::vector<double> edit_ms;
  lo.before_frame = [&](std::size_t k) -> Status {
    const auto t0 = bench::Clock::now();
    auto e = t.apply_edit(crater_for(t, path.frames[k], k));
    edit_ms.push_back(bench::ms_since(t0));
    if (!e) return e.error();
    if (!e->empty()) {
      const bench::CellBox c = cells_of(t.info(), e->changed);
      meter.refresh(c.i0, c.j0, c.i1, c.j1);
      technique.terrain_changed(c);
    }
    return {};
  };
  auto r = bench::run_path(technique, path.frames, &meter, lo);
  if (!r) return r.error();
  r->series["edit_ms"] = std::move(edit_ms);
  return r;
}

// ROAM on a fresh copy of the terrain: the view pulls each crater from the terrain's change log
// inside its update.
Result<Run> storm_roam(const Pristine& pr, const NamedPath& path, const Setting& st,
                       RoamMode mode, const Options& o) {
  auto t = pr.fresh();
  if (!t) return Error{"storm: cannot rebuild the terrain"};
  auto l = Landscape::create(t, {.patch_exponent = 6});
  if (!l) return l.error();
  auto v = RoamView::create(*l, st.roam(mode));
  if (!v) return v.error();
  MeshErrorMeter meter(*t, o.stride);
  bench::RoamTechnique roam(std::move(*v), mode == RoamMode::kCoherent);
  return run_storm_mode(*t, meter, path, roam_loop(o, mode, false), roam);
}

// The uniform grid re-samples its vertices inside the changed box; CDLOD refreshes the min/max
// nodes over it and selects (both inside their timed update).
Result<Run> storm_comparator(Scene& base, const Pristine& pr, const NamedPath& path,
                             double target, const Options& o, bool cdlod) {
  auto t = pr.fresh();
  if (!t) return Error{"storm: cannot rebuild the terrain"};
  const bench::Grid hf(*t);  // reads the terrain's live samples: the craters show
  MeshErrorMeter meter(*t, o.stride);
  Result<Run> r = Error{""};
  if (cdlod) {
    // Calibrated on the unedited terrain.
    const CdlodChoice ch = calibrate_cdlod(base, path, target);
    bench::CdlodTechnique technique(std::make_unique<Cdlod>(hf, ch.grid), ch.r0);
    r = run_storm_mode(*t, meter, path, o.loop(), technique);
    if (!r) return r;
    r->summary["chunk_grid"] = ch.grid;
    r->summary["r0_m"] = ch.r0;
  } else {
    bench::GridTechnique technique(hf, target);
    r = run_storm_mode(*t, meter, path, o.loop(), technique);
    if (!r) return r;
  }
  r->summary["target_triangles"] = target;
  r->summary["matched_ratio"] = bench::median(r->triangles) / std::max(1.0, target);
  return r;
}
}  // namespace

Result<Json> run_storm(Scene& base, const Options& o, std::string& csv_out) {
  const auto t0 = bench::Clock::now();
  const Pristine pr = pristine_of(base.terrain->surface().to_heightfield().value());
  std::string csv;
  const std::string name = "storm_" + base.name;
  Json paths = Json::array();
  for (const NamedPath& p : bench::make_paths(*base.terrain, o.frames)) {
    if (p.name != "flyover" && p.name != "drive") continue;
    Json rows = Json::array();
    for (double th : o.thresholds) {
      const Setting st{"threshold", th};
      std::vector<Run> modes;
      for (RoamMode mode : {RoamMode::kCoherent, RoamMode::kRebuild}) {
        auto r = storm_roam(pr, p, st, mode, o);
        if (!r) return r.error();
        modes.push_back(std::move(*r));
      }
      const double target = bench::median(modes.front().triangles);
      for (bool cdlod : {false, true}) {
        auto r = storm_comparator(base, pr, p, target, o, cdlod);
        if (!r) return r.error();
        modes.push_back(std::move(*r));
      }
      const std::string prefix = name + "," + p.name + ",threshold," + cli::csv_number(th);
      rows.push_back({{"kind", "threshold"}, {"value", th}, {"modes", modes_json(modes, prefix, csv)}});
      std::fprintf(stderr, "ridge report: %s %s threshold %g done (%.1f s)\n", name.c_str(),
                   p.name.c_str(), th, bench::ms_since(t0) / 1000);
    }
    paths.push_back({{"name", p.name}, {"frames", p.frames.size()}, {"settings", rows}});
  }
  csv_out += csv;
  const WorldInfo& hf = base.terrain->info();
  return Json{{"name", name},
              {"source", base.source + ", a crater every frame (apply_edit) where the view ray "
                                       "meets the ground, radius 6-12 m, depth 2 m"},
              {"samples", {hf.width, hf.height}},
              {"spacing_m", {hf.spacing_x, hf.spacing_z}},
              {"paths", paths},
              {"wall_s", bench::ms_since(t0) / 1000}};
}

}  // namespace ridgeline::report
