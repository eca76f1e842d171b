// Camera path JSON (PATH.json version 1, docs/cli.md "Camera paths"), parsed with nlohmann-json.
#include "ridgeline/camera_path.h"

#include <cmath>
#include <nlohmann/json.hpp>

#include "format.h"
#include "json_util.h"

namespace ridgeline::io {

namespace {

using nlohmann::json;
using detail::json_number;

bool vec(const json& o, const char* key, std::size_t n, double* out, bool required,
         std::string& err) {
  auto it = o.find(key);
  if (it == o.end()) {
    if (required) err = fmt("'%s' is missing", key);
    return !required;
  }
  if (!it->is_array() || it->size() != n) {
    err = fmt("'%s' must be an array of %zu numbers", key, n);
    return false;
  }
  for (std::size_t k = 0; k < n; ++k) {
    const json& v = (*it)[k];
    if (!v.is_number() || !std::isfinite(v.get<double>())) {
      err = fmt("'%s'[%zu] is not a finite number", key, k);
      return false;
    }
    out[k] = v.get<double>();
  }
  return true;
}

}  // namespace

Result<std::vector<PathFrame>> parse_camera_path(std::string_view text, std::size_t max_frames) {
  json doc = json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/false);
  if (doc.is_discarded()) return Error{"camera path: not valid JSON"};
  if (!doc.is_object()) return Error{"camera path: the document must be a JSON object"};
  auto ver = doc.find("version");
  if (ver == doc.end() || !ver->is_number_integer() || ver->get<std::int64_t>() != 1)
    return Error{"camera path: 'version' must be 1"};
  auto frames = doc.find("frames");
  if (frames == doc.end() || !frames->is_array())
    return Error{"camera path: 'frames' must be an array"};
  if (frames->empty()) return Error{"camera path: 'frames' is empty"};
  if (frames->size() > max_frames)
    return Error{fmt("camera path: %zu frames; at most %zu", frames->size(), max_frames)};
  std::vector<PathFrame> out;
  out.reserve(frames->size());
  for (std::size_t k = 0; k < frames->size(); ++k) {
    const json& f = (*frames)[k];
    if (!f.is_object()) return Error{fmt("camera path: frame %zu is not an object", k)};
    PathFrame pf;
    Camera& c = pf.camera;
    std::string err;
    double v3[3], v2[2];
    double fov = 0;
    bool ok = vec(f, "eye", 3, v3, true, err);
    if (ok) c.eye = {v3[0], v3[1], v3[2]};
    ok = ok && vec(f, "target", 3, v3, true, err);
    if (ok) c.target = {v3[0], v3[1], v3[2]};
    v3[0] = 0, v3[1] = 1, v3[2] = 0;
    ok = ok && vec(f, "up", 3, v3, false, err);
    if (ok) c.up = {v3[0], v3[1], v3[2]};
    ok = ok && json_number(f, "fov_y", fov, true, err);
    c.fov_y_deg = fov;
    ok = ok && vec(f, "viewport", 2, v2, true, err);
    if (ok) {
      if (!(v2[0] >= 1 && v2[1] >= 1 && v2[0] <= 65536 && v2[1] <= 65536) ||
          v2[0] != std::floor(v2[0]) || v2[1] != std::floor(v2[1])) {
        err = "'viewport' must be two integers in 1 .. 65536";
        ok = false;
      } else {
        c.viewport = {int(v2[0]), int(v2[1])};
      }
    }
    ok = ok && json_number(f, "near", c.near_m, false, err);
    ok = ok && json_number(f, "far", c.far_m, false, err);
    ok = ok && json_number(f, "dt", pf.dt, false, err);
    if (ok && !(pf.dt > 0)) {
      err = "'dt' must be > 0";
      ok = false;
    }
    if (ok) {
      if (auto s = validate_camera(c); !s) {
        err = s.message();
        ok = false;
      }
    }
    if (!ok) return Error{fmt("camera path: frame %zu: %s", k, err.c_str())};
    out.push_back(pf);
  }
  return out;
}

Result<std::vector<PathFrame>> load_camera_path(const std::string& path) {
  auto text = detail::read_text_file(path, std::size_t{512} << 20, "camera path");
  if (!text) return Error{text.error().message};
  auto r = parse_camera_path(*text);
  if (!r) return Error{fmt("%s (in '%s')", r.error().message.c_str(), path.c_str())};
  return r;
}

}  // namespace ridgeline::io
