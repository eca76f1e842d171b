// Runtime deformation (docs/deformation.md): brushes, the edit transaction's result and limits,
// and saving / loading the edit layer in memory or through a stream (files: edit_file.h, in
// Ridgeline::io).
//
// The transaction itself is Terrain::apply_edit() (terrain.h): it changes the heights, refreshes
// the ray pyramid, bumps the terrain's edit_version() and records the changed region in its
// change log, all inside the call, and returns that region. Landscapes, views, physics and
// engines learn of it by pulling Terrain::changes_since(); nothing is called back.
#pragma once

#include <cstdint>
#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "ridgeline/edit_limits.h"
#include "ridgeline/result.h"
#include "ridgeline/terrain.h"

namespace ridgeline {

/// The brushes (docs/deformation.md gives each one's formula).
enum class Brush : std::uint8_t {
  kCrater,   ///< bowl of `depth` metres with a raised rim (`rim` x depth) out to 1.5 x radius
  kRaise,    ///< adds strength x depth metres at the centre, smooth falloff to 0 at the radius
  kLower,    ///< the same, downwards
  kFlatten,  ///< blends towards world height `height`: full weight inside radius / 2, smooth to 0
  kSmooth,   ///< blends each sample towards the mean of its 3 x 3 neighbourhood
  /// Removes the ground over every stored cell whose centre lies within `radius` of (x, z): no
  /// height, no triangle, rays and bodies pass through (docs/deformation.md, "Holes"). Heights
  /// are kept, so kFillHole gives them back. strength, depth, rim and height are not used.
  kHole,
  /// Gives the ground back over the hole cells whose centre lies within `radius`, with the
  /// heights they had.
  kFillHole,
};

/// "crater", "raise", "lower", "flatten", "smooth", "hole", "fill_hole".
const char* brush_name(Brush b) noexcept;
/// "crater, raise, lower, flatten, smooth, hole or fill_hole": every brush name, for messages.
const char* brush_names() noexcept;
/// The brush named `name`; empty for anything else.
std::optional<Brush> parse_brush(std::string_view name) noexcept;

/// One edit: the same fields in C++, JSON (edit_json.h), Lua tables and the save file.
struct Edit {
  Brush brush = Brush::kCrater;
  double x = 0, z = 0;    ///< centre, world metres
  double radius = 10;     ///< metres, > 0; the crater's rim reaches out to 1.5 x radius
  double strength = 1;    ///< 0..1: scales raise / lower / crater, blend weight of flatten / smooth
  double depth = 2;       ///< metres: crater depth (negative makes a mound), raise / lower amount
  double rim = 0.2;       ///< crater rim height as a fraction of depth, 0..1
  double height = 0;      ///< flatten: target world height, metres
  /// Edits are stored at the base spacing and procedural detail rides on top of them, so the
  /// detail shows through an edited site (a flattened one included). false asks for the brush to
  /// replace the detail under it: Terrain::apply_edit() refuses that on a terrain with detail
  /// (an error saying so; nothing changes), and on a terrain without detail, where there is no
  /// detail to replace, it is the same edit as true (docs/deformation.md, "keep_detail").
  bool keep_detail = true;
};

/// Checks every field (finite, radius > 0, strength and rim in 0..1). The error names the field
/// and the value, e.g. "edit: radius is -3; need a finite value > 0".
Status validate_edit(const Edit& edit);

/// What an edit did.
struct EditResult {
  /// The region whose surface (heights, normals or holes) changed: every cell touching a changed
  /// sample and every cell made a hole or given back, in world metres; y spans the old and new
  /// heights there. Empty (empty()) for a brush wholly outside the terrain or one that changed
  /// nothing.
  Box changed;
  std::size_t samples_changed = 0;
  /// The brush was larger than EditLimits::max_area_m2 and was applied with radius `radius_used`.
  bool clipped = false;
  double radius_used = 0;
  /// Some samples hit EditLimits' height range and were clamped (`samples_clamped` of them).
  bool clamped = false;
  std::size_t samples_clamped = 0;
  /// Stored cells made holes or given back by `hole` / `fill_hole` (or by loading an edit file).
  std::size_t cells_changed = 0;
  bool empty() const noexcept { return samples_changed == 0 && cells_changed == 0; }
};

// ---- the edit layer saved and loaded (docs/deformation.md, "The edit file") -------------------
// The core writes and reads the edit file's bytes; where they go is the caller's: memory (an
// engine's own save game), a stream of its own (EditSink, EditSource), or a file through
// Ridgeline::io (io::save_edits / io::load_edits in edit_file.h: written to a temporary name and
// renamed). The core touches no file system.

/// Where save_edits() writes an edit file's bytes: an engine's save game, a network buffer, a
/// file. Implemented by the caller; used by one save at a time.
class EditSink {
 public:
  virtual ~EditSink() = default;
  /// Appends `bytes` (at most 64 KiB a call, in file order). An error stops the save, and
  /// save_edits() returns it unchanged.
  virtual Status write(std::string_view bytes) = 0;
};

/// Where load_edits() reads an edit file's bytes from. Implemented by the caller.
class EditSource {
 public:
  virtual ~EditSource() = default;
  /// Reads up to `buffer.size()` bytes into `buffer` and returns how many it read: 0 only at the
  /// end of the data. An error stops the load (nothing changes), and load_edits() returns it
  /// unchanged.
  virtual Result<std::size_t> read(std::span<char> buffer) = 0;
};

/// Writes the terrain's edit layer to `out` as an edit file: versioned, with a checksum and the
/// hashes of the base data and detail parameters it belongs to (docs/deformation.md), 72 bytes
/// plus 4,104 per edited 32 x 32 chunk, in a few write() calls. Returns the sink's first error
/// (the sink then holds part of a file: a caller that replaces an earlier save keeps it until the
/// save succeeded, as io::save_edits does). Const: may run while other threads query.
Status save_edits(const Terrain& terrain, EditSink& out);

/// The same into memory: the bytes of the edit file (what an engine stores in its save game).
std::string save_edits_to_memory(const Terrain& terrain);

/// Replaces the terrain's edit layer with the one read from `in` (edits made since are undone),
/// as one transaction: the heights, bounds and views update as for apply_edit(). Everything is
/// read and checked first (magic, version, size, checksum, the base and detail hashes, every
/// chunk index and value); a truncated, corrupted or foreign file, or a source error, is refused
/// with an error naming the problem ("edit file: ...") and changes nothing. Reads at most one
/// chunk more than the largest edit file of this terrain can hold: a longer stream is refused
/// without reading it all. Exclusive access as for apply_edit().
Result<EditResult> load_edits(Terrain& terrain, EditSource& in);

/// The same from the bytes of an edit file in memory (the fuzz target's entry point).
Result<EditResult> load_edits_from_memory(Terrain& terrain, std::string_view bytes);

}  // namespace ridgeline
