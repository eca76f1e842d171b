// Fuzz target: io::parse_edits (the edits JSON, docs/deformation.md "Brushes"); every edit it
// accepts must pass validate_edit and apply to a small terrain, failing only with the one refusal
// the default limits have: a radius larger than the terrain (regression input
// crash-radius-beyond-terrain).
#include <cstdint>
#include <string_view>

#include "ridgeline/edit.h"
#include "ridgeline/edit_json.h"
#include "ridgeline/heightfield.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace ridgeline;
  const std::string_view json(reinterpret_cast<const char*>(data), size);
  auto edits = io::parse_edits(json);
  if (!edits) return 0;
  DefaultTerrainParams p;
  p.size = 33;
  p.spacing = 8;
  auto terrain = Terrain::create(std::move(make_default_heightfield(p)).value()).value();
  const Heightfield hf = terrain->surface().to_heightfield().value();
  const double extent = hf.extent_x() > hf.extent_z() ? hf.extent_x() : hf.extent_z();
  for (const Edit& e : *edits) {
    if (!validate_edit(e)) __builtin_trap();  // parse_edits let through an invalid edit
    if (!terrain->apply_edit(e) && !(e.radius > extent)) __builtin_trap();
  }
  return 0;
}
