// ScriptRunner: runs the game's Lua scripts in the binding's sandboxed Host, keeps their event
// handlers, reloads them when their files change and records their errors and log lines
// (docs/game_scripting.md). The `game` table itself is lua_game.cpp.
#pragma once

#include <cstdint>
#include <deque>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "game_api.h"
#include "ridgeline/lua/host.h"
#include "ridgeline/result.h"

struct lua_State;

namespace game {

struct ScriptError {
  std::string script;
  std::string message;  ///< error and traceback
  std::uint64_t frame = 0;
};

/// Events scripts register handlers for with game.on (null-terminated, for luaL_checkoption).
extern const char* const kScriptEvents[];

/// Threading: one thread (the game's). Holds a reference to the game, which must outlive it.
class ScriptRunner {
 public:
  /// Creates the host and installs the `game` table for `game`. `console` receives every line
  /// scripts log (game.log, "loaded NAME") and every error, in every mode (windowed, offscreen,
  /// headless); null: stderr.
  static ridgeline::Result<std::unique_ptr<ScriptRunner>> create(
      GameApi& game, const ridgeline::lua::HostOptions& options,
      std::function<void(const std::string&)> console = {});
  ~ScriptRunner();
  ScriptRunner(const ScriptRunner&) = delete;
  ScriptRunner& operator=(const ScriptRunner&) = delete;

  /// Loads and runs a script file; it stays registered for reload. A script that fails to
  /// compile or run is recorded in errors() and logged (the game goes on); the Status says what
  /// failed. A file that cannot be read is an error too (and is not registered).
  ridgeline::Status load(const std::string& path);
  /// Re-runs every script whose file changed since it was loaded (its event handlers are
  /// replaced). Returns how many were reloaded.
  int reload_changed();
  /// Re-runs every script (the panel's Reload button, F5).
  int reload_all();

  /// Calls the handlers of `event` (one of kScriptEvents) of every script that has not failed;
  /// `push` pushes the arguments and returns their count. A failing handler is recorded and its
  /// script's handlers are switched off until it is reloaded.
  void emit(const char* event, int (*push)(lua_State*, void*), void* user);
  /// Registers the function at stack index `fn` for event number `event` of the running script
  /// (game.on). False when no script is running.
  bool add_handler(lua_State* L, int event, int fn);

  /// The script whose chunk or handler is running, or -1.
  int current() const noexcept { return current_; }
  /// Name of the running script, or "game".
  std::string current_name() const;
  /// A line in the log (the panel's script log, last 200 lines) and on the console.
  void log(const std::string& line);
  void record_error(int script, const std::string& message);

  const std::deque<ScriptError>& errors() const noexcept { return errors_; }
  std::uint64_t error_count() const noexcept { return error_count_; }
  const std::deque<std::string>& log_lines() const noexcept { return log_lines_; }
  std::vector<std::string> names() const;
  std::size_t size() const noexcept { return scripts_.size(); }
  ridgeline::lua::Host& host() noexcept { return *host_; }
  /// Milliseconds spent in script chunks and handlers since the last call (the frame's scripts
  /// time; game.burn_ms load included).
  double take_script_ms() noexcept;

 private:
  struct Script {
    std::string name, path;
    std::filesystem::file_time_type mtime{};
    bool failed = false;  ///< its handlers are off until it is reloaded
  };
  ScriptRunner(GameApi& game) : game_(game) {}
  ridgeline::Status run(int index);

  GameApi& game_;
  std::function<void(const std::string&)> console_;
  std::unique_ptr<ridgeline::lua::Host> host_;
  std::vector<Script> scripts_;
  int current_ = -1;
  std::deque<ScriptError> errors_;
  std::uint64_t error_count_ = 0;
  std::deque<std::string> log_lines_;
  double script_ms_ = 0;
};

}  // namespace game
