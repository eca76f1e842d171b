// `ridge bench lod --mode soar` (bench_soar.h): per frame, one SOAR refinement that emits the
// whole strip (timed: wall and thread CPU), then, untimed, the measurement of the mesh.
#include "bench_soar.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "cli_util.h"
#include "report/modes.h"
#include "report/soar.h"
#include "report/stats.h"
#include "ridgeline/camera_path.h"
#include "ridgeline/mesh_error.h"

namespace ridgeline::cli {

namespace {
using Clock = std::chrono::steady_clock;

double percentile(std::vector<double> v, double q) {
  return v.empty() ? 0.0 : report::quantile(std::move(v), q);
}
}  // namespace

int run_bench_lod_soar(const SoarBenchArgs& a) {
  if (!a.budget_ms.empty())
    return report_error("--budget-ms: the soar mode has no time budget (one full pass a frame)");
  if (a.threshold.empty() && a.triangles.empty())
    return report_error("give --threshold PX and/or --triangles N");
  double threshold = 0;
  if (!a.threshold.empty()) {
    auto t = parse_finite(a.threshold, "--threshold");
    if (!t) return report_error(t.error().message);
    if (*t < 0) return report_error("--threshold must be >= 0");
    threshold = *t;
  }
  std::uint64_t cap = 0;
  if (!a.triangles.empty()) {
    auto n = parse_count(a.triangles, "--triangles", 1, 0xffffffffu);
    if (!n) return report_error(n.error().message);
    cap = *n;
  }
  auto terrain = a.terrain->load_terrain();
  if (!terrain) return report_error(terrain.error().message);
  const Terrain& t = **terrain;
  std::vector<Camera> cams;
  for (const auto& f : *a.frames) cams.push_back(f.camera);

  // The vertex data (heights, nested errors and radii) of the finest lattice: the preprocess,
  // reported apart like ROAM's bounds.
  const auto t_pre = Clock::now();
  if (std::max(t.surface().lattice().vertices_x, t.surface().lattice().vertices_z) > std::int64_t{report::Soar::kMaxSide})
    return report_error("--mode soar: the finest lattice is " + std::to_string(t.surface().lattice().vertices_x) +
                        " x " + std::to_string(t.surface().lattice().vertices_z) +
                        " vertices; the comparator takes at most " +
                        std::to_string(report::Soar::kMaxSide) + " per side");
  auto fine = report::finest_lattice(t);
  if (!fine) return report_error(fine.error().message);
  const Heightfield& lattice = *fine;
  const report::Soar soar(lattice);
  const double preprocess_ms =
      std::chrono::duration<double, std::milli>(Clock::now() - t_pre).count();
  // --triangles N: one kappa for the whole path, the one whose median count over the path is
  // closest to N (calibrated untimed, on every 6th frame); with --threshold too, a frame uses
  // the smaller of the two kappas.
  double path_kappa = std::numeric_limits<double>::infinity();
  if (cap > 0)
    path_kappa = soar.match(cams, double(cap), std::max<std::size_t>(1, cams.size() / 60)).kappa;
  auto kappa_of = [&](const Camera& c) {
    return std::min(threshold > 0 ? report::Soar::kappa_for(c, threshold)
                                  : std::numeric_limits<double>::infinity(),
                    path_kappa);
  };
  const MeshErrorMeter meter(lattice, static_cast<std::uint32_t>(a.error_stride));

  std::vector<std::uint32_t> strip;
  OtherWork other(a.flush_mb);
  for (std::uint64_t k = 0; k < a.warmup; ++k) {
    other.touch();
    (void)soar.refine(cams[k % cams.size()], kappa_of(cams[k % cams.size()]), strip);
  }
  nlohmann::ordered_json out_frames = nlohmann::ordered_json::array();
  std::vector<double> ms, cpu, refine_only, tris, in_view, upload, max_err, rms_err, px_err;
  DrawnHeights drawn;
  for (std::uint64_t rep = 0; rep < a.repeat; ++rep) {
    for (std::size_t k = 0; k < cams.size(); ++k) {
      const Camera& c = cams[k];
      const double kappa = kappa_of(c);
      other.touch();
      const long faults0 = thread_minor_faults();
      const double cpu0 = thread_cpu_ns();
      const auto t0 = Clock::now();
      const report::Soar::Frame f = soar.refine(c, kappa, strip);
      const double wall_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      const double cpu_ms = (thread_cpu_ns() - cpu0) * 1e-6;
      const long faults = thread_minor_faults() - faults0;
      nlohmann::ordered_json fj = {{"update_ms", wall_ms},
                                   {"update_cpu_ms", cpu_ms},
                                   {"page_faults", faults},
                                   {"output_ms", 0.0},
                                   {"upload_bytes", strip.size() * sizeof(std::uint32_t)},
                                   {"triangles", f.triangles},
                                   {"kappa", report::num(kappa)}};
      // Measured on the frames whose error is measured (the next refinement finds the caches
      // as the measurement left them, as the ROAM modes' does).
      if (a.error_every > 0 && k % a.error_every == 0) {
        // The same refinement without emitting: what the strip costs is the difference. Run
        // between frames, it would find what the next timed refinement reads in the caches.
        const auto t1 = Clock::now();
        (void)soar.count(c, kappa);
        const double count_ms =
            std::chrono::duration<double, std::milli>(Clock::now() - t1).count();
        fj["refine_only_ms"] = count_ms;
        refine_only.push_back(count_ms);
        const DrawnMesh mesh = soar.mesh(strip);
        meter.rasterize(mesh, drawn);
        const MeshError e = meter.measure(drawn, c);
        const auto n = meter.triangles_in_view(mesh, c);
        fj["triangles_in_view"] = n;
        fj["max_error"] = e.max_m;
        fj["rms_error"] = e.rms_m;
        fj["max_screen_error_px"] = e.max_px;
        fj["p99_screen_error_px"] = e.p99_px;
        fj["uncovered_vertices"] = e.uncovered;
        in_view.push_back(double(n));
        max_err.push_back(e.max_m);
        rms_err.push_back(e.rms_m);
        px_err.push_back(e.max_px);
      }
      out_frames.push_back(fj);
      ms.push_back(wall_ms);
      cpu.push_back(cpu_ms);
      tris.push_back(double(f.triangles));
      upload.push_back(double(strip.size() * sizeof(std::uint32_t)));
    }
  }
  const double mem = double(soar.memory_bytes() + strip.capacity() * sizeof(std::uint32_t));
  nlohmann::ordered_json summary = {
      {"frames", ms.size()},
      {"mode", "soar"},
      {"threshold", threshold},
      {"max_triangles", cap},
      {"budget_ms", 0},
      {"kappa", cap > 0 ? report::num(path_kappa) : nlohmann::ordered_json("per frame")},
      {"update_ms_median", percentile(ms, 0.5)},
      {"update_ms_p99", percentile(ms, 0.99)},
      {"update_cpu_ms_median", percentile(cpu, 0.5)},
      {"update_cpu_ms_p99", percentile(cpu, 0.99)},
      {"update_ms_max", percentile(ms, 1.0)},
      {"refine_only_ms_median", percentile(refine_only, 0.5)},
      {"output_ms_median", 0.0},
      {"upload_bytes_median", percentile(upload, 0.5)},
      {"triangles_median", percentile(tris, 0.5)},
      {"triangles_p99", percentile(tris, 0.99)},
      {"triangles_in_view_median", percentile(in_view, 0.5)},
      {"changes_per_frame_median", nullptr},
      {"view_memory_bytes_median", mem},
      {"view_bytes_per_triangle", mem / std::max(1.0, percentile(tris, 0.5))},
      {"max_error_median", percentile(max_err, 0.5)},
      {"max_error_max", percentile(max_err, 1.0)},
      {"rms_error_median", percentile(rms_err, 0.5)},
      {"max_screen_error_px_median", percentile(px_err, 0.5)},
      {"bounds_build_ms", preprocess_ms},
      {"bounds_bytes", soar.memory_bytes()},
      {"error_every", a.error_every},
      {"error_stride", a.error_stride},
      {"flush_mb", a.flush_mb},
      {"emitted",
       "one generalised triangle strip of 32-bit vertex indices (the whole mesh, every "
       "frame, inside update_ms; output_ms is 0); vertices static"},
  };
  nlohmann::ordered_json j = {{"summary", summary}, {"frames", out_frames}};
  if (auto st = write_json(j, a.json_path); !st) return report_error(st.message());
  return 0;
}

}  // namespace ridgeline::cli
