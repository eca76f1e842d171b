// The deformation storm of `ridge report`: a crater every frame (Terrain::apply_edit) where the
// view ray meets the ground while the camera flies, every mode on its own fresh copy of the
// terrain seeing the same craters (docs/report_method.md, "Scenes").
#pragma once

#include <string>

#include "report/modes.h"

namespace ridgeline::report {

/// Runs the storm on `base` (thresholds of `o` only; the flyover and drive paths), appending
/// its CSV rows to `csv_out`; returns the scene's JSON.
Result<Json> run_storm(Scene& base, const Options& o, std::string& csv_out);

}  // namespace ridgeline::report
