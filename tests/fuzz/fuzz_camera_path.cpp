// Fuzz target: io::parse_camera_path (PATH.json, version 1).
#include <cstdint>
#include <string_view>

#include "ridgeline/camera_path.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view json(reinterpret_cast<const char*>(data), size);
  auto frames = ridgeline::io::parse_camera_path(json);
  if (frames) {
    for (const auto& f : *frames) (void)f;
  }
  return 0;
}
