// `ridge mesh` (converge a ROAM mesh for one view and export it as .glb) and `ridge bench lod`
// (run a camera path and report per-frame cost and error as JSON).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <numeric>

#include "bench_soar.h"
#include "cli_util.h"
#include "commands.h"
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

// Leaves whose box (lattice extent, heights of the corners) meets the camera's frustum and that
// are drawn (not padding): the triangles a renderer that culls per triangle would draw.
std::uint64_t triangles_in_view(const RoamView& v, const Camera& c) {
  const Frustum f(c);
  const Surface& s = v.landscape().terrain().surface();
  const SurfaceLattice& at = s.lattice();
  const double off = at.height_offset;
  std::uint64_t n = 0;
  v.for_each_leaf([&](std::uint32_t, std::uint64_t, const LatticeTriangle& t) {
    const Landscape::LatticeBox b = Landscape::box_of(t);
    if (b.i0 >= at.vertices_x - 1 || b.j0 >= at.vertices_z - 1) return;  // padding, not drawn
    const double ha = double(float(s.vertex_height(t.ax, t.az))),
                 hl = double(float(s.vertex_height(t.lx, t.lz))),
                 hr = double(float(s.vertex_height(t.rx, t.rz)));
    const glm::dvec3 lo(at.origin_x + double(b.i0) * at.spacing_x, off + std::min({ha, hl, hr}),
                        at.origin_z + double(b.j0) * at.spacing_z);
    const glm::dvec3 hi(at.origin_x + double(b.i1) * at.spacing_x, off + std::max({ha, hl, hr}),
                        at.origin_z + double(b.j1) * at.spacing_z);
    n += f.classify_box(lo, hi) != Frustum::Cull::kOut;
  });
  return n;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(q * double(v.size())));
  return v[k];
}

int run_bench_lod(const BenchLodArgs& a) {
  keep_freed_memory();
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
  if (a.lod.mode == "soar")  // the stateless comparator (bench_soar.h)
    return run_bench_lod_soar({&a.lod.terrain, &*frames, a.lod.threshold, a.lod.triangles,
                               a.lod.budget_ms, *every, *stride, *warmup, *repeat, *flush_mb,
                               a.lod.json_path});
  double bounds_ms = 0;
  std::size_t bound_bytes = 0;
  auto view = a.lod.view(&bounds_ms, &bound_bytes);
  if (!view) return report_error(view.error().message);
  RoamView& v = **view;
  OtherWork other(*flush_mb);

  // Warm-up frames (the first frames of the path, not reported), then the path `repeat` times.
  for (std::uint64_t k = 0; k < *warmup; ++k) {
    other.touch();
    if (auto st = v.update((*frames)[k % frames->size()].camera); !st)
      return report_error(st.error().message);
    (void)v.take_dirty_patches();
  }
  nlohmann::ordered_json out_frames = nlohmann::ordered_json::array();
  std::vector<double> ms, cpu, out_ms, out_cpu, total_ms, total_cpu, tris, in_view, changes,
      max_err, rms_err, px_err, mem, out_mem, upload;
  std::uint32_t time_stops = 0, rebuilds = 0, compactions = 0;
  for (std::uint64_t rep = 0; rep < *repeat; ++rep) {
    for (std::size_t k = 0; k < frames->size(); ++k) {
      const Camera& c = (*frames)[k].camera;
      // CPU time of this thread as well as the wall time update() reports: on a shared machine
      // the difference is time the update was preempted, which no budget can keep.
      other.touch();
      const long faults0 = thread_minor_faults();
      const double cpu0 = thread_cpu_ns();
      auto st = v.update(c);
      const double cpu1 = thread_cpu_ns();
      const long faults = thread_minor_faults() - faults0;
      if (!st) return report_error(st.error().message);
      // The output an engine uploads: the update keeps the patch buffers in step; what is left
      // is taking the dirty patches and their ranges.
      const auto w0 = std::chrono::steady_clock::now();
      const std::vector<std::uint32_t> dirty = v.take_dirty_patches();
      const double o_ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - w0).count();
      const double o_cpu = (thread_cpu_ns() - cpu1) * 1e-6;
      const double cpu_ms = (cpu1 - cpu0) * 1e-6;
      nlohmann::ordered_json f = {{"update_ms", st->update_ms},
                                  {"update_cpu_ms", cpu_ms},
                                  {"page_faults", faults},
                                  {"output_ms", o_ms},
                                  {"output_cpu_ms", o_cpu},
                                  {"triangles", st->triangles},
                                  {"splits", st->splits + st->forced_splits},
                                  {"forced_splits", st->forced_splits},
                                  {"merges", st->merges},
                                  {"priority_updates", st->priority_updates},
                                  {"front_size", st->front_size},
                                  {"upload_bytes", st->upload_bytes},
                                  {"dirty_patches", dirty.size()},
                                  {"compacted_patches", st->compacted_patches},
                                  {"rebuilt", st->rebuilt},
                                  {"stopped_by", stop_reason_name(st->stop)},
                                  {"morph_threshold", st->morph_threshold}};
      // Measured on the frames whose error is measured, as the soar mode does: the walk over
      // every leaf between two updates would change what the next update finds in the caches.
      if (*every > 0 && k % *every == 0) {
        const std::uint64_t visible = triangles_in_view(v, c);
        f["triangles_in_view"] = visible;
        in_view.push_back(double(visible));
        const auto e = v.measure_error(c, static_cast<std::uint32_t>(*stride));
        f["max_error"] = e.max_m;
        f["rms_error"] = e.rms_m;
        f["max_screen_error_px"] = e.max_px;
        f["p99_screen_error_px"] = e.p99_px;
        max_err.push_back(e.max_m);
        rms_err.push_back(e.rms_m);
        px_err.push_back(e.max_px);
      }
      f["max_remaining_error_px"] = st->max_remaining_error;
      out_frames.push_back(f);
      ms.push_back(st->update_ms);
      cpu.push_back(cpu_ms);
      out_ms.push_back(o_ms);
      out_cpu.push_back(o_cpu);
      total_ms.push_back(st->update_ms + o_ms);
      total_cpu.push_back(cpu_ms + o_cpu);
      tris.push_back(st->triangles);
      changes.push_back(st->splits + st->forced_splits + st->merges);
      mem.push_back(double(st->memory_bytes));
      out_mem.push_back(double(st->output_bytes));
      upload.push_back(double(st->upload_bytes));
      time_stops += st->stop == StopReason::kTimeBudget;
      compactions += st->compacted_patches;
      rebuilds += st->rebuilt;
    }
  }
  const RoamSettings s = v.settings();
  const double tri_median = std::max(1.0, percentile(tris, 0.5));
  nlohmann::ordered_json summary = {
      {"frames", ms.size()},
      {"mode", s.mode == RoamMode::kCoherent ? "coherent" : "rebuild"},
      {"threshold", s.threshold},
      {"max_triangles", s.max_triangles},
      {"budget_ms", s.budget_ms},
      {"update_ms_median", percentile(ms, 0.5)},
      {"update_ms_p99", percentile(ms, 0.99)},
      {"update_cpu_ms_median", percentile(cpu, 0.5)},
      {"update_cpu_ms_p99", percentile(cpu, 0.99)},
      {"update_ms_max", percentile(ms, 1.0)},
      {"output_ms_median", percentile(out_ms, 0.5)},
      {"output_cpu_ms_median", percentile(out_cpu, 0.5)},
      {"update_plus_output_ms_median", percentile(total_ms, 0.5)},
      {"update_plus_output_cpu_ms_median", percentile(total_cpu, 0.5)},
      {"update_plus_output_cpu_ms_p99", percentile(total_cpu, 0.99)},
      {"triangles_median", percentile(tris, 0.5)},
      {"triangles_p99", percentile(tris, 0.99)},
      {"triangles_in_view_median", percentile(in_view, 0.5)},
      {"changes_per_frame_median", percentile(changes, 0.5)},
      {"upload_bytes_median", percentile(upload, 0.5)},
      {"upload_bytes_mean",
       upload.empty() ? 0.0
                      : std::accumulate(upload.begin(), upload.end(), 0.0) / double(upload.size())},
      {"upload_bytes_p99", percentile(upload, 0.99)},
      {"view_memory_bytes_median", percentile(mem, 0.5)},
      {"view_bytes_per_triangle", percentile(mem, 0.5) / tri_median},
      {"output_bytes_per_triangle", percentile(out_mem, 0.5) / tri_median},
      {"max_error_median", percentile(max_err, 0.5)},
      {"max_error_max", percentile(max_err, 1.0)},
      {"rms_error_median", percentile(rms_err, 0.5)},
      {"max_screen_error_px_median", percentile(px_err, 0.5)},
      {"max_screen_error_px_max", percentile(px_err, 1.0)},
      {"time_budget_stops", time_stops},
      {"rebuilds", rebuilds},
      {"compacted_patches", compactions},
      {"bounds_build_ms", bounds_ms},
      {"bounds_bytes", bound_bytes},
      {"error_every", *every},
      {"error_stride", *stride},
      {"flush_mb", *flush_mb},
  };
  if (s.budget_ms > 0) {
    summary["time_budget_met"] = percentile(ms, 0.99) <= 1.1 * s.budget_ms + 0.1;
    summary["time_budget_met_cpu"] = percentile(cpu, 0.99) <= 1.1 * s.budget_ms + 0.1;
  }
  nlohmann::ordered_json j = {{"summary", summary}, {"frames", out_frames}};
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
