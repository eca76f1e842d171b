// `ridge bench queries`: runs bench_queries() (bench_queries.h) and prints its JSON.
#include <limits>
#include <memory>

#include "bench_queries.h"
#include "cli_util.h"
#include "commands.h"
#include "terrain_args.h"

namespace ridgeline::cli {

namespace {

struct BenchQueriesArgs {
  TerrainArgs terrain;
  std::string points = "1000000", repetitions = "5", seed = "1", json_path;
};

int run_bench_queries(const BenchQueriesArgs& a) {
  BenchQueriesOptions options;
  auto points = parse_count(a.points, "--points", 1, 1000000000);
  if (!points) return report_error(points.error().message);
  auto reps = parse_count(a.repetitions, "--repetitions", 1, 1000);
  if (!reps) return report_error(reps.error().message);
  auto seed = parse_count(a.seed, "--seed", 0, std::numeric_limits<std::uint64_t>::max());
  if (!seed) return report_error(seed.error().message);
  options.points = static_cast<std::size_t>(*points);
  options.repetitions = static_cast<int>(*reps);
  options.seed = *seed;
  auto terrain = a.terrain.load_terrain();
  if (!terrain) return report_error(terrain.error().message);
  nlohmann::json j = bench_queries(**terrain, options);
  if (!j.is_object()) j = {{"result", j}};
  if (!j.contains("terrain")) {
    const WorldInfo& hf = (*terrain)->info();
    j["terrain"] = {{"source", a.terrain.source()},
                    {"width", hf.width},
                    {"height", hf.height},
                    {"spacing", {hf.spacing_x, hf.spacing_z}}};
  }
  if (auto s = write_json(j, a.json_path); !s) return report_error(s.message());
  return 0;
}

}  // namespace

Command add_bench_queries_command(CLI::App& bench) {
  auto* app = bench.add_subcommand(
      "queries",
      "ns per height query, height+normal, vertical ray and slanted ray (256 cells), medians "
      "over repetitions (JSON)");
  auto a = std::make_shared<BenchQueriesArgs>();
  a->terrain.add_to(*app);
  app->add_option("--points", a->points,
                  "Random points (and rays) per repetition (default 1000000)")
      ->type_name("N");
  app->add_option("--repetitions", a->repetitions, "Repetitions; medians are reported (default 5)")
      ->type_name("R");
  app->add_option("--seed", a->seed, "Seed of the random points (default 1)")->type_name("S");
  app->add_option("--json", a->json_path, "Write the JSON to FILE instead of standard output")
      ->type_name("FILE");
  return {app, [a] { return run_bench_queries(*a); }};
}

}  // namespace ridgeline::cli
