// Fuzz target: the deformation-state loader (load_edits_from_memory, what load_edits runs on the
// file's bytes) onto a fresh small terrain per input. The seed is a real save of that terrain, so
// the fuzzer starts past the header and hash checks.
#include <cstdint>
#include <string_view>

#include "ridgeline/edit.h"
#include "ridgeline/heightfield.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace ridgeline;
  DefaultTerrainParams p;
  p.size = 33;
  p.spacing = 8;
  auto terrain = Terrain::create(std::move(make_default_heightfield(p)).value());
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  auto r = load_edits_from_memory(*terrain, bytes);
  if (r) (void)terrain->height(100, 100);
  return 0;
}
