// Internals shared by the files that bind the game to Lua: lua_game.cpp (the `game` table),
// lua_vehicles.cpp (vehicle handles) and lua_bodies.cpp (loose-body handles). Conventions follow
// the ridgeline binding and use its checks (ridgeline/lua/check.h): misuse raises an argument error
// naming the field, an expected miss returns nil, message; option tables refuse unknown fields.
#pragma once

#include <string>

#include "game_api.h"

struct lua_State;

namespace game {

class ScriptRunner;

namespace lua_api {

/// What every bound function reaches through its upvalue 1 (a light userdata).
struct Context {
  GameApi* game = nullptr;
  ScriptRunner* runner = nullptr;
};
Context& context(lua_State* L);

/// Registers the vehicle metatable (once per state); every method gets `ctx` as upvalue 1.
void register_vehicle_type(lua_State* L, Context* ctx);
/// Pushes a handle to vehicle `id`.
void push_vehicle(lua_State* L, int id);
/// The vehicle behind argument `arg`; raises for another type or a removed vehicle.
VehicleEntry& check_vehicle(lua_State* L, int arg);
/// The id of the vehicle handle at stack index `index`, or -1 when it is none.
int test_vehicle(lua_State* L, int index);

/// Registers the loose-body metatable `game.body` (once per state), like the vehicle's.
void register_body_type(lua_State* L, Context* ctx);
/// Pushes a handle to loose body `id`.
void push_body(lua_State* L, int id);
/// game.spawn_body{...}, game.bodies(), game.body(id) (lua_bodies.cpp).
int g_spawn_body(lua_State* L);
int g_bodies(lua_State* L);
int g_body(lua_State* L);

/// Sets field `k` of the table on top of the stack.
void set_number(lua_State* L, const char* k, double v);
void set_bool(lua_State* L, const char* k, bool v);
void set_string(lua_State* L, const char* k, const std::string& v);

/// Pushes the `game` table (vehicle type registered, game.terrain set). May raise (memory).
void push_game_table(lua_State* L, Context* ctx);

}  // namespace lua_api
}  // namespace game
