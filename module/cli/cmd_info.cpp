// `ridge info`: what a terrain is, as JSON.
#include <cmath>
#include <cstdio>
#include <memory>

#include "cli_util.h"
#include "commands.h"
#include "terrain_args.h"

namespace ridgeline::cli {

namespace {

struct InfoOptions {
  TerrainArgs terrain;
  std::string json_path;
};

const char* source_of(bool flag, bool from_file) {
  return flag ? "flag" : from_file ? "geotiff" : "default";
}

int run_info(const InfoOptions& o) {
  io::LoadReport report;
  auto terrain = o.terrain.load_terrain(&report);
  if (!terrain) return report_error(terrain.error().message);
  const WorldInfo& hf = (*terrain)->info();
  const std::uint64_t samples = std::uint64_t{hf.width} * hf.height;
  char hash[24];
  std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(hf.content_hash));
  const std::size_t bytes = (*terrain)->memory_bytes();
  const nlohmann::ordered_json j = {
      {"source", o.terrain.source()},
      {"width", hf.width},
      {"height", hf.height},
      {"samples", samples},
      {"pixel_type", report.pixel_type},
      {"spacing", {hf.spacing_x, hf.spacing_z}},
      {"spacing_source", source_of(o.terrain.given("--spacing"), report.spacing_from_file)},
      {"origin", {hf.origin_x, hf.origin_z}},
      {"origin_source", source_of(o.terrain.given("--origin"), report.origin_from_file)},
      {"file_placement", report.file_placement
                             ? nlohmann::ordered_json(report.file_placement->description)
                             : nlohmann::ordered_json()},
      {"extent", {hf.extent_x(), hf.extent_z()}},
      {"height_offset", hf.height_offset},
      {"height_scale", hf.height_scale},
      {"height_min", hf.height_offset + double(hf.min_local)},
      {"height_max", hf.height_offset + double(hf.max_local)},
      {"has_materials", hf.has_materials},
      {"filled_samples", hf.filled_samples},
      {"filled_fraction", double(hf.filled_samples) / double(samples)},
      {"stored_bytes", (*terrain)->world_stats().resident_bytes},
      {"memory_bytes", bytes},
      {"bytes_per_sample", double(bytes) / double(samples)},
      {"content_hash", hash},
      {"detail_levels", (*terrain)->surface().detail_levels()},
      {"finest_spacing",
       {std::ldexp(hf.spacing_x, -int((*terrain)->surface().detail_levels())),
        std::ldexp(hf.spacing_z, -int((*terrain)->surface().detail_levels()))}},
      {"warnings", report.warnings},
  };
  if (auto s = write_json(j, o.json_path); !s) return report_error(s.message());
  return 0;
}

}  // namespace

Command add_info_command(CLI::App& parent) {
  auto* app = parent.add_subcommand(
      "info", "Size, extent, height range, memory used and content hash of a terrain (JSON)");
  auto o = std::make_shared<InfoOptions>();
  o->terrain.add_to(*app);
  app->add_option("--json", o->json_path, "Write the JSON to FILE instead of standard output")
      ->type_name("FILE");
  return {app, [o] { return run_info(*o); }};
}

}  // namespace ridgeline::cli
