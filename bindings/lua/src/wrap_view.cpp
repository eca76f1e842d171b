// Lua userdata `ridgeline.view`: the ROAM mesh of one camera over a terrain (docs/roam.md).
#include <algorithm>
#include <cstdio>
#include <exception>
#include <new>

#include "lua_util.h"

namespace ridgeline::lua::detail {
namespace {

ViewBox* live_view(lua_State* L) {
  auto* box = static_cast<ViewBox*>(check_self(L, kViewMeta));
  if (!box->view) luaL_error(L, "attempt to use a released ridgeline.view");
  return box;
}

const char* const kCameraFields[] = {"eye",      "target", "up",  "fov_y",
                                     "viewport", "near",   "far", nullptr};
const char* const kNewViewFields[] = {"eye",       "target",    "up",   "fov_y",
                                      "viewport",  "near",      "far",  "threshold",
                                      "triangles", "budget_ms", nullptr};

// Applies the camera fields present in the table at `arg` to `cam` (absent fields keep their
// value). Raises on a wrong type.
void read_camera(lua_State* L, int arg, Camera* cam) {
  double v[3];
  if (get_vector_field(L, arg, "eye", 3, v)) cam->eye = {v[0], v[1], v[2]};
  if (get_vector_field(L, arg, "target", 3, v)) cam->target = {v[0], v[1], v[2]};
  if (get_vector_field(L, arg, "up", 3, v)) cam->up = {v[0], v[1], v[2]};
  get_number_field(L, arg, "fov_y", &cam->fov_y_deg);
  if (get_vector_field(L, arg, "viewport", 2, v)) {
    if (v[0] < 1 || v[1] < 1 || v[0] > 65536 || v[1] > 65536)
      luaL_argerror(L, arg, "field 'viewport': {width, height} in 1 .. 65536 pixels expected");
    cam->viewport = {static_cast<int>(v[0]), static_cast<int>(v[1])};
  }
  get_number_field(L, arg, "near", &cam->near_m);
  get_number_field(L, arg, "far", &cam->far_m);
}

bool camera_ok(const Camera& cam, char* err) noexcept {
  try {
    const Status s = validate_camera(cam);
    if (!s) copy_error(err, s.message().c_str());
    return s.ok();
  } catch (const std::exception& e) {
    copy_error(err, e.what());
    return false;
  }
}

// Raises `bad argument #arg (camera: ...)` after the helper's objects are gone (validate_camera's
// messages already begin with "camera: ").
void check_camera(lua_State* L, int arg, const Camera& cam) {
  char err[kErrSize];
  if (!camera_ok(cam, err)) luaL_argerror(L, arg, err);
}

std::uint32_t clamp_triangles(double t) {
  if (t <= 0 || t > kMaxViewTriangles) return kMaxViewTriangles;
  return static_cast<std::uint32_t>(t);
}

// ---- the object budget (ModuleConfig::object_memory_limit) ----
// A view's memory (RoamStats::memory_bytes + output_bytes) is a part per patch plus a part per
// leaf triangle: measured on the default terrain, about 2.6 KiB a patch and 110 bytes a triangle
// (up to 170 with the vectors' spare capacity); the estimates below are above both.
constexpr std::size_t kViewBytesPerPatch = 3 << 10, kViewBytesPerTriangle = 192;
constexpr std::size_t kLandscapeLogBytes = 64 << 10;  // the landscape's log of changed regions

std::size_t patches_of(const Terrain& t, std::uint32_t exponent) {
  const std::size_t p = std::size_t{1} << exponent;
  const WorldInfo& info = t.info();
  return ((info.width - 1 + p - 1) / p) * ((info.height - 1 + p - 1) / p);
}

// The patches of a landscape made with the default exponent (6, raised until at most 64 patches
// a side).
std::size_t default_patches(const Terrain& t) {
  return std::min<std::size_t>(patches_of(t, 6), 64 * 64);
}

// Before a landscape exists: its bounds are 6 bytes a stored diamond of the level-0 pages (about
// half the samples, aprons included) plus the coarser levels' (docs/roam.md, "Error bounds"):
// under 4 bytes a sample. A paged terrain's bounds live in its pages (charged with its cache).
std::size_t landscape_estimate(const Terrain& t) {
  if (t.paged()) return kLandscapeLogBytes;
  const WorldInfo& info = t.info();
  return std::size_t{info.width} * info.height * 4 + kLandscapeLogBytes;
}

std::size_t view_base_bytes(const Landscape& l) {
  return std::size_t{l.patch_count()} * kViewBytesPerPatch + (64 << 10);
}

bool build_view(TerrainBox* terrain, ViewBox* view, const RoamSettings& settings,
                char* err) noexcept {
  try {
    if (!terrain->landscape) {
      auto landscape = Landscape::create(terrain->terrain);
      if (!landscape) {
        copy_error(err, landscape.error().message.c_str());
        return false;
      }
      terrain->landscape = std::move(*landscape);
      terrain->landscape_charge = std::make_shared<Charge>(
          terrain->budget,
          (terrain->terrain->paged() ? 0 : terrain->landscape->bound_bytes()) + kLandscapeLogBytes);
    }
    auto created = RoamView::create(terrain->landscape, settings);
    if (!created) {
      copy_error(err, created.error().message.c_str());
      return false;
    }
    view->view = std::move(*created);
    view->budget = terrain->budget;
    view->terrain_charge = terrain->terrain_charge;
    view->landscape_charge = terrain->landscape_charge;
    view->charge = std::make_shared<Charge>(terrain->budget, view_base_bytes(*terrain->landscape));
    return true;
  } catch (const std::exception& e) {
    view->view.reset();
    copy_error(err, e.what());
    return false;
  }
}

bool apply_settings(ViewBox* box, const RoamSettings& settings, char* err) noexcept {
  try {
    const Status s = box->view->set_settings(settings);
    if (!s) copy_error(err, s.message().c_str());
    return s.ok();
  } catch (const std::exception& e) {
    copy_error(err, e.what());
    return false;
  }
}

// Updates the view. `cap` (0: none) is the most leaf triangles the object budget leaves room
// for: when it is below the view's own cap, this update runs under it and `held` says whether
// it stopped there. The view's charge follows its memory afterwards.
bool run_update(ViewBox* box, std::uint32_t cap, bool* held, char* err) noexcept {
  try {
    const RoamSettings own = box->view->settings();
    const bool limited = cap != 0 && cap < own.max_triangles;
    if (limited) {
      RoamSettings s = own;
      s.max_triangles = cap;
      if (const Status st = box->view->set_settings(s); !st) {
        copy_error(err, st.message().c_str());
        return false;
      }
    }
    auto stats = box->view->update(box->camera);
    if (limited) (void)box->view->set_settings(own);
    if (!stats) {
      copy_error(err, stats.error().message.c_str());
      return false;
    }
    box->last = *stats;
    box->has_stats = true;
    *held = limited && stats->stop == StopReason::kTriangleBudget;
    if (box->charge) box->charge->set(stats->memory_bytes + stats->output_bytes);
    return true;
  } catch (const std::exception& e) {
    copy_error(err, e.what());
    return false;
  }
}

void push_stats(lua_State* L, const RoamStats& s) {
  lua_createtable(L, 0, 12);
  const auto set = [L](const char* k, double v) {
    lua_pushnumber(L, v);
    lua_setfield(L, -2, k);
  };
  const auto seti = [L](const char* k, lua_Integer v) {
    lua_pushinteger(L, v);
    lua_setfield(L, -2, k);
  };
  seti("triangles", s.triangles);
  seti("splits", s.splits);
  seti("forced_splits", s.forced_splits);
  seti("merges", s.merges);
  seti("priority_updates", s.priority_updates);
  seti("dirty_patches", s.dirty_patches);
  seti("memory_bytes", static_cast<lua_Integer>(s.memory_bytes));
  set("update_ms", s.update_ms);
  set("max_remaining_error", s.max_remaining_error);
  lua_pushstring(L, s.stop == StopReason::kConverged        ? "converged"
                    : s.stop == StopReason::kTriangleBudget ? "triangle_budget"
                                                            : "time_budget");
  lua_setfield(L, -2, "stop");
  lua_pushboolean(L, s.rebuilt);
  lua_setfield(L, -2, "rebuilt");
}

// view:set_camera{eye=, target=, up=, fov_y=, viewport=, near=, far=}: absent fields keep their
// values; the whole camera is checked before anything changes.
int v_set_camera(lua_State* L) {
  ViewBox* box = live_view(L);
  luaL_checktype(L, 2, LUA_TTABLE);
  check_fields(L, 2, kCameraFields);
  Camera cam = box->camera;
  read_camera(L, 2, &cam);
  check_camera(L, 2, cam);
  box->camera = cam;
  return 0;
}

// view:update() -> stats table
int v_update(lua_State* L) {
  ViewBox* box = live_view(L);
  std::uint32_t cap = 0;
  char detail[160];
  if (box->budget && box->budget->limit != 0) {
    // Room for this view: the limit less what every other object holds.
    const std::size_t own = box->charge ? box->charge->bytes() : 0;
    const std::size_t base = view_base_bytes(box->view->landscape());
    reserve_objects(L, box->budget, base, "view:update", own);
    const ObjectBudget& b = *box->budget;
    const std::size_t room = (b.limit - (b.used - own) - base) / kViewBytesPerTriangle;
    cap = static_cast<std::uint32_t>(std::min<std::size_t>(room, kMaxViewTriangles));
    if (cap < box->view->landscape().root_count()) {
      std::snprintf(detail, sizeof detail, "no room for this view's %u root triangles",
                    box->view->landscape().root_count());
      return object_budget_error(L, b, "view:update", detail);
    }
  }
  char err[kErrSize];
  bool held = false;
  if (!run_update(box, cap, &held, err)) return luaL_error(L, "view:update: %s", err);
  if (held || (box->budget && box->budget->limit != 0 && box->budget->used > box->budget->limit)) {
    std::snprintf(detail, sizeof detail,
                  "the view was held to %u triangles, below its budget of %u; view:stats() has "
                  "the update's figures",
                  box->last.triangles, box->view->settings().max_triangles);
    return object_budget_error(L, *box->budget, "view:update", detail);
  }
  push_stats(L, box->last);
  return 1;
}

// view:stats() -> stats of the last update, or nil before the first
int v_stats(lua_State* L) {
  ViewBox* box = live_view(L);
  if (!box->has_stats) return lua_pushnil(L), 1;
  push_stats(L, box->last);
  return 1;
}

int v_set_threshold(lua_State* L) {
  ViewBox* box = live_view(L);
  const double px = check_finite(L, 2);
  if (px < 0) luaL_argerror(L, 2, "threshold in pixels >= 0 expected");
  RoamSettings s = box->view->settings();
  s.threshold = px;
  char err[kErrSize];
  if (!apply_settings(box, s, err)) luaL_argerror(L, 2, err);
  return 0;
}

int v_threshold(lua_State* L) {
  lua_pushnumber(L, live_view(L)->view->settings().threshold);
  return 1;
}

// view:set_budget{triangles=, ms=}: triangles 0 or absent = the binding's cap
int v_set_budget(lua_State* L) {
  ViewBox* box = live_view(L);
  luaL_checktype(L, 2, LUA_TTABLE);
  static const char* const kFields[] = {"triangles", "ms", nullptr};
  check_fields(L, 2, kFields);
  RoamSettings s = box->view->settings();
  double v = 0;
  if (get_number_field(L, 2, "triangles", &v)) {
    if (v < 0) luaL_argerror(L, 2, "field 'triangles': number >= 0 expected");
    s.max_triangles = clamp_triangles(v);
  }
  if (get_number_field(L, 2, "ms", &v)) {
    if (v < 0 || v > 60000) luaL_argerror(L, 2, "field 'ms': milliseconds in 0 .. 60000 expected");
    s.budget_ms = v;
  }
  char err[kErrSize];
  if (!apply_settings(box, s, err)) luaL_argerror(L, 2, err);
  return 0;
}

// view:budget() -> triangles, ms
int v_budget(lua_State* L) {
  const RoamSettings& s = live_view(L)->view->settings();
  lua_pushinteger(L, s.max_triangles);
  lua_pushnumber(L, s.budget_ms);
  return 2;
}

int v_release(lua_State* L) {
  auto* box = static_cast<ViewBox*>(check_self(L, kViewMeta));
  box->view.reset();
  box->charge.reset();
  box->terrain_charge.reset();
  box->landscape_charge.reset();
  box->budget.reset();
  return 0;
}

int v_tostring(lua_State* L) {
  auto* box = static_cast<ViewBox*>(check_self(L, kViewMeta));
  if (!box->view) {
    lua_pushliteral(L, "ridgeline.view (released)");
    return 1;
  }
  char text[128];
  std::snprintf(text, sizeof text, "ridgeline.view (%u triangles, threshold %g px)",
                box->view->triangle_count(), box->view->settings().threshold);
  lua_pushstring(L, text);
  return 1;
}

const luaL_Reg kMethods[] = {{"set_camera", v_set_camera},
                             {"update", v_update},
                             {"stats", v_stats},
                             {"set_threshold", v_set_threshold},
                             {"threshold", v_threshold},
                             {"set_budget", v_set_budget},
                             {"budget", v_budget},
                             {"release", v_release},
                             {nullptr, nullptr}};
const luaL_Reg kMeta[] = {
    {"__gc", v_release}, {"__close", v_release}, {"__tostring", v_tostring}, {nullptr, nullptr}};

}  // namespace

ViewBox* push_view_box(lua_State* L) {
  void* mem = lua_newuserdatauv(L, sizeof(ViewBox), 0);
  auto* box = new (mem) ViewBox();
  push_metatable(L, kViewMeta, kMethods, kMeta);
  lua_setmetatable(L, -2);
  return box;
}

// terrain:new_view{eye=, target=, up=, fov_y=, viewport=, near=, far=, threshold=, triangles=,
// budget_ms=} -> view
int new_view(lua_State* L) {
  auto* terrain = static_cast<TerrainBox*>(check_self(L, kTerrainMeta));
  if (!terrain->terrain) luaL_error(L, "attempt to use a released ridgeline.terrain");
  if (lua_isnoneornil(L, 2)) {
    lua_settop(L, 1);
    lua_newtable(L);
  }
  luaL_checktype(L, 2, LUA_TTABLE);
  check_fields(L, 2, kNewViewFields);
  Camera cam;
  read_camera(L, 2, &cam);
  check_camera(L, 2, cam);
  RoamSettings settings;
  settings.max_triangles = kDefaultViewTriangles;
  double v = 0;
  if (get_number_field(L, 2, "threshold", &v)) {
    if (v < 0) luaL_argerror(L, 2, "field 'threshold': pixels >= 0 expected");
    settings.threshold = v;
  }
  if (get_number_field(L, 2, "triangles", &v)) {
    if (v < 0) luaL_argerror(L, 2, "field 'triangles': number >= 0 expected");
    settings.max_triangles = clamp_triangles(v);
  }
  if (get_number_field(L, 2, "budget_ms", &v)) {
    if (v < 0 || v > 60000)
      luaL_argerror(L, 2, "field 'budget_ms': milliseconds in 0 .. 60000 expected");
    settings.budget_ms = v;
  }
  // The landscape (built by the first view of a terrain) and the view's own start.
  const std::size_t bytes =
      (terrain->landscape ? 0 : landscape_estimate(*terrain->terrain)) +
      (terrain->landscape ? std::size_t{terrain->landscape->patch_count()}
                          : default_patches(*terrain->terrain)) *
          kViewBytesPerPatch +
      (64 << 10);
  reserve_objects(L, terrain->budget, bytes, "new_view");
  ViewBox* box = push_view_box(L);
  box->camera = cam;
  char err[kErrSize];
  if (!build_view(terrain, box, settings, err)) return luaL_error(L, "new_view: %s", err);
  account_memory(L, box->view->landscape().bound_bytes() / 8 + (64u << 10));
  return 1;
}

}  // namespace ridgeline::lua::detail
