// ridgeline.so: `require "ridgeline"` from the stock lua5.4 interpreter. No sandbox here: the
// user owns that interpreter (docs/lua_api.md).
#include <lua.hpp>

#include "ridgeline/lua/module.h"

extern "C" int luaopen_ridgeline(lua_State* L) {
  return ridgeline::lua::open_module(L, ridgeline::lua::ModuleConfig{});
}
