// `ridge bake --out WORLD`: a heightmap (one file or several), the default terrain or a generated
// world baked into a world file (ridgeline/world_file.h; docs/worlds.md), with a progress bar on
// the terminal and Ctrl-C cancelling; prints what it did as JSON.
#include <csignal>
#include <cstdio>
#include <memory>
#include <thread>
#include <unistd.h>

#include "cli_util.h"
#include "commands.h"
#include "ridgeline/scenes.h"
#include "ridgeline/world_file.h"
#include "terrain_args.h"

namespace ridgeline::cli {

namespace {

volatile std::sig_atomic_t g_interrupted = 0;
extern "C" void on_interrupt(int) { g_interrupted = 1; }

struct BakeArgs {
  TerrainArgs terrain;
  std::string out, json_path, patch_exponent = "0", morph_window, morph_delay, tolerance,
                              threads = "0", compression = "1", generate, size = "4097",
                              seed = "1";
  bool quiet = false;
};

int run_bake(const BakeArgs& a) {
  if (a.out.empty()) return report_usage("bake: --out WORLD is required");
  io::BakeOptions o;
  auto k = parse_count(a.patch_exponent, "--patch-exponent", 0, 10);
  if (!k) return report_error(k.error().message);
  o.landscape.patch_exponent = std::uint32_t(*k);
  if (!a.morph_window.empty()) {
    auto v = parse_finite(a.morph_window, "--morph-window");
    if (!v) return report_error(v.error().message);
    o.landscape.morph_window = *v;
  }
  if (!a.morph_delay.empty()) {
    auto v = parse_finite(a.morph_delay, "--morph-delay");
    if (!v) return report_error(v.error().message);
    o.landscape.morph_delay = *v;
  }
  if (!a.tolerance.empty()) {
    auto v = parse_finite(a.tolerance, "--tolerance");
    if (!v) return report_error(v.error().message);
    o.tolerance = *v;
  }
  auto th = parse_count(a.threads, "--threads", 0, 256);
  if (!th) return report_error(th.error().message);
  o.threads = std::uint32_t(*th);
  auto lv = parse_count(a.compression, "--compression", 1, 12);
  if (!lv) return report_error(lv.error().message);
  o.compression_level = int(*lv);

  // The progress bar, on a terminal; Ctrl-C cancels (the temporary file is removed).
  const bool bar = !a.quiet && ::isatty(2);
  int last = -1;
  std::string last_stage;
  o.progress = [&](double f, const char* stage) {
    const int pct = int(f * 100.0);
    if (bar && (pct != last || last_stage != stage)) {
      const int filled = pct / 4;
      std::fprintf(stderr, "\rbake: %-9s [%.*s%*s] %3d%%", stage, filled,
                   "#########################", 25 - filled, "", pct);
      std::fflush(stderr);
      last = pct, last_stage = stage;
    }
    return g_interrupted == 0;
  };
  std::signal(SIGINT, on_interrupt);

  Result<io::BakeReport> rep = Error{"bake: nothing to bake"};
  double generate_s = 0;
  if (!a.generate.empty()) {
    if (a.generate != "noise")
      return report_usage("bake: --generate '" + a.generate + "': the generator is 'noise'");
    if (a.terrain.given("--heightmap") || a.terrain.given("--default-terrain") ||
        a.terrain.given("--world"))
      return report_usage("bake: --generate replaces --heightmap / --default-terrain");
    auto n = parse_count(a.size, "--size", 2, 1u << 20);
    if (!n) return report_error(n.error().message);
    auto seed = parse_count(a.seed, "--seed", 0, 0xffffffffu);
    if (!seed) return report_error(seed.error().message);
    io::BakeSamples s;
    s.info.width = s.info.height = std::uint32_t(*n);
    s.info.spacing_x = s.info.spacing_z = 1.0;
    s.info.height_scale = scenes::kWorldHeightScale;
    s.info.format = SampleFormat::kU16;
    s.info.name = "generated noise " + a.size;
    std::vector<std::uint16_t> values;
    try {
      values.resize(std::size_t(*n) * std::size_t(*n));
    } catch (const std::bad_alloc&) {
      return report_error("bake: " + a.size + " x " + a.size +
                          " samples do not fit in memory (2 bytes a sample)");
    }
    const auto t0 = std::chrono::steady_clock::now();
    const unsigned threads = o.threads ? o.threads : std::max(1u, std::thread::hardware_concurrency());
    std::vector<std::thread> pool;
    const std::uint32_t rows = std::uint32_t(*n);
    for (unsigned t = 0; t < threads; ++t)
      pool.emplace_back([&, t] {
        // Interleaved bands of 64 rows (the threads progress alike).
        for (std::uint32_t j0 = 64 * t; j0 < rows; j0 += 64 * threads)
          scenes::generated_world_rows(rows, j0, std::min(rows, j0 + 64), std::uint32_t(*seed),
                                       values.data() + std::size_t(j0) * rows);
      });
    for (auto& p : pool) p.join();
    generate_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    s.u16 = values.data();
    rep = io::bake_world(s, a.out, o);
  } else {
    io::LoadReport lr;
    auto hf = a.terrain.load_heightfield(&lr);
    if (!hf) return report_error(hf.error().message);
    rep = io::bake_world(*hf, a.out, o);
  }
  if (bar) std::fprintf(stderr, "\n");
  std::signal(SIGINT, SIG_DFL);
  if (!rep) return report_error(rep.error().message);
  char hash[24];
  std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(rep->content_hash));
  nlohmann::ordered_json j = {
      {"out", a.out},
      {"samples", rep->samples},
      {"bytes", rep->bytes},
      {"bytes_per_sample", double(rep->bytes) / double(rep->samples)},
      {"pages", rep->pages},
      {"format", rep->format == SampleFormat::kU16 ? "u16" : "f32"},
      {"max_error_m", rep->max_error_m},
      {"seconds", rep->seconds},
      {"bounds_seconds", rep->bounds_seconds},
      {"pages_seconds", rep->pages_seconds},
      {"hole_cells", rep->hole_cells},
      {"samples_per_second", double(rep->samples) / std::max(rep->seconds, 1e-9)},
      {"patch_exponent", rep->patch_exponent},
      {"content_hash", hash},
  };
  if (!a.generate.empty()) j["generate_seconds"] = generate_s;
  if (auto s = write_json(j, a.json_path); !s) return report_error(s.message());
  return 0;
}

}  // namespace

Command add_bake_command(CLI::App& parent) {
  auto* app = parent.add_subcommand(
      "bake",
      "Bake a heightmap (or several files, or a generated world) into a world file that every "
      "command opens with --world: tiled 16-bit or float GeoTIFF with overviews, Ridgeline's "
      "index and the tessellator's coarse bounds (JSON report)");
  auto a = std::make_shared<BakeArgs>();
  a->terrain.add_to(*app);
  // --generate needs no terrain flag.
  app->parse_complete_callback([app, a] {
    if (a->generate.empty() && !a->terrain.given("--heightmap") &&
        !a->terrain.given("--default-terrain"))
      throw CLI::RequiredError(
          "no terrain given: pass --heightmap FILE, --default-terrain or --generate noise",
          CLI::ExitCodes::RequiredError);
    (void)app;
  });
  app->add_option("--out", a->out, "The world file to write (replaced atomically)")
      ->type_name("WORLD");
  app->add_option("--patch-exponent", a->patch_exponent,
                  "Patch exponent the coarse bounds are baked for, 2..10 (default 0: 6, raised "
                  "until at most 64 patches per side)")
      ->type_name("K");
  app->add_option("--morph-window", a->morph_window, "Geomorph window baked for (default 0.2)")
      ->type_name("W");
  app->add_option("--morph-delay", a->morph_delay, "Geomorph delay baked for (default 0.1)")
      ->type_name("D");
  app->add_option("--tolerance", a->tolerance,
                  "Float input: quantise to 16 bits within M metres (the measured maximum error "
                  "is reported); default: keep floats exactly")
      ->type_name("M");
  app->add_option("--threads", a->threads, "Threads, 0..256 (default 0: every hardware thread)")
      ->type_name("N");
  app->add_option("--compression", a->compression, "Deflate level, 1..12 (default 1: files about 4 % larger than at 2 and a third faster to write; reading is as fast at every level)")
      ->type_name("L");
  app->add_option("--generate", a->generate,
                  "Bake a generated world instead of a file: 'noise' (value-noise fBm, 1 m "
                  "spacing, 2 cm steps)")
      ->type_name("noise");
  app->add_option("--size", a->size, "Samples per side of the generated world (default 4097)")
      ->type_name("N");
  app->add_option("--seed", a->seed, "Seed of the generated world (default 1)")->type_name("S");
  app->add_flag("--quiet", a->quiet, "No progress bar");
  app->add_option("--json", a->json_path, "Write the JSON to FILE instead of standard output")
      ->type_name("FILE");
  return {app, [a] { return run_bake(*a); }};
}

}  // namespace ridgeline::cli
