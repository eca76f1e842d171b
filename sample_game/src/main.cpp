// ridgeline_game: the sample game (docs/game.md). Modes: a window when a display exists,
// --offscreen (hidden GLFW window + FBO under an X server such as Xvfb, or EGL surfaceless
// without one) and --headless (simulation only, no GL). Fixed simulation step.
// Exit codes: 0 done, 1 error, 2 bad command line, 3 no OpenGL context could be created.
#define GL_GLEXT_PROTOTYPES 1
#define GLFW_INCLUDE_NONE
#include <GL/gl.h>
#include <GLFW/glfw3.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "game.h"
#include "gl_context.h"
#include "panel.h"
#include "renderer.h"
#include "ridgeline/bench/clock.h"
#include "ridgeline/camera_path.h"
#include "run_stats.h"

namespace {

using ridgeline::bench::Clock;
using ridgeline::bench::ms_since;

struct Args {
  bool headless = false, offscreen = false, egl = false, no_panel = false, wireframe = false;
  bool panel_open = false;
  std::uint64_t frames = 0;
  std::vector<std::string> scripts;
  std::string screenshot, stats, out_dir = "out", camera, record_path;
  std::uint64_t screenshot_every = 0, steady_from = 0;
  int width = 1280, height = 720;
  double threshold = 0, target_ms = 33, dt = 1.0 / 60.0, tess_ms = 8;
  double render_scale = 0;  // fixed (with --threshold); 0: 1 or the controller's
  std::uint32_t triangles = 60000;
  int detail_levels = -1;  // -1: the default world's
  double detail_amplitude = -1;
  bool prefill_detail = false;
  bool full_fragments = false, unsorted = false;
  std::uint32_t patch_exponent = game::GameOptions{}.patch_exponent;
  std::string world, heightmap;
  double spacing = 1, height_scale = 1, height_offset = 0;
  std::size_t cache_mb = 192;
};

// Writes the frames as a PATH.json camera path (docs/cli.md, "Camera paths").
ridgeline::Status write_camera_path(const std::string& file,
                                    const std::vector<ridgeline::io::PathFrame>& frames) {
  nlohmann::json out = {{"version", 1}, {"frames", nlohmann::json::array()}};
  for (const ridgeline::io::PathFrame& f : frames) {
    const ridgeline::Camera& c = f.camera;
    out["frames"].push_back({{"eye", {c.eye.x, c.eye.y, c.eye.z}},
                             {"target", {c.target.x, c.target.y, c.target.z}},
                             {"up", {c.up.x, c.up.y, c.up.z}},
                             {"fov_y", c.fov_y_deg},
                             {"viewport", {c.viewport.x, c.viewport.y}},
                             {"near", c.near_m},
                             {"far", c.far_m},
                             {"dt", f.dt}});
  }
  std::ofstream os(file);
  if (!os) return ridgeline::Error{"camera path '" + file + "': cannot open for writing"};
  os << out.dump() << "\n";
  os.close();
  if (!os) return ridgeline::Error{"camera path '" + file + "': write failed"};
  return {};
}

void read_window_input(GLFWwindow* w, game::Game& g, bool keyboard_free, double dt) {
  auto down = [w](int k) { return glfwGetKey(w, k) == GLFW_PRESS; };
  game::Input in;
  if (keyboard_free) {
    in.up = down(GLFW_KEY_UP) || down(GLFW_KEY_W);
    in.down = down(GLFW_KEY_DOWN) || down(GLFW_KEY_S);
    in.left = down(GLFW_KEY_LEFT) || down(GLFW_KEY_A);
    in.right = down(GLFW_KEY_RIGHT) || down(GLFW_KEY_D);
    in.brake = down(GLFW_KEY_SPACE);
    game::CameraRig& r = g.rig();
    if (r.mode == game::CameraMode::kFree) {
      // Free camera: I/K forward/back, J/L turn, U/O up/down, Y/H pitch.
      const double speed = (down(GLFW_KEY_LEFT_SHIFT) ? 300.0 : 80.0) * dt;
      const glm::dvec3 fwd(std::sin(r.free_yaw), 0, std::cos(r.free_yaw));
      if (down(GLFW_KEY_I)) r.free_eye += fwd * speed;
      if (down(GLFW_KEY_K)) r.free_eye -= fwd * speed;
      if (down(GLFW_KEY_U)) r.free_eye.y += speed;
      if (down(GLFW_KEY_O)) r.free_eye.y -= speed;
      if (down(GLFW_KEY_J)) r.free_yaw += 1.2 * dt;
      if (down(GLFW_KEY_L)) r.free_yaw -= 1.2 * dt;
      if (down(GLFW_KEY_Y)) r.free_pitch = std::min(1.5, r.free_pitch + dt);
      if (down(GLFW_KEY_H)) r.free_pitch = std::max(-1.5, r.free_pitch - dt);
      if (auto h = g.terrain().height(r.free_eye.x, r.free_eye.z))
        r.free_eye.y = std::max(r.free_eye.y, *h + 2.0);
    }
  }
  g.set_input(in);
}

int run(const Args& a) {
  game::GameOptions o;
  o.assets_dir = RIDGELINE_GAME_ASSETS;
  o.scripts_dir = RIDGELINE_GAME_SCRIPTS;
  o.dt = a.dt;
  o.viewport = {a.width, a.height};
  o.fixed_threshold = a.threshold;
  o.budget.target_ms = a.target_ms;
  o.max_triangles = a.triangles;
  o.tessellation_budget_ms = a.tess_ms;
  o.fixed_render_scale = a.render_scale;
  o.world_path = a.world;
  o.world_cache_bytes = a.cache_mb << 20;
  o.heightmap_path = a.heightmap;
  o.heightmap_placement.spacing_x = o.heightmap_placement.spacing_z = a.spacing;
  o.heightmap_placement.height_scale = a.height_scale;
  o.heightmap_placement.height_offset = a.height_offset;
  // The built-in terrain's detail is tuned for it: a user's world has none unless asked for.
  if (!a.world.empty() || !a.heightmap.empty()) o.detail.levels = 0;
  if (a.detail_levels >= 0) o.detail.levels = std::uint32_t(a.detail_levels);
  if (a.detail_amplitude >= 0) o.detail.amplitude = a.detail_amplitude;
  o.prefill_detail = a.prefill_detail;
  o.patch_exponent = a.patch_exponent;
  std::vector<std::string> scripts = a.scripts;
  if (scripts.empty())
    for (const char* s : {"default.lua", "artillery.lua", "budget.lua", "earthworks.lua"})
      scripts.push_back(std::string(RIDGELINE_GAME_SCRIPTS) + "/" + s);
  // A script file that cannot be read is a start-up error (a typo in --script must not give a
  // game with no vehicles and exit 0); errors inside a script are reported and the game goes on.
  for (const std::string& s : scripts) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(s, ec) || !std::ifstream(s)) {
      std::fprintf(
          stderr, "ridgeline_game: script '%s': %s\n", s.c_str(),
          std::filesystem::exists(s, ec) ? "cannot be read (not a readable file)" : "no such file");
      return 1;
    }
  }
  auto created = game::Game::create(o);
  if (!created) {
    std::fprintf(stderr, "ridgeline_game: %s\n", created.error().message.c_str());
    return 1;
  }
  game::Game& g = **created;
  for (const std::string& s : scripts) (void)g.load_script(s);  // errors are recorded, not fatal
  if (a.threshold > 0) {  // the command line wins over scripts: reproducible pictures
    g.set_controller_on(false);
    g.set_threshold(a.threshold);
    g.set_render_scale(a.render_scale > 0 ? a.render_scale : 1.0);
    g.set_tessellation_budget_ms(a.tess_ms);
  }
  if (!a.camera.empty()) {
    if (a.camera == "free") g.rig().mode = game::CameraMode::kFree;
    if (a.camera == "follow") g.rig().mode = game::CameraMode::kFollow;
    if (a.camera == "map") g.rig().mode = game::CameraMode::kMap;
  }

  std::unique_ptr<game::GlContext> ctx;
  std::unique_ptr<game::Renderer> renderer;
  std::unique_ptr<game::Panel> panel;
  std::string mode = "headless";
  if (!a.headless) {
    const bool display = std::getenv("DISPLAY") != nullptr && *std::getenv("DISPLAY") != '\0';
    game::GlMode gm = game::GlMode::kWindow;
    if (a.offscreen)
      gm = (display && !a.egl) ? game::GlMode::kHiddenWindow : game::GlMode::kEglSurfaceless;
    if (!a.offscreen && !display) {
      std::fprintf(stderr,
                   "ridgeline_game: no display (DISPLAY is not set); use --offscreen or "
                   "--headless\n");
      return 3;
    }
    auto c = game::GlContext::create(gm, a.width, a.height, "Ridgeline sample game");
    if (!c && gm == game::GlMode::kHiddenWindow) {
      std::fprintf(stderr, "ridgeline_game: %s; trying EGL surfaceless\n",
                   c.error().message.c_str());
      c = game::GlContext::create(game::GlMode::kEglSurfaceless, a.width, a.height, "");
    }
    if (!c) {
      std::fprintf(stderr, "ridgeline_game: no OpenGL context: %s\n", c.error().message.c_str());
      return 3;
    }
    ctx = std::move(*c);
    mode = to_string(ctx->mode());
    std::fprintf(stderr, "ridgeline_game: %s\n", ctx->description().c_str());
    auto r = game::Renderer::create(g, a.width, a.height);
    if (!r) {
      std::fprintf(stderr, "ridgeline_game: %s\n", r.error().message.c_str());
      return 1;
    }
    renderer = std::move(*r);
    if (!a.no_panel) {
      panel = std::make_unique<game::Panel>(
          ctx->mode() == game::GlMode::kWindow ? ctx->window() : nullptr, a.width, a.height);
      panel->set_open(a.panel_open);
    }
  }
  if (!a.out_dir.empty() && (a.screenshot_every > 0))
    std::filesystem::create_directories(a.out_dir);

  game::RenderSettings rs;
  rs.wireframe = a.wireframe;
  rs.cheap_fragments = !a.full_fragments;
  rs.front_to_back = !a.unsorted;
  game::RunStats stats;
  double last_frame_ms = 0;
  double accumulator = 0;
  bool f5_was_down = false, tab_was_down = false, f1_was_down = false, f2_was_down = false;
  std::uint64_t frame = 0;
  const bool window = ctx && ctx->mode() == game::GlMode::kWindow;
  auto wall0 = Clock::now();
  std::vector<ridgeline::io::PathFrame> recorded;  // --record-path: the active camera per frame
  while (a.frames == 0 || frame < a.frames) {
    if (ctx && ctx->should_close()) break;
    const auto t0 = Clock::now();
    // CPU time of the whole process (every thread: llvmpipe's rasterisers, the detail workers)
    // and of this thread: on a shared machine these move less than wall time.
    const double cpu0 = ridgeline::bench::process_cpu_ms(),
                 main0 = ridgeline::bench::thread_cpu_ms();
    if (window) {
      GLFWwindow* w = ctx->window();
      read_window_input(w, g, !(panel && panel->wants_keyboard()), 1.0 / 60.0);
      const bool f5 = glfwGetKey(w, GLFW_KEY_F5) == GLFW_PRESS;
      if (f5 && !f5_was_down) g.reload_all_scripts();
      f5_was_down = f5;
      const bool tab = glfwGetKey(w, GLFW_KEY_TAB) == GLFW_PRESS;
      if (tab && !tab_was_down) g.rig().mode = game::CameraMode((int(g.rig().mode) + 1) % 3);
      tab_was_down = tab;
      const bool f1 = glfwGetKey(w, GLFW_KEY_F1) == GLFW_PRESS;
      if (f1 && !f1_was_down) rs.wireframe = !rs.wireframe;
      f1_was_down = f1;
      const bool f2 = glfwGetKey(w, GLFW_KEY_F2) == GLFW_PRESS;
      if (f2 && !f2_was_down && panel) panel->toggle();
      f2_was_down = f2;
    }
    if (frame % 30 == 0) g.reload_changed_scripts();  // hot reload: edit a script, it re-runs
    // Fixed steps: offscreen and headless take exactly one per frame (reproducible); a window
    // takes as many as wall-clock time asks for (at most 5 per frame).
    int steps = 1;
    if (window) {
      const double now = std::chrono::duration<double>(Clock::now() - wall0).count();
      accumulator = now - g.time();
      steps = std::clamp(int(accumulator / g.dt()), 0, 5);
      if (accumulator > 0.5)
        wall0 += std::chrono::duration_cast<Clock::duration>(
            std::chrono::duration<double>(accumulator - 0.1));
    }
    const auto ts = Clock::now();
    double burn = 0;
    for (int s = 0; s < steps; ++s) {
      g.step();
      burn += g.burned_ms();
    }
    const double sim_ms = ms_since(ts);
    const game::StepTimes step_times = g.take_step_times();
    const game::ViewFrame vf = g.update_view(last_frame_ms);
    if (!a.record_path.empty()) recorded.push_back({g.camera(), std::max(steps, 1) * g.dt()});
    game::RenderStats rstats;
    double render_ms = 0, panel_ms = 0;
    if (renderer) {
      const auto tr = Clock::now();
      rstats = renderer->draw(g, rs);
      if (panel) {
        const auto tp = Clock::now();
        game::PanelInput pin{last_frame_ms, rstats};
        panel->draw(g, rs, pin, last_frame_ms / 1000.0);
        panel_ms = ms_since(tp);
      }
      glFinish();  // llvmpipe renders in threads: count the whole frame
      if (window) {
        int ww = 0, wh = 0;
        glfwGetFramebufferSize(ctx->window(), &ww, &wh);
        renderer->blit_to_window(ww, wh);
      }
      render_ms = ms_since(tr) - rstats.upload_ms;
    }
    // The frame's work, before waiting for vsync and before screenshots: writing a PNG (about
    // 120 ms at 1280 x 720) is not part of the game's frame, so it is neither in the frame time
    // the controller sees nor in the statistics (the next frame starts after it).
    const double frame_ms = ms_since(t0);
    const double frame_cpu_ms = ridgeline::bench::process_cpu_ms() - cpu0;
    const double frame_main_cpu_ms = ridgeline::bench::thread_cpu_ms() - main0;
    const auto tshot = Clock::now();
    if (renderer) {
      const bool last = a.frames > 0 && frame + 1 == a.frames;
      if (!a.screenshot.empty() && last) {
        if (auto s = game::write_png(a.screenshot, renderer->width(), renderer->height(),
                                     renderer->read_pixels());
            !s)
          std::fprintf(stderr, "ridgeline_game: %s\n", s.message().c_str());
      }
      if (a.screenshot_every > 0 && (frame + 1) % a.screenshot_every == 0) {
        char name[64];
        std::snprintf(name, sizeof name, "/frame_%06llu.png",
                      static_cast<unsigned long long>(frame + 1));
        if (auto s = game::write_png(a.out_dir + name, renderer->width(), renderer->height(),
                                     renderer->read_pixels());
            !s)
          std::fprintf(stderr, "ridgeline_game: %s\n", s.message().c_str());
      }
    }
    const double screenshot_ms = ms_since(tshot);
    if (ctx) ctx->present();
    last_frame_ms = frame_ms;
    g.set_last_frame_ms(frame_ms);
    game::FrameRecord rec;
    rec.frame = frame;
    rec.time_s = g.time();
    rec.frame_ms = frame_ms;
    rec.cpu_ms = frame_cpu_ms;
    rec.main_cpu_ms = frame_main_cpu_ms;
    rec.sim_ms = sim_ms;
    rec.scripts_ms = step_times.scripts_ms;
    rec.physics_ms = step_times.physics_ms;
    rec.tess_ms = vf.stats.update_ms;
    rec.upload_ms = rstats.upload_ms;
    rec.patch_mesh_ms = rstats.patch_mesh_ms;
    rec.render_ms = render_ms;
    rec.panel_ms = panel_ms;
    rec.burn_ms = burn;
    rec.screenshot_ms = screenshot_ms;
    rec.threshold = vf.threshold;
    rec.wall_s =
        std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
    rec.smoothed_ms = g.controller().state().smoothed_ms;
    rec.reversals = g.controller().state().reversals;
    rec.render_scale = vf.render_scale;
    rec.triangles = vf.stats.triangles;
    rec.splits = vf.stats.splits + vf.stats.forced_splits;
    rec.merges = vf.stats.merges;
    rec.pending_splits = vf.stats.pending_splits;
    rec.stop = vf.updated ? int(vf.stats.stop) : -1;
    rec.patches_uploaded = rstats.patches_uploaded;
    rec.bytes_uploaded = rstats.bytes_uploaded;
    rec.view_upload_bytes = vf.stats.upload_bytes;
    rec.contacts = g.contacts();
    rec.body_contacts = g.body_contacts();
    rec.bodies = g.bodies().size();
    for (const auto& [id, b] : g.bodies()) rec.bodies_awake += !b.sleeping();
    if (auto ds = g.detail_stats()) {
      rec.tiles_resident = ds->resident_tiles;
      rec.tiles_pending = ds->pending;
      rec.tiles_generated = ds->generated;
    }
    for (const auto& [id, e] : g.vehicles()) {
      game::FrameRecord::VehicleRecord vr{};
      const glm::dvec3 p = e.body.position();
      vr.id = id;
      vr.x = p.x;
      vr.y = p.y;
      vr.z = p.z;
      vr.speed = e.body.speed();
      vr.reached = e.autopilot.reached;
      vr.material = e.body.ground_material();
      vr.collisions = e.body.collisions;
      vr.body_hits = e.body.body_hits;
      vr.min_gap = 1e9;
      for (const auto& w : e.body.wheels()) {
        vr.min_gap = std::min(vr.min_gap, w.surface_gap);
        if (w.contact) {
          ++vr.contacts;
          vr.max_contact_gap = std::max(vr.max_contact_gap, std::abs(w.surface_gap));
        }
      }
      rec.vehicles.push_back(vr);
    }
    stats.record(g, std::move(rec));
    ++frame;
  }
  if (!a.record_path.empty()) {
    if (auto s = write_camera_path(a.record_path, recorded); !s) {
      std::fprintf(stderr, "ridgeline_game: %s\n", s.message().c_str());
      return 1;
    }
  }
  if (!a.stats.empty()) {
    if (auto s = stats.write(a.stats, mode, g, a.steady_from); !s) {
      std::fprintf(stderr, "ridgeline_game: %s\n", s.message().c_str());
      return 1;
    }
  }
  std::fprintf(stderr,
               "ridgeline_game: %llu frames (%s), %zu vehicles, %zu craters, %llu script "
               "errors\n",
               static_cast<unsigned long long>(frame), mode.c_str(), g.vehicles().size(),
               g.craters().size(), static_cast<unsigned long long>(g.error_count()));
  panel.reset();
  renderer.reset();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
#if defined(__GLIBC__)
  // Page-sized buffers of a baked world (--world), made on loader threads and freed on others,
  // are reused from one arena rather than fragmenting glibc's per-thread arenas (docs/worlds.md,
  // "Memory"). Before any thread starts.
  (void)::mallopt(M_ARENA_MAX, 1);
#endif
  CLI::App app{"Ridgeline sample game: vehicles on deformable terrain, driven by Lua"};
  Args a;
  app.add_flag("--headless", a.headless, "simulation only, no OpenGL");
  app.add_flag("--offscreen", a.offscreen,
               "render without a display: a hidden window under X (Xvfb), else EGL surfaceless");
  app.add_flag("--egl", a.egl, "with --offscreen: use EGL surfaceless even when X is there");
  app.add_option("--frames", a.frames, "exit after N frames (0: run until the window closes)");
  app.add_option("--script", a.scripts,
                 "Lua script to run (repeatable; default: default, artillery, budget and "
                 "earthworks from scripts/game); a file that cannot be read exits with 1");
  app.add_option("--screenshot", a.screenshot, "write the last frame to FILE.png (needs --frames)");
  app.add_option("--screenshot-every", a.screenshot_every,
                 "write every Nth frame to the output folder");
  app.add_option("--out", a.out_dir, "output folder for --screenshot-every")->capture_default_str();
  app.add_option("--stats", a.stats, "write per-frame statistics to FILE.json");
  app.add_option("--steady-from", a.steady_from,
                 "frames before this are left out of the stats summary's percentiles");
  app.add_option("--width", a.width, "pixels")->check(CLI::Range(64, 8192))->capture_default_str();
  app.add_option("--height", a.height, "pixels")
      ->check(CLI::Range(64, 8192))
      ->capture_default_str();
  app.add_option("--threshold", a.threshold,
                 "fixed pixel threshold (turns the budget controller off)")
      ->check(CLI::Range(0.25, 256.0));
  app.add_option("--target-ms", a.target_ms, "frame time the controller holds")
      ->check(CLI::Range(1.0, 1000.0))
      ->capture_default_str();
  app.add_option("--triangles", a.triangles, "triangle budget of the views")
      ->check(CLI::Range(100, 4000000))
      ->capture_default_str();
  app.add_option("--tess-ms", a.tess_ms, "tessellation time budget per frame (0: none)")
      ->check(CLI::Range(0.0, 1000.0))
      ->capture_default_str();
  app.add_option("--dt", a.dt, "fixed simulation step, seconds")
      ->check(CLI::Range(0.001, 0.1))
      ->capture_default_str();
  app.add_option("--record-path", a.record_path,
                 "write the active camera of every frame as a PATH.json camera path");
  app.add_option("--camera", a.camera, "initial camera (overrides scripts)")
      ->check(CLI::IsMember({"free", "follow", "map"}));
  app.add_option("--render-scale", a.render_scale,
                 "with --threshold: fixed render scale (fraction of the resolution per axis)")
      ->check(CLI::Range(0.25, 1.0));
  // The defaults quoted from the world's own (docs/game.md states them; ctest docs_facts compares).
  const ridgeline::DetailParams world_detail = game::default_world_detail();
  app.add_option("--detail-levels", a.detail_levels,
                 "procedural detail levels of the world (0: none; default " +
                     std::to_string(world_detail.levels) + ")")
      ->check(CLI::Range(0, 6));
  app.add_option("--detail-amplitude", a.detail_amplitude,
                 [&] {
                   char text[64];
                   std::snprintf(text, sizeof text, "first detail octave, metres (default %g)",
                                 world_detail.amplitude);
                   return std::string(text);
                 }())
      ->check(CLI::Range(0.0, 10.0));
  app.add_option("--patch-exponent", a.patch_exponent, "ROAM patches of 2^k stored cells per side")
      ->check(CLI::Range(3, 8))
      ->capture_default_str();
  auto* world = app.add_option("--world", a.world,
                                "play on a baked world (ridge bake --out WORLD), paged in under "
                                "--cache-mb; the scripts lay their course around its centre")
                    ->check(CLI::ExistingFile);
  auto* heightmap = app.add_option("--heightmap", a.heightmap,
                                   "play on a heightmap file (PNG, TIFF, EXR; --spacing, "
                                   "--height-scale, --height-offset place it)")
                        ->check(CLI::ExistingFile)
                        ->excludes(world);
  app.add_option("--spacing", a.spacing, "metres between --heightmap samples")
                      ->check(CLI::Range(1e-3, 1e4))
                      ->needs(heightmap);
  app.add_option("--height-scale", a.height_scale, "metres per --heightmap unit")
      ->check(CLI::Range(1e-9, 1e6))
      ->needs(heightmap);
  app.add_option("--height-offset", a.height_offset, "metres added to --heightmap heights")
      ->check(CLI::Range(-1e7, 1e7))
      ->needs(heightmap);
  app.add_option("--cache-mb", a.cache_mb, "page cache of a --world, MiB (default 192)")
      ->check(CLI::Range(4, 1 << 20))
      ->needs(world);
  app.add_flag("--prefill-detail", a.prefill_detail,
               "each view update waits for the detail tiles it asked for (pictures that do not "
               "depend on tile arrival)");
  app.add_flag("--full-fragments", a.full_fragments,
               "light and fog per pixel (the default computes them per vertex: the cheaper "
               "fragment path)");
  app.add_flag("--unsorted", a.unsorted, "draw terrain patches in index order, not nearest first");
  app.add_flag("--no-panel", a.no_panel, "no debug panel (reproducible pictures)");
  app.add_flag("--panel-open", a.panel_open,
               "start with the debug panel unfolded (it starts folded; F2 toggles it)");
  app.add_flag("--wireframe", a.wireframe, "start in wireframe");
  CLI11_PARSE(app, argc, argv);
  if (a.headless && a.offscreen) {
    std::fprintf(stderr, "ridgeline_game: --headless and --offscreen exclude each other\n");
    return 2;
  }
  if (!a.screenshot.empty() && a.frames == 0) {
    std::fprintf(stderr, "ridgeline_game: --screenshot needs --frames N\n");
    return 2;
  }
  if (a.render_scale > 0 && a.threshold <= 0) {
    std::fprintf(stderr,
                 "ridgeline_game: --render-scale needs --threshold (the controller "
                 "chooses the scale otherwise)\n");
    return 2;
  }
  if (a.headless && (!a.screenshot.empty() || a.screenshot_every > 0)) {
    std::fprintf(stderr, "ridgeline_game: --headless renders nothing: no screenshots\n");
    return 2;
  }
  return run(a);
}
