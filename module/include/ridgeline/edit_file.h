// Edit files (docs/deformation.md, "The edit file"): a terrain's edit layer saved to a file and
// loaded back. Part of Ridgeline::io; the core (edit.h) writes and reads the same bytes in memory
// or through an engine's own stream, without a file system.
#pragma once

#include <string>

#include "ridgeline/edit.h"
#include "ridgeline/result.h"
#include "ridgeline/terrain.h"

namespace ridgeline::io {

/// Writes the terrain's edit layer (save_edits(), edit.h) to `path`, durably: to a temporary
/// file in the same folder (`path`.tmp.PID), flushed to disk, renamed over `path`, and the folder
/// flushed, so a crash, a kill or a full disk during the save leaves the previous file intact.
/// Built with RIDGELINE_PORTABLE (std::ofstream and std::filesystem::rename, no POSIX calls) it
/// renames the same way but forces nothing to disk: a power cut may lose the new file. Errors
/// name the path and the cause, e.g. "save edits 'a.bin': writing failed (No space left on
/// device); the previous file is unchanged". Const: may run while other threads query.
Status save_edits(const Terrain& terrain, const std::string& path);

/// Replaces the terrain's edit layer with the one saved in `path` (load_edits(), edit.h: checked
/// whole before anything changes). Errors name the path: "load edits 'a.bin': No such file or
/// directory", "load edits 'a.bin': edit file: checksum mismatch (the file is corrupted)".
/// Exclusive access as for Terrain::apply_edit().
Result<EditResult> load_edits(Terrain& terrain, const std::string& path);

}  // namespace ridgeline::io
