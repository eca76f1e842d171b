// The scenes of `ridge report` (docs/report_method.md, "Scenes"): the noise field and the real DEM as a
// user would load them (loader messages captured), the procedural-detail world, the synthetic
// fields of the smoke run and the hard cases, and the loader hard cases written to files and
// read back. Part of the `ridge` tool (it uses Ridgeline::io).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "report/modes.h"
#include "ridgeline/scenes.h"

namespace ridgeline::report {

/// The noise field loaded from `png` (spacing 1, height scale 0.005).
Result<Scene> noise_scene(const std::string& png);
/// A real DEM loaded first without a fill policy (the refusal is recorded), then with
/// `--fill nearest`; `spacing` SX,SZ metres, `nodata` as given or empty (the file's tag).
Result<Scene> dem_scene(const std::string& file, const std::vector<double>& spacing,
                        const std::string& nodata);
/// The procedural-detail world: the default terrain at size x size (2 m) with `levels` detail
/// levels, a fresh cold tile cache for every ROAM run, and the finest lattice baked.
Result<Scene> detail_scene(std::uint32_t size, std::uint32_t levels);
/// A synthetic n x n field of `shape` (scenes.h) at `spacing`, origin (origin, origin).
Scene synthetic_scene(const std::string& name, std::uint32_t n, scenes::Shape shape, double origin,
                      double spacing);
/// The loader hard cases: files written to `dir`, read back through Ridgeline::io's raw loader;
/// a refused file gives a scene without terrain (the refusal is the result).
Result<std::vector<Scene>> loader_cases(const std::filesystem::path& dir, std::uint32_t n);

}  // namespace ridgeline::report
