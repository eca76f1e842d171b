// ridge: the Ridgeline command-line tool. One binary, one subcommand per job; see docs/cli.md.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include "process_memory.h"
#include "cli_util.h"
#include "commands.h"
#include "io/oiio_lsan_suppressions.h"

namespace {

// "info, query, ..." : the subcommands of `app`.
std::string subcommand_list(const CLI::App& app) {
  std::string out;
  for (const CLI::App* s : app.get_subcommands([](const CLI::App*) { return true; }))
    out += (out.empty() ? "" : ", ") + s->get_name();
  return out;
}

// CLI11 reads an unknown word where a subcommand is expected as a stray argument and reports
// "A subcommand is required"; name it instead. Walks the words before the first flag down the
// subcommand tree. Returns the message, or empty when every word names a subcommand.
std::string unknown_subcommand(const CLI::App& app, int argc, char** argv) {
  const CLI::App* level = &app;
  std::string path = "ridge";
  for (int k = 1; k < argc; ++k) {
    const std::string word = argv[k];
    if (word.empty() || word[0] == '-') return {};
    const auto subs = level->get_subcommands([](const CLI::App*) { return true; });
    if (subs.empty()) return {};
    const CLI::App* next = nullptr;
    for (const CLI::App* s : subs)
      if (s->get_name() == word) next = s;
    if (next == nullptr)
      return "unknown subcommand '" + word + "' of " + path + " (the subcommands are " +
             subcommand_list(*level) + "; see " + path + " --help)";
    level = next;
    path += " " + word;
  }
  return {};
}

}  // namespace

int main(int argc, char** argv) {
  using namespace ridgeline::cli;
  keep_page_buffers_in_one_arena();
  CLI::App app{"ridge: the Ridgeline terrain tool (heightmap info, queries, profiles, benchmarks)",
               "ridge"};
  // Before the subcommands are added: they copy it.
  app.failure_message([](const CLI::App* a, const CLI::Error& e) {
    std::string path = a->get_name();  // the subcommands given: "ridge bench lod"
    for (auto given = a->get_subcommands(); !given.empty();
         given = given.front()->get_subcommands())
      path += " " + given.front()->get_name();
    return "ridge: error: " + std::string(e.what()) + " (see " + path + " --help)\n";
  });
  app.set_version_flag("--version", std::string("ridge ") + RIDGELINE_VERSION,
                       "Print the version and exit");
  app.require_subcommand(1);
  std::vector<Command> commands;
  commands.push_back(add_info_command(app));
  commands.push_back(add_bake_command(app));
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
  commands.push_back(add_bench_world_command(*bench));

  if (const std::string unknown = unknown_subcommand(app, argc, argv); !unknown.empty()) {
    std::fprintf(stderr, "ridge: error: %s\n", unknown.c_str());
    return kExitUsage;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);  // prints help and the version to stdout, errors to stderr
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
