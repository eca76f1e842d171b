// Host: a sandboxed Lua 5.4 state for game scripts, after lua.c (message handler, protected
// calls) with an instruction budget (count hook) and a memory cap (counting allocator).
#include "ridgeline/lua/host.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <lua.hpp>
#include <sstream>

#include "lua_util.h"
#include "sandbox_guards.h"
#include "ridgeline/lua/module.h"

namespace ridgeline::lua {

struct Host::Limits {
  std::uint64_t instruction_limit = 0;
  std::uint64_t instructions = 0;  // counted in the current call
  std::size_t memory_limit = 0;    // 0: none
  std::size_t hard_limit = 0;      // refused above this (memory_limit + headroom)
  std::size_t used = 0;            // bytes held by the owned state
  bool active = false;             // limits apply (off while the host sets the state up)
  std::uint64_t failed_request = 0;
  double time_limit = 0;                          // seconds per call; 0: none
  std::chrono::steady_clock::time_point started;  // of the current call
  lua_State* main = nullptr;  // the thread the host calls on
};

namespace {

constexpr int kHookStep = 1000;
char kLimitsKey;    // registry key (light userdata address) of the Limits
char kSandboxKey;   // registry key of the sandbox environment table
char kTemplateKey;  // registry key of the sandbox's pristine globals (Host::reset)

void* limited_alloc(void* ud, void* ptr, std::size_t osize, std::size_t nsize) {
  auto* lim = static_cast<Host::Limits*>(ud);
  const std::size_t old = ptr != nullptr ? osize : 0;
  if (nsize == 0) {
    std::free(ptr);
    lim->used -= old;
    return nullptr;
  }
  if (lim->active && lim->memory_limit != 0 && nsize > old &&
      lim->used - old + nsize > lim->hard_limit) {
    lim->failed_request = nsize;
    return nullptr;  // Lua raises "not enough memory" (after an emergency collection)
  }
  void* p = std::realloc(ptr, nsize);
  if (p != nullptr) {
    lim->used = lim->used - old + nsize;
    // C functions that build big strings or tables (string.rep, table.concat, gsub) do work the
    // hook does not count: every 64 bytes allocated cost one instruction.
    if (lim->active && nsize > old) lim->instructions += (nsize - old) / 64;
  }
  return p;
}

Host::Limits* limits_of(lua_State* L) {
  lua_rawgetp(L, LUA_REGISTRYINDEX, &kLimitsKey);
  auto* lim = static_cast<Host::Limits*>(lua_touserdata(L, -1));
  lua_pop(L, 1);
  return lim;
}

bool over_limits(const Host::Limits& lim) {
  return (lim.instruction_limit != 0 && lim.instructions > lim.instruction_limit) ||
         (lim.memory_limit != 0 && lim.used > lim.memory_limit) ||
         (lim.time_limit > 0 &&
          std::chrono::duration<double>(std::chrono::steady_clock::now() - lim.started).count() >
              lim.time_limit);
}

// Once a limit is exceeded the hook fires on every instruction of the running thread and of the
// host's main thread, so that a script cannot keep going by catching the error with pcall (at a
// 1000-instruction period the check would keep landing inside the pcall'ed loop).
void count_hook(lua_State* L, lua_Debug*) {
  Host::Limits* lim = limits_of(L);
  if (lim == nullptr || !lim->active) return;
  const int step = lua_gethookcount(L);
  lim->instructions += static_cast<std::uint64_t>(step);
  const bool over_instructions =
      lim->instruction_limit != 0 && lim->instructions > lim->instruction_limit;
  const bool over_memory = lim->memory_limit != 0 && lim->used > lim->memory_limit;
  // Wall clock, for single instructions whose C work is proportional to a string's length
  // (comparing two long equal strings is one instruction and one memcmp).
  const bool over_time =
      lim->time_limit > 0 &&
      std::chrono::duration<double>(std::chrono::steady_clock::now() - lim->started).count() >
          lim->time_limit;
  if (!over_instructions && !over_memory && !over_time) {
    if (step != kHookStep) lua_sethook(L, count_hook, LUA_MASKCOUNT, kHookStep);
    return;
  }
  lua_sethook(L, count_hook, LUA_MASKCOUNT, 1);
  if (lim->main != nullptr && lim->main != L) lua_sethook(lim->main, count_hook, LUA_MASKCOUNT, 1);
  if (over_instructions)
    luaL_error(L, "instruction limit exceeded (%I instructions per call)",
               static_cast<lua_Integer>(lim->instruction_limit));
  if (over_time) luaL_error(L, "time limit exceeded (%f s per call)", lim->time_limit);
  luaL_error(L, "memory limit exceeded (%I bytes in use, limit %I)",
             static_cast<lua_Integer>(lim->used), static_cast<lua_Integer>(lim->memory_limit));
}

// Adds a traceback to the error (lua.c's msghandler, without its __tostring call: when the error
// was raised by the count hook, Lua runs the handler with hooks off, so a script's __tostring
// would run unbounded).
int message_handler(lua_State* L) {
  const char* msg = lua_type(L, 1) == LUA_TSTRING || lua_type(L, 1) == LUA_TNUMBER
                        ? lua_tostring(L, 1)
                        : nullptr;
  if (msg == nullptr)
    msg = lua_pushfstring(L, "(error object is a %s value)", luaL_typename(L, 1));
  luaL_traceback(L, L, msg, 1);
  return 1;
}

// The message handler a script gives xpcall, wrapped: when the error comes from the count hook
// (a limit), Lua calls the handler with hooks still off, and a looping handler would never end.
// Past a limit the error goes on unhandled; otherwise the script's handler runs as usual.
int guarded_handler(lua_State* L) {
  const Host::Limits* lim = limits_of(L);
  if (lim != nullptr && lim->active && over_limits(*lim)) return 1;
  lua_pushvalue(L, lua_upvalueindex(1));
  lua_insert(L, 1);
  lua_call(L, lua_gettop(L) - 1, 1);
  return 1;
}

// xpcall(f, msgh, ...) with msgh wrapped as above.
int safe_xpcall(lua_State* L) {
  luaL_checktype(L, 2, LUA_TFUNCTION);
  lua_pushvalue(L, 2);
  lua_pushcclosure(L, guarded_handler, 1);
  lua_replace(L, 2);
  lua_pushvalue(L, lua_upvalueindex(1));
  lua_insert(L, 1);
  lua_call(L, lua_gettop(L) - 1, LUA_MULTRET);
  return lua_gettop(L);
}

// A reader function given to load, wrapped so that the bytes it returns are charged: the parser
// runs in C, and a reader that keeps returning one long comment would parse forever.
int charged_reader(lua_State* L) {
  lua_pushvalue(L, lua_upvalueindex(1));
  lua_call(L, 0, 1);
  std::size_t len = 0;
  if (lua_type(L, -1) == LUA_TSTRING) lua_tolstring(L, -1, &len);
  detail::charge_work(L, static_cast<double>(len), "load");
  return 1;
}

// load(chunk [, name [, mode [, env]]]): text chunks only; the default environment is the
// sandbox, never the state's real globals. The chunk's bytes are charged to the budget (parsing
// is C work the hook does not see).
int safe_load(lua_State* L) {
  lua_settop(L, 4);
  if (lua_type(L, 1) == LUA_TSTRING) {
    detail::charge_work(L, static_cast<double>(lua_rawlen(L, 1)), "load");
  } else if (lua_type(L, 1) == LUA_TFUNCTION) {
    lua_pushvalue(L, 1);
    lua_pushcclosure(L, charged_reader, 1);
    lua_replace(L, 1);
  }
  lua_pushvalue(L, lua_upvalueindex(1));  // the original load
  lua_pushvalue(L, 1);
  lua_pushvalue(L, 2);
  lua_pushliteral(L, "t");
  if (lua_isnil(L, 4))
    lua_rawgetp(L, LUA_REGISTRYINDEX, &kSandboxKey);
  else
    lua_pushvalue(L, 4);
  lua_call(L, 4, LUA_MULTRET);
  return lua_gettop(L) - 4;
}

// setmetatable refusing __gc: finalizers run with hooks disabled, so a looping __gc would escape
// the instruction budget.
int safe_setmetatable(lua_State* L) {
  if (lua_type(L, 2) == LUA_TTABLE && lua_getfield(L, 2, "__gc") != LUA_TNIL)
    luaL_argerror(L, 2, "__gc metamethods are not allowed in the sandbox");
  lua_settop(L, 2);
  lua_pushvalue(L, lua_upvalueindex(1));
  lua_insert(L, 1);
  lua_call(L, 2, 1);
  return 1;
}

// collectgarbage limited to options that cannot switch the collector off or retune it. A collection
// walks the whole heap in C: "collect" and "step" are charged one instruction per 16 bytes in use.
int safe_collectgarbage(lua_State* L) {
  static const char* const kAllowed[] = {"collect", "count", "step", "isrunning", nullptr};
  const int opt = luaL_checkoption(L, 1, "collect", kAllowed);
  if (opt == 0 || opt == 2) {
    const Host::Limits* lim = limits_of(L);
    const double used = lim != nullptr ? static_cast<double>(lim->used) : 0;
    detail::charge_work(L, used / 16, "collectgarbage");
  }
  lua_pushvalue(L, lua_upvalueindex(1));
  lua_insert(L, 1);
  lua_call(L, lua_gettop(L) - 1, LUA_MULTRET);
  return lua_gettop(L);
}

struct SetupArgs {
  const HostOptions* options;
};

// Copies the globals in table `from` into table `to` (stack indices), every table value copied
// one level deep (the libraries' functions and the module's are shared), `_G` left out.
void copy_globals(lua_State* L, int from, int to) {
  lua_pushnil(L);
  while (lua_next(L, from) != 0) {  // key -2, value -1
    if (lua_type(L, -2) == LUA_TSTRING && std::strcmp(lua_tostring(L, -2), "_G") == 0) {
      lua_pop(L, 1);
      continue;
    }
    if (lua_type(L, -1) == LUA_TTABLE) {
      lua_newtable(L);
      lua_pushnil(L);
      while (lua_next(L, -3) != 0) {
        lua_pushvalue(L, -2);
        lua_insert(L, -2);
        lua_rawset(L, -4);
      }
      lua_replace(L, -2);
    }
    lua_pushvalue(L, -2);
    lua_insert(L, -2);
    lua_rawset(L, to);
  }
}

// Opens the libraries and builds the sandbox environment; runs under lua_pcall.
int setup_state(lua_State* L) {
  const auto* args = static_cast<const SetupArgs*>(lua_touserdata(L, 1));
  const HostOptions& o = *args->options;
  if (!o.sandbox) {
    luaL_openlibs(L);
    ModuleConfig config;
    config.max_samples = o.max_samples;
    config.max_samples_limit = o.max_samples_limit;
    config.object_memory_limit = o.object_memory_limit;
    open_module(L, config);
    lua_setglobal(L, "ridgeline");
    lua_pushglobaltable(L);
    lua_rawsetp(L, LUA_REGISTRYINDEX, &kSandboxKey);
    return 0;
  }
  static const luaL_Reg kLibs[] = {{LUA_GNAME, luaopen_base},
                                   {LUA_STRLIBNAME, luaopen_string},
                                   {LUA_TABLIBNAME, luaopen_table},
                                   {LUA_MATHLIBNAME, luaopen_math},
                                   {LUA_UTF8LIBNAME, luaopen_utf8},
                                   {LUA_COLIBNAME, luaopen_coroutine},
                                   {nullptr, nullptr}};
  lua_newtable(L);  // the sandbox environment
  const int env = lua_gettop(L);
  for (const luaL_Reg* lib = kLibs; lib->func != nullptr; ++lib) {
    luaL_requiref(L, lib->name, lib->func, 0);
    // Guards in the library tables themselves (the string metatable indexes the original).
    if (lib->func == luaopen_string) detail::install_string_guards(L, lua_absindex(L, -1));
    if (lib->func == luaopen_table) detail::install_table_guards(L, lua_absindex(L, -1));
    if (lib->func == luaopen_coroutine) detail::install_coroutine_guards(L, lua_absindex(L, -1));
    if (lib->func == luaopen_utf8) detail::install_utf8_guards(L, lua_absindex(L, -1));
    if (lib == kLibs) {  // base: copy the allowed functions only
      static const char* const kBase[] = {
          "assert",   "error",  "ipairs",       "next",     "pairs",  "pcall",    "print",
          "rawequal", "rawget", "rawlen",       "rawset",   "select", "tonumber", "tostring",
          "type",     "getmetatable", "_VERSION", nullptr};
      for (const char* const* n = kBase; *n != nullptr; ++n) {
        lua_getfield(L, -1, *n);
        lua_setfield(L, env, *n);
      }
      // Guarded versions, each closing over the original.
      static const luaL_Reg kGuarded[] = {{"load", safe_load},
                                          {"setmetatable", safe_setmetatable},
                                          {"xpcall", safe_xpcall},
                                          {"collectgarbage", safe_collectgarbage},
                                          {nullptr, nullptr}};
      for (const luaL_Reg* g = kGuarded; g->name != nullptr; ++g) {
        lua_getfield(L, -1, g->name);
        lua_pushcclosure(L, g->func, 1);
        lua_setfield(L, env, g->name);
      }
    } else {
      // A copy: scripts that change `string.rep` change their copy, not the string methods.
      lua_newtable(L);
      lua_pushnil(L);
      while (lua_next(L, -3) != 0) {
        lua_pushvalue(L, -2);
        lua_insert(L, -2);
        lua_settable(L, -4);
      }
      lua_setfield(L, env, lib->name);
    }
    lua_pop(L, 1);
  }
  lua_pushvalue(L, env);
  lua_setfield(L, env, "_G");
  // Protect the string metatable: getmetatable("") returns this string instead.
  lua_pushliteral(L, "");
  if (lua_getmetatable(L, -1)) {
    lua_pushliteral(L, "string");
    lua_setfield(L, -2, "__metatable");
    lua_pop(L, 1);
  }
  lua_pop(L, 1);
  ModuleConfig config;
  config.confine_paths = true;
  config.root = o.data_root.c_str();
  config.max_samples = o.max_samples;
  config.max_samples_limit = o.max_samples_limit;
  config.object_memory_limit = o.object_memory_limit;
  open_module(L, config);
  lua_setfield(L, env, "ridgeline");
  lua_pushvalue(L, env);
  lua_rawsetp(L, LUA_REGISTRYINDEX, &kSandboxKey);
  // The pristine globals, for Host::reset: every table (the library copies, `ridgeline`) copied
  // once more, so that a script's changes to its copies never reach the template.
  lua_newtable(L);
  copy_globals(L, env, lua_gettop(L));
  lua_rawsetp(L, LUA_REGISTRYINDEX, &kTemplateKey);
  return 0;
}

// A fresh sandbox environment from the template (runs under lua_pcall).
int reset_state(lua_State* L) {
  lua_rawgetp(L, LUA_REGISTRYINDEX, &kTemplateKey);
  const int from = lua_gettop(L);
  lua_newtable(L);
  const int env = lua_gettop(L);
  copy_globals(L, from, env);
  lua_pushvalue(L, env);
  lua_setfield(L, env, "_G");
  lua_pushvalue(L, env);
  lua_rawsetp(L, LUA_REGISTRYINDEX, &kSandboxKey);
  return 0;
}

// Looks the global up inside the protected call (the lookup may allocate) and calls it.
int call_global_protected(lua_State* L) {
  const char* name = static_cast<const char*>(lua_touserdata(L, 1));
  lua_rawgetp(L, LUA_REGISTRYINDEX, &kSandboxKey);
  lua_pushstring(L, name);
  if (lua_rawget(L, -2) != LUA_TFUNCTION)
    return luaL_error(L, "global '%s' is not a function", name);
  lua_call(L, 0, 0);
  return 0;
}

std::string top_message(lua_State* L, int rc, const Host::Limits& lim) {
  const char* m = lua_tostring(L, -1);
  std::string msg = m != nullptr ? m : "(error object is not a string)";
  if (rc == LUA_ERRMEM && lim.memory_limit != 0) {
    char extra[200];
    std::snprintf(extra, sizeof extra,
                  " (memory limit exceeded: a request of %llu bytes refused with %llu bytes in "
                  "use, limit %llu; Lua runs no message handler for memory errors, so there is "
                  "no traceback)",
                  static_cast<unsigned long long>(lim.failed_request),
                  static_cast<unsigned long long>(lim.used),
                  static_cast<unsigned long long>(lim.memory_limit));
    msg += extra;
  }
  return msg;
}

}  // namespace

namespace detail {

double work_limit(lua_State* L) {
  const Host::Limits* lim = limits_of(L);
  return lim != nullptr && lim->active ? static_cast<double>(lim->instruction_limit) : 0;
}

void charge_work(lua_State* L, double steps, const char* what) {
  Host::Limits* lim = limits_of(L);
  if (lim == nullptr || !lim->active || lim->instruction_limit == 0 || !(steps > 0)) return;
  const double limit = static_cast<double>(lim->instruction_limit);
  const double after = static_cast<double>(lim->instructions) + std::ceil(steps);
  lim->instructions = after >= limit ? lim->instruction_limit + 1
                                     : static_cast<std::uint64_t>(after);
  if (lim->instructions <= lim->instruction_limit) return;
  // Over: as count_hook does, every later instruction raises again.
  lua_sethook(L, count_hook, LUA_MASKCOUNT, 1);
  if (lim->main != nullptr && lim->main != L) lua_sethook(lim->main, count_hook, LUA_MASKCOUNT, 1);
  luaL_error(L, "instruction limit exceeded (%I instructions per call; %s)",
             static_cast<lua_Integer>(lim->instruction_limit), what);
}

}  // namespace detail

Result<std::unique_ptr<Host>> Host::create(const HostOptions& options) {
  std::unique_ptr<Host> host(new Host());
  host->limits_ = std::make_unique<Limits>();
  host->L_ = lua_newstate(limited_alloc, host->limits_.get());
  if (host->L_ == nullptr) return Error{"lua: cannot create a state"};
  host->owned_ = true;
  Status s = host->setup(options);
  if (!s) return Error{s.message()};
  return host;
}

Result<std::unique_ptr<Host>> Host::attach(lua_State* L, const HostOptions& options) {
  if (L == nullptr) return Error{"lua: null state"};
  std::unique_ptr<Host> host(new Host());
  host->limits_ = std::make_unique<Limits>();
  host->L_ = L;
  Status s = host->setup(options);
  if (!s) return Error{s.message()};
  return host;
}

Status Host::setup(const HostOptions& options) {
  if (options.data_root.size() >= sizeof(detail::ConfigBox::root))
    return Error{"lua host: data_root is too long"};
  Limits& lim = *limits_;
  lim.instruction_limit = options.instruction_limit;
  lim.time_limit = options.time_limit_seconds > 0 ? options.time_limit_seconds : 0;
  lim.memory_limit = owned_ ? options.memory_limit : 0;
  lim.hard_limit =
      lim.memory_limit + std::max<std::size_t>(std::size_t{1} << 20, lim.memory_limit / 8);
  lua_State* L = L_;
  lim.main = L;
  lua_pushlightuserdata(L, &lim);  // no allocation: safe outside a protected call
  lua_rawsetp(L, LUA_REGISTRYINDEX, &kLimitsKey);
  SetupArgs args{&options};
  lua_pushcfunction(L, setup_state);
  lua_pushlightuserdata(L, &args);
  if (lua_pcall(L, 1, 0, 0) != LUA_OK) {
    std::string msg = std::string("lua host setup: ") + lua_tostring(L, -1);
    lua_pop(L, 1);
    return Error{msg};
  }
  lua_sethook(L, count_hook, LUA_MASKCOUNT, kHookStep);
  lim.active = true;
  sandbox_ = options.sandbox;
  return {};
}

Host::~Host() {
  if (L_ == nullptr) return;
  if (owned_) {
    limits_->active = false;
    lua_close(L_);
  } else {
    lua_sethook(L_, nullptr, 0, 0);
    lua_pushnil(L_);
    lua_rawsetp(L_, LUA_REGISTRYINDEX, &kLimitsKey);
  }
}

Status Host::reset() {
  if (!sandbox_) return Error{"lua host: reset needs a sandboxed host"};
  lua_State* L = L_;
  if (!lua_checkstack(L, 8)) return Error{"lua host: stack overflow"};
  limits_->active = false;  // the host's own work: not charged to the next call
  lua_pushcfunction(L, reset_state);
  const int rc = lua_pcall(L, 0, 0, 0);
  std::string msg;
  if (rc != LUA_OK) {
    msg = lua_tostring(L, -1) != nullptr ? lua_tostring(L, -1) : "error";
    lua_pop(L, 1);
  } else {
    // Whatever only the old globals held (terrains, views, coroutines) goes now, and with it
    // their share of the object budget.
    lua_gc(L, LUA_GCCOLLECT, 0);
  }
  limits_->active = true;
  if (rc != LUA_OK) return Error{"lua host: reset: " + msg};
  return {};
}

Status Host::call(int nargs, int nresults) {
  lua_State* L = L_;
  const int base = lua_gettop(L) - nargs;
  if (base < 1) return Error{"lua host: call without a function"};
  if (!lua_checkstack(L, 2)) return Error{"lua host: stack overflow"};
  lua_pushcfunction(L, message_handler);
  lua_insert(L, base);
  limits_->instructions = 0;
  limits_->started = std::chrono::steady_clock::now();
  lua_sethook(L, count_hook, LUA_MASKCOUNT, kHookStep);
  const int rc = lua_pcall(L, nargs, nresults, base);
  lua_remove(L, base);
  if (rc == LUA_OK) return {};
  std::string msg = top_message(L, rc, *limits_);
  lua_pop(L, 1);
  // Give the next call a clean start when this one ran into the memory cap.
  if (limits_->memory_limit != 0 && limits_->used > limits_->memory_limit / 2) {
    limits_->active = false;
    lua_gc(L, LUA_GCCOLLECT, 0);
    limits_->active = true;
  }
  return Error{msg};
}

Status Host::run(std::string_view source, std::string_view name) {
  lua_State* L = L_;
  char chunkname[256];
  std::snprintf(chunkname, sizeof chunkname, "=%.*s",
                static_cast<int>(std::min<std::size_t>(name.size(), 200)), name.data());
  limits_->instructions = 0;
  if (!lua_checkstack(L, 4)) return Error{"lua host: stack overflow"};
  const int rc = luaL_loadbufferx(L, source.data(), source.size(), chunkname, "t");
  if (rc != LUA_OK) {
    std::string msg = top_message(L, rc, *limits_);
    lua_pop(L, 1);
    return Error{msg};
  }
  lua_rawgetp(L, LUA_REGISTRYINDEX, &kSandboxKey);
  lua_setupvalue(L, -2, 1);  // _ENV of the main chunk
  return call(0, 0);
}

Status Host::run_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{"cannot open script '" + path + "'"};
  std::ostringstream text;
  text << in.rdbuf();
  return run(text.str(), path);
}

Status Host::call_global(const char* name) {
  lua_State* L = L_;
  if (!lua_checkstack(L, 4)) return Error{"lua host: stack overflow"};
  lua_pushcfunction(L, call_global_protected);
  lua_pushlightuserdata(L, const_cast<char*>(name));
  return call(1, 0);
}

Status Host::set_global(const char* name) {
  lua_State* L = L_;
  if (lua_gettop(L) < 1) return Error{"lua host: set_global: no value on the stack"};
  if (!lua_checkstack(L, 4)) return Error{"lua host: stack overflow"};
  // rawset on a table with a string key cannot raise except for memory: do it protected.
  lua_pushcfunction(L, [](lua_State* S) -> int {
    lua_rawgetp(S, LUA_REGISTRYINDEX, &kSandboxKey);
    lua_pushvalue(S, 1);
    lua_pushvalue(S, 2);
    lua_rawset(S, -3);
    return 0;
  });
  lua_pushstring(L, name);
  lua_pushvalue(L, -3);
  const int rc = lua_pcall(L, 2, 0, 0);
  if (rc != LUA_OK) {
    std::string msg = lua_tostring(L, -1) != nullptr ? lua_tostring(L, -1) : "error";
    lua_pop(L, 2);
    return Error{"lua host: set_global '" + std::string(name) + "': " + msg};
  }
  lua_pop(L, 1);
  return {};
}

std::size_t Host::memory_used() const noexcept {
  return owned_ ? limits_->used : 0;
}
std::size_t Host::object_memory_used() const noexcept {
  return ridgeline::lua::object_memory_used(L_);
}
std::uint64_t Host::last_instructions() const noexcept {
  return limits_->instructions;
}

}  // namespace ridgeline::lua
