// Lua userdata `ridgeline.terrain`: queries, batched heights, placement of game objects, the
// change log (edit_version, changes_since).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <glm/geometric.hpp>
#include <new>
#include <optional>
#include <type_traits>

#include "lua_util.h"

namespace ridgeline::lua::detail {
namespace {

const Terrain& live_terrain(lua_State* L) {
  auto* box = static_cast<TerrainBox*>(check_self(L, kTerrainMeta));
  if (!box->terrain) luaL_error(L, "attempt to use a released ridgeline.terrain");
  return *box->terrain;
}

int t_height(lua_State* L) {
  const Terrain& t = live_terrain(L);
  const double x = check_finite(L, 2), z = check_finite(L, 3);
  const std::optional<double> h = t.height(x, z);
  if (!h) return lua_pushnil(L), 1;
  lua_pushnumber(L, *h);
  return 1;
}

int push_normal(lua_State* L, const std::optional<glm::vec3>& n) {
  if (!n) return lua_pushnil(L), 1;
  lua_pushnumber(L, n->x);
  lua_pushnumber(L, n->y);
  lua_pushnumber(L, n->z);
  return 3;
}

int t_normal(lua_State* L) {
  const Terrain& t = live_terrain(L);
  const double x = check_finite(L, 2), z = check_finite(L, 3);
  return push_normal(L, t.face_normal(x, z));
}

int t_smooth_normal(lua_State* L) {
  const Terrain& t = live_terrain(L);
  const double x = check_finite(L, 2), z = check_finite(L, 3);
  return push_normal(L, t.smooth_normal(x, z));
}

void set_number(lua_State* L, const char* key, double v) {
  lua_pushnumber(L, v);
  lua_setfield(L, -2, key);
}

void set_vector(lua_State* L, const char* key, double x, double y, double z) {
  lua_createtable(L, 3, 0);
  lua_pushnumber(L, x);
  lua_rawseti(L, -2, 1);
  lua_pushnumber(L, y);
  lua_rawseti(L, -2, 2);
  lua_pushnumber(L, z);
  lua_rawseti(L, -2, 3);
  lua_setfield(L, -2, key);
}

// terrain:sample(x, z) -> {height=, normal={...}, smooth_normal={...}, material=} or nil
int t_sample(lua_State* L) {
  const Terrain& t = live_terrain(L);
  const double x = check_finite(L, 2), z = check_finite(L, 3);
  const std::optional<SurfaceSample> s = t.sample(x, z);
  if (!s) return lua_pushnil(L), 1;
  lua_createtable(L, 0, 4);
  set_number(L, "height", s->height);
  set_vector(L, "normal", s->face_normal.x, s->face_normal.y, s->face_normal.z);
  set_vector(L, "smooth_normal", s->smooth_normal.x, s->smooth_normal.y, s->smooth_normal.z);
  lua_pushinteger(L, s->material);
  lua_setfield(L, -2, "material");
  return 1;
}

// terrain:heights(xz [, out]) -> out: flat {x1, z1, x2, z2, ...} in, one height per point out.
int t_heights(lua_State* L) {
  const Terrain& t = live_terrain(L);
  luaL_checktype(L, 2, LUA_TTABLE);
  const lua_Unsigned len = lua_rawlen(L, 2);
  if (len % 2 != 0)
    luaL_argerror(L, 2,
                  lua_pushfstring(L, "flat array of x, z pairs expected, got %I numbers",
                                  static_cast<lua_Integer>(len)));
  const lua_Unsigned n = len / 2;
  if (n > kMaxBatchPoints)
    luaL_argerror(
        L, 2,
        lua_pushfstring(L, "at most %I points per call, got %I",
                        static_cast<lua_Integer>(kMaxBatchPoints), static_cast<lua_Integer>(n)));
  if (lua_isnoneornil(L, 3)) {
    lua_settop(L, 2);
    lua_createtable(L, static_cast<int>(n), 0);
  } else {
    luaL_checktype(L, 3, LUA_TTABLE);
    lua_settop(L, 3);
  }
  constexpr int kChunk = 256;
  glm::dvec2 xz[kChunk];  // trivially destructible: safe across a longjmp
  double out[kChunk];
  for (lua_Unsigned base = 0; base < n; base += kChunk) {
    const int m = static_cast<int>(std::min<lua_Unsigned>(kChunk, n - base));
    for (int k = 0; k < m; ++k) {
      const lua_Integer idx = static_cast<lua_Integer>(2 * (base + k) + 1);
      const int tx = lua_rawgeti(L, 2, idx), tz = lua_rawgeti(L, 2, idx + 1);
      if (tx != LUA_TNUMBER || tz != LUA_TNUMBER) {
        const int bad = tx != LUA_TNUMBER ? -2 : -1;
        luaL_argerror(L, 2,
                      lua_pushfstring(L, "entry %I: number expected, got %s", idx + (bad == -1),
                                      luaL_typename(L, bad)));
      }
      xz[k] = {lua_tonumber(L, -2), lua_tonumber(L, -1)};
      lua_pop(L, 2);
    }
    t.heights({xz, static_cast<std::size_t>(m)}, {out, static_cast<std::size_t>(m)});
    for (int k = 0; k < m; ++k) {
      lua_pushnumber(L, out[k]);
      lua_rawseti(L, 3, static_cast<lua_Integer>(base + k + 1));
    }
  }
  return 1;
}

// terrain:raycast(ox, oy, oz, dx, dy, dz [, max]) -> distance, x, y, z, nx, ny, nz or nil
int t_raycast(lua_State* L) {
  const Terrain& t = live_terrain(L);
  double v[6];
  for (int i = 0; i < 6; ++i) v[i] = check_finite(L, i + 2);
  double max = INFINITY;
  if (!lua_isnoneornil(L, 8)) {
    if (lua_type(L, 8) != LUA_TNUMBER) luaL_typeerror(L, 8, "number");
    max = lua_tonumber(L, 8);
    if (std::isnan(max)) luaL_argerror(L, 8, "number or math.huge expected, got nan");
  }
  const std::optional<RayHit> hit = t.raycast({v[0], v[1], v[2]}, {v[3], v[4], v[5]}, max);
  if (!hit) return lua_pushnil(L), 1;
  lua_pushnumber(L, hit->distance);
  lua_pushnumber(L, hit->point.x);
  lua_pushnumber(L, hit->point.y);
  lua_pushnumber(L, hit->point.z);
  lua_pushnumber(L, hit->normal.x);
  lua_pushnumber(L, hit->normal.y);
  lua_pushnumber(L, hit->normal.z);
  return 7;
}

// Frame of heading h (radians about +y, counterclockwise from above, 0 along +z): the vehicle's
// local (a, b) offset (a along its +x, b forward) goes to world (a cos h + b sin h, -a sin h + b
// cos h).
void to_world(double h, double a, double b, double* dx, double* dz) {
  *dx = a * std::cos(h) + b * std::sin(h);
  *dz = -a * std::sin(h) + b * std::cos(h);
}

struct Placement {
  double x, y, z, pitch, roll;
  glm::dvec3 forward, up, right;
};

// Fits a plane h = c0 + cu * u + cv * v to a 3 x 3 grid of surface heights over the footprint
// (u across, v along the heading; least squares on a symmetric grid), then lifts it until no
// grid point is above it: the box rests on the highest contact. False when any point is off
// the terrain.
bool place_box(const Terrain& t, double x, double z, double length, double width, double h,
               Placement* p) noexcept {
  double sum = 0, su = 0, sv = 0, suu = 0, svv = 0, hs[9], us[9], vs[9];
  int k = 0;
  for (int i = -1; i <= 1; ++i) {
    for (int j = -1; j <= 1; ++j, ++k) {
      const double u = i * width / 2, v = j * length / 2;
      double dx, dz;
      to_world(h, u, v, &dx, &dz);
      const std::optional<double> hh = t.height(x + dx, z + dz);
      if (!hh) return false;
      hs[k] = *hh, us[k] = u, vs[k] = v;
      sum += *hh, su += u * *hh, sv += v * *hh, suu += u * u, svv += v * v;
    }
  }
  const double cu = suu > 0 ? su / suu : 0, cv = svv > 0 ? sv / svv : 0;
  double c0 = sum / 9, lift = -INFINITY;
  for (k = 0; k < 9; ++k) lift = std::max(lift, hs[k] - (c0 + cu * us[k] + cv * vs[k]));
  c0 += lift;
  double fx, fz, sx, sz;
  to_world(h, 0, 1, &fx, &fz);
  to_world(h, 1, 0, &sx, &sz);
  const glm::dvec3 f = glm::normalize(glm::dvec3(fx, cv, fz));  // forward along the plane
  const glm::dvec3 s = glm::normalize(glm::dvec3(sx, cu, sz));  // local +x along the plane
  p->up = glm::normalize(glm::cross(f, s));
  p->forward = f;
  p->right = glm::normalize(glm::cross(f, p->up));
  p->x = x, p->y = c0, p->z = z;
  p->pitch = std::asin(std::clamp(p->forward.y, -1.0, 1.0));
  p->roll = std::asin(std::clamp(-p->right.y, -1.0, 1.0));
  return true;
}

// terrain:place(x, z, {length=, width=, heading=}) -> placement table or nil, message
int t_place(lua_State* L) {
  const Terrain& t = live_terrain(L);
  const double x = check_finite(L, 2), z = check_finite(L, 3);
  luaL_checktype(L, 4, LUA_TTABLE);
  static const char* const kFields[] = {"length", "width", "heading", nullptr};
  check_fields(L, 4, kFields);
  double length = 0, width = 0, heading = 0;
  if (!get_number_field(L, 4, "length", &length) || length <= 0 || length > 1e6)
    luaL_argerror(L, 4, "field 'length': number in (0, 1e6] metres expected");
  if (!get_number_field(L, 4, "width", &width) || width <= 0 || width > 1e6)
    luaL_argerror(L, 4, "field 'width': number in (0, 1e6] metres expected");
  get_number_field(L, 4, "heading", &heading);
  Placement p;
  if (!place_box(t, x, z, length, width, heading, &p)) {
    lua_pushnil(L);
    lua_pushliteral(L, "footprint leaves the terrain");
    return 2;
  }
  lua_createtable(L, 0, 9);
  set_number(L, "x", p.x);
  set_number(L, "y", p.y);
  set_number(L, "z", p.z);
  set_number(L, "heading", heading);
  set_number(L, "pitch", p.pitch);
  set_number(L, "roll", p.roll);
  set_vector(L, "forward", p.forward.x, p.forward.y, p.forward.z);
  set_vector(L, "up", p.up.x, p.up.y, p.up.z);
  set_vector(L, "right", p.right.x, p.right.y, p.right.z);
  return 1;
}

// terrain:contacts(x, z, heading, offsets) -> array: per offset {x=, y=, z=, nx=, ny=, nz=,
// material=} or false (off the terrain). One vertical ray per wheel, cast from above the highest
// point of the terrain.
int t_contacts(lua_State* L) {
  const Terrain& t = live_terrain(L);
  const double x = check_finite(L, 2), z = check_finite(L, 3), heading = check_finite(L, 4);
  luaL_checktype(L, 5, LUA_TTABLE);
  const lua_Unsigned n = lua_rawlen(L, 5);
  if (n > kMaxContacts)
    luaL_argerror(
        L, 5,
        lua_pushfstring(L, "at most %I offsets per call, got %I",
                        static_cast<lua_Integer>(kMaxContacts), static_cast<lua_Integer>(n)));
  const WorldInfo& hf = t.info();
  const double top = hf.height_offset + hf.max_local + 1.0;
  const double depth = hf.max_local - hf.min_local + 2.0;
  lua_settop(L, 5);
  lua_createtable(L, static_cast<int>(n), 0);
  for (lua_Unsigned i = 1; i <= n; ++i) {
    lua_rawgeti(L, 5, static_cast<lua_Integer>(i));
    double o[2];
    for (int c = 0; c < 2; ++c) {
      int isnum = 0;
      if (lua_type(L, -1) == LUA_TTABLE) {
        isnum = lua_rawgeti(L, -1, c + 1) == LUA_TNUMBER;  // no string coercion
        o[c] = lua_tonumber(L, -1);
        lua_pop(L, 1);
      }
      if (!isnum || !std::isfinite(o[c]))
        luaL_argerror(L, 5,
                      lua_pushfstring(L, "offset %I: {x, z} of finite numbers expected",
                                      static_cast<lua_Integer>(i)));
    }
    lua_pop(L, 1);
    double dx, dz;
    to_world(heading, o[0], o[1], &dx, &dz);
    const std::optional<RayHit> hit = t.raycast({x + dx, top, z + dz}, {0, -1, 0}, depth);
    if (!hit) {
      lua_pushboolean(L, 0);
    } else {
      lua_createtable(L, 0, 7);
      set_number(L, "x", hit->point.x);
      set_number(L, "y", hit->point.y);
      set_number(L, "z", hit->point.z);
      set_number(L, "nx", hit->normal.x);
      set_number(L, "ny", hit->normal.y);
      set_number(L, "nz", hit->normal.z);
      lua_pushinteger(L, hit->material);
      lua_setfield(L, -2, "material");
    }
    lua_rawseti(L, -2, static_cast<lua_Integer>(i));
  }
  return 1;
}

// terrain:bounds() -> min_x, min_z, max_x, max_z, min_height, max_height (metres)
int t_bounds(lua_State* L) {
  const WorldInfo& hf = live_terrain(L).info();
  lua_pushnumber(L, hf.origin_x);
  lua_pushnumber(L, hf.origin_z);
  lua_pushnumber(L, hf.origin_x + hf.extent_x());
  lua_pushnumber(L, hf.origin_z + hf.extent_z());
  lua_pushnumber(L, hf.height_offset + hf.min_local);
  lua_pushnumber(L, hf.height_offset + hf.max_local);
  return 6;
}

// terrain:edit_version() -> integer: 0 as created, one more per edit or load that changed heights
int t_edit_version(lua_State* L) {
  lua_pushinteger(L, static_cast<lua_Integer>(live_terrain(L).edit_version()));
  return 1;
}

// Copies at most `room` entries of changes_since(since) into `out` (memory Lua owns) and returns
// how many there are, or -1 with a message in `err`. No Lua calls: the answer's vector is gone
// before the caller allocates or raises (correct under longjmp).
static_assert(std::is_trivially_copyable_v<TerrainChange>);
long long copy_changes(const Terrain& t, std::uint64_t since, TerrainChange* out, std::size_t room,
                       std::uint64_t* version, bool* trimmed, char* err) noexcept {
  try {
    const TerrainChanges c = t.changes_since(since);
    *version = c.version;
    *trimmed = c.trimmed;
    for (std::size_t k = 0; k < c.changes.size() && k < room; ++k) out[k] = c.changes[k];
    return static_cast<long long>(c.changes.size());
  } catch (const std::exception& ex) {
    copy_error(err, ex.what());
    return -1;
  }
}

// terrain:changes_since(version) -> changes, version, trimmed; changes = {{version=, min_x=,
// min_y=, min_z=, max_x=, max_y=, max_z=, i0=, j0=, i1=, j1=}, ...}
int t_changes_since(lua_State* L) {
  const Terrain& t = live_terrain(L);
  const lua_Integer since = luaL_checkinteger(L, 2);
  if (since < 0) luaL_argerror(L, 2, "version >= 0 expected (an earlier edit_version())");
  char err[kErrSize];
  std::uint64_t version = 0;
  bool trimmed = false;
  const long long n = copy_changes(t, std::uint64_t(since), nullptr, 0, &version, &trimmed, err);
  if (n < 0) return luaL_error(L, "%s", err);
  auto* buf = static_cast<TerrainChange*>(
      lua_newuserdatauv(L, std::size_t(n) * sizeof(TerrainChange) + 1, 0));
  const long long again =
      copy_changes(t, std::uint64_t(since), buf, std::size_t(n), &version, &trimmed, err);
  if (again != n) return luaL_error(L, "%s", again < 0 ? err : "changes_since: terrain changed");
  lua_createtable(L, static_cast<int>(n), 0);
  for (long long k = 0; k < n; ++k) {
    const TerrainChange& c = buf[k];
    lua_createtable(L, 0, 11);
    lua_pushinteger(L, static_cast<lua_Integer>(c.version));
    lua_setfield(L, -2, "version");
    set_number(L, "min_x", c.box.min.x);
    set_number(L, "min_y", c.box.min.y);
    set_number(L, "min_z", c.box.min.z);
    set_number(L, "max_x", c.box.max.x);
    set_number(L, "max_y", c.box.max.y);
    set_number(L, "max_z", c.box.max.z);
    const std::int64_t ij[4] = {c.vertices.i0, c.vertices.j0, c.vertices.i1, c.vertices.j1};
    const char* const names[4] = {"i0", "j0", "i1", "j1"};
    for (int q = 0; q < 4; ++q) {
      lua_pushinteger(L, static_cast<lua_Integer>(ij[q]));
      lua_setfield(L, -2, names[q]);
    }
    lua_rawseti(L, -2, static_cast<lua_Integer>(k) + 1);
  }
  lua_pushinteger(L, static_cast<lua_Integer>(version));
  lua_pushboolean(L, trimmed);
  return 3;
}

int t_release(lua_State* L) {
  auto* box = static_cast<TerrainBox*>(check_self(L, kTerrainMeta));
  box->terrain.reset();
  box->landscape.reset();
  box->root.reset();
  box->terrain_charge.reset();
  box->landscape_charge.reset();
  box->budget.reset();
  return 0;
}

int t_tostring(lua_State* L) {
  auto* box = static_cast<TerrainBox*>(check_self(L, kTerrainMeta));
  if (!box->terrain) {
    lua_pushliteral(L, "ridgeline.terrain (released)");
    return 1;
  }
  const WorldInfo& hf = box->terrain->info();
  char text[160];
  std::snprintf(text, sizeof text, "ridgeline.terrain (%u x %u samples, %g x %g m spacing)",
                hf.width, hf.height, hf.spacing_x, hf.spacing_z);
  lua_pushstring(L, text);
  return 1;
}

const luaL_Reg kMethods[] = {{"height", t_height},
                             {"normal", t_normal},
                             {"smooth_normal", t_smooth_normal},
                             {"sample", t_sample},
                             {"heights", t_heights},
                             {"raycast", t_raycast},
                             {"place", t_place},
                             {"contacts", t_contacts},
                             {"bounds", t_bounds},
                             {"new_view", new_view},
                             {"deform", t_deform},
                             {"get_heights", t_get_heights},
                             {"set_heights", t_set_heights},
                             {"save_edits", t_save_edits},
                             {"load_edits", t_load_edits},
                             {"edit_version", t_edit_version},
                             {"changes_since", t_changes_since},
                             {"release", t_release},
                             {nullptr, nullptr}};
const luaL_Reg kMeta[] = {
    {"__gc", t_release}, {"__close", t_release}, {"__tostring", t_tostring}, {nullptr, nullptr}};

}  // namespace

TerrainBox* push_terrain_box(lua_State* L) {
  void* mem = lua_newuserdatauv(L, sizeof(TerrainBox), 0);
  auto* box = new (mem) TerrainBox();  // empty shared_ptrs: nothing to leak if the next call raises
  push_metatable(L, kTerrainMeta, kMethods, kMeta);
  lua_setmetatable(L, -2);
  return box;
}

}  // namespace ridgeline::lua::detail
