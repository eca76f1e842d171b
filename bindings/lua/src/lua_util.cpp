// Argument checking (the public ridgeline/lua/check.h), metatables and path confinement shared by
// the wrap files.
#include "lua_util.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <system_error>

namespace ridgeline::lua {

namespace {

const char* non_finite_name(double v) {
  return std::isnan(v) ? "nan" : (v > 0 ? "inf" : "-inf");
}

}  // namespace

double check_finite(lua_State* L, int arg) {
  // No string coercion, as in option tables: t:height("10", 1) is refused like t:height({}, 1).
  if (lua_type(L, arg) != LUA_TNUMBER) luaL_typeerror(L, arg, "number");
  const double v = lua_tonumber(L, arg);
  if (!std::isfinite(v)) {
    lua_pushfstring(L, "finite number expected, got %s", non_finite_name(v));
    luaL_argerror(L, arg, lua_tostring(L, -1));
  }
  return v;
}

double opt_finite(lua_State* L, int arg, double def) {
  return lua_isnoneornil(L, arg) ? def : check_finite(L, arg);
}

void check_fields(lua_State* L, int arg, const char* const* names) {
  lua_pushnil(L);
  while (lua_next(L, arg) != 0) {
    lua_pop(L, 1);  // value
    bool known = false;
    if (lua_type(L, -1) == LUA_TSTRING) {
      const char* key = lua_tostring(L, -1);
      for (const char* const* n = names; *n != nullptr && !known; ++n)
        known = std::strcmp(*n, key) == 0;
    }
    if (!known) {
      lua_pushfstring(L, "unknown field '%s'", luaL_tolstring(L, -1, nullptr));
      luaL_argerror(L, arg, lua_tostring(L, -1));
    }
  }
}

bool get_number_field(lua_State* L, int arg, const char* name, double* out) {
  const int type = lua_getfield(L, arg, name);
  if (type == LUA_TNIL) {
    lua_pop(L, 1);
    return false;
  }
  int isnum = 0;
  const double v = lua_tonumberx(L, -1, &isnum);
  if (type != LUA_TNUMBER) {  // no string coercion in option tables
    lua_pushfstring(L, "field '%s': number expected, got %s", name, luaL_typename(L, -1));
    luaL_argerror(L, arg, lua_tostring(L, -1));
  }
  if (!std::isfinite(v)) {
    lua_pushfstring(L, "field '%s': finite number expected, got %s", name, non_finite_name(v));
    luaL_argerror(L, arg, lua_tostring(L, -1));
  }
  lua_pop(L, 1);
  *out = v;
  return true;
}

bool get_bool_field(lua_State* L, int arg, const char* name, bool* out) {
  const int type = lua_getfield(L, arg, name);
  if (type == LUA_TNIL) {
    lua_pop(L, 1);
    return false;
  }
  if (type != LUA_TBOOLEAN) {
    lua_pushfstring(L, "field '%s': boolean expected, got %s", name, luaL_typename(L, -1));
    luaL_argerror(L, arg, lua_tostring(L, -1));
  }
  *out = lua_toboolean(L, -1) != 0;
  lua_pop(L, 1);
  return true;
}

bool get_string_field(lua_State* L, int arg, const char* name, const char** out, std::size_t* len) {
  const int type = lua_getfield(L, arg, name);
  if (type == LUA_TNIL) {
    lua_pop(L, 1);
    return false;
  }
  if (type != LUA_TSTRING) {  // no number-to-string coercion either
    lua_pushfstring(L, "field '%s': string expected, got %s", name, luaL_typename(L, -1));
    luaL_argerror(L, arg, lua_tostring(L, -1));
  }
  std::size_t n = 0;
  *out = lua_tolstring(L, -1, &n);  // the table holds the string: it outlives the pop
  if (len != nullptr) *len = n;
  lua_pop(L, 1);
  return true;
}

bool get_vector_field(lua_State* L, int arg, const char* name, int n, double* out) {
  const int type = lua_getfield(L, arg, name);
  if (type == LUA_TNIL) {
    lua_pop(L, 1);
    return false;
  }
  if (type != LUA_TTABLE || lua_rawlen(L, -1) != static_cast<lua_Unsigned>(n)) {
    lua_pushfstring(L, "field '%s': array of %d numbers expected, got %s", name, n,
                    luaL_typename(L, -1));
    luaL_argerror(L, arg, lua_tostring(L, -1));
  }
  for (int i = 0; i < n; ++i) {
    lua_rawgeti(L, -1, i + 1);
    int isnum = 0;
    const double v = lua_tonumberx(L, -1, &isnum);
    isnum = isnum && lua_type(L, -1) == LUA_TNUMBER;
    if (!isnum || !std::isfinite(v)) {
      lua_pushfstring(L, "field '%s': entry %d: finite number expected, got %s", name, i + 1,
                      isnum ? non_finite_name(v) : luaL_typename(L, -1));
      luaL_argerror(L, arg, lua_tostring(L, -1));
    }
    out[i] = v;
    lua_pop(L, 1);
  }
  lua_pop(L, 1);
  return true;
}

}  // namespace ridgeline::lua

namespace ridgeline::lua::detail {

void copy_error(char* err, const char* text) noexcept {
  std::strncpy(err, text, kErrSize - 1);
  err[kErrSize - 1] = '\0';
}

void* check_self(lua_State* L, const char* tname) {
  void* p = lua_touserdata(L, 1);
  if (p != nullptr && lua_getmetatable(L, 1)) {
    const bool ok = lua_rawequal(L, -1, lua_upvalueindex(1));
    lua_pop(L, 1);
    if (ok) return p;
  }
  luaL_typeerror(L, 1, tname);
  return nullptr;
}

void push_metatable(lua_State* L, const char* tname, const luaL_Reg* methods,
                    const luaL_Reg* metamethods) {
  if (luaL_newmetatable(L, tname) == 0) return;  // already registered in this state
  lua_newtable(L);                               // methods
  lua_pushvalue(L, -2);
  luaL_setfuncs(L, methods, 1);
  lua_setfield(L, -2, "__index");
  lua_pushvalue(L, -1);
  luaL_setfuncs(L, metamethods, 1);
  // Scripts may not read or replace the metatable (getmetatable returns the type name).
  lua_pushstring(L, tname);
  lua_setfield(L, -2, "__metatable");
}

bool resolve_path(const ConfigBox& config, const char* name, char* out, std::size_t size,
                  char* err) noexcept {
  return resolve_path(config.confine_paths, config.root, name, out, size, err);
}

void set_path_rules(TerrainBox* box, const ConfigBox& config) {
  box->confine_paths = config.confine_paths;
  box->root = std::make_shared<const std::string>(config.root);
}

bool resolve_path(bool confine_paths, const char* config_root, const char* name, char* out,
                  std::size_t size, char* err) noexcept {
  namespace fs = std::filesystem;
  if (config_root == nullptr) config_root = "";
  try {
    if (name[0] == '\0') {
      copy_error(err, "empty file name");
      return false;
    }
    if (!confine_paths) {
      if (std::strlen(name) + 1 > size) {
        copy_error(err, "file name too long");
        return false;
      }
      std::strcpy(out, name);
      return true;
    }
    // The name as given, shortened so that the reason still fits the error buffer.
    const std::string_view given(name);
    std::string msg =
        "file '" +
        (given.size() > 160 ? std::string(given.substr(0, 160)) + "..." : std::string(given)) +
        "': ";
    if (config_root[0] == '\0') {
      copy_error(err, (msg + "file access is not granted to scripts").c_str());
      return false;
    }
    const fs::path rel(name);
    if (rel.is_absolute() || rel.has_root_name() || rel.has_root_directory() || name[0] == '~') {
      copy_error(err, (msg + "absolute paths are not allowed; give a path relative to the "
                             "granted folder")
                          .c_str());
      return false;
    }
    for (const fs::path& part : rel) {
      if (part == "..") {
        copy_error(err, (msg + "'..' is not allowed in file names").c_str());
        return false;
      }
    }
    if (std::strchr(name, '\\') != nullptr) {
      copy_error(err, (msg + "backslashes are not allowed in file names").c_str());
      return false;
    }
    // Symbolic links may still point outside: compare canonical forms.
    std::error_code ec;
    const fs::path root = fs::weakly_canonical(fs::path(config_root), ec);
    if (ec) {
      copy_error(err, (msg + "the granted folder is not accessible").c_str());
      return false;
    }
    const fs::path full = fs::weakly_canonical(root / rel, ec);
    if (ec) {
      copy_error(err, (msg + "cannot resolve: " + ec.message()).c_str());
      return false;
    }
    const auto [root_end, full_it] =
        std::mismatch(root.begin(), root.end(), full.begin(), full.end());
    if (root_end != root.end()) {
      copy_error(err, (msg + "resolves outside the granted folder").c_str());
      return false;
    }
    const std::string s = full.string();
    if (s.size() + 1 > size) {
      copy_error(err, (msg + "file name too long").c_str());
      return false;
    }
    std::strcpy(out, s.c_str());
    return true;
  } catch (const std::exception& e) {
    copy_error(err, e.what());
    return false;
  }
}

void account_memory(lua_State* L, std::size_t bytes) {
  const int kb = static_cast<int>(std::min<std::size_t>(bytes / 1024, 1 << 20));
  if (kb > 0) lua_gc(L, LUA_GCSTEP, kb);
}

namespace {
char kConfigKey;  // registry key (light userdata address) of the last opened module's config
}  // namespace

void register_config(lua_State* L, int index) {
  lua_pushvalue(L, index);
  lua_rawsetp(L, LUA_REGISTRYINDEX, &kConfigKey);
}

std::shared_ptr<ObjectBudget> object_budget_of(lua_State* L) {
  lua_rawgetp(L, LUA_REGISTRYINDEX, &kConfigKey);
  const auto* config = static_cast<const ConfigBox*>(lua_touserdata(L, -1));
  lua_pop(L, 1);
  return config != nullptr ? config->budget : nullptr;
}

int object_budget_error(lua_State* L, const ObjectBudget& budget, const char* what,
                        const char* detail) {
  constexpr double kMiB = 1024.0 * 1024.0;
  char text[512];
  std::snprintf(text, sizeof text,
                "%s: C++ object memory budget exceeded (%s): %.1f MiB of %.1f MiB held by the "
                "terrains, landscapes and views made by scripts; release objects (obj:release(), "
                "a <close> variable) or ask the host to raise its object_memory_limit",
                what, detail, double(budget.used) / kMiB, double(budget.limit) / kMiB);
  return luaL_error(L, "%s", text);
}

bool make_room(lua_State* L, const std::shared_ptr<ObjectBudget>& budget, std::size_t bytes,
               std::size_t own) {
  if (!budget || budget->limit == 0) return true;
  const ObjectBudget& b = *budget;
  if (b.used - std::min(own, b.used) + bytes <= b.limit) return true;
  lua_gc(L, LUA_GCCOLLECT, 0);
  return b.used - std::min(own, b.used) + bytes <= b.limit;
}

void reserve_objects(lua_State* L, const std::shared_ptr<ObjectBudget>& budget, std::size_t bytes,
                     const char* what, std::size_t own) {
  if (make_room(L, budget, bytes, own)) return;
  char detail[96];
  std::snprintf(detail, sizeof detail, "%.1f MiB more needed", double(bytes) / (1024.0 * 1024.0));
  object_budget_error(L, *budget, what, detail);
}

std::size_t terrain_charge_bytes(const Terrain& terrain, std::size_t cache_bytes, bool shared) {
  const WorldInfo& info = terrain.info();
  // An edit copies the pages holding the samples it changes (copy on write, their coarser levels
  // too): at most every level-0 page once more, its samples as floats, its apron and its ray
  // bounds, plus a third for the coarser levels.
  const std::size_t pages = ((std::size_t{info.width} + kPageCells - 1) / kPageCells) *
                            ((std::size_t{info.height} + kPageCells - 1) / kPageCells);
  const std::size_t edit_layer = pages * kPageEntries * (sizeof(float) + 2) * 4 / 3;
  const std::size_t change_log = kChangeLogCapacity * (sizeof(TerrainChange) + 16);
  return (shared ? 0 : terrain.memory_bytes()) + edit_layer + change_log + cache_bytes;
}

std::size_t paged_terrain_charge_bytes(const Terrain& terrain, std::size_t cache_bytes) {
  const std::size_t change_log = kChangeLogCapacity * (sizeof(TerrainChange) + 16);
  return std::max(cache_bytes, terrain.memory_bytes()) + change_log;
}

}  // namespace ridgeline::lua::detail
