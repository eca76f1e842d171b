// Summaries of a run (summary.h).
#include "ridgeline/bench/summary.h"

#include <algorithm>

#include "ridgeline/bench/stats.h"

namespace ridgeline::bench {

namespace {
// Element-wise a + b.
std::vector<double> sum(const std::vector<double>& a, const std::vector<double>& b) {
  std::vector<double> out(a);
  for (std::size_t k = 0; k < out.size() && k < b.size(); ++k) out[k] += b[k];
  return out;
}
}  // namespace

void append(Json& j, const Json& more) {
  for (const auto& [k, v] : more.items()) j[k] = v;
}

Json report_figures(const Run& r) {
  auto med = [](const std::vector<double>& v) { return number(median(v)); };
  auto most = [](const std::vector<double>& v) { return number(max_of(v)); };
  auto morph = [&](const std::vector<double>& v) { return r.has_morph ? most(v) : Json(nullptr); };
  Json j = {{"mode", r.technique},
            {"frames", r.wall_ms.size()},
            {"triangles_median", med(r.triangles)},
            {"triangles_in_view_median", med(r.in_view)},
            {"update_ms_median", med(r.wall_ms)},
            {"update_ms_p99", number(quantile(r.wall_ms, 0.99))},
            {"update_cpu_ms_median", med(r.cpu_ms)},
            {"update_cpu_ms_p99", number(quantile(r.cpu_ms, 0.99))},
            {"changes_per_frame_median", med(r.changes)},
            {"upload_bytes_median", med(r.upload_bytes)},
            {"error_max_m", most(r.max_m)},
            {"error_rms_m", med(r.rms_m)},
            {"screen_error_max_px", most(r.max_px)},
            {"screen_error_p99_px", med(r.p99_px)},
            {"screen_error_geomorph_max_px", morph(r.morph_max_px)},
            {"popping_max_px", most(r.jump)},
            {"popping_geomorph_max_px", morph(r.jump_morph)},
            {"pop_max_px", most(r.pop)},
            {"pop_geomorph_max_px", morph(r.pop_morph)},
            {"memory_bytes", med(sum(r.memory_bytes, r.data_bytes))},
            {"measured_frames", r.max_m.size()},
            {"measured_vertices_median", med(r.vertices)},
            {"uncovered_vertices", r.uncovered}};
  if (const auto& e = r.named("edit_ms"); !e.empty()) {
    j["edit_ms_median"] = med(e);
    j["edit_ms_p99"] = number(quantile(e, 0.99));
  }
  if (const auto& p = r.named("pending_splits"); !p.empty()) {
    j["pending_splits_median"] = med(p);
    j["pending_splits_max"] = most(p);
    j["tiles_resident_median"] = med(r.named("tiles_resident"));
    j["tiles_resident_max"] = most(r.named("tiles_resident"));
    j["detail_memory_bytes_median"] = med(r.named("detail_bytes"));
    j["tiles_pending_median"] = med(r.named("tiles_pending"));
  }
  j["wall_s"] = r.wall_s;
  j["measure_s"] = r.measure_s;
  append(j, r.summary);
  return j;
}

Json lod_figures(const Run& r) {
  // Figures of the measured frames are 0 when none was measured (--error-every 0).
  auto measured = [](const std::vector<double>& v, double q) { return quantile_or(v, q, 0); };
  const std::vector<double> total = sum(r.wall_ms, r.output_ms),
                            total_cpu = sum(r.cpu_ms, r.output_cpu_ms);
  const double tri_median = std::max(1.0, or_value(median(r.triangles), 1.0));
  Json j = {
      {"frames", r.wall_ms.size()},
      {"update_ms_median", number(median(r.wall_ms))},
      {"update_ms_p99", number(quantile(r.wall_ms, 0.99))},
      {"update_cpu_ms_median", number(median(r.cpu_ms))},
      {"update_cpu_ms_p99", number(quantile(r.cpu_ms, 0.99))},
      {"update_ms_max", number(max_of(r.wall_ms))},
      {"output_ms_median", number(median(r.output_ms))},
      {"output_cpu_ms_median", number(median(r.output_cpu_ms))},
      {"update_plus_output_ms_median", number(median(total))},
      {"update_plus_output_ms_p99", number(quantile(total, 0.99))},
      {"update_plus_output_cpu_ms_median", number(median(total_cpu))},
      {"update_plus_output_cpu_ms_p99", number(quantile(total_cpu, 0.99))},
      {"triangles_median", number(median(r.triangles))},
      {"triangles_p99", number(quantile(r.triangles, 0.99))},
      {"triangles_in_view_median", measured(r.in_view, 0.5)},
      {"changes_per_frame_median", number(median(r.changes))},
      {"upload_bytes_median", number(median(r.upload_bytes))},
      {"upload_bytes_mean", number(mean(r.upload_bytes))},
      {"upload_bytes_p99", number(quantile(r.upload_bytes, 0.99))},
      {"view_memory_bytes_median", number(median(r.memory_bytes))},
      {"view_bytes_per_triangle", number(median(r.memory_bytes) / tri_median)},
      {"output_bytes_per_triangle", number(median(r.output_bytes) / tri_median)},
      {"max_error_median", measured(r.max_m, 0.5)},
      {"max_error_max", measured(r.max_m, 1.0)},
      {"rms_error_median", measured(r.rms_m, 0.5)},
      {"max_screen_error_px_median", measured(r.max_px, 0.5)},
      {"max_screen_error_px_max", measured(r.max_px, 1.0)},
  };
  append(j, r.summary);
  return j;
}

Json time_budget_figures(const Run& r, double budget_ms) {
  const double limit = 1.1 * budget_ms + 0.1;
  return {{"time_budget_met", quantile(r.wall_ms, 0.99) <= limit},
          {"time_budget_met_cpu", quantile(r.cpu_ms, 0.99) <= limit}};
}

}  // namespace ridgeline::bench
