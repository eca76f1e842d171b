// ROAM against SOAR in one process, frame by frame (docs/benchmarks.md, "ROAM against SOAR, like
// for like"): on the noise field and its circular flyover (ridgeline/scenes.h), each frame times
// RoamView::update plus take_dirty_patches (update + output) and the stateless SOAR refinement
// with the emission of its strip (refine + emit), in alternating order, with the same treatment
// of the caches between frames for both. Core library only (no OpenImageIO), so that
// valgrind's callgrind runs it too. Prints JSON.
//
// Usage: bench_roam_core [--triangles N] [--threshold PX] [--rounds R] [--flush-mb M]
//                        [--only roam|soar] [--patch-exponent K] [--json FILE]
//   --triangles N   ROAM with a cap of N (threshold 0 unless given), SOAR with the one kappa
//                   whose median count over the path is closest to N (as `ridge bench lod`)
//   --threshold PX  both at PX pixels (without --triangles)
//   --flush-mb M    between frames, read and write M MiB of other memory (the rest of an
//                   engine's frame evicting the terrain's data); 0 (default): caches stay warm
//   --cold N        instead: N fresh views' first updates at the path's first camera (cold
//                   start: the mesh built from the roots), their median (ROAM only)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "cli_util.h"
#include "report/soar.h"
#include "report/stats.h"
#include "ridgeline/roam_view.h"
#include "ridgeline/scenes.h"

#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#else
#define CALLGRIND_START_INSTRUMENTATION
#define CALLGRIND_STOP_INSTRUMENTATION
#endif

using namespace ridgeline;

namespace {

double thread_cpu_ms() { return cli::thread_cpu_ns() * 1e-6; }

// The median as `ridge bench lod` and the report take it (0 when there is nothing).
double median(const std::vector<double>& v) {
  return v.empty() ? 0.0 : report::quantile(v, 0.5);
}

struct Sample {
  std::vector<double> wall, cpu, tris, changes;
};

int usage(const char* why) {
  std::fprintf(stderr,
               "bench_roam_core: %s\nusage: bench_roam_core [--triangles N] [--threshold PX] "
               "[--rounds R] [--flush-mb M] [--only roam|soar] [--patch-exponent K] "
               "[--json FILE]\n",
               why);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  double threshold = -1, flush_mb = 0;
  unsigned triangles = 0, rounds = 1, patch_exponent = 6, cold = 0;
  std::string only, json_path;
  for (int k = 1; k < argc; ++k) {
    const std::string a = argv[k];
    const char* v = k + 1 < argc ? argv[k + 1] : nullptr;
    auto number = [&](double lo, double hi) {
      if (v == nullptr) std::exit(usage(("missing value after " + a).c_str()));
      char* end = nullptr;
      const double x = std::strtod(v, &end);
      if (end == v || *end != '\0' || !std::isfinite(x) || x < lo || x > hi)
        std::exit(usage(("bad value '" + std::string(v) + "' for " + a).c_str()));
      ++k;
      return x;
    };
    if (a == "--triangles")
      triangles = unsigned(number(2, 1e8));
    else if (a == "--threshold")
      threshold = number(0, 1e4);
    else if (a == "--rounds")
      rounds = unsigned(number(1, 1000));
    else if (a == "--flush-mb")
      flush_mb = number(0, 4096);
    else if (a == "--cold")
      cold = unsigned(number(1, 1000));
    else if (a == "--patch-exponent")
      patch_exponent = unsigned(number(2, 10));
    else if (a == "--only" && v != nullptr &&
             (std::string(v) == "roam" || std::string(v) == "soar"))
      only = argv[++k];
    else if (a == "--json" && v != nullptr)
      json_path = argv[++k];
    else
      return usage(("unknown argument " + a).c_str());
  }
  if (triangles == 0 && threshold < 0) return usage("give --triangles N and/or --threshold PX");
  if (threshold < 0) threshold = 0;

  auto hf = scenes::noise_field();
  if (!hf) return usage(hf.error().message.c_str());
  const std::shared_ptr<const Terrain> terrain = Terrain::create(std::move(*hf)).value();
  const std::vector<Camera> cams = scenes::noise_circle();
  const bool do_roam = only != "soar", do_soar = only != "roam";

  std::unique_ptr<RoamView> view;
  std::shared_ptr<const Landscape> landscape;
  // One memory for every view of the run, so that a view takes over the pages of the one before.
  const std::shared_ptr<RoamMemory> memory = RoamMemory::create();
  if (do_roam) {
    auto land = Landscape::create(terrain, {.patch_exponent = patch_exponent});
    if (!land) return usage(land.error().message.c_str());
    landscape = *land;
    RoamSettings s;
    s.threshold = threshold;
    s.max_triangles = triangles;
    auto v = RoamView::create(*land, s, memory);
    if (!v) return usage(v.error().message.c_str());
    view = std::move(*v);
  }
  if (cold > 0 && view) {
    // The first view of the process faults its memory in; later ones reuse what the previous
    // one left in the RoamMemory. Both are reported, with the page faults of each update.
    std::vector<double> ms;
    std::vector<long> faults;
    std::size_t tris = 0;
    const RoamSettings settings = view->settings();
    view.reset();
    for (unsigned k = 0; k < cold; ++k) {
      auto v = RoamView::create(landscape, settings, memory).value();
      const long f0 = cli::thread_minor_faults();
      const auto w0 = std::chrono::steady_clock::now();
      const auto st = v->update(cams[0]);
      ms.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - w0).count());
      faults.push_back(cli::thread_minor_faults() - f0);
      tris = st ? st->triangles : 0;
    }
    const double first = ms[0];
    const long first_faults = faults[0];
    std::printf(
        "{\n \"cold_start_first_update_ms\": %.3f,\n \"cold_start_first_page_faults\": %ld,\n"
        " \"cold_start_update_ms_median\": %.3f,\n \"page_faults_median\": %ld,\n"
        " \"triangles\": %zu,\n \"runs\": %u\n}\n",
        first, first_faults, median(ms), faults[faults.size() / 2], tris, cold);
    return 0;
  }
  std::unique_ptr<report::Soar> soar;
  double path_kappa = INFINITY;
  if (do_soar) {
    soar = std::make_unique<report::Soar>(terrain->surface().to_heightfield().value());
    if (triangles > 0) path_kappa = soar->match(cams, triangles, cams.size() / 60).kappa;
  }
  auto kappa_of = [&](const Camera& c) {
    return std::min(threshold > 0 ? report::Soar::kappa_for(c, threshold) : INFINITY, path_kappa);
  };

  std::vector<unsigned char> other(std::size_t(flush_mb * 1048576.0), 1);
  volatile unsigned sink = 0;
  auto flush = [&] {
    unsigned s = 0;
    for (std::size_t k = 0; k < other.size(); k += 64) s += other[k]++;
    sink = sink + s;
  };
  std::vector<std::uint32_t> strip;
  auto run_roam = [&](const Camera& c, Sample* out) {
    flush();
    const auto w0 = std::chrono::steady_clock::now();
    const double c0 = thread_cpu_ms();
    const auto st = view->update(c);
    const auto dirty = view->take_dirty_patches();
    const double c1 = thread_cpu_ms();
    const auto w1 = std::chrono::steady_clock::now();
    if (!st) std::exit(usage(st.error().message.c_str()));
    if (out == nullptr) return;
    out->wall.push_back(std::chrono::duration<double, std::milli>(w1 - w0).count());
    out->cpu.push_back(c1 - c0);
    out->tris.push_back(st->triangles);
    out->changes.push_back(st->splits + st->forced_splits + st->merges);
  };
  auto run_soar = [&](const Camera& c, Sample* out) {
    flush();
    const double kappa = kappa_of(c);
    const auto w0 = std::chrono::steady_clock::now();
    const double c0 = thread_cpu_ms();
    const auto f = soar->refine(c, kappa, strip);
    const double c1 = thread_cpu_ms();
    const auto w1 = std::chrono::steady_clock::now();
    if (out == nullptr) return;
    out->wall.push_back(std::chrono::duration<double, std::milli>(w1 - w0).count());
    out->cpu.push_back(c1 - c0);
    out->tris.push_back(double(f.triangles));
  };

  // Warm-up: the first 60 frames of the path (ROAM converges from its roots there).
  for (std::size_t k = 0; k < 60; ++k) {
    if (do_roam) run_roam(cams[k], nullptr);
    if (do_soar) run_soar(cams[k], nullptr);
  }
  Sample roam, sr;
  std::vector<double> ratio;
  CALLGRIND_START_INSTRUMENTATION;
  for (unsigned r = 0; r < rounds; ++r)
    for (std::size_t k = 0; k < cams.size(); ++k) {
      const bool roam_first = (k + r) % 2 == 0;
      if (do_roam && roam_first) run_roam(cams[k], &roam);
      if (do_soar) run_soar(cams[k], &sr);
      if (do_roam && !roam_first) run_roam(cams[k], &roam);
      if (do_roam && do_soar) ratio.push_back(sr.wall.back() / roam.wall.back());
    }
  CALLGRIND_STOP_INSTRUMENTATION;

  char buf[2048];
  std::snprintf(
      buf, sizeof buf,
      "{\n \"command\": \"bench_roam_core%s%s%s%s\",\n \"frames\": %zu,\n \"flush_mb\": %g,\n"
      " \"roam_update_plus_output_ms_median\": %.4f,\n \"roam_cpu_ms_median\": %.4f,\n"
      " \"roam_triangles_median\": %.0f,\n \"roam_changes_median\": %.0f,\n"
      " \"soar_refine_emit_ms_median\": %.4f,\n \"soar_cpu_ms_median\": %.4f,\n"
      " \"soar_triangles_median\": %.0f,\n \"soar_over_roam_median_of_frame_ratios\": %.3f,\n"
      " \"soar_over_roam_ratio_of_medians\": %.3f\n}\n",
      triangles ? (" --triangles " + std::to_string(triangles)).c_str() : "",
      threshold > 0 ? (" --threshold " + std::to_string(threshold)).c_str() : "",
      flush_mb > 0 ? (" --flush-mb " + std::to_string(int(flush_mb))).c_str() : "",
      rounds > 1 ? (" --rounds " + std::to_string(rounds)).c_str() : "",
      std::max(roam.wall.size(), sr.wall.size()), flush_mb, median(roam.wall), median(roam.cpu),
      median(roam.tris), median(roam.changes), median(sr.wall), median(sr.cpu), median(sr.tris),
      median(ratio), median(roam.wall) > 0 ? median(sr.wall) / median(roam.wall) : 0.0);
  if (json_path.empty()) {
    std::fputs(buf, stdout);
  } else {
    FILE* f = std::fopen(json_path.c_str(), "w");
    if (f == nullptr || std::fputs(buf, f) < 0 || std::fclose(f) != 0)
      return usage(("cannot write " + json_path).c_str());
  }
  return 0;
}
