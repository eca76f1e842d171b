// Host: runs game scripts in a (by default sandboxed) Lua 5.4 state with the ridgeline module.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "ridgeline/result.h"

struct lua_State;

namespace ridgeline::lua {

/// What a Host allows its scripts. Defaults are the game-script sandbox.
struct HostOptions {
  /// Sandbox (default): the globals hold only base (without dofile, loadfile, and load refuses
  /// binary chunks), string (without dump), table, math, utf8, coroutine and `ridgeline`; no io,
  /// os, package, debug, require. The string metatable is protected. When false, every standard
  /// library is opened (trusted tools).
  bool sandbox = true;
  /// Lua VM instructions one host call (run, call) may execute, counted by a hook every 1000
  /// instructions; 0 = no limit. Exceeding it ends the call with an error and a traceback.
  /// In the sandbox, C work the hook cannot see is charged too: allocations (one instruction per
  /// 64 bytes), pattern matching, table.move/sort, load and collectgarbage (docs/lua_api.md).
  std::uint64_t instruction_limit = 100'000'000;
  /// Wall-clock seconds one host call may take, checked by the same hook (so a single C call
  /// is not interrupted; the sandbox bounds those, see docs/lua_api.md); 0 = no limit. A backstop
  /// for instructions whose cost grows with their operands (comparing two long equal strings).
  double time_limit_seconds = 10;
  /// Bytes the Lua state may hold (owned states only; 0 = no limit). Above it the next hook
  /// check ends the call with an error and a traceback; a single allocation that would pass the
  /// limit plus a headroom of max(1 MiB, limit / 8) is refused (Lua's "not enough memory").
  /// C++ objects made for scripts are not counted here: see object_memory_limit.
  std::size_t memory_limit = std::size_t{64} << 20;
  /// Bytes of C++ memory that the terrains, landscapes and views scripts make may hold together
  /// (each terrain counted with the most its edit layer, change log and detail cache can grow
  /// to; each view with what its last update holds); 0 = no limit. It applies to owned and
  /// attached states, sandboxed or not; an engine's own terrains handed in with push_terrain()
  /// are not counted. A call that would pass it raises "C++ object memory budget exceeded"
  /// naming the sizes (after one garbage collection to reclaim dropped objects), and a view's
  /// update is held to the triangles that fit (the call then raises the same error). Objects
  /// give their share back when released (`release()`, `<close>`) or collected. The default
  /// holds about 24 copies of the default terrain, or one 2048 x 2048 terrain with a view.
  std::size_t object_memory_limit = std::size_t{256} << 20;
  /// Folder sandboxed scripts may read from (ridgeline.load); empty: no file access. Paths given
  /// by scripts are relative to it, without `..`, never absolute. Unused without the sandbox.
  std::string data_root;
  /// Largest heightmap a script may load, samples (default 4097 x 4097). Larger maps are baked
  /// (`ridge bake`) and opened paged with ridgeline.open_world, whose memory is the cache budget.
  std::uint64_t max_samples = std::uint64_t{4097} * 4097;
  /// How far a script may raise that cap for one load (`ridgeline.load{max_samples = N}`);
  /// below max_samples it is max_samples (the default: scripts cannot raise it).
  std::uint64_t max_samples_limit = 0;
};

/// Owns or borrows a lua_State and runs chunks and callbacks under a traceback message handler.
/// A failing script returns a Status whose message holds the error and the traceback; the host
/// and its state stay usable.
///
/// Threading: a Host and its lua_State are used by one thread at a time.
class Host {
 public:
  /// Creates a new state (with the counting allocator) and opens the libraries per `options`.
  static Result<std::unique_ptr<Host>> create(const HostOptions& options = {});
  /// Uses an engine's state: installs the hook and, with options.sandbox, replaces the globals of
  /// `L` with the sandbox. The memory limit does not apply (the engine owns the allocator).
  /// `L` must outlive the Host; the Host does not close it.
  static Result<std::unique_ptr<Host>> attach(lua_State* L, const HostOptions& options = {});
  ~Host();
  Host(const Host&) = delete;
  Host& operator=(const Host&) = delete;

  lua_State* state() const noexcept { return L_; }

  /// Compiles `source` (text only) as chunk `name` and runs it. Errors carry a traceback.
  Status run(std::string_view source, std::string_view name);
  /// Reads a file with the host's own (unconfined) file access and runs it as text.
  Status run_file(const std::string& path);
  /// Calls the function below `nargs` arguments on top of the stack (like lua_pcall) under the
  /// message handler and the limits, leaving `nresults` results (LUA_MULTRET allowed) on
  /// success and nothing on failure.
  Status call(int nargs, int nresults);
  /// Calls global function `name` with no arguments and no results (a game callback).
  Status call_global(const char* name);

  /// Sandboxed hosts: gives scripts a fresh global environment, as at creation: the library
  /// tables and the `ridgeline` table copied again from pristine copies (a script's changes to
  /// them are gone), every global a script or set_global() made gone, then a full garbage
  /// collection (objects only the old globals held are freed and give back their share of the
  /// object budget). What stays: the state, its limits, the module's cached default terrain, and
  /// anything the engine keeps referenced. For reloading a game's scripts, and for the fuzz
  /// target that reuses one host across inputs. Fails without the sandbox.
  Status reset();

  /// Pops the value on top of the stack and stores it as global `name` of the scripts'
  /// environment (the sandbox table, or the real globals without the sandbox): how an engine
  /// hands its own API (a `game` table) to its scripts. Fails only for memory or an empty stack.
  Status set_global(const char* name);

  /// Bytes held by an owned state (0 for an attached one).
  std::size_t memory_used() const noexcept;
  /// Bytes charged to the object budget by the terrains, landscapes and views scripts hold.
  std::size_t object_memory_used() const noexcept;
  /// Instructions counted during the last call (in steps of 1000).
  std::uint64_t last_instructions() const noexcept;

  struct Limits;  // hook and allocator state (host.cpp)

 private:
  Host() = default;
  Status setup(const HostOptions& options);
  lua_State* L_ = nullptr;
  bool owned_ = false;
  bool sandbox_ = false;
  std::unique_ptr<Limits> limits_;
};

}  // namespace ridgeline::lua
