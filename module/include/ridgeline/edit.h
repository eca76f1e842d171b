// Runtime deformation (docs/deformation.md): brushes, the edit transaction's result and limits,
// and saving / loading the edit layer.
//
// The transaction itself is Terrain::apply_edit() (terrain.h): it changes the heights, refreshes
// the ray pyramid, bumps the terrain's edit_version() and records the changed region in its
// change log, all inside the call, and returns that region. Landscapes, views, physics and
// engines learn of it by pulling Terrain::changes_since(); nothing is called back.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

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
};

/// "crater", "raise", "lower", "flatten", "smooth".
const char* brush_name(Brush b) noexcept;
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

/// Limits that give every edit a defined answer. Plain data; Terrain::set_edit_limits().
struct EditLimits {
  /// Largest area one edit may cover, square metres (pi x reach^2, reach being the brush's outer
  /// radius). A larger edit is clipped to this area (its radius shrunk, EditResult::clipped) or,
  /// with refuse_oversize, refused. Default 1e6 m^2 (a crater of ~560 m reach).
  double max_area_m2 = 1e6;
  bool refuse_oversize = false;
  /// World heights an edit may produce; samples driven past them are clamped and the result says
  /// so (EditResult::clamped). Defaults: -1e5 .. 1e5 m relative to the heightfield's offset.
  double min_height_rel = -1e5, max_height_rel = 1e5;
};

/// What an edit did.
struct EditResult {
  /// The region whose surface (heights or normals) changed: every cell touching a changed
  /// sample, in world metres; y spans the old and new heights there. Empty (samples_changed == 0)
  /// for a brush wholly outside the terrain or one that changed nothing.
  Box changed;
  std::size_t samples_changed = 0;
  /// The brush was larger than EditLimits::max_area_m2 and was applied with radius `radius_used`.
  bool clipped = false;
  double radius_used = 0;
  /// Some samples hit EditLimits' height range and were clamped (`samples_clamped` of them).
  bool clamped = false;
  std::size_t samples_clamped = 0;
  bool empty() const noexcept { return samples_changed == 0; }
};

/// Writes the terrain's edit layer to `path`: a versioned binary file (docs/deformation.md) with
/// a checksum and the hashes of the base data and detail parameters it belongs to. Written to a
/// temporary file in the same folder, flushed to disk and renamed over `path`, so a crash or a
/// full disk during the save leaves the previous file intact. Errors name the path and the cause.
Status save_edits(const Terrain& terrain, const std::string& path);

/// Replaces the terrain's edit layer with the one saved in `path` (edits made since are undone),
/// as one transaction: the heights, bounds and views update as for apply_edit(). The whole file
/// is read and checked first (magic, version, size, checksum, the base and detail hashes, every
/// chunk index and value); a truncated, corrupted or foreign file is refused with a clear error
/// and changes nothing. Exclusive access as for apply_edit().
Result<EditResult> load_edits(Terrain& terrain, const std::string& path);

/// The same from bytes already in memory (what load_edits() does after reading the file; the
/// fuzz target's entry point).
Result<EditResult> load_edits_from_memory(Terrain& terrain, std::string_view bytes);

}  // namespace ridgeline
