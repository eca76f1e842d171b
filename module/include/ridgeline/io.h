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
/// (they come from the file) and its name is replaced by the file name in messages.
struct LoadOptions {
  HeightfieldDesc placement;
  /// Which channel of a multi-channel image to use. -1 (default): refuse images with more than
  /// one colour channel (greyscale + alpha uses the grey channel and says so in the log).
  int channel = -1;
  /// Path of an optional 8-bit single-channel image of the same size holding material ids.
  std::string materials_path;
};

/// Loads a heightmap through OpenImageIO: 8- and 16-bit greyscale PNG, 16-bit and float TIFF,
/// float EXR (anything else OpenImageIO reads with one channel works too). Integer formats give
/// the raw integer as value (0..255 or 0..65535), float formats the float. Headers are checked
/// (size, channels, format) before any pixel is allocated. Missing, truncated or corrupt files,
/// unsupported formats and every bad value get a precise error naming the file.
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

/// Loads by extension: ".raw"/".r16"/".r32" need `raw` (with nonzero size), anything else goes
/// through load_image().
Result<Heightfield> load_heightmap(const std::string& path, const LoadOptions& options,
                                   const RawFormat* raw = nullptr);

}  // namespace ridgeline::io
