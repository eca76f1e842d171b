// Fuzz target: Lua scripts run through the sandboxed host (a fresh host per input, small limits,
// the test data folder granted). Any input must end in success or an error, never a crash, a
// sanitizer report or a hang (libFuzzer's -timeout catches those). Seeds and dictionary use the
// tiny test heightmaps: the built-in 1025 x 1025 terrain is regenerated per host (per input), and
// its first view builds error bounds for a million samples, seconds under ASan.
#include <cstdint>
#include <string_view>

#include "ridgeline/lua/host.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  ridgeline::lua::HostOptions options;
  options.instruction_limit = 1'000'000;
  options.memory_limit = std::size_t{16} << 20;
  options.time_limit_seconds = 0;  // deterministic: the instruction budget ends runaway scripts
  options.data_root = RIDGELINE_TEST_DATA;
  options.max_samples = 1 << 16;
  auto host = ridgeline::lua::Host::create(options);
  if (!host) __builtin_trap();
  const std::string_view source(reinterpret_cast<const char*>(data), size);
  (void)(*host)->run(source, "fuzz");
  // The host stays usable after whatever the input did. The check reads no global: a script may
  // legitimately reassign its own globals (`ridgeline = false`, `assert = nil`), which once
  // made this check trap on a healthy host (regression input crash-globals-reassigned.lua).
  if (!(*host)->run("local t = {1, 2}; return #t", "alive")) __builtin_trap();
  return 0;
}
