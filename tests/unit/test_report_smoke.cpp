// `ridge report --smoke` end to end: the JSON and CSV are complete and sane (what CI runs of the
// report; the full report is scripts/report.sh).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

namespace {

using nlohmann::json;

std::string slurp(const std::string& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

bool finite_number(const json& j) {
  return j.is_number() && std::isfinite(j.get<double>());
}

TEST(ReportSmoke, JsonAndCsvAreCompleteAndSane) {
  const std::string out = std::string(RIDGELINE_TEST_TMP) + "/report_smoke";
  const std::string cmd = std::string(RIDGE) + " report --smoke --out " + out + " --work " + out +
                          "/work 2> " + out + ".log";
  std::system(("mkdir -p " + out).c_str());
  ASSERT_EQ(std::system(cmd.c_str()), 0) << slurp(out + ".log");
  const json r = json::parse(slurp(out + "/report.json"));
  ASSERT_TRUE(r["smoke"].get<bool>());

  // Every scene, path and setting has the five modes (the storm four: no SOAR) with finite
  // figures.
  std::size_t rows = 0;
  auto check_scene = [&](const json& sc, bool all_paths, bool storm = false) {
    SCOPED_TRACE(sc["name"].get<std::string>());
    ASSERT_EQ(sc["paths"].size(), all_paths ? 6u : 2u);
    for (const json& p : sc["paths"]) {
      SCOPED_TRACE(p["name"].get<std::string>());
      for (const json& st : p["settings"]) {
        const std::string kind = st["kind"];
        const double value = st["value"];
        ASSERT_EQ(st["modes"].size(), storm ? 4u : 5u);
        std::map<std::string, json> m;
        for (const json& x : st["modes"]) m[x["mode"]] = x;
        for (const char* name :
             {"roam_coherent", "roam_rebuild", "uniform_grid", "cdlod", "soar"}) {
          SCOPED_TRACE(name);
          if (storm && std::string(name) == "soar") continue;
          ASSERT_TRUE(m.count(name));
          const json& x = m[name];
          ++rows;
          for (const char* f :
               {"triangles_median", "triangles_in_view_median", "update_ms_median", "update_ms_p99",
                "update_cpu_ms_median", "error_max_m", "error_rms_m", "screen_error_max_px",
                "screen_error_p99_px", "popping_max_px", "pop_max_px", "memory_bytes"})
            EXPECT_TRUE(finite_number(x[f])) << f << " = " << x[f];
          if (std::string(name) != "soar") {
            EXPECT_TRUE(finite_number(x["changes_per_frame_median"])) << x;
          }
          EXPECT_GT(x["triangles_in_view_median"].get<double>(), 0.0);
          if (std::string(name) == "uniform_grid") {  // a subset of a mesh that never changes
            EXPECT_LE(x["triangles_in_view_median"].get<double>(),
                      x["triangles_median"].get<double>());
          }
          // A geomorphing mode reports its morphed error and its morphed jump and pop.
          const bool morphs = std::string(name) == "cdlod" ||
                              (std::string(name).rfind("roam_", 0) == 0 && kind != "triangles");
          for (const char* f :
               {"screen_error_geomorph_max_px", "popping_geomorph_max_px", "pop_geomorph_max_px"})
            EXPECT_EQ(finite_number(x[f]), morphs) << f << " = " << x[f];
          EXPECT_GT(x["measured_frames"].get<int>(), 0);
          EXPECT_GT(x["measured_vertices_median"].get<double>(), 0);
          EXPECT_EQ(x["uncovered_vertices"].get<int>(), 0) << "holes in the drawn mesh";
          EXPECT_GE(x["error_max_m"].get<double>(), x["error_rms_m"].get<double>());
          EXPECT_GE(x["screen_error_max_px"].get<double>(), x["screen_error_p99_px"].get<double>());
          EXPECT_GE(x["update_ms_p99"].get<double>(), x["update_ms_median"].get<double>());
          EXPECT_GT(x["memory_bytes"].get<double>(), 0);
        }
        // ROAM converges to the threshold every frame: its screen error is at most the threshold
        // (with detail, unless splits waited for tiles: pending_splits counts them).
        const bool waited = m["roam_coherent"].contains("pending_splits_max") &&
                            m["roam_coherent"]["pending_splits_max"].get<double>() > 0;
        if (kind == "threshold" && !waited) {
          EXPECT_LE(m["roam_coherent"]["screen_error_max_px"].get<double>(), value + 1e-9);
        }
        if (kind == "triangles") {
          EXPECT_LE(m["roam_coherent"]["triangles_median"].get<double>(), value);
        }
        // The uniform grid is matched to ROAM's median count within 10 % (5 % stated in tests).
        const double target = m["roam_coherent"]["triangles_median"];
        if (target >= 50) {
          EXPECT_NEAR(m["uniform_grid"]["triangles_median"].get<double>() / target, 1.0, 0.10);
        }
        EXPECT_TRUE(finite_number(m["cdlod"]["matched_ratio"]));
        // A static grid never pops, except where the storm's craters change the surface.
        if (storm) {
          EXPECT_GT(m["uniform_grid"]["popping_max_px"].get<double>(), 0.0);
        } else {
          EXPECT_EQ(m["uniform_grid"]["popping_max_px"].get<double>(), 0.0);
          EXPECT_EQ(m["uniform_grid"]["pop_max_px"].get<double>(), 0.0);
          // SOAR refines at the same threshold (or to the same triangle count).
          EXPECT_GT(m["soar"]["triangles_median"].get<double>(), 0.0);
        }
      }
    }
  };
  ASSERT_EQ(r["scenes"].size(), 3u);
  check_scene(r["scenes"][0], true);
  // The procedural-detail world: measured on the finest lattice (65 samples, 2 levels: 257),
  // ROAM streaming tiles (resident tiles, detail memory and pending splits reported).
  const json& detail = r["scenes"][1];
  ASSERT_EQ(detail["name"], "detail65");
  EXPECT_EQ(detail["measured_lattice"], json::array({257, 257}));
  EXPECT_EQ(detail["detail"]["levels"], 2);
  check_scene(detail, true);
  for (const json& p : detail["paths"])
    for (const json& st : p["settings"])
      for (const json& m : st["modes"]) {
        if (m["mode"].get<std::string>().rfind("roam_", 0) != 0) continue;
        EXPECT_TRUE(finite_number(m["pending_splits_median"])) << m;
        EXPECT_GT(m["tiles_resident_max"].get<double>(), 0) << m;
        EXPECT_GT(m["detail_memory_bytes_median"].get<double>(), 0) << m;
        EXPECT_GT(m["tiles_generated"].get<double>(), 0) << m;
        EXPECT_TRUE(finite_number(m["pop_geomorph_max_px"])) << m;  // measured there too
      }
  // The deformation storm: craters every frame, flyover and drive; apply_edit timed per mode.
  const json& storm = r["scenes"][2];
  ASSERT_EQ(storm["name"], "storm_synthetic129");
  check_scene(storm, false, true);
  for (const json& p : storm["paths"])
    for (const json& st : p["settings"])
      for (const json& m : st["modes"]) EXPECT_TRUE(finite_number(m["edit_ms_median"])) << m;

  // Hard cases: all present; the far origins give the same mesh and errors as origin 0.
  std::map<std::string, json> hard;
  for (const json& h : r["hard_cases"]) hard[h["name"]] = h;
  for (const char* n :
       {"origin_0", "origin_1e6", "origin_1e7", "cliff_1000m", "flat", "saturated_u16",
        "nonfinite_f32_refuse", "nonfinite_f32_fill_nearest", "huge_f32"})
    ASSERT_TRUE(hard.count(n)) << n;
  for (const char* n : {"origin_0", "origin_1e6", "origin_1e7", "cliff_1000m", "flat",
                        "saturated_u16", "nonfinite_f32_fill_nearest"})
    check_scene(hard[n], false);
  auto coherent = [&](const char* n, const char* f) {
    return hard[n]["paths"][0]["settings"][0]["modes"][0][f].get<double>();
  };
  for (const char* far : {"origin_1e6", "origin_1e7"}) {
    EXPECT_EQ(coherent(far, "triangles_median"), coherent("origin_0", "triangles_median"));
    EXPECT_NEAR(coherent(far, "error_rms_m"), coherent("origin_0", "error_rms_m"), 1e-6);
    EXPECT_NEAR(coherent(far, "error_max_m"), coherent("origin_0", "error_max_m"), 1e-6);
  }
  EXPECT_EQ(coherent("flat", "error_max_m"), 0.0);
  EXPECT_EQ(coherent("flat", "triangles_median"), 2.0);
  EXPECT_FALSE(hard["nonfinite_f32_refuse"]["loaded"].get<bool>());
  EXPECT_NE(hard["nonfinite_f32_refuse"]["loader_messages"].dump().find("nan"), std::string::npos);
  EXPECT_NE(hard["nonfinite_f32_fill_nearest"]["loader_messages"].dump().find("3 samples filled"),
            std::string::npos);
  // Heights near FLT_MAX are refused by the loader, naming the sample and the limit.
  EXPECT_FALSE(hard["huge_f32"]["loaded"].get<bool>());
  EXPECT_NE(hard["huge_f32"]["loader_messages"].dump().find("100000 m limit"), std::string::npos)
      << hard["huge_f32"]["loader_messages"];
  EXPECT_FALSE(r.contains("not_done"));

  // CSV: one row per scene, path, setting and mode, 23 fields, no header.
  std::ifstream csv(out + "/report.csv");
  std::size_t lines = 0;
  for (std::string line; std::getline(csv, line); ++lines) {
    EXPECT_EQ(std::count(line.begin(), line.end(), ','), 22) << line;
    if (lines == 0) {
      EXPECT_EQ(line.rfind("synthetic129,flyover,threshold,2,roam_coherent,", 0), 0u) << line;
    }
  }
  EXPECT_EQ(lines, rows);
}

// `ridge report --write-noise-field` and `ridge bench lod --mode soar` end to end: the files load
// as the peers' inputs, the SOAR mode prints the same summary fields as the ROAM modes, and every
// bad input is refused naming the flag.
TEST(BenchLodSoar, RunsOnTheNoiseFieldAndRefusesBadInput) {
  const std::string dir = std::string(RIDGELINE_TEST_TMP) + "/soar_bench";
  const std::string log = dir + ".log";
  const std::string ridge = RIDGE;
  ASSERT_EQ(std::system((ridge + " report --write-noise-field " + dir + " 2> " + log).c_str()), 0)
      << slurp(log);
  const std::string terrain = " --heightmap " + dir + "/noise1025.png --spacing 1 --height-scale " +
                              "0.005 --path " + dir + "/noise1025_circle.json";
  const std::string cmd = ridge + " bench lod" + terrain +
                          " --mode soar --threshold 2.048 --error-every 40 --json " + dir +
                          "/soar.json 2> " + log;
  ASSERT_EQ(std::system(cmd.c_str()), 0) << slurp(log);
  const json s = json::parse(slurp(dir + "/soar.json"))["summary"];
  EXPECT_EQ(s["mode"], "soar");
  EXPECT_EQ(s["frames"], 360);
  EXPECT_EQ(s["flush_mb"], 0.0);
  for (const char* f :
       {"update_ms_median", "update_cpu_ms_median", "triangles_median", "triangles_in_view_median",
        "rms_error_median", "max_error_max", "output_ms_median", "upload_bytes_median"})
    EXPECT_TRUE(finite_number(s[f])) << f << " = " << s[f];
  // The peers' nu = 250 setting: 20.8k triangles and 0.64 m RMS (within 5 %).
  EXPECT_NEAR(s["triangles_median"].get<double>() / 20800.0, 1.0, 0.05);
  EXPECT_NEAR(s["rms_error_median"].get<double>() / 0.64, 1.0, 0.05);
  EXPECT_LE(s["triangles_in_view_median"].get<double>(), s["triangles_median"].get<double>());
  // The whole strip every frame: at least one 4-byte index per triangle.
  EXPECT_GT(s["upload_bytes_median"].get<double>(), 4 * s["triangles_median"].get<double>());
  // Bad input: each refused with a message naming the flag, exit code non-zero.
  const std::pair<const char*, const char*> bad[] = {
      {" --mode soar --threshold 2 --budget-ms 1", "--budget-ms"},
      {" --mode soar", "--threshold"},
      {" --mode soar --triangles 0", "--triangles"},
      {" --mode soar --threshold -1", "--threshold"},
      {" --mode soar --threshold 2 --error-stride 0", "--error-stride"},
      {" --mode soar --threshold 2 --flush-mb -1", "--flush-mb"},
      {" --threshold 2 --flush-mb nan", "--flush-mb"},
      {" --threshold 2 --flush-mb 5000", "--flush-mb"}};
  for (const auto& [flags, word] : bad) {
    const int rc = std::system((ridge + " bench lod" + terrain + flags + " 2> " + log).c_str());
    EXPECT_NE(rc, 0) << flags;
    EXPECT_NE(slurp(log).find(word), std::string::npos) << flags << ": " << slurp(log);
  }
  const int rc = std::system((ridge + " bench lod --default-terrain --detail-levels 4 --path " +
                              dir + "/noise1025_circle.json --mode soar --threshold 2 2> " + log)
                                 .c_str());
  EXPECT_NE(rc, 0);
  EXPECT_NE(slurp(log).find("at most 8193"), std::string::npos) << slurp(log);
}

}  // namespace
