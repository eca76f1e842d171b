// Fuzz target: io::load_image on whole files (our header checks before and after OpenImageIO opens
// the file, the channel/pixel-type choice, the reads). The first byte picks the file extension
// (OpenImageIO tries the matching reader first); the rest is written to a temporary file.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

#include "io/oiio_lsan_suppressions.h"
#include "ridgeline/io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  static const char* const kExt[] = {".png", ".tif", ".exr", ".pgm", ".hdr", ".bmp", ".tga", ""};
  const std::string path = "/tmp/ridgeline_fuzz_image_" + std::to_string(getpid()) + kExt[data[0] % 8];
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) return 0;
  std::fwrite(data + 1, 1, size - 1, f);
  std::fclose(f);
  ridgeline::io::LoadOptions options;
  options.placement.max_samples = 1 << 16;
  options.channel = (data[0] & 8) != 0 ? static_cast<int>(data[0] >> 4) % 4 : -1;
  auto hf = ridgeline::io::load_image(path, options);
  (void)hf;
  std::remove(path.c_str());
  return 0;
}
