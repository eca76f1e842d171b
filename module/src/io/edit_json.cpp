// Edit lists as JSON (docs/deformation.md, "Brushes"), parsed with nlohmann-json.
#include "ridgeline/edit_json.h"

#include <algorithm>
#include <nlohmann/json.hpp>

#include "format.h"
#include "json_util.h"

namespace ridgeline::io {

Result<std::vector<Edit>> parse_edits(std::string_view text) {
  using nlohmann::json;
  json doc = json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/false);
  if (doc.is_discarded()) return Error{"edits: not valid JSON"};
  if (!doc.is_object()) return Error{"edits: the document must be a JSON object"};
  for (const auto& kv : doc.items())
    if (kv.key() != "edits") return Error{"edits: unknown key '" + kv.key() + "'"};
  auto list = doc.find("edits");
  if (list == doc.end() || !list->is_array()) return Error{"edits: 'edits' must be an array"};
  if (list->size() > kMaxEditsPerDocument)
    return Error{fmt("edits: %zu edits; at most %zu", list->size(), kMaxEditsPerDocument)};
  static const char* const kKeys[] = {"brush", "x",   "z",      "radius",     "strength",
                                      "depth", "rim", "height", "keep_detail"};
  std::vector<Edit> out;
  out.reserve(list->size());
  for (std::size_t k = 0; k < list->size(); ++k) {
    const json& e = (*list)[k];
    if (!e.is_object()) return Error{fmt("edits[%zu]: not an object", k)};
    for (const auto& kv : e.items())
      if (std::find(std::begin(kKeys), std::end(kKeys), kv.key()) == std::end(kKeys))
        return Error{fmt("edits[%zu]: unknown key '%s'", k, kv.key().c_str())};
    Edit ed;
    auto b = e.find("brush");
    if (b == e.end() || !b->is_string())
      return Error{fmt("edits[%zu]: 'brush' must be one of %s", k, brush_names())};
    auto brush = parse_brush(b->get_ref<const std::string&>());
    if (!brush)
      return Error{fmt("edits[%zu]: unknown brush '%s'; need %s", k,
                       b->get_ref<const std::string&>().c_str(), brush_names())};
    ed.brush = *brush;
    std::string err;
    bool ok = detail::json_number(e, "x", ed.x, true, err) &&
              detail::json_number(e, "z", ed.z, true, err) &&
              detail::json_number(e, "radius", ed.radius, true, err) &&
              detail::json_number(e, "strength", ed.strength, false, err) &&
              detail::json_number(e, "depth", ed.depth, false, err) &&
              detail::json_number(e, "rim", ed.rim, false, err) &&
              detail::json_number(e, "height", ed.height, false, err);
    if (ok) {
      auto kd = e.find("keep_detail");
      if (kd != e.end()) {
        if (!kd->is_boolean()) {
          err = "'keep_detail' must be true or false";
          ok = false;
        } else {
          ed.keep_detail = kd->get<bool>();
        }
      }
    }
    if (ok) {
      if (auto s = validate_edit(ed); !s) {
        err = s.message();
        ok = false;
      }
    }
    if (!ok) return Error{fmt("edits[%zu]: %s", k, err.c_str())};
    out.push_back(ed);
  }
  return out;
}

Result<std::vector<Edit>> load_edits_json(const std::string& path) {
  auto text = detail::read_text_file(path, std::size_t{256} << 20, "edits");
  if (!text) return Error{text.error().message};
  auto r = parse_edits(*text);
  if (!r) return Error{fmt("%s (in '%s')", r.error().message.c_str(), path.c_str())};
  return r;
}

}  // namespace ridgeline::io
