// `ridge report`: what each level of accuracy costs. For every scene, camera path and setting
// (thresholds in pixels, triangle caps, time budgets) it runs, in one process, ROAM coherent,
// ROAM rebuild, the SOAR refinement, and at ROAM's median triangle count a uniform grid and a
// CDLOD-like quadtree, and writes per-setting medians as JSON and CSV (docs/report.md). This file
// is the command-line glue; what it runs is in report/ (stats, modes, storm, inputs).
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <sstream>
#include <thread>

#include "cli_util.h"
#include "commands.h"
#include "report/inputs.h"
#include "report/noise_files.h"
#include "report/storm.h"
#include "ridgeline/bench/clock.h"
#include "ridgeline/bench/stats.h"

namespace ridgeline::cli {

namespace {

using bench::Clock;
using bench::ms_since;
using report::Json;
using report::NamedPath;
using report::Options;
using report::Run;
using report::Scene;
using report::Setting;

// One scene: every path (or the chosen ones) and every setting; appends CSV rows only when the
// whole scene ran.
Result<Json> run_scene(Scene& sc, const Options& o, const std::vector<Setting>& settings,
                       std::string& csv_out) {
  const auto t0 = Clock::now();
  std::string csv;
  const WorldInfo& hf = sc.terrain->info();
  Json j = {{"name", sc.name},
            {"source", sc.source},
            {"samples", {hf.width, hf.height}},
            {"spacing_m", {hf.spacing_x, hf.spacing_z}},
            {"origin_m", {hf.origin_x, hf.origin_z}},
            {"height_range_m",
             {hf.height_offset + hf.min_local, hf.height_offset + hf.max_local}},
            {"filled_samples", hf.filled_samples},
            {"loader", sc.loader},
            {"loader_messages", sc.messages}};
  if (sc.fine) {
    j["detail"] = sc.detail;
    j["measured_lattice"] = {sc.fine->width(), sc.fine->height()};
    j["measured_lattice_spacing_m"] = {sc.fine->spacing_x(), sc.fine->spacing_z()};
  }
  j["error_stride"] = o.stride;
  Json paths = Json::array();
  for (const NamedPath& p : bench::make_paths(*sc.terrain, o.frames)) {
    if (!o.paths.empty() && std::find(o.paths.begin(), o.paths.end(), p.name) == o.paths.end())
      continue;
    Json rows = Json::array();
    for (const Setting& st : settings) {
      std::vector<Run> modes;
      for (RoamMode mode : {RoamMode::kCoherent, RoamMode::kRebuild}) {
        auto r = report::run_roam(sc, p, st, mode, o);
        if (!r) return r.error();
        modes.push_back(std::move(*r));
      }
      const double target = bench::median(modes.front().triangles);
      for (auto run : {&report::run_uniform, &report::run_cdlod}) {
        auto r = run(sc, p, target, o);
        if (!r) return r.error();
        modes.push_back(std::move(*r));
      }
      if (o.soar) {
        auto r = report::run_soar(sc, p, st, o);
        if (!r) return r.error();
        modes.push_back(std::move(*r));
      }
      const std::string prefix =
          sc.name + "," + p.name + "," + st.kind + "," + csv_number(st.value);
      rows.push_back({{"kind", st.kind},
                      {"value", st.value},
                      {"modes", report::modes_json(modes, prefix, csv)}});
      std::fprintf(stderr, "ridge report: %s %s %s %g done (%.1f s)\n", sc.name.c_str(),
                   p.name.c_str(), st.kind.c_str(), st.value, ms_since(t0) / 1000);
    }
    paths.push_back({{"name", p.name}, {"frames", p.frames.size()}, {"settings", rows}});
  }
  j["paths"] = paths;
  j["wall_s"] = ms_since(t0) / 1000;
  csv_out += csv;
  return j;
}

// ---- the command ------------------------------------------------------------------------

struct ReportArgs {
  bool smoke = false;
  std::string skip;  // comma-separated: detail, storm, hard
  std::string out = "docs/benchmarks/report", noise, dem, dem_spacing = "598,927", dem_nodata,
              frames, error_every, paths, work, write_noise;
};

// The options of a run, from the flags; an error names the flag.
Result<Options> options_of(const ReportArgs& a) {
  Options o;
  if (a.smoke) {
    o.frames = 12;
    o.error_every = 3;
    o.thresholds = {2, 8};
    o.triangle_caps = {2000};
    o.time_budgets = {1};
  }
  if (!a.frames.empty()) {
    auto f = parse_count(a.frames, "--frames", 3, 100000);
    if (!f) return f.error();
    o.frames = int(*f);
  }
  if (!a.error_every.empty()) {
    auto k = parse_count(a.error_every, "--error-every", 2, 100000);
    if (!k) return k.error();
    o.error_every = int(*k);
  }
  if (o.frames <= o.error_every)
    return Error{"--frames must exceed --error-every (errors are measured every K-th frame)"};
  static const char* known[] = {"flyover", "drive", "fast_yaw", "zoom", "down", "fast_pass"};
  std::stringstream ss(a.paths);
  for (std::string p; std::getline(ss, p, ',');) {
    if (std::find_if(std::begin(known), std::end(known), [&](const char* k) { return p == k; }) ==
        std::end(known))
      return Error{"--paths: unknown path '" + p +
                   "' (flyover, drive, fast_yaw, zoom, down, fast_pass)"};
    o.paths.push_back(p);
  }
  return o;
}

// The parts of the report to leave out (--skip).
Result<std::vector<std::string>> skips_of(const std::string& list) {
  std::vector<std::string> skip;
  std::stringstream ss(list);
  for (std::string p; std::getline(ss, p, ',');) {
    if (p != "detail" && p != "storm" && p != "hard" && p != "soar")
      return Error{"--skip: unknown part '" + p + "' (detail, storm, hard, soar)"};
    skip.push_back(p);
  }
  return skip;
}

// The main scenes: the smoke run's synthetic field, or the noise field and the DEM given.
Result<std::vector<Scene>> main_scenes(const ReportArgs& a, bool detail_skipped) {
  std::vector<Scene> scenes;
  if (a.smoke) {
    scenes.push_back(report::synthetic_scene("synthetic129", 129, scenes::Shape::kHills, 0.0, 4.0));
    return scenes;
  }
  if (a.noise.empty() && a.dem.empty() && detail_skipped)
    return Error{"give --noise FILE and/or --dem FILE (or --smoke)"};
  if (!a.noise.empty()) {
    auto sc = report::noise_scene(a.noise);
    if (!sc) return sc.error();
    scenes.push_back(std::move(*sc));
  }
  if (!a.dem.empty()) {
    auto sp = parse_finite_list(a.dem_spacing, "--dem-spacing", 2, 2);
    if (!sp) return sp.error();
    if ((*sp)[0] <= 0 || (*sp)[1] <= 0) return Error{"--dem-spacing must be > 0"};
    auto sc = report::dem_scene(a.dem, *sp, a.dem_nodata);
    if (!sc) return sc.error();
    scenes.push_back(std::move(*sc));
  }
  return scenes;
}

// Numerical hard cases: one setting (2 px), flyover and drive, every mode.
Result<Json> run_hard_cases(const ReportArgs& a, const Options& o, std::string& csv) {
  Options ho = o;
  ho.frames = a.smoke ? 12 : 60;
  ho.paths = {"flyover", "drive"};
  const std::vector<Setting> hs = {{"threshold", 2.0}};
  const std::uint32_t hn = a.smoke ? 65 : 257;
  using report::synthetic_scene;
  using scenes::Shape;
  std::vector<Scene> hard;
  hard.push_back(synthetic_scene("origin_0", hn, Shape::kHills, 0.0, 4.0));
  hard.push_back(synthetic_scene("origin_1e6", hn, Shape::kHills, 1e6, 4.0));
  hard.push_back(synthetic_scene("origin_1e7", hn, Shape::kHills, 1e7, 4.0));
  hard.push_back(synthetic_scene("cliff_1000m", hn, Shape::kCliff, 0.0, 4.0));
  hard.push_back(synthetic_scene("flat", hn, Shape::kFlat, 0.0, 4.0));
  const std::filesystem::path work = a.work.empty()
                                         ? std::filesystem::temp_directory_path() / "ridge_report"
                                         : std::filesystem::path(a.work);
  auto lc = report::loader_cases(work, hn);
  if (!lc) return lc.error();
  for (auto& s : *lc) hard.push_back(std::move(s));
  Json out = Json::array();
  for (Scene& sc : hard) {
    if (!sc.terrain) {  // the loader refused it: that is the result
      out.push_back({{"name", sc.name},
                     {"source", sc.source},
                     {"loader", sc.loader},
                     {"loader_messages", sc.messages},
                     {"loaded", false}});
      continue;
    }
    auto j = run_scene(sc, ho, hs, csv);
    if (!j) {
      out.push_back({{"name", sc.name},
                     {"loader_messages", sc.messages},
                     {"loaded", true},
                     {"run_error", j.error().message}});
      continue;
    }
    (*j)["loaded"] = true;
    out.push_back(*j);
  }
  return out;
}

int run_report(const ReportArgs& a) {
  bench::keep_freed_memory();
  if (!a.write_noise.empty()) {  // only the input files
    if (auto s = report::write_noise_field(a.write_noise); !s) return report_error(s.message());
    return 0;
  }
  const auto t0 = Clock::now();
  auto opt = options_of(a);
  if (!opt) return report_error(opt.error().message);
  Options& o = *opt;
  auto skip = skips_of(a.skip);
  if (!skip) return report_error(skip.error().message);
  auto skips = [&](const char* part) {
    return std::find(skip->begin(), skip->end(), part) != skip->end();
  };
  o.soar = !skips("soar");
  auto scenes = main_scenes(a, skips("detail"));
  if (!scenes) return report_error(scenes.error().message);

  std::string csv;
  Json out_scenes = Json::array();
  for (Scene& sc : *scenes) {
    auto j = run_scene(sc, o, o.settings(), csv);
    if (!j) return report_error(sc.name + ": " + j.error().message);
    out_scenes.push_back(*j);
  }
  // The procedural-detail world: three thresholds (1, 4, 16 px; smoke: its own), to keep the
  // full report within 30 minutes.
  if (!skips("detail")) {
    auto sc = a.smoke ? report::detail_scene(65, 2) : report::detail_scene(129, 2);
    if (!sc) return report_error("detail scene: " + sc.error().message);
    std::vector<Setting> ds;
    for (double t : a.smoke ? o.thresholds : std::vector<double>{1, 4, 16})
      ds.push_back({"threshold", t});
    auto j = run_scene(*sc, o, ds, csv);
    if (!j) return report_error(sc->name + ": " + j.error().message);
    out_scenes.push_back(*j);
  }
  // The deformation storm on the first scene (the noise field; the smoke field with --smoke).
  if (!scenes->empty() && !skips("storm")) {
    auto j = report::run_storm(scenes->front(), o, csv);
    if (!j) return report_error("storm: " + j.error().message);
    out_scenes.push_back(*j);
  }
  Json out_hard = Json::array();
  if (!skips("hard")) {
    auto h = run_hard_cases(a, o, csv);
    if (!h) return report_error(h.error().message);
    out_hard = *h;
  }

  Json root = {{"report", "ridge report"},
               {"smoke", a.smoke},
               {"machine", {{"hardware_threads", std::thread::hardware_concurrency()}}},
               {"frames_per_path", o.frames},
               {"error_every", o.error_every},
               {"error_stride", o.stride},
               {"match_tolerance", report::kMatchTolerance},
               {"settings",
                {{"thresholds_px", o.thresholds},
                 {"triangle_caps", o.triangle_caps},
                 {"time_budgets_ms", o.time_budgets},
                 {"time_budget_threshold_px", 1.0}}},
               {"scenes", out_scenes},
               {"hard_cases", out_hard},
               {"wall_s", ms_since(t0) / 1000}};
  std::error_code ec;
  std::filesystem::create_directories(a.out, ec);
  if (auto s = write_json(root, (std::filesystem::path(a.out) / "report.json").string()); !s)
    return report_error(s.message());
  if (auto s = write_output(csv, (std::filesystem::path(a.out) / "report.csv").string()); !s)
    return report_error(s.message());
  std::fprintf(stderr, "ridge report: wrote %s/report.json and report.csv in %.1f s\n",
               a.out.c_str(), ms_since(t0) / 1000);
  return 0;
}

}  // namespace

Command add_report_command(CLI::App& parent) {
  auto* app = parent.add_subcommand(
      "report",
      "Speed versus error: ROAM (coherent, rebuild), SOAR, a uniform grid and a CDLOD-like "
      "quadtree over thresholds, triangle caps and time budgets, every scene and camera path, in "
      "one run "
      "(JSON + CSV; docs/report.md)");
  auto a = std::make_shared<ReportArgs>();
  app->add_flag("--smoke", a->smoke,
                "A tiny synthetic scene, 12 frames per path, 2 thresholds (for CI)");
  app->add_option("--skip", a->skip,
                  "Leave out parts of the report (comma-separated: detail, storm, hard, soar)")
      ->type_name("LIST");
  app->add_option("--out", a->out, "Output directory (default docs/benchmarks/report)")
      ->type_name("DIR");
  app->add_option(
         "--noise", a->noise,
         "The 1025 x 1025 noise field (--write-noise-field writes it; spacing 1, scale 0.005)")
      ->type_name("FILE.png");
  app->add_option("--dem", a->dem,
                  "A real DEM (elev.tif of r-cran-terra); no-data (its GDAL tag) filled nearest")
      ->type_name("FILE");
  app->add_option("--dem-spacing", a->dem_spacing,
                  "The DEM's cell size in metres (default 598,927: elev.tif's 1/120 degree at "
                  "49.8 N)")
      ->type_name("SX,SZ");
  app->add_option("--dem-nodata", a->dem_nodata,
                  "The DEM's no-data value (default: the file's GDAL_NODATA tag, -32768 in "
                  "elev.tif, which the image loader reads)")
      ->type_name("V");
  app->add_option("--frames", a->frames, "Frames per path (default 60; smoke 12)")->type_name("N");
  app->add_option("--error-every", a->error_every,
                  "Measure error and popping every K-th frame (default 6; smoke 3)")
      ->type_name("K");
  app->add_option("--paths", a->paths, "Only these paths (comma-separated)")->type_name("LIST");
  app->add_option("--write-noise-field", a->write_noise,
                  "Only write the noise field and its circle path (noise1025.png, "
                  "noise1025_circle.json) into DIR, then exit")
      ->type_name("DIR");
  app->add_option("--work", a->work, "Directory for the loader hard cases' files (default: temp)")
      ->type_name("DIR");
  return {app, [a] { return run_report(*a); }};
}

}  // namespace ridgeline::cli
