// The game-side Lua API: the `game` table, vehicle handles, events, hot reload. Conventions follow
// the ridgeline binding (docs/lua_api.md): misuse raises an argument error naming the field, an
// expected miss returns nil, message; option tables refuse unknown fields. Documented in
// docs/game_scripting.md.
#include <lua.hpp>

#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include "game.h"
#include "ridgeline/lua/module.h"

namespace game {

using ridgeline::Status;

namespace {

char kHandlersKey;  // registry: {[script index] = {[event] = {fn, ...}}}
constexpr char kVehicleMeta[] = "game.vehicle";
const char* const kEvents[] = {"tick", "waypoint", "crater", nullptr};

Game& game_of(lua_State* L) {
  return *static_cast<Game*>(lua_touserdata(L, lua_upvalueindex(1)));
}

// ---- argument helpers (same messages as the ridgeline binding) ------------------------------
void check_fields(lua_State* L, int arg, const char* const* names) {
  lua_pushnil(L);
  while (lua_next(L, arg) != 0) {
    lua_pop(L, 1);
    bool known = false;
    if (lua_type(L, -1) == LUA_TSTRING)
      for (const char* const* n = names; *n != nullptr; ++n)
        if (std::strcmp(lua_tostring(L, -1), *n) == 0) known = true;
    if (!known) {
      const char* key = lua_type(L, -1) == LUA_TSTRING ? lua_tostring(L, -1) : luaL_typename(L, -1);
      luaL_argerror(L, arg, lua_pushfstring(L, "unknown field '%s'", key));
    }
  }
}

bool number_field(lua_State* L, int arg, const char* name, double* out) {
  const int t = lua_getfield(L, arg, name);
  if (t == LUA_TNIL) {
    lua_pop(L, 1);
    return false;
  }
  if (t != LUA_TNUMBER || !std::isfinite(lua_tonumber(L, -1)))
    luaL_argerror(L, arg,
                  lua_pushfstring(L, "field '%s': finite number expected, got %s", name,
                                  t == LUA_TNUMBER ? "non-finite" : luaL_typename(L, -1)));
  *out = lua_tonumber(L, -1);
  lua_pop(L, 1);
  return true;
}

bool bool_field(lua_State* L, int arg, const char* name, bool* out) {
  const int t = lua_getfield(L, arg, name);
  if (t == LUA_TNIL) {
    lua_pop(L, 1);
    return false;
  }
  if (t != LUA_TBOOLEAN)
    luaL_argerror(L, arg, lua_pushfstring(L, "field '%s': boolean expected, got %s", name,
                                          luaL_typename(L, -1)));
  *out = lua_toboolean(L, -1);
  lua_pop(L, 1);
  return true;
}

double check_finite(lua_State* L, int arg) {
  const double v = luaL_checknumber(L, arg);
  if (!std::isfinite(v)) luaL_argerror(L, arg, "finite number expected");
  return v;
}

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

// ---- vehicles ---------------------------------------------------------------------------------
struct VehicleHandle {
  int id;
};

void push_vehicle(lua_State* L, int id) {
  auto* h = static_cast<VehicleHandle*>(lua_newuserdatauv(L, sizeof(VehicleHandle), 0));
  h->id = id;
  luaL_setmetatable(L, kVehicleMeta);
}

VehicleEntry& check_vehicle(lua_State* L, int arg) {
  auto* h = static_cast<VehicleHandle*>(luaL_checkudata(L, arg, kVehicleMeta));
  VehicleEntry* e = game_of(L).vehicle(h->id);
  if (e == nullptr) luaL_error(L, "attempt to use a removed vehicle (id %d)", h->id);
  return *e;
}

int v_set_controls(lua_State* L) {
  VehicleEntry& e = check_vehicle(L, 1);
  luaL_checktype(L, 2, LUA_TTABLE);
  static const char* const kFields[] = {"throttle", "steer", "brake", nullptr};
  check_fields(L, 2, kFields);
  Controls c = e.body.controls;
  if (number_field(L, 2, "throttle", &c.throttle) && std::abs(c.throttle) > 1)
    luaL_argerror(L, 2, "field 'throttle': -1 .. 1 expected");
  if (number_field(L, 2, "steer", &c.steer) && std::abs(c.steer) > 1)
    luaL_argerror(L, 2, "field 'steer': -1 .. 1 expected");
  if (number_field(L, 2, "brake", &c.brake) && (c.brake < 0 || c.brake > 1))
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
  if (lua_getfield(L, 2, "waypoints") != LUA_TTABLE)
    luaL_argerror(L, 2, "field 'waypoints': array of {x, z} expected");
  const lua_Integer n = luaL_len(L, -1);
  if (n < 1 || n > 1000) luaL_argerror(L, 2, "field 'waypoints': 1 .. 1000 points expected");
  std::vector<glm::dvec2> pts;
  for (lua_Integer i = 1; i <= n; ++i) {
    lua_rawgeti(L, -1, i);
    double xz[2];
    bool ok = lua_type(L, -1) == LUA_TTABLE;
    for (int k = 0; ok && k < 2; ++k) {
      lua_rawgeti(L, -1 - k, k + 1);
      ok = lua_type(L, -1) == LUA_TNUMBER && std::isfinite(lua_tonumber(L, -1));
      xz[k] = ok ? lua_tonumber(L, -1) : 0;
    }
    if (!ok)
      luaL_argerror(L, 2, lua_pushfstring(L, "waypoint %d: {x, z} with finite numbers expected",
                                          static_cast<int>(i)));
    lua_pop(L, 3);
    pts.push_back({xz[0], xz[1]});
  }
  lua_pop(L, 1);
  Autopilot a;
  a.waypoints = std::move(pts);
  if (number_field(L, 2, "speed", &a.speed) && (a.speed <= 0 || a.speed > 40))
    luaL_argerror(L, 2, "field 'speed': 0 < m/s <= 40 expected");
  if (number_field(L, 2, "reach", &a.reach) && (a.reach <= 0 || a.reach > 200))
    luaL_argerror(L, 2, "field 'reach': 0 < metres <= 200 expected");
  bool_field(L, 2, "loop", &a.loop);
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
  lua_createtable(L, 0, 10);
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
  return 1;
}

int v_place(lua_State* L) {
  VehicleEntry& e = check_vehicle(L, 1);
  const double x = check_finite(L, 2), z = check_finite(L, 3);
  const double heading = lua_isnoneornil(L, 4) ? e.body.heading() : check_finite(L, 4);
  Game& g = game_of(L);
  const auto h = g.terrain().height(x, z);
  if (!h) {
    lua_pushnil(L);
    lua_pushfstring(L, "place: (%f, %f) is off the terrain", x, z);
    return 2;
  }
  e.body.place_on_surface(g.terrain(), x, z, heading);
  lua_pushboolean(L, 1);
  return 1;
}

int v_remove(lua_State* L) {
  auto* h = static_cast<VehicleHandle*>(luaL_checkudata(L, 1, kVehicleMeta));
  lua_pushboolean(L, game_of(L).remove_vehicle(h->id));
  return 1;
}

int v_id(lua_State* L) {
  auto* h = static_cast<VehicleHandle*>(luaL_checkudata(L, 1, kVehicleMeta));
  lua_pushinteger(L, h->id);
  return 1;
}

int v_alive(lua_State* L) {
  auto* h = static_cast<VehicleHandle*>(luaL_checkudata(L, 1, kVehicleMeta));
  lua_pushboolean(L, game_of(L).vehicle(h->id) != nullptr);
  return 1;
}

int v_tostring(lua_State* L) {
  auto* h = static_cast<VehicleHandle*>(luaL_checkudata(L, 1, kVehicleMeta));
  const VehicleEntry* e = game_of(L).vehicle(h->id);
  if (e == nullptr)
    lua_pushfstring(L, "game.vehicle %d (removed)", h->id);
  else
    lua_pushfstring(L, "game.vehicle %d '%s' (%s)", h->id, e->name.c_str(), e->model.c_str());
  return 1;
}

int v_eq(lua_State* L) {
  auto* a = static_cast<VehicleHandle*>(luaL_checkudata(L, 1, kVehicleMeta));
  auto* b = static_cast<VehicleHandle*>(luaL_checkudata(L, 2, kVehicleMeta));
  lua_pushboolean(L, a->id == b->id);
  return 1;
}

// ---- the game table ---------------------------------------------------------------------------
// game.spawn{model=, x=, z=, heading=, name=} -> vehicle or nil, message
int g_spawn(lua_State* L) {
  luaL_checktype(L, 1, LUA_TTABLE);
  static const char* const kFields[] = {"model", "x", "z", "heading", "name", nullptr};
  check_fields(L, 1, kFields);
  double x = 0, z = 0, heading = 0;
  if (!number_field(L, 1, "x", &x) || !number_field(L, 1, "z", &z))
    luaL_argerror(L, 1, "fields 'x' and 'z' (metres) are required");
  number_field(L, 1, "heading", &heading);
  std::string model = "truck", name;
  if (lua_getfield(L, 1, "model") != LUA_TNIL) {
    if (lua_type(L, -1) != LUA_TSTRING) luaL_argerror(L, 1, "field 'model': string expected");
    model = lua_tostring(L, -1);
  }
  lua_pop(L, 1);
  if (lua_getfield(L, 1, "name") != LUA_TNIL) {
    if (lua_type(L, -1) != LUA_TSTRING) luaL_argerror(L, 1, "field 'name': string expected");
    name = lua_tostring(L, -1);
  }
  lua_pop(L, 1);
  auto id = game_of(L).spawn(model, x, z, heading, name);
  if (!id) {
    lua_pushnil(L);
    lua_pushstring(L, id.error().message.c_str());
    return 2;
  }
  push_vehicle(L, *id);
  return 1;
}

int g_vehicles(lua_State* L) {
  Game& g = game_of(L);
  lua_createtable(L, static_cast<int>(g.vehicles().size()), 0);
  int i = 0;
  for (const auto& [id, e] : g.vehicles()) {
    push_vehicle(L, id);
    lua_rawseti(L, -2, ++i);
  }
  return 1;
}

int g_vehicle(lua_State* L) {
  const lua_Integer id = luaL_checkinteger(L, 1);
  if (game_of(L).vehicle(static_cast<int>(id)) == nullptr) return lua_pushnil(L), 1;
  push_vehicle(L, static_cast<int>(id));
  return 1;
}

// game.on(event, fn): fn runs on each event until its script is reloaded or fails.
int g_on(lua_State* L) {
  const int ev = luaL_checkoption(L, 1, nullptr, kEvents);
  luaL_checktype(L, 2, LUA_TFUNCTION);
  Game& g = game_of(L);
  if (g.current_script < 0) return luaL_error(L, "game.on: no script is running");
  lua_rawgetp(L, LUA_REGISTRYINDEX, &kHandlersKey);
  if (lua_rawgeti(L, -1, g.current_script + 1) != LUA_TTABLE) {
    lua_pop(L, 1);
    lua_newtable(L);
    lua_pushvalue(L, -1);
    lua_rawseti(L, -3, g.current_script + 1);
  }
  if (lua_getfield(L, -1, kEvents[ev]) != LUA_TTABLE) {
    lua_pop(L, 1);
    lua_newtable(L);
    lua_pushvalue(L, -1);
    lua_setfield(L, -3, kEvents[ev]);
  }
  lua_pushvalue(L, 2);
  lua_rawseti(L, -2, static_cast<lua_Integer>(lua_rawlen(L, -2)) + 1);
  return 0;
}

int g_log(lua_State* L) {
  std::string line;
  const int n = lua_gettop(L);
  for (int i = 1; i <= n; ++i) {
    if (i > 1) line += ' ';
    line += luaL_tolstring(L, i, nullptr);
    lua_pop(L, 1);
  }
  Game& g = game_of(L);
  const std::string who =
      g.current_script >= 0 ? g.scripts[g.current_script].name : std::string("game");
  g.log("[" + who + "] " + line);
  return 0;
}

int g_time(lua_State* L) {
  lua_pushnumber(L, game_of(L).time());
  return 1;
}
int g_frame(lua_State* L) {
  lua_pushinteger(L, static_cast<lua_Integer>(game_of(L).frame()));
  return 1;
}
int g_dt(lua_State* L) {
  lua_pushnumber(L, game_of(L).dt());
  return 1;
}

int g_input(lua_State* L) {
  const Input& in = game_of(L).input;
  lua_createtable(L, 0, 5);
  set_bool(L, "up", in.up);
  set_bool(L, "down", in.down);
  set_bool(L, "left", in.left);
  set_bool(L, "right", in.right);
  set_bool(L, "brake", in.brake);
  return 1;
}

void push_camera(lua_State* L, const Game& gc) {
  Game& g = const_cast<Game&>(gc);
  const CameraRig& r = g.rig();
  const ridgeline::Camera c = g.camera();
  lua_createtable(L, 0, 6);
  lua_pushstring(L, to_string(r.mode));
  lua_setfield(L, -2, "mode");
  lua_createtable(L, 3, 0);
  for (int i = 0; i < 3; ++i) {
    lua_pushnumber(L, c.eye[i]);
    lua_rawseti(L, -2, i + 1);
  }
  lua_setfield(L, -2, "eye");
  lua_createtable(L, 3, 0);
  for (int i = 0; i < 3; ++i) {
    lua_pushnumber(L, c.target[i]);
    lua_rawseti(L, -2, i + 1);
  }
  lua_setfield(L, -2, "target");
  if (r.follow_vehicle >= 0 && g.vehicle(r.follow_vehicle) != nullptr) {
    push_vehicle(L, r.follow_vehicle);
    lua_setfield(L, -2, "vehicle");
  }
}

// game.camera{mode=, vehicle=, eye=, yaw=, pitch=, centre=, height=, distance=} / game.camera()
int g_camera(lua_State* L) {
  Game& g = game_of(L);
  if (lua_isnoneornil(L, 1)) {
    push_camera(L, g);
    return 1;
  }
  luaL_checktype(L, 1, LUA_TTABLE);
  static const char* const kFields[] = {"mode", "vehicle", "eye", "yaw", "pitch",
                                        "centre", "height", "distance", nullptr};
  check_fields(L, 1, kFields);
  CameraRig r = g.rig();
  if (lua_getfield(L, 1, "mode") != LUA_TNIL) {
    const char* m = lua_type(L, -1) == LUA_TSTRING ? lua_tostring(L, -1) : "";
    if (std::strcmp(m, "free") == 0) r.mode = CameraMode::kFree;
    else if (std::strcmp(m, "follow") == 0) r.mode = CameraMode::kFollow;
    else if (std::strcmp(m, "map") == 0) r.mode = CameraMode::kMap;
    else
      luaL_argerror(L, 1, lua_pushfstring(L, "field 'mode': 'free', 'follow' or 'map' expected, "
                                             "got '%s'", luaL_tolstring(L, -1, nullptr)));
  }
  lua_pop(L, 1);
  if (lua_getfield(L, 1, "vehicle") != LUA_TNIL) {
    auto* h = static_cast<VehicleHandle*>(luaL_testudata(L, -1, kVehicleMeta));
    if (h == nullptr) luaL_argerror(L, 1, "field 'vehicle': game.vehicle expected");
    r.follow_vehicle = h->id;
  }
  lua_pop(L, 1);
  if (lua_getfield(L, 1, "eye") != LUA_TNIL) {
    if (!lua_istable(L, -1)) luaL_argerror(L, 1, "field 'eye': {x, y, z} expected");
    for (int i = 0; i < 3; ++i) {
      lua_rawgeti(L, -1, i + 1);
      if (lua_type(L, -1) != LUA_TNUMBER || !std::isfinite(lua_tonumber(L, -1)))
        luaL_argerror(L, 1, "field 'eye': {x, y, z} with finite numbers expected");
      r.free_eye[i] = lua_tonumber(L, -1);
      lua_pop(L, 1);
    }
  }
  lua_pop(L, 1);
  number_field(L, 1, "yaw", &r.free_yaw);
  if (number_field(L, 1, "pitch", &r.free_pitch) && std::abs(r.free_pitch) > 1.55)
    luaL_argerror(L, 1, "field 'pitch': -1.55 .. 1.55 radians expected");
  if (lua_getfield(L, 1, "centre") != LUA_TNIL) {
    if (!lua_istable(L, -1)) luaL_argerror(L, 1, "field 'centre': {x, z} expected");
    for (int i = 0; i < 2; ++i) {
      lua_rawgeti(L, -1, i + 1);
      if (lua_type(L, -1) != LUA_TNUMBER || !std::isfinite(lua_tonumber(L, -1)))
        luaL_argerror(L, 1, "field 'centre': {x, z} with finite numbers expected");
      r.map_centre[i] = lua_tonumber(L, -1);
      lua_pop(L, 1);
    }
  }
  lua_pop(L, 1);
  if (number_field(L, 1, "height", &r.map_height) && (r.map_height < 10 || r.map_height > 20000))
    luaL_argerror(L, 1, "field 'height': 10 .. 20000 metres expected");
  if (number_field(L, 1, "distance", &r.follow_distance) &&
      (r.follow_distance < 2 || r.follow_distance > 500))
    luaL_argerror(L, 1, "field 'distance': 2 .. 500 metres expected");
  g.rig() = r;
  return 0;
}

int g_budget(lua_State* L) {
  Game& g = game_of(L);
  const auto& c = g.controller();
  lua_createtable(L, 0, 9);
  set_number(L, "threshold", g.threshold());
  set_bool(L, "controller", g.controller_on());
  set_number(L, "target_ms", c.desc().target_ms);
  set_number(L, "min", c.desc().min_threshold);
  set_number(L, "max", c.desc().max_threshold);
  set_number(L, "smoothed_ms", c.state().smoothed_ms);
  set_number(L, "triangles", g.max_triangles());
  set_number(L, "tess_ms", g.tessellation_budget_ms());
  set_number(L, "frame_ms", g.last_frame_ms);
  return 1;
}

// game.set_budget{controller=, threshold=, target_ms=, min=, max=, triangles=, tess_ms=}
int g_set_budget(lua_State* L) {
  Game& g = game_of(L);
  luaL_checktype(L, 1, LUA_TTABLE);
  static const char* const kFields[] = {"controller", "threshold", "target_ms", "min",
                                        "max",        "triangles", "tess_ms",   nullptr};
  check_fields(L, 1, kFields);
  bool on = g.controller_on();
  bool_field(L, 1, "controller", &on);
  double threshold = g.threshold(), target = g.controller().desc().target_ms;
  double lo = g.controller().desc().min_threshold, hi = g.controller().desc().max_threshold;
  double tris = g.max_triangles(), tess = g.tessellation_budget_ms();
  const bool has_threshold = number_field(L, 1, "threshold", &threshold);
  if (has_threshold && (threshold < 0.25 || threshold > 256))
    luaL_argerror(L, 1, "field 'threshold': 0.25 .. 256 pixels expected");
  const bool has_target = number_field(L, 1, "target_ms", &target);
  if (has_target && (target < 1 || target > 1000))
    luaL_argerror(L, 1, "field 'target_ms': 1 .. 1000 ms expected");
  const bool has_lo = number_field(L, 1, "min", &lo), has_hi = number_field(L, 1, "max", &hi);
  if ((has_lo || has_hi) && !(lo >= 0.25 && hi <= 256 && lo <= hi))
    luaL_argerror(L, 1, "fields 'min', 'max': 0.25 <= min <= max <= 256 pixels expected");
  if (number_field(L, 1, "triangles", &tris) && (tris < 100 || tris > 4'000'000))
    luaL_argerror(L, 1, "field 'triangles': 100 .. 4000000 expected");
  if (number_field(L, 1, "tess_ms", &tess) && (tess < 0 || tess > 1000))
    luaL_argerror(L, 1, "field 'tess_ms': 0 .. 1000 ms expected (0: none)");
  // All checked: apply.
  if (has_target) (void)g.controller().set_target_ms(target);
  if (has_lo || has_hi) (void)g.controller().set_range(lo, hi);
  if (has_threshold) {
    g.set_threshold(threshold);
    (void)g.controller().reset(std::clamp(threshold, g.controller().desc().min_threshold,
                                          g.controller().desc().max_threshold));
  }
  g.set_controller_on(on);
  if (on && !has_threshold) g.set_threshold(g.controller().threshold());
  g.set_max_triangles(static_cast<std::uint32_t>(tris));
  g.set_tessellation_budget_ms(tess);
  return 0;
}

// game.burn_ms(ms): busy-waits (an artificial load for budget tests); 0 .. 100 ms per call.
int g_burn_ms(lua_State* L) {
  const double ms = check_finite(L, 1);
  if (ms < 0 || ms > 100) luaL_argerror(L, 1, "0 .. 100 milliseconds expected");
  const auto t0 = std::chrono::steady_clock::now();
  volatile double sink = 0;
  while (std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() <
         ms)
    sink = sink + 1;
  game_of(L).add_burn(ms);
  return 0;
}

// game.crater{x=, z=, radius=, depth=} -> samples changed, or nil, message
int g_crater(lua_State* L) {
  luaL_checktype(L, 1, LUA_TTABLE);
  static const char* const kFields[] = {"x", "z", "radius", "depth", nullptr};
  check_fields(L, 1, kFields);
  double x = 0, z = 0, radius = 8, depth = 3;
  if (!number_field(L, 1, "x", &x) || !number_field(L, 1, "z", &z))
    luaL_argerror(L, 1, "fields 'x' and 'z' (metres) are required");
  number_field(L, 1, "radius", &radius);
  number_field(L, 1, "depth", &depth);
  if (radius <= 0 || radius > 200) luaL_argerror(L, 1, "field 'radius': 0 < metres <= 200 expected");
  if (depth <= 0 || depth > 100) luaL_argerror(L, 1, "field 'depth': 0 < metres <= 100 expected");
  Game& g = game_of(L);
  auto r = g.crater(x, z, radius, depth);
  if (!r) {
    lua_pushnil(L);
    lua_pushstring(L, r.error().message.c_str());
    return 2;
  }
  lua_pushinteger(L, static_cast<lua_Integer>(*r));
  return 1;
}

int g_stats(lua_State* L) {
  Game& g = game_of(L);
  const ViewFrame& v = g.last_view_frame();
  lua_createtable(L, 0, 8);
  set_number(L, "frame_ms", g.last_frame_ms);
  set_number(L, "triangles", v.stats.triangles);
  set_number(L, "threshold", g.threshold());
  set_number(L, "splits", v.stats.splits + v.stats.forced_splits);
  set_number(L, "merges", v.stats.merges);
  set_number(L, "tess_ms", v.stats.update_ms);
  set_number(L, "craters", double(g.craters().size()));
  set_number(L, "script_errors", double(g.error_count()));
  return 1;
}

int g_models(lua_State* L) {
  const auto names = game_of(L).model_names();
  lua_createtable(L, static_cast<int>(names.size()), 0);
  for (std::size_t i = 0; i < names.size(); ++i) {
    lua_pushstring(L, names[i].c_str());
    lua_rawseti(L, -2, static_cast<lua_Integer>(i) + 1);
  }
  return 1;
}

const luaL_Reg kVehicleMethods[] = {
    {"set_controls", v_set_controls}, {"controls", v_controls}, {"follow", v_follow},
    {"stop", v_stop},                 {"progress", v_progress}, {"position", v_position},
    {"state", v_state},               {"place", v_place},       {"remove", v_remove},
    {"id", v_id},                     {"alive", v_alive},       {nullptr, nullptr}};

const luaL_Reg kGame[] = {{"spawn", g_spawn},
                          {"vehicles", g_vehicles},
                          {"vehicle", g_vehicle},
                          {"on", g_on},
                          {"log", g_log},
                          {"time", g_time},
                          {"frame", g_frame},
                          {"dt", g_dt},
                          {"input", g_input},
                          {"camera", g_camera},
                          {"budget", g_budget},
                          {"set_budget", g_set_budget},
                          {"burn_ms", g_burn_ms},
                          {"crater", g_crater},
                          {"stats", g_stats},
                          {"models", g_models},
                          {nullptr, nullptr}};

int install(lua_State* L) {
  Game* g = static_cast<Game*>(lua_touserdata(L, 1));
  lua_newtable(L);
  lua_rawsetp(L, LUA_REGISTRYINDEX, &kHandlersKey);
  luaL_newmetatable(L, kVehicleMeta);
  lua_newtable(L);
  lua_pushlightuserdata(L, g);
  luaL_setfuncs(L, kVehicleMethods, 1);
  lua_setfield(L, -2, "__index");
  lua_pushlightuserdata(L, g);
  lua_pushcclosure(L, v_tostring, 1);
  lua_setfield(L, -2, "__tostring");
  lua_pushlightuserdata(L, g);
  lua_pushcclosure(L, v_eq, 1);
  lua_setfield(L, -2, "__eq");
  lua_pushliteral(L, "game.vehicle");
  lua_setfield(L, -2, "__metatable");
  lua_pop(L, 1);
  lua_newtable(L);
  lua_pushlightuserdata(L, g);
  luaL_setfuncs(L, kGame, 1);
  ridgeline::lua::push_terrain(L, g->terrain_ptr());
  lua_setfield(L, -2, "terrain");
  return 1;
}

}  // namespace

Status install_game_api(Game& g) {
  lua_State* L = g.host().state();
  lua_pushcfunction(L, install);
  lua_pushlightuserdata(L, &g);
  if (Status s = g.host().call(1, 1); !s) return s;
  return g.host().set_global("game");
}

Status Game::run_script(int index) {
  Script& s = scripts[index];
  std::error_code ec;
  s.mtime = std::filesystem::last_write_time(s.path, ec);
  std::ifstream in(s.path, std::ios::binary);
  if (!in) {
    const std::string msg = "cannot read script '" + s.path + "'";
    record_error(index, msg);
    return ridgeline::Error{msg};
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
  current_script = index;
  Status st = host_->run(ss.str(), "@" + s.name);
  current_script = -1;
  if (!st) {
    record_error(index, st.message());
    return st;
  }
  log("loaded " + s.name);
  return {};
}

void emit_event(Game& g, const char* event, int (*push)(lua_State*, void*), void* user) {
  lua_State* L = g.host().state();
  const int top0 = lua_gettop(L);
  for (std::size_t i = 0; i < g.scripts.size(); ++i) {
    if (g.scripts[i].failed) continue;
    lua_rawgetp(L, LUA_REGISTRYINDEX, &kHandlersKey);
    if (lua_rawgeti(L, -1, static_cast<lua_Integer>(i) + 1) != LUA_TTABLE ||
        lua_getfield(L, -1, event) != LUA_TTABLE) {
      lua_settop(L, top0);
      continue;
    }
    const auto n = static_cast<lua_Integer>(lua_rawlen(L, -1));
    const int list = lua_gettop(L);
    for (lua_Integer k = 1; k <= n && !g.scripts[i].failed; ++k) {
      lua_rawgeti(L, list, k);
      const int nargs = push(L, user);
      g.current_script = static_cast<int>(i);
      const Status st = g.host().call(nargs, 0);
      g.current_script = -1;
      if (!st) g.record_error(static_cast<int>(i), st.message());
      lua_settop(L, list);
    }
    lua_settop(L, top0);
  }
}

}  // namespace game
