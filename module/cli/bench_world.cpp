// ridge-bench-world (`ridge bench world` runs it): worlds larger than memory, measured (JSON;
// docs/worlds.md, "Figures"). For each size of the project's generated world (1 m spacing, 2 cm
// steps), in this order:
//   1. bake: the generator feeds bake_world() directly (skipped when the world file is there);
//   2. open to first mesh: Terrain::open + Landscape::create + RoamView::create + the first
//      update, each timed, and the process's memory after it;
//   3. convergence: wall time until the view has converged with every page it waits for
//      resident, after the open and after teleports to random places;
//   4. a flight at constant ground speed around the world, paced in real time (1280 x 720, a
//      pixel threshold, a time budget per update): update times, splits waiting for pages, the
//      cache's bytes and the whole process's resident memory sampled every second.
// The program links the core and Ridgeline::world only (no OpenImageIO): its memory is what an
// engine streaming a baked world pays.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "process_memory.h"
#include "ridgeline/edit.h"
#include "ridgeline/bench/clock.h"
#include "ridgeline/bench/stats.h"
#include "ridgeline/landscape.h"
#include "ridgeline/roam_view.h"
#include "ridgeline/scenes.h"
#include "ridgeline/terrain.h"
#include "ridgeline/world_file.h"

using namespace ridgeline;
using bench::Clock;
using bench::ms_between;

namespace {

// The process's resident memory (VmRSS) and its peak since the last reset (VmHWM), bytes.
std::size_t status_bytes(const char* key) {
  std::ifstream f("/proc/self/status");
  std::string line;
  const std::string k = std::string(key) + ":";
  while (std::getline(f, line))
    if (line.rfind(k, 0) == 0) return std::size_t(std::stoull(line.substr(k.size()))) * 1024;
  return 0;
}
void reset_peak_rss() {
  std::ofstream f("/proc/self/clear_refs");
  f << "5";
}
std::string load_average() {
  std::ifstream f("/proc/loadavg");
  std::string a, b, c;
  f >> a >> b >> c;
  return a + " " + b + " " + c;
}

// The quantile of ridgeline/bench/stats.h (rank floor(q n)), 0 for an empty series.
double quantile(const std::vector<double>& v, double q) { return bench::quantile_or(v, q, 0.0); }

struct Options {
  std::string dir = "build/worlds";
  std::vector<std::uint32_t> sizes{4097, 16385};
  std::uint32_t seed = 1;
  double minutes = 10, speed = 300, fps = 60, pixels = 2, update_budget_ms = 2;
  int width = 1280, height = 720;
  std::size_t budget_mb = 128;  // the process stays under 256 MB at 16385^2 (docs/worlds.md)
  std::uint32_t workers = 2, teleports = 5, bake_threads = 0;
  bool in_memory = false;  // also fly each size over the terrain made in memory
  double clearance = 120;
};

// The generated world's 16-bit samples, `n` a side, made on every core.
std::vector<std::uint16_t> generate(const Options& o, std::uint32_t n) {
  std::vector<std::uint16_t> raw(std::size_t(n) * n);
  std::vector<std::thread> pool;
  const unsigned threads = std::max(1u, std::thread::hardware_concurrency());
  for (unsigned t = 0; t < threads; ++t)
    pool.emplace_back([&, t] {
      for (std::uint32_t j0 = 64 * t; j0 < n; j0 += 64 * threads)
        scenes::generated_world_rows(n, j0, std::min(n, j0 + 64), o.seed,
                                     raw.data() + std::size_t(j0) * n);
    });
  for (auto& th : pool) th.join();
  return raw;
}

// Bakes the generated world of `n` samples a side into `path` unless a world this build reads is
// there (one of an older format version is baked again).
nlohmann::json bake_if_missing(const Options& o, std::uint32_t n, const std::string& path) {
  nlohmann::json j;
  if (std::filesystem::exists(path) && io::open_world(path)) {
    j["cached"] = true;
    j["bytes"] = std::filesystem::file_size(path);
    j["bytes_per_sample"] = double(std::filesystem::file_size(path)) / (double(n) * n);
    return j;
  }
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  const auto t0 = Clock::now();
  const std::vector<std::uint16_t> raw = generate(o, n);
  const double generate_s = ms_between(t0, Clock::now()) / 1000;
  io::BakeSamples s;
  s.info.width = s.info.height = n;
  s.info.spacing_x = s.info.spacing_z = 1.0;
  s.info.height_scale = scenes::kWorldHeightScale;
  s.info.format = SampleFormat::kU16;
  s.info.name = "generated world " + std::to_string(n);
  s.u16 = raw.data();
  io::BakeOptions bo;
  bo.threads = o.bake_threads;
  auto r = io::bake_world(s, path, bo);
  if (!r) {
    std::fprintf(stderr, "ridge-bench-world: %s\n", r.error().message.c_str());
    std::exit(1);
  }
  j["cached"] = false;
  j["generate_seconds"] = generate_s;
  j["bake_seconds"] = r->seconds;
  j["bounds_seconds"] = r->bounds_seconds;
  j["pages_seconds"] = r->pages_seconds;
  j["samples_per_second"] = double(r->samples) / r->seconds;
  j["bytes"] = r->bytes;
  j["bytes_per_sample"] = double(r->bytes) / double(r->samples);
  j["peak_rss_bytes"] = status_bytes("VmHWM");
  return j;
}

// The flight: a circle of radius 0.4 x the extent around the middle at constant ground speed,
// looking ahead and 0.25 rad down, `clearance` metres over the ground below (smoothed; the
// ground ahead is prefetched so the height query never waits).
struct Flight {
  double cx, cz, radius, speed;
  double altitude = 0;
  bool started = false;
  glm::dvec2 at(double t) const {
    const double a = t * speed / radius;
    return {cx + radius * std::cos(a), cz + radius * std::sin(a)};
  }
  Camera camera(const Terrain& terrain, double t, const Options& o) {
    const glm::dvec2 p = at(t), q = at(t + 0.05);
    const WorldInfo& w = terrain.info();
    const double ground = terrain.height(p.x, p.y).value_or(w.height_offset);
    const double want = ground + o.clearance;
    altitude = started ? std::max(want, altitude + 0.05 * (want - altitude)) : want;
    started = true;
    Camera c;
    c.eye = {p.x, altitude, p.y};
    const glm::dvec2 d = glm::normalize(q - p);
    c.target = c.eye + glm::dvec3(d.x, -std::tan(0.25), d.y);
    c.fov_y_deg = 60;
    c.viewport = {o.width, o.height};
    return c;
  }
};

// One size over the baked world (`memory` false) or over the terrain made in memory from the same
// samples (`memory` true: the open is the generation, the heightfield and Terrain::create; no
// clone is timed, since a clone of it is the same as the paged one's).
nlohmann::json run_size(const Options& o, std::uint32_t n, bool memory) {
  nlohmann::json out;
  out["size"] = n;
  out["samples"] = double(n) * n;
  const std::string path =
      o.dir + "/generated_" + std::to_string(n) + "_s" + std::to_string(o.seed) + ".tif";
  out["path"] = memory ? "memory" : "paged";
  if (!memory) {
    out["world"] = path;
    out["bake"] = bake_if_missing(o, n, path);
    std::fprintf(stderr, "size %u: baked (%s)\n", n, out["bake"].dump().c_str());
  }

  // ---- open to first mesh ------------------------------------------------------------------
  reset_peak_rss();
  const std::size_t rss_before = status_bytes("VmRSS");
  const auto t0 = Clock::now();
  Result<std::shared_ptr<const PageSource>> source = Error{"in memory"};
  std::optional<Heightfield> samples;
  if (memory) {
    const std::vector<std::uint16_t> raw = generate(o, n);
    HeightfieldDesc d;
    d.width = d.height = n;
    d.spacing_x = d.spacing_z = 1.0;
    d.height_scale = scenes::kWorldHeightScale;
    d.max_samples = ~std::uint64_t{0};
    d.name = "generated world " + std::to_string(n);
    auto hf = Heightfield::create(d, std::vector<float>(raw.begin(), raw.end()));
    if (!hf) {
      std::fprintf(stderr, "ridge-bench-world: %s\n", hf.error().message.c_str());
      std::exit(1);
    }
    samples.emplace(std::move(*hf));
  } else {
    source = io::open_world(path);
    if (!source) {
      std::fprintf(stderr, "ridge-bench-world: %s\n", source.error().message.c_str());
      std::exit(1);
    }
  }
  const auto t1 = Clock::now();
  WorldCacheDesc cache;
  cache.budget_bytes = o.budget_mb << 20;
  cache.worker_threads = o.workers;
  auto terrain = memory ? Terrain::create(std::move(*samples)).value()
                        : Terrain::open(*source, cache).value();
  samples.reset();
  const auto t2 = Clock::now();
  auto landscape = Landscape::create(terrain).value();
  const auto t3 = Clock::now();
  RoamSettings settings;
  settings.threshold = o.pixels;
  settings.budget_ms = o.update_budget_ms;
  auto view = RoamView::create(landscape, settings).value();
  const auto t4 = Clock::now();
  const WorldInfo& w = terrain->info();
  Flight flight{w.origin_x + 0.5 * w.extent_x(), w.origin_z + 0.5 * w.extent_z(),
                0.4 * std::min(w.extent_x(), w.extent_z()), o.speed};
  Camera cam = flight.camera(*terrain, 0, o);
  auto first = view->update(cam);
  const auto t5 = Clock::now();
  out["open"] = {{memory ? "generate_and_heightfield_ms" : "open_world_ms", ms_between(t0, t1)},
                 {memory ? "terrain_create_ms" : "terrain_open_ms", ms_between(t1, t2)},
                 {"landscape_create_ms", ms_between(t2, t3)},
                 {"view_create_ms", ms_between(t3, t4)},
                 {"first_update_ms", ms_between(t4, t5)},
                 {"open_to_first_mesh_ms", ms_between(t0, t5)},
                 {"first_mesh_triangles", first ? first->triangles : 0},
                 {"rss_growth_bytes", status_bytes("VmRSS") - std::min(rss_before, status_bytes("VmRSS"))}};

  // ---- a snapshot for another thread (Terrain::clone), before and after edits ----------------
  if (!memory) {
    // On a terrain of its own over the same world (its edits stay out of the flight).
    auto scratch = Terrain::open(*source, cache).value();
    auto time_clone = [&] {
      const std::size_t r0 = status_bytes("VmRSS");
      const auto c0 = Clock::now();
      auto copy = scratch->clone();
      const auto c1 = Clock::now();
      const std::size_t r1 = status_bytes("VmRSS");
      return nlohmann::json{{"ms", ms_between(c0, c1)}, {"rss_growth_bytes", r1 - std::min(r0, r1)}};
    };
    nlohmann::json clone;
    clone["pristine"] = time_clone();
    for (int k = 0; k < 16; ++k) {
      Edit e;
      e.brush = Brush::kCrater;
      e.x = w.origin_x + (0.2 + 0.04 * k) * w.extent_x();
      e.z = w.origin_z + 0.3 * w.extent_z();
      e.radius = 12;
      e.depth = 2;
      (void)scratch->apply_edit(e);
    }
    clone["after_16_craters"] = time_clone();
    out["clone"] = clone;
  }

  // ---- convergence after the open and after teleports ----------------------------------------
  const double period_s = 1.0 / o.fps;
  auto converge_wall = [&](const Camera& c) {
    const auto s0 = Clock::now();
    std::uint32_t frames = 0;
    for (;;) {
      const auto f0 = Clock::now();
      auto st = view->update(c);
      ++frames;
      if (st && st->stop == StopReason::kConverged && st->pending_splits == 0 &&
          st->requested_pages == 0)
        break;
      if (ms_between(s0, Clock::now()) > 30000) break;
      std::this_thread::sleep_until(f0 + std::chrono::duration<double>(period_s));
    }
    return nlohmann::json{{"seconds", ms_between(s0, Clock::now()) / 1000},
                          {"frames", frames},
                          {"triangles", view->triangle_count()}};
  };
  out["converge_after_open"] = converge_wall(cam);
  std::mt19937 rng(o.seed);
  std::uniform_real_distribution<double> u(0.05, 0.95), ang(0, 6.283);
  nlohmann::json tele = nlohmann::json::array();
  for (std::uint32_t k = 0; k < o.teleports; ++k) {
    Camera c = cam;
    const double x = w.origin_x + u(rng) * w.extent_x(), z = w.origin_z + u(rng) * w.extent_z();
    const double ground = terrain->height(x, z).value_or(w.height_offset);
    const double a = ang(rng);
    c.eye = {x, ground + o.clearance, z};
    c.target = c.eye + glm::dvec3(std::cos(a), -std::tan(0.25), std::sin(a));
    tele.push_back(converge_wall(c));
  }
  out["converge_after_teleport"] = tele;
  std::vector<double> tele_s;
  for (const auto& t : tele) tele_s.push_back(t["seconds"].get<double>());
  out["converge_after_teleport_max_seconds"] =
      tele_s.empty() ? 0.0 : *std::max_element(tele_s.begin(), tele_s.end());

  // ---- the flight ------------------------------------------------------------------------------
  std::fprintf(stderr, "size %u: flying %.1f min at %.0f m/s\n", n, o.minutes, o.speed);
  reset_peak_rss();
  const WorldStats ws0 = terrain->world_stats();
  std::vector<double> update_ms, frame_ms;
  std::uint64_t frames_waiting = 0, pending_splits = 0, overruns = 0;
  std::uint32_t longest_wait = 0, wait_run = 0;
  std::size_t rss_max = 0, cache_max = 0, samples_at_cache_max = 0, triangles_max = 0;
  double bytes_per_sample_max = 0;
  const auto start = Clock::now();
  auto next_sample = start;
  const double total_s = o.minutes * 60;
  for (std::uint64_t frame = 0;; ++frame) {
    const double t = double(frame) * period_s;
    if (t >= total_s) break;
    const auto due = start + std::chrono::duration_cast<Clock::duration>(
                                 std::chrono::duration<double>(t));
    std::this_thread::sleep_until(due);
    const auto f0 = Clock::now();
    cam = flight.camera(*terrain, t, o);
    // The ground ahead (3 s), as a game keeps the pages under its player's path resident.
    const glm::dvec2 ahead = flight.at(t + 3.0);
    terrain->prefetch({{ahead.x - 300, -1e9, ahead.y - 300}, {ahead.x + 300, 1e9, ahead.y + 300}});
    auto st = view->update(cam);
    const auto f1 = Clock::now();
    if (!st) continue;
    update_ms.push_back(st->update_ms);
    frame_ms.push_back(ms_between(f0, f1));
    if (ms_between(due, f1) > 1000.0 * period_s) ++overruns;
    pending_splits += st->pending_splits;
    triangles_max = std::max<std::size_t>(triangles_max, st->triangles);
    if (st->requested_pages > 0 || st->pending_splits > 0) {
      ++frames_waiting;
      longest_wait = std::max(longest_wait, ++wait_run);
    } else {
      wait_run = 0;
    }
    if (f1 >= next_sample) {
      next_sample = f1 + std::chrono::seconds(1);
      rss_max = std::max(rss_max, status_bytes("VmRSS"));
      const WorldStats s = terrain->world_stats();
      if (s.resident_bytes > cache_max) {
        cache_max = s.resident_bytes;
        samples_at_cache_max = s.resident_samples;
      }
      if (s.resident_samples > 0)
        bytes_per_sample_max =
            std::max(bytes_per_sample_max, double(s.resident_bytes) / double(s.resident_samples));
    }
  }
  const WorldStats ws1 = terrain->world_stats();
  const double budget = settings.budget_ms;
  out["flight"] = {
      {"minutes", o.minutes},
      {"speed_m_per_s", o.speed},
      {"frames", update_ms.size()},
      {"threshold_px", o.pixels},
      {"viewport", {o.width, o.height}},
      {"update_budget_ms", budget},
      {"update_ms_median", quantile(update_ms, 0.5)},
      {"update_ms_p99", quantile(update_ms, 0.99)},
      {"update_ms_max", quantile(update_ms, 1.0)},
      {"update_p99_limit_ms", budget > 0 ? 1.1 * budget + 0.1 : 0.0},
      {"frame_ms_p99", quantile(frame_ms, 0.99)},
      {"frames_over_period", overruns},
      {"frames_waiting_for_pages", frames_waiting},
      {"longest_wait_frames", longest_wait},
      {"splits_waiting_total", pending_splits},
      {"triangles_max", triangles_max},
      {"pages_loaded", ws1.loaded - ws0.loaded},
      {"pages_evicted", ws1.evicted - ws0.evicted},
      {"sync_loads", ws1.sync_loads - ws0.sync_loads},
      {"load_seconds", ws1.load_seconds - ws0.load_seconds},
      {"cache_budget_bytes", ws1.budget_bytes},
      {"cache_bytes_max", cache_max},
      {"cache_over_budget", double(cache_max) / double(std::max<std::size_t>(1, ws1.budget_bytes))},
      {"resident_samples_at_max", samples_at_cache_max},
      {"bytes_per_resident_sample_max", bytes_per_sample_max},
      {"process_rss_max_bytes", rss_max},
      {"process_rss_peak_bytes", status_bytes("VmHWM")}};
  std::fprintf(stderr, "size %u: %s\n", n, out["flight"].dump().c_str());
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  ridgeline::cli::keep_page_buffers_in_one_arena();
  CLI::App app{
      "ridge bench world: bakes the project's generated worlds, then measures open to first mesh, "
      "convergence and a real-time flight under a cache budget (JSON; docs/worlds.md)"};
  Options o;
  std::string json_path;
  app.add_option("--dir", o.dir, "Folder of the baked worlds (made when missing; default build/worlds)");
  app.add_option("--sizes", o.sizes, "Samples per side of the generated worlds (default 4097 16385)")
      ->delimiter(',')
      ->check(CLI::Range(257u, 1u << 20));
  app.add_option("--seed", o.seed, "Seed of the generated worlds (default 1)");
  app.add_option("--minutes", o.minutes, "Length of each flight, minutes (default 10)")
      ->check(CLI::Range(0.0, 600.0));
  app.add_option("--speed", o.speed, "Ground speed, m/s (default 300)")->check(CLI::Range(1.0, 1e4));
  app.add_option("--fps", o.fps, "Frames per second of the flight (default 60)")
      ->check(CLI::Range(1.0, 1000.0));
  app.add_option("--pixels", o.pixels, "Screen-space threshold, pixels (default 2)")
      ->check(CLI::Range(0.1, 100.0));
  app.add_option("--update-budget-ms", o.update_budget_ms,
                 "Time budget of each view update, ms (default 2; 0 = none)")
      ->check(CLI::Range(0.0, 1000.0));
  app.add_option("--cache-mb", o.budget_mb, "Page cache budget, MiB (default 128)")
      ->check(CLI::Range(4, 1 << 20));
  app.add_option("--workers", o.workers, "Page loading threads (default 2)")->check(CLI::Range(0, 64));
  app.add_option("--teleports", o.teleports, "Teleports timed after the open (default 5)")
      ->check(CLI::Range(0, 1000));
  app.add_option("--bake-threads", o.bake_threads, "Bake threads (default 0: every core)");
  app.add_flag("--in-memory", o.in_memory,
               "Also fly each size over the terrain made in memory from the same samples (after "
               "every baked world's run; it needs about 12 bytes a sample while made, and sizes that would "
               "not fit in memory are reported as skipped)");
  app.add_option("--json", json_path, "Write the JSON to FILE instead of standard output");
  CLI11_PARSE(app, argc, argv);

  nlohmann::json j;
  j["benchmark"] = "world";
  j["load_average_before"] = load_average();
  j["hardware_threads"] = std::thread::hardware_concurrency();
  j["runs"] = nlohmann::json::array();
  // Every baked world first, then (--in-memory) the terrains made in memory: the memory an
  // in-memory terrain leaves to the allocator would count in a paged run after it.
  for (std::uint32_t n : o.sizes) j["runs"].push_back(run_size(o, n, false));
  for (std::uint32_t n : o.sizes) {
    if (!o.in_memory) break;
    // The terrain in memory holds its samples as floats while it is made (4 bytes a sample,
    // beside the 2-byte generated ones) and about 6 bytes a sample after: a size that would not
    // fit in the machine's memory is reported, not tried.
    const double need = 12.0 * double(n) * double(n);
    const double have = double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGE_SIZE));
    if (need > 0.8 * have) {
      j["runs"].push_back({{"size", n},
                           {"path", "memory"},
                           {"skipped", "needs about " + std::to_string(int(need / 1e9)) +
                                           " GB in memory; the machine has " +
                                           std::to_string(int(have / 1e9)) + " GB"}});
      continue;
    }
    j["runs"].push_back(run_size(o, n, true));
  }
  j["load_average_after"] = load_average();
  const std::string text = j.dump(2) + "\n";
  if (json_path.empty()) {
    std::fwrite(text.data(), 1, text.size(), stdout);
  } else {
    std::ofstream f(json_path);
    f << text;
    if (!f) {
      std::fprintf(stderr, "ridge-bench-world: cannot write '%s'\n", json_path.c_str());
      return 1;
    }
  }
  return 0;
}
