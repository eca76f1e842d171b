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

/// The C++ memory of the objects a module table made on its scripts' behalf (terrains, their
/// edit layers and detail caches, landscapes, views), against ModuleConfig::object_memory_limit.
/// Lua's allocator never sees these bytes; every object made charges what it holds (or at most
/// can hold) here and gives it back when it is released or collected.
struct ObjectBudget {
  std::size_t limit = 0;  ///< bytes; 0: none
  std::size_t used = 0;   ///< bytes charged by live objects
};

/// One object's share of an ObjectBudget, given back by the destructor. Shared by everything
/// that keeps the object alive (a view keeps its terrain's and landscape's charges).
class Charge {
 public:
  Charge(std::shared_ptr<ObjectBudget> budget, std::size_t bytes) noexcept
      : budget_(std::move(budget)), bytes_(bytes) {
    if (budget_) budget_->used += bytes_;
  }
  ~Charge() {
    if (budget_) budget_->used -= bytes_;
  }
  Charge(const Charge&) = delete;
  Charge& operator=(const Charge&) = delete;
  void set(std::size_t bytes) noexcept {
    if (budget_) budget_->used = budget_->used - bytes_ + bytes;
    bytes_ = bytes;
  }
  std::size_t bytes() const noexcept { return bytes_; }

 private:
  std::shared_ptr<ObjectBudget> budget_;
  std::size_t bytes_ = 0;
};

/// Per-module-table settings and caches: a userdata (with __gc) that module functions reach as
/// upvalue 1, also kept in the registry (object_budget_of).
struct ConfigBox {
  bool confine_paths = false;
  std::uint64_t max_samples = 0;
  std::uint64_t max_samples_limit = 0;  // >= max_samples
  char root[4096] = {};
  std::shared_ptr<ObjectBudget> budget;
  // Built on the first default_terrain() call and never handed out: every call returns a clone,
  // so one script's craters never reach another's terrain.
  std::shared_ptr<const Terrain> default_terrain;
  std::shared_ptr<Charge> default_charge;
};

/// Charge of a paged terrain: its cache budget (or more when pinned, coarse and edited pages pass
/// it) and its change log.
std::size_t paged_terrain_charge_bytes(const Terrain& terrain, std::size_t cache_bytes);

/// A terrain userdata. Released: `terrain` is empty.
struct TerrainBox {
  std::shared_ptr<Terrain> terrain;
  // The path rules of the module that made it (terrain:save_edits / load_edits).
  bool confine_paths = true;
  std::shared_ptr<const std::string> root;
  std::shared_ptr<const Landscape> landscape;  // built on the first new_view
  // The budget new landscapes and views of this terrain are charged to (null: none), and the
  // charges of the terrain itself (terrains made by scripts; an engine's pushed terrain has
  // none) and of its landscape.
  std::shared_ptr<ObjectBudget> budget;
  std::shared_ptr<Charge> terrain_charge, landscape_charge;
  // A paged terrain (ridgeline.open_world): its cache budget, the floor of its charge (edits
  // raise the charge as their pages stay resident).
  std::size_t cache_bytes = 0;
};

/// A view userdata. Released: `view` is empty.
struct ViewBox {
  std::unique_ptr<RoamView> view;
  Camera camera;
  RoamStats last;
  bool has_stats = false;
  // The view's own charge, and those of the terrain and landscape it keeps alive.
  std::shared_ptr<ObjectBudget> budget;
  std::shared_ptr<Charge> charge, terrain_charge, landscape_charge;
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

/// The budget of the module table last opened in this state (null when none or unlimited).
std::shared_ptr<ObjectBudget> object_budget_of(lua_State* L);
/// Whether `bytes` more fit in `budget` (null or no limit: always): when they do not, collects
/// garbage once (dropped objects give their charges back in __gc) and looks again. `own` bytes
/// already charged by the object asking are not counted against it.
bool make_room(lua_State* L, const std::shared_ptr<ObjectBudget>& budget, std::size_t bytes,
               std::size_t own = 0);
/// make_room() or raise "`what`: C++ object memory budget exceeded (N MiB more needed): ..."
/// (object_budget_error). `budget` must not be a local copy (errors may longjmp over it).
void reserve_objects(lua_State* L, const std::shared_ptr<ObjectBudget>& budget, std::size_t bytes,
                     const char* what, std::size_t own = 0);
/// Raises "`what`: C++ object memory budget exceeded (`detail`): ..." with the sizes and how to
/// raise the limit. Never returns (declared int for `return object_budget_error(...)`).
int object_budget_error(lua_State* L, const ObjectBudget& budget, const char* what,
                        const char* detail);
/// Remembers the module table's config userdata at `index` in the registry (object_budget_of).
void register_config(lua_State* L, int index);
/// What a terrain made for a script can hold at most: its pages (samples and ray bounds) and
/// detail field (Terrain::memory_bytes(); not when `shared`: a copy sharing another terrain's
/// pages), a copy of every page an edit may make, a full change log, and `cache_bytes` of detail
/// tiles.
std::size_t terrain_charge_bytes(const Terrain& terrain, std::size_t cache_bytes,
                                 bool shared = false);

/// Method tables, for `open_module`.
int new_view(lua_State* L);               // terrain:new_view, defined in wrap_view.cpp
int new_budget_controller(lua_State* L);  // ridgeline.budget_controller, wrap_budget.cpp
int t_deform(lua_State* L);               // terrain:deform, wrap_edit.cpp
int t_get_heights(lua_State* L);          // terrain:get_heights, wrap_edit.cpp
int t_set_heights(lua_State* L);          // terrain:set_heights, wrap_edit.cpp
int r_save_edits(lua_State* L);           // ridgeline.save_edits, wrap_edit.cpp
int r_load_edits(lua_State* L);           // ridgeline.load_edits, wrap_edit.cpp
int t_save_edits(lua_State* L);           // terrain:save_edits, wrap_edit.cpp
int t_load_edits(lua_State* L);           // terrain:load_edits, wrap_edit.cpp

}  // namespace ridgeline::lua::detail
