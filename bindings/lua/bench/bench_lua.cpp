// Lua binding speed (docs/lua_api.md): ns per Lua call of terrain:height and per point of
// terrain:heights, end to end from a Lua loop, on the default terrain. Prints JSON; medians of
// 7 runs. The empty-loop cost (the same loop without the call) is reported alongside.
#include <algorithm>
#include <cstdio>
#include <lua.hpp>
#include <vector>

#include "ridgeline/bench/clock.h"
#include "ridgeline/bench/stats.h"
#include "ridgeline/lua/host.h"

namespace {

constexpr const char* kScript = R"(
local t = ridgeline.default_terrain()
function bench_height(n)
  local s = 0
  for i = 1, n do s = s + t:height(100 + (i % 1000) * 1.7, 200.5 + (i % 777)) end
  return s
end
function bench_empty(n)
  local s = 0
  for i = 1, n do s = s + (100 + (i % 1000) * 1.7) + (200.5 + (i % 777)) end
  return s
end
local xz, out = {}, {}
function prepare(points)
  xz, out = {}, {}
  for i = 1, points do xz[2 * i - 1] = 100 + (i % 1000) * 1.7; xz[2 * i] = 200.5 + (i % 777) end
end
function bench_heights(reps) for r = 1, reps do t:heights(xz, out) end end
)";

// Seconds for global `fn`(arg), median of 7.
double time_call(ridgeline::lua::Host& host, const char* fn, double arg) {
  lua_State* L = host.state();
  std::vector<double> runs;
  for (int r = 0; r < 7; ++r) {
    lua_getglobal(L, fn);
    lua_pushnumber(L, arg);
    const auto t0 = ridgeline::bench::Clock::now();
    const auto s = host.call(1, 0);
    const double ms = ridgeline::bench::ms_since(t0);
    if (!s) {
      std::fprintf(stderr, "%s\n", s.message().c_str());
      return -1;
    }
    runs.push_back(ms * 1e-3);
  }
  return ridgeline::bench::median(runs);
}

}  // namespace

int main() {
  ridgeline::lua::HostOptions options;
  options.sandbox = false;  // so the benchmark reaches its globals; the hook is installed anyway
  options.instruction_limit = 0;
  auto host = ridgeline::lua::Host::create(options);
  if (!host) return 1;
  if (auto s = (*host)->run(kScript, "bench"); !s) {
    std::fprintf(stderr, "%s\n", s.message().c_str());
    return 1;
  }
  const double calls = 2e6;
  const double t_height = time_call(**host, "bench_height", calls);
  const double t_empty = time_call(**host, "bench_empty", calls);
  const int points = 65536, reps = 40;
  lua_State* L = (*host)->state();
  lua_getglobal(L, "prepare");
  lua_pushinteger(L, points);
  if (!(*host)->call(1, 0)) return 1;
  const double t_batch = time_call(**host, "bench_heights", reps);
  if (t_height < 0 || t_empty < 0 || t_batch < 0) return 1;
  std::printf(
      "{\n  \"terrain\": \"default (1025 x 1025, 2 m)\",\n"
      "  \"height_call_ns\": %.1f,\n  \"empty_loop_ns\": %.1f,\n"
      "  \"height_call_minus_loop_ns\": %.1f,\n  \"heights_points_per_call\": %d,\n"
      "  \"heights_ns_per_point\": %.2f,\n  \"targets\": {\"height_call_ns\": 150, "
      "\"heights_ns_per_point\": 30}\n}\n",
      t_height / calls * 1e9, t_empty / calls * 1e9, (t_height - t_empty) / calls * 1e9, points,
      t_batch / (double(points) * reps) * 1e9);
  return 0;
}
