// Stats JSON with nlohmann-json; PNG screenshots with OpenImageIO.
#include "run_stats.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

namespace game {

void RunStats::record(const Game& game, FrameRecord r) {
  (void)game;
  frames_.push_back(std::move(r));
}

namespace {
double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const double k = p / 100.0 * double(v.size() - 1);
  const auto i = static_cast<std::size_t>(k);
  const double f = k - double(i);
  return i + 1 < v.size() ? v[i] * (1 - f) + v[i + 1] * f : v[i];
}
}  // namespace

ridgeline::Status RunStats::write(const std::string& path, const std::string& mode,
                                  const Game& game, std::uint64_t skip_frames) const {
  using nlohmann::json;
  json frames = json::array();
  std::vector<double> ms, thr, tris;
  for (const FrameRecord& f : frames_) {
    json vs = json::array();
    for (const auto& v : f.vehicles)
      vs.push_back({{"id", v.id},
                    {"position", {v.x, v.y, v.z}},
                    {"speed", v.speed},
                    {"waypoints_reached", v.reached},
                    {"min_wheel_gap_m", v.min_gap},
                    {"max_contact_gap_m", v.max_contact_gap},
                    {"wheels_in_contact", v.contacts}});
    frames.push_back({{"frame", f.frame},
                      {"time_s", f.time_s},
                      {"frame_ms", f.frame_ms},
                      {"sim_ms", f.sim_ms},
                      {"tessellation_ms", f.tess_ms},
                      {"render_ms", f.render_ms},
                      {"burn_ms", f.burn_ms},
                      {"threshold_px", f.threshold},
                      {"triangles", f.triangles},
                      {"splits", f.splits},
                      {"merges", f.merges},
                      {"patches_uploaded", f.patches_uploaded},
                      {"vehicles", vs}});
    if (f.frame >= skip_frames) {
      ms.push_back(f.frame_ms);
      thr.push_back(f.threshold);
      tris.push_back(f.triangles);
    }
  }
  json errors = json::array();
  for (const ScriptError& e : game.errors())
    errors.push_back({{"script", e.script}, {"frame", e.frame}, {"message", e.message}});
  json summary = {
      {"frames", frames_.size()},
      {"steady_state_from_frame", skip_frames},
      {"frame_ms", {{"p10", percentile(ms, 10)}, {"p50", percentile(ms, 50)},
                    {"p90", percentile(ms, 90)}, {"p99", percentile(ms, 99)},
                    {"max", ms.empty() ? 0.0 : *std::max_element(ms.begin(), ms.end())}}},
      {"threshold_px", {{"p10", percentile(thr, 10)}, {"p50", percentile(thr, 50)},
                        {"p90", percentile(thr, 90)}}},
      {"triangles", {{"p50", percentile(tris, 50)}, {"max", tris.empty() ? 0.0 : *std::max_element(tris.begin(), tris.end())}}},
      {"target_ms", game.controller().desc().target_ms},
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
  if (!out->open(tmp, spec)) return ridgeline::Error{"screenshot '" + path + "': " + out->geterror()};
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
