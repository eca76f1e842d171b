// Private helpers shared by the image and raw loaders.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "ridgeline/io.h"

namespace ridgeline::io::detail {

/// "heightmap 'PATH'": the name used in every message about a heightmap file.
std::string heightmap_name(const std::string& path);

/// Fails unless `path` names an existing regular file. `name` prefixes the message.
Status check_regular_file(const std::string& path, const std::string& name);

/// Loads `options.materials_path` (an 8-bit single-channel image of width x height) as one
/// material id per sample. Empty result when no path is set.
Result<std::vector<std::uint8_t>> load_material_ids(const LoadOptions& options, std::uint32_t width,
                                                    std::uint32_t height);

/// Loads the material layer if any and builds the Heightfield from `desc` and raw `values`.
/// Logs a warning (and adds it to `report`) when more than kFilledWarningFraction of the samples
/// were filled.
Result<Heightfield> finish_heightfield(const HeightfieldDesc& desc, std::span<const float> values,
                                       const LoadOptions& options, LoadReport* report);

/// Logs a warning about `name` and records it (without the name) in `report` when not null.
void warn(const std::string& name, const std::string& what, LoadReport* report);

}  // namespace ridgeline::io::detail
