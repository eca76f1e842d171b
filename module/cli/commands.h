// The `ridge` subcommands. Each add_*_command() registers a subcommand (its flags and help) on
// `parent` and returns the function main() runs when that subcommand was given.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace ridgeline::cli {

struct Command {
  CLI::App* app = nullptr;   ///< the subcommand; run() is called when it was parsed
  std::function<int()> run;  ///< returns the process exit code
};

/// `ridge info`: size, extent, height range, memory, filled samples, content hash (JSON).
Command add_info_command(CLI::App& parent);
/// `ridge bake --out WORLD`: a heightmap, several files or a generated world baked into a world
/// file (JSON report).
Command add_bake_command(CLI::App& parent);
/// `ridge query --points IN.csv`: height and face normal per point (CSV).
Command add_query_command(CLI::App& parent);
/// `ridge profile --from X,Z --to X,Z --steps N`: a text profile with an ASCII plot.
Command add_profile_command(CLI::App& parent);
/// `ridge mesh`: converge a ROAM mesh for one view, write it as .glb (cmd_roam.cpp).
Command add_mesh_command(CLI::App& parent);
/// `ridge bench lod`: per-frame ROAM cost and error along a camera path (cmd_roam.cpp).
Command add_bench_lod_command(CLI::App& bench);
/// `ridge report`: speed versus error of ROAM and two comparators (cmd_report.cpp).
Command add_report_command(CLI::App& parent);
/// `ridge deform --edits EDITS.json [--save STATE.bin]`: apply edits, save the state (JSON report).
Command add_deform_command(CLI::App& parent);
/// `ridge bench deform`: ms per crater edit for several radii (JSON).
Command add_bench_deform_command(CLI::App& bench);
/// `ridge bench detail`: detail tile generation and the detail cache along a flight (JSON).
Command add_bench_detail_command(CLI::App& bench);
/// `ridge bench queries`: query speed (JSON), measured by bench_queries.h.
Command add_bench_queries_command(CLI::App& bench);
/// `ridge bench world`: baked worlds measured by ridge-bench-world (JSON; cmd_bench_world.cpp).
Command add_bench_world_command(CLI::App& bench);

}  // namespace ridgeline::cli
