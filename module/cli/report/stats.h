// The report's figures: settings, per-mode results over a path, and how they are summarised
// (medians, percentiles, maxima) into JSON and CSV rows (docs/report.md, docs/cli.md).
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "ridgeline/roam_view.h"

namespace ridgeline::report {

using Json = nlohmann::ordered_json;

/// The q-quantile (0..1) of `v` (the element at floor(q * n) of the sorted values), NaN if empty.
double quantile(std::vector<double> v, double q);
/// Largest of `v`, NaN if empty.
double vmax(const std::vector<double>& v);
/// A JSON number, or null for NaN and infinities.
Json num(double v);

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
};

/// One mode's figures along one path: per-frame series, summarised by json() and csv().
struct ModeResult {
  std::string mode;
  // Per updated frame.
  std::vector<double> ms, cpu_ms, tris, tris_in_view, changes, mem, upload_bytes;
  // Per measured frame (every K-th): error of the mesh as drawn without geomorphs, and of the
  // morphed mesh; the per-vertex jump and the pop, unmorphed and morphed (docs/report.md).
  std::vector<double> max_m, rms_m, max_px, p99_px, vertices, morph_max_px;
  std::vector<double> jump, jump_morph, pop, pop_morph;
  std::vector<double> edit_ms;  ///< deformation storm: Terrain::apply_edit per frame
  // Procedural detail (ROAM on a detail terrain): per updated frame.
  std::vector<double> pending_splits, tiles_resident, detail_bytes, tiles_pending;
  std::uint64_t uncovered = 0;
  double wall_s = 0, measure_s = 0;  ///< this mode's run, and the measurement in it
  bool has_morph = false;            ///< the mode draws a geomorphed mesh too
  Json extra = Json::object();       ///< mode-specific figures, appended to json()

  Json json() const;
  /// One CSV row: `prefix` (scene,path,kind,value), then the columns of docs/cli.md.
  std::string csv(const std::string& prefix) const;
};

/// True for the frames whose mesh the measurement reads: K-1, K, 2K-1, 2K, ... (errors at
/// frames K, 2K, ...; jump and pop between frames nK-1 and nK).
bool measured_frame(std::size_t k, int K);

}  // namespace ridgeline::report
