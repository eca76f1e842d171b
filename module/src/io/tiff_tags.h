// A small bounded reader for the TIFF tags OpenImageIO does not expose: GDAL_NODATA and the
// GeoTIFF placement tags (ModelPixelScale, ModelTiepoint, ModelTransformation, GeoKeyDirectory
// and its double parameters).
//
// OpenImageIO 2.4 (Debian 12) reads GeoTIFF files as plain TIFF and drops private tags such as
// GDAL's no-data tag (42113, ASCII, e.g. "-32768") and the GeoTIFF tags, so
// `ImageSpec::extra_attribs` never holds them (checked on r-cran-terra's elev.tif). This reads
// them straight from the file's first IFD: classic TIFF and BigTIFF, either byte order. Every
// offset and count is checked against the file size before it is used, at most kMaxIfdEntries
// entries are scanned and at most `max_values` values read per tag, so a corrupt or hostile file
// costs a few small reads and yields "no tag" or an error message, never a crash or a large
// allocation.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "ridgeline/result.h"

namespace ridgeline::io::detail {

inline constexpr std::uint64_t kMaxIfdEntries = 4096;
inline constexpr std::uint64_t kMaxNodataChars = 256;
/// Values read per tag by the image loader (a GeoKeyDirectory of 1,000 keys is 4,004 shorts).
inline constexpr std::uint64_t kMaxTagValues = 8192;

inline constexpr std::uint16_t kTagModelPixelScale = 33550;
inline constexpr std::uint16_t kTagModelTiepoint = 33922;
inline constexpr std::uint16_t kTagModelTransformation = 34264;
inline constexpr std::uint16_t kTagGeoKeyDirectory = 34735;
inline constexpr std::uint16_t kTagGeoDoubleParams = 34736;
inline constexpr std::uint16_t kTagGdalNodata = 42113;

/// Reads `n` bytes at `offset` into `out`; false when they are not all there.
using ReadAt = std::function<bool(std::uint64_t offset, std::size_t n, unsigned char* out)>;

/// One tag of the first IFD with its value decoded.
struct TiffTag {
  std::uint16_t tag = 0;
  std::uint16_t type = 0;   ///< TIFF field type (2 ASCII, 3 SHORT, 4 LONG, 12 DOUBLE, ...)
  std::uint64_t count = 0;  ///< values (characters for ASCII) the entry claims
  /// Numeric types (BYTE, SHORT, LONG, LONG8, their signed forms, FLOAT, DOUBLE, RATIONAL,
  /// SRATIONAL) as doubles, in order.
  std::vector<double> numbers;
  /// ASCII: the characters up to the first NUL.
  std::string text;
  /// Non-empty when the value was not read; says why ("value (24 bytes at offset 9999) lies
  /// outside the file", "holds 100000 values (at most 8192 are read)", "type 13 is not read").
  std::string error;
};

/// The tags of `wanted` present in the first IFD of a TIFF whose bytes `read` gives (`size`
/// bytes in all), in file order; at most `max_values` values are read per tag (a longer tag gets
/// an `error`). Empty optional: not a TIFF. Error: the file is a TIFF whose header or first IFD
/// is malformed (offsets outside the file, too many entries); the message says which.
Result<std::optional<std::vector<TiffTag>>> read_tiff_tags(const ReadAt& read, std::uint64_t size,
                                                           std::span<const std::uint16_t> wanted,
                                                           std::uint64_t max_values);

/// The same for a file on disk (opened, read with bounded reads, closed). A file that cannot be
/// opened is "not a TIFF" (OpenImageIO reports that case itself).
Result<std::optional<std::vector<TiffTag>>> read_tiff_tags_file(
    const std::string& path, std::span<const std::uint16_t> wanted, std::uint64_t max_values);

/// The tag `tag` of `tags`, or null.
const TiffTag* find_tag(const std::vector<TiffTag>& tags, std::uint16_t tag);

/// The GDAL_NODATA tag's text (without its terminating NUL and surrounding blanks) out of tags
/// read by read_tiff_tags. Empty optional: no such tag. Error: the tag is malformed (a wrong
/// type, an over-long value, a value outside the file); the message says which.
Result<std::optional<std::string>> gdal_nodata_text(const std::vector<TiffTag>& tags);

/// read_tiff_tags + gdal_nodata_text for the one tag 42113.
Result<std::optional<std::string>> read_gdal_nodata(const ReadAt& read, std::uint64_t size);

/// The same for a file on disk.
Result<std::optional<std::string>> read_gdal_nodata_file(const std::string& path);

/// Parses the tag's text as a number: a finite or non-finite double, or empty when the text is
/// not one number (GDAL writes "%.18g" or "nan").
std::optional<double> parse_nodata_text(const std::string& text);

}  // namespace ridgeline::io::detail
