// Fuzz target: the deformation-state loader (load_edits_from_memory, what load_edits runs on the
// file's bytes) onto a small terrain per input. The seeds are real saves of that terrain, so
// the fuzzer starts past the header and hash checks. Inputs whose first byte is even get their
// trailing FNV-1a checksum recomputed (the file format's, module/src/edit/edit_file.cpp), so that mutations
// reach the chunk parsing instead of stopping at "checksum mismatch". A refused input must leave
// the terrain unchanged; an accepted one is one change-log entry at most, with a ray pyramid equal
// to a rebuild.
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <string_view>

#include "ridgeline/edit.h"
#include "ridgeline/heightfield.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace ridgeline;
  // Every input loads onto a clone of one pristine terrain: the clone shares its pages until an
  // edit writes one (Terrain::clone), so an input that is refused allocates no page (a fresh
  // terrain's pages are fresh memory for each input under ASan's allocator: 30x slower). The
  // terrain is the one the seeds were saved from by `ridge deform --default-terrain
  // --default-size 33` (an edit file names its terrain by a hash of its data).
  static const std::shared_ptr<const Terrain> pristine = [] {
    DefaultTerrainParams p;
    p.size = 33;
    return std::shared_ptr<const Terrain>(
        Terrain::create(std::move(make_default_heightfield(p)).value()).value());
  }();
  auto terrain = pristine->clone();
  std::string bytes(reinterpret_cast<const char*>(data), size);
  if (size >= 8 && (data[0] & 1) == 0) {
    std::uint64_t h = 1469598103934665603ull;
    for (std::size_t k = 0; k + 8 < size; ++k) {
      h ^= static_cast<unsigned char>(bytes[k]);
      h *= 1099511628211ull;
    }
    std::memcpy(bytes.data() + size - 8, &h, 8);  // little-endian, as the file stores it
  }
  const std::uint64_t before = terrain->surface().heights_hash();
  auto r = load_edits_from_memory(*terrain, bytes);
  if (r) {
    (void)terrain->height(100, 100);
    // A load is one change at most, recorded in the log, and the ray pyramid follows it.
    const TerrainChanges c = terrain->changes_since(0);
    if (c.version != (r->empty() ? 0u : 1u) || c.changes.size() != c.version) __builtin_trap();
    if (!terrain->check_invariants().empty()) __builtin_trap();
  } else if (terrain->surface().heights_hash() != before || terrain->edit_version() != 0) {
    __builtin_trap();  // a refused file changed the terrain
  }
  return 0;
}
