// Deformation from Lua: terrain:deform{...} (a terrain method) and the module functions
// ridgeline.save_edits / ridgeline.load_edits (they need the module's path rules).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <exception>
#include <span>

#include "lua_util.h"
#include "ridgeline/edit.h"
#include "ridgeline/edit_file.h"

namespace ridgeline::lua::detail {
namespace {

Terrain& editable_terrain(lua_State* L, int arg) {
  auto* box = static_cast<TerrainBox*>(luaL_checkudata(L, arg, kTerrainMeta));
  if (!box->terrain) luaL_error(L, "attempt to use a released ridgeline.terrain");
  return *box->terrain;
}

// Most bytes the pages under edit `e`'s reach can add once copied for it (their heights as
// floats, ray pyramid and bounds, a third more for their coarser levels).
std::size_t edit_page_bytes(const Terrain& t, const Edit& e) {
  const WorldInfo& i = t.info();
  const double reach = 1.5 * std::abs(e.radius) + 2.0 * std::max(i.spacing_x, i.spacing_z);
  const double cells_x = std::min(2.0 * reach / i.spacing_x, double(i.width));
  const double cells_z = std::min(2.0 * reach / i.spacing_z, double(i.height));
  const double pages = (std::ceil(cells_x / kPageCells) + 1) * (std::ceil(cells_z / kPageCells) + 1);
  return std::size_t(pages * double(kPageEntries) * 12.0 * 4.0 / 3.0);
}

// Reads the edit table at `arg` (docs/deformation.md's fields) into plain data; raises on a bad
// field.
Edit check_edit(lua_State* L, int arg) {
  luaL_checktype(L, arg, LUA_TTABLE);
  static const char* const kFields[] = {"brush", "x",   "z",      "radius",      "strength",
                                        "depth", "rim", "height", "keep_detail", nullptr};
  check_fields(L, arg, kFields);
  Edit e;
  lua_getfield(L, arg, "brush");
  const char* name = lua_type(L, -1) == LUA_TSTRING ? lua_tostring(L, -1) : nullptr;
  const std::optional<Brush> brush = name ? parse_brush(name) : std::nullopt;
  if (!brush) {
    lua_pushfstring(L, "field 'brush': one of %s expected", brush_names());
    luaL_argerror(L, arg, lua_tostring(L, -1));
  }
  lua_pop(L, 1);
  e.brush = *brush;
  if (!get_number_field(L, arg, "x", &e.x)) luaL_argerror(L, arg, "field 'x': number expected");
  if (!get_number_field(L, arg, "z", &e.z)) luaL_argerror(L, arg, "field 'z': number expected");
  if (!get_number_field(L, arg, "radius", &e.radius))
    luaL_argerror(L, arg, "field 'radius': number expected");
  get_number_field(L, arg, "strength", &e.strength);
  get_number_field(L, arg, "depth", &e.depth);
  get_number_field(L, arg, "rim", &e.rim);
  get_number_field(L, arg, "height", &e.height);
  if (lua_getfield(L, arg, "keep_detail") != LUA_TNIL) {
    if (!lua_isboolean(L, -1)) luaL_argerror(L, arg, "field 'keep_detail': boolean expected");
    e.keep_detail = lua_toboolean(L, -1);
  }
  lua_pop(L, 1);
  char err[kErrSize];
  bool ok = true;
  try {
    if (auto s = validate_edit(e); !s) {
      copy_error(err, s.message().c_str());
      ok = false;
    }
  } catch (const std::exception& ex) {
    copy_error(err, ex.what());
    ok = false;
  }
  if (!ok) luaL_argerror(L, arg, err);
  return e;
}

// Copies a transaction's result or its error (no Lua calls).
bool take_result(const Result<EditResult>& r, EditResult* out, char* err) noexcept {
  if (!r) {
    copy_error(err, r.error().message.c_str());
    return false;
  }
  *out = *r;
  return true;
}

// Runs apply() (-> Result<EditResult>) for the terrain at index 1 and pushes its result or nil,
// message. On a paged terrain, room for the pages under `reach` comes first (raising `what`'s
// budget error) and the charge then follows what the terrain holds.
void push_edit_result(lua_State* L, const EditResult& r);

template <class Apply>
int scripted_edit(lua_State* L, Terrain& t, const Edit& reach, const char* what, Apply apply) {
  auto* box = static_cast<TerrainBox*>(lua_touserdata(L, 1));
  const bool charge_pages = t.paged() && box->terrain_charge && box->budget;
  if (charge_pages) {
    const std::size_t own = box->terrain_charge->bytes();
    reserve_objects(L, box->budget, own + edit_page_bytes(t, reach), what, own);
  }
  char err[kErrSize];
  EditResult r;
  bool ok = false;
  try {
    ok = take_result(apply(), &r, err);
  } catch (const std::exception& ex) {
    copy_error(err, ex.what());
  }
  if (charge_pages) box->terrain_charge->set(paged_terrain_charge_bytes(t, box->cache_bytes));
  if (!ok) {
    lua_pushnil(L);
    lua_pushstring(L, err);
    return 2;
  }
  push_edit_result(L, r);
  return 1;
}

void set_field(lua_State* L, const char* key, double v) {
  lua_pushnumber(L, v);
  lua_setfield(L, -2, key);
}

void push_edit_result(lua_State* L, const EditResult& r) {
  lua_createtable(L, 0, 11);
  lua_pushinteger(L, static_cast<lua_Integer>(r.samples_changed));
  lua_setfield(L, -2, "samples");
  lua_pushinteger(L, static_cast<lua_Integer>(r.cells_changed));
  lua_setfield(L, -2, "hole_cells");
  if (!r.empty()) {
    set_field(L, "min_x", r.changed.min.x);
    set_field(L, "min_y", r.changed.min.y);
    set_field(L, "min_z", r.changed.min.z);
    set_field(L, "max_x", r.changed.max.x);
    set_field(L, "max_y", r.changed.max.y);
    set_field(L, "max_z", r.changed.max.z);
  }
  lua_pushboolean(L, r.clipped);
  lua_setfield(L, -2, "clipped");
  lua_pushboolean(L, r.clamped);
  lua_setfield(L, -2, "clamped");
  set_field(L, "radius", r.radius_used);
}

ConfigBox* config_of(lua_State* L) {
  return static_cast<ConfigBox*>(lua_touserdata(L, lua_upvalueindex(1)));
}

enum class FileOp { kSave, kLoad };

bool do_file(bool confine, const char* root, Terrain& t, const char* name, FileOp op,
             EditResult* out, char* err) noexcept {
  try {
    char path[4096];
    if (!resolve_path(confine, root, name, path, sizeof path, err)) return false;
    if (op == FileOp::kSave) {
      if (auto s = io::save_edits(t, path); !s) {
        copy_error(err, s.message().c_str());
        return false;
      }
      return true;
    }
    return take_result(io::load_edits(t, path), out, err);
  } catch (const std::exception& ex) {
    copy_error(err, ex.what());
    return false;
  }
}

// `method`: terrain:save_edits / load_edits (the terrain's own path rules); otherwise the module
// functions (the module's rules, upvalue 1).
int file_op(lua_State* L, FileOp op, bool method) {
  Terrain& t = editable_terrain(L, 1);
  luaL_checktype(L, 2, LUA_TSTRING);  // a number is not a file name (no coercion)
  const char* name = lua_tostring(L, 2);
  if (std::strlen(name) != lua_rawlen(L, 2)) luaL_argerror(L, 2, "file name holds a NUL byte");
  bool confine = true;
  const char* root = nullptr;  // kept alive by the terrain box or the module's config
  if (method) {
    const auto* box = static_cast<TerrainBox*>(lua_touserdata(L, 1));
    confine = box->confine_paths;
    root = box->root ? box->root->c_str() : nullptr;
  } else {
    const ConfigBox* config = config_of(L);
    confine = config->confine_paths;
    root = config->root;
  }
  char err[kErrSize];
  EditResult r;
  if (!do_file(confine, root, t, name, op, &r, err)) {
    lua_pushnil(L);
    lua_pushstring(L, err);
    return 2;
  }
  if (op == FileOp::kSave) {
    lua_pushboolean(L, 1);
    return 1;
  }
  push_edit_result(L, r);
  return 1;
}

}  // namespace

// terrain:deform{brush=, x=, z=, radius=, strength=, depth=, rim=, height=, keep_detail=}
//   -> {samples=, min_x=, ..., max_z=, clipped=, clamped=, radius=} or nil, message
int t_deform(lua_State* L) {
  Terrain& t = editable_terrain(L, 1);
  const Edit e = check_edit(L, 2);
  return scripted_edit(L, t, e, "deform", [&] { return t.apply_edit(e); });
}

namespace {

// The rectangle fields {i0=, j0=, width=, height=} of get_heights / set_heights: whole numbers,
// at most kMaxBatchPoints samples.
void check_rect(lua_State* L, int arg, std::uint32_t v[4]) {
  const char* names[4] = {"i0", "j0", "width", "height"};
  for (int k = 0; k < 4; ++k) {
    double x = 0;
    if (!get_number_field(L, arg, names[k], &x) || x != std::floor(x) || x < 0 || x > 4294967295.0)
      luaL_argerror(L, arg, lua_pushfstring(L, "field '%s': whole number >= 0 expected", names[k]));
    v[k] = std::uint32_t(x);
  }
  if (double(v[2]) * double(v[3]) > double(kMaxBatchPoints))
    luaL_argerror(L, arg, lua_pushfstring(L, "%d x %d samples: at most %d per call",
                                          int(v[2]), int(v[3]), int(kMaxBatchPoints)));
}

// Scratch floats the Lua collector owns, pushed on the stack: an error raised later (a longjmp
// when Lua is built as C) cannot leak them as it would a std::vector.
float* scratch_floats(lua_State* L, std::size_t n) {
  return static_cast<float*>(lua_newuserdatauv(L, std::max<std::size_t>(n, 1) * sizeof(float), 0));
}

}  // namespace

// terrain:get_heights{i0=, j0=, width=, height=} -> array of width x height heights, row by row
// (stored heights in metres, edits included) or nil, message
int t_get_heights(lua_State* L) {
  Terrain& t = editable_terrain(L, 1);
  luaL_checktype(L, 2, LUA_TTABLE);
  static const char* const kFields[] = {"i0", "j0", "width", "height", nullptr};
  check_fields(L, 2, kFields);
  std::uint32_t v[4];
  check_rect(L, 2, v);
  const std::size_t n = std::size_t(v[2]) * v[3];
  float* out = scratch_floats(L, n);
  char err[kErrSize];
  bool ok = false;
  try {
    const Status s = t.get_heights(v[0], v[1], v[2], v[3], std::span<float>(out, n), v[2]);
    ok = bool(s);
    if (!ok) copy_error(err, s.message().c_str());
  } catch (const std::exception& ex) {
    copy_error(err, ex.what());
  }
  if (!ok) {
    lua_pushnil(L);
    lua_pushstring(L, err);
    return 2;
  }
  lua_createtable(L, int(n), 0);
  for (std::size_t k = 0; k < n; ++k) {
    lua_pushnumber(L, double(out[k]));
    lua_rawseti(L, -2, lua_Integer(k + 1));
  }
  return 1;
}

// terrain:set_heights{i0=, j0=, width=, height=, heights=} -> result (as deform) or nil, message
int t_set_heights(lua_State* L) {
  Terrain& t = editable_terrain(L, 1);
  luaL_checktype(L, 2, LUA_TTABLE);
  static const char* const kFields[] = {"i0", "j0", "width", "height", "heights", nullptr};
  check_fields(L, 2, kFields);
  std::uint32_t v[4];
  check_rect(L, 2, v);
  const std::size_t n = std::size_t(v[2]) * v[3];
  float* in = scratch_floats(L, n);
  if (lua_getfield(L, 2, "heights") != LUA_TTABLE)
    luaL_argerror(L, 2, lua_pushfstring(L, "field 'heights': table expected, got %s",
                                        luaL_typename(L, -1)));
  if (lua_rawlen(L, -1) != n)
    luaL_argerror(L, 2, lua_pushfstring(L, "field 'heights': %d values for %d x %d samples",
                                        int(lua_rawlen(L, -1)), int(v[2]), int(v[3])));
  for (std::size_t k = 0; k < n; ++k) {
    if (lua_rawgeti(L, -1, lua_Integer(k + 1)) != LUA_TNUMBER)
      luaL_argerror(L, 2, lua_pushfstring(L, "field 'heights': value %d is not a number",
                                          int(k + 1)));
    in[k] = float(lua_tonumber(L, -1));
    lua_pop(L, 1);
  }
  lua_pop(L, 1);
  // The brush reaching over the rectangle, for the pages it may copy.
  Edit reach;
  const WorldInfo& i = t.info();
  reach.radius = 0.5 * std::max(double(v[2]) * i.spacing_x, double(v[3]) * i.spacing_z) / 1.5;
  return scripted_edit(L, t, reach, "set_heights",
                       [&] { return t.set_heights(v[0], v[1], v[2], v[3], std::span<const float>(in, n), v[2]); });
}

// ridgeline.save_edits(terrain, file) -> true or nil, message
int r_save_edits(lua_State* L) { return file_op(L, FileOp::kSave, false); }
// ridgeline.load_edits(terrain, file) -> result table (as deform) or nil, message
int r_load_edits(lua_State* L) { return file_op(L, FileOp::kLoad, false); }
// terrain:save_edits(file) -> true or nil, message; terrain:load_edits(file) -> result or nil, message
int t_save_edits(lua_State* L) { return file_op(L, FileOp::kSave, true); }
int t_load_edits(lua_State* L) { return file_op(L, FileOp::kLoad, true); }

}  // namespace ridgeline::lua::detail
