// The report's modes and their shared measurement loop (modes.h).
#include "report/modes.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iterator>

#include "cli_util.h"
#include "report/roam_drawn.h"
#include "ridgeline/detail.h"
#include "ridgeline/roam_view.h"

namespace ridgeline::report {

namespace {
using Clock = std::chrono::steady_clock;
constexpr double kMatchTolerance = 0.10;  // comparators' median triangles within 10 % of ROAM's

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}
}  // namespace

const Cdlod& Scene::cdlod(std::uint32_t grid) {
  auto& p = cdlod_[grid];
  if (!p) p = std::make_unique<Cdlod>(lattice(), grid);
  return *p;
}

const Heightfield& Scene::lattice() {
  if (!fine) fine = std::make_shared<const Heightfield>(finest_lattice(*terrain).value());
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

Result<Heightfield> finest_lattice(const Terrain& t) {
  const WorldInfo& stored = t.info();
  HeightfieldDesc d;
  d.width = static_cast<std::uint32_t>(t.surface().lattice().vertices_x);
  d.height = static_cast<std::uint32_t>(t.surface().lattice().vertices_z);
  d.spacing_x = stored.spacing_x / double(1u << t.surface().detail_levels());
  d.spacing_z = stored.spacing_z / double(1u << t.surface().detail_levels());
  d.origin_x = stored.origin_x;
  d.origin_z = stored.origin_z;
  d.height_offset = stored.height_offset;
  d.max_samples = std::uint64_t{1} << 31;
  d.name = "finest lattice";
  std::vector<float> v(std::size_t(d.width) * d.height);
  for (std::uint32_t j = 0; j < d.height; ++j)
    for (std::uint32_t i = 0; i < d.width; ++i)
      v[i + std::size_t(j) * d.width] = static_cast<float>(t.surface().vertex_height(i, j));
  return Heightfield::create(d, v);
}

Timing timed(const std::function<void()>& work) {
  const double cpu0 = cli::thread_cpu_ns();
  const auto t0 = Clock::now();
  work();
  return {ms_since(t0), (cli::thread_cpu_ns() - cpu0) * 1e-6};
}

void run_mode(const MeshErrorMeter& meter, const std::vector<Camera>& frames, const Options& o,
              const std::function<void(std::size_t)>& update,
              const std::function<Drawable()>& capture, ModeResult& r) {
  const auto t_run = Clock::now();
  const int K = std::max(o.error_every, 2);
  Drawable before;  // the mesh of frame nK - 1
  DrawnHeights now, now_m, prev, prev_m;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const Camera& c = frames[k];
    update(k);
    const auto t_measure = Clock::now();
    if (int(k % K) == K - 1) before = capture();
    if (k % K == 0 && k > 0 && before) {
      const Drawable cur = capture();
      const DrawnMesh mesh = cur(c, false);
      meter.rasterize(mesh, now);
      const MeshError e = meter.measure(now, c);
      r.max_m.push_back(e.max_m);
      r.rms_m.push_back(e.rms_m);
      r.max_px.push_back(e.max_px);
      r.p99_px.push_back(e.p99_px);
      r.vertices.push_back(double(e.vertices));
      r.uncovered += e.uncovered;
      r.tris_in_view.push_back(double(meter.triangles_in_view(mesh, c)));
      // Without geomorphs the camera does not change the drawn mesh: the previous frame's mesh
      // serves both the per-vertex jump and the pop.
      meter.rasterize(before(frames[k - 1], false), prev);
      r.jump.push_back(meter.jump_px(prev, now, c, &frames[k - 1]));
      r.pop.push_back(meter.jump_px(prev, now, c, &frames[k - 1]));
      if (r.has_morph) {
        meter.rasterize(cur(c, true), now_m);
        r.morph_max_px.push_back(meter.measure(now_m, c).max_px);
        meter.rasterize(before(frames[k - 1], true), prev_m);
        r.jump_morph.push_back(meter.jump_px(prev_m, now_m, c, &frames[k - 1]));
        // The pop: both meshes morphed for the current camera, so only the topology differs;
        // over the vertices in view in both frames, like the jump (a region coming into view
        // refines unseen).
        meter.rasterize(before(c, true), prev_m);
        r.pop_morph.push_back(meter.jump_px(prev_m, now_m, c, &frames[k - 1]));
      }
    }
    r.measure_s += ms_since(t_measure) / 1000;
  }
  r.wall_s = ms_since(t_run) / 1000;
}

namespace {
// One ROAM frame's figures (the patches are taken as a renderer would).
void record_roam(RoamView& view, const RoamStats& s, const Timing& t, std::size_t bound_bytes,
                 ModeResult& r) {
  (void)view.take_dirty_patches();
  r.ms.push_back(s.update_ms);
  r.cpu_ms.push_back(t.cpu_ms);
  r.tris.push_back(s.triangles);
  r.changes.push_back(s.splits + s.forced_splits + s.merges);
  r.mem.push_back(double(s.memory_bytes + bound_bytes));
}

Drawable roam_capture(RoamView& view, const MeshErrorMeter& meter) {
  auto snap = std::make_shared<RoamSnapshot>(RoamSnapshot::capture(view));
  return [snap, &meter](const Camera& c, bool morph) { return snap->draw(meter, c, morph); };
}
}  // namespace

Result<ModeResult> run_roam(Scene& sc, const NamedPath& path, const Setting& st, RoamMode mode,
                            const Options& o) {
  std::shared_ptr<const Terrain> terrain = sc.terrain;
  std::shared_ptr<const Landscape> land = sc.landscape;
  if (sc.fresh) {  // a cold tile cache for every run: each pays for its own tiles
    auto f = sc.fresh();
    if (!f) return f.error();
    terrain = f->first;
    land = f->second;
  }
  DetailCache* cache = terrain->surface().detail_cache();
  auto v = RoamView::create(land, st.roam(mode));
  if (!v) return v.error();
  RoamView& view = **v;
  ModeResult r;
  r.mode = mode == RoamMode::kCoherent ? "roam_coherent" : "roam_rebuild";
  r.has_morph = st.threshold_px() > 0;  // geomorph factors need a pixel threshold
  if (mode == RoamMode::kCoherent || cache) {
    // Converged for the first frame, tiles included (the start a game has after loading; for
    // rebuild only the tiles matter, its next update starts from the roots again).
    for (int round = 0; round < 64; ++round) {
      if (cache) cache->update();
      auto s = view.converge(path.frames[0]);
      if (!s) return s.error();
      if (!cache || s->pending_splits == 0) break;
      (void)cache->wait_idle(60.0);
    }
  }
  std::string err;
  std::uint32_t time_stops = 0;
  std::vector<double> cache_ms;
  const double field_bytes = cache ? double(terrain->surface().detail()->memory_bytes()) : 0.0;
  const MeshErrorMeter& meter = sc.meter(o.stride);
  auto update = [&](std::size_t k) {
    if (cache) {  // the frame loop's once-per-frame cache update (integrate, evict, publish)
      const auto t1 = Clock::now();
      cache->update();
      cache_ms.push_back(ms_since(t1));
    }
    // Rebuild: its mesh depends on the current camera alone, so it is updated only on the
    // frames the measurement reads; with detail it runs every frame, since the tiles it
    // requests on a frame arrive for the later ones.
    if (mode == RoamMode::kRebuild && !cache && !measured_frame(k, std::max(o.error_every, 2)))
      return;
    Result<RoamStats> s = Error{""};
    const Timing t = timed([&] { s = view.update(path.frames[k]); });
    if (!s) {
      err = s.error().message;
      return;
    }
    record_roam(view, *s, t, land->bound_bytes(), r);
    time_stops += s->stop == StopReason::kTimeBudget;
    if (cache) {
      const DetailCacheStats cs = cache->stats();
      r.pending_splits.push_back(s->pending_splits);
      r.tiles_resident.push_back(double(cs.resident_tiles));
      r.detail_bytes.push_back(double(cs.resident_bytes) + field_bytes);
      r.tiles_pending.push_back(double(cs.pending));
    }
  };
  run_mode(
      meter, path.frames, o, update, [&] { return roam_capture(view, meter); }, r);
  if (!err.empty()) return Error{err};
  if (st.kind == "time_ms") {
    r.extra["time_budget_stops"] = time_stops;
    r.extra["time_budget_met"] = quantile(r.ms, 0.99) <= 1.1 * st.value + 0.1;
    r.extra["time_budget_met_cpu"] = quantile(r.cpu_ms, 0.99) <= 1.1 * st.value + 0.1;
  }
  if (cache) {
    const DetailCacheStats cs = cache->stats();
    r.extra["cache_update_ms_median"] = num(quantile(cache_ms, 0.5));
    r.extra["tiles_generated"] = cs.generated;
    r.extra["tiles_evicted"] = cs.evicted;
    r.extra["tile_generation_s"] = cs.generation_seconds;
    r.extra["worst_tile_lag_frames"] = cs.worst_lag_frames;
  }
  return r;
}

ModeResult run_uniform(Scene& sc, const NamedPath& path, double target, const Options& o) {
  const Heightfield& hf = sc.lattice();
  ModeResult r;
  r.mode = "uniform_grid";
  const UniformGrid g = UniformGrid::for_triangles(hf, target);
  const auto mesh = std::make_shared<const DrawnMesh>(g.mesh(hf));
  run_mode(
      sc.meter(o.stride), path.frames, o,
      [&](std::size_t) {
        r.ms.push_back(0.0);  // a static mesh: no per-frame work
        r.cpu_ms.push_back(0.0);
        r.tris.push_back(double(g.triangles()));
        r.changes.push_back(0);
        r.upload_bytes.push_back(0);
        r.mem.push_back(double(g.memory_bytes()));
      },
      [&]() -> Drawable { return [mesh](const Camera&, bool) { return *mesh; }; }, r);
  r.extra["target_triangles"] = target;
  r.extra["matched_ratio"] = double(g.triangles()) / std::max(1.0, target);
  r.extra["grid_quads"] = {g.nx, g.nz};
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

namespace {
// Quadrants entering or leaving a CDLOD selection between two frames (its "splits + merges").
std::size_t selection_changes(const Cdlod::Selection& sel, std::vector<std::uint64_t>& prev) {
  std::vector<std::uint64_t> keys;
  for (const auto& c : sel.chunks)
    for (int q = 0; q < 4; ++q)
      if (c.quadrants >> q & 1)
        keys.push_back(std::uint64_t(c.level) << 58 | std::uint64_t(c.i0) << 30 |
                       std::uint64_t(c.j0) << 2 | std::uint64_t(q));
  std::sort(keys.begin(), keys.end());
  std::vector<std::uint64_t> diff;
  std::set_symmetric_difference(keys.begin(), keys.end(), prev.begin(), prev.end(),
                                std::back_inserter(diff));
  prev = std::move(keys);
  return diff.size();
}
}  // namespace

ModeResult run_cdlod(Scene& sc, const NamedPath& path, double target, const Options& o) {
  ModeResult r;
  r.mode = "cdlod";
  r.has_morph = true;
  const auto t_cal = Clock::now();
  const CdlodChoice ch = calibrate_cdlod(sc, path, target);
  r.extra["calibrate_s"] = ms_since(t_cal) / 1000;
  const Cdlod& cd = sc.cdlod(ch.grid);
  Cdlod::Selection sel;
  std::vector<std::uint64_t> keys;
  run_mode(
      sc.meter(o.stride), path.frames, o,
      [&](std::size_t k) {
        const Timing t = timed([&] { sel = cd.select(path.frames[k], ch.r0); });
        r.ms.push_back(t.wall_ms);
        r.cpu_ms.push_back(t.cpu_ms);
        r.tris.push_back(double(sel.triangles));
        r.mem.push_back(double(cd.memory_bytes()));
        const std::size_t changed = selection_changes(sel, keys);
        r.changes.push_back(k == 0 ? 0.0 : double(changed));
      },
      [&]() -> Drawable {
        return [sel, &cd](const Camera& c, bool morph) { return cd.mesh(sel, c, morph); };
      },
      r);
  r.extra["target_triangles"] = target;
  r.extra["matched_ratio"] = quantile(r.tris, 0.5) / std::max(1.0, target);
  r.extra["chunk_grid"] = ch.grid;
  r.extra["r0_m"] = ch.r0;
  r.extra["min_r0_m"] = cd.min_r0();
  r.extra["levels"] = cd.levels();
  return r;
}

ModeResult run_soar(Scene& sc, const NamedPath& path, const Setting& st, const Options& o) {
  ModeResult r;
  r.mode = "soar";
  const Soar& soar = sc.soar();
  const double threshold = st.threshold_px();
  double fixed_kappa = 0;
  if (st.kind == "triangles") {
    const auto t_cal = Clock::now();
    const Soar::Match m =
        soar.match(path.frames, st.value, std::max<std::size_t>(1, path.frames.size() / 40));
    fixed_kappa = m.kappa;
    r.extra["calibrate_s"] = ms_since(t_cal) / 1000;
    r.extra["kappa"] = m.kappa;
  }
  if (st.kind == "time_ms") r.extra["time_budget"] = "none: SOAR runs unbudgeted at 1 px";
  std::vector<std::uint32_t> strip;
  run_mode(
      sc.meter(o.stride), path.frames, o,
      [&](std::size_t k) {
        const Camera& c = path.frames[k];
        const double kappa = fixed_kappa > 0 ? fixed_kappa : Soar::kappa_for(c, threshold);
        Soar::Frame f;
        const Timing t = timed([&] { f = soar.refine(c, kappa, strip); });
        r.ms.push_back(t.wall_ms);
        r.cpu_ms.push_back(t.cpu_ms);
        r.tris.push_back(double(f.triangles));
        r.upload_bytes.push_back(double(strip.size() * sizeof(std::uint32_t)));
        r.mem.push_back(double(soar.memory_bytes() + strip.capacity() * sizeof(std::uint32_t)));
      },
      [&]() -> Drawable {
        auto mesh = std::make_shared<const DrawnMesh>(soar.mesh(strip));
        return [mesh](const Camera&, bool) { return *mesh; };
      },
      r);
  r.extra["emitted"] = "one generalised triangle strip of 32-bit indices, whole mesh every frame";
  return r;
}

}  // namespace ridgeline::report
