// Runs Lua test files in one sandboxed Host (as a game would), the data folder granted.
// Usage: lua_test_host [--no-sandbox] [--data DIR] FILE...   Exit code 0 when every file passes.
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "ridgeline/lua/host.h"

int main(int argc, char** argv) {
  ridgeline::lua::HostOptions options;
  // No wall-clock limit: CI machines are shared and sanitizer builds slow (the instruction and
  // memory limits stay; LuaHost.WallClock* tests the clock).
  options.time_limit_seconds = 0;
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--no-sandbox") == 0) {
      options.sandbox = false;
    } else if (std::strcmp(argv[i], "--data") == 0 && i + 1 < argc) {
      options.data_root = argv[++i];
    } else {
      files.emplace_back(argv[i]);
    }
  }
  auto host = ridgeline::lua::Host::create(options);
  if (!host) {
    std::fprintf(stderr, "%s\n", host.error().message.c_str());
    return 2;
  }
  // Scripts see DATA = "" (paths are relative to the granted folder).
  if (auto s = (*host)->run("DATA = ''", "setup"); !s) {
    std::fprintf(stderr, "%s\n", s.message().c_str());
    return 2;
  }
  for (const std::string& f : files) {
    if (auto s = (*host)->run_file(f); !s) {
      std::fprintf(stderr, "FAIL %s\n%s\n", f.c_str(), s.message().c_str());
      return 1;
    }
  }
  std::printf("ok (%zu files, %zu bytes of Lua memory at the end)\n", files.size(),
              (*host)->memory_used());
  return 0;
}
