// Helpers shared by the wrap files. Rules for every lua_CFunction here (the stock interpreter
// carries the C build of Lua, whose errors longjmp over C++ frames):
//  - read and check every argument first, into plain data (no object with a destructor);
//  - do the C++ work in a `noexcept` helper that makes no Lua call, catches std::exception (never
//    `...`) and reports failure through a char buffer;
//  - push results only after the helper has returned and its objects are gone.
#pragma once

#include <cstddef>
#include <cstdint>
#include <lua.hpp>
#include <memory>
#include <string>

#include "ridgeline/landscape.h"
#include "ridgeline/lua/check.h"
#include "ridgeline/lua/module.h"
#include "ridgeline/roam_view.h"
#include "ridgeline/terrain.h"

namespace ridgeline::lua::detail {

inline constexpr char kTerrainMeta[] = "ridgeline.terrain";
inline constexpr char kViewMeta[] = "ridgeline.view";
inline constexpr char kConfigMeta[] = "ridgeline.config";
inline constexpr char kBudgetMeta[] = "ridgeline.budget_controller";
inline constexpr std::size_t kErrSize = 512;

/// Per-module-table settings and caches: a userdata (with __gc) that module functions reach as
/// upvalue 1.
struct ConfigBox {
  bool confine_paths = false;
  std::uint64_t max_samples = 0;
  char root[4096] = {};
  // Built on the first default_terrain() call and never handed out: every call returns a clone,
  // so one script's craters never reach another's terrain.
  std::shared_ptr<const Terrain> default_terrain;
};

/// A terrain userdata. Released: `terrain` is empty.
struct TerrainBox {
  std::shared_ptr<Terrain> terrain;
  // The path rules of the module that made it (terrain:save_edits / load_edits).
  bool confine_paths = true;
  std::shared_ptr<const std::string> root;
  std::shared_ptr<const Landscape> landscape;  // built on the first new_view
};

/// A view userdata. Released: `view` is empty.
struct ViewBox {
  std::unique_ptr<RoamView> view;
  Camera camera;
  RoamStats last;
  bool has_stats = false;
};

/// Copies `text` into `err` (kErrSize bytes), truncating.
void copy_error(char* err, const char* text) noexcept;

// The argument checks are public (ridgeline/lua/check.h, for games binding their own types).
using ridgeline::lua::check_fields;
using ridgeline::lua::check_finite;
using ridgeline::lua::get_bool_field;
using ridgeline::lua::get_number_field;
using ridgeline::lua::get_string_field;
using ridgeline::lua::get_vector_field;
using ridgeline::lua::opt_finite;

/// Metatable check against upvalue 1 of the running method (fast: no registry lookup). Raises a
/// type error naming `tname` when argument 1 is not such a userdata.
void* check_self(lua_State* L, const char* tname);

/// Creates (once) the metatable `tname` with `methods` as __index and the given metamethods;
/// every method gets the metatable as upvalue 1. Leaves the metatable on the stack.
void push_metatable(lua_State* L, const char* tname, const luaL_Reg* methods,
                    const luaL_Reg* metamethods);

/// Pushes a new, empty, released-state terrain userdata with its metatable.
TerrainBox* push_terrain_box(lua_State* L);
/// Registers the view metatable (called by new_view).
ViewBox* push_view_box(lua_State* L);

/// Resolves a script-given file name under the config's rules into `out` (a buffer of `size`
/// bytes). Returns false with a message in `err` when the name is refused. No Lua calls.
bool resolve_path(const ConfigBox& config, const char* name, char* out, std::size_t size,
                  char* err) noexcept;
/// The same with the rules spelled out (`root` may be null: no file access when confined).
bool resolve_path(bool confine_paths, const char* root, const char* name, char* out,
                  std::size_t size, char* err) noexcept;
/// Gives a new terrain box the module's path rules.
void set_path_rules(TerrainBox* box, const ConfigBox& config);

/// Tells the collector about C++ memory held by a new object (kilobytes), so that dropped
/// objects are finalized before they pile up.
void account_memory(lua_State* L, std::size_t bytes);

/// Method tables, for `open_module`.
int new_view(lua_State* L);               // terrain:new_view, defined in wrap_view.cpp
int new_budget_controller(lua_State* L);  // ridgeline.budget_controller, wrap_budget.cpp
int t_deform(lua_State* L);               // terrain:deform, wrap_edit.cpp
int r_save_edits(lua_State* L);           // ridgeline.save_edits, wrap_edit.cpp
int r_load_edits(lua_State* L);           // ridgeline.load_edits, wrap_edit.cpp
int t_save_edits(lua_State* L);           // terrain:save_edits, wrap_edit.cpp
int t_load_edits(lua_State* L);           // terrain:load_edits, wrap_edit.cpp

}  // namespace ridgeline::lua::detail
