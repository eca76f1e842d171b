// Ridgeline::io: baked worlds (docs/worlds.md). `bake_world` turns a heightmap, a set of tiles or
// generated samples into one world file (a tiled, overview-carrying GeoTIFF that GIS tools open,
// with Ridgeline's index, aprons and tessellator bounds inside); `open_world` reads one back as a
// PageSource for Terrain::open, which pages it in under a byte budget.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>

#include "ridgeline/heightfield.h"
#include "ridgeline/landscape.h"
#include "ridgeline/result.h"
#include "ridgeline/world.h"

namespace ridgeline::io {

/// Opens a baked world: reads and checks its locator and index (magic, version, checksums, sizes:
/// a truncated, corrupt, foreign or newer file is refused with a message naming the file and the
/// fault), reads nothing proportional to the world but the page summaries (16 bytes per 65,536
/// samples). A page's entry (32 bytes) is read with its chunk of 1,024 when a page of the chunk is
/// first loaded; chunks and pages are checked (checksum, sizes) when read. Worlds of format
/// versions 3 and 4 hold the entries in the index, read whole here. The returned source may be
/// used from any number of threads; it keeps the file open.
Result<std::shared_ptr<const PageSource>> open_world(const std::string& path);

/// Samples to bake, held in memory: width x height values, row-major, either 16-bit values
/// (height = height_offset + float(height_scale * value)) or float local heights (height =
/// height_offset + value), and optionally one material id per sample (cell (i, j) takes sample
/// (i, j)'s). The caller keeps them alive during bake_world().
struct BakeSamples {
  WorldInfo info;  ///< size, placement, encoding (format says which pointer is used), name
  const std::uint16_t* u16 = nullptr;
  const float* f32 = nullptr;
  const std::uint8_t* materials = nullptr;
  /// Cells without ground (index i + j (width - 1), as Heightfield::hole_cells() gives them):
  /// stored with the world (PageSource::holes) and its bounds made around them, as a terrain in
  /// memory makes them. Empty: none.
  std::span<const std::uint64_t> hole_cells;
};

/// How to bake.
struct BakeOptions {
  /// The tessellator configuration the coarse bounds are made for (landscape.h): a Landscape
  /// over the world must use the same (patch_exponent 0 picks it as Landscape::create would).
  LandscapeDesc landscape;
  /// Float input: quantise to 16 bits when every height stays within this many metres (the
  /// measured maximum error is reported); refused when 16 bits cannot meet it. Empty: floats
  /// are kept exactly. 16-bit input is always kept exactly.
  std::optional<double> tolerance;
  /// Threads, 1..256; 0: every hardware thread.
  std::uint32_t threads = 0;
  /// Deflate level, 1..12 (libdeflate): 1 fastest, 6 the TIFF writers' usual.
  int compression_level = 1;
  /// Called now and then with the fraction done (0..1) and the stage's name, from the baking
  /// thread; return false to cancel (the bake then stops, removes its temporary file and fails
  /// with "cancelled").
  std::function<bool(double fraction, const char* stage)> progress;
};

/// What a bake did.
struct BakeReport {
  std::uint64_t samples = 0;      ///< width * height
  std::uint64_t bytes = 0;        ///< the file's size
  std::uint64_t pages = 0;        ///< pages of every level
  double seconds = 0;             ///< wall time of the whole bake
  double bounds_seconds = 0;      ///< of which computing the tessellator's bounds
  double pages_seconds = 0;       ///< of which compressing and writing the pages
  SampleFormat format = SampleFormat::kU16;  ///< how the heights were stored
  double max_error_m = 0;         ///< largest |stored - input| height (0 when kept exactly)
  std::uint64_t content_hash = 0; ///< the world's WorldInfo::content_hash
  std::uint32_t patch_exponent = 0;  ///< the baked bounds' configuration
  std::uint64_t hole_cells = 0;      ///< cells without ground stored with the world
};

/// Bakes `samples` into the world file `path`: written to a temporary file beside it, flushed and
/// renamed, so that `path` is either the previous file or the whole new world; on any error (a
/// full disk, a refused tolerance, cancellation) the temporary file is removed and the message
/// names the cause. Checks the samples (finite, within kMaxRelativeHeight) and the placement as
/// Heightfield does. Memory: the samples plus about 1.6 bytes a sample while the bounds are made.
Result<BakeReport> bake_world(const BakeSamples& samples, const std::string& path,
                              const BakeOptions& options = {});

/// Bakes a Heightfield (16-bit when every sample is an integer times its height scale, floats
/// otherwise, as Terrain::create stores it) with its holes: the world's surface equals the
/// terrain's Terrain::create(heightfield) makes, bit for bit, and so does its content hash.
Result<BakeReport> bake_world(const Heightfield& heightfield, const std::string& path,
                              const BakeOptions& options = {});

}  // namespace ridgeline::io
