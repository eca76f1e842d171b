// The peers' noise field and circle path as files (`ridge report --write-noise-field DIR`), from
// the shared scenes (ridgeline/scenes.h), so that scripts and users need nothing else.
#pragma once

#include <string>

#include "ridgeline/result.h"

namespace ridgeline::report {

/// Writes DIR/noise1025.png (1025 x 1025, 16-bit grey; height = 0.005 x value metres at spacing
/// 1 m) and DIR/noise1025_circle.json (a PATH.json of 360 frames), creating DIR. Each file is
/// written to a temporary name and renamed. Fails naming the file.
Status write_noise_field(const std::string& dir);

}  // namespace ridgeline::report
