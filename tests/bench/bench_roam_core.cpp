// ROAM against SOAR in one process, frame by frame (docs/benchmarks.md): on the noise field and
// its circular flyover (ridgeline/scenes.h), the frame loop of Ridgeline::bench runs ROAM
// (RoamView::update, then take_dirty_patches: update + output) and the stateless SOAR refinement
// with the emission of its strip (refine + emit) in alternating order on every frame, with the
// same treatment of the caches between frames for both. Core library only (no OpenImageIO), so
// that valgrind's callgrind runs it too. Prints JSON.
//
// Usage: bench_roam_core [--triangles N] [--threshold PX] [--rounds R] [--flush-mb M]
//                        [--only roam|soar] [--patch-exponent K] [--cold N] [--json FILE]
//   --triangles N   ROAM with a cap of N (threshold 0 unless given), SOAR with the one kappa
//                   whose median count over the path is closest to N (as `ridge bench lod`)
//   --threshold PX  both at PX pixels (without --triangles)
//   --flush-mb M    before each update, read and write M MiB of other memory (the rest of an
//                   engine's frame evicting the terrain's data); 0 (default): caches stay warm
//   --cold N        instead: N fresh views' first updates at the path's first camera (cold
//                   start: the mesh built from the roots), their median (ROAM only)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>
#include <vector>

#include "ridgeline/bench/clock.h"
#include "ridgeline/bench/frame_loop.h"
#include "ridgeline/bench/stats.h"
#include "ridgeline/bench/techniques.h"
#include "ridgeline/roam_view.h"
#include "ridgeline/scenes.h"

#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#else
#define CALLGRIND_START_INSTRUMENTATION
#define CALLGRIND_STOP_INSTRUMENTATION
#endif

using namespace ridgeline;
using bench::median;

namespace {

int usage(const char* why) {
  std::fprintf(stderr,
               "bench_roam_core: %s\nusage: bench_roam_core [--triangles N] [--threshold PX] "
               "[--rounds R] [--flush-mb M] [--only roam|soar] [--patch-exponent K] [--cold N] "
               "[--json FILE]\n",
               why);
  return 2;
}

// The --cold figures: the first update of `runs` fresh views at `first`, with their page faults.
bench::Json cold_start(const std::shared_ptr<const Landscape>& landscape, const RoamSettings& s,
                       const Camera& first, unsigned runs,
                       const std::shared_ptr<RoamMemory>& memory) {
  std::vector<double> ms, faults;
  std::size_t tris = 0;
  for (unsigned k = 0; k < runs; ++k) {
    auto v = RoamView::create(landscape, s, memory).value();
    Result<RoamStats> st = Error{""};
    const bench::Timing t = bench::timed([&] { st = v->update(first); });
    ms.push_back(t.wall_ms);
    faults.push_back(double(t.faults));
    tris = st ? st->triangles : 0;
  }
  // The first view of the process faults its memory in; later ones reuse what the previous one
  // left in the RoamMemory. Both are reported.
  return {{"cold_start_first_update_ms", ms[0]},
          {"cold_start_first_page_faults", faults[0]},
          {"cold_start_update_ms_median", median(ms)},
          {"page_faults_median", median(faults)},
          {"triangles", tris},
          {"runs", runs}};
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

  // One memory for every view of the run, so that a view takes over the pages of the one before.
  const std::shared_ptr<RoamMemory> memory = RoamMemory::create();
  std::vector<bench::Technique*> techniques;
  std::unique_ptr<bench::RoamTechnique> roam;
  if (do_roam) {
    auto land = Landscape::create(terrain, {.patch_exponent = patch_exponent});
    if (!land) return usage(land.error().message.c_str());
    RoamSettings s;
    s.threshold = threshold;
    s.max_triangles = triangles;
    if (cold > 0) {
      const std::string text = cold_start(*land, s, cams[0], cold, memory).dump(1);
      std::printf("%s\n", text.c_str());
      return 0;
    }
    auto v = RoamView::create(*land, s, memory);
    if (!v) return usage(v.error().message.c_str());
    roam = std::make_unique<bench::RoamTechnique>(std::move(*v));
    techniques.push_back(roam.get());
  }
  std::unique_ptr<bench::Soar> soar;
  std::unique_ptr<bench::SoarTechnique> soar_technique;
  if (do_soar) {
    soar = std::make_unique<bench::Soar>(terrain->surface().to_heightfield().value());
    double path_kappa = std::numeric_limits<double>::infinity();
    if (triangles > 0) path_kappa = soar->match(cams, triangles, cams.size() / 60).kappa;
    soar_technique = std::make_unique<bench::SoarTechnique>(*soar, threshold, path_kappa);
    techniques.push_back(soar_technique.get());
  }

  // Warm-up: the first 60 frames of the path (ROAM converges from its roots there); then the
  // path `rounds` times, the two taking turns at going first.
  bench::LoopOptions lo;
  lo.warmup = 60;
  lo.repeat = rounds;
  lo.flush_mb = flush_mb;
  lo.alternate = true;
  CALLGRIND_START_INSTRUMENTATION;
  auto runs = bench::run_path(techniques, cams, nullptr, lo);
  CALLGRIND_STOP_INSTRUMENTATION;
  if (!runs) return usage(runs.error().message.c_str());

  static const bench::Run kNone;
  const bench::Run& r = do_roam ? runs->front() : kNone;
  const bench::Run& s = do_soar ? runs->back() : kNone;
  std::vector<double> roam_ms(r.wall_ms), ratio;
  for (std::size_t k = 0; k < roam_ms.size(); ++k) roam_ms[k] += r.output_ms[k];
  std::vector<double> roam_cpu(r.cpu_ms);
  for (std::size_t k = 0; k < roam_cpu.size(); ++k) roam_cpu[k] += r.output_cpu_ms[k];
  if (do_roam && do_soar)
    for (std::size_t k = 0; k < roam_ms.size(); ++k) ratio.push_back(s.wall_ms[k] / roam_ms[k]);
  std::string command = "bench_roam_core";
  if (triangles) command += " --triangles " + std::to_string(triangles);
  if (threshold > 0) command += " --threshold " + std::to_string(threshold);
  if (flush_mb > 0) command += " --flush-mb " + std::to_string(int(flush_mb));
  if (rounds > 1) command += " --rounds " + std::to_string(rounds);
  auto value = [](double x) { return bench::number(bench::or_value(x, 0.0)); };
  const double roam_median = bench::or_value(median(roam_ms), 0.0);
  const bench::Json j = {
      {"command", command},
      {"frames", std::max(r.wall_ms.size(), s.wall_ms.size())},
      {"flush_mb", flush_mb},
      {"roam_update_plus_output_ms_median", value(roam_median)},
      {"roam_cpu_ms_median", value(median(roam_cpu))},
      {"roam_triangles_median", value(median(r.triangles))},
      {"roam_changes_median", value(median(r.changes))},
      {"soar_refine_emit_ms_median", value(median(s.wall_ms))},
      {"soar_cpu_ms_median", value(median(s.cpu_ms))},
      {"soar_triangles_median", value(median(s.triangles))},
      {"soar_over_roam_median_of_frame_ratios", value(median(ratio))},
      {"soar_over_roam_ratio_of_medians",
       value(roam_median > 0 ? median(s.wall_ms) / roam_median : 0.0)}};
  const std::string text = j.dump(1) + "\n";
  if (json_path.empty()) {
    std::fputs(text.c_str(), stdout);
  } else {
    FILE* f = std::fopen(json_path.c_str(), "w");
    if (f == nullptr || std::fputs(text.c_str(), f) < 0 || std::fclose(f) != 0)
      return usage(("cannot write " + json_path).c_str());
  }
  return 0;
}
