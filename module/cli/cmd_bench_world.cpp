// `ridge bench world [flags]`: runs ridge-bench-world (bench_world.cpp), installed beside `ridge`,
// with the same flags. The benchmark is its own program so that the memory it measures is an
// engine's (the core and Ridgeline::world), not this tool's (OpenImageIO and its dependencies
// hold ~120 MB of any process that links them).
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include "cli_util.h"
#include "commands.h"

namespace ridgeline::cli {

Command add_bench_world_command(CLI::App& bench) {
  auto* app = bench.add_subcommand(
      "world",
      "Baked worlds: bake, open to first mesh, convergence and a real-time flight under a cache "
      "budget (JSON); runs ridge-bench-world, see ridge-bench-world --help");
  app->allow_extras();
  app->set_help_flag();  // --help goes to the benchmark itself
  return {app, [app] {
            std::error_code ec;
            const auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
            const std::string exe = (self.parent_path() / "ridge-bench-world").string();
            if (ec || !std::filesystem::exists(exe))
              return report_error("bench world: '" + exe +
                                  "' is missing (it is built and installed with ridge)");
            std::vector<std::string> args{exe};
            for (const std::string& s : app->remaining()) args.push_back(s);
            std::vector<char*> argv;
            for (auto& s : args) argv.push_back(s.data());
            argv.push_back(nullptr);
            ::execv(exe.c_str(), argv.data());
            return report_error("bench world: cannot run '" + exe + "'");
          }};
}

}  // namespace ridgeline::cli
