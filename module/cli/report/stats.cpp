// Summaries of the report's per-frame figures (stats.h).
#include "report/stats.h"

#include <algorithm>
#include <cmath>

#include "cli_util.h"

namespace ridgeline::report {

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * double(v.size())))];
}

double vmax(const std::vector<double>& v) {
  return v.empty() ? std::nan("") : *std::max_element(v.begin(), v.end());
}

Json num(double v) {
  return std::isfinite(v) ? Json(v) : Json(nullptr);
}

RoamSettings Setting::roam(RoamMode mode) const {
  RoamSettings s;
  s.mode = mode;
  if (kind == "threshold") {
    s.threshold = value;
  } else if (kind == "triangles") {
    s.threshold = 0;
    s.max_triangles = static_cast<std::uint32_t>(value);
  } else {
    s.threshold = 1.0;
    s.budget_ms = value;
  }
  return s;
}

double Setting::threshold_px() const {
  return kind == "threshold" ? value : kind == "triangles" ? 0.0 : 1.0;
}

std::vector<Setting> Options::settings() const {
  std::vector<Setting> s;
  for (double t : thresholds) s.push_back({"threshold", t});
  for (double n : triangle_caps) s.push_back({"triangles", n});
  for (double b : time_budgets) s.push_back({"time_ms", b});
  return s;
}

Json ModeResult::json() const {
  Json j = {{"mode", mode},
            {"frames", ms.size()},
            {"triangles_median", num(quantile(tris, 0.5))},
            {"triangles_in_view_median", num(quantile(tris_in_view, 0.5))},
            {"update_ms_median", num(quantile(ms, 0.5))},
            {"update_ms_p99", num(quantile(ms, 0.99))},
            {"update_cpu_ms_median", num(quantile(cpu_ms, 0.5))},
            {"update_cpu_ms_p99", num(quantile(cpu_ms, 0.99))},
            {"changes_per_frame_median", num(quantile(changes, 0.5))},
            {"upload_bytes_median", num(quantile(upload_bytes, 0.5))},
            {"error_max_m", num(vmax(max_m))},
            {"error_rms_m", num(quantile(rms_m, 0.5))},
            {"screen_error_max_px", num(vmax(max_px))},
            {"screen_error_p99_px", num(quantile(p99_px, 0.5))},
            {"screen_error_geomorph_max_px", has_morph ? num(vmax(morph_max_px)) : Json(nullptr)},
            {"popping_max_px", num(vmax(jump))},
            {"popping_geomorph_max_px", has_morph ? num(vmax(jump_morph)) : Json(nullptr)},
            {"pop_max_px", num(vmax(pop))},
            {"pop_geomorph_max_px", has_morph ? num(vmax(pop_morph)) : Json(nullptr)},
            {"memory_bytes", num(quantile(mem, 0.5))},
            {"measured_frames", max_m.size()},
            {"measured_vertices_median", num(quantile(vertices, 0.5))},
            {"uncovered_vertices", uncovered}};
  if (!edit_ms.empty()) {
    j["edit_ms_median"] = num(quantile(edit_ms, 0.5));
    j["edit_ms_p99"] = num(quantile(edit_ms, 0.99));
  }
  if (!pending_splits.empty()) {
    j["pending_splits_median"] = num(quantile(pending_splits, 0.5));
    j["pending_splits_max"] = num(vmax(pending_splits));
    j["tiles_resident_median"] = num(quantile(tiles_resident, 0.5));
    j["tiles_resident_max"] = num(vmax(tiles_resident));
    j["detail_memory_bytes_median"] = num(quantile(detail_bytes, 0.5));
    j["tiles_pending_median"] = num(quantile(tiles_pending, 0.5));
  }
  j["wall_s"] = wall_s;
  j["measure_s"] = measure_s;
  for (auto& [k, v] : extra.items()) j[k] = v;
  return j;
}

std::string ModeResult::csv(const std::string& prefix) const {
  auto n = [](double v) { return std::isfinite(v) ? cli::csv_number(v) : std::string(); };
  auto morph = [&](const std::vector<double>& v) { return has_morph ? n(vmax(v)) : std::string(); };
  std::string matched;
  if (extra.contains("matched_ratio"))
    matched = cli::csv_number(extra["matched_ratio"].get<double>());
  return prefix + "," + mode + "," + n(quantile(tris, 0.5)) + "," + n(quantile(ms, 0.5)) + "," +
         n(quantile(ms, 0.99)) + "," + n(quantile(changes, 0.5)) + "," + n(vmax(max_m)) + "," +
         n(quantile(rms_m, 0.5)) + "," + n(vmax(max_px)) + "," + n(quantile(p99_px, 0.5)) + "," +
         n(vmax(jump)) + "," + morph(jump_morph) + "," + n(quantile(mem, 0.5)) + "," + matched +
         "," + n(vmax(pop)) + "," + morph(pop_morph) + "," + morph(morph_max_px) + "," +
         n(quantile(cpu_ms, 0.5)) + "," + n(quantile(cpu_ms, 0.99)) + "," +
         n(quantile(tris_in_view, 0.5)) + "\n";
}

bool measured_frame(std::size_t k, int K) {
  return int(k % K) == K - 1 || (k % K == 0 && k > 0);
}

}  // namespace ridgeline::report
