// The deformation storm (storm.h).
#include "report/storm.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>

#include "cli_util.h"
#include "report/roam_drawn.h"
#include "ridgeline/edit.h"
#include "ridgeline/roam_view.h"

namespace ridgeline::report {

namespace {
using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

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

// Lattice cells [i0, i1] x [j0, j1] an edit's changed box covers (one cell of margin).
struct CellBox {
  std::int64_t i0, j0, i1, j1;
};
CellBox cells_of(const WorldInfo& hf, const Box& b) {
  return {std::int64_t(std::floor((b.min.x - hf.origin_x) / hf.spacing_x)) - 1,
          std::int64_t(std::floor((b.min.z - hf.origin_z) / hf.spacing_z)) - 1,
          std::int64_t(std::ceil((b.max.x - hf.origin_x) / hf.spacing_x)) + 1,
          std::int64_t(std::ceil((b.max.z - hf.origin_z) / hf.spacing_z)) + 1};
}

// One mode in the storm: what it does after each frame's crater (inside its timed update), and
// its mesh as drawn.
struct StormMode {
  std::string name;
  bool morph = false;
  // Frame k after the crater (`changed`: the cells it changed, if any); records into r.
  std::function<Status(std::size_t k, const std::optional<CellBox>& changed, ModeResult& r)> step;
  std::function<Drawable()> capture;
};

// Runs one mode on its own terrain `t`: the crater of every frame (timed into edit_ms), the
// meter's surface refreshed over it, then the mode's step.
Result<ModeResult> run_storm_mode(Terrain& t, MeshErrorMeter& meter, const NamedPath& path,
                                  const Options& o, const StormMode& m) {
  ModeResult r;
  r.mode = m.name;
  r.has_morph = m.morph;
  std::string err;
  run_mode(
      meter, path.frames, o,
      [&](std::size_t k) {
        const auto t0 = Clock::now();
        auto e = t.apply_edit(crater_for(t, path.frames[k], k));
        r.edit_ms.push_back(ms_since(t0));
        if (!e) {
          err = e.error().message;
          return;
        }
        std::optional<CellBox> changed;
        if (!e->empty()) {
          changed = cells_of(t.info(), e->changed);
          meter.refresh(changed->i0, changed->j0, changed->i1, changed->j1);
        }
        if (auto s = m.step(k, changed, r); !s) err = s.message();
      },
      m.capture, r);
  if (!err.empty()) return Error{err};
  return r;
}

Result<ModeResult> storm_roam(const Pristine& pr, const NamedPath& path, const Setting& st,
                              RoamMode mode, const Options& o) {
  auto t = pr.fresh();
  if (!t) return Error{"storm: cannot rebuild the terrain"};
  auto l = Landscape::create(t, {.patch_exponent = 6});
  if (!l) return l.error();
  auto v = RoamView::create(*l, st.roam(mode));
  if (!v) return v.error();
  RoamView& view = **v;
  if (mode == RoamMode::kCoherent)
    if (auto s = view.converge(path.frames[0]); !s) return s.error();
  MeshErrorMeter meter(*t, o.stride);
  StormMode m;
  m.name = mode == RoamMode::kCoherent ? "roam_coherent" : "roam_rebuild";
  m.morph = st.threshold_px() > 0;
  m.step = [&](std::size_t k, const std::optional<CellBox>&, ModeResult& r) -> Status {
    // Rebuild: its mesh depends on the current camera and terrain alone, so it is updated only
    // on the frames the measurement reads (the craters land every frame regardless).
    if (mode == RoamMode::kRebuild && !measured_frame(k, std::max(o.error_every, 2)))
      return Status{};
    Result<RoamStats> s = Error{""};
    const Timing tm = timed([&] { s = view.update(path.frames[k]); });
    if (!s) return s.error();
    (void)view.take_dirty_patches();
    r.ms.push_back(s->update_ms);
    r.cpu_ms.push_back(tm.cpu_ms);
    r.tris.push_back(s->triangles);
    r.changes.push_back(s->splits + s->forced_splits + s->merges);
    r.mem.push_back(double(s->memory_bytes + (*l)->bound_bytes()));
    return Status{};
  };
  m.capture = [&]() -> Drawable {
    auto snap = std::make_shared<RoamSnapshot>(RoamSnapshot::capture(view));
    return [snap, &meter](const Camera& c, bool morph) { return snap->draw(meter, c, morph); };
  };
  return run_storm_mode(*t, meter, path, o, m);
}

// The uniform grid re-samples its vertices inside the changed box; CDLOD refreshes the min/max
// nodes over it and selects (both inside their timed update).
Result<ModeResult> storm_comparator(Scene& base, const Pristine& pr, const NamedPath& path,
                                    double target, const Options& o, bool cdlod) {
  auto t = pr.fresh();
  if (!t) return Error{"storm: cannot rebuild the terrain"};
  const Grid hf(*t);  // reads the terrain's live samples: the craters show
  MeshErrorMeter meter(*t, o.stride);
  StormMode m;
  Json extra = {{"target_triangles", target}};
  // The grid's state.
  const UniformGrid g = UniformGrid::for_triangles(hf, target);
  std::vector<glm::dvec3> verts;
  std::size_t resampled = 0;
  // CDLOD's, calibrated on the unedited terrain.
  CdlodChoice ch;
  std::unique_ptr<Cdlod> cd;
  Cdlod::Selection sel;
  if (cdlod) {
    ch = calibrate_cdlod(base, path, target);
    cd = std::make_unique<Cdlod>(hf, ch.grid);
    m.name = "cdlod";
    m.morph = true;
    m.step = [&](std::size_t k, const std::optional<CellBox>& c, ModeResult& r) -> Status {
      const Timing tm = timed([&] {
        if (c) cd->refresh(c->i0, c->j0, c->i1, c->j1);
        sel = cd->select(path.frames[k], ch.r0);
      });
      r.ms.push_back(tm.wall_ms);
      r.cpu_ms.push_back(tm.cpu_ms);
      r.tris.push_back(double(sel.triangles));
      r.changes.push_back(0);  // not counted in the storm
      r.mem.push_back(double(cd->memory_bytes()));
      return Status{};
    };
    m.capture = [&]() -> Drawable {
      return
          [s = sel, c = cd.get()](const Camera& cam, bool morph) { return c->mesh(s, cam, morph); };
    };
    extra["chunk_grid"] = ch.grid;
    extra["r0_m"] = ch.r0;
  } else {
    verts = g.vertices(hf);
    m.name = "uniform_grid";
    m.step = [&](std::size_t, const std::optional<CellBox>& c, ModeResult& r) -> Status {
      const Timing tm = timed([&] {
        if (c)
          resampled +=
              g.resample(hf, verts, double(c->i0), double(c->j0), double(c->i1), double(c->j1));
      });
      r.ms.push_back(tm.wall_ms);
      r.cpu_ms.push_back(tm.cpu_ms);
      r.tris.push_back(double(g.triangles()));
      r.changes.push_back(0);
      r.mem.push_back(double(g.memory_bytes()));
      return Status{};
    };
    m.capture = [&]() -> Drawable {
      auto mesh = std::make_shared<const DrawnMesh>(g.mesh_of(verts));
      return [mesh](const Camera&, bool) { return *mesh; };
    };
    extra["grid_quads"] = {g.nx, g.nz};
  }
  auto r = run_storm_mode(*t, meter, path, o, m);
  if (!r) return r;
  for (auto& [k, v] : extra.items()) r->extra[k] = v;
  r->extra["matched_ratio"] = quantile(r->tris, 0.5) / std::max(1.0, target);
  if (!cdlod) r->extra["vertices_resampled"] = resampled;
  return r;
}
}  // namespace

Result<Json> run_storm(Scene& base, const Options& o, std::string& csv_out) {
  const auto t0 = Clock::now();
  const Pristine pr = pristine_of(base.terrain->surface().to_heightfield().value());
  std::string csv;
  const std::string name = "storm_" + base.name;
  Json paths = Json::array();
  for (const NamedPath& p : make_paths(*base.terrain, o.frames)) {
    if (p.name != "flyover" && p.name != "drive") continue;
    Json rows = Json::array();
    for (double th : o.thresholds) {
      const Setting st{"threshold", th};
      std::vector<ModeResult> modes;
      for (RoamMode mode : {RoamMode::kCoherent, RoamMode::kRebuild}) {
        auto r = storm_roam(pr, p, st, mode, o);
        if (!r) return r.error();
        modes.push_back(std::move(*r));
      }
      const double target = quantile(modes.front().tris, 0.5);
      for (bool cdlod : {false, true}) {
        auto r = storm_comparator(base, pr, p, target, o, cdlod);
        if (!r) return r.error();
        modes.push_back(std::move(*r));
      }
      Json mj = Json::array();
      const std::string prefix = name + "," + p.name + ",threshold," + cli::csv_number(th);
      for (const ModeResult& m : modes) {
        mj.push_back(m.json());
        csv += m.csv(prefix);
      }
      rows.push_back({{"kind", "threshold"}, {"value", th}, {"modes", mj}});
      std::fprintf(stderr, "ridge report: %s %s threshold %g done (%.1f s)\n", name.c_str(),
                   p.name.c_str(), th, ms_since(t0) / 1000);
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
              {"wall_s", ms_since(t0) / 1000}};
}

}  // namespace ridgeline::report
