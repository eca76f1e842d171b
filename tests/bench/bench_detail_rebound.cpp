// Re-bounding on tile arrival (docs/detail.md, "Measured bounds"): on the default terrain with
// procedural detail, a view that refines while its detail tiles stream in on a worker (each
// diamond created before its tile was resident gets the tile's measured bound when it arrives),
// against a view created once every one of those tiles is resident (the measured-bound floor).
// Prints JSON.
//
//   bench_detail_rebound [--levels L] [--amplitude M] [--threshold PX] [--height H]
//                        [--size N] [--workers W]
//
// The camera: at the terrain's centre, H metres (default 150) above the ground there, looking
// 400 m along +z at the ground, 60 degrees vertical field of view, 1280 x 720. The streamed view
// flies there first: 120 updates from 1,000 m further back along -z and 500 m higher, with the
// tiles arriving whenever the worker has made them (no waiting), so that most diamonds are made
// with the analytic bound and must be re-bounded when their tile arrives; then it holds the
// final camera (waiting for the worker before each update) until it has converged.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "ridgeline/bench/clock.h"
#include "ridgeline/detail.h"
#include "ridgeline/landscape.h"
#include "ridgeline/roam_view.h"
#include "ridgeline/terrain.h"

using namespace ridgeline;
using ridgeline::bench::Clock;
using ridgeline::bench::ms_since;

namespace {

int usage(const char* why) {
  std::fprintf(stderr,
               "bench_detail_rebound: %s\nusage: bench_detail_rebound [--levels L] "
               "[--amplitude M] [--threshold PX] [--height H] [--size N] [--workers W]\n",
               why);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  std::uint32_t levels = 3, size = 1025, workers = 1;
  double amplitude = 0.25, threshold = 2.0, height = 150.0;
  for (int k = 1; k < argc; ++k) {
    const std::string a = argv[k];
    if (k + 1 >= argc) return usage(("missing the value of " + a).c_str());
    char* end = nullptr;
    const double v = std::strtod(argv[++k], &end);
    if (end == argv[k] || *end != '\0' || !(v >= 0) || v > 1e6)
      return usage(("bad value for " + a).c_str());
    if (a == "--levels" && v >= 1 && v <= 6)
      levels = std::uint32_t(v);
    else if (a == "--amplitude" && v > 0)
      amplitude = v;
    else if (a == "--threshold" && v >= 0.25)
      threshold = v;
    else if (a == "--height" && v >= 1)
      height = v;
    else if (a == "--size" && v >= 65 && v <= 4097)
      size = std::uint32_t(v);
    else if (a == "--workers" && v >= 1 && v <= 8)
      workers = std::uint32_t(v);
    else
      return usage(("unknown option or value out of range: " + a).c_str());
  }
  auto hf = make_default_heightfield({.size = size});
  if (!hf) return usage(hf.error().message.c_str());
  DetailParams p;
  p.levels = levels;
  p.amplitude = amplitude;
  DetailCacheDesc cache;
  cache.budget_bytes = std::size_t{2} << 30;  // every tile the view needs stays resident
  cache.worker_threads = workers;
  auto terrain = Terrain::create(std::move(hf).value(), p, cache);
  if (!terrain) return usage(terrain.error().message.c_str());
  const std::shared_ptr<const Terrain> t = *terrain;
  auto land = Landscape::create(t, {});
  if (!land) return usage(land.error().message.c_str());

  const double mid = 0.5 * (size - 1) * t->info().spacing_x;
  const auto ground = [&](double x, double z) { return t->height(x, z).value_or(0.0); };
  Camera cam;
  cam.eye = {mid, ground(mid, mid) + height, mid};
  cam.target = {mid, ground(mid, mid + 400.0), mid + 400.0};

  // Streamed: each update requests the tiles its splits wait for; during the flight they arrive
  // when they are made, then the worker makes them before the next update (wait_idle).
  auto streamed = RoamView::create(*land, {.threshold = threshold});
  if (!streamed) return usage(streamed.error().message.c_str());
  std::uint64_t rebounded = 0, frames = 0;
  RoamStats st{};
  const auto s0 = Clock::now();
  double update_ms = 0;
  constexpr int kFlight = 120;
  for (int k = 0; k < kFlight; ++k) {
    const double back = 1.0 - double(k) / kFlight;
    Camera c = cam;
    c.eye += glm::dvec3(0.0, 500.0 * back, -1000.0 * back);
    c.target += glm::dvec3(0.0, 0.0, -1000.0 * back);
    auto s = (*streamed)->update(c);
    if (!s) return usage(s.error().message.c_str());
    update_ms += s->update_ms;
    rebounded += s->rebounded;
  }
  for (; frames < 5000; ++frames) {
    t->surface().detail_cache()->wait_idle(30.0);
    auto s = (*streamed)->update(cam);
    if (!s) return usage(s.error().message.c_str());
    st = *s;
    update_ms += st.update_ms;
    rebounded += st.rebounded;
    if (frames > 3 && st.pending_splits == 0 && st.splits + st.merges + st.forced_splits == 0)
      break;
  }
  const double streamed_ms = ms_since(s0);
  const DetailCacheStats cs = t->surface().detail_cache()->stats();

  // The floor: a new view over the same resident tiles, converged in one update.
  auto fresh = RoamView::create(*land, {.threshold = threshold});
  if (!fresh) return usage(fresh.error().message.c_str());
  const auto f0 = Clock::now();
  auto f = (*fresh)->converge(cam);
  if (!f) return usage(f.error().message.c_str());
  const double fresh_ms = ms_since(f0);

  std::printf(
      "{\n"
      "  \"command\": \"bench_detail_rebound --levels %u --amplitude %g --threshold %g "
      "--height %g --size %u --workers %u\",\n"
      "  \"streamed_triangles\": %u,\n"
      "  \"streamed_frames\": %llu,\n"
      "  \"streamed_hold_frames\": %llu,\n"
      "  \"streamed_pending_splits\": %u,\n"
      "  \"streamed_update_ms_total\": %.1f,\n"
      "  \"streamed_wall_ms\": %.1f,\n"
      "  \"rebounded\": %llu,\n"
      "  \"fresh_triangles\": %u,\n"
      "  \"fresh_pending_splits\": %u,\n"
      "  \"fresh_converge_ms\": %.1f,\n"
      "  \"streamed_over_fresh\": %.5f,\n"
      "  \"resident_tiles\": %zu,\n"
      "  \"resident_mib\": %.1f,\n"
      "  \"view_mib\": %.1f\n"
      "}\n",
      levels, amplitude, threshold, height, size, workers, st.triangles,
      static_cast<unsigned long long>(frames + kFlight), static_cast<unsigned long long>(frames),
      st.pending_splits, update_ms, streamed_ms, static_cast<unsigned long long>(rebounded),
      f->triangles, f->pending_splits, fresh_ms,
      double(st.triangles) / double(std::max<std::uint32_t>(1, f->triangles)), cs.resident_tiles,
      double(cs.resident_bytes) / double(1 << 20), double(st.memory_bytes) / double(1 << 20));
  return st.pending_splits == 0 && f->pending_splits == 0 ? 0 : 1;
}
