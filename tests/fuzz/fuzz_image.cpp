// Fuzz target: io::load_image on whole files (our header checks before and after OpenImageIO opens
// the file, the PNG chunk walk, the channel/pixel-type choice, the reads). The first byte picks
// the file extension (bits 0-2), whether a channel is chosen (bit 3) and which (bits 4-5), and
// whether the CRCs of a PNG's chunks are fixed up (bit 7); the rest is written to a file.
//
// The loader offers a file to the reader its extension names, then to the one its first bytes
// name (module/src/io/image_loader.cpp): the extension-less inputs reach every accepted reader
// through the signatures. Speed (docs/reliability/fuzzing.md): images are capped at 4,096
// samples before any pixel is decoded, and OpenImageIO runs on one thread. Mutated PNG bytes would almost always fail their
// chunk's CRC (the loader walks the chunks first), so half the PNG inputs get their CRCs
// recomputed to reach the decoder.
#include <OpenImageIO/imageio.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "io/oiio_lsan_suppressions.h"
#include "ridgeline/io.h"

namespace {

std::uint32_t crc32(const unsigned char* p, std::size_t n) {
  std::uint32_t c = 0xffffffffu;
  for (std::size_t k = 0; k < n; ++k) {
    c ^= p[k];
    for (int b = 0; b < 8; ++b) c = (c & 1) ? 0xedb88320u ^ (c >> 1) : c >> 1;
  }
  return c ^ 0xffffffffu;
}

// Recomputes the CRC of every whole chunk after the 8-byte signature.
void fix_png_crcs(std::vector<unsigned char>& b) {
  std::size_t at = 8;
  while (at + 12 <= b.size()) {
    const std::uint64_t len = (std::uint64_t(b[at]) << 24) | (std::uint64_t(b[at + 1]) << 16) |
                              (std::uint64_t(b[at + 2]) << 8) | b[at + 3];
    if (len > b.size() - at - 12) break;
    const std::uint32_t c = crc32(&b[at + 4], std::size_t(len) + 4);
    for (int k = 0; k < 4; ++k) b[at + 8 + len + k] = static_cast<unsigned char>(c >> (24 - 8 * k));
    at += std::size_t(len) + 12;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const bool init = [] {
    OIIO::attribute("threads", 1);
    OIIO::attribute("exr_threads", 1);
    return true;
  }();
  (void)init;
  if (size < 1) return 0;
  static const char* const kExt[] = {".png", ".tif", ".exr", ".pgm", ".hdr", ".bmp", ".tga", ""};
  const char* ext = kExt[data[0] % 8];
  std::vector<unsigned char> bytes(data + 1, data + size);
  if (std::strcmp(ext, ".png") == 0 && (data[0] & 0x80) != 0) fix_png_crcs(bytes);
  const std::string path = "/tmp/ridgeline_fuzz_image_" + std::to_string(getpid()) + ext;
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) return 0;
  std::fwrite(bytes.data(), 1, bytes.size(), f);
  std::fclose(f);
  ridgeline::io::LoadOptions options;
  options.placement.max_samples = 1 << 12;
  options.channel = (data[0] & 8) != 0 ? static_cast<int>(data[0] >> 4) % 4 : -1;
  auto hf = ridgeline::io::load_image(path, options);
  (void)hf;
  std::remove(path.c_str());
  return 0;
}
