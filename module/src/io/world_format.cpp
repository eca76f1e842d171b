// The baked world's format helpers (world_format.h): checksum, Deflate, TIFF predictors.
#include "io/world_format.h"

#include <libdeflate.h>

#include <memory>

namespace ridgeline::io::world_file {

std::uint64_t checksum(const void* data, std::size_t n) noexcept {
  const auto* p = static_cast<const std::uint8_t*>(data);
  std::uint64_t h = 0x9e3779b97f4a7c15ull ^ n;
  auto mix = [&](std::uint64_t v) {
    h ^= v;
    h *= 0xbf58476d1ce4e5b9ull;
    h ^= h >> 31;
  };
  std::size_t k = 0;
  for (; k + 8 <= n; k += 8) {
    std::uint64_t v;
    std::memcpy(&v, p + k, 8);
    mix(v);
  }
  std::uint64_t tail = 0;
  for (std::size_t b = 0; k < n; ++k, ++b) tail |= std::uint64_t(p[k]) << (8 * b);
  mix(tail);
  h ^= h >> 29;
  h *= 0x94d049bb133111ebull;
  return h ^ (h >> 32);
}

namespace {

struct CompressorDeleter {
  void operator()(libdeflate_compressor* c) const { libdeflate_free_compressor(c); }
};
struct DecompressorDeleter {
  void operator()(libdeflate_decompressor* d) const { libdeflate_free_decompressor(d); }
};

}  // namespace

std::vector<std::uint8_t> deflate(std::span<const std::uint8_t> in, int level) {
  // One compressor per thread and level (allocating one costs more than a small page).
  thread_local std::unique_ptr<libdeflate_compressor, CompressorDeleter> c;
  thread_local int c_level = -1;
  if (!c || c_level != level) {
    c.reset(libdeflate_alloc_compressor(level));
    c_level = level;
  }
  // Compressed into a scratch buffer kept per thread, then copied at its size (a fresh buffer of
  // the bound's size would be zeroed, fresh pages from the system, for every tile).
  thread_local std::vector<std::uint8_t> scratch;
  const std::size_t bound = libdeflate_zlib_compress_bound(c.get(), in.size());
  if (scratch.size() < bound) scratch.resize(bound);
  const std::size_t n = libdeflate_zlib_compress(c.get(), in.data(), in.size(), scratch.data(), bound);
  return std::vector<std::uint8_t>(scratch.begin(), scratch.begin() + std::ptrdiff_t(n));
}

bool inflate(std::span<const std::uint8_t> in, std::span<std::uint8_t> out) {
  thread_local std::unique_ptr<libdeflate_decompressor, DecompressorDeleter> d(
      libdeflate_alloc_decompressor());
  std::size_t got = 0;
  const libdeflate_result r =
      libdeflate_zlib_decompress(d.get(), in.data(), in.size(), out.data(), out.size(), &got);
  return r == LIBDEFLATE_SUCCESS && got == out.size();
}

void encode_u16(std::vector<std::uint16_t>& tile) {
  for (std::uint32_t r = 0; r < kTile; ++r) {
    std::uint16_t* row = tile.data() + std::size_t(r) * kTile;
    for (std::uint32_t c = kTile - 1; c > 0; --c) row[c] = std::uint16_t(row[c] - row[c - 1]);
  }
}

void decode_u16(std::uint16_t* tile) {
  for (std::uint32_t r = 0; r < kTile; ++r) {
    std::uint16_t* row = tile + std::size_t(r) * kTile;
    for (std::uint32_t c = 1; c < kTile; ++c) row[c] = std::uint16_t(row[c] + row[c - 1]);
  }
}

std::vector<std::uint8_t> encode_f32(const std::vector<float>& tile) {
  std::vector<std::uint8_t> out(kTileSamples * 4);
  for (std::uint32_t r = 0; r < kTile; ++r) {
    std::uint8_t* row = out.data() + std::size_t(r) * kTile * 4;
    for (std::uint32_t c = 0; c < kTile; ++c) {
      std::uint32_t v;
      std::memcpy(&v, &tile[std::size_t(r) * kTile + c], 4);
      for (int b = 0; b < 4; ++b) row[std::size_t(b) * kTile + c] = std::uint8_t(v >> (24 - 8 * b));
    }
    for (std::size_t k = std::size_t(kTile) * 4 - 1; k > 0; --k)
      row[k] = std::uint8_t(row[k] - row[k - 1]);
  }
  return out;
}

void decode_f32(const std::uint8_t* planes, float* tile) {
  std::uint8_t row[kTile * 4];
  for (std::uint32_t r = 0; r < kTile; ++r) {
    std::memcpy(row, planes + std::size_t(r) * kTile * 4, sizeof row);
    for (std::size_t k = 1; k < sizeof row; ++k) row[k] = std::uint8_t(row[k] + row[k - 1]);
    for (std::uint32_t c = 0; c < kTile; ++c) {
      std::uint32_t v = 0;
      for (int b = 0; b < 4; ++b) v |= std::uint32_t(row[std::size_t(b) * kTile + c]) << (24 - 8 * b);
      std::memcpy(&tile[std::size_t(r) * kTile + c], &v, 4);
    }
  }
}

}  // namespace ridgeline::io::world_file
