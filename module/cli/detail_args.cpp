#include "detail_args.h"

#include <cstdio>
#include <limits>

#include "cli_util.h"

namespace ridgeline::cli {

void DetailArgs::add_to(CLI::App& app, std::uint32_t default_levels) {
  default_levels_ = default_levels;
  const std::string g = "Detail";
  const DetailParams d;
  auto num = [](double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return std::string(buf);
  };
  app.add_option("--detail-levels", levels_,
                 "Detail levels L, 0.." + std::to_string(kMaxDetailLevels) +
                     ": finest spacing = spacing / 2^L (default " + std::to_string(default_levels) +
                     ")")
      ->type_name("N")
      ->group(g);
  app.add_option("--detail-seed", seed_,
                 "Seed of the detail hash (default " + std::to_string(d.seed) + ")")
      ->type_name("S")
      ->group(g);
  app.add_option("--detail-amplitude", amplitude_,
                 "Amplitude of level 1's octave in metres where the shape is 1, 0..1000 (default " +
                     num(d.amplitude) + ")")
      ->type_name("M")
      ->group(g);
  app.add_option("--detail-gain", gain_,
                 "Amplitude ratio between successive levels, (0, 1] (default " + num(d.gain) + ")")
      ->type_name("G")
      ->group(g);
  app.add_option(
         "--detail-flat-shape", flat_shape_,
         "Shape (amplitude factor) on flat ground, 0..1 (default " + num(d.flat_shape) + ")")
      ->type_name("F")
      ->group(g);
  app.add_option("--detail-steep-shape", steep_shape_,
                 "Shape on steep ground, 0..1 (default " + num(d.steep_shape) + ")")
      ->type_name("F")
      ->group(g);
  app.add_option(
         "--detail-flat-slope", flat_slope_,
         "Slope (rise/run) at or below which ground is flat (default " + num(d.flat_slope) + ")")
      ->type_name("S")
      ->group(g);
  app.add_option("--detail-steep-slope", steep_slope_,
                 "Slope at or above which ground is steep (default " + num(d.steep_slope) + ")")
      ->type_name("S")
      ->group(g);
  app.add_option("--detail-blur-radius", blur_radius_,
                 "Box-blur radius of the slope map in stored samples, 0..64 (default " +
                     std::to_string(d.blur_radius) + ")")
      ->type_name("R")
      ->group(g);
}

Result<DetailParams> DetailArgs::params() const {
  DetailParams p;
  p.levels = default_levels_;
  if (!levels_.empty()) {
    auto v = parse_count(levels_, "--detail-levels", 0, kMaxDetailLevels);
    if (!v) return v.error();
    p.levels = static_cast<std::uint32_t>(*v);
  }
  if (!seed_.empty()) {
    auto v = parse_count(seed_, "--detail-seed", 0, std::numeric_limits<std::uint64_t>::max());
    if (!v) return v.error();
    p.seed = *v;
  }
  if (!blur_radius_.empty()) {
    auto v = parse_count(blur_radius_, "--detail-blur-radius", 0, 64);
    if (!v) return v.error();
    p.blur_radius = static_cast<std::uint32_t>(*v);
  }
  const struct {
    const std::string& text;
    const char* flag;
    double* field;
  } reals[] = {{amplitude_, "--detail-amplitude", &p.amplitude},
               {gain_, "--detail-gain", &p.gain},
               {flat_shape_, "--detail-flat-shape", &p.flat_shape},
               {steep_shape_, "--detail-steep-shape", &p.steep_shape},
               {flat_slope_, "--detail-flat-slope", &p.flat_slope},
               {steep_slope_, "--detail-steep-slope", &p.steep_slope}};
  for (const auto& r : reals) {
    if (r.text.empty()) continue;
    auto v = parse_finite(r.text, r.flag);
    if (!v) return v.error();
    *r.field = *v;
  }
  if (auto s = validate_detail_params(p); !s) return Error{s.message()};
  return p;
}

}  // namespace ridgeline::cli
