// `ridge deform` (apply an edit list, save the state) and `ridge bench deform` (cost of one edit
// and of the view update that follows it).
#include <algorithm>
#include <cstdio>
#include <limits>
#include <memory>
#include <glm/common.hpp>
#include <random>

#include "cli_util.h"
#include "ridgeline/bench/clock.h"
#include "ridgeline/bench/stats.h"
#include "commands.h"
#include "ridgeline/edit.h"
#include "ridgeline/edit_file.h"
#include "ridgeline/edit_json.h"
#include "ridgeline/landscape.h"
#include "ridgeline/roam_view.h"
#include "terrain_args.h"

namespace ridgeline::cli {

namespace {

std::string hex(std::uint64_t v) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

nlohmann::ordered_json box_json(const Box& b) {
  return {{"min", {b.min.x, b.min.y, b.min.z}}, {"max", {b.max.x, b.max.y, b.max.z}}};
}

// ---- ridge deform -----------------------------------------------------------------------------

struct DeformArgs {
  TerrainArgs terrain;
  std::string edits, save, json_path;
};

int run_deform(const DeformArgs& a) {
  auto edits = io::load_edits_json(a.edits);
  if (!edits) return report_error(edits.error().message);
  auto terrain = a.terrain.load_terrain();
  if (!terrain) return report_error(terrain.error().message);
  Terrain& t = **terrain;
  std::size_t changed = 0, empty = 0, clipped = 0, clamped = 0;
  std::uint64_t samples = 0, hole_cells = 0;
  Box total{glm::dvec3(std::numeric_limits<double>::infinity()),
            glm::dvec3(-std::numeric_limits<double>::infinity())};
  const auto t0 = bench::Clock::now();
  for (std::size_t k = 0; k < edits->size(); ++k) {
    auto r = t.apply_edit((*edits)[k]);
    if (!r) return report_error("edits[" + std::to_string(k) + "]: " + r.error().message);
    if (r->empty()) {
      ++empty;
      continue;
    }
    ++changed;
    clipped += r->clipped;
    clamped += r->clamped;
    samples += r->samples_changed;
    hole_cells += r->cells_changed;
    total.min = glm::min(total.min, r->changed.min);
    total.max = glm::max(total.max, r->changed.max);
  }
  const double ms = bench::ms_since(t0);
  if (!a.save.empty())
    if (auto s = io::save_edits(t, a.save); !s) return report_error(s.message());
  nlohmann::ordered_json j = {{"source", a.terrain.source()},
                              {"edits", edits->size()},
                              {"edits_changed", changed},
                              {"edits_empty", empty},
                              {"edits_clipped", clipped},
                              {"edits_clamped", clamped},
                              {"samples_changed", samples},
                              {"hole_cells_changed", hole_cells},
                              {"hole_cells", t.surface().hole_cells()},
                              {"edited_chunks", t.surface().edited_chunks()},
                              {"apply_ms", ms},
                              {"base_hash", hex(t.base_hash())},
                              {"heights_hash", hex(t.surface().heights_hash())}};
  if (changed > 0) j["changed"] = box_json(total);
  if (!a.save.empty()) j["saved"] = a.save;
  if (auto s = write_json(j, a.json_path); !s) return report_error(s.message());
  return 0;
}

// ---- ridge bench deform -----------------------------------------------------------------------

struct BenchDeformArgs {
  TerrainArgs terrain;
  std::string radii = "5,20,100", count = "200", patch_exponent = "6", seed = "1", json_path;
};

int run_bench_deform(const BenchDeformArgs& a) {
  auto radii = parse_finite_list(a.radii, "--radii", 1, 16);
  if (!radii) return report_error(radii.error().message);
  auto count = parse_count(a.count, "--count", 1, 1000000);
  if (!count) return report_error(count.error().message);
  auto k = parse_count(a.patch_exponent, "--patch-exponent", 2, 10);
  if (!k) return report_error(k.error().message);
  auto seed = parse_count(a.seed, "--seed", 0, std::numeric_limits<std::uint32_t>::max());
  if (!seed) return report_error(seed.error().message);
  auto terrain = a.terrain.load_terrain();
  if (!terrain) return report_error(terrain.error().message);
  Terrain& t = **terrain;
  const WorldInfo& hf = t.info();
  auto land = Landscape::create(*terrain, {.patch_exponent = static_cast<std::uint32_t>(*k)});
  if (!land) return report_error(land.error().message);
  // One view converged for a camera above the middle, looking across: the edits land in its
  // mesh, so the cost includes refreshing and requeueing view nodes and marking patches dirty.
  auto view = RoamView::create(*land, {.threshold = 2.0});
  if (!view) return report_error(view.error().message);
  const double cx = hf.origin_x + 0.5 * hf.extent_x(), cz = hf.origin_z + 0.5 * hf.extent_z();
  Camera cam;
  cam.eye = {cx, hf.height_offset + hf.max_local + 100.0, hf.origin_z};
  cam.target = {cx, hf.height_offset, cz};
  if (auto s = (*view)->converge(cam); !s) return report_error(s.error().message);

  std::mt19937_64 rng(*seed);
  nlohmann::ordered_json rows = nlohmann::ordered_json::array();
  for (double radius : *radii) {
    if (!(radius > 0)) return report_error("--radii: every radius must be > 0");
    std::uniform_real_distribution<double> ux(hf.origin_x, hf.origin_x + hf.extent_x());
    std::uniform_real_distribution<double> uz(hf.origin_z, hf.origin_z + hf.extent_z());
    std::vector<double> ms, edit_cpu, update_cpu, both_cpu, both_wall, samples;
    for (std::uint64_t n = 0; n < *count; ++n) {
      Edit e;
      e.brush = Brush::kCrater;
      e.x = ux(rng), e.z = uz(rng);
      e.radius = radius;
      e.depth = (n & 1) ? -1.0 : 1.0;  // alternate craters and mounds: heights stay bounded
      // The edit, then the view's next update (which brings its mesh up to the edit): wall time
      // and this thread's CPU time (steadier on a shared machine).
      Result<EditResult> r = Error{""};
      const bench::Timing edit = bench::timed([&] { r = t.apply_edit(e); });
      if (!r) return report_error(r.error().message);
      Result<RoamStats> u = Error{""};
      const bench::Timing update = bench::timed([&] { u = (*view)->update(cam); });
      if (!u) return report_error(u.error().message);
      ms.push_back(edit.wall_ms);
      both_wall.push_back(edit.wall_ms + update.wall_ms);
      edit_cpu.push_back(edit.cpu_ms);
      update_cpu.push_back(update.cpu_ms);
      both_cpu.push_back(edit.cpu_ms + update.cpu_ms);
      samples.push_back(double(r->samples_changed));
    }
    rows.push_back({{"brush", "crater"},
                    {"radius_m", radius},
                    {"edits", *count},
                    {"median_ms", bench::quantile_or(ms, 0.5, 0)},
                    {"p90_ms", bench::quantile_or(ms, 0.9, 0)},
                    {"max_ms", bench::quantile_or(ms, 1.0, 0)},
                    {"median_edit_cpu_ms", bench::quantile_or(edit_cpu, 0.5, 0)},
                    {"median_update_cpu_ms", bench::quantile_or(update_cpu, 0.5, 0)},
                    {"median_edit_update_cpu_ms", bench::quantile_or(both_cpu, 0.5, 0)},
                    {"p90_edit_update_cpu_ms", bench::quantile_or(both_cpu, 0.9, 0)},
                    {"median_edit_update_ms", bench::quantile_or(both_wall, 0.5, 0)},
                    {"median_samples_changed", bench::quantile_or(samples, 0.5, 0)}});
  }
  nlohmann::ordered_json j = {
      {"benchmark", "deform"},
      {"source", a.terrain.source()},
      {"spacing", {hf.spacing_x, hf.spacing_z}},
      {"patch_exponent", *k},
      {"what",
       "per crater at a random position: Terrain::apply_edit alone (wall: median_ms; CPU), then "
       "the next update of one converged RoamView, which brings its landscape's bounds and its "
       "mesh up to the edit (CPU time of this thread; wall for edit + update)"},
      {"results", rows}};
  if (auto s = write_json(j, a.json_path); !s) return report_error(s.message());
  return 0;
}

}  // namespace

Command add_deform_command(CLI::App& parent) {
  auto* app = parent.add_subcommand(
      "deform", "Apply the edits of EDITS.json to a terrain and optionally save the edit state");
  auto a = std::make_shared<DeformArgs>();
  a->terrain.add_to(*app);
  app->add_option("--edits", a->edits,
                  "Edit list: {\"edits\": [{\"brush\": \"crater\", \"x\": .., \"z\": .., "
                  "\"radius\": .., \"depth\": ..}, ...]}")
      ->type_name("EDITS.json")
      ->required();
  app->add_option("--save", a->save, "Save the resulting edit state (temporary file + rename)")
      ->type_name("STATE.bin");
  app->add_option("--json", a->json_path, "Write the JSON to FILE instead of standard output")
      ->type_name("FILE");
  return {app, [a] { return run_deform(*a); }};
}

Command add_bench_deform_command(CLI::App& bench) {
  auto* app = bench.add_subcommand(
      "deform",
      "ms per crater edit, and per edit plus the next view update (bounds, view queues, dirty "
      "patches), per radius (JSON)");
  auto a = std::make_shared<BenchDeformArgs>();
  a->terrain.add_to(*app);
  app->add_option("--radii", a->radii, "Crater radii in metres (default 5,20,100)")
      ->type_name("R1,R2,..");
  app->add_option("--count", a->count, "Edits per radius (default 200)")->type_name("N");
  app->add_option("--patch-exponent", a->patch_exponent, "Patch size 2^K cells (default 6)")
      ->type_name("K");
  app->add_option("--seed", a->seed, "Seed of the edit positions (default 1)")->type_name("S");
  app->add_option("--json", a->json_path, "Write the JSON to FILE instead of standard output")
      ->type_name("FILE");
  return {app, [a] { return run_bench_deform(*a); }};
}

}  // namespace ridgeline::cli
