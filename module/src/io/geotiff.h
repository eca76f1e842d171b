// GeoTIFF placement: the model tags and geo keys of a TIFF turned into Ridgeline's spacing and
// origin (io.h, FilePlacement, says what the conversion is).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "io/tiff_tags.h"
#include "ridgeline/io.h"

namespace ridgeline::io::detail {

/// The tags geotiff_placement reads (give them to read_tiff_tags).
inline constexpr std::uint16_t kGeoTiffTags[] = {kTagModelPixelScale, kTagModelTiepoint,
                                                 kTagModelTransformation, kTagGeoKeyDirectory,
                                                 kTagGeoDoubleParams};

/// What a file's GeoTIFF tags give.
struct GeoTiffPlacement {
  /// The placement, when the tags give a usable one.
  std::optional<FilePlacement> placement;
  /// Non-empty when the file has placement tags that cannot be used; says why ("ModelPixelScale
  /// without a GeoKeyDirectory: the units are unknown").
  std::string problem;
};

/// Reads the placement of a raster of `height` rows from its tags (as read_tiff_tags gives
/// them). No placement tags: both fields empty. Never fails otherwise: malformed or unsupported
/// tags give a `problem`.
GeoTiffPlacement geotiff_placement(const std::vector<TiffTag>& tags, std::uint32_t height);

}  // namespace ridgeline::io::detail
