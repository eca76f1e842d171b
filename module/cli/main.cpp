// ridge: the Ridgeline command-line tool. One binary, one subcommand per job; see docs/cli.md.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <vector>

#include "cli_util.h"
#include "commands.h"
#include "io/oiio_lsan_suppressions.h"

int main(int argc, char** argv) {
  using namespace ridgeline::cli;
  CLI::App app{"ridge: the Ridgeline terrain tool (heightmap info, queries, profiles, benchmarks)",
               "ridge"};
  app.require_subcommand(1);
  std::vector<Command> commands;
  commands.push_back(add_info_command(app));
  commands.push_back(add_query_command(app));
  commands.push_back(add_profile_command(app));
  commands.push_back(add_mesh_command(app));
  commands.push_back(add_report_command(app));
  commands.push_back(add_deform_command(app));
  auto* bench = app.add_subcommand("bench", "Benchmarks that print JSON");
  bench->require_subcommand(1);
  commands.push_back(add_bench_queries_command(*bench));
  commands.push_back(add_bench_lod_command(*bench));
  commands.push_back(add_bench_deform_command(*bench));
  commands.push_back(add_bench_detail_command(*bench));

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);  // prints help to stdout, errors to stderr
    return code == 0 ? 0 : kExitUsage;
  }
  install_log_sink();
  try {
    for (const Command& c : commands)
      if (c.app->parsed()) return c.run();
  } catch (const std::exception& e) {
    return report_error(e.what());
  }
  return report_error("no subcommand given (see ridge --help)");
}
