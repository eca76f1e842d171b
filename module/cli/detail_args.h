// The detail flags of the `ridge` subcommands (--detail-levels, --detail-seed, ... : every field
// of DetailParams, docs/detail.md), defined once so that every subcommand reads them the same way.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "ridgeline/detail.h"
#include "ridgeline/result.h"

namespace ridgeline::cli {

/// Holds the values of the detail flags after parsing. Add them with add_to(), parse, then call
/// params(), which parses every given value strictly and validates the result
/// (validate_detail_params), naming the bad flag.
class DetailArgs {
 public:
  /// Adds --detail-levels, --detail-seed, --detail-amplitude, --detail-gain,
  /// --detail-flat-shape, --detail-steep-shape, --detail-flat-slope, --detail-steep-slope and
  /// --detail-blur-radius to `app`, in an option group "Detail". `default_levels` is the level
  /// count used when --detail-levels is not given. The object must outlive the parse.
  void add_to(CLI::App& app, std::uint32_t default_levels);

  /// DetailParams with the given flags applied over the defaults.
  Result<DetailParams> params() const;

 private:
  std::uint32_t default_levels_ = 4;
  std::string levels_, seed_, amplitude_, gain_, flat_shape_, steep_shape_, flat_slope_,
      steep_slope_, blur_radius_;
};

}  // namespace ridgeline::cli
