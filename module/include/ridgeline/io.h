// Ridgeline::io: heightmaps from image files (through OpenImageIO) and headerless raw files.
// Kept out of Ridgeline::terrain so an engine can embed the core without image libraries.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "ridgeline/heightfield.h"
#include "ridgeline/result.h"

namespace ridgeline::io {

/// How a heightmap file becomes a Heightfield. `placement` gives spacing, origin, height scale
/// and offset, no-data value, fill policy and the size cap; its width and height are ignored
/// (they come from the file) and its name is replaced by "heightmap 'PATH'" in messages.
///
/// Threading: the loaders keep no state of their own; loading different files from several
/// threads at once is safe (OpenImageIO's ImageInput is used by one thread per file).
struct LoadOptions {
  HeightfieldDesc placement;
  /// Which channel of a multi-channel image to use (0-based; logged at info level when the image
  /// has several). -1 (default): refuse images with more than one channel, except greyscale +
  /// alpha, which uses the grey channel (0) and says so in the log (info level). A channel the
  /// image does not have is an error.
  int channel = -1;
  /// Path of an optional 8-bit single-channel image of exactly the heightmap's size holding one
  /// material id per sample; cell (i, j) takes the id of sample (i, j). Empty: no material layer.
  /// Used by every loader (image and raw).
  std::string materials_path;
  /// Take the spacing from the file's own georeferencing (GeoTIFF tags, see FilePlacement) when
  /// it has one, instead of `placement.spacing_x/z`. Off by default: the placement is used as
  /// given. Tools set it when the user gave no spacing (`ridge`, `ridgeline.load`); a file
  /// without usable tags keeps `placement`'s spacing (and a warning says why when it has tags
  /// that cannot be used).
  bool spacing_from_file = false;
  /// The same for the origin; only projected files (metres) carry one.
  bool origin_from_file = false;
  /// Samples whose alpha is 0 are missing, as no-data samples are, and the fill policy decides
  /// what they become (FillPolicy::kHole: holes, no ground). Images only; an image without an
  /// alpha channel (or whose chosen channel is its alpha) is refused when this is set. Off by
  /// default: alpha is ignored.
  bool alpha_nodata = false;
};

/// Georeferencing read from a heightmap file (GeoTIFF: ModelPixelScale + ModelTiepoint or an
/// axis-aligned ModelTransformation, and the GeoKeyDirectory's model type, raster type and
/// units), converted to Ridgeline's placement. World x is easting and world z is -northing:
/// image rows run south, and with x east and y up a right-handed frame has +z pointing south.
///  - Projected files (GTModelTypeGeoKey 1) in metres, feet or US survey feet: spacing and
///    origin in metres. The origin is the position of sample (0, 0): the centre of pixel (0, 0)
///    for PixelIsArea files (the GeoTIFF default: the tie point is the pixel's corner), the tie
///    point itself for PixelIsPoint files.
///  - Geographic files (GTModelTypeGeoKey 2) in degrees: the pixel size in degrees converted to
///    metres at the latitude of the raster's centre on the WGS 84 ellipsoid (other datums differ
///    by less than 0.1 %); no origin (degrees give no metre position), so `has_origin` is false.
///    The cells of such a grid are not square, and away from the centre latitude the true
///    east-west size differs (by cos(latitude)); the conversion is for a local terrain.
struct FilePlacement {
  double spacing_x = 0;  ///< metres between samples along x (columns); finite, > 0
  double spacing_z = 0;  ///< metres between samples along z (rows); finite, > 0
  bool has_origin = false;
  double origin_x = 0;      ///< world x of sample (0, 0), metres (easting); when has_origin
  double origin_z = 0;      ///< world z of sample (0, 0), metres (-northing); when has_origin
  bool geographic = false;  ///< spacing converted from degrees
  /// One line for messages and reports: what the tags say and how they were converted, e.g.
  /// "GeoTIFF geographic (EPSG 4326), 0.00833333 x 0.00833333 degree pixels = 599.9 x 926.9 m at
  /// the centre latitude 49.817 N".
  std::string description;
};

/// Fraction of filled (no-data or non-finite) samples above which the loaders log a warning
/// (and LoadReport holds it): the filled area is invented terrain.
inline constexpr double kFilledWarningFraction = 0.05;

/// What a loader found and decided, for tools that report it (`ridge info`). Optional: pass a
/// pointer to receive it.
struct LoadReport {
  /// The file's sample type as read: "uint8", "uint16", "int16", "uint32", "int32", "half",
  /// "float", "double" (images), "u16" / "f32" (raw files).
  std::string pixel_type;
  /// The file's georeferencing when it has usable tags, whether or not it was used.
  std::optional<FilePlacement> file_placement;
  bool spacing_from_file = false;  ///< the heightfield's spacing came from file_placement
  bool origin_from_file = false;   ///< the heightfield's origin came from file_placement
  /// Every warning the loader logged (placement tags that cannot be used, a malformed no-data
  /// tag, more than kFilledWarningFraction of the samples filled), without the file name prefix.
  std::vector<std::string> warnings;
};

/// Loads a heightmap through OpenImageIO: 8- and 16-bit greyscale PNG, 16-bit and float TIFF,
/// float EXR; also PNM, Radiance HDR, BMP, TGA and JPEG. The reader is the one the extension names,
/// else the one the file's first bytes name; OpenImageIO's other formats are refused (docs/
/// data_model.md, "File formats"). Integer formats give
/// the raw integer as value (0..255 or 0..65535; signed and 32-bit integers likewise, the latter
/// rounded to float above 2^24), half/float formats the float, double pixels are rounded to float.
/// Headers are checked (size against `placement.max_samples`, channels, pixel type) before any
/// pixel is allocated, and only the chosen channel is read. Missing, truncated or corrupt files,
/// unsupported formats and every bad value get a precise error naming the file; no-data and
/// non-finite samples are handled by Heightfield::create (refused unless a fill policy is set).
/// TIFF files are also read for GDAL's no-data tag (used when `placement.nodata` is not set)
/// and for GeoTIFF placement (used as `spacing_from_file` and `origin_from_file` say).
/// `report`, when not null, receives what was found and used.
Result<Heightfield> load_image(const std::string& path, const LoadOptions& options,
                               LoadReport* report = nullptr);

/// Sample type of a headerless raw heightmap (little-endian).
enum class RawType { kU16, kF32 };

struct RawFormat {
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  RawType type = RawType::kU16;
};

/// Loads a headerless little-endian raw file of exactly width * height samples. The file size
/// must match exactly (a truncated or oversized file is refused, naming both sizes).
Result<Heightfield> load_raw(const std::string& path, const RawFormat& format,
                             const LoadOptions& options, LoadReport* report = nullptr);

/// Parses raw bytes already in memory (the part load_raw shares with the fuzzer).
Result<Heightfield> parse_raw(std::span<const std::byte> bytes, const RawFormat& format,
                              const LoadOptions& options, const std::string& name,
                              LoadReport* report = nullptr);

/// Parses "u16" / "f32".
Result<RawType> parse_raw_type(const std::string& text);

/// Loads any supported heightmap: when `raw` is given with a nonzero size the file is read as raw
/// whatever its extension; otherwise ".raw"/".r16"/".r32" files are refused (they need a size)
/// and anything else goes through load_image().
Result<Heightfield> load_heightmap(const std::string& path, const LoadOptions& options,
                                   const RawFormat* raw = nullptr, LoadReport* report = nullptr);

/// How the files of a world made of several heightmaps lie (load_tiles()).
struct TileLayout {
  /// An explicit grid: `columns` x `rows` files, given row by row (the first row at the smallest
  /// z). 0 x 0: place every file by its own georeferencing (projected GeoTIFFs).
  std::uint32_t columns = 0, rows = 0;
  /// Neighbouring files repeat their shared edge of samples (the usual DEM convention: a 1025-
  /// sample tile shares its last row with the next one's first); false: they abut.
  bool shared_edges = true;
};

/// Loads the files of one world and joins them into one Heightfield: placed by `layout` (or by
/// their georeferencing), each loaded as load_heightmap() does with `options` (the size cap
/// applies to the joined field). Refused, naming the files: different spacings, height scales
/// or offsets, a mixture of files with and without materials, files off the common sample grid,
/// shared samples that disagree, and holes. 16-bit input stays 16-bit. One file and no layout:
/// load_heightmap().
Result<Heightfield> load_tiles(const std::vector<std::string>& paths, const LoadOptions& options,
                               const TileLayout& layout, const RawFormat* raw = nullptr,
                               LoadReport* report = nullptr);

}  // namespace ridgeline::io
