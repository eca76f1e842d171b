// glTF 2.0 binary export of a ROAM mesh (through tinygltf). Part of Ridgeline::io.
#pragma once

#include <string>

#include "ridgeline/result.h"
#include "ridgeline/roam_view.h"

namespace ridgeline::io {

struct GltfExportOptions {
  bool normals = true;           ///< write the smooth vertex normals
};

/// Writes the view's current mesh as a .glb: one mesh per non-empty patch holding patch-local
/// float positions (x, height, z) and normals, placed by its node's translation (the patch's
/// double-precision origin, so a terrain at 1e7 m exports exactly). Written to a temporary file
/// and renamed, so a failure never leaves a half-written file. Errors name the file.
Status write_glb(RoamView& view, const std::string& path, const GltfExportOptions& options = {});

}  // namespace ridgeline::io
