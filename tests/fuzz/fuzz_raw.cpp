// Fuzz target: io::parse_raw (headerless raw heightmaps). Byte 0 and 1 choose the size (0..63),
// byte 2 the sample type, the no-data value and the fill policy; the rest is the file.
#include <cstdint>
#include <span>

#include "ridgeline/io.h"
#include "ridgeline/terrain.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace ridgeline;
  if (size < 3) return 0;
  io::RawFormat format;
  format.width = data[0] % 64;
  format.height = data[1] % 64;
  format.type = (data[2] & 1) != 0 ? io::RawType::kF32 : io::RawType::kU16;
  io::LoadOptions options;
  options.placement.max_samples = 1 << 12;
  if ((data[2] & 2) != 0) options.placement.nodata = 0.0;
  if ((data[2] & 4) != 0) options.placement.fill = FillPolicy::kNearest;
  const auto bytes = std::as_bytes(std::span(data + 3, size - 3));
  auto hf = io::parse_raw(bytes, format, options, "fuzz");
  if (hf) {
    // A heightfield that was created must answer queries over its whole extent.
    const double w = hf->width(), h = hf->height();
    auto terrain = Terrain::create(std::move(*hf)).value();
    for (double x = -1; x <= w; x += 0.75)
      for (double z = -1; z <= h; z += 1.25) (void)terrain->height(x, z);
  }
  return 0;
}
