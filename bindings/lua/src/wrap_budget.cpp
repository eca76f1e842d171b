// Lua userdata `ridgeline.budget_controller`: the frame-time controller of the pixel threshold
// (ridgeline/budget_controller.h). The controller is plain data (trivially destructible), so the
// userdata needs no __gc and no Lua error can leak anything.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <new>
#include <type_traits>

#include "lua_util.h"
#include "ridgeline/budget_controller.h"

namespace ridgeline::lua::detail {
namespace {

static_assert(std::is_trivially_destructible_v<BudgetController>,
              "the userdata has no __gc: the controller must hold no resources");

BudgetController* self(lua_State* L) {
  return static_cast<BudgetController*>(check_self(L, kBudgetMeta));
}

// Runs `fn` (which returns a Status or Result) and copies its error into `err`.
template <class F>
bool attempt(F&& fn, char* err) noexcept {
  try {
    auto r = fn();
    if (!r.ok()) {
      if constexpr (std::is_same_v<decltype(r), Status>)
        copy_error(err, r.message().c_str());
      else
        copy_error(err, r.error().message.c_str());
      return false;
    }
    return true;
  } catch (const std::exception& e) {
    copy_error(err, e.what());
    return false;
  }
}

bool build(const BudgetControllerDesc& d, BudgetController* out, char* err) noexcept {
  try {
    auto c = BudgetController::create(d);
    if (!c) {
      copy_error(err, c.error().message.c_str());
      return false;
    }
    new (out) BudgetController(*c);
    return true;
  } catch (const std::exception& e) {
    copy_error(err, e.what());
    return false;
  }
}

// ctl:update(frame_ms, dt_s) -> threshold (pixels), render scale for the next frame
int b_update(lua_State* L) {
  BudgetController* c = self(L);
  const double ms = check_finite(L, 2);
  const double dt = check_finite(L, 3);
  if (ms < 0) luaL_argerror(L, 2, "frame time in milliseconds >= 0 expected");
  if (dt < 0) luaL_argerror(L, 3, "time step in seconds >= 0 expected");
  lua_pushnumber(L, c->update(ms, dt));
  lua_pushnumber(L, c->render_scale());
  return 2;
}

int b_threshold(lua_State* L) {
  lua_pushnumber(L, self(L)->threshold());
  return 1;
}

int b_render_scale(lua_State* L) {
  lua_pushnumber(L, self(L)->render_scale());
  return 1;
}

// ctl:state() -> {threshold=, render_scale=, smoothed_ms=, filtered_ms=, last_frame_ms=,
//                 action=, updates=, reversals=, warming_up=, at_min=, at_max=, target_ms=,
//                 min=, max=, min_render_scale=, render_scale_from=}
int b_state(lua_State* L) {
  const BudgetController* c = self(L);
  const BudgetState& s = c->state();
  lua_createtable(L, 0, 16);
  lua_pushnumber(L, s.threshold);
  lua_setfield(L, -2, "threshold");
  lua_pushnumber(L, s.render_scale);
  lua_setfield(L, -2, "render_scale");
  lua_pushnumber(L, s.smoothed_ms);
  lua_setfield(L, -2, "smoothed_ms");
  lua_pushnumber(L, s.filtered_ms);
  lua_setfield(L, -2, "filtered_ms");
  lua_pushnumber(L, s.last_frame_ms);
  lua_setfield(L, -2, "last_frame_ms");
  lua_pushboolean(L, s.warming_up);
  lua_setfield(L, -2, "warming_up");
  lua_pushstring(L, to_string(s.action));
  lua_setfield(L, -2, "action");
  lua_pushinteger(L, static_cast<lua_Integer>(s.updates));
  lua_setfield(L, -2, "updates");
  lua_pushinteger(L, static_cast<lua_Integer>(s.reversals));
  lua_setfield(L, -2, "reversals");
  lua_pushboolean(L, s.at_min);
  lua_setfield(L, -2, "at_min");
  lua_pushboolean(L, s.at_max);
  lua_setfield(L, -2, "at_max");
  lua_pushnumber(L, c->desc().target_ms);
  lua_setfield(L, -2, "target_ms");
  lua_pushnumber(L, c->desc().min_threshold);
  lua_setfield(L, -2, "min");
  lua_pushnumber(L, c->desc().max_threshold);
  lua_setfield(L, -2, "max");
  lua_pushnumber(L, c->desc().min_render_scale);
  lua_setfield(L, -2, "min_render_scale");
  lua_pushnumber(L, c->desc().render_scale_from_px);
  lua_setfield(L, -2, "render_scale_from");
  return 1;
}

int b_set_target(lua_State* L) {
  BudgetController* c = self(L);
  const double ms = check_finite(L, 2);
  char err[kErrSize];
  if (!attempt([&] { return c->set_target_ms(ms); }, err)) luaL_argerror(L, 2, err);
  return 0;
}

int b_set_range(lua_State* L) {
  BudgetController* c = self(L);
  const double lo = check_finite(L, 2);
  const double hi = check_finite(L, 3);
  char err[kErrSize];
  if (!attempt([&] { return c->set_range(lo, hi); }, err)) luaL_argerror(L, 2, err);
  return 0;
}

// ctl:set_render_scale_range(min_render_scale, render_scale_from)
int b_set_render_scale_range(lua_State* L) {
  BudgetController* c = self(L);
  const double lo = check_finite(L, 2);
  const double from = opt_finite(L, 3, 0.0);
  char err[kErrSize];
  if (!attempt([&] { return c->set_render_scale_range(lo, from); }, err)) luaL_argerror(L, 2, err);
  return 0;
}

// ctl:reset(threshold [, render_scale])
int b_reset(lua_State* L) {
  BudgetController* c = self(L);
  const double t = check_finite(L, 2);
  const double s = opt_finite(L, 3, 1.0);
  char err[kErrSize];
  if (!attempt([&] { return c->reset(t, s); }, err)) luaL_argerror(L, 2, err);
  return 0;
}

int b_tostring(lua_State* L) {
  const BudgetController* c = self(L);
  char text[200];
  std::snprintf(text, sizeof text,
                "ridgeline.budget_controller (threshold %g px, render scale %g, target %g ms, "
                "smoothed %g ms)",
                c->threshold(), c->render_scale(), c->desc().target_ms, c->state().smoothed_ms);
  lua_pushstring(L, text);
  return 1;
}

const luaL_Reg kMethods[] = {{"update", b_update},
                             {"threshold", b_threshold},
                             {"render_scale", b_render_scale},
                             {"state", b_state},
                             {"set_target", b_set_target},
                             {"set_range", b_set_range},
                             {"set_render_scale_range", b_set_render_scale_range},
                             {"reset", b_reset},
                             {nullptr, nullptr}};
const luaL_Reg kMeta[] = {{"__tostring", b_tostring}, {nullptr, nullptr}};

// Reads an optional integer field in [lo, hi] (a count): raises naming the field otherwise.
bool get_count_field(lua_State* L, int arg, const char* name, double lo, double hi,
                     std::uint32_t* out) {
  double v = 0;
  if (!get_number_field(L, arg, name, &v)) return false;
  if (v != std::floor(v) || v < lo || v > hi) {
    lua_pushfstring(L, "field '%s': integer %d .. %d expected, got %f", name, int(lo), int(hi), v);
    luaL_argerror(L, arg, lua_tostring(L, -1));
  }
  *out = static_cast<std::uint32_t>(v);
  return true;
}

}  // namespace

// ridgeline.budget_controller{target_ms=, min=, max=, threshold=, deadband=, headroom_gain=,
//   smoothing_s=, raise_gain=, lower_gain=, reverse_hold_s=, warmup_frames=, median_frames=, max_step_s=,
//   min_render_scale=, render_scale_from=} -> controller; bad settings raise an error naming
//   the field (through BudgetController::create's message).
int new_budget_controller(lua_State* L) {
  static const char* const kFields[] = {"target_ms",
                                        "min",
                                        "max",
                                        "threshold",
                                        "deadband",
                                        "headroom_gain",
                                        "smoothing_s",
                                        "raise_gain",
                                        "lower_gain",
                                        "reverse_hold_s",
                                        "warmup_frames",
                                        "median_frames",
                                        "max_step_s",
                                        "min_render_scale",
                                        "render_scale_from",
                                        nullptr};
  BudgetControllerDesc d;
  if (!lua_isnoneornil(L, 1)) {
    luaL_checktype(L, 1, LUA_TTABLE);
    check_fields(L, 1, kFields);
    get_number_field(L, 1, "target_ms", &d.target_ms);
    get_number_field(L, 1, "min", &d.min_threshold);
    get_number_field(L, 1, "max", &d.max_threshold);
    if (!get_number_field(L, 1, "threshold", &d.initial_threshold))
      d.initial_threshold =
          d.initial_threshold < d.min_threshold
              ? d.min_threshold
              : (d.initial_threshold > d.max_threshold ? d.max_threshold : d.initial_threshold);
    get_number_field(L, 1, "deadband", &d.deadband);
    get_number_field(L, 1, "headroom_gain", &d.headroom_gain);
    get_number_field(L, 1, "smoothing_s", &d.smoothing_s);
    get_number_field(L, 1, "raise_gain", &d.raise_gain);
    get_number_field(L, 1, "lower_gain", &d.lower_gain);
    get_number_field(L, 1, "reverse_hold_s", &d.reverse_hold_s);
    get_count_field(L, 1, "warmup_frames", 0, 1000, &d.warmup_frames);
    get_count_field(L, 1, "median_frames", 1, 15, &d.median_frames);
    get_number_field(L, 1, "max_step_s", &d.max_step_s);
    get_number_field(L, 1, "min_render_scale", &d.min_render_scale);
    get_number_field(L, 1, "render_scale_from", &d.render_scale_from_px);
  }
  void* mem = lua_newuserdatauv(L, sizeof(BudgetController), 0);
  char err[kErrSize];
  if (!build(d, static_cast<BudgetController*>(mem), err)) luaL_argerror(L, 1, err);
  push_metatable(L, kBudgetMeta, kMethods, kMeta);
  lua_setmetatable(L, -2);
  return 1;
}

}  // namespace ridgeline::lua::detail
