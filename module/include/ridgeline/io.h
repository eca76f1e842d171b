// Ridgeline::io: heightmaps from image files (through OpenImageIO) and headerless raw files.
// Kept out of Ridgeline::terrain so an engine can embed the core without image libraries.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

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
};

/// Loads a heightmap through OpenImageIO: 8- and 16-bit greyscale PNG, 16-bit and float TIFF,
/// float EXR (anything else OpenImageIO reads with one channel works too). Integer formats give
/// the raw integer as value (0..255 or 0..65535; signed and 32-bit integers likewise, the latter
/// rounded to float above 2^24), half/float formats the float, double pixels are rounded to float.
/// Headers are checked (size against `placement.max_samples`, channels, pixel type) before any
/// pixel is allocated, and only the chosen channel is read. Missing, truncated or corrupt files,
/// unsupported formats and every bad value get a precise error naming the file; no-data and
/// non-finite samples are handled by Heightfield::create (refused unless a fill policy is set).
Result<Heightfield> load_image(const std::string& path, const LoadOptions& options);

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
                             const LoadOptions& options);

/// Parses raw bytes already in memory (the part load_raw shares with the fuzzer).
Result<Heightfield> parse_raw(std::span<const std::byte> bytes, const RawFormat& format,
                              const LoadOptions& options, const std::string& name);

/// Parses "u16" / "f32".
Result<RawType> parse_raw_type(const std::string& text);

/// Loads any supported heightmap: when `raw` is given with a nonzero size the file is read as raw
/// whatever its extension; otherwise ".raw"/".r16"/".r32" files are refused (they need a size)
/// and anything else goes through load_image().
Result<Heightfield> load_heightmap(const std::string& path, const LoadOptions& options,
                                   const RawFormat* raw = nullptr);

}  // namespace ridgeline::io
