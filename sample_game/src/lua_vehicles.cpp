// Vehicle handles for game scripts (`game.vehicle` userdata): a handle holds an id, so a removed
// vehicle is detected instead of dangling. docs/game_scripting.md, "Vehicles".
#include <cmath>
#include <lua.hpp>
#include <vector>

#include "lua_api.h"
#include "ridgeline/lua/check.h"

namespace game::lua_api {
namespace {

using ridgeline::lua::check_fields;
using ridgeline::lua::check_finite;
using ridgeline::lua::get_bool_field;
using ridgeline::lua::get_number_field;
using ridgeline::lua::opt_finite;

constexpr char kVehicleMeta[] = "game.vehicle";

struct VehicleHandle {
  int id;
};

GameApi& game_of(lua_State* L) {
  return *context(L).game;
}

VehicleHandle* check_handle(lua_State* L, int arg) {
  return static_cast<VehicleHandle*>(luaL_checkudata(L, arg, kVehicleMeta));
}

int v_set_controls(lua_State* L) {
  VehicleEntry& e = check_vehicle(L, 1);
  luaL_checktype(L, 2, LUA_TTABLE);
  static const char* const kFields[] = {"throttle", "steer", "brake", nullptr};
  check_fields(L, 2, kFields);
  Controls c = e.body.controls;
  if (get_number_field(L, 2, "throttle", &c.throttle) && std::abs(c.throttle) > 1)
    luaL_argerror(L, 2, "field 'throttle': -1 .. 1 expected");
  if (get_number_field(L, 2, "steer", &c.steer) && std::abs(c.steer) > 1)
    luaL_argerror(L, 2, "field 'steer': -1 .. 1 expected");
  if (get_number_field(L, 2, "brake", &c.brake) && (c.brake < 0 || c.brake > 1))
    luaL_argerror(L, 2, "field 'brake': 0 .. 1 expected");
  e.body.controls = c;
  e.autopilot.active = false;  // manual control takes over
  return 0;
}

int v_controls(lua_State* L) {
  const Controls& c = check_vehicle(L, 1).body.controls;
  lua_createtable(L, 0, 3);
  set_number(L, "throttle", c.throttle);
  set_number(L, "steer", c.steer);
  set_number(L, "brake", c.brake);
  return 1;
}

// v:follow{waypoints={{x, z}, ...}, speed=, loop=, reach=}
int v_follow(lua_State* L) {
  VehicleEntry& e = check_vehicle(L, 1);
  luaL_checktype(L, 2, LUA_TTABLE);
  static const char* const kFields[] = {"waypoints", "speed", "loop", "reach", nullptr};
  check_fields(L, 2, kFields);
  Autopilot a;
  if (get_number_field(L, 2, "speed", &a.speed) && (a.speed <= 0 || a.speed > 40))
    luaL_argerror(L, 2, "field 'speed': 0 < m/s <= 40 expected");
  if (get_number_field(L, 2, "reach", &a.reach) && (a.reach <= 0 || a.reach > 200))
    luaL_argerror(L, 2, "field 'reach': 0 < metres <= 200 expected");
  get_bool_field(L, 2, "loop", &a.loop);
  if (lua_getfield(L, 2, "waypoints") != LUA_TTABLE)
    luaL_argerror(L, 2, "field 'waypoints': array of {x, z} expected");
  const lua_Integer n = luaL_len(L, -1);
  if (n < 1 || n > 1000) luaL_argerror(L, 2, "field 'waypoints': 1 .. 1000 points expected");
  // (The game links the C++ build of Lua: an error unwinds, so the vector is freed.)
  for (lua_Integer i = 1; i <= n; ++i) {
    lua_rawgeti(L, -1, i);
    double xz[2] = {0, 0};
    bool ok = lua_type(L, -1) == LUA_TTABLE;
    for (int k = 0; ok && k < 2; ++k) {
      lua_rawgeti(L, -1 - k, k + 1);
      ok = lua_type(L, -1) == LUA_TNUMBER && std::isfinite(lua_tonumber(L, -1));
      xz[k] = ok ? lua_tonumber(L, -1) : 0;
    }
    if (!ok)
      luaL_argerror(L, 2,
                    lua_pushfstring(L, "waypoint %d: {x, z} with finite numbers expected",
                                    static_cast<int>(i)));
    lua_pop(L, 3);
    a.waypoints.push_back({xz[0], xz[1]});
  }
  lua_pop(L, 1);
  a.active = true;
  e.autopilot = std::move(a);
  return 0;
}

int v_stop(lua_State* L) {
  VehicleEntry& e = check_vehicle(L, 1);
  e.autopilot.active = false;
  e.body.controls = {0, 0, 1};
  return 0;
}

int v_progress(lua_State* L) {
  const VehicleEntry& e = check_vehicle(L, 1);
  lua_createtable(L, 0, 5);
  set_number(L, "reached", double(e.autopilot.reached));
  set_number(L, "next", double(e.autopilot.next) + 1);
  set_number(L, "count", double(e.autopilot.waypoints.size()));
  set_bool(L, "active", e.autopilot.active);
  set_number(L, "distance", e.distance_m);
  return 1;
}

int v_position(lua_State* L) {
  const glm::dvec3 p = check_vehicle(L, 1).body.position();
  lua_pushnumber(L, p.x);
  lua_pushnumber(L, p.y);
  lua_pushnumber(L, p.z);
  return 3;
}

int v_state(lua_State* L) {
  const VehicleEntry& e = check_vehicle(L, 1);
  const glm::dvec3 p = e.body.position();
  int contacts = 0;
  for (const WheelState& w : e.body.wheels()) contacts += w.contact;
  lua_createtable(L, 0, 13);
  set_number(L, "id", e.id);
  set_string(L, "name", e.name);
  set_string(L, "model", e.model);
  set_number(L, "x", p.x);
  set_number(L, "y", p.y);
  set_number(L, "z", p.z);
  set_number(L, "speed", e.body.speed());
  set_number(L, "heading", e.body.heading());
  set_number(L, "wheels_in_contact", contacts);
  set_number(L, "distance", e.distance_m);
  set_number(L, "material", e.body.ground_material());
  set_number(L, "collisions", double(e.body.collisions));
  set_number(L, "body_hits", double(e.body.body_hits));
  return 1;
}

int v_place(lua_State* L) {
  VehicleEntry& e = check_vehicle(L, 1);
  const double x = check_finite(L, 2), z = check_finite(L, 3);
  const double heading = opt_finite(L, 4, e.body.heading());
  GameApi& g = game_of(L);
  const ridgeline::Terrain& t = *g.terrain_ptr();
  if (!t.height(x, z)) {
    lua_pushnil(L);
    lua_pushfstring(L, "place: (%f, %f) is off the terrain", x, z);
    return 2;
  }
  e.body.place_on_surface(x, z, heading);
  lua_pushboolean(L, 1);
  return 1;
}

int v_remove(lua_State* L) {
  lua_pushboolean(L, game_of(L).remove_vehicle(check_handle(L, 1)->id));
  return 1;
}

int v_id(lua_State* L) {
  lua_pushinteger(L, check_handle(L, 1)->id);
  return 1;
}

int v_alive(lua_State* L) {
  lua_pushboolean(L, game_of(L).vehicle(check_handle(L, 1)->id) != nullptr);
  return 1;
}

int v_tostring(lua_State* L) {
  const int id = check_handle(L, 1)->id;
  const VehicleEntry* e = game_of(L).vehicle(id);
  if (e == nullptr)
    lua_pushfstring(L, "game.vehicle %d (removed)", id);
  else
    lua_pushfstring(L, "game.vehicle %d '%s' (%s)", id, e->name.c_str(), e->model.c_str());
  return 1;
}

int v_eq(lua_State* L) {
  lua_pushboolean(L, check_handle(L, 1)->id == check_handle(L, 2)->id);
  return 1;
}

const luaL_Reg kVehicleMethods[] = {{"set_controls", v_set_controls},
                                    {"controls", v_controls},
                                    {"follow", v_follow},
                                    {"stop", v_stop},
                                    {"progress", v_progress},
                                    {"position", v_position},
                                    {"state", v_state},
                                    {"place", v_place},
                                    {"remove", v_remove},
                                    {"id", v_id},
                                    {"alive", v_alive},
                                    {nullptr, nullptr}};

}  // namespace

void set_number(lua_State* L, const char* k, double v) {
  lua_pushnumber(L, v);
  lua_setfield(L, -2, k);
}
void set_bool(lua_State* L, const char* k, bool v) {
  lua_pushboolean(L, v);
  lua_setfield(L, -2, k);
}
void set_string(lua_State* L, const char* k, const std::string& v) {
  lua_pushlstring(L, v.data(), v.size());
  lua_setfield(L, -2, k);
}

Context& context(lua_State* L) {
  return *static_cast<Context*>(lua_touserdata(L, lua_upvalueindex(1)));
}

void register_vehicle_type(lua_State* L, Context* ctx) {
  if (luaL_newmetatable(L, kVehicleMeta) == 0) {
    lua_pop(L, 1);
    return;
  }
  lua_newtable(L);
  lua_pushlightuserdata(L, ctx);
  luaL_setfuncs(L, kVehicleMethods, 1);
  lua_setfield(L, -2, "__index");
  lua_pushlightuserdata(L, ctx);
  lua_pushcclosure(L, v_tostring, 1);
  lua_setfield(L, -2, "__tostring");
  lua_pushlightuserdata(L, ctx);
  lua_pushcclosure(L, v_eq, 1);
  lua_setfield(L, -2, "__eq");
  lua_pushliteral(L, "game.vehicle");
  lua_setfield(L, -2, "__metatable");
  lua_pop(L, 1);
}

void push_vehicle(lua_State* L, int id) {
  auto* h = static_cast<VehicleHandle*>(lua_newuserdatauv(L, sizeof(VehicleHandle), 0));
  h->id = id;
  luaL_setmetatable(L, kVehicleMeta);
}

VehicleEntry& check_vehicle(lua_State* L, int arg) {
  const int id = check_handle(L, arg)->id;
  VehicleEntry* e = game_of(L).vehicle(id);
  if (e == nullptr) luaL_error(L, "attempt to use a removed vehicle (id %d)", id);
  return *e;
}

int test_vehicle(lua_State* L, int index) {
  auto* h = static_cast<VehicleHandle*>(luaL_testudata(L, index, kVehicleMeta));
  return h == nullptr ? -1 : h->id;
}

}  // namespace game::lua_api
