// `ridge profile`: heights along a segment as text a person can judge (summary, ASCII plot,
// sparkline, table), optionally also as JSON.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cli_util.h"
#include "commands.h"
#include "terrain_args.h"

namespace ridgeline::cli {

namespace {

constexpr int kPlotRows = 12;
constexpr std::size_t kMaxPlotColumns = 96;

struct ProfileOptions {
  TerrainArgs terrain;
  std::string from, to, steps = "32", json_path;
};

struct ProfilePoint {
  double distance, x, z;
  std::optional<double> height;
};

std::string fixed(double v, int decimals = 2) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

/// Which point each plot column shows: every point when they fit, else evenly spread ones.
std::vector<std::size_t> plot_columns(std::size_t points) {
  std::vector<std::size_t> cols;
  const std::size_t n = std::min(points, kMaxPlotColumns);
  for (std::size_t c = 0; c < n; ++c)
    cols.push_back(n == 1 ? 0
                          : static_cast<std::size_t>(
                                std::llround(double(c) * double(points - 1) / double(n - 1))));
  return cols;
}

void print_profile(const std::vector<ProfilePoint>& pts, const std::string& source,
                   const std::vector<double>& from, const std::vector<double>& to) {
  const double length = pts.back().distance;
  std::printf("Profile of %s from (%s, %s) to (%s, %s): %s m in %zu steps of %s m\n",
              source.c_str(), csv_number(from[0]).c_str(), csv_number(from[1]).c_str(),
              csv_number(to[0]).c_str(), csv_number(to[1]).c_str(), fixed(length).c_str(),
              pts.size() - 1, fixed(length / double(pts.size() - 1)).c_str());

  std::size_t on = 0, lo = 0, hi = 0;
  double sum = 0, climb = 0, descent = 0, steepest = 0;
  std::size_t steepest_at = 0;
  const ProfilePoint* prev = nullptr;
  for (std::size_t k = 0; k < pts.size(); ++k) {
    if (!pts[k].height) {
      prev = nullptr;
      continue;
    }
    const double h = *pts[k].height;
    if (on == 0 || h < *pts[lo].height) lo = k;
    if (on == 0 || h > *pts[hi].height) hi = k;
    ++on;
    sum += h;
    if (prev) {
      const double dh = h - *prev->height;
      (dh > 0 ? climb : descent) += dh;
      const double run = pts[k].distance - prev->distance;
      if (run > 0 && std::abs(dh) / run > std::abs(steepest)) {
        steepest = dh / run;
        steepest_at = k;
      }
    }
    prev = &pts[k];
  }
  if (on == 0) {
    std::printf("Every point is off the terrain: nothing to plot.\n");
    return;
  }
  const double hmin = *pts[lo].height, hmax = *pts[hi].height;
  std::printf("Heights: min %s m at %s m, max %s m at %s m, mean %s m\n", fixed(hmin).c_str(),
              fixed(pts[lo].distance).c_str(), fixed(hmax).c_str(), fixed(pts[hi].distance).c_str(),
              fixed(sum / double(on)).c_str());
  std::printf("Climb +%s m, descent %s m", fixed(climb).c_str(), fixed(descent).c_str());
  if (steepest != 0)
    std::printf(", steepest step %s %% (%s) ending at %s m",
                fixed(100 * std::abs(steepest), 1).c_str(), steepest > 0 ? "up" : "down",
                fixed(pts[steepest_at].distance).c_str());
  std::printf("\n");
  if (on != pts.size())
    std::printf("Off the terrain: %zu of %zu points (shown as '?')\n", pts.size() - on, pts.size());

  // Plot: one column per (selected) point; the lowest height fills one row, the highest all.
  const auto cols = plot_columns(pts.size());
  auto level = [&](double h) {
    if (hmax <= hmin) return 1;
    return 1 + static_cast<int>(std::lround((h - hmin) / (hmax - hmin) * (kPlotRows - 1)));
  };
  std::printf("\n");
  for (int row = kPlotRows; row >= 1; --row) {
    std::string label(12, ' ');
    if (row == kPlotRows) label = fixed(hmax) + " m";
    if (row == 1) label = fixed(hmin) + " m";
    std::printf("%12s |", label.c_str());
    std::string line;
    for (std::size_t c : cols) {
      if (!pts[c].height)
        line += row == 1 ? '?' : ' ';
      else
        line += level(*pts[c].height) >= row ? '#' : ' ';
    }
    std::printf("%s\n", line.c_str());
  }
  std::printf("%12s +%s\n", "", std::string(cols.size(), '-').c_str());
  const std::string left = "0 m", right = fixed(length) + " m";
  const std::size_t gap =
      cols.size() > left.size() + right.size() ? cols.size() - left.size() - right.size() : 1;
  std::printf("%12s  %s%s%s\n", "", left.c_str(), std::string(gap, ' ').c_str(), right.c_str());

  // Sparkline: ten levels from low to high.
  static const char kRamp[] = " .:-=+*#%@";
  std::string spark;
  for (std::size_t c : cols) {
    if (!pts[c].height) {
      spark += '?';
      continue;
    }
    const double t = hmax > hmin ? (*pts[c].height - hmin) / (hmax - hmin) : 0.0;
    spark += kRamp[std::clamp(static_cast<int>(std::lround(t * 9)), 0, 9)];
  }
  std::printf("%12s  %s\n\n", "sparkline", spark.c_str());

  std::printf("%6s %14s %14s %14s %12s\n", "step", "distance_m", "x_m", "z_m", "height_m");
  for (std::size_t k = 0; k < pts.size(); ++k)
    std::printf("%6zu %14s %14s %14s %12s\n", k, fixed(pts[k].distance).c_str(),
                fixed(pts[k].x).c_str(), fixed(pts[k].z).c_str(),
                pts[k].height ? fixed(*pts[k].height).c_str() : "off");
}

int run_profile(const ProfileOptions& o) {
  auto from = parse_finite_list(o.from, "--from", 2, 2);
  if (!from) return report_error(from.error().message);
  auto to = parse_finite_list(o.to, "--to", 2, 2);
  if (!to) return report_error(to.error().message);
  auto steps = parse_count(o.steps, "--steps", 1, 100000);
  if (!steps) return report_error(steps.error().message);
  auto terrain = o.terrain.load_terrain();
  if (!terrain) return report_error(terrain.error().message);

  const double dx = (*to)[0] - (*from)[0], dz = (*to)[1] - (*from)[1];
  const double length = std::hypot(dx, dz);
  std::vector<ProfilePoint> pts;
  for (std::uint64_t k = 0; k <= *steps; ++k) {
    const double t = double(k) / double(*steps);
    ProfilePoint p{t * length, (*from)[0] + t * dx, (*from)[1] + t * dz, std::nullopt};
    if (k == *steps) p.x = (*to)[0], p.z = (*to)[1];  // exact end point
    p.height = (*terrain)->height(p.x, p.z);
    pts.push_back(p);
  }
  print_profile(pts, o.terrain.source(), *from, *to);
  if (std::fflush(stdout) != 0) return report_error("cannot write to standard output");

  if (!o.json_path.empty()) {
    nlohmann::json j = {{"source", o.terrain.source()},
                        {"from", *from},
                        {"to", *to},
                        {"length", length},
                        {"points", nlohmann::json::array()}};
    for (const auto& p : pts)
      j["points"].push_back({{"distance", p.distance},
                             {"x", p.x},
                             {"z", p.z},
                             {"height", p.height ? nlohmann::json(*p.height) : nlohmann::json()}});
    if (auto s = write_json(j, o.json_path); !s) return report_error(s.message());
  }
  return 0;
}

}  // namespace

Command add_profile_command(CLI::App& parent) {
  auto* app = parent.add_subcommand(
      "profile",
      "Heights along the segment from --from to --to: a summary, an ASCII plot, a sparkline and "
      "a table (text for people)");
  auto o = std::make_shared<ProfileOptions>();
  o->terrain.add_to(*app);
  app->add_option("--from", o->from, "Start of the segment, world metres")
      ->type_name("X,Z")
      ->required();
  app->add_option("--to", o->to, "End of the segment, world metres")->type_name("X,Z")->required();
  app->add_option("--steps", o->steps,
                  "Number of steps (points = steps + 1), 1..100000 (default 32)")
      ->type_name("N");
  app->add_option("--json", o->json_path,
                  "Also write the points as JSON to FILE (heights null off the terrain)")
      ->type_name("FILE");
  return {app, [o] { return run_profile(*o); }};
}

}  // namespace ridgeline::cli
