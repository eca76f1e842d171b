// A small bounded reader for the one TIFF tag OpenImageIO does not expose: GDAL_NODATA.
//
// OpenImageIO 2.4 (Debian 12) reads GeoTIFF files as plain TIFF and drops private tags such as
// GDAL's no-data tag (42113, ASCII, e.g. "-32768"), so `ImageSpec::extra_attribs` never holds
// it (checked on r-cran-terra's elev.tif). This reads it straight from the file's first IFD:
// classic TIFF and BigTIFF, either byte order. Every offset and count is checked against the
// file size before it is used, at most kMaxIfdEntries entries are scanned and at most
// kMaxNodataChars characters read, so a corrupt or hostile file costs a few small reads and
// yields "no tag" or an error message, never a crash or a large allocation.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include "ridgeline/result.h"

namespace ridgeline::io::detail {

inline constexpr std::uint64_t kMaxIfdEntries = 4096;
inline constexpr std::uint64_t kMaxNodataChars = 256;

/// Reads `n` bytes at `offset` into `out`; false when they are not all there.
using ReadAt = std::function<bool(std::uint64_t offset, std::size_t n, unsigned char* out)>;

/// The GDAL_NODATA tag's text (without its terminating NUL and surrounding blanks) of the first
/// image of a TIFF whose bytes `read` gives (`size` bytes in all). Empty optional: not a TIFF,
/// or no such tag. Error: the file is a TIFF whose first IFD or whose tag is malformed (offsets
/// outside the file, a wrong type, an over-long value); the message says which.
Result<std::optional<std::string>> read_gdal_nodata(const ReadAt& read, std::uint64_t size);

/// The same for a file on disk (opened, read with bounded reads, closed).
Result<std::optional<std::string>> read_gdal_nodata_file(const std::string& path);

/// Parses the tag's text as a number: a finite or non-finite double, or empty when the text is
/// not one number (GDAL writes "%.18g" or "nan").
std::optional<double> parse_nodata_text(const std::string& text);

}  // namespace ridgeline::io::detail
