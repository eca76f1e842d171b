// `ridge bench detail`: detail tile generation time per level on one core, bytes per tile, and
// the detail cache along a camera path (a PATH.json or a built-in straight flight): per frame,
// the tiles the request rule asks for (detail_stream.h), resident bytes, pending tiles, lag and
// generation rate. JSON; docs/cli.md and docs/detail.md.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <glm/geometric.hpp>
#include <memory>
#include <thread>

#include "cli_util.h"
#include "ridgeline/bench/clock.h"
#include "ridgeline/bench/stats.h"
#include "commands.h"
#include "ridgeline/camera_path.h"
#include "ridgeline/detail_stream.h"
#include "terrain_args.h"

namespace ridgeline::cli {

namespace {

using bench::Clock;

struct BenchDetailArgs {
  TerrainArgs terrain;
  std::string tile_reps = "101";
  std::string path, from, to, distance, speed = "300", altitude = "50", fps = "60",
                                        viewport = "1280,720", fov = "60";
  std::string pixels = "1", prefetch = "0.25";
  std::string workers = "2", budget_mb, terrain_budget_mb;
  bool no_pace = false, prefill = false;
  std::string frames_every = "60";
  std::string json_path;
};

// Peak resident set of this process (VmHWM), bytes; 0 where /proc is not there.
std::size_t peak_rss_bytes() {
  std::ifstream in("/proc/self/status");
  std::string key;
  while (in >> key) {
    if (key == "VmHWM:") {
      std::size_t kb = 0;
      in >> kb;
      return kb * 1024;
    }
    std::getline(in, key);
  }
  return 0;
}

// Generation time of one tile per level, each timed alone, from a fixed parent on this thread.
nlohmann::ordered_json time_tiles(const DetailField& f, int reps, std::size_t* tile_bytes) {
  nlohmann::ordered_json out = nlohmann::ordered_json::array();
  volatile std::int32_t sink = 0;
  for (std::uint32_t level = 1; level <= f.levels(); ++level) {
    // The tile over the middle of the terrain.
    const DetailTileKey key{
        level, std::int32_t(((std::int64_t{f.base_width()} - 1) / 2 << level) / kDetailTileCells),
        std::int32_t(((std::int64_t{f.base_height()} - 1) / 2 << level) / kDetailTileCells)};
    const auto parent = level > 1 ? f.make_tile_chain(key.parent()) : nullptr;
    std::vector<double> ms;
    for (int r = -3; r < reps; ++r) {  // three unreported warm-up runs
      const auto t0 = Clock::now();
      const auto tile = f.make_tile(key, parent.get());
      const double t = bench::ms_since(t0);
      sink = sink + tile->raw(64, 64);
      *tile_bytes = tile->memory_bytes();
      if (r >= 0) ms.push_back(t);
    }
    const double spacing = std::ldexp(std::max(f.spacing_x(), f.spacing_z()), -int(level));
    out.push_back({{"level", level},
                   {"spacing_m", spacing},
                   {"median_ms", bench::quantile_or(ms, 0.5, 0)},
                   {"p99_ms", bench::quantile_or(ms, 0.99, 0)},
                   {"min_ms", bench::quantile_or(ms, 0.0, 0)},
                   {"bytes", *tile_bytes}});
  }
  return out;
}

// The cameras of the flight: a PATH.json, or a straight line at `altitude` metres above the
// stored surface, looking ahead and slightly down.
struct Flight {
  std::vector<io::PathFrame> frames;
  double metres = 0;
  nlohmann::ordered_json description;
};

Result<Flight> make_flight(const BenchDetailArgs& a, const Terrain& terrain) {
  Flight fl;
  auto vp = parse_finite_list(a.viewport, "--viewport", 2, 2);
  if (!vp) return vp.error();
  if ((*vp)[0] < 1 || (*vp)[1] < 1 || (*vp)[0] > 65536 || (*vp)[1] > 65536 ||
      (*vp)[0] != std::floor((*vp)[0]) || (*vp)[1] != std::floor((*vp)[1]))
    return Error{"--viewport: need whole W,H in 1 .. 65536"};
  auto fov = parse_finite(a.fov, "--fov-y");
  if (!fov) return fov.error();
  if (!a.path.empty()) {
    if (!a.from.empty() || !a.to.empty() || !a.distance.empty())
      return Error{"--from, --to and --distance describe the built-in flight; not with --path"};
    auto frames = io::load_camera_path(a.path);
    if (!frames) return frames.error();
    fl.frames = std::move(*frames);
    for (std::size_t k = 1; k < fl.frames.size(); ++k)
      fl.metres += glm::length(fl.frames[k].camera.eye - fl.frames[k - 1].camera.eye);
    fl.description = {{"path", a.path}, {"frames", fl.frames.size()}};
    return fl;
  }
  const WorldInfo& hf = terrain.info();
  const double mid_z = hf.origin_z + 0.5 * hf.extent_z();
  std::vector<double> from = {hf.origin_x + 0.05 * hf.extent_x(), mid_z};
  std::vector<double> to = {hf.origin_x + 0.95 * hf.extent_x(), mid_z};
  if (!a.from.empty()) {
    auto v = parse_finite_list(a.from, "--from", 2, 2);
    if (!v) return v.error();
    from = *v;
  }
  if (!a.to.empty()) {
    auto v = parse_finite_list(a.to, "--to", 2, 2);
    if (!v) return v.error();
    to = *v;
  }
  for (const auto& p : {from, to})
    if (!terrain.height(p[0], p[1]))
      return Error{"--from/--to: (" + csv_number(p[0]) + ", " + csv_number(p[1]) +
                   ") is off the terrain"};
  auto speed = parse_finite(a.speed, "--speed");
  if (!speed) return speed.error();
  if (*speed <= 0) return Error{"--speed must be > 0 (metres per second)"};
  auto altitude = parse_finite(a.altitude, "--altitude");
  if (!altitude) return altitude.error();
  if (*altitude < 0) return Error{"--altitude must be >= 0 (metres above the stored surface)"};
  auto fps = parse_finite(a.fps, "--fps");
  if (!fps) return fps.error();
  if (*fps <= 0 || *fps > 10000) return Error{"--fps must be in (0, 10000]"};
  const glm::dvec2 p0(from[0], from[1]), p1(to[0], to[1]);
  double length = glm::length(p1 - p0);
  if (length <= 0) return Error{"--from and --to are the same point"};
  if (!a.distance.empty()) {
    auto d = parse_finite(a.distance, "--distance");
    if (!d) return d.error();
    if (*d <= 0) return Error{"--distance must be > 0 metres"};
    length = std::min(length, *d);
  }
  const double step = *speed / *fps;
  const double n = std::floor(length / step);
  if (n > 10000000) return Error{"the flight would take more than 10,000,000 frames"};
  const glm::dvec2 dir = (p1 - p0) / glm::length(p1 - p0);
  for (std::size_t k = 0; k <= std::size_t(n); ++k) {
    const glm::dvec2 p = p0 + dir * (step * double(k));
    const double y = *terrain.height(p.x, p.y) + *altitude;
    io::PathFrame f;
    f.dt = 1.0 / *fps;
    f.camera.eye = {p.x, y, p.y};
    f.camera.target = {p.x + 200 * dir.x, y - 30, p.y + 200 * dir.y};
    f.camera.fov_y_deg = *fov;
    f.camera.viewport = {int((*vp)[0]), int((*vp)[1])};
    if (auto s = validate_camera(f.camera); !s) return Error{s.message()};
    fl.frames.push_back(f);
  }
  fl.metres = step * n;
  fl.description = {{"from", from},        {"to", to},
                    {"metres", fl.metres}, {"speed_m_per_s", *speed},
                    {"fps", *fps},         {"altitude_m", *altitude},
                    {"viewport", *vp},     {"fov_y", *fov}};
  return fl;
}

int run_bench_detail(const BenchDetailArgs& a) {
  auto params = a.terrain.detail_params();
  if (!params) return report_error(params.error().message);
  if (params->levels == 0) return report_error("--detail-levels must be >= 1 for a detail bench");
  if (a.terrain.given("--detail-budget-mb"))
    return report_error(
        "--detail-budget-mb sizes the terrain's own query cache; the streamed cache of this "
        "bench takes --budget-mb or --terrain-budget-mb");
  auto reps = parse_count(a.tile_reps, "--tile-reps", 1, 1000000);
  if (!reps) return report_error(reps.error().message);
  auto workers = parse_count(a.workers, "--workers", 0, 64);
  if (!workers) return report_error(workers.error().message);
  auto every = parse_count(a.frames_every, "--frames-every", 0, 1000000000);
  if (!every) return report_error(every.error().message);
  DetailViewRule rule;
  auto px = parse_finite(a.pixels, "--pixels");
  if (!px) return report_error(px.error().message);
  rule.pixels = *px;
  auto pf = parse_finite(a.prefetch, "--prefetch");
  if (!pf) return report_error(pf.error().message);
  rule.prefetch = *pf;
  if (auto s = validate_detail_view_rule(rule); !s) return report_error(s.message());
  if (!a.budget_mb.empty() && !a.terrain_budget_mb.empty())
    return report_error(
        "--budget-mb (tiles) and --terrain-budget-mb (all terrain data) exclude "
        "each other");

  // The terrain with its detail (as every subcommand loads it, --load included); the bench
  // streams the terrain's detail field through a cache of its own.
  const auto field_t0 = Clock::now();
  auto t = a.terrain.load_terrain();
  if (!t) return report_error(t.error().message);
  const double load_ms = bench::ms_since(field_t0);
  const std::shared_ptr<const Terrain> terrain = *t;
  const WorldInfo& hf = terrain->info();
  if (!terrain->surface().detail()) return report_error("the terrain has no detail field");
  const std::shared_ptr<const DetailField> field(terrain, terrain->surface().detail());
  // Heights, materials, ray pyramid and the detail field's shape map.
  const std::size_t base_bytes = terrain->memory_bytes();

  std::size_t budget = std::size_t{256} << 20;
  if (!a.budget_mb.empty() || !a.terrain_budget_mb.empty()) {
    const bool total = !a.terrain_budget_mb.empty();
    const char* flag = total ? "--terrain-budget-mb" : "--budget-mb";
    auto mb = parse_finite(total ? a.terrain_budget_mb : a.budget_mb, flag);
    if (!mb) return report_error(mb.error().message);
    if (*mb <= 0 || *mb > 1e7) return report_error(std::string(flag) + " must be in (0, 1e7]");
    const double bytes = *mb * double(1 << 20) - (total ? double(base_bytes) : 0.0);
    if (bytes <= 0)
      return report_error(std::string(flag) + ": the base terrain and the detail field already " +
                          "take " + std::to_string(base_bytes) + " bytes");
    budget = std::size_t(bytes);
  }

  auto flight = make_flight(a, *terrain);
  if (!flight) return report_error(flight.error().message);

  // Tile generation on this thread, before the workers start.
  std::size_t tile_bytes = 0;
  nlohmann::ordered_json tiles = time_tiles(*field, int(*reps), &tile_bytes);

  DetailCacheDesc desc;
  desc.budget_bytes = budget;
  desc.worker_threads = static_cast<std::uint32_t>(*workers);
  auto cache = DetailCache::create(field, desc);
  if (!cache) return report_error(cache.error().message);
  auto stream = DetailStream::create(terrain->surface(), **cache, rule);
  if (!stream) return report_error(stream.error().message);

  const Camera& first = flight->frames.front().camera;
  nlohmann::ordered_json radii = nlohmann::ordered_json::array();
  for (std::uint32_t l = 1; l <= field->levels(); ++l)
    radii.push_back(detail_level_radius(*field, first, l, rule));

  // A loading screen: the first frame's tiles generated before the flight (not reported).
  std::size_t prefill_frames = 0;
  if (a.prefill) {
    for (int round = 0; round < 4; ++round) {
      auto st = stream->frame(first);
      if (!st) return report_error(st.error().message);
      ++prefill_frames;
      if (st->needed_resident == st->needed) break;
      (*cache)->wait_idle(600.0);
    }
  }

  const bool pace = desc.worker_threads > 0 && !a.no_pace;
  std::vector<double> frame_ms, request_ms, update_ms, fraction, gen_rate;
  std::uint64_t worst_late = 0;
  std::size_t max_resident = 0, max_pending = 0, max_requested = 0, max_needed = 0;
  std::size_t frames_missing = 0, first_complete = flight->frames.size();
  std::uint64_t worst_late_after_first_complete = 0, overrun_frames = 0;
  nlohmann::ordered_json frames = nlohmann::ordered_json::array();
  const std::uint64_t frame0 = (*cache)->stats().frame;
  const auto wall0 = Clock::now();
  auto deadline = wall0;
  for (std::size_t k = 0; k < flight->frames.size(); ++k) {
    const io::PathFrame& pf_k = flight->frames[k];
    auto st = stream->frame(pf_k.camera);
    if (!st) return report_error("frame " + std::to_string(k) + ": " + st.error().message);
    const double ms = st->request_ms + st->update_ms;
    frame_ms.push_back(ms);
    request_ms.push_back(st->request_ms);
    update_ms.push_back(st->update_ms);
    worst_late = std::max(worst_late, st->late_frames);
    const double frac = st->needed ? double(st->needed_resident) / double(st->needed) : 1.0;
    fraction.push_back(frac);
    if (st->cache.generated_per_second > 0) gen_rate.push_back(st->cache.generated_per_second);
    max_resident = std::max(max_resident, st->cache.resident_bytes);
    max_pending = std::max(max_pending, st->cache.pending);
    max_requested = std::max(max_requested, st->requested);
    max_needed = std::max(max_needed, st->needed);
    if (st->needed_resident < st->needed) ++frames_missing;
    if (first_complete == flight->frames.size() && st->needed_resident == st->needed)
      first_complete = k;
    if (first_complete < k)
      worst_late_after_first_complete = std::max(worst_late_after_first_complete, st->late_frames);
    if (*every > 0 && k % *every == 0)
      frames.push_back({{"frame", k},
                        {"eye", {pf_k.camera.eye.x, pf_k.camera.eye.y, pf_k.camera.eye.z}},
                        {"requested", st->requested},
                        {"needed", st->needed},
                        {"needed_resident", st->needed_resident},
                        {"late_frames", st->late_frames},
                        {"resident_tiles", st->cache.resident_tiles},
                        {"resident_bytes", st->cache.resident_bytes},
                        {"pending", st->cache.pending},
                        {"generated_per_second", st->cache.generated_per_second},
                        {"frame_ms", ms}});
    if (pace) {
      // A game loop: the next frame starts dt after this one was due.
      deadline +=
          std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(pf_k.dt));
      if (Clock::now() > deadline)
        ++overrun_frames;
      else
        std::this_thread::sleep_until(deadline);
    }
  }
  const double wall_s = std::chrono::duration<double>(Clock::now() - wall0).count();
  const DetailCacheStats cs = (*cache)->stats();
  const std::uint64_t virtual_samples_x = (std::uint64_t{hf.width} - 1) << field->levels();
  const std::uint64_t virtual_samples_z = (std::uint64_t{hf.height} - 1) << field->levels();
  const double spacing = std::max(hf.spacing_x, hf.spacing_z);
  const std::size_t n = flight->frames.size();

  nlohmann::ordered_json j;
  j["terrain"] = {{"source", a.terrain.source()},
                  {"width", hf.width},
                  {"height", hf.height},
                  {"spacing_m", {hf.spacing_x, hf.spacing_z}},
                  {"extent_m", {hf.extent_x(), hf.extent_z()}},
                  {"memory_bytes", terrain->memory_bytes()}};
  j["detail"] = {{"levels", params->levels},
                 {"seed", params->seed},
                 {"amplitude", params->amplitude},
                 {"gain", params->gain},
                 {"flat_shape", params->flat_shape},
                 {"steep_shape", params->steep_shape},
                 {"flat_slope", params->flat_slope},
                 {"steep_slope", params->steep_slope},
                 {"blur_radius", params->blur_radius},
                 {"finest_spacing_m", std::ldexp(spacing, -int(params->levels))},
                 {"virtual_samples", double(virtual_samples_x + 1) * double(virtual_samples_z + 1)},
                 {"field_bytes", field->memory_bytes()},
                 {"terrain_load_ms", load_ms},
                 {"amplitude_bound_m", field->contribution_bound(1)}};
  j["tiles"] = tiles;
  j["tile_bytes"] = tile_bytes;
  j["rule"] = {{"pixels", rule.pixels},
               {"prefetch", rule.prefetch},
               {"projection_scale", projection_scale(first)},
               {"radius_m_by_level", radii}};
  j["flight"] = flight->description;
  j["cache"] = {{"workers", desc.worker_threads},
                {"mode", desc.worker_threads ? "asynchronous" : "synchronous"},
                {"budget_bytes", budget},
                {"paced", pace},
                {"prefill_frames", prefill_frames}};
  j["summary"] = {
      {"frames", n},
      {"simulated_s", flight->metres > 0 && n > 1 ? double(n - 1) * flight->frames[0].dt : 0.0},
      {"wall_s", wall_s},
      {"max_resident_bytes", max_resident},
      {"max_resident_mb", double(max_resident) / double(1 << 20)},
      {"resident_within_budget", max_resident <= budget},
      {"max_terrain_data_bytes", max_resident + base_bytes},
      {"base_and_field_bytes", base_bytes},
      {"max_working_set_bytes", max_requested * tile_bytes},
      {"max_requested_tiles", max_requested},
      {"max_needed_tiles", max_needed},
      {"needed_resident_fraction_min", bench::quantile_or(fraction, 0.0, 0)},
      {"needed_resident_fraction_mean",
       fraction.empty() ? 1.0 : [&] {
         double s = 0;
         for (double f : fraction) s += f;
         return s / double(fraction.size());
       }()},
      {"frames_missing_needed_tiles", frames_missing},
      {"first_complete_frame", first_complete < n ? nlohmann::ordered_json(first_complete)
                                                  : nlohmann::ordered_json(nullptr)},
      {"worst_late_frames", worst_late},
      {"worst_late_frames_after_first_complete", worst_late_after_first_complete},
      {"cache_worst_lag_frames", cs.worst_lag_frames},
      {"max_pending", max_pending},
      {"generated", cs.generated},
      {"evicted", cs.evicted},
      {"generated_per_second_median", bench::quantile_or(gen_rate, 0.5, 0)},
      {"generated_per_second_max", bench::quantile_or(gen_rate, 1.0, 0)},
      {"generation_ms_per_tile",
       cs.generated ? 1000.0 * cs.generation_seconds / double(cs.generated) : 0.0},
      {"frame_ms_median", bench::quantile_or(frame_ms, 0.5, 0)},
      {"frame_ms_p99", bench::quantile_or(frame_ms, 0.99, 0)},
      {"frame_ms_max", bench::quantile_or(frame_ms, 1.0, 0)},
      {"request_ms_median", bench::quantile_or(request_ms, 0.5, 0)},
      {"request_ms_p99", bench::quantile_or(request_ms, 0.99, 0)},
      {"update_ms_median", bench::quantile_or(update_ms, 0.5, 0)},
      {"update_ms_p99", bench::quantile_or(update_ms, 0.99, 0)},
      {"overrun_frames", overrun_frames},
      {"cache_frames", cs.frame - frame0},
      {"process_peak_rss_bytes", peak_rss_bytes()}};
  j["frames"] = frames;
  if (auto s = write_json(j, a.json_path); !s) return report_error(s.message());
  return 0;
}

}  // namespace

Command add_bench_detail_command(CLI::App& bench) {
  auto* app = bench.add_subcommand(
      "detail",
      "Detail tile generation ms per level, bytes per tile, and the detail cache along a camera "
      "path: resident bytes, needed tiles resident, lag, generation rate (JSON)");
  auto a = std::make_shared<BenchDetailArgs>();
  a->terrain.add_to(*app);
  app->add_option("--tile-reps", a->tile_reps,
                  "Tiles timed per level for the generation figures (default 101)")
      ->type_name("N");
  auto* fl = app->add_option_group("Flight");
  fl->add_option("--path", a->path,
                 "Camera path (PATH.json, docs/cli.md) instead of the straight flight")
      ->type_name("PATH.json");
  fl->add_option("--from", a->from,
                 "Start of the straight flight (default: 5 % in from the west edge, middle z)")
      ->type_name("X,Z");
  fl->add_option("--to", a->to, "End of the straight flight (default: 5 % in from the east edge)")
      ->type_name("X,Z");
  fl->add_option("--distance", a->distance, "Stop after this many metres (default: all the way)")
      ->type_name("M");
  fl->add_option("--speed", a->speed, "Metres per second (default 300)")->type_name("V");
  fl->add_option("--altitude", a->altitude,
                 "Eye height above the stored surface under it, metres (default 50)")
      ->type_name("M");
  fl->add_option("--fps", a->fps, "Frames per second: dt = 1 / fps (default 60)")->type_name("F");
  fl->add_option("--viewport", a->viewport, "Viewport in pixels (default 1280,720)")
      ->type_name("W,H");
  fl->add_option("--fov-y", a->fov, "Vertical field of view, degrees (default 60)")
      ->type_name("DEG");
  auto* st = app->add_option_group("Streaming");
  st->add_option(
        "--pixels", a->pixels,
        "Level l is needed within spacing_l * projection_scale / PX of the eye (default 1)")
      ->type_name("PX");
  st->add_option("--prefetch", a->prefetch,
                 "Request tiles within (1 + F) times that radius (default 0.25)")
      ->type_name("F");
  st->add_option("--workers", a->workers, "Worker threads; 0 = synchronous (default 2)")
      ->type_name("N");
  st->add_option("--budget-mb", a->budget_mb, "Byte budget of the tile cache in MiB (default 256)")
      ->type_name("MB");
  st->add_option("--terrain-budget-mb", a->terrain_budget_mb,
                 "Budget of all terrain data in MiB: the tile cache gets what the base terrain and "
                 "the detail field leave")
      ->type_name("MB");
  st->add_flag("--no-pace", a->no_pace,
               "Run frames back to back instead of one per dt of wall time (asynchronous mode)");
  st->add_flag("--prefill", a->prefill,
               "Generate the first frame's tiles before the flight (a loading screen)");
  app->add_option("--frames-every", a->frames_every,
                  "Write every K-th frame's figures (default 60; 0 = summary only)")
      ->type_name("K");
  app->add_option("--json", a->json_path, "Write the JSON to FILE instead of standard output")
      ->type_name("FILE");
  return {app, [a] { return run_bench_detail(*a); }};
}

}  // namespace ridgeline::cli
