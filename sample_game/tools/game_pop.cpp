// game_pop: the pop metric of `ridge report` (docs/report_method.md, "Pop") for a camera path the game
// recorded (`ridgeline_game --record-path PATH.json`), on the game's own world: the default
// terrain with the default world's procedural detail, the game's ROAM patches, a coherent
// RoamView at a fixed threshold, geomorphs as the game's renderer draws them. A front end of
// Ridgeline::bench's frame loop, as `ridge report` is; prints the report's figures for the path
// as JSON (pop_geomorph_max_px is the one the renderer shows).
// Usage: game_pop PATH.json [--threshold PX] [--every K] [--stride S] [--json FILE]
#include <CLI/CLI.hpp>
#include <cstdio>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "game.h"
#include "ridgeline/bench/grid.h"
#include "ridgeline/bench/summary.h"
#include "ridgeline/bench/techniques.h"
#include "ridgeline/camera_path.h"
#include "ridgeline/heightfield.h"
#include "ridgeline/landscape.h"
#include "ridgeline/terrain.h"

int main(int argc, char** argv) {
  CLI::App app{"Pop metric of a recorded game camera path (docs/game.md, \"Geomorphs\")"};
  std::string path_file, json_file;
  double threshold = 2;
  int every = 2;
  std::uint32_t stride = 1, patch_exponent = game::GameOptions{}.patch_exponent;
  app.add_option("path", path_file, "PATH.json written by ridgeline_game --record-path")
      ->required();
  app.add_option("--threshold", threshold, "pixel threshold of the view (the game's default: 2)")
      ->check(CLI::PositiveNumber);
  app.add_option("--every", every, "measure the pop between frames nK-1 and nK")
      ->check(CLI::Range(2, 1000));
  app.add_option("--stride", stride, "measure every S-th lattice vertex per axis")
      ->check(CLI::Range(1, 64));
  app.add_option("--patch-exponent", patch_exponent, "ROAM patches of 2^k stored cells")
      ->check(CLI::Range(2, 10));
  app.add_option("--json", json_file, "also write the figures to this file");
  CLI11_PARSE(app, argc, argv);

  auto frames = ridgeline::io::load_camera_path(path_file);
  if (!frames) {
    std::fprintf(stderr, "game_pop: %s\n", frames.error().message.c_str());
    return 1;
  }
  if (frames->size() < 3) {
    std::fprintf(stderr, "game_pop: camera path '%s' has %zu frames; need at least 3\n",
                 path_file.c_str(), frames->size());
    return 1;
  }
  auto hf = ridgeline::make_default_heightfield();
  if (!hf) {
    std::fprintf(stderr, "game_pop: %s\n", hf.error().message.c_str());
    return 1;
  }
  ridgeline::DetailCacheDesc cd;
  cd.worker_threads = 2;
  auto terrain = ridgeline::Terrain::create(std::move(*hf), game::default_world_detail(), cd);
  if (!terrain) {
    std::fprintf(stderr, "game_pop: %s\n", terrain.error().message.c_str());
    return 1;
  }
  auto land = ridgeline::Landscape::create(*terrain, {.patch_exponent = patch_exponent});
  if (!land) {
    std::fprintf(stderr, "game_pop: %s\n", land.error().message.c_str());
    return 1;
  }
  // Measured on the finest lattice baked into a heightfield, as `ridge report` measures.
  auto fine = ridgeline::bench::finest_lattice(**terrain);
  if (!fine) {
    std::fprintf(stderr, "game_pop: %s\n", fine.error().message.c_str());
    return 1;
  }
  const ridgeline::MeshErrorMeter meter(*fine, stride);
  ridgeline::RoamSettings settings;
  settings.threshold = threshold;
  auto view = ridgeline::RoamView::create(*land, settings);
  if (!view) {
    std::fprintf(stderr, "game_pop: %s\n", view.error().message.c_str());
    return 1;
  }
  ridgeline::bench::RoamTechnique roam(std::move(*view), /*converge_first=*/true);
  std::vector<ridgeline::Camera> cams;
  for (const ridgeline::io::PathFrame& f : *frames) cams.push_back(f.camera);
  ridgeline::bench::LoopOptions o;
  o.error_every = static_cast<std::uint32_t>(every);
  o.pops = true;
  auto r = ridgeline::bench::run_path(roam, cams, &meter, o);
  if (!r) {
    std::fprintf(stderr, "game_pop: %s\n", r.error().message.c_str());
    return 1;
  }
  nlohmann::ordered_json out = ridgeline::bench::report_figures(*r);
  out["path"] = path_file;
  out["frames"] = cams.size();
  out["threshold_px"] = threshold;
  out["every"] = every;
  out["stride"] = stride;
  out["patch_exponent"] = patch_exponent;
  out["morph_window"] = (*land)->geomorph().window;
  out["morph_delay"] = (*land)->geomorph().delay;
  const std::string text = out.dump(2);
  std::printf("%s\n", text.c_str());
  if (!json_file.empty()) {
    std::ofstream os(json_file);
    os << text << "\n";
    if (!os) {
      std::fprintf(stderr, "game_pop: cannot write '%s'\n", json_file.c_str());
      return 1;
    }
  }
  return 0;
}
