// Private helpers of the JSON readers in Ridgeline::io (camera paths, edits).
#pragma once

#include <cmath>
#include <cstdint>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "format.h"
#include "ridgeline/result.h"

namespace ridgeline::io::detail {

using nlohmann::json;
using ridgeline::detail::fmt;

// Reads a finite number; false (with `err` set) when missing or wrong.
inline bool json_number(const json& o, const char* key, double& out, bool required, std::string& err) {
  auto it = o.find(key);
  if (it == o.end()) {
    if (required) err = fmt("'%s' is missing", key);
    return !required;
  }
  if (!it->is_number()) {
    err = fmt("'%s' is %s; need a number", key, it->type_name());
    return false;
  }
  out = it->get<double>();
  if (!std::isfinite(out)) {
    err = fmt("'%s' is not finite", key);
    return false;
  }
  return true;
}


/// The whole file as text; errors name `what` and the path. At most `max_bytes`.
inline Result<std::string> read_text_file(const std::string& path, std::size_t max_bytes,
                                          const char* what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{fmt("%s '%s': cannot open", what, path.c_str())};
  in.seekg(0, std::ios::end);
  const auto size = static_cast<std::int64_t>(in.tellg());
  if (size < 0) return Error{fmt("%s '%s': cannot read", what, path.c_str())};
  if (std::uint64_t(size) > max_bytes)
    return Error{fmt("%s '%s': %lld bytes; at most %zu", what, path.c_str(),
                     static_cast<long long>(size), max_bytes)};
  in.seekg(0);
  std::string text(static_cast<std::size_t>(size), '\0');
  in.read(text.data(), size);
  if (!in) return Error{fmt("%s '%s': read failed", what, path.c_str())};
  return text;
}

}  // namespace ridgeline::io::detail
