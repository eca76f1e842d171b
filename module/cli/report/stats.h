// The report's settings and how a mode's run becomes its JSON figures and CSV row
// (docs/report.md, docs/cli.md). The runs and their figures are Ridgeline::bench's
// (ridgeline/bench/frame_loop.h, summary.h).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "ridgeline/bench/frame_loop.h"
#include "ridgeline/roam_view.h"

namespace ridgeline::report {

using bench::Json;

/// One setting a user can choose.
struct Setting {
  std::string kind;  ///< "threshold" (px), "triangles" (cap), "time_ms" (budget, at 1 px)
  double value = 0;
  /// ROAM's settings for it.
  RoamSettings roam(RoamMode mode) const;
  /// The pixel threshold the setting runs at (0 for a triangle cap).
  double threshold_px() const;
};

/// What the report runs (`ridge report` flags).
struct Options {
  int frames = 60;
  int error_every = 6;
  std::uint32_t stride = 1;
  std::vector<double> thresholds{0.5, 1, 2, 4, 8, 16};
  std::vector<double> triangle_caps{5000, 20000, 80000};
  std::vector<double> time_budgets{0.5, 2};
  std::vector<std::string> paths;  ///< empty: all six
  bool soar = true;                ///< run the SOAR comparator
  /// Every setting: thresholds, then caps, then budgets.
  std::vector<Setting> settings() const;
  /// The frame loop's options for a mode: errors, jumps and pops every error_every-th frame.
  bench::LoopOptions loop() const;
};

/// One CSV row of a mode's figures (bench::report_figures of its run, with the report's own
/// fields such as matched_ratio added): `prefix` (scene,path,kind,value), then the columns of
/// docs/cli.md.
std::string mode_csv(const Json& figures, const std::string& prefix);
/// Every mode's figures of one setting as a JSON array, their CSV rows appended to `csv`.
Json modes_json(const std::vector<bench::Run>& modes, const std::string& prefix, std::string& csv);

}  // namespace ridgeline::report
