#include "terrain_args.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>

#include "cli_util.h"
#include "ridgeline/detail.h"
#include "ridgeline/edit.h"
#include "ridgeline/edit_file.h"
#include "ridgeline/io.h"
#include "ridgeline/log.h"
#include "ridgeline/world_file.h"

namespace ridgeline::cli {

namespace {
// The spacings --spacing accepts, metres (docs/data_model.md, "Placement").
constexpr double kMinSpacingM = 1e-6, kMaxSpacingM = 1e6;
}  // namespace

void TerrainArgs::add_to(CLI::App& app) {
  app_ = &app;
  const std::string g = "Terrain";
  auto* hm = app.add_option("--heightmap", heightmaps_,
                            "Heightmap file: 8/16-bit greyscale PNG, 16-bit or float TIFF, float "
                            "EXR, or headerless raw (with --raw-size, --raw-type). Repeat it for a "
                            "world of several files (placed by --layout, or by their GeoTIFF "
                            "georeferencing)")
                 ->type_name("FILE")
                 ->group(g);
  auto* wd = app.add_option("--world", world_,
                            "A baked world (made by ridge bake --out WORLD), paged in under "
                            "--cache-mb")
                 ->type_name("WORLD")
                 ->group(g);
  app.add_option("--layout", layout_,
                 "Files of a world of several --heightmap files as a grid of COLS x ROWS, given "
                 "row by row (default: by their georeferencing)")
      ->type_name("COLSxROWS")
      ->group(g);
  app.add_flag("--unshared-edges", unshared_edges_,
               "Neighbouring --heightmap files abut instead of repeating their shared edge")
      ->group(g);
  app.add_option("--cache-mb", cache_mb_,
                 "Memory budget of a baked world's pages in MiB, >= 4 (default 192)")
      ->type_name("MB")
      ->group(g);
  app.add_option("--cache-workers", cache_workers_,
                 "Threads loading a baked world's pages, 0..64 (default 0 for the tools: a page "
                 "is loaded when first needed)")
      ->type_name("N")
      ->group(g);
  auto* dt = app.add_flag("--default-terrain", default_terrain_,
                          "Use the built-in default terrain (1025 x 1025 samples, 2 m spacing, "
                          "seed 1337)")
                 ->group(g);
  app.add_option("--default-size", default_size_,
                 "Samples per side of the default terrain, 2..65536 (default 1025; the same "
                 "landscape, stretched)")
      ->type_name("N")
      ->group(g);
  hm->excludes(dt);
  dt->excludes(hm);
  wd->excludes(hm);
  wd->excludes(dt);
  hm->excludes(wd);
  dt->excludes(wd);
  // A terrain source is required: a usage error (exit 2) found after parsing, after --help.
  app.parse_complete_callback([this] {
    if (!given("--heightmap") && !given("--world") && !default_terrain_)
      throw CLI::RequiredError(
          "no terrain given: pass --heightmap FILE, --world WORLD or --default-terrain",
          CLI::ExitCodes::RequiredError);
  });
  app.add_option("--raw-size", raw_size_, "Size of a raw heightmap in samples")
      ->type_name("W,H")
      ->group(g);
  app.add_option("--raw-type", raw_type_,
                 "Sample type of a raw heightmap, little-endian (default from the extension: "
                 ".r16 u16, .r32 f32)")
      ->type_name("u16|f32")
      ->group(g);
  app.add_option("--spacing", spacing_,
                 "Metres between samples, 1e-6 .. 1e6: one value for both axes or SX,SZ "
                 "(default: a GeoTIFF's own placement, else 1)")
      ->type_name("S|SX,SZ")
      ->group(g);
  app.add_option(
         "--height-scale", height_scale_,
         "Height = offset + scale * value, value being the raw integer or float (default 1)")
      ->type_name("K")
      ->group(g);
  app.add_option("--height-offset", height_offset_, "Height offset in metres (default 0)")
      ->type_name("O")
      ->group(g);
  app.add_option("--origin", origin_,
                 "World position of sample (0, 0) in metres (default: a projected GeoTIFF's own "
                 "placement, else 0,0)")
      ->type_name("X,Z")
      ->group(g);
  app.add_option("--nodata", nodata_,
                 "Raw value that marks a missing sample (refused unless --fill is given)")
      ->type_name("V")
      ->group(g);
  app.add_option("--fill", fill_,
                 "Replace missing (no-data or non-finite) samples: by the nearest valid sample, "
                 "by the raw value V, or make every cell with a missing corner a hole (no ground)")
      ->type_name("nearest|constant:V|hole")
      ->group(g);
  app.add_option("--max-samples", max_samples_,
                 "Refuse heightmaps of more samples than N, checked before allocating (default "
                 "268468225 = 16385 x 16385; bake larger maps with ridge bake)")
      ->type_name("N")
      ->group(g);
  app.add_option("--channel", channel_,
                 "Channel of a multi-channel image to use (0-based); without it colour images are "
                 "refused")
      ->type_name("C")
      ->group(g);
  app.add_flag("--alpha-nodata", alpha_nodata_,
               "Samples whose alpha is 0 are missing (as no-data samples are; --fill hole makes "
               "them holes)")
      ->group(g);
  app.add_option("--materials", materials_,
                 "8-bit single-channel image of the heightmap's size holding a material id per "
                 "sample")
      ->type_name("FILE")
      ->group(g);
  const std::string gd = "Procedural detail";
  app.add_option("--detail-levels", detail_levels_,
                 "Detail levels below the stored resolution, 0..12, each halving the spacing "
                 "(default 0: none)")
      ->type_name("N")
      ->group(gd);
  app.add_option("--detail-seed", detail_seed_, "Seed of the detail function (default 1)")
      ->type_name("S")
      ->group(gd);
  app.add_option("--detail-amplitude", detail_amplitude_,
                 "Amplitude of the first detail octave in metres where the shape is 1 (default 2)")
      ->type_name("M")
      ->group(gd);
  app.add_option("--detail-gain", detail_gain_,
                 "Amplitude ratio between successive detail levels, (0, 1] (default 0.5)")
      ->type_name("G")
      ->group(gd);
  const struct {
    const char* flag;
    std::string* value;
    const char* help;
  } shape_flags[] = {
      {"--detail-flat-shape", &detail_flat_shape_,
       "Detail shape (amplitude factor) on flat ground, 0..1 (default 0.25)"},
      {"--detail-steep-shape", &detail_steep_shape_,
       "Detail shape on steep ground, 0..1 (default 1)"},
      {"--detail-flat-slope", &detail_flat_slope_,
       "Slope (rise/run) at or below which ground is flat for the detail (default 0.05)"},
      {"--detail-steep-slope", &detail_steep_slope_,
       "Slope at or above which ground is steep for the detail (default 0.6)"},
      {"--detail-blur-radius", &detail_blur_radius_,
       "Box-blur radius of the slope map in stored samples, 0..64 (default 2)"}};
  for (const auto& f : shape_flags)
    app.add_option(f.flag, *f.value, f.help)->type_name("X")->group(gd);
  app.add_option("--detail-budget-mb", detail_budget_mb_,
                 "Memory budget of the detail tile cache in MiB (default 256)")
      ->type_name("MB")
      ->group(gd);
  app.add_option("--load", load_,
                 "Apply the edit state saved by `ridge deform --save` (refused when it belongs to "
                 "another terrain)")
      ->type_name("STATE.bin")
      ->group(g);
}

bool TerrainArgs::given(const char* flag) const {
  return app_ && app_->count(flag) > 0;
}

std::string TerrainArgs::source() const {
  if (default_terrain_) return "default terrain";
  if (given("--world")) return world_;
  std::string s;
  for (const std::string& h : heightmaps_) s += (s.empty() ? "" : " + ") + h;
  return s;
}

namespace {

// The loaders' warning for a map mostly filled from no-data, for the generated terrain placed
// with --nodata and --fill (loaded files get it from the loader).
void warn_if_filled(const Heightfield& hf, io::LoadReport* report) {
  const double samples = double(hf.width()) * double(hf.height());
  const double fraction = double(hf.filled_samples()) / samples;
  if (fraction <= io::kFilledWarningFraction) return;
  char text[160];
  std::snprintf(text, sizeof text,
                "%llu of %.0f samples (%.1f %%) are filled from no-data: that part of the terrain "
                "is invented",
                static_cast<unsigned long long>(hf.filled_samples()), samples, 100.0 * fraction);
  log_message(LogLevel::kWarning, std::string("default terrain: ") + text);
  if (report != nullptr) report->warnings.push_back(text);
}

}  // namespace

Result<HeightfieldDesc> TerrainArgs::placement() const {
  HeightfieldDesc d;
  if (given("--spacing")) {
    auto v = parse_finite_list(spacing_, "--spacing", 1, 2);
    if (!v) return v.error();
    d.spacing_x = (*v)[0];
    d.spacing_z = v->size() == 2 ? (*v)[1] : (*v)[0];
    if (d.spacing_x <= 0 || d.spacing_z <= 0)
      return Error{"--spacing '" + spacing_ + "': spacing must be > 0"};
    // docs/data_model.md, "Placement": below a micrometre the lattice's float positions and
    // normals lose their meaning; above 1,000 km a sample is no longer terrain.
    for (const double s : {d.spacing_x, d.spacing_z})
      if (s < kMinSpacingM || s > kMaxSpacingM)
        return Error{"--spacing '" + spacing_ + "': spacing must be within 1e-6 .. 1e6 metres"};
  }
  if (given("--height-scale")) {
    auto v = parse_finite(height_scale_, "--height-scale");
    if (!v) return v.error();
    if (*v <= 0) return Error{"--height-scale '" + height_scale_ + "': must be > 0"};
    d.height_scale = *v;
  }
  if (given("--height-offset")) {
    auto v = parse_finite(height_offset_, "--height-offset");
    if (!v) return v.error();
    d.height_offset = *v;
  }
  if (given("--origin")) {
    auto v = parse_finite_list(origin_, "--origin", 2, 2);
    if (!v) return v.error();
    d.origin_x = (*v)[0];
    d.origin_z = (*v)[1];
  }
  if (given("--nodata")) {
    auto v = parse_finite(nodata_, "--nodata");
    if (!v) return v.error();
    d.nodata = *v;
  }
  if (given("--fill")) {
    if (fill_ == "nearest") {
      d.fill = FillPolicy::kNearest;
    } else if (fill_ == "hole") {
      d.fill = FillPolicy::kHole;
    } else if (fill_.rfind("constant:", 0) == 0) {
      auto v = parse_finite(std::string_view(fill_).substr(9), "--fill constant");
      if (!v) return v.error();
      d.fill = FillPolicy::kConstant;
      d.fill_constant = *v;
    } else {
      return Error{"--fill '" + fill_ + "': expected 'nearest', 'constant:V' or 'hole'"};
    }
  }
  if (given("--max-samples")) {
    auto v =
        parse_count(max_samples_, "--max-samples", 4, std::numeric_limits<std::uint64_t>::max());
    if (!v) return v.error();
    d.max_samples = *v;
  }
  return d;
}

namespace {

// A size cap's message with the flag that raises it.
Error with_cap_hint(Error e) {
  if (e.message.find("max_samples") != std::string::npos)
    e.message += "; raise it with --max-samples N, or bake the map with ridge bake for a world "
                 "larger than memory";
  return e;
}

}  // namespace

Result<Heightfield> TerrainArgs::load_heightfield(io::LoadReport* report) const {
  auto hf = load_heightfield_uncapped(report);
  if (!hf) return with_cap_hint(hf.error());
  return hf;
}

Result<Heightfield> TerrainArgs::load_heightfield_uncapped(io::LoadReport* report) const {
  if (given("--world"))
    return Error{"--world: a baked world is paged in, not loaded as one heightfield (this "
                 "command needs --heightmap or --default-terrain)"};
  if (!given("--heightmap") && !default_terrain_)
    return Error{"no terrain given: pass --heightmap FILE, --world WORLD or --default-terrain"};
  auto desc = placement();
  if (!desc) return desc.error();
  for (const char* flag : {"--cache-mb", "--cache-workers"})
    if (given(flag)) return Error{std::string(flag) + " applies to --world"};
  if ((given("--layout") || given("--unshared-edges")) && heightmaps_.size() < 2)
    return Error{"--layout and --unshared-edges apply to a world of several --heightmap files"};

  if (given("--default-size") && !default_terrain_)
    return Error{"--default-size applies to --default-terrain"};
  if (default_terrain_) {
    for (const char* flag : {"--raw-size", "--raw-type", "--channel", "--materials", "--alpha-nodata"})
      if (given(flag))
        return Error{std::string(flag) + " applies to --heightmap, not to --default-terrain"};
    DefaultTerrainParams params;
    if (given("--default-size")) {
      auto n = parse_count(default_size_, "--default-size", 2, 65536);
      if (!n) return n.error();
      params.size = static_cast<std::uint32_t>(*n);
    }
    HeightfieldDesc d = *desc;
    d.width = d.height = params.size;
    d.name = "default terrain";
    // A placement flag changes only what it names: the terrain keeps its 2 m spacing unless
    // --spacing is given.
    if (!given("--spacing")) d.spacing_x = d.spacing_z = params.spacing;
    // The cap and the placement are checked before the terrain is generated.
    if (auto s = validate_heightfield_desc(d); !s) return Error{s.message()};
    auto base = make_default_heightfield(params);
    if (!base) return base.error();
    if (report != nullptr) report->pixel_type = "float (generated)";
    const bool placed = given("--spacing") || given("--height-scale") || given("--height-offset") ||
                        given("--origin") || given("--nodata") || given("--fill");
    if (!placed) return base;
    // The generated heights act as raw values for the placement flags.
    std::vector<std::uint8_t> mats;
    mats.reserve(std::size_t{base->width() - 1} * (base->height() - 1));
    for (std::uint32_t j = 0; j + 1 < base->height(); ++j)
      for (std::uint32_t i = 0; i + 1 < base->width(); ++i) mats.push_back(base->material(i, j));
    auto placed_hf = Heightfield::create(d, base->local_heights(), mats);
    if (placed_hf) warn_if_filled(*placed_hf, report);
    return placed_hf;
  }

  io::LoadOptions options;
  options.placement = *desc;
  options.materials_path = materials_;
  // A GeoTIFF's own placement unless the flags give one.
  options.spacing_from_file = !given("--spacing");
  options.origin_from_file = !given("--origin");
  options.alpha_nodata = alpha_nodata_;
  if (given("--channel")) {
    auto c = parse_count(channel_, "--channel", 0, 1023);
    if (!c) return c.error();
    options.channel = static_cast<int>(*c);
  }
  if (!given("--raw-size") && given("--raw-type")) return Error{"--raw-type needs --raw-size W,H"};
  io::TileLayout layout;
  layout.shared_edges = !unshared_edges_;
  if (given("--layout")) {
    unsigned c = 0, r = 0;
    char x = 0, extra = 0;
    if (std::sscanf(layout_.c_str(), "%u%c%u%c", &c, &x, &r, &extra) != 3 || (x != 'x' && x != 'X') ||
        c == 0 || r == 0)
      return Error{"--layout '" + layout_ + "': expected COLSxROWS, e.g. 2x3"};
    layout.columns = c, layout.rows = r;
  }
  if (given("--raw-size")) {
    io::RawFormat raw;
    auto size = parse_finite_list(raw_size_, "--raw-size", 2, 2);
    if (!size) return size.error();
    for (double v : *size)
      if (v != std::floor(v) || v < 0 || v > std::numeric_limits<std::uint32_t>::max())
        return Error{"--raw-size '" + raw_size_ + "': expected two whole numbers W,H"};
    raw.width = static_cast<std::uint32_t>((*size)[0]);
    raw.height = static_cast<std::uint32_t>((*size)[1]);
    std::string type = raw_type_;
    if (!given("--raw-type")) {
      const std::string ext = std::filesystem::path(heightmaps_[0]).extension().string();
      if (ext == ".r16") type = "u16";
      if (ext == ".r32") type = "f32";
    }
    if (type.empty()) return Error{"--raw-size needs --raw-type u16|f32"};
    auto t = io::parse_raw_type(type);
    if (!t) return Error{"--raw-type: " + t.error().message};
    raw.type = *t;
    if (heightmaps_.size() == 1) return io::load_raw(heightmaps_[0], raw, options, report);
    return io::load_tiles(heightmaps_, options, layout, &raw, report);
  }
  if (heightmaps_.size() == 1)
    return io::load_heightmap(heightmaps_[0], options, nullptr, report);
  return io::load_tiles(heightmaps_, options, layout, nullptr, report);
}

Result<DetailParams> TerrainArgs::detail_params() const {
  DetailParams detail;
  detail.levels = 0;
  if (given("--detail-levels")) {
    auto n = parse_count(detail_levels_, "--detail-levels", 0, kMaxDetailLevels);
    if (!n) return n.error();
    detail.levels = static_cast<std::uint32_t>(*n);
  }
  if (detail.levels == 0) {
    for (const char* flag : {"--detail-seed", "--detail-amplitude", "--detail-gain",
                             "--detail-budget-mb", "--detail-flat-shape", "--detail-steep-shape",
                             "--detail-flat-slope", "--detail-steep-slope", "--detail-blur-radius"})
      if (given(flag)) return Error{std::string(flag) + " needs --detail-levels N (N >= 1)"};
  }
  if (given("--detail-seed")) {
    auto v =
        parse_count(detail_seed_, "--detail-seed", 0, std::numeric_limits<std::uint64_t>::max());
    if (!v) return v.error();
    detail.seed = *v;
  }
  if (given("--detail-blur-radius")) {
    auto v = parse_count(detail_blur_radius_, "--detail-blur-radius", 0, 64);
    if (!v) return v.error();
    detail.blur_radius = static_cast<std::uint32_t>(*v);
  }
  const struct {
    const char* flag;
    const std::string& text;
    double* field;
  } reals[] = {{"--detail-amplitude", detail_amplitude_, &detail.amplitude},
               {"--detail-gain", detail_gain_, &detail.gain},
               {"--detail-flat-shape", detail_flat_shape_, &detail.flat_shape},
               {"--detail-steep-shape", detail_steep_shape_, &detail.steep_shape},
               {"--detail-flat-slope", detail_flat_slope_, &detail.flat_slope},
               {"--detail-steep-slope", detail_steep_slope_, &detail.steep_slope}};
  for (const auto& r : reals) {
    if (!given(r.flag)) continue;
    auto v = parse_finite(r.text, r.flag);
    if (!v) return v.error();
    *r.field = *v;
  }
  if (auto s = validate_detail_params(detail); !s) return Error{s.message()};
  return detail;
}

Result<std::shared_ptr<Terrain>> TerrainArgs::load_terrain(io::LoadReport* report) const {
  auto detail = detail_params();
  if (!detail) return detail.error();
  if (given("--world")) {
    // A baked world: its own placement and heights; detail is not baked into worlds.
    for (const char* flag : {"--spacing", "--height-scale", "--height-offset", "--origin",
                             "--nodata", "--fill", "--max-samples", "--channel", "--materials",
                             "--alpha-nodata",
                             "--raw-size", "--raw-type", "--layout", "--unshared-edges"})
      if (given(flag))
        return Error{std::string(flag) + " does not apply to --world (the world carries its "
                                         "own placement and heights)"};
    if (detail->levels > 0)
      return Error{"--detail-levels: procedural detail over a baked world is not supported; use "
                   "--heightmap for a terrain with detail"};
    WorldCacheDesc desc;
    desc.worker_threads = 0;
    if (given("--cache-mb")) {
      auto v = parse_count(cache_mb_, "--cache-mb", 4, 1u << 22);
      if (!v) return v.error();
      desc.budget_bytes = std::size_t(*v) << 20;
    }
    if (given("--cache-workers")) {
      auto v = parse_count(cache_workers_, "--cache-workers", 0, 64);
      if (!v) return v.error();
      desc.worker_threads = std::uint32_t(*v);
    }
    auto source = io::open_world(world_);
    if (!source) return source.error();
    auto t = Terrain::open(std::move(*source), desc);
    if (!t) return t.error();
    if (report != nullptr) report->pixel_type = (*t)->info().format == SampleFormat::kU16 ? "uint16 (baked)" : "float (baked)";
    std::shared_ptr<Terrain> terrain = std::move(*t);
    if (given("--load")) {
      auto r = io::load_edits(*terrain, load_);
      if (!r) return Error{"--load: " + r.error().message};
    }
    return terrain;
  }
  auto hf = load_heightfield(report);
  if (!hf) return hf.error();
  DetailCacheDesc cache;
  cache.worker_threads = 0;  // tools: synchronous, reproducible
  if (given("--detail-budget-mb")) {
    auto v = parse_count(detail_budget_mb_, "--detail-budget-mb", 1, 1u << 20);
    if (!v) return v.error();
    cache.budget_bytes = std::size_t(*v) << 20;
  }
  auto created = Terrain::create(std::move(*hf), *detail, cache);
  if (!created) return Error{created.error().message};
  std::shared_ptr<Terrain> terrain = std::move(*created);
  if (given("--load")) {
    auto r = io::load_edits(*terrain, load_);
    if (!r) return Error{"--load: " + r.error().message};
  }
  return terrain;
}

}  // namespace ridgeline::cli
