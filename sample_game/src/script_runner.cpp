// Running and reloading game scripts: one sandboxed Lua state for all of them, handlers kept per
// script in the registry so that a reload replaces exactly that script's handlers.
#include "script_runner.h"

#include <cstdio>
#include <fstream>
#include <lua.hpp>
#include <sstream>

#include "lua_api.h"
#include "ridgeline/bench/clock.h"

namespace game {

using ridgeline::Error;
using ridgeline::Status;

const char* const kScriptEvents[] = {"tick", "waypoint", "crater", "hit", nullptr};

namespace {

char kHandlersKey;  // registry: {[script index] = {[event] = {fn, ...}}}
char kContextKey;   // registry: the lua_api::Context userdata (owned by the state)

// Runs in protected mode (host().call): builds the registry entries and the `game` table.
int install(lua_State* L) {
  auto* ctx = static_cast<lua_api::Context*>(lua_touserdata(L, 1));
  lua_newtable(L);
  lua_rawsetp(L, LUA_REGISTRYINDEX, &kHandlersKey);
  lua_api::push_game_table(L, ctx);
  return 1;
}

}  // namespace

ridgeline::Result<std::unique_ptr<ScriptRunner>> ScriptRunner::create(
    GameApi& game, const ridgeline::lua::HostOptions& options,
    std::function<void(const std::string&)> console) {
  std::unique_ptr<ScriptRunner> r(new ScriptRunner(game));
  r->console_ = console ? std::move(console) : [](const std::string& line) {
    std::fprintf(stderr, "%s\n", line.c_str());
  };
  auto host = ridgeline::lua::Host::create(options);
  if (!host) return Error{host.error().message};
  r->host_ = std::move(*host);
  lua_State* L = r->host_->state();
  // The context lives in the Lua state (a full userdata without __gc: plain pointers), so the
  // bound functions never outlive it.
  auto* ctx = static_cast<lua_api::Context*>(lua_newuserdatauv(L, sizeof(lua_api::Context), 0));
  *ctx = {&game, r.get()};
  lua_rawsetp(L, LUA_REGISTRYINDEX, &kContextKey);
  lua_pushcfunction(L, install);
  lua_pushlightuserdata(L, ctx);
  if (Status s = r->host_->call(1, 1); !s) return Error{s.message()};
  if (Status s = r->host_->set_global("game"); !s) return Error{s.message()};
  return r;
}

ScriptRunner::~ScriptRunner() = default;

std::string ScriptRunner::current_name() const {
  return current_ >= 0 && current_ < int(scripts_.size()) ? scripts_[current_].name : "game";
}

void ScriptRunner::log(const std::string& line) {
  console_(line);
  log_lines_.push_back(line);
  while (log_lines_.size() > 200) log_lines_.pop_front();
}

void ScriptRunner::record_error(int script, const std::string& message) {
  ScriptError e;
  e.script = script >= 0 && script < int(scripts_.size()) ? scripts_[script].name : "(game)";
  e.message = message;
  e.frame = game_.frame();
  console_("script error in " + e.script + " (frame " + std::to_string(e.frame) + "): " + message);
  errors_.push_back(std::move(e));
  while (errors_.size() > 20) errors_.pop_front();
  ++error_count_;
  if (script >= 0 && script < int(scripts_.size())) scripts_[script].failed = true;
}

std::vector<std::string> ScriptRunner::names() const {
  std::vector<std::string> out;
  for (const Script& s : scripts_) out.push_back(s.name);
  return out;
}

double ScriptRunner::take_script_ms() noexcept {
  const double ms = script_ms_;
  script_ms_ = 0;
  return ms;
}

Status ScriptRunner::load(const std::string& path) {
  for (std::size_t i = 0; i < scripts_.size(); ++i)
    if (scripts_[i].path == path) return run(int(i));
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    const std::string msg =
        "script '" + path +
        "': " + (std::filesystem::exists(path, ec) ? "not a regular file" : "no such file");
    record_error(-1, msg);
    return Error{msg};
  }
  Script s;
  s.path = path;
  s.name = std::filesystem::path(path).filename().string();
  scripts_.push_back(s);
  return run(int(scripts_.size() - 1));
}

int ScriptRunner::reload_changed() {
  int n = 0;
  for (std::size_t i = 0; i < scripts_.size(); ++i) {
    std::error_code ec;
    const auto t = std::filesystem::last_write_time(scripts_[i].path, ec);
    if (!ec && t != scripts_[i].mtime) {
      (void)run(int(i));
      ++n;
    }
  }
  return n;
}

int ScriptRunner::reload_all() {
  for (std::size_t i = 0; i < scripts_.size(); ++i) (void)run(int(i));
  return int(scripts_.size());
}

Status ScriptRunner::run(int index) {
  Script& s = scripts_[index];
  std::error_code ec;
  s.mtime = std::filesystem::last_write_time(s.path, ec);
  std::ifstream in(s.path, std::ios::binary);
  if (!in) {
    const std::string msg = "cannot read script '" + s.path + "'";
    record_error(index, msg);
    return Error{msg};
  }
  std::stringstream ss;
  ss << in.rdbuf();
  lua_State* L = host_->state();
  // Drop the handlers of the previous run of this script.
  lua_rawgetp(L, LUA_REGISTRYINDEX, &kHandlersKey);
  lua_pushnil(L);
  lua_rawseti(L, -2, index + 1);
  lua_pop(L, 1);
  s.failed = false;
  current_ = index;
  const auto t0 = ridgeline::bench::Clock::now();
  Status st = host_->run(ss.str(), "@" + s.name);
  script_ms_ += ridgeline::bench::ms_since(t0);
  current_ = -1;
  if (!st) {
    record_error(index, st.message());
    return st;
  }
  log("loaded " + s.name);
  return {};
}

bool ScriptRunner::add_handler(lua_State* L, int event, int fn) {
  if (current_ < 0) return false;
  fn = lua_absindex(L, fn);
  lua_rawgetp(L, LUA_REGISTRYINDEX, &kHandlersKey);
  if (lua_rawgeti(L, -1, current_ + 1) != LUA_TTABLE) {
    lua_pop(L, 1);
    lua_newtable(L);
    lua_pushvalue(L, -1);
    lua_rawseti(L, -3, current_ + 1);
  }
  if (lua_getfield(L, -1, kScriptEvents[event]) != LUA_TTABLE) {
    lua_pop(L, 1);
    lua_newtable(L);
    lua_pushvalue(L, -1);
    lua_setfield(L, -3, kScriptEvents[event]);
  }
  lua_pushvalue(L, fn);
  lua_rawseti(L, -2, static_cast<lua_Integer>(lua_rawlen(L, -2)) + 1);
  lua_pop(L, 3);
  return true;
}

void ScriptRunner::emit(const char* event, int (*push)(lua_State*, void*), void* user) {
  lua_State* L = host_->state();
  const int top0 = lua_gettop(L);
  const auto t0 = ridgeline::bench::Clock::now();
  for (std::size_t i = 0; i < scripts_.size(); ++i) {
    if (scripts_[i].failed) continue;
    lua_rawgetp(L, LUA_REGISTRYINDEX, &kHandlersKey);
    if (lua_rawgeti(L, -1, static_cast<lua_Integer>(i) + 1) != LUA_TTABLE ||
        lua_getfield(L, -1, event) != LUA_TTABLE) {
      lua_settop(L, top0);
      continue;
    }
    const auto n = static_cast<lua_Integer>(lua_rawlen(L, -1));
    const int list = lua_gettop(L);
    for (lua_Integer k = 1; k <= n && !scripts_[i].failed; ++k) {
      lua_rawgeti(L, list, k);
      const int nargs = push(L, user);
      current_ = static_cast<int>(i);
      const Status st = host_->call(nargs, 0);
      current_ = -1;
      if (!st) record_error(static_cast<int>(i), st.message());
      lua_settop(L, list);
    }
    lua_settop(L, top0);
  }
  script_ms_ += ridgeline::bench::ms_since(t0);
}

}  // namespace game
