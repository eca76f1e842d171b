// Stats JSON with nlohmann-json; PNG screenshots with OpenImageIO.
#include "run_stats.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "ridgeline/bench/stats.h"

namespace game {

void RunStats::record(const Game& game, FrameRecord r) {
  (void)game;
  frames_.push_back(std::move(r));
}

namespace {
// The q-quantile of ridgeline/bench/stats.h, 0 when there are no frames.
double at(const std::vector<double>& v, double q) { return ridgeline::bench::quantile_or(v, q, 0.0); }
}  // namespace

ridgeline::Status RunStats::write(const std::string& path, const std::string& mode,
                                  const Game& game, std::uint64_t skip_frames) const {
  using nlohmann::json;
  json frames = json::array();
  std::vector<double> ms, thr, scale, tris, cpu, main_cpu;
  struct Part {
    const char* name;
    double FrameRecord::*field;
    std::vector<double> v;
  };
  std::vector<Part> parts = {
      {"scripts", &FrameRecord::scripts_ms, {}},   {"physics", &FrameRecord::physics_ms, {}},
      {"tessellation", &FrameRecord::tess_ms, {}}, {"upload", &FrameRecord::upload_ms, {}},
      {"render", &FrameRecord::render_ms, {}},     {"panel", &FrameRecord::panel_ms, {}}};
  std::vector<double> other;
  std::size_t resident_max = 0, pending_max = 0, steady = 0, converged = 0, capped = 0, timed = 0;
  std::uint64_t generated_first = 0, generated_last = 0, contact_frames = 0, body_frames = 0;
  std::size_t bodies_max = 0;
  bool first_steady = true;
  for (const FrameRecord& f : frames_) {
    json vs = json::array();
    for (const auto& v : f.vehicles)
      vs.push_back({{"id", v.id},
                    {"position", {v.x, v.y, v.z}},
                    {"speed", v.speed},
                    {"waypoints_reached", v.reached},
                    {"min_wheel_gap_m", v.min_gap},
                    {"max_contact_gap_m", v.max_contact_gap},
                    {"wheels_in_contact", v.contacts},
                    {"material", v.material},
                    {"collisions", v.collisions},
                    {"body_hits", v.body_hits}});
    frames.push_back({{"frame", f.frame},
                      {"time_s", f.time_s},
                      {"wall_s", f.wall_s},
                      {"smoothed_ms", f.smoothed_ms},
                      {"controller_reversals", f.reversals},
                      {"frame_ms", f.frame_ms},
                      {"cpu_ms", f.cpu_ms},
                      {"main_thread_cpu_ms", f.main_cpu_ms},
                      {"sim_ms", f.sim_ms},
                      {"scripts_ms", f.scripts_ms},
                      {"physics_ms", f.physics_ms},
                      {"tessellation_ms", f.tess_ms},
                      {"upload_ms", f.upload_ms},
                      {"patch_mesh_ms", f.patch_mesh_ms},
                      {"render_ms", f.render_ms},
                      {"panel_ms", f.panel_ms},
                      {"burn_ms", f.burn_ms},
                      {"screenshot_ms", f.screenshot_ms},
                      {"threshold_px", f.threshold},
                      {"render_scale", f.render_scale},
                      {"triangles", f.triangles},
                      {"splits", f.splits},
                      {"merges", f.merges},
                      {"pending_splits", f.pending_splits},
                      {"stop", f.stop == 0   ? "converged"
                               : f.stop == 1 ? "triangles"
                               : f.stop == 2 ? "time"
                                             : "none"},
                      {"patches_uploaded", f.patches_uploaded},
                      {"bytes_uploaded", f.bytes_uploaded},
                      {"view_upload_bytes", f.view_upload_bytes},
                      {"vehicle_contacts", f.contacts},
                      {"body_vehicle_contacts", f.body_contacts},
                      {"bodies", f.bodies},
                      {"bodies_awake", f.bodies_awake},
                      {"detail_tiles_resident", f.tiles_resident},
                      {"detail_tiles_pending", f.tiles_pending},
                      {"detail_tiles_generated", f.tiles_generated},
                      {"vehicles", vs}});
    if (f.frame >= skip_frames) {
      ms.push_back(f.frame_ms);
      cpu.push_back(f.cpu_ms);
      main_cpu.push_back(f.main_cpu_ms);
      thr.push_back(f.threshold);
      scale.push_back(f.render_scale);
      tris.push_back(f.triangles);
      double sum = 0;
      for (Part& p : parts) {
        p.v.push_back(f.*(p.field));
        sum += f.*(p.field);
      }
      other.push_back(std::max(0.0, f.frame_ms - sum));
      resident_max = std::max(resident_max, f.tiles_resident);
      pending_max = std::max(pending_max, f.tiles_pending);
      if (first_steady) generated_first = f.tiles_generated;
      first_steady = false;
      generated_last = f.tiles_generated;
      ++steady;
      converged += f.stop == 0;
      capped += f.stop == 1;
      timed += f.stop == 2;
      contact_frames += f.contacts > 0;
      body_frames += f.body_contacts > 0;
      bodies_max = std::max(bodies_max, f.bodies);
    }
  }
  json errors = json::array();
  for (const ScriptError& e : game.errors())
    errors.push_back({{"script", e.script}, {"frame", e.frame}, {"message", e.message}});
  auto pcts = [](const std::vector<double>& v) {
    return json{{"p10", at(v, 0.10)},
                {"p50", at(v, 0.50)},
                {"p90", at(v, 0.90)},
                {"p99", at(v, 0.99)},
                {"max", v.empty() ? 0.0 : *std::max_element(v.begin(), v.end())}};
  };
  auto mean = [](const std::vector<double>& v) {
    return ridgeline::bench::or_value(ridgeline::bench::mean(v), 0.0);
  };
  json breakdown = json::object();
  for (const Part& p : parts)
    breakdown[p.name] = {{"p50", at(p.v, 0.50)}, {"mean", mean(p.v)}};
  breakdown["other"] = {{"p50", at(other, 0.50)}, {"mean", mean(other)}};
  {
    std::vector<double> pm;
    for (const FrameRecord& f : frames_)
      if (f.frame >= skip_frames) pm.push_back(f.patch_mesh_ms);
    breakdown["upload_patch_mesh_part"] = {{"p50", at(pm, 0.50)}, {"mean", mean(pm)}};
  }
  json upload_bytes;
  {
    std::vector<double> b;
    for (const FrameRecord& f : frames_)
      if (f.frame >= skip_frames) b.push_back(double(f.bytes_uploaded));
    upload_bytes = {{"p50", at(b, 0.50)},
                    {"p99", at(b, 0.99)},
                    {"mean", mean(b)},
                    {"max", b.empty() ? 0.0 : *std::max_element(b.begin(), b.end())}};
  }
  const double n = steady > 0 ? double(steady) : 1.0;
  json summary = {
      {"frames", frames_.size()},
      {"steady_state_from_frame", skip_frames},
      {"frame_ms", pcts(ms)},
      {"cpu_ms", pcts(cpu)},
      {"main_thread_cpu_ms", pcts(main_cpu)},
      {"threshold_px",
       {{"p10", at(thr, 0.10)}, {"p50", at(thr, 0.50)}, {"p90", at(thr, 0.90)}}},
      {"render_scale",
       {{"p10", at(scale, 0.10)},
        {"p50", at(scale, 0.50)},
        {"p90", at(scale, 0.90)},
        {"min", scale.empty() ? 1.0 : *std::min_element(scale.begin(), scale.end())}}},
      {"upload_bytes", upload_bytes},
      {"triangles",
       {{"p50", at(tris, 0.50)},
        {"max", tris.empty() ? 0.0 : *std::max_element(tris.begin(), tris.end())}}},
      {"view_stop_fraction",
       {{"converged", double(converged) / n},
        {"triangles", double(capped) / n},
        {"time", double(timed) / n}}},
      {"frame_time_breakdown_ms", breakdown},
      {"detail_levels", game.terrain().surface().detail_levels()},
      {"detail_tiles_resident_max", resident_max},
      {"detail_tiles_pending_max", pending_max},
      {"detail_tiles_generated", generated_last - generated_first},
      {"frames_with_vehicle_contacts", contact_frames},
      {"frames_with_bodies_touching_vehicles", body_frames},
      {"loose_bodies_max", bodies_max},
      {"target_ms", game.controller().desc().target_ms},
      {"controller_range_px",
       {game.controller().desc().min_threshold, game.controller().desc().max_threshold}},
      {"controller_min_render_scale", game.controller().desc().min_render_scale},
      {"controller", game.controller_on()},
      {"craters", game.craters().size()},
      {"script_errors", game.error_count()}};
  json doc = {{"mode", mode},
              {"dt_s", game.dt()},
              {"viewport", {game.options().viewport.x, game.options().viewport.y}},
              {"summary", summary},
              {"errors", errors},
              {"frames", frames}};
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    if (!out) return ridgeline::Error{"stats: cannot write '" + path + "'"};
    out << doc.dump(1) << "\n";
    if (!out) return ridgeline::Error{"stats: write to '" + path + "' failed"};
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) return ridgeline::Error{"stats: cannot rename to '" + path + "': " + ec.message()};
  return {};
}

ridgeline::Status write_png(const std::string& path, int width, int height,
                            const std::vector<std::uint8_t>& rgba) {
  const std::string tmp = path + ".tmp.png";
  auto out = OIIO::ImageOutput::create(tmp);
  if (!out) return ridgeline::Error{"screenshot '" + path + "': no PNG writer"};
  OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
  if (!out->open(tmp, spec))
    return ridgeline::Error{"screenshot '" + path + "': " + out->geterror()};
  // RGBA in memory, RGB in the file: the x stride skips alpha.
  if (!out->write_image(OIIO::TypeDesc::UINT8, rgba.data(), 4, OIIO::AutoStride)) {
    const std::string e = out->geterror();
    out->close();
    return ridgeline::Error{"screenshot '" + path + "': " + e};
  }
  out->close();
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) return ridgeline::Error{"screenshot: cannot rename to '" + path + "': " + ec.message()};
  return {};
}

}  // namespace game
