// `ridge mesh` (converge a ROAM mesh for one view and export it as .glb) and `ridge bench lod`
// (run a camera path and report per-frame cost and error as JSON).
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "cli_util.h"
#include "commands.h"
#include "ridgeline/bench/clock.h"
#include "ridgeline/bench/summary.h"
#include "ridgeline/bench/techniques.h"
#include "ridgeline/camera_path.h"
#include "ridgeline/gltf_export.h"
#include "ridgeline/roam_view.h"
#include "terrain_args.h"

namespace ridgeline::cli {

namespace {

// Flags shared by mesh and bench lod: the landscape and the LOD settings.
struct LodArgs {
  TerrainArgs terrain;
  std::string patch_exponent = "6", threshold, triangles, tolerance, budget_ms, mode = "coherent",
              morph_window, morph_delay;
  std::string json_path;

  void add_to(CLI::App& app) {
    terrain.add_to(app);
    auto* g = app.add_option_group("Level of detail");
    g->add_option("--patch-exponent", patch_exponent,
                  "Patches of 2^K cells per side, K in 2..10 (default 6: 65 x 65 samples)")
        ->type_name("K");
    g->add_option("--threshold", threshold, "Detail threshold in screen pixels")->type_name("PX");
    g->add_option("--triangles", triangles,
                  "Hard cap on leaf triangles (alone: the best mesh of at most N triangles)")
        ->type_name("N");
    g->add_option("--tolerance", tolerance,
                  "View-independent mode: every triangle within METRES of the samples under it; "
                  "whole terrain, no culling")
        ->type_name("METRES");
    g->add_option("--budget-ms", budget_ms, "Time budget per update, milliseconds")
        ->type_name("MS");
    g->add_option("--mode", mode,
                  "coherent (the mesh carried over, split and merged) or rebuild (built from the "
                  "roots every update); bench lod also soar (the stateless SOAR comparator)")
        ->type_name("MODE");
    g->add_option("--morph-window", morph_window,
                  "Geomorph window w, 0..4 (default 0.2; 0: no geomorphs, no morph nesting)")
        ->type_name("W");
    g->add_option("--morph-delay", morph_delay,
                  "Geomorph delay, 0..1 (default 0.1): a new vertex stays on its edge until its "
                  "bound projects to (1 + delay) x the threshold")
        ->type_name("D");
    app.add_option("--json", json_path, "Write the JSON to FILE instead of standard output")
        ->type_name("FILE");
    // Without any of the three there is nothing to tessellate for: a usage error (exit 2).
    app.callback([this] {
      if (threshold.empty() && triangles.empty() && tolerance.empty())
        throw CLI::RequiredError("give --threshold PX, --triangles N or --tolerance METRES",
                                 CLI::ExitCodes::RequiredError);
    });
  }

  Result<RoamSettings> settings() const {
    RoamSettings s;
    if (!threshold.empty() + !triangles.empty() + !tolerance.empty() == 0)
      return Error{"give --threshold PX, --triangles N or --tolerance METRES"};
    if (!tolerance.empty() && !threshold.empty())
      return Error{
          "--tolerance (metres, view independent) and --threshold (pixels) exclude "
          "each other"};
    if (!threshold.empty()) {
      auto t = parse_finite(threshold, "--threshold");
      if (!t) return t.error();
      if (*t < 0) return Error{"--threshold must be >= 0"};
      s.threshold = *t;
    } else if (!tolerance.empty()) {
      auto t = parse_finite(tolerance, "--tolerance");
      if (!t) return t.error();
      if (*t < 0) return Error{"--tolerance must be >= 0"};
      s.threshold = *t;
      s.metric = ErrorMetric::kWorldMetres;
    } else {
      s.threshold = 0.0;  // only the triangle cap limits refinement
    }
    if (!triangles.empty()) {
      auto n = parse_count(triangles, "--triangles", 1, 0xffffffffu);
      if (!n) return n.error();
      s.max_triangles = static_cast<std::uint32_t>(*n);
    }
    if (!budget_ms.empty()) {
      auto b = parse_finite(budget_ms, "--budget-ms");
      if (!b) return b.error();
      if (*b < 0) return Error{"--budget-ms must be >= 0"};
      s.budget_ms = *b;
    }
    if (mode == "coherent")
      s.mode = RoamMode::kCoherent;
    else if (mode == "rebuild")
      s.mode = RoamMode::kRebuild;
    else
      return Error{"--mode '" + mode + "': need coherent or rebuild"};
    return s;
  }

  Result<std::unique_ptr<RoamView>> view(double* bounds_ms, std::size_t* bound_bytes) const {
    auto s = settings();
    if (!s) return s.error();
    auto k = parse_count(patch_exponent, "--patch-exponent", 2, 10);
    if (!k) return k.error();
    auto t = terrain.load_terrain();
    if (!t) return t.error();
    LandscapeDesc desc{.patch_exponent = static_cast<std::uint32_t>(*k)};
    if (!morph_window.empty()) {
      auto w = parse_finite(morph_window, "--morph-window");
      if (!w) return w.error();
      desc.morph_window = *w;
    }
    if (!morph_delay.empty()) {
      auto d = parse_finite(morph_delay, "--morph-delay");
      if (!d) return d.error();
      desc.morph_delay = *d;
    }
    auto l = Landscape::create(*t, desc);
    if (!l) return l.error();
    *bounds_ms = (*l)->build_ms();
    *bound_bytes = (*l)->bound_bytes();
    return RoamView::create(*l, *s);
  }
};

nlohmann::ordered_json stats_json(const RoamStats& s) {
  return {{"triangles", s.triangles},
          {"splits", s.splits},
          {"forced_splits", s.forced_splits},
          {"merges", s.merges},
          {"priority_updates", s.priority_updates},
          {"update_ms", s.update_ms},
          {"stopped_by", stop_reason_name(s.stop)},
          {"rebuilt", s.rebuilt},
          {"max_remaining_error", s.max_remaining_error},
          {"memory_bytes", s.memory_bytes},
          {"output_bytes", s.output_bytes}};
}

// ---- ridge mesh ---------------------------------------------------------------------------

struct MeshArgs {
  LodArgs lod;
  std::string eye, target, up = "0,1,0", fov = "60", viewport = "1280,720", far = "50000", out;
};

int run_mesh(const MeshArgs& a) {
  Camera c;
  const bool tolerance = !a.lod.tolerance.empty();
  if (!tolerance || !a.eye.empty()) {
    if (a.eye.empty() || a.target.empty())
      return report_usage("give --eye X,Y,Z and --target X,Y,Z (or --tolerance alone)");
    auto e = parse_finite_list(a.eye, "--eye", 3, 3);
    if (!e) return report_error(e.error().message);
    auto t = parse_finite_list(a.target, "--target", 3, 3);
    if (!t) return report_error(t.error().message);
    auto u = parse_finite_list(a.up, "--up", 3, 3);
    if (!u) return report_error(u.error().message);
    auto f = parse_finite(a.fov, "--fov-y");
    if (!f) return report_error(f.error().message);
    auto vp = parse_finite_list(a.viewport, "--viewport", 2, 2);
    if (!vp) return report_error(vp.error().message);
    auto fa = parse_finite(a.far, "--far");
    if (!fa) return report_error(fa.error().message);
    c.eye = {(*e)[0], (*e)[1], (*e)[2]};
    c.target = {(*t)[0], (*t)[1], (*t)[2]};
    c.up = {(*u)[0], (*u)[1], (*u)[2]};
    c.fov_y_deg = *f;
    if ((*vp)[0] < 1 || (*vp)[1] < 1 || (*vp)[0] > 65536 || (*vp)[1] > 65536)
      return report_error("--viewport: need W,H in 1 .. 65536");
    c.viewport = {int((*vp)[0]), int((*vp)[1])};
    c.far_m = *fa;
    if (auto s = validate_camera(c); !s) return report_error(s.message());
  }
  if (a.out.empty()) return report_error("give --out FILE.glb");
  double bounds_ms = 0;
  std::size_t bound_bytes = 0;
  auto view = a.lod.view(&bounds_ms, &bound_bytes);
  if (!view) return report_error(view.error().message);
  auto st = (*view)->converge(c);
  if (!st) return report_error(st.error().message);
  // Every finest-lattice vertex up to 4M of them; beyond (detail, huge fields) a fixed
  // stratified sample of every k-th vertex per axis (docs/surface.md, "Error and budgets"),
  // reported as measured_stride.
  const SurfaceLattice& at = (*view)->landscape().terrain().surface().lattice();
  const double verts = double(at.vertices_x) * double(at.vertices_z);
  const auto stride = static_cast<std::uint32_t>(std::max(1.0, std::ceil(std::sqrt(verts / 4e6))));
  const auto err = (*view)->measure_error(c, stride);
  io::GltfExportOptions go;
  if (auto s = io::write_glb(**view, a.out, go); !s) return report_error(s.message());
  const Landscape& l = (*view)->landscape();
  nlohmann::ordered_json j = stats_json(*st);
  j["out"] = a.out;
  j["patches"] = l.patch_count();
  j["bounds_build_ms"] = bounds_ms;
  j["bounds_bytes_per_sample"] =
      double(bound_bytes) /
      double(std::uint64_t{l.terrain().info().width} * l.terrain().info().height);
  j["measured_max_error_m"] = err.max_m;
  j["measured_rms_error_m"] = err.rms_m;
  j["measured_max_error_px"] = err.max_px;
  j["measured_vertices"] = err.vertices;
  j["measured_stride"] = stride;
  if (auto s = write_json(j, a.lod.json_path); !s) return report_error(s.message());
  return 0;
}

// ---- ridge bench lod ----------------------------------------------------------------------

struct BenchLodArgs {
  LodArgs lod;
  std::string path, error_every = "1", error_stride = "1", warmup = "0", repeat = "1",
              flush_mb = "0";
};

// The technique of --mode soar: the stateless SOAR comparator over the finest lattice (its
// preprocess reported as the bounds' build, like ROAM's), with the cap as the one kappa whose
// median count over the path is closest to N (calibrated untimed, on every 60th part of the path);
// with --threshold too, a frame uses the smaller of the two kappas.
struct SoarMode {
  std::unique_ptr<bench::Soar> soar;
  std::unique_ptr<bench::SoarTechnique> technique;
  double threshold = 0, preprocess_ms = 0;
  std::uint64_t cap = 0;
};

Result<SoarMode> soar_mode(const LodArgs& a, const std::vector<Camera>& cams,
                           std::shared_ptr<const Terrain>* terrain) {
  if (!a.budget_ms.empty())
    return Error{"--budget-ms: the soar mode has no time budget (one full pass a frame)"};
  if (a.threshold.empty() && a.triangles.empty())
    return Error{"give --threshold PX and/or --triangles N"};
  SoarMode m;
  if (!a.threshold.empty()) {
    auto th = parse_finite(a.threshold, "--threshold");
    if (!th) return th.error();
    if (*th < 0) return Error{"--threshold must be >= 0"};
    m.threshold = *th;
  }
  if (!a.triangles.empty()) {
    auto n = parse_count(a.triangles, "--triangles", 1, 0xffffffffu);
    if (!n) return n.error();
    m.cap = *n;
  }
  auto loaded = a.terrain.load_terrain();
  if (!loaded) return loaded.error();
  *terrain = *loaded;
  const Terrain& t = **terrain;
  const SurfaceLattice& at = t.surface().lattice();
  if (std::max(at.vertices_x, at.vertices_z) > std::int64_t{bench::Soar::kMaxSide})
    return Error{"--mode soar: the finest lattice is " + std::to_string(at.vertices_x) + " x " +
                 std::to_string(at.vertices_z) + " vertices; the comparator takes at most " +
                 std::to_string(bench::Soar::kMaxSide) + " per side"};
  const auto t0 = bench::Clock::now();
  auto fine = bench::finest_lattice(t);
  if (!fine) return fine.error();
  m.soar = std::make_unique<bench::Soar>(*fine);
  m.preprocess_ms = bench::ms_since(t0);
  double path_kappa = std::numeric_limits<double>::infinity();
  if (m.cap > 0)
    path_kappa =
        m.soar->match(cams, double(m.cap), std::max<std::size_t>(1, cams.size() / 60)).kappa;
  m.technique = std::make_unique<bench::SoarTechnique>(*m.soar, m.threshold, path_kappa);
  return m;
}

int run_bench_lod(const BenchLodArgs& a) {
  bench::keep_freed_memory();
  if (a.path.empty()) return report_error("give --path PATH.json");
  auto frames = io::load_camera_path(a.path);
  if (!frames) return report_error(frames.error().message);
  auto every = parse_count(a.error_every, "--error-every", 0, 1000000);
  if (!every) return report_error(every.error().message);
  auto stride = parse_count(a.error_stride, "--error-stride", 1, 1024);
  if (!stride) return report_error(stride.error().message);
  auto warmup = parse_count(a.warmup, "--warmup", 0, 10000000);
  if (!warmup) return report_error(warmup.error().message);
  auto repeat = parse_count(a.repeat, "--repeat", 1, 1000);
  if (!repeat) return report_error(repeat.error().message);
  auto flush_mb = parse_finite(a.flush_mb, "--flush-mb");
  if (!flush_mb) return report_error(flush_mb.error().message);
  if (*flush_mb < 0 || *flush_mb > 4096) return report_error("--flush-mb must be in 0..4096");
  std::vector<Camera> cams;
  for (const io::PathFrame& f : *frames) cams.push_back(f.camera);

  // The technique: ROAM (coherent or rebuild) or SOAR, and the settings it runs at.
  std::shared_ptr<const Terrain> terrain;
  std::unique_ptr<bench::RoamTechnique> roam;
  Result<SoarMode> soar = Error{""};
  bench::Technique* technique = nullptr;
  nlohmann::ordered_json summary;
  double bounds_ms = 0, budget_ms = 0;
  std::size_t bound_bytes = 0;
  if (a.lod.mode == "soar") {
    soar = soar_mode(a.lod, cams, &terrain);
    if (!soar) return report_error(soar.error().message);
    technique = soar->technique.get();
    summary = {{"mode", "soar"},
               {"threshold", soar->threshold},
               {"max_triangles", soar->cap},
               {"budget_ms", 0}};
    bounds_ms = soar->preprocess_ms;
    bound_bytes = soar->soar->memory_bytes();
  } else {
    auto view = a.lod.view(&bounds_ms, &bound_bytes);
    if (!view) return report_error(view.error().message);
    const RoamSettings s = (*view)->settings();
    terrain = (*view)->landscape().terrain_ptr();
    roam = std::make_unique<bench::RoamTechnique>(std::move(*view));
    technique = roam.get();
    budget_ms = s.budget_ms;
    summary = {{"mode", s.mode == RoamMode::kCoherent ? "coherent" : "rebuild"},
               {"threshold", s.threshold},
               {"max_triangles", s.max_triangles},
               {"budget_ms", s.budget_ms}};
  }

  // The frame loop: the warm-up (the path's first frames, not reported), the path `repeat`
  // times, the mesh measured every K-th frame on every S-th lattice vertex.
  bench::LoopOptions lo;
  lo.warmup = *warmup;
  lo.repeat = *repeat;
  lo.error_every = static_cast<std::uint32_t>(*every);
  lo.flush_mb = *flush_mb;
  lo.keep_frames = true;
  std::unique_ptr<MeshErrorMeter> meter;
  if (*every > 0) meter = std::make_unique<MeshErrorMeter>(*terrain, static_cast<std::uint32_t>(*stride));
  auto run = bench::run_path(*technique, cams, meter.get(), lo);
  if (!run) return report_error(run.error().message);

  bench::append(summary, bench::lod_figures(*run));
  summary["bounds_build_ms"] = bounds_ms;
  summary["bounds_bytes"] = bound_bytes;
  summary["error_every"] = *every;
  summary["error_stride"] = *stride;
  summary["flush_mb"] = *flush_mb;
  if (budget_ms > 0)
    bench::append(summary, bench::time_budget_figures(*run, budget_ms));
  nlohmann::ordered_json j = {{"summary", summary}, {"frames", run->frames}};
  if (auto st = write_json(j, a.lod.json_path); !st) return report_error(st.message());
  return 0;
}

}  // namespace

Command add_mesh_command(CLI::App& parent) {
  auto* app = parent.add_subcommand(
      "mesh", "Converge the ROAM mesh for one view and write it as glTF 2.0 binary (.glb)");
  auto a = std::make_shared<MeshArgs>();
  a->lod.add_to(*app);
  auto* g = app->add_option_group("Camera");
  g->add_option("--eye", a->eye, "Eye position")->type_name("X,Y,Z");
  g->add_option("--target", a->target, "Point looked at")->type_name("X,Y,Z");
  g->add_option("--up", a->up, "Up vector (default 0,1,0)")->type_name("X,Y,Z");
  g->add_option("--fov-y", a->fov, "Vertical field of view, degrees (default 60)")
      ->type_name("DEG");
  g->add_option("--viewport", a->viewport, "Viewport in pixels (default 1280,720)")
      ->type_name("W,H");
  g->add_option("--far", a->far, "Far plane, metres (default 50000)")->type_name("M");
  app->add_option("--out", a->out, "Output .glb file")->type_name("FILE.glb")->required();
  return {app, [a] { return run_mesh(*a); }};
}

Command add_bench_lod_command(CLI::App& bench) {
  auto* app = bench.add_subcommand(
      "lod", "Run a camera path: per-frame update ms, triangles, splits, merges and error (JSON)");
  auto a = std::make_shared<BenchLodArgs>();
  a->lod.add_to(*app);
  app->add_option("--path", a->path, "Camera path (PATH.json, docs/cli.md)")
      ->type_name("PATH.json")
      ->required();
  app->add_option("--error-every", a->error_every,
                  "Measure the mesh error every K-th frame (default 1; 0 = never)")
      ->type_name("K");
  app->add_option("--error-stride", a->error_stride,
                  "Measure every S-th lattice vertex along each axis (default 1 = all)")
      ->type_name("S");
  app->add_option("--warmup", a->warmup, "Unreported frames before the run (default 0)")
      ->type_name("N");
  app->add_option("--repeat", a->repeat, "Run the path N times (default 1)")->type_name("N");
  app->add_option("--flush-mb", a->flush_mb,
                  "Before each update, read and write M MiB of other memory: the rest of a "
                  "game's frame evicting the terrain's data from the caches (default 0)")
      ->type_name("M");
  return {app, [a] { return run_bench_lod(*a); }};
}

}  // namespace ridgeline::cli
