// Loose bodies for game scripts: game.spawn_body and the `game.body` handle (an id, so a removed
// or despawned body is detected instead of dangling). docs/game_scripting.md, "Loose bodies".
#include <cmath>
#include <cstring>
#include <lua.hpp>

#include "lua_api.h"
#include "ridgeline/lua/check.h"

namespace game::lua_api {
namespace {

using ridgeline::lua::check_fields;
using ridgeline::lua::get_number_field;
using ridgeline::lua::get_string_field;
using ridgeline::lua::get_vector_field;

constexpr char kBodyMeta[] = "game.body";

struct BodyHandle {
  int id;
};

GameApi& game_of(lua_State* L) {
  return *context(L).game;
}

BodyHandle* check_handle(lua_State* L, int arg) {
  return static_cast<BodyHandle*>(luaL_checkudata(L, arg, kBodyMeta));
}

LooseBody& check_body(lua_State* L, int arg) {
  const int id = check_handle(L, arg)->id;
  LooseBody* b = game_of(L).body(id);
  if (b == nullptr) luaL_error(L, "attempt to use a removed body (id %d)", id);
  return *b;
}

void push_xyz(lua_State* L, const glm::dvec3& v) {
  lua_pushnumber(L, v.x);
  lua_pushnumber(L, v.y);
  lua_pushnumber(L, v.z);
}

int b_position(lua_State* L) {
  push_xyz(L, check_body(L, 1).position());
  return 3;
}

int b_velocity(lua_State* L) {
  push_xyz(L, check_body(L, 1).velocity());
  return 3;
}

int b_state(lua_State* L) {
  const LooseBody& b = check_body(L, 1);
  const glm::dvec3 p = b.position(), v = b.velocity();
  lua_createtable(L, 0, 14);
  set_number(L, "id", b.id());
  set_string(L, "name", b.spec().name);
  set_string(L, "shape", to_string(b.spec().shape));
  set_number(L, "x", p.x);
  set_number(L, "y", p.y);
  set_number(L, "z", p.z);
  set_number(L, "vx", v.x);
  set_number(L, "vy", v.y);
  set_number(L, "vz", v.z);
  set_number(L, "speed", glm::length(v));
  set_bool(L, "sleeping", b.sleeping());
  set_number(L, "mass", b.mass());
  set_number(L, "hits", double(b.vehicle_hits));
  if (b.spec().shape == BodyShape::kSphere) {
    set_number(L, "radius", b.spec().size.x);
  } else {
    const glm::dvec3 s = b.spec().size * 2.0;
    lua_createtable(L, 3, 0);
    for (int i = 0; i < 3; ++i) {
      lua_pushnumber(L, s[i]);
      lua_rawseti(L, -2, i + 1);
    }
    lua_setfield(L, -2, "size");
  }
  return 1;
}

// b:push{x=, y=, z=}: an impulse, N s (each component finite, |impulse| <= 1e6).
int b_push(lua_State* L) {
  LooseBody& b = check_body(L, 1);
  luaL_checktype(L, 2, LUA_TTABLE);
  static const char* const kFields[] = {"x", "y", "z", nullptr};
  check_fields(L, 2, kFields);
  glm::dvec3 j(0);
  get_number_field(L, 2, "x", &j.x);
  get_number_field(L, 2, "y", &j.y);
  get_number_field(L, 2, "z", &j.z);
  if (glm::length(j) > 1e6) luaL_argerror(L, 2, "impulse of at most 1e6 N s expected");
  b.push(j);
  return 0;
}

int b_remove(lua_State* L) {
  lua_pushboolean(L, game_of(L).remove_body(check_handle(L, 1)->id));
  return 1;
}

int b_id(lua_State* L) {
  lua_pushinteger(L, check_handle(L, 1)->id);
  return 1;
}

int b_alive(lua_State* L) {
  lua_pushboolean(L, game_of(L).body(check_handle(L, 1)->id) != nullptr);
  return 1;
}

int b_tostring(lua_State* L) {
  const int id = check_handle(L, 1)->id;
  const LooseBody* b = game_of(L).body(id);
  if (b == nullptr)
    lua_pushfstring(L, "game.body %d (removed)", id);
  else
    lua_pushfstring(L, "game.body %d '%s' (%s)", id, b->spec().name.c_str(),
                    to_string(b->spec().shape));
  return 1;
}

int b_eq(lua_State* L) {
  lua_pushboolean(L, check_handle(L, 1)->id == check_handle(L, 2)->id);
  return 1;
}

const luaL_Reg kBodyMethods[] = {{"position", b_position}, {"velocity", b_velocity},
                                 {"state", b_state},       {"push", b_push},
                                 {"remove", b_remove},     {"id", b_id},
                                 {"alive", b_alive},       {nullptr, nullptr}};

// A vector field of 3 finite numbers whose length is at most `limit`; false when absent.
bool get_bounded_vector(lua_State* L, int arg, const char* name, double limit, glm::dvec3* out) {
  double v[3];
  if (!get_vector_field(L, arg, name, 3, v)) return false;
  *out = {v[0], v[1], v[2]};
  if (glm::length(*out) > limit)
    luaL_argerror(L, arg,
                  lua_pushfstring(L, "field '%s': length of at most %f expected", name, limit));
  return true;
}

}  // namespace

// game.spawn_body{shape=, x=, z=, y=, radius=, size=, mass=, velocity=, spin=, name=}
//   -> body, or nil, message
int g_spawn_body(lua_State* L) {
  luaL_checktype(L, 1, LUA_TTABLE);
  static const char* const kFields[] = {"shape", "x",        "z",    "y",    "radius", "size",
                                        "mass",  "velocity", "spin", "name", nullptr};
  check_fields(L, 1, kFields);
  BodySpec s;
  const char* shape = "sphere";
  get_string_field(L, 1, "shape", &shape);
  if (std::strcmp(shape, "box") == 0)
    s.shape = BodyShape::kBox;
  else if (std::strcmp(shape, "sphere") != 0)
    luaL_argerror(L, 1,
                  lua_pushfstring(L, "field 'shape': 'sphere' or 'box' expected, got '%s'", shape));
  if (!get_number_field(L, 1, "x", &s.position.x) || !get_number_field(L, 1, "z", &s.position.z))
    luaL_argerror(L, 1, "fields 'x' and 'z' (metres) are required");
  double radius = 0.6;
  if (get_number_field(L, 1, "radius", &radius)) {
    if (s.shape != BodyShape::kSphere)
      luaL_argerror(L, 1, "field 'radius': for spheres; boxes take 'size'");
    if (radius < 0.05 || radius > 5)
      luaL_argerror(L, 1, "field 'radius': 0.05 .. 5 metres expected");
  }
  glm::dvec3 size(1.0);  // a box's full size, metres
  double v[3];
  if (get_vector_field(L, 1, "size", 3, v)) {
    if (s.shape != BodyShape::kBox)
      luaL_argerror(L, 1, "field 'size': for boxes; spheres take 'radius'");
    size = {v[0], v[1], v[2]};
    for (int i = 0; i < 3; ++i)
      if (size[i] < 0.1 || size[i] > 10)
        luaL_argerror(L, 1, "field 'size': 3 sides of 0.1 .. 10 metres expected");
  }
  s.size = s.shape == BodyShape::kSphere ? glm::dvec3(radius) : size * 0.5;
  if (get_number_field(L, 1, "mass", &s.mass) && !(s.mass > 0 && s.mass <= 1e6))
    luaL_argerror(L, 1, "field 'mass': 0 < kg <= 1e6 expected");
  get_bounded_vector(L, 1, "velocity", 200, &s.velocity);
  get_bounded_vector(L, 1, "spin", 100, &s.angular_velocity);
  const char* name = "";
  get_string_field(L, 1, "name", &name);
  s.name = name[0] != '\0' ? name : (s.shape == BodyShape::kSphere ? "boulder" : "debris");
  GameApi& g = game_of(L);
  const auto ground = g.terrain_ptr()->height(s.position.x, s.position.z);
  // Default height: the body's lowest point 0.5 m above the ground.
  if (!get_number_field(L, 1, "y", &s.position.y) && ground)
    s.position.y = *ground + s.size.y + 0.5;
  auto id = g.spawn_body(s);
  if (!id) {
    lua_pushnil(L);
    lua_pushstring(L, id.error().message.c_str());
    return 2;
  }
  push_body(L, *id);
  return 1;
}

int g_bodies(lua_State* L) {
  const auto& bs = game_of(L).bodies();
  lua_createtable(L, static_cast<int>(bs.size()), 0);
  int i = 0;
  for (const auto& [id, b] : bs) {
    push_body(L, id);
    lua_rawseti(L, -2, ++i);
  }
  return 1;
}

int g_body(lua_State* L) {
  const lua_Integer id = luaL_checkinteger(L, 1);
  if (game_of(L).body(static_cast<int>(id)) == nullptr) return lua_pushnil(L), 1;
  push_body(L, static_cast<int>(id));
  return 1;
}

void register_body_type(lua_State* L, Context* ctx) {
  if (luaL_newmetatable(L, kBodyMeta) == 0) {
    lua_pop(L, 1);
    return;
  }
  lua_newtable(L);
  lua_pushlightuserdata(L, ctx);
  luaL_setfuncs(L, kBodyMethods, 1);
  lua_setfield(L, -2, "__index");
  lua_pushlightuserdata(L, ctx);
  lua_pushcclosure(L, b_tostring, 1);
  lua_setfield(L, -2, "__tostring");
  lua_pushlightuserdata(L, ctx);
  lua_pushcclosure(L, b_eq, 1);
  lua_setfield(L, -2, "__eq");
  lua_pushliteral(L, "game.body");
  lua_setfield(L, -2, "__metatable");
  lua_pop(L, 1);
}

void push_body(lua_State* L, int id) {
  auto* h = static_cast<BodyHandle*>(lua_newuserdatauv(L, sizeof(BodyHandle), 0));
  h->id = id;
  luaL_setmetatable(L, kBodyMeta);
}

}  // namespace game::lua_api
