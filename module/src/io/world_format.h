// Private: the baked world's file format (docs/worlds.md, "The world file"), shared by the writer
// (world_writer.cpp, `ridge bake`) and the reader (world_reader.cpp).
//
// A world file is a little-endian BigTIFF that GIS tools open: image 0 is the heights at full
// resolution, tiled 256 x 256, Deflate-compressed with TIFF's predictor (horizontal differencing
// for 16-bit samples, the floating-point predictor for floats), with GeoTIFF placement tags; the
// images after it are its overviews, one per level of the page pyramid (every 4^k-th sample,
// tiled the same way). Ridgeline reads none of the TIFF structure: a locator in the 64 bytes
// after the BigTIFF header points at its own index (the world's header, the page summaries, and
// for every page where its four parts lie), and every page's parts lie together:
//   tile       the page's 256 x 256 samples exactly as the TIFF tile (what TileOffsets points at)
//   apron      the ring of entries around the tile (kPageEntries - 256^2 samples), Deflate
//   materials  kPageEntries material ids, Deflate (empty when the world has none)
//   records    the tessellator's baked bounds of the page (levels >= 1), Deflate (roam/records.h)
// The index ends with the world's holes (version 4): their count, then (j, i0, i1) per run of
// hole cells along a row of cells. From version 5 the page entries are not in the index: they lie
// in chunks of kChunkEntries before it, and the index holds each chunk's offset and checksum, so
// that opening reads the index (the header, the page summaries, the chunk table, the holes) and
// nothing per page; a chunk is read and checked when a page of its is first loaded. Versions 3
// and 4 hold the entries in the index.
// A level whose size is 2^k + 1 samples has one column and row past its pages' tiles: the TIFF
// gets extra tiles for them (after the last page of each row and column, outside the index), so
// that its tile grid covers the image; Ridgeline reads those samples from the pages' aprons.
// Every part is covered by the page's checksum, the index by its own, and the locator by its
// own. A file is written to a temporary name, flushed and renamed: a reader sees a whole world or
// none.
#pragma once

#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <vector>

#include "ridgeline/world.h"

namespace ridgeline::io::world_file {

inline constexpr char kMagic[8] = {'R', 'I', 'D', 'G', 'E', 'W', 'L', 'D'};
/// 2: six-entry aprons; 3: 4-byte bounds; 4: holes; 5: page entries in chunks outside the index.
inline constexpr std::uint32_t kVersion = 5;
/// The oldest version this build reads (3: as 4 without holes).
inline constexpr std::uint32_t kOldestVersion = 3;
/// Bytes 16 .. 79 of the file: the locator.
inline constexpr std::size_t kLocatorAt = 16;
inline constexpr std::size_t kLocatorBytes = 64;
inline constexpr std::size_t kDataStart = kLocatorAt + kLocatorBytes;
/// Samples per tile side (a page's cells; the TIFF's TileWidth and TileLength).
inline constexpr std::uint32_t kTile = 256;
inline constexpr std::size_t kTileSamples = std::size_t(kTile) * kTile;
inline constexpr std::size_t kApronSamples = kPageEntries - kTileSamples;

/// Bytes of a page's entry (offset, the four sizes, checksum).
inline constexpr std::size_t kEntryBytes = 32;
/// Page entries a chunk (version 5): 32 KiB, read and checked when a page of its is first loaded.
inline constexpr std::size_t kChunkEntries = 1024;
/// Where one page's parts lie (offset of the tile; the others follow it).
struct PageEntry {
  std::uint64_t offset = 0;
  std::uint32_t tile = 0, apron = 0, materials = 0, records = 0;  ///< compressed bytes
  std::uint64_t checksum = 0;  ///< over the four parts' bytes
  std::uint64_t bytes() const noexcept {
    return std::uint64_t(tile) + apron + materials + records;
  }
};

/// The 64-bit checksum of the format (a word-wise multiply-xorshift; not cryptographic).
std::uint64_t checksum(const void* data, std::size_t n) noexcept;

/// Appends little-endian values.
struct Writer {
  std::vector<std::uint8_t> bytes;
  template <class T>
  void put(const T& v) {
    const auto* p = reinterpret_cast<const std::uint8_t*>(&v);
    bytes.insert(bytes.end(), p, p + sizeof v);
  }
  void put_string(const std::string& s) {
    put(std::uint32_t(s.size()));
    bytes.insert(bytes.end(), s.begin(), s.end());
  }
};

/// Reads little-endian values, refusing to read past the end (ok() false then, values 0).
struct Reader {
  std::span<const std::uint8_t> bytes;
  std::size_t at = 0;
  bool failed = false;
  template <class T>
  T get() {
    T v{};
    if (failed || bytes.size() - at < sizeof v) {
      failed = true;
      return v;
    }
    std::memcpy(&v, bytes.data() + at, sizeof v);
    at += sizeof v;
    return v;
  }
  std::string get_string(std::size_t max) {
    const std::uint32_t n = get<std::uint32_t>();
    if (failed || n > max || bytes.size() - at < n) {
      failed = true;
      return {};
    }
    std::string s(reinterpret_cast<const char*>(bytes.data() + at), n);
    at += n;
    return s;
  }
  bool ok() const noexcept { return !failed; }
};

/// Deflate (zlib stream) compression and decompression of whole buffers (libdeflate). A
/// decompression that does not give exactly `out.size()` bytes fails.
std::vector<std::uint8_t> deflate(std::span<const std::uint8_t> in, int level);
bool inflate(std::span<const std::uint8_t> in, std::span<std::uint8_t> out);

/// TIFF's predictors applied to one tile (kTile rows of kTile samples) in place: horizontal
/// differencing of 16-bit samples (Predictor 2), and the floating-point predictor (Predictor 3:
/// each row's bytes split into planes, most significant first, then byte differencing).
void encode_u16(std::vector<std::uint16_t>& tile);
void decode_u16(std::uint16_t* tile);
std::vector<std::uint8_t> encode_f32(const std::vector<float>& tile);
void decode_f32(const std::uint8_t* planes, float* tile);

}  // namespace ridgeline::io::world_file
