// The `game` table of game scripts: spawning, events, cameras, the LOD budget, deformation, and
// the game's terrain as a `ridgeline.terrain`. Documented in docs/game_scripting.md.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <lua.hpp>

#include "lua_api.h"
#include "materials.h"
#include "ridgeline/bench/clock.h"
#include "ridgeline/detail.h"
#include "ridgeline/lua/check.h"
#include "ridgeline/lua/module.h"
#include "script_runner.h"

namespace game::lua_api {
namespace {

using ridgeline::lua::check_fields;
using ridgeline::lua::check_finite;
using ridgeline::lua::get_bool_field;
using ridgeline::lua::get_number_field;
using ridgeline::lua::get_string_field;
using ridgeline::lua::get_vector_field;

GameApi& game_of(lua_State* L) {
  return *context(L).game;
}
ScriptRunner& runner_of(lua_State* L) {
  return *context(L).runner;
}

// game.spawn{model=, x=, z=, heading=, name=} -> vehicle or nil, message
int g_spawn(lua_State* L) {
  luaL_checktype(L, 1, LUA_TTABLE);
  static const char* const kFields[] = {"model", "x", "z", "heading", "name", nullptr};
  check_fields(L, 1, kFields);
  double x = 0, z = 0, heading = 0;
  if (!get_number_field(L, 1, "x", &x) || !get_number_field(L, 1, "z", &z))
    luaL_argerror(L, 1, "fields 'x' and 'z' (metres) are required");
  get_number_field(L, 1, "heading", &heading);
  const char* model = "truck";
  const char* name = "";
  get_string_field(L, 1, "model", &model);
  get_string_field(L, 1, "name", &name);
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
  const auto& vs = game_of(L).vehicles();
  lua_createtable(L, static_cast<int>(vs.size()), 0);
  int i = 0;
  for (const auto& [id, e] : vs) {
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
  const int ev = luaL_checkoption(L, 1, nullptr, kScriptEvents);
  luaL_checktype(L, 2, LUA_TFUNCTION);
  if (!runner_of(L).add_handler(L, ev, 2)) return luaL_error(L, "game.on: no script is running");
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
  ScriptRunner& r = runner_of(L);
  std::string out = "[";  // (appended piecewise: GCC 12 warns falsely about "[" + s + "] ")
  out += r.current_name();
  out += "] ";
  out += line;
  r.log(out);
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
  const Input& in = game_of(L).input();
  lua_createtable(L, 0, 5);
  set_bool(L, "up", in.up);
  set_bool(L, "down", in.down);
  set_bool(L, "left", in.left);
  set_bool(L, "right", in.right);
  set_bool(L, "brake", in.brake);
  return 1;
}

void push_vec(lua_State* L, const glm::dvec3& v) {
  lua_createtable(L, 3, 0);
  for (int i = 0; i < 3; ++i) {
    lua_pushnumber(L, v[i]);
    lua_rawseti(L, -2, i + 1);
  }
}

void push_camera(lua_State* L, GameApi& g) {
  const CameraRig& r = g.rig();
  const ridgeline::Camera c = g.camera();
  lua_createtable(L, 0, 6);
  lua_pushstring(L, to_string(r.mode));
  lua_setfield(L, -2, "mode");
  push_vec(L, c.eye);
  lua_setfield(L, -2, "eye");
  push_vec(L, c.target);
  lua_setfield(L, -2, "target");
  if (r.follow_vehicle >= 0 && g.vehicle(r.follow_vehicle) != nullptr) {
    push_vehicle(L, r.follow_vehicle);
    lua_setfield(L, -2, "vehicle");
  }
}

// game.camera{mode=, vehicle=, eye=, yaw=, pitch=, centre=, height=, distance=, lift=, ahead=} /
// game.camera()
int g_camera(lua_State* L) {
  GameApi& g = game_of(L);
  if (lua_isnoneornil(L, 1)) {
    push_camera(L, g);
    return 1;
  }
  luaL_checktype(L, 1, LUA_TTABLE);
  static const char* const kFields[] = {"mode",   "vehicle",  "eye",  "yaw",   "pitch", "centre",
                                        "height", "distance", "lift", "ahead", nullptr};
  check_fields(L, 1, kFields);
  CameraRig r = g.rig();
  const char* mode = nullptr;
  if (get_string_field(L, 1, "mode", &mode)) {
    if (std::strcmp(mode, "free") == 0)
      r.mode = CameraMode::kFree;
    else if (std::strcmp(mode, "follow") == 0)
      r.mode = CameraMode::kFollow;
    else if (std::strcmp(mode, "map") == 0)
      r.mode = CameraMode::kMap;
    else
      luaL_argerror(L, 1,
                    lua_pushfstring(L,
                                    "field 'mode': 'free', 'follow' or 'map' expected, "
                                    "got '%s'",
                                    mode));
  }
  if (lua_getfield(L, 1, "vehicle") != LUA_TNIL) {
    const int id = test_vehicle(L, -1);
    if (id < 0) luaL_argerror(L, 1, "field 'vehicle': game.vehicle expected");
    r.follow_vehicle = id;
  }
  lua_pop(L, 1);
  double v[3];
  if (get_vector_field(L, 1, "eye", 3, v)) r.free_eye = {v[0], v[1], v[2]};
  get_number_field(L, 1, "yaw", &r.free_yaw);
  if (get_number_field(L, 1, "pitch", &r.free_pitch) && std::abs(r.free_pitch) > 1.55)
    luaL_argerror(L, 1, "field 'pitch': -1.55 .. 1.55 radians expected");
  if (get_vector_field(L, 1, "centre", 2, v)) r.map_centre = {v[0], v[1]};
  if (get_number_field(L, 1, "height", &r.map_height) &&
      (r.map_height < 10 || r.map_height > 20000))
    luaL_argerror(L, 1, "field 'height': 10 .. 20000 metres expected");
  if (get_number_field(L, 1, "distance", &r.follow_distance) &&
      (r.follow_distance < 2 || r.follow_distance > 500))
    luaL_argerror(L, 1, "field 'distance': 2 .. 500 metres expected");
  if (get_number_field(L, 1, "lift", &r.follow_height) &&
      (r.follow_height < 0.5 || r.follow_height > 200))
    luaL_argerror(L, 1, "field 'lift': 0.5 .. 200 metres expected");
  if (get_number_field(L, 1, "ahead", &r.follow_ahead) &&
      (r.follow_ahead < 0 || r.follow_ahead > 200))
    luaL_argerror(L, 1, "field 'ahead': 0 .. 200 metres expected");
  g.rig() = r;
  return 0;
}

int g_budget(lua_State* L) {
  GameApi& g = game_of(L);
  const ridgeline::BudgetController& c = g.controller();
  const BudgetSettings b = g.budget();
  lua_createtable(L, 0, 13);
  set_number(L, "threshold", b.threshold);
  set_number(L, "render_scale", b.render_scale);
  set_bool(L, "controller", b.controller);
  set_number(L, "target_ms", c.desc().target_ms);
  set_number(L, "min", c.desc().min_threshold);
  set_number(L, "max", c.desc().max_threshold);
  set_number(L, "min_scale", c.desc().min_render_scale);
  set_number(L, "scale_from", c.desc().render_scale_from_px);
  set_number(L, "smoothed_ms", c.state().smoothed_ms);
  set_number(L, "triangles", b.max_triangles);
  set_number(L, "tess_ms", b.tessellation_ms);
  set_number(L, "frame_ms", g.last_frame_ms());
  return 1;
}

// game.set_budget{controller=, threshold=, render_scale=, target_ms=, deadband=, headroom=, min=,
//                 max=, min_scale=, scale_from=, triangles=, tess_ms=}: every field checked before
//                 any applies.
int g_set_budget(lua_State* L) {
  GameApi& g = game_of(L);
  luaL_checktype(L, 1, LUA_TTABLE);
  static const char* const kFields[] = {
      "controller", "threshold", "render_scale", "target_ms", "deadband", "headroom", "min",
      "max",        "min_scale", "scale_from",   "triangles", "tess_ms",  nullptr};
  check_fields(L, 1, kFields);
  ridgeline::BudgetController& c = g.controller();
  BudgetSettings b = g.budget();
  get_bool_field(L, 1, "controller", &b.controller);
  double target = c.desc().target_ms, lo = c.desc().min_threshold, hi = c.desc().max_threshold;
  double min_scale = c.desc().min_render_scale, scale_from = c.desc().render_scale_from_px;
  double tris = b.max_triangles;
  const bool has_threshold = get_number_field(L, 1, "threshold", &b.threshold);
  if (has_threshold && (b.threshold < 0.25 || b.threshold > 256))
    luaL_argerror(L, 1, "field 'threshold': 0.25 .. 256 pixels expected");
  const bool has_scale = get_number_field(L, 1, "render_scale", &b.render_scale);
  if (has_scale && (b.render_scale < 0.25 || b.render_scale > 1))
    luaL_argerror(L, 1, "field 'render_scale': 0.25 .. 1 expected");
  const bool has_target = get_number_field(L, 1, "target_ms", &target);
  if (has_target && (target < 1 || target > 1000))
    luaL_argerror(L, 1, "field 'target_ms': 1 .. 1000 ms expected");
  double deadband = c.desc().deadband;
  const bool has_deadband = get_number_field(L, 1, "deadband", &deadband);
  if (has_deadband && !(deadband >= 0 && deadband < 0.5))
    luaL_argerror(L, 1,
                  "field 'deadband': 0 .. 0.5 (exclusive) expected, a fraction of the target");
  double headroom = c.desc().headroom_gain;
  const bool has_headroom = get_number_field(L, 1, "headroom", &headroom);
  if (has_headroom && !(headroom >= 0 && headroom <= 100))
    luaL_argerror(L, 1, "field 'headroom': 0 .. 100 expected (the gain spending headroom; 0: off)");
  const bool has_lo = get_number_field(L, 1, "min", &lo);
  const bool has_hi = get_number_field(L, 1, "max", &hi);
  if ((has_lo || has_hi) && !(lo >= 0.25 && hi <= 256 && lo <= hi))
    luaL_argerror(L, 1, "fields 'min', 'max': 0.25 <= min <= max <= 256 pixels expected");
  const bool has_min_scale = get_number_field(L, 1, "min_scale", &min_scale);
  if (has_min_scale && !(min_scale >= 0.25 && min_scale <= 1))
    luaL_argerror(L, 1, "field 'min_scale': 0.25 .. 1 expected");
  const bool has_from = get_number_field(L, 1, "scale_from", &scale_from);
  if ((has_from || has_lo || has_hi) && scale_from != 0 && (scale_from < lo || scale_from > hi))
    luaL_argerror(L, 1,
                  "field 'scale_from': 0 (the maximum) or a threshold within [min, max] "
                  "expected");
  if (get_number_field(L, 1, "triangles", &tris) && (tris < g.root_triangles() || tris > 4'000'000))
    luaL_argerror(L, 1,
                  lua_pushfstring(L,
                                  "field 'triangles': %d .. 4000000 expected (the views' "
                                  "root triangles at least), got %f",
                                  int(g.root_triangles()), tris));
  if (get_number_field(L, 1, "tess_ms", &b.tessellation_ms) &&
      (b.tessellation_ms < 0 || b.tessellation_ms > 1000))
    luaL_argerror(L, 1, "field 'tess_ms': 0 .. 1000 ms expected (0: none)");
  // All checked: apply.
  if (has_target) (void)c.set_target_ms(target);
  if (has_deadband) (void)c.set_deadband(deadband);
  if (has_headroom) (void)c.set_headroom_gain(headroom);
  if (has_lo || has_hi) (void)c.set_range(lo, hi);
  if (has_min_scale || has_from) (void)c.set_render_scale_range(min_scale, scale_from);
  if (has_threshold || has_scale) {
    const double t = std::clamp(b.threshold, c.desc().min_threshold, c.desc().max_threshold);
    const double s = std::clamp(b.render_scale, c.desc().min_render_scale, 1.0);
    (void)c.reset(t, s);
  } else if (b.controller) {
    b.threshold = c.threshold();
    b.render_scale = c.render_scale();
  }
  b.max_triangles = static_cast<std::uint32_t>(tris);
  g.set_budget(b);
  return 0;
}

// game.burn_ms(ms): busy-waits (an artificial load for budget tests); 0 .. 100 ms per call.
int g_burn_ms(lua_State* L) {
  const double ms = check_finite(L, 1);
  if (ms < 0 || ms > 100) luaL_argerror(L, 1, "0 .. 100 milliseconds expected");
  const auto t0 = ridgeline::bench::Clock::now();
  volatile double sink = 0;
  while (ridgeline::bench::ms_since(t0) < ms) sink = sink + 1;
  game_of(L).add_burn(ms);
  return 0;
}

// game.crater{x=, z=, radius=, depth=} -> samples changed, or nil, message
int g_crater(lua_State* L) {
  luaL_checktype(L, 1, LUA_TTABLE);
  static const char* const kFields[] = {"x", "z", "radius", "depth", nullptr};
  check_fields(L, 1, kFields);
  double x = 0, z = 0, radius = 8, depth = 3;
  if (!get_number_field(L, 1, "x", &x) || !get_number_field(L, 1, "z", &z))
    luaL_argerror(L, 1, "fields 'x' and 'z' (metres) are required");
  get_number_field(L, 1, "radius", &radius);
  get_number_field(L, 1, "depth", &depth);
  if (radius <= 0 || radius > 200)
    luaL_argerror(L, 1, "field 'radius': 0 < metres <= 200 expected");
  if (depth <= 0 || depth > 100) luaL_argerror(L, 1, "field 'depth': 0 < metres <= 100 expected");
  auto r = game_of(L).crater(x, z, radius, depth);
  if (!r) {
    lua_pushnil(L);
    lua_pushstring(L, r.error().message.c_str());
    return 2;
  }
  lua_pushinteger(L, static_cast<lua_Integer>(*r));
  return 1;
}

int g_stats(lua_State* L) {
  GameApi& g = game_of(L);
  const ViewFrame& v = g.last_view_frame();
  lua_createtable(L, 0, 12);
  set_number(L, "frame_ms", g.last_frame_ms());
  set_number(L, "triangles", v.stats.triangles);
  set_number(L, "threshold", v.threshold);
  set_number(L, "render_scale", v.render_scale);
  set_number(L, "splits", v.stats.splits + v.stats.forced_splits);
  set_number(L, "merges", v.stats.merges);
  set_number(L, "tess_ms", v.stats.update_ms);
  set_number(L, "craters", double(g.crater_count()));
  set_number(L, "script_errors", double(runner_of(L).error_count()));
  set_number(L, "bodies", double(g.bodies().size()));
  if (const ridgeline::DetailCache* cache = g.terrain_ptr()->surface().detail_cache()) {
    const ridgeline::DetailCacheStats s = cache->stats();
    set_number(L, "tiles_resident", double(s.resident_tiles));
    set_number(L, "tiles_pending", double(s.pending));
    set_number(L, "tiles_generated", double(s.generated));
  }
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

// game.materials() -> {[id] = {name=, friction=}, ...} for the ids the terrain uses.
int g_materials(lua_State* L) {
  lua_createtable(L, 0, kMaterialCount);
  for (int id = 0; id < kMaterialCount; ++id) {
    const Material& m = material(static_cast<std::uint8_t>(id));
    lua_createtable(L, 0, 2);
    lua_pushstring(L, m.name);
    lua_setfield(L, -2, "name");
    set_number(L, "friction", m.friction);
    lua_rawseti(L, -2, id);
  }
  return 1;
}

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
                          {"materials", g_materials},
                          {"spawn_body", g_spawn_body},
                          {"bodies", g_bodies},
                          {"body", g_body},
                          {nullptr, nullptr}};

}  // namespace

void push_game_table(lua_State* L, Context* ctx) {
  register_vehicle_type(L, ctx);
  register_body_type(L, ctx);
  lua_newtable(L);
  lua_pushlightuserdata(L, ctx);
  luaL_setfuncs(L, kGame, 1);
  ridgeline::lua::push_terrain(L, ctx->game->terrain_ptr());
  lua_setfield(L, -2, "terrain");
}

}  // namespace game::lua_api
