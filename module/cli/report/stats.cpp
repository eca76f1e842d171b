// The report's settings and rows (stats.h).
#include "report/stats.h"

#include <algorithm>

#include "cli_util.h"
#include "ridgeline/bench/summary.h"

namespace ridgeline::report {

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

bench::LoopOptions Options::loop() const {
  bench::LoopOptions o;
  o.error_every = static_cast<std::uint32_t>(std::max(error_every, 2));
  o.pops = true;
  return o;
}

std::string mode_csv(const Json& figures, const std::string& prefix) {
  // The columns of docs/cli.md, in order; an empty field where the figure is null.
  static const char* const kColumns[] = {
      "mode", "triangles_median", "update_ms_median", "update_ms_p99", "changes_per_frame_median",
      "error_max_m", "error_rms_m", "screen_error_max_px", "screen_error_p99_px", "popping_max_px",
      "popping_geomorph_max_px", "memory_bytes", "matched_ratio", "pop_max_px",
      "pop_geomorph_max_px", "screen_error_geomorph_max_px", "update_cpu_ms_median",
      "update_cpu_ms_p99", "triangles_in_view_median"};
  std::string row = prefix;
  for (const char* c : kColumns) {
    row += ",";
    const Json* v = figures.contains(c) ? &figures[c] : nullptr;
    if (v != nullptr && v->is_string()) row += v->get<std::string>();
    else if (v != nullptr && v->is_number()) row += cli::csv_number(v->get<double>());
  }
  return row + "\n";
}

Json modes_json(const std::vector<bench::Run>& modes, const std::string& prefix, std::string& csv) {
  Json out = Json::array();
  for (const bench::Run& m : modes) {
    out.push_back(bench::report_figures(m));
    csv += mode_csv(out.back(), prefix);
  }
  return out;
}

}  // namespace ridgeline::report
