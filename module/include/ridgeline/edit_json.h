// Edits as JSON (the schema of edit.h and docs/deformation.md): {"edits": [{"brush": "crater",
// "x": .., "z": .., "radius": .., "depth": ..}, ...]}. Part of Ridgeline::io.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "ridgeline/edit.h"
#include "ridgeline/result.h"

namespace ridgeline::io {

/// Most edits one document may hold.
inline constexpr std::size_t kMaxEditsPerDocument = 1'000'000;

/// Parses an edit list. Every edit needs "brush", "x", "z" and "radius"; "strength", "depth",
/// "rim", "height" and "keep_detail" are optional with the defaults of struct Edit. Unknown keys,
/// wrong types, non-finite or out-of-range numbers (validate_edit) are errors naming the edit's
/// index and the field, e.g. "edits[3]: 'radius' is string; need a number".
Result<std::vector<Edit>> parse_edits(std::string_view json);
/// Reads and parses a file (at most 256 MiB).
Result<std::vector<Edit>> load_edits_json(const std::string& path);

}  // namespace ridgeline::io
