// `ridge report`: what each level of accuracy costs. For every scene, camera path and setting
// (thresholds in pixels, triangle caps, time budgets) it runs, in one process, ROAM coherent,
// ROAM rebuild, and at ROAM's median triangle count a uniform grid and a CDLOD-like quadtree
// (report/meshes.h), and writes per-setting medians as JSON and CSV (docs/report.md).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <sstream>
#include <thread>

#include "cli_util.h"
#include "commands.h"
#include "report/meshes.h"
#include "report/paths.h"
#include "ridgeline/detail.h"
#include "ridgeline/edit.h"
#include "ridgeline/io.h"
#include "ridgeline/log.h"
#include "ridgeline/roam_view.h"

namespace ridgeline::cli {

namespace {

using report::Cdlod;
using report::DisplayedHeights;
using report::DrawnMesh;
using report::NamedPath;
using report::UniformGrid;
using Json = nlohmann::ordered_json;
using Clock = std::chrono::steady_clock;

constexpr double kMatchTolerance = 0.10;  // comparators' median triangles within 10 % of ROAM's

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * double(v.size())))];
}
double vmax(const std::vector<double>& v) {
  return v.empty() ? std::nan("") : *std::max_element(v.begin(), v.end());
}
Json num(double v) {
  return std::isfinite(v) ? Json(v) : Json(nullptr);
}

// ---- captured loader messages -----------------------------------------------------------

struct Captured {
  std::vector<std::string> lines;
};
void capture_sink(LogLevel level, std::string_view m, void* user) {
  if (level == LogLevel::kDebug) return;
  const char* tag = level == LogLevel::kInfo      ? "note"
                    : level == LogLevel::kWarning ? "warning"
                                                  : "error";
  static_cast<Captured*>(user)->lines.push_back(std::string(tag) + ": " + std::string(m));
}

// ---- settings and results ---------------------------------------------------------------

struct Setting {
  std::string kind;  // "threshold" (px), "triangles" (cap), "time_ms" (budget, at 1 px)
  double value;
  RoamSettings roam(RoamMode mode) const {
    RoamSettings s;
    s.mode = mode;
    if (kind == "threshold") {
      s.threshold = value;
    } else if (kind == "triangles") {
      s.threshold = 0;
      s.max_triangles = static_cast<std::uint32_t>(value);
    } else {
      s.threshold = 1.0;
      s.budget_ms = value;
    }
    return s;
  }
};

struct ModeResult {
  std::string mode;
  std::vector<double> ms, tris, changes, mem;
  std::vector<double> max_m, rms_m, max_px, p99_px, vertices, pop, pop_morph;
  std::vector<double> edit_ms;  // deformation storm: Terrain::apply_edit per frame
  // Procedural detail (ROAM on a detail terrain): per updated frame.
  std::vector<double> pending_splits, tiles_resident, detail_bytes, tiles_pending;
  std::uint64_t uncovered = 0;
  double wall_s = 0, measure_s = 0;  // this mode's run, and the error/popping measurement in it
  bool has_morph = false;
  Json extra = Json::object();

  Json json() const {
    Json j = {{"mode", mode},
              {"frames", ms.size()},
              {"triangles_median", num(quantile(tris, 0.5))},
              {"update_ms_median", num(quantile(ms, 0.5))},
              {"update_ms_p99", num(quantile(ms, 0.99))},
              {"changes_per_frame_median", num(quantile(changes, 0.5))},
              {"error_max_m", num(vmax(max_m))},
              {"error_rms_m", num(quantile(rms_m, 0.5))},
              {"screen_error_max_px", num(vmax(max_px))},
              {"screen_error_p99_px", num(quantile(p99_px, 0.5))},
              {"popping_max_px", num(vmax(pop))},
              {"popping_geomorph_max_px", has_morph ? num(vmax(pop_morph)) : Json(nullptr)},
              {"memory_bytes", num(quantile(mem, 0.5))},
              {"measured_frames", max_m.size()},
              {"measured_vertices_median", num(quantile(vertices, 0.5))},
              {"uncovered_vertices", uncovered}};
    if (!edit_ms.empty()) {
      j["edit_ms_median"] = num(quantile(edit_ms, 0.5));
      j["edit_ms_p99"] = num(quantile(edit_ms, 0.99));
    }
    if (!pending_splits.empty()) {
      j["pending_splits_median"] = num(quantile(pending_splits, 0.5));
      j["pending_splits_max"] = num(vmax(pending_splits));
      j["tiles_resident_median"] = num(quantile(tiles_resident, 0.5));
      j["tiles_resident_max"] = num(vmax(tiles_resident));
      j["detail_memory_bytes_median"] = num(quantile(detail_bytes, 0.5));
      j["tiles_pending_median"] = num(quantile(tiles_pending, 0.5));
    }
    j["wall_s"] = wall_s;
    j["measure_s"] = measure_s;
    for (auto& [k, v] : extra.items()) j[k] = v;
    return j;
  }
  std::string csv(const std::string& prefix) const {
    auto n = [](double v) { return std::isfinite(v) ? csv_number(v) : std::string(); };
    std::string matched;
    if (extra.contains("matched_ratio")) matched = csv_number(extra["matched_ratio"].get<double>());
    return prefix + "," + mode + "," + n(quantile(tris, 0.5)) + "," + n(quantile(ms, 0.5)) + "," +
           n(quantile(ms, 0.99)) + "," + n(quantile(changes, 0.5)) + "," + n(vmax(max_m)) + "," +
           n(quantile(rms_m, 0.5)) + "," + n(vmax(max_px)) + "," + n(quantile(p99_px, 0.5)) + "," +
           n(vmax(pop)) + "," + (has_morph ? n(vmax(pop_morph)) : std::string()) + "," +
           n(quantile(mem, 0.5)) + "," + matched + "\n";
  }
};

struct Options {
  int frames = 60;
  int error_every = 6;
  std::uint32_t stride = 1;
  std::vector<double> thresholds{0.5, 1, 2, 4, 8, 16};
  std::vector<double> triangle_caps{5000, 20000, 80000};
  std::vector<double> time_budgets{0.5, 2};
  std::vector<std::string> paths;  // empty: all six
};

// True for the frames whose mesh the measurement reads: K-1, K, 2K-1, 2K, ... (errors at frame
// K, 2K, ...; popping between frames nK-1 and nK).
bool measured_frame(std::size_t k, int K) {
  return int(k % K) == K - 1 || (k % K == 0 && k > 0);
}

// Runs one mode along a path: `update(k)` does frame k's work and records its cost; `draw(camera,
// morph)` returns the mesh as drawn. Errors every K-th frame; popping between frames K-1 and K.
template <class Update, class Draw>
void run_mode(const Heightfield& hf, const std::vector<Camera>& frames, const Options& o,
              Update update, Draw draw, ModeResult& r) {
  const auto t_run = Clock::now();
  DisplayedHeights prev(hf, o.stride), prev_m(hf, o.stride), cur(hf, o.stride), cur_m(hf, o.stride);
  const int K = std::max(o.error_every, 2);
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const Camera& c = frames[k];
    update(k);
    const auto t_measure = Clock::now();
    if (int(k % K) == K - 1) {
      prev.rasterize(draw(c, false));
      if (r.has_morph) prev_m.rasterize(draw(c, true));
    }
    if (k % K == 0 && k > 0) {
      cur.rasterize(draw(c, false));
      const auto e = report::measure(hf, cur, c);
      r.max_m.push_back(e.max_m);
      r.rms_m.push_back(e.rms_m);
      r.max_px.push_back(e.max_px);
      r.p99_px.push_back(e.p99_px);
      r.vertices.push_back(double(e.vertices));
      r.uncovered += e.uncovered;
      r.pop.push_back(report::popping_px(hf, prev, frames[k - 1], cur, c));
      if (r.has_morph) {
        cur_m.rasterize(draw(c, true));
        r.pop_morph.push_back(report::popping_px(hf, prev_m, frames[k - 1], cur_m, c));
      }
    }
    r.measure_s += ms_since(t_measure) / 1000;
  }
  r.wall_s = ms_since(t_run) / 1000;
}

// ---- a scene ----------------------------------------------------------------------------

struct Scene {
  std::string name, source;
  std::shared_ptr<const Terrain> terrain;
  std::shared_ptr<const Landscape> landscape;
  std::vector<std::string> messages;
  Json loader = Json::object();
  std::map<std::uint32_t, std::unique_ptr<Cdlod>> cdlod;  // by grid size
  // Procedural detail: the full-detail surface as a heightfield of the finest lattice (what the
  // error is measured against and what the comparators draw from), and a fresh terrain with a
  // cold tile cache and its landscape for every ROAM run.
  std::shared_ptr<const Heightfield> fine;
  std::function<
      Result<std::pair<std::shared_ptr<const Terrain>, std::shared_ptr<const Landscape>>>()>
      fresh;
  Json detail = nullptr;

  const Heightfield& lattice() const { return fine ? *fine : terrain->heightfield(); }
  const Cdlod& cd(std::uint32_t g) {
    auto& p = cdlod[g];
    if (!p) p = std::make_unique<Cdlod>(lattice(), g);
    return *p;
  }
};

// One ROAM frame's figures (the patches are taken as a renderer would).
void record_roam(RoamView& view, const RoamStats& s, std::size_t bound_bytes, ModeResult& r) {
  (void)view.take_dirty_patches();
  r.ms.push_back(s.update_ms);
  r.tris.push_back(s.triangles);
  r.changes.push_back(s.splits + s.forced_splits + s.merges);
  r.mem.push_back(double(s.memory_bytes + bound_bytes));
}

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
  DetailCache* cache = terrain->detail_cache();
  auto v = RoamView::create(land, st.roam(mode));
  if (!v) return v.error();
  RoamView& view = **v;
  ModeResult r;
  r.mode = mode == RoamMode::kCoherent ? "roam_coherent" : "roam_rebuild";
  // Geomorph factors need a pixel threshold; with detail the mesh is read from the leaves.
  r.has_morph = st.kind != "triangles" && !cache;
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
  const double field_bytes = cache ? double(terrain->detail()->memory_bytes()) : 0.0;
  run_mode(
      sc.lattice(), path.frames, o,
      [&](std::size_t k) {
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
        auto s = view.update(path.frames[k]);
        if (!s) {
          err = s.error().message;
          return;
        }
        record_roam(view, *s, land->bound_bytes(), r);
        time_stops += s->stop == StopReason::kTimeBudget;
        if (cache) {
          const DetailCacheStats cs = cache->stats();
          r.pending_splits.push_back(s->pending_splits);
          r.tiles_resident.push_back(double(cs.resident_tiles));
          r.detail_bytes.push_back(double(cs.resident_bytes) + field_bytes);
          r.tiles_pending.push_back(double(cs.pending));
        }
      },
      [&](const Camera& c, bool morph) {
        // With detail, the leaves themselves (no geomorph popping: see detail_scene()).
        return cache ? report::roam_leaves(view, sc.lattice())
                     : report::roam_mesh(view, sc.lattice(), c, morph);
      },
      r);
  if (!err.empty()) return Error{err};
  if (st.kind == "time_ms") {
    r.extra["time_budget_stops"] = time_stops;
    r.extra["time_budget_met"] = quantile(r.ms, 0.99) <= 1.1 * st.value + 0.1;
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
  const auto t_run = Clock::now();
  const Heightfield& hf = sc.lattice();
  ModeResult r;
  r.mode = "uniform_grid";
  const UniformGrid g = UniformGrid::for_triangles(hf, target);
  DisplayedHeights shown(hf, o.stride);
  shown.rasterize(g.mesh(hf));
  const int K = std::max(o.error_every, 2);
  for (std::size_t k = 0; k < path.frames.size(); ++k) {
    r.ms.push_back(0.0);  // a static mesh: no per-frame work
    r.tris.push_back(double(g.triangles()));
    r.changes.push_back(0);
    r.mem.push_back(double(g.memory_bytes()));
    if (k % K == 0 && k > 0) {
      const auto e = report::measure(hf, shown, path.frames[k]);
      r.max_m.push_back(e.max_m);
      r.rms_m.push_back(e.rms_m);
      r.max_px.push_back(e.max_px);
      r.p99_px.push_back(e.p99_px);
      r.vertices.push_back(double(e.vertices));
      r.uncovered += e.uncovered;
      r.pop.push_back(0.0);  // the mesh never changes
    }
  }
  r.wall_s = r.measure_s = ms_since(t_run) / 1000;
  r.extra["target_triangles"] = target;
  r.extra["matched_ratio"] = double(g.triangles()) / std::max(1.0, target);
  r.extra["grid_quads"] = {g.nx, g.nz};
  return r;
}

Result<std::shared_ptr<const Landscape>> landscape_of(std::shared_ptr<const Terrain> t);

struct CdlodChoice {
  std::uint32_t grid = 32;
  double r0 = 0, median = 0;
};

// The chunk grid and range that match `target` triangles: 32 x 32 chunks (a common CDLOD size)
// unless the shortest ranges the morph constraint allows already draw too much, then finer.
CdlodChoice calibrate_cdlod(Scene& sc, const NamedPath& path, double target) {
  CdlodChoice best;
  double best_err = std::numeric_limits<double>::infinity();
  const std::size_t step = std::max<std::size_t>(1, path.frames.size() / 40);
  for (std::uint32_t g : {32u, 16u, 8u, 4u}) {
    const auto m = sc.cd(g).match(path.frames, target, step);
    const double e = std::abs(m.median / std::max(1.0, target) - 1.0);
    if (e < best_err) {
      best_err = e;
      best = {g, m.r0, m.median};
    }
    if (best_err <= kMatchTolerance / 2) break;
  }
  return best;
}

ModeResult run_cdlod(Scene& sc, const NamedPath& path, double target, const Options& o) {
  ModeResult r;
  r.mode = "cdlod";
  r.has_morph = true;
  const auto t_cal = Clock::now();
  const CdlodChoice ch = calibrate_cdlod(sc, path, target);
  r.extra["calibrate_s"] = ms_since(t_cal) / 1000;
  const Cdlod& cd = sc.cd(ch.grid);
  Cdlod::Selection sel;
  std::vector<std::uint64_t> keys, prev_keys;
  run_mode(
      sc.lattice(), path.frames, o,
      [&](std::size_t k) {
        const auto t0 = Clock::now();
        sel = cd.select(path.frames[k], ch.r0);
        r.ms.push_back(ms_since(t0));
        r.tris.push_back(double(sel.triangles));
        r.mem.push_back(double(cd.memory_bytes()));
        // Quadrants entering or leaving the selection (the comparator's "splits + merges").
        keys.clear();
        for (const auto& c : sel.chunks)
          for (int q = 0; q < 4; ++q)
            if (c.quadrants >> q & 1)
              keys.push_back(std::uint64_t(c.level) << 58 | std::uint64_t(c.i0) << 30 |
                             std::uint64_t(c.j0) << 2 | std::uint64_t(q));
        std::sort(keys.begin(), keys.end());
        std::vector<std::uint64_t> diff;
        std::set_symmetric_difference(keys.begin(), keys.end(), prev_keys.begin(), prev_keys.end(),
                                      std::back_inserter(diff));
        r.changes.push_back(k == 0 ? 0.0 : double(diff.size()));
        std::swap(keys, prev_keys);
      },
      [&](const Camera& c, bool morph) { return cd.mesh(sel, c, morph); }, r);
  r.extra["target_triangles"] = target;
  r.extra["matched_ratio"] = quantile(r.tris, 0.5) / std::max(1.0, target);
  r.extra["chunk_grid"] = ch.grid;
  r.extra["r0_m"] = ch.r0;
  r.extra["min_r0_m"] = cd.min_r0();
  r.extra["levels"] = cd.levels();
  return r;
}

// ---- the deformation storm ----------------------------------------------------------------

// The stored heights of a scene, to make a fresh mutable terrain for each mode (every mode sees
// the same craters on the same start).
struct Pristine {
  HeightfieldDesc desc;
  std::vector<float> local;
  std::shared_ptr<Terrain> fresh() const {
    auto hf = Heightfield::create(desc, local);
    return hf ? Terrain::create(std::move(*hf)) : nullptr;
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
CellBox cells_of(const Heightfield& hf, const Box& b) {
  return {std::int64_t(std::floor((b.min.x - hf.origin_x()) / hf.spacing_x())) - 1,
          std::int64_t(std::floor((b.min.z - hf.origin_z()) / hf.spacing_z())) - 1,
          std::int64_t(std::ceil((b.max.x - hf.origin_x()) / hf.spacing_x())) + 1,
          std::int64_t(std::ceil((b.max.z - hf.origin_z()) / hf.spacing_z())) + 1};
}

// Applies frame k's crater to `t`, timing it into r.edit_ms; the lattice cells it changed (none
// when it changed nothing), or the edit's error.
Result<std::optional<CellBox>> storm_edit(Terrain& t, const Camera& c, std::size_t k,
                                          ModeResult& r) {
  const auto t0 = Clock::now();
  auto e = t.apply_edit(crater_for(t, c, k));
  r.edit_ms.push_back(ms_since(t0));
  if (!e) return e.error();
  if (e->empty()) return std::optional<CellBox>{};
  return std::optional<CellBox>{cells_of(t.heightfield(), e->changed)};
}

Result<ModeResult> storm_roam(const Pristine& pr, const NamedPath& path, const Setting& st,
                              RoamMode mode, const Options& o) {
  auto t = pr.fresh();
  if (!t) return Error{"storm: cannot rebuild the terrain"};
  auto l = landscape_of(t);
  if (!l) return l.error();
  auto v = RoamView::create(*l, st.roam(mode));
  if (!v) return v.error();
  RoamView& view = **v;
  ModeResult r;
  r.mode = mode == RoamMode::kCoherent ? "roam_coherent" : "roam_rebuild";
  r.has_morph = st.kind != "triangles";
  if (mode == RoamMode::kCoherent)
    if (auto s = view.converge(path.frames[0]); !s) return s.error();
  std::string err;
  run_mode(
      t->heightfield(), path.frames, o,
      [&](std::size_t k) {
        if (auto e = storm_edit(*t, path.frames[k], k, r); !e) err = e.error().message;
        // Rebuild: its mesh depends on the current camera and terrain alone, so it is updated
        // only on the frames the measurement reads (the craters land every frame regardless).
        if (mode == RoamMode::kRebuild && !measured_frame(k, std::max(o.error_every, 2))) return;
        auto s = view.update(path.frames[k]);
        if (!s) {
          err = s.error().message;
          return;
        }
        record_roam(view, *s, (*l)->bound_bytes(), r);
      },
      [&](const Camera& c, bool morph) { return report::roam_mesh(view, c, morph); }, r);
  if (!err.empty()) return Error{err};
  return r;
}

Result<ModeResult> storm_uniform(const Pristine& pr, const NamedPath& path, double target,
                                 const Options& o) {
  auto t = pr.fresh();
  if (!t) return Error{"storm: cannot rebuild the terrain"};
  const Heightfield& hf = t->heightfield();
  ModeResult r;
  r.mode = "uniform_grid";
  const UniformGrid g = UniformGrid::for_triangles(hf, target);
  std::vector<glm::dvec3> verts = g.vertices(hf);
  std::string err;
  std::size_t resampled = 0;
  run_mode(
      hf, path.frames, o,
      [&](std::size_t k) {
        auto e = storm_edit(*t, path.frames[k], k, r);
        if (!e) {
          err = e.error().message;
          return;
        }
        const auto t1 = Clock::now();
        if (const auto& c = *e)
          resampled +=
              g.resample(hf, verts, double(c->i0), double(c->j0), double(c->i1), double(c->j1));
        r.ms.push_back(ms_since(t1));
        r.tris.push_back(double(g.triangles()));
        r.changes.push_back(0);
        r.mem.push_back(double(g.memory_bytes()));
      },
      [&](const Camera&, bool) { return g.mesh_of(verts); }, r);
  if (!err.empty()) return Error{err};
  r.extra["target_triangles"] = target;
  r.extra["matched_ratio"] = double(g.triangles()) / std::max(1.0, target);
  r.extra["grid_quads"] = {g.nx, g.nz};
  r.extra["vertices_resampled"] = resampled;
  return r;
}

Result<ModeResult> storm_cdlod(Scene& base, const Pristine& pr, const NamedPath& path,
                               double target, const Options& o) {
  const CdlodChoice ch = calibrate_cdlod(base, path, target);  // on the unedited terrain
  auto t = pr.fresh();
  if (!t) return Error{"storm: cannot rebuild the terrain"};
  const Heightfield& hf = t->heightfield();
  Cdlod cd(hf, ch.grid);
  ModeResult r;
  r.mode = "cdlod";
  r.has_morph = true;
  Cdlod::Selection sel;
  std::string err;
  run_mode(
      hf, path.frames, o,
      [&](std::size_t k) {
        auto e = storm_edit(*t, path.frames[k], k, r);
        if (!e) {
          err = e.error().message;
          return;
        }
        const auto t1 = Clock::now();
        if (const auto& c = *e) cd.refresh(c->i0, c->j0, c->i1, c->j1);
        sel = cd.select(path.frames[k], ch.r0);
        r.ms.push_back(ms_since(t1));
        r.tris.push_back(double(sel.triangles));
        r.changes.push_back(0);  // not counted in the storm
        r.mem.push_back(double(cd.memory_bytes()));
      },
      [&](const Camera& c, bool morph) { return cd.mesh(sel, c, morph); }, r);
  if (!err.empty()) return Error{err};
  r.extra["target_triangles"] = target;
  r.extra["matched_ratio"] = quantile(r.tris, 0.5) / std::max(1.0, target);
  r.extra["chunk_grid"] = ch.grid;
  r.extra["r0_m"] = ch.r0;
  return r;
}

// Craters every frame (Terrain::apply_edit) while the camera flies, on a fresh copy of `base`
// for every mode; thresholds only, flyover and drive.
Result<Json> run_storm(Scene& base, const Options& o, std::string& csv_out) {
  const auto t0 = Clock::now();
  const Pristine pr = pristine_of(base.terrain->heightfield());
  std::string csv;
  const std::string name = "storm_" + base.name;
  Json paths = Json::array();
  for (const NamedPath& p : report::make_paths(*base.terrain, o.frames)) {
    if (p.name != "flyover" && p.name != "drive") continue;
    Json rows = Json::array();
    for (double th : o.thresholds) {
      const Setting st{"threshold", th};
      auto coherent = storm_roam(pr, p, st, RoamMode::kCoherent, o);
      if (!coherent) return coherent.error();
      auto rebuild = storm_roam(pr, p, st, RoamMode::kRebuild, o);
      if (!rebuild) return rebuild.error();
      const double target = quantile(coherent->tris, 0.5);
      auto uniform = storm_uniform(pr, p, target, o);
      if (!uniform) return uniform.error();
      auto cdlod = storm_cdlod(base, pr, p, target, o);
      if (!cdlod) return cdlod.error();
      Json mj = Json::array();
      const std::string prefix = name + "," + p.name + ",threshold," + csv_number(th);
      for (const ModeResult* m : {&*coherent, &*rebuild, &*uniform, &*cdlod}) {
        mj.push_back(m->json());
        csv += m->csv(prefix);
      }
      rows.push_back({{"kind", "threshold"}, {"value", th}, {"modes", mj}});
      std::fprintf(stderr, "ridge report: %s %s threshold %g done (%.1f s)\n", name.c_str(),
                   p.name.c_str(), th, ms_since(t0) / 1000);
    }
    paths.push_back({{"name", p.name}, {"frames", p.frames.size()}, {"settings", rows}});
  }
  csv_out += csv;
  const Heightfield& hf = base.terrain->heightfield();
  return Json{{"name", name},
              {"source", base.source + ", a crater every frame (apply_edit) where the view ray "
                                       "meets the ground, radius 6-12 m, depth 2 m"},
              {"samples", {hf.width(), hf.height()}},
              {"spacing_m", {hf.spacing_x(), hf.spacing_z()}},
              {"paths", paths},
              {"wall_s", ms_since(t0) / 1000}};
}

// One scene: every path (or the chosen ones) and every setting; appends CSV rows.
Result<Json> run_scene(Scene& sc, const Options& o, const std::vector<Setting>& settings,
                       std::string& csv_out) {
  const auto t0 = Clock::now();
  std::string csv;  // appended to csv_out only when the whole scene ran
  const Heightfield& hf = sc.terrain->heightfield();
  Json j = {{"name", sc.name},
            {"source", sc.source},
            {"samples", {hf.width(), hf.height()}},
            {"spacing_m", {hf.spacing_x(), hf.spacing_z()}},
            {"origin_m", {hf.origin_x(), hf.origin_z()}},
            {"height_range_m",
             {hf.height_offset() + hf.min_local(), hf.height_offset() + hf.max_local()}},
            {"filled_samples", hf.filled_samples()},
            {"loader", sc.loader},
            {"loader_messages", sc.messages}};
  if (sc.fine) {
    j["detail"] = sc.detail;
    j["measured_lattice"] = {sc.fine->width(), sc.fine->height()};
    j["measured_lattice_spacing_m"] = {sc.fine->spacing_x(), sc.fine->spacing_z()};
  }
  j["error_stride"] = o.stride;
  Json paths = Json::array();
  for (const NamedPath& p : report::make_paths(*sc.terrain, o.frames)) {
    if (!o.paths.empty() && std::find(o.paths.begin(), o.paths.end(), p.name) == o.paths.end())
      continue;
    Json pj = {{"name", p.name}, {"frames", p.frames.size()}};
    Json rows = Json::array();
    for (const Setting& st : settings) {
      auto coherent = run_roam(sc, p, st, RoamMode::kCoherent, o);
      if (!coherent) return coherent.error();
      auto rebuild = run_roam(sc, p, st, RoamMode::kRebuild, o);
      if (!rebuild) return rebuild.error();
      const double target = quantile(coherent->tris, 0.5);
      const ModeResult modes[4] = {*coherent, *rebuild, run_uniform(sc, p, target, o),
                                   run_cdlod(sc, p, target, o)};
      Json mj = Json::array();
      const std::string prefix =
          sc.name + "," + p.name + "," + st.kind + "," + csv_number(st.value);
      for (const ModeResult& m : modes) {
        mj.push_back(m.json());
        csv += m.csv(prefix);
      }
      rows.push_back({{"kind", st.kind}, {"value", st.value}, {"modes", mj}});
      std::fprintf(stderr, "ridge report: %s %s %s %g done (%.1f s)\n", sc.name.c_str(),
                   p.name.c_str(), st.kind.c_str(), st.value, ms_since(t0) / 1000);
    }
    pj["settings"] = rows;
    paths.push_back(pj);
  }
  j["paths"] = paths;
  j["wall_s"] = ms_since(t0) / 1000;
  csv_out += csv;
  return j;
}

Result<std::shared_ptr<const Landscape>> landscape_of(std::shared_ptr<const Terrain> t) {
  return Landscape::create(std::move(t), {.patch_exponent = 6});
}

// Fills a scene from a heightfield load result; a refused load yields a scene without terrain.
Status finish_scene(Scene& sc, Result<Heightfield> hf) {
  if (!hf) {
    sc.messages.push_back("refused: " + hf.error().message);
    return Status{};
  }
  sc.terrain = Terrain::create(std::move(*hf));
  auto l = landscape_of(sc.terrain);
  if (!l) return l.error();
  sc.landscape = *l;
  return Status{};
}

// Synthetic fields for the smoke run and the hard cases.
std::vector<float> synthetic(std::uint32_t n, int kind) {
  std::vector<float> v(std::size_t(n) * n);
  for (std::uint32_t j = 0; j < n; ++j)
    for (std::uint32_t i = 0; i < n; ++i) {
      const double x = double(i) / (n - 1), z = double(j) / (n - 1);
      double h = 60 * std::sin(6.1 * x) * std::cos(4.3 * z) + 25 * std::sin(23 * x + 17 * z) +
                 8 * std::sin(71 * x) * std::sin(53 * z) + 100;
      if (kind == 1) h = (i >= n / 2 ? 1000.0 : 0.0) + 0.05 * h;  // a 1,000 m cliff
      if (kind == 2) h = 0;                                       // flat
      v[i + std::size_t(j) * n] = static_cast<float>(h);
    }
  return v;
}

Scene synthetic_scene(const std::string& name, std::uint32_t n, int kind, double origin,
                      double spacing) {
  Scene sc;
  sc.name = name;
  sc.source = "synthetic (in memory)";
  HeightfieldDesc d;
  d.width = d.height = n;
  d.spacing_x = d.spacing_z = spacing;
  d.origin_x = d.origin_z = origin;
  d.name = name;
  const auto v = synthetic(n, kind);
  (void)finish_scene(sc, Heightfield::create(d, v));
  return sc;
}

// The procedural-detail world: the default terrain at `size` x `size` samples (2 m) with
// `levels` detail levels (docs/detail.md; default parameters otherwise), tiles generated
// asynchronously by one worker thread under the default 256 MiB budget, as in a game. The
// full-detail surface is also baked into a heightfield of the finest lattice: the error is
// measured against it, and the comparators draw from it (a CDLOD or grid renderer would need
// the detail baked into its height texture: counted in their memory).
Result<Scene> detail_scene(std::uint32_t size, std::uint32_t levels) {
  DefaultTerrainParams dp;
  dp.size = size;
  auto base = make_default_heightfield(dp);
  if (!base) return base.error();
  const Pristine pr = pristine_of(*base);
  DetailParams params;
  params.levels = levels;
  DetailCacheDesc cache;
  cache.worker_threads = 1;
  auto make = [pr, params, cache]()
      -> Result<std::pair<std::shared_ptr<const Terrain>, std::shared_ptr<const Landscape>>> {
    auto hf = Heightfield::create(pr.desc, pr.local);
    if (!hf) return hf.error();
    auto t = Terrain::create(std::move(*hf), params, cache);
    if (!t) return t.error();
    std::shared_ptr<const Terrain> ct = std::move(*t);
    auto l = landscape_of(ct);
    if (!l) return l.error();
    return std::make_pair(ct, *l);
  };
  Scene sc;
  sc.name = "detail" + std::to_string(size);
  sc.source = "default terrain " + std::to_string(size) + " x " + std::to_string(size) +
              " (2 m) with " + std::to_string(levels) + " procedural detail levels";
  auto first = make();
  if (!first) return first.error();
  sc.terrain = first->first;
  sc.landscape = first->second;
  sc.fresh = make;
  const auto t0 = Clock::now();
  const Terrain& t = *sc.terrain;
  const Heightfield& stored = t.heightfield();
  HeightfieldDesc d;
  d.width = static_cast<std::uint32_t>(t.fine_width());
  d.height = static_cast<std::uint32_t>(t.fine_height());
  d.spacing_x = stored.spacing_x() / double(1u << levels);
  d.spacing_z = stored.spacing_z() / double(1u << levels);
  d.origin_x = stored.origin_x();
  d.origin_z = stored.origin_z();
  d.height_offset = stored.height_offset();
  d.name = sc.name + " finest lattice";
  std::vector<float> v(std::size_t(d.width) * d.height);
  for (std::uint32_t j = 0; j < d.height; ++j)
    for (std::uint32_t i = 0; i < d.width; ++i)
      v[i + std::size_t(j) * d.width] = static_cast<float>(t.fine_local_height(i, j));
  auto fine = Heightfield::create(d, v);
  if (!fine) return fine.error();
  sc.fine = std::make_shared<const Heightfield>(std::move(*fine));
  sc.detail = {{"levels", levels},
               {"seed", params.seed},
               {"amplitude_m", params.amplitude},
               {"gain", params.gain},
               {"finest_spacing_m", {d.spacing_x, d.spacing_z}},
               {"cache_budget_bytes", cache.budget_bytes},
               {"cache_worker_threads", cache.worker_threads},
               {"field_bytes", t.detail()->memory_bytes()},
               {"baked_lattice_bytes", sc.fine->memory_bytes()},
               {"bake_s", ms_since(t0) / 1000},
               {"comparators",
                "the uniform grid and CDLOD draw from the full-detail surface baked into a "
                "heightfield of the finest lattice (their memory counts it as CDLOD's height "
                "texture); ROAM streams detail tiles from a fresh cold cache in every run"},
               {"geomorph_popping",
                "not measured for ROAM here: its drawn mesh is read from the bintree leaves, "
                "because building patch meshes (full-detail normals) for every measured frame "
                "cost minutes per setting"}};
  return sc;
}

template <class T>
Status write_raw(const std::filesystem::path& p, const std::vector<T>& v) {
  std::ofstream f(p, std::ios::binary);
  f.write(reinterpret_cast<const char*>(v.data()), std::streamsize(v.size() * sizeof(T)));
  if (!f) return Error{"cannot write " + p.string()};
  return Status{};
}

// The loader hard cases: files written here, read back through Ridgeline::io's raw loader.
Result<std::vector<Scene>> loader_cases(const std::filesystem::path& dir, std::uint32_t n) {
  std::vector<Scene> out;
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  const auto base = synthetic(n, 0);
  auto load = [&](const std::string& name, const std::filesystem::path& file, io::RawType type,
                  std::optional<double> scale, bool fill) -> Status {
    Scene sc;
    sc.name = name;
    sc.source = file.filename().string();
    io::LoadOptions lo;
    lo.placement.name = name;
    if (scale) lo.placement.height_scale = *scale;
    if (fill) lo.placement.fill = FillPolicy::kNearest;
    sc.loader = {{"raw", type == io::RawType::kU16 ? "u16" : "f32"},
                 {"size", {n, n}},
                 {"fill", fill ? "nearest" : "refuse"},
                 {"height_scale", lo.placement.height_scale}};
    Captured cap;
    set_log_sink(capture_sink, &cap);
    const io::RawFormat rf{n, n, type};
    auto hf = io::load_raw(file.string(), rf, lo);
    install_log_sink();
    sc.messages = cap.lines;
    if (hf) {
      sc.messages.push_back("loaded: " + std::to_string(hf->filled_samples()) + " samples filled");
    }
    if (auto s = finish_scene(sc, std::move(hf)); !s) return s;
    out.push_back(std::move(sc));
    return Status{};
  };
  {  // saturated 16-bit: half the samples at 65535, half at 0
    std::vector<std::uint16_t> v(base.size());
    for (std::size_t k = 0; k < v.size(); ++k) v[k] = (k % n) >= n / 2 ? 65535 : 0;
    const auto f = dir / "saturated_u16.raw";
    if (auto s = write_raw(f, v); !s) return Error{s.message()};
    if (auto s = load("saturated_u16", f, io::RawType::kU16, 0.01, false); !s)
      return Error{s.message()};
  }
  {  // non-finite floats: NaN, +inf and -inf samples
    std::vector<float> v = base;
    v[n * 3 + 5] = std::nanf("");
    v[n * (n / 2) + n / 2] = std::numeric_limits<float>::infinity();
    v[n * (n - 4) + 7] = -std::numeric_limits<float>::infinity();
    const auto f = dir / "nonfinite_f32.raw";
    if (auto s = write_raw(f, v); !s) return Error{s.message()};
    if (auto s = load("nonfinite_f32_refuse", f, io::RawType::kF32, std::nullopt, false); !s)
      return Error{s.message()};
    if (auto s = load("nonfinite_f32_fill_nearest", f, io::RawType::kF32, std::nullopt, true); !s)
      return Error{s.message()};
  }
  {  // saturated floats: +-3e38 (finite, near FLT_MAX)
    std::vector<float> v(base.size());
    for (std::size_t k = 0; k < v.size(); ++k) v[k] = (k % n) >= n / 2 ? 3e38f : -3e38f;
    const auto f = dir / "huge_f32.raw";
    if (auto s = write_raw(f, v); !s) return Error{s.message()};
    if (auto s = load("huge_f32", f, io::RawType::kF32, std::nullopt, false); !s)
      return Error{s.message()};
  }
  return out;
}

// ---- the command ------------------------------------------------------------------------

struct ReportArgs {
  bool smoke = false;
  std::string skip;  // comma-separated: detail, storm, hard
  std::string out = "docs/benchmarks/report", noise, dem, dem_spacing = "598,927", dem_nodata,
              frames, error_every, paths, work;
};

int run_report(const ReportArgs& a) {
  const auto t0 = Clock::now();
  Options o;
  if (a.smoke) {
    o.frames = 12;
    o.error_every = 3;
    o.thresholds = {2, 8};
    o.triangle_caps = {2000};
    o.time_budgets = {1};
  }
  if (!a.frames.empty()) {
    auto f = parse_count(a.frames, "--frames", 3, 100000);
    if (!f) return report_error(f.error().message);
    o.frames = int(*f);
  }
  if (!a.error_every.empty()) {
    auto k = parse_count(a.error_every, "--error-every", 2, 100000);
    if (!k) return report_error(k.error().message);
    o.error_every = int(*k);
  }
  if (o.frames <= o.error_every)
    return report_error(
        "--frames must exceed --error-every (errors are measured every K-th frame)");
  if (!a.paths.empty()) {
    std::stringstream ss(a.paths);
    for (std::string p; std::getline(ss, p, ',');) {
      static const char* known[] = {"flyover", "drive", "fast_yaw", "zoom", "down", "fast_pass"};
      if (std::find_if(std::begin(known), std::end(known), [&](const char* k) { return p == k; }) ==
          std::end(known))
        return report_error("--paths: unknown path '" + p +
                            "' (flyover, drive, fast_yaw, zoom, down, fast_pass)");
      o.paths.push_back(p);
    }
  }
  std::vector<std::string> skip;
  {
    std::stringstream ss(a.skip);
    for (std::string p; std::getline(ss, p, ',');) {
      if (p != "detail" && p != "storm" && p != "hard")
        return report_error("--skip: unknown part '" + p + "' (detail, storm, hard)");
      skip.push_back(p);
    }
  }
  auto skips = [&](const char* part) {
    return std::find(skip.begin(), skip.end(), part) != skip.end();
  };
  std::vector<Setting> settings;
  for (double t : o.thresholds) settings.push_back({"threshold", t});
  for (double n : o.triangle_caps) settings.push_back({"triangles", n});
  for (double b : o.time_budgets) settings.push_back({"time_ms", b});

  std::vector<Scene> scenes;
  if (a.smoke) {
    scenes.push_back(synthetic_scene("synthetic129", 129, 0, 0.0, 4.0));
  } else {
    if (a.noise.empty() && a.dem.empty() && skips("detail"))
      return report_error("give --noise FILE and/or --dem FILE (or --smoke)");
    if (!a.noise.empty()) {
      Scene sc;
      sc.name = "noise1025";
      sc.source = a.noise;
      io::LoadOptions lo;
      lo.placement.spacing_x = lo.placement.spacing_z = 1.0;
      lo.placement.height_scale = 0.005;
      sc.loader = {{"spacing", {1, 1}}, {"height_scale", 0.005}};
      Captured cap;
      set_log_sink(capture_sink, &cap);
      auto hf = io::load_heightmap(a.noise, lo);
      install_log_sink();
      if (!hf) return report_error(hf.error().message);
      sc.messages = cap.lines;
      if (auto s = finish_scene(sc, std::move(hf)); !s) return report_error(s.message());
      scenes.push_back(std::move(sc));
    }
    if (!a.dem.empty()) {
      auto sp = parse_finite_list(a.dem_spacing, "--dem-spacing", 2, 2);
      if (!sp) return report_error(sp.error().message);
      if ((*sp)[0] <= 0 || (*sp)[1] <= 0) return report_error("--dem-spacing must be > 0");
      Scene sc;
      sc.name = "elev_lux";
      sc.source = a.dem;
      io::LoadOptions lo;
      lo.placement.spacing_x = (*sp)[0];
      lo.placement.spacing_z = (*sp)[1];
      lo.placement.fill = FillPolicy::kNearest;
      sc.loader = {
          {"spacing", *sp},
          {"nodata", a.dem_nodata.empty() ? "from the file's GDAL_NODATA tag" : a.dem_nodata},
          {"fill", "nearest"}};
      Captured cap;
      set_log_sink(capture_sink, &cap);
      // As a user would load it: first plain (the loader takes the no-data value from the
      // file's GDAL_NODATA tag and refuses the missing samples without a fill policy), then
      // with --fill nearest (what the report uses).
      if (!a.dem_nodata.empty()) {
        auto nd = parse_finite(a.dem_nodata, "--dem-nodata");
        if (!nd) return report_error(nd.error().message);
        lo.placement.nodata = *nd;
      }
      lo.placement.fill = FillPolicy::kRefuse;
      if (auto r = io::load_heightmap(a.dem, lo); !r)
        cap.lines.push_back("without --fill: " + r.error().message);
      else
        cap.lines.push_back("without --fill: loaded, heights " + std::to_string(r->min_local()) +
                            " .. " + std::to_string(r->max_local()) + " m");
      lo.placement.fill = FillPolicy::kNearest;
      auto hf = io::load_heightmap(a.dem, lo);
      install_log_sink();
      if (!hf) return report_error(hf.error().message);
      cap.lines.push_back("with --fill nearest: " + std::to_string(hf->filled_samples()) +
                          " samples filled");
      sc.messages = cap.lines;
      if (auto s = finish_scene(sc, std::move(hf)); !s) return report_error(s.message());
      scenes.push_back(std::move(sc));
    }
  }

  std::string csv;
  Json out_scenes = Json::array();
  for (Scene& sc : scenes) {
    auto j = run_scene(sc, o, settings, csv);
    if (!j) return report_error(sc.name + ": " + j.error().message);
    out_scenes.push_back(*j);
  }
  // The procedural-detail world (thresholds only): measured against the finest lattice on a
  // fixed stratified sample (every 2nd vertex along each axis, SPEC.md) in the full report.
  if (!skips("detail")) {
    auto sc = a.smoke ? detail_scene(65, 2) : detail_scene(129, 2);
    if (!sc) return report_error("detail scene: " + sc.error().message);
    Options dopt = o;
    dopt.stride = 1;
    // Three thresholds (1, 4, 16 px; smoke: its own), to keep the full report within 30 min.
    std::vector<Setting> ds;
    for (double t : a.smoke ? o.thresholds : std::vector<double>{1, 4, 16})
      ds.push_back({"threshold", t});
    auto j = run_scene(*sc, dopt, ds, csv);
    if (!j) return report_error(sc->name + ": " + j.error().message);
    out_scenes.push_back(*j);
  }
  // The deformation storm on the first scene (the noise field; the smoke field with --smoke).
  if (!scenes.empty() && !skips("storm")) {
    auto j = run_storm(scenes.front(), o, csv);
    if (!j) return report_error("storm: " + j.error().message);
    out_scenes.push_back(*j);
  }

  // Numerical hard cases: one setting (2 px), flyover and drive, every mode.
  Options ho = o;
  ho.frames = a.smoke ? 12 : 60;
  ho.paths = {"flyover", "drive"};
  const std::vector<Setting> hs = {{"threshold", 2.0}};
  const std::uint32_t hn = a.smoke ? 65 : 257;
  std::vector<Scene> hard;
  if (!skips("hard")) {
    hard.push_back(synthetic_scene("origin_0", hn, 0, 0.0, 4.0));
    hard.push_back(synthetic_scene("origin_1e6", hn, 0, 1e6, 4.0));
    hard.push_back(synthetic_scene("origin_1e7", hn, 0, 1e7, 4.0));
    hard.push_back(synthetic_scene("cliff_1000m", hn, 1, 0.0, 4.0));
    hard.push_back(synthetic_scene("flat", hn, 2, 0.0, 4.0));
    const std::filesystem::path work = a.work.empty()
                                           ? std::filesystem::temp_directory_path() / "ridge_report"
                                           : std::filesystem::path(a.work);
    auto lc = loader_cases(work, hn);
    if (!lc) return report_error(lc.error().message);
    for (auto& s : *lc) hard.push_back(std::move(s));
  }
  Json out_hard = Json::array();
  for (Scene& sc : hard) {
    if (!sc.terrain) {  // the loader refused it: that is the result
      out_hard.push_back({{"name", sc.name},
                          {"source", sc.source},
                          {"loader", sc.loader},
                          {"loader_messages", sc.messages},
                          {"loaded", false}});
      continue;
    }
    auto j = run_scene(sc, ho, hs, csv);
    if (!j) {
      out_hard.push_back({{"name", sc.name},
                          {"loader_messages", sc.messages},
                          {"loaded", true},
                          {"run_error", j.error().message}});
      continue;
    }
    (*j)["loaded"] = true;
    out_hard.push_back(*j);
  }

  Json root = {{"report", "ridge report"},
               {"smoke", a.smoke},
               {"machine", {{"hardware_threads", std::thread::hardware_concurrency()}}},
               {"frames_per_path", o.frames},
               {"error_every", o.error_every},
               {"error_stride", o.stride},
               {"match_tolerance", kMatchTolerance},
               {"settings",
                {{"thresholds_px", o.thresholds},
                 {"triangle_caps", o.triangle_caps},
                 {"time_budgets_ms", o.time_budgets},
                 {"time_budget_threshold_px", 1.0}}},
               {"scenes", out_scenes},
               {"hard_cases", out_hard},
               {"wall_s", ms_since(t0) / 1000}};
  std::error_code ec;
  std::filesystem::create_directories(a.out, ec);
  if (auto s = write_json(root, (std::filesystem::path(a.out) / "report.json").string()); !s)
    return report_error(s.message());
  if (auto s = write_output(csv, (std::filesystem::path(a.out) / "report.csv").string()); !s)
    return report_error(s.message());
  std::fprintf(stderr, "ridge report: wrote %s/report.json and report.csv in %.1f s\n",
               a.out.c_str(), ms_since(t0) / 1000);
  return 0;
}

}  // namespace

Command add_report_command(CLI::App& parent) {
  auto* app = parent.add_subcommand(
      "report",
      "Speed versus error: ROAM (coherent, rebuild), a uniform grid and a CDLOD-like quadtree "
      "over thresholds, triangle caps and time budgets, every scene and camera path, in one run "
      "(JSON + CSV; docs/report.md)");
  auto a = std::make_shared<ReportArgs>();
  app->add_flag("--smoke", a->smoke,
                "A tiny synthetic scene, 12 frames per path, 2 thresholds (for CI)");
  app->add_option("--skip", a->skip,
                  "Leave out parts of the report (comma-separated: detail, storm, hard)")
      ->type_name("LIST");
  app->add_option("--out", a->out, "Output directory (default docs/benchmarks/report)")
      ->type_name("DIR");
  app->add_option("--noise", a->noise,
                  "The 1025 x 1025 noise field of make-noise-field (spacing 1, scale 0.005)")
      ->type_name("FILE.png");
  app->add_option("--dem", a->dem,
                  "A real DEM (elev.tif of r-cran-terra); no-data (its GDAL tag) filled nearest")
      ->type_name("FILE");
  app->add_option("--dem-spacing", a->dem_spacing,
                  "The DEM's cell size in metres (default 598,927: elev.tif's 1/120 degree at "
                  "49.8 N)")
      ->type_name("SX,SZ");
  app->add_option("--dem-nodata", a->dem_nodata,
                  "The DEM's no-data value (default: the file's GDAL_NODATA tag, -32768 in "
                  "elev.tif, which the image loader reads)")
      ->type_name("V");
  app->add_option("--frames", a->frames, "Frames per path (default 60; smoke 12)")->type_name("N");
  app->add_option("--error-every", a->error_every,
                  "Measure error and popping every K-th frame (default 6; smoke 3)")
      ->type_name("K");
  app->add_option("--paths", a->paths, "Only these paths (comma-separated)")->type_name("LIST");
  app->add_option("--work", a->work, "Directory for the loader hard cases' files (default: temp)")
      ->type_name("DIR");
  return {app, [a] { return run_report(*a); }};
}

}  // namespace ridgeline::cli
