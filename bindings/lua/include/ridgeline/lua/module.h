// The `ridgeline` Lua module: what `require "ridgeline"` returns, and the limits it enforces.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

struct lua_State;

namespace ridgeline {
class Terrain;
}

namespace ridgeline::lua {

/// Points one call of terrain:heights() accepts (the hook never fires inside a C function, so
/// every bound call that can do unbounded work has its own cap).
inline constexpr std::size_t kMaxBatchPoints = 65536;
/// Wheel offsets one call of terrain:contacts() accepts.
inline constexpr std::size_t kMaxContacts = 64;
/// Upper bound on the leaf triangles of one view (view:set_budget{triangles=} is clamped to it,
/// and 0 means this cap).
inline constexpr std::uint32_t kMaxViewTriangles = 4'000'000;
/// Default triangle budget of a new view.
inline constexpr std::uint32_t kDefaultViewTriangles = 500'000;

/// How the module treats file names and sizes. Plain data; copied into the Lua state when the
/// module is opened, so it may be destroyed afterwards.
struct ModuleConfig {
  /// When true, file names given by scripts must be relative, free of `..` and absolute parts,
  /// and resolve inside `root` (symbolic links included). When false (the stock interpreter),
  /// any path the process can read is accepted.
  bool confine_paths = false;
  /// Folder granted to scripts (used only with confine_paths; empty: no file access at all).
  const char* root = "";
  /// Largest heightmap ridgeline.load accepts, in samples (checked before allocating); default
  /// 8193 x 8193.
  std::uint64_t max_samples = std::uint64_t{8193} * 8193;
  /// How far a script may raise that cap for one load (`ridgeline.load{max_samples = N}`); below
  /// max_samples it is max_samples. Default: no limit (the stock interpreter's user owns it).
  std::uint64_t max_samples_limit = ~std::uint64_t{0};
  /// Bytes of C++ memory the objects scripts make through this module table may hold together
  /// (terrains with their edit layers, change logs and detail caches, landscapes, views; 0 = no
  /// limit, the stock interpreter's default). Lua's allocator does not see this memory. A call
  /// that would go past it raises "C++ object memory budget exceeded"; a view's update is held
  /// to the triangles that fit. Objects give their share back when released or collected.
  std::size_t object_memory_limit = 0;
};

/// Pushes a new `ridgeline` module table on the stack of `L` (the bound types' metatables are
/// registered on first use). May raise a Lua error (memory); call it from a protected context
/// or from luaopen_*. Returns 1.
int open_module(lua_State* L, const ModuleConfig& config);

/// Pushes a `ridgeline.terrain` userdata that shares `terrain` with the engine (the engine's own
/// terrain, so that scripts query what the game simulates). May raise a Lua error (memory). The
/// terrain itself is not charged to the object budget (the engine made it); landscapes and views
/// scripts build on it are.
void push_terrain(lua_State* L, std::shared_ptr<Terrain> terrain);

/// Bytes charged to the object budget of the module table last opened in `L` (0 when none).
std::size_t object_memory_used(lua_State* L);

}  // namespace ridgeline::lua

extern "C" {
/// Entry point of ridgeline.so for `require "ridgeline"`: unconfined paths, default caps.
int luaopen_ridgeline(lua_State* L);
}
