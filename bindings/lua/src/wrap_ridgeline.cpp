// The `ridgeline` module table: loading terrains; the per-module configuration userdata.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <new>

#include "lua_util.h"
#include "ridgeline/detail.h"
#include "ridgeline/io.h"
#include "ridgeline/world_file.h"

namespace ridgeline::lua::detail {
namespace {

ConfigBox* config_of(lua_State* L) {
  return static_cast<ConfigBox*>(lua_touserdata(L, lua_upvalueindex(1)));
}

// Charges a terrain made for a script to the module's budget (no Lua calls).
bool charge_terrain(TerrainBox* box, const std::shared_ptr<ObjectBudget>& budget, std::size_t bytes,
                    char* err) noexcept {
  try {
    box->budget = budget;
    box->terrain_charge = std::make_shared<Charge>(budget, bytes);
    return true;
  } catch (const std::exception& e) {
    box->terrain.reset();
    copy_error(err, e.what());
    return false;
  }
}

// Plain data read from the option table of ridgeline.load before any C++ object exists.
struct LoadArgs {
  const char* heightmap = nullptr;  // kept alive by the option table on the stack
  double spacing[2] = {1, 1};
  double origin[2] = {0, 0};
  bool has_spacing = false, has_origin = false;  // else a GeoTIFF's own placement is used
  double height_scale = 1, height_offset = 0;
  bool has_nodata = false;
  double nodata = 0;
  FillPolicy fill = FillPolicy::kRefuse;
  bool alpha_nodata = false;
  double detail_levels = 0, detail_seed = 1, detail_amplitude = 0, detail_gain = 0;
  bool has_amplitude = false, has_gain = false;
  io::RawFormat raw;  // width 0: not a raw file
  std::uint64_t max_samples = 0;  // 0: the module's cap
};

std::string fmt_spacing(double v) {
  char text[128];
  std::snprintf(text, sizeof text, "spacing %g m is outside 1e-6 .. 1e6 m", v);
  return text;
}

bool do_load(const ConfigBox& config, const LoadArgs& a, TerrainBox* box, std::size_t* charge_bytes,
             char* err) noexcept {
  try {
    char path[4096];
    if (!resolve_path(config, a.heightmap, path, sizeof path, err)) return false;
    // The range of docs/data_model.md ("Placement"), as `ridge --spacing` checks it (values
    // <= 0 get the heightfield's own message).
    for (const double v : a.spacing)
      if (a.has_spacing && v > 0 && (v < 1e-6 || v > 1e6)) {
        copy_error(err, fmt_spacing(v).c_str());
        return false;
      }
    io::LoadOptions options;
    HeightfieldDesc& p = options.placement;
    p.spacing_x = a.spacing[0];
    p.spacing_z = a.spacing[1];
    p.origin_x = a.origin[0];
    p.origin_z = a.origin[1];
    options.spacing_from_file = !a.has_spacing;
    options.origin_from_file = !a.has_origin;
    p.height_scale = a.height_scale;
    p.height_offset = a.height_offset;
    if (a.has_nodata) p.nodata = a.nodata;
    p.fill = a.fill;
    options.alpha_nodata = a.alpha_nodata;
    p.max_samples = a.max_samples != 0 ? a.max_samples : config.max_samples;
    auto hf = io::load_heightmap(path, options, a.raw.width != 0 ? &a.raw : nullptr);
    if (!hf) {
      // Under confinement, name the file as the script gave it, not the host's full path.
      std::string m = hf.error().message;
      if (m.find("HeightfieldDesc::max_samples") != std::string::npos) {
        const std::uint64_t limit = std::max(config.max_samples_limit, config.max_samples);
        char more[320];
        if (p.max_samples < limit)
          std::snprintf(more, sizeof more,
                        "; raise it with ridgeline.load{max_samples = N} (up to %llu here, "
                        "HostOptions::max_samples_limit), or bake the map (ridge bake) and open it "
                        "paged with ridgeline.open_world",
                        static_cast<unsigned long long>(limit));
        else
          std::snprintf(more, sizeof more,
                        "; this host allows at most %llu (HostOptions::max_samples_limit): bake "
                        "the map (ridge bake) and open it paged with ridgeline.open_world",
                        static_cast<unsigned long long>(limit));
        m += more;
      }
      if (config.confine_paths && std::strstr(m.c_str(), path) != nullptr) {
        std::string msg = m;
        const auto at = msg.find(path);
        msg.replace(at, std::strlen(path), a.heightmap);
        copy_error(err, msg.c_str());
      } else {
        copy_error(err, m.c_str());
      }
      return false;
    }
    DetailParams detail;
    detail.levels = static_cast<std::uint32_t>(a.detail_levels);
    detail.seed = static_cast<std::uint64_t>(a.detail_seed);
    if (a.has_amplitude) detail.amplitude = a.detail_amplitude;
    if (a.has_gain) detail.gain = a.detail_gain;
    // Scripts never wait for tiles: two workers generate them; views hold coarser meanwhile.
    DetailCacheDesc cache;
    cache.worker_threads = 2;
    // Under an object budget the tiles get a quarter of it (charged in full: the cache may fill).
    if (config.budget && config.budget->limit != 0)
      cache.budget_bytes =
          std::min(cache.budget_bytes, std::max(config.budget->limit / 4, std::size_t{4} << 20));
    auto t = Terrain::create(std::move(*hf), detail, cache);
    if (!t) {
      copy_error(err, t.error().message.c_str());
      return false;
    }
    box->terrain = std::move(*t);
    *charge_bytes = terrain_charge_bytes(*box->terrain, detail.levels > 0 ? cache.budget_bytes : 0);
    set_path_rules(box, config);
    return true;
  } catch (const std::exception& e) {
    copy_error(err, e.what());
    return false;
  }
}

// The `raw = {width=, height=, type=}` field of ridgeline.load (a headerless little-endian file).
void read_raw_format(lua_State* L, int t, io::RawFormat& raw) {
  const int type = lua_getfield(L, t, "raw");
  if (type == LUA_TNIL) {
    lua_pop(L, 1);
    return;
  }
  if (type != LUA_TTABLE)
    luaL_argerror(L, t, lua_pushfstring(L, "field 'raw': table {width=, height=, type=} expected, "
                                           "got %s", luaL_typename(L, -1)));
  const int r = lua_gettop(L);
  static const char* const kRawFields[] = {"width", "height", "type", nullptr};
  check_fields(L, r, kRawFields);
  double size[2] = {0, 0};
  const char* names[2] = {"width", "height"};
  for (int k = 0; k < 2; ++k)
    if (!get_number_field(L, r, names[k], &size[k]) || size[k] != std::floor(size[k]) ||
        size[k] < 2 || size[k] > 4294967295.0)
      luaL_argerror(L, t, lua_pushfstring(L, "field 'raw.%s': whole number >= 2 expected",
                                          names[k]));
  raw.width = std::uint32_t(size[0]);
  raw.height = std::uint32_t(size[1]);
  if (lua_getfield(L, r, "type") != LUA_TNIL) {
    const char* text = lua_type(L, -1) == LUA_TSTRING ? lua_tostring(L, -1) : "";
    if (std::strcmp(text, "u16") == 0)
      raw.type = io::RawType::kU16;
    else if (std::strcmp(text, "f32") == 0)
      raw.type = io::RawType::kF32;
    else
      luaL_argerror(L, t, "field 'raw.type': 'u16' or 'f32' expected");
  }
  lua_pop(L, 2);
}

// Opens a baked world for a script: plain data in, the terrain or a message out (no Lua calls).
bool do_open_world(const ConfigBox& config, const char* name, const WorldCacheDesc& desc,
                   TerrainBox* box, char* err) noexcept {
  try {
    char path[4096];
    if (!resolve_path(config, name, path, sizeof path, err)) return false;
    auto source = io::open_world(path);
    if (!source) {
      std::string m = source.error().message;
      if (config.confine_paths)
        for (auto at = m.find(path); at != std::string::npos; at = m.find(path))
          m.replace(at, std::strlen(path), name);
      copy_error(err, m.c_str());
      return false;
    }
    auto t = Terrain::open(std::move(*source), desc);
    if (!t) {
      copy_error(err, t.error().message.c_str());
      return false;
    }
    box->terrain = std::move(*t);
    set_path_rules(box, config);
    return true;
  } catch (const std::exception& e) {
    copy_error(err, e.what());
    return false;
  }
}

// ridgeline.open_world{world=, cache_mb=, workers=} -> terrain or nil, message: a baked world
// (ridge bake) paged in under a cache budget.
int r_open_world(lua_State* L) {
  const ConfigBox* config = config_of(L);
  luaL_checktype(L, 1, LUA_TTABLE);
  static const char* const kFields[] = {"world", "cache_mb", "workers", nullptr};
  check_fields(L, 1, kFields);
  lua_settop(L, 1);
  if (lua_getfield(L, 1, "world") != LUA_TSTRING)
    luaL_argerror(L, 1, lua_pushfstring(L, "field 'world': string expected, got %s",
                                        luaL_typename(L, -1)));
  const char* name = lua_tostring(L, -1);  // stays at index 2
  if (std::strlen(name) != lua_rawlen(L, -1))
    luaL_argerror(L, 1, "field 'world': embedded zero in file name");
  WorldCacheDesc desc;
  // Under an object budget the pages get a quarter of it unless the script asks.
  if (config->budget && config->budget->limit != 0)
    desc.budget_bytes =
        std::min(desc.budget_bytes, std::max(config->budget->limit / 4, std::size_t{4} << 20));
  double v = 0;
  if (get_number_field(L, 1, "cache_mb", &v)) {
    if (!(v >= 4 && v <= 1048576) || v != std::floor(v))
      luaL_argerror(L, 1, "field 'cache_mb': whole number in 4..1048576 expected");
    desc.budget_bytes = std::size_t(v) << 20;
  }
  if (get_number_field(L, 1, "workers", &v)) {
    if (!(v >= 0 && v <= 8) || v != std::floor(v))
      luaL_argerror(L, 1, "field 'workers': whole number in 0..8 expected");
    desc.worker_threads = std::uint32_t(v);
  }
  // The cache may fill to its budget: reserved before anything is read.
  reserve_objects(L, config->budget, desc.budget_bytes, "open_world");
  TerrainBox* box = push_terrain_box(L);
  char err[kErrSize];
  if (!do_open_world(*config, name, desc, box, err)) {
    lua_pushnil(L);
    lua_pushstring(L, err);
    return 2;
  }
  const std::size_t bytes = paged_terrain_charge_bytes(*box->terrain, desc.budget_bytes);
  if (!make_room(L, config->budget, bytes)) {
    box->terrain.reset();
    char detail[96];
    std::snprintf(detail, sizeof detail, "the world's page cache needs %.1f MiB",
                  double(bytes) / (1024.0 * 1024.0));
    return object_budget_error(L, *config->budget, "open_world", detail);
  }
  if (!charge_terrain(box, config->budget, bytes, err)) return luaL_error(L, "open_world: %s", err);
  box->cache_bytes = desc.budget_bytes;
  return 1;
}

// ridgeline.load{heightmap=, spacing=, origin=, height_scale=, height_offset=, nodata=, fill=}
//   -> terrain or nil, message
int r_load(lua_State* L) {
  const ConfigBox* config = config_of(L);
  luaL_checktype(L, 1, LUA_TTABLE);
  static const char* const kFields[] = {
      "heightmap",   "spacing",       "origin",      "height_scale",     "height_offset",
      "nodata",      "fill",          "detail_levels", "detail_seed",    "detail_amplitude",
      "detail_gain", "raw",           "max_samples",   "alpha_nodata",  nullptr};
  check_fields(L, 1, kFields);
  lua_settop(L, 1);
  LoadArgs a;
  if (lua_getfield(L, 1, "heightmap") != LUA_TSTRING)
    luaL_argerror(
        L, 1,
        lua_pushfstring(L, "field 'heightmap': string expected, got %s", luaL_typename(L, -1)));
  a.heightmap = lua_tostring(L, -1);  // stays at index 2 while we work
  if (std::strlen(a.heightmap) != lua_rawlen(L, -1))
    luaL_argerror(L, 1, "field 'heightmap': embedded zero in file name");
  if (lua_getfield(L, 1, "spacing") == LUA_TTABLE) {
    lua_pop(L, 1);
    a.has_spacing = get_vector_field(L, 1, "spacing", 2, a.spacing);
  } else {
    lua_pop(L, 1);
    a.has_spacing = get_number_field(L, 1, "spacing", &a.spacing[0]);
    if (a.has_spacing) a.spacing[1] = a.spacing[0];
  }
  a.has_origin = get_vector_field(L, 1, "origin", 2, a.origin);
  get_number_field(L, 1, "height_scale", &a.height_scale);
  get_number_field(L, 1, "height_offset", &a.height_offset);
  a.has_nodata = get_number_field(L, 1, "nodata", &a.nodata);
  const int fill = lua_getfield(L, 1, "fill");
  if (fill != LUA_TNIL) {
    const char* f = fill == LUA_TSTRING ? lua_tostring(L, -1) : "";
    if (std::strcmp(f, "nearest") == 0)
      a.fill = FillPolicy::kNearest;
    else if (std::strcmp(f, "hole") == 0)
      a.fill = FillPolicy::kHole;
    else if (std::strcmp(f, "refuse") != 0)
      luaL_argerror(L, 1, "field 'fill': 'refuse', 'nearest' or 'hole' expected");
  }
  lua_pop(L, 1);
  const int alpha = lua_getfield(L, 1, "alpha_nodata");
  if (alpha != LUA_TNIL && alpha != LUA_TBOOLEAN)
    luaL_argerror(L, 1, "field 'alpha_nodata': boolean expected");
  a.alpha_nodata = lua_toboolean(L, -1) != 0;
  lua_pop(L, 1);
  if (get_number_field(L, 1, "detail_levels", &a.detail_levels) &&
      (a.detail_levels != std::floor(a.detail_levels) || a.detail_levels < 0 ||
       a.detail_levels > kMaxDetailLevels))
    luaL_argerror(L, 1, "field 'detail_levels': whole number in 0..12 expected");
  if (get_number_field(L, 1, "detail_seed", &a.detail_seed) &&
      (a.detail_seed != std::floor(a.detail_seed) || a.detail_seed < 0 || a.detail_seed > 9007199254740992.0))
    luaL_argerror(L, 1, "field 'detail_seed': whole number in 0..2^53 expected");
  a.has_amplitude = get_number_field(L, 1, "detail_amplitude", &a.detail_amplitude);
  a.has_gain = get_number_field(L, 1, "detail_gain", &a.detail_gain);
  read_raw_format(L, 1, a.raw);
  double max_samples = 0;
  if (get_number_field(L, 1, "max_samples", &max_samples)) {
    const std::uint64_t limit = std::max(config->max_samples_limit, config->max_samples);
    if (!(max_samples >= 1) || max_samples != std::floor(max_samples) || max_samples > 9.0e15)
      luaL_argerror(L, 1, "field 'max_samples': whole number >= 1 expected");
    if (max_samples > double(limit))
      luaL_argerror(L, 1, lua_pushfstring(L, "field 'max_samples': %I is above this host's limit "
                                             "%I (HostOptions::max_samples_limit)",
                                          static_cast<lua_Integer>(max_samples),
                                          static_cast<lua_Integer>(std::min<std::uint64_t>(
                                              limit, std::uint64_t{1} << 62))));
    a.max_samples = std::uint64_t(max_samples);
  }
  TerrainBox* box = push_terrain_box(L);
  char err[kErrSize];
  std::size_t bytes = 0;
  if (!do_load(*config, a, box, &bytes, err)) {
    lua_pushnil(L);
    lua_pushstring(L, err);
    return 2;
  }
  // The size is known once loaded: a terrain past the budget is dropped before the error.
  if (!make_room(L, config->budget, bytes)) {
    box->terrain.reset();
    char detail[96];
    std::snprintf(detail, sizeof detail, "the terrain needs %.1f MiB",
                  double(bytes) / (1024.0 * 1024.0));
    return object_budget_error(L, *config->budget, "load", detail);
  }
  if (!charge_terrain(box, config->budget, bytes, err)) return luaL_error(L, "load: %s", err);
  account_memory(L, box->terrain->memory_bytes());
  return 1;
}

// Generates the pristine default terrain once per module table, charged to its budget for the
// module's lifetime.
bool make_original(ConfigBox* config, char* err) noexcept {
  try {
    if (config->default_terrain) return true;
    auto hf = make_default_heightfield();
    if (!hf) {
      copy_error(err, hf.error().message.c_str());
      return false;
    }
    config->default_terrain = Terrain::create(std::move(*hf)).value();
    config->default_charge =
        std::make_shared<Charge>(config->budget, config->default_terrain->memory_bytes());
    return true;
  } catch (const std::exception& e) {
    copy_error(err, e.what());
    return false;
  }
}

bool make_default(ConfigBox* config, TerrainBox* box, std::size_t bytes, char* err) noexcept {
  try {
    box->terrain = config->default_terrain->clone();
    set_path_rules(box, *config);
    return charge_terrain(box, config->budget, bytes, err);
  } catch (const std::exception& e) {
    copy_error(err, e.what());
    return false;
  }
}

// ridgeline.default_terrain() -> terrain: a fresh copy of the built-in 2048 m terrain on every
// call (generated once per module table, then cloned: a few milliseconds and ~6 MB each), so an
// edit one script makes is never seen by another and a released terrain is simply gone.
int r_default_terrain(lua_State* L) {
  ConfigBox* config = config_of(L);
  char err[kErrSize];
  if (!make_original(config, err)) return luaL_error(L, "default_terrain: %s", err);
  // A copy shares the original's pages (charged once, with the module) until it edits them.
  const std::size_t bytes = terrain_charge_bytes(*config->default_terrain, 0, true);
  reserve_objects(L, config->budget, bytes, "default_terrain");
  TerrainBox* box = push_terrain_box(L);
  if (!make_default(config, box, bytes, err)) return luaL_error(L, "default_terrain: %s", err);
  account_memory(L, box->terrain->memory_bytes());
  return 1;
}

int config_gc(lua_State* L) {
  auto* c = static_cast<ConfigBox*>(luaL_checkudata(L, 1, kConfigMeta));
  c->default_terrain.reset();
  c->default_charge.reset();
  c->budget.reset();
  return 0;
}

const luaL_Reg kFunctions[] = {
    {"load", r_load},
    {"open_world", r_open_world},
    {"default_terrain", r_default_terrain},
    {"budget_controller", new_budget_controller},
    {"save_edits", r_save_edits},
    {"load_edits", r_load_edits},
    {nullptr, nullptr}};

}  // namespace
}  // namespace ridgeline::lua::detail

namespace ridgeline::lua {

void push_terrain(lua_State* L, std::shared_ptr<Terrain> terrain) {
  detail::TerrainBox* box = detail::push_terrain_box(L);
  // No Lua call after the push that can raise: nothing can longjmp over these.
  box->terrain = std::move(terrain);
  box->budget = detail::object_budget_of(L);
}

std::size_t object_memory_used(lua_State* L) {
  const std::shared_ptr<detail::ObjectBudget> budget = detail::object_budget_of(L);
  return budget ? budget->used : 0;
}

int open_module(lua_State* L, const ModuleConfig& config) {
  using namespace detail;
  lua_createtable(L, 0, 8);
  void* mem = lua_newuserdatauv(L, sizeof(ConfigBox), 0);
  auto* box = new (mem) ConfigBox();
  if (luaL_newmetatable(L, kConfigMeta)) {
    lua_pushcfunction(L, config_gc);
    lua_setfield(L, -2, "__gc");
    lua_pushliteral(L, "ridgeline.config");
    lua_setfield(L, -2, "__metatable");
  }
  lua_setmetatable(L, -2);
  box->confine_paths = config.confine_paths;
  box->max_samples = config.max_samples;
  box->max_samples_limit = std::max(config.max_samples_limit, config.max_samples);
  try {
    box->budget = std::make_shared<ObjectBudget>();
  } catch (const std::exception&) {
    box->budget.reset();
  }
  if (!box->budget) return luaL_error(L, "ridgeline: not enough memory");
  box->budget->limit = config.object_memory_limit;
  register_config(L, -1);
  std::strncpy(box->root, config.root != nullptr ? config.root : "", sizeof box->root - 1);
  luaL_setfuncs(L, kFunctions, 1);  // the config is upvalue 1 of every function
  lua_pushinteger(L, static_cast<lua_Integer>(kMaxBatchPoints));
  lua_setfield(L, -2, "max_batch_points");
  lua_pushinteger(L, static_cast<lua_Integer>(kMaxContacts));
  lua_setfield(L, -2, "max_contacts");
  lua_pushliteral(L, "0.1.0");
  lua_setfield(L, -2, "version");
  return 1;
}

}  // namespace ridgeline::lua
