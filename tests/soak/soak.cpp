// Soak (issue 9): random flight over the default terrain (speeds up to 1,000 km/h, snap turns,
// zooms) with random threshold and triangle-budget changes and random edits, checking every
// invariant every --check-every frames:
//  - the mesh is crack-free (RoamView::check_invariants: symmetric neighbours, no T-junctions);
//  - the triangle budget holds;
//  - bounds are honest: when an update converged (nothing above the threshold left, budget not
//    the limit), the measured screen error of the mesh is at most the threshold;
//  - queries agree with the mesh: every mesh vertex is on the surface that Terrain::height()
//    answers, and for finest-level leaves the query inside the triangle is its plane;
//  - memory stays under a budget (the view's own accounting and the process RSS).
// Prints one JSON line with the totals; exit status 1 on the first violated invariant (with the
// seed, frame and the violation).
//
// Usage: ridgeline_soak [--frames N] [--edits N] [--seed S] [--check-every N] [--size N]
//                       [--progress N]  (a line on stderr every N frames: frame, edits, seconds)
//   CI (asan stage): --frames 2000 --edits 200 --size 257; full run: --frames 100000 --edits 10000
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>

#include "ridgeline/edit.h"
#include "ridgeline/heightfield.h"
#include "ridgeline/landscape.h"
#include "ridgeline/roam_view.h"
#include "ridgeline/terrain.h"

namespace {

using namespace ridgeline;

struct Args {
  long frames = 2000;
  long edits = 200;
  unsigned seed = 1;
  long check_every = 100;
  unsigned size = 257;
  long progress = 0;  // frames between progress lines on stderr (0: none)
  std::size_t view_memory_budget = std::size_t{512} << 20;  // bytes
};

[[noreturn]] void fail(const Args& a, long frame, const std::string& what) {
  std::fprintf(stderr, "soak FAILED (seed %u, frame %ld): %s\n", a.seed, frame, what.c_str());
  std::exit(1);
}

long rss_kib() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss;
}

}  // namespace

int main(int argc, char** argv) {
  Args a;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i];
    const char* v = argv[i + 1];
    if (k == "--frames") a.frames = std::atol(v);
    else if (k == "--edits") a.edits = std::atol(v);
    else if (k == "--seed") a.seed = static_cast<unsigned>(std::atol(v));
    else if (k == "--check-every") a.check_every = std::max(1L, std::atol(v));
    else if (k == "--size") a.size = static_cast<unsigned>(std::atol(v));
    else if (k == "--progress") a.progress = std::max(0L, std::atol(v));
    else {
      std::fprintf(stderr, "unknown option %s\n", k.c_str());
      return 2;
    }
  }
  DefaultTerrainParams tp;
  tp.size = a.size;
  tp.spacing = 2048.0 / (a.size - 1);
  auto hf = make_default_heightfield(tp);
  if (!hf) fail(a, 0, hf.error().message);
  std::shared_ptr<Terrain> terrain = Terrain::create(std::move(*hf)).value();
  auto landscape = Landscape::create(terrain);
  if (!landscape) fail(a, 0, landscape.error().message);
  RoamSettings settings;
  settings.threshold = 2.0;
  settings.max_triangles = 200'000;
  auto view_r = RoamView::create(*landscape, settings);
  if (!view_r) fail(a, 0, view_r.error().message);
  RoamView& view = **view_r;
  const Heightfield field = terrain->surface().to_heightfield().value();
  const double ext_x = field.extent_x(), ext_z = field.extent_z();

  std::mt19937_64 rng(a.seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const auto uni = [&](double lo, double hi) { return lo + (hi - lo) * u01(rng); };

  // Flight state.
  double x = ext_x / 2, z = ext_z / 2, alt = 120, yaw = 0, pitch = -0.3, speed = 50;
  Camera cam;
  cam.viewport = {640, 360};
  cam.fov_y_deg = 60;
  const double dt = 1.0 / 60.0, kMaxSpeed = 1000.0 / 3.6;  // m/s

  long edits_done = 0, edits_clipped = 0, checks = 0, converged_checks = 0, snap_turns = 0;
  long budget_changes = 0, vertices_checked = 0;
  double worst_ratio = 0;  // measured screen error / threshold at converged checks
  std::size_t peak_view_memory = 0;
  std::uint64_t total_triangles = 0;
  const double edit_rate = a.frames > 0 ? static_cast<double>(a.edits) / a.frames : 0;

  const auto start = std::chrono::steady_clock::now();
  for (long frame = 1; frame <= a.frames; ++frame) {
    // Flight: random walk of speed, heading and pitch; occasional snap turns and zooms.
    speed = std::clamp(speed + uni(-40, 40), 0.0, kMaxSpeed);
    if (u01(rng) < 0.002) speed = kMaxSpeed;
    yaw += uni(-0.05, 0.05);
    if (u01(rng) < 0.003) {
      yaw += uni(M_PI / 2, M_PI);
      ++snap_turns;
    }
    pitch = std::clamp(pitch + uni(-0.03, 0.03), -1.4, 0.3);
    if (u01(rng) < 0.005) cam.fov_y_deg = uni(15, 100);
    x += std::sin(yaw) * speed * dt;
    z += std::cos(yaw) * speed * dt;
    // Leave the terrain and come back: reflect at a margin outside it.
    if (x < -300 || x > ext_x + 300) yaw = -yaw, x = std::clamp(x, -300.0, ext_x + 300);
    if (z < -300 || z > ext_z + 300) yaw = M_PI - yaw, z = std::clamp(z, -300.0, ext_z + 300);
    alt = std::clamp(alt + uni(-3, 3), 2.0, 1500.0);
    const double ground = terrain->height(std::clamp(x, 0.0, ext_x), std::clamp(z, 0.0, ext_z))
                              .value_or(0.0);
    cam.eye = {x, ground + alt, z};
    cam.target = cam.eye + glm::dvec3(std::sin(yaw) * std::cos(pitch), std::sin(pitch),
                                      std::cos(yaw) * std::cos(pitch));
    cam.up = {0, 1, 0};

    // Settings changes.
    if (u01(rng) < 0.005) {
      RoamSettings s = view.settings();
      s.threshold = uni(0.75, 8);
      const double r = u01(rng);
      s.max_triangles = r < 0.2 ? 0 : static_cast<std::uint32_t>(uni(2'000, 300'000));
      if (auto st = view.set_settings(s); !st) fail(a, frame, "set_settings: " + st.message());
      ++budget_changes;
    }
    // Edits.
    if (u01(rng) < edit_rate && edits_done < a.edits) {
      Edit e;
      e.brush = static_cast<Brush>(rng() % 5);
      e.x = uni(-50, ext_x + 50);
      e.z = uni(-50, ext_z + 50);
      e.radius = uni(2, 120);
      e.strength = uni(0, 1);
      e.depth = uni(-10, 30);
      e.rim = uni(0, 1);
      e.height = uni(0, 250);
      auto r = terrain->apply_edit(e);
      if (!r) fail(a, frame, "apply_edit: " + r.error().message);
      edits_clipped += r->clipped ? 1 : 0;
      ++edits_done;
    }

    auto st = view.update(cam);
    if (!st) fail(a, frame, "update: " + st.error().message);
    total_triangles += st->triangles;
    peak_view_memory = std::max(peak_view_memory, st->memory_bytes);

    if (a.progress > 0 && frame % a.progress == 0) {
      const double elapsed =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      std::fprintf(stderr, "progress: frame %ld, edits %ld, checks %ld, worst ratio %.4f, %.0f s\n",
                   frame, edits_done, checks, worst_ratio, elapsed);
    }
    if (frame % a.check_every != 0) continue;
    ++checks;
    if (std::string inv = view.check_invariants(); !inv.empty()) fail(a, frame, "cracks: " + inv);
    const RoamSettings& s = view.settings();
    if (s.max_triangles != 0 && st->triangles > s.max_triangles)
      fail(a, frame, "triangle budget exceeded: " + std::to_string(st->triangles) + " > " +
                         std::to_string(s.max_triangles));
    if (st->memory_bytes > a.view_memory_budget)
      fail(a, frame, "view memory over budget: " + std::to_string(st->memory_bytes));
    // Honest bounds: converged and not held back by the triangle budget.
    const bool capped = s.max_triangles != 0 && st->triangles + 64 >= s.max_triangles;
    if (st->max_remaining_error <= s.threshold && !capped) {
      const auto m = view.measure_error(cam, 2);
      ++converged_checks;
      worst_ratio = std::max(worst_ratio, m.max_px / s.threshold);
      if (m.max_px > s.threshold * (1 + 1e-9) + 1e-9)
        fail(a, frame, "measured screen error " + std::to_string(m.max_px) + " px above threshold " +
                           std::to_string(s.threshold));
    }
    // Queries agree with the mesh.
    const Landscape& ls = **landscape;
    const double sx = field.spacing_x(), sz = field.spacing_z();
    const double ox = field.origin_x(), oz = field.origin_z(), off = field.height_offset();
    long leaf = 0;
    std::string bad;
    view.for_each_leaf([&](std::uint32_t, std::uint64_t heap, const LatticeTriangle& t) {
      if (!bad.empty() || (leaf++ % 97) != 0) return;
      const std::int64_t vi[3] = {t.ax, t.lx, t.rx}, vj[3] = {t.az, t.lz, t.rz};
      double plane = 0;
      bool inside = true;
      for (int k = 0; k < 3; ++k) {
        const double want = double(float(ls.terrain().surface().vertex_height(vi[k], vj[k]))) + off;
        plane += want / 3;
        const auto got = terrain->height(ox + vi[k] * sx, oz + vj[k] * sz);
        if (!got) {
          inside = false;
          continue;  // padding: off the terrain
        }
        ++vertices_checked;
        if (std::abs(*got - want) > 1e-3)
          bad = "vertex (" + std::to_string(vi[k]) + ", " + std::to_string(vj[k]) + "): query " +
                std::to_string(*got) + " vs mesh " + std::to_string(want);
      }
      const int level = 63 - __builtin_clzll(heap);
      if (inside && static_cast<std::uint32_t>(level) == ls.max_level()) {
        const double cx = ox + (t.ax + t.lx + t.rx) / 3.0 * sx, cz = oz + (t.az + t.lz + t.rz) / 3.0 * sz;
        const auto q = terrain->height(cx, cz);
        if (q && std::abs(*q - plane) > 1e-3)
          bad = "finest leaf centroid: query " + std::to_string(*q) + " vs plane " +
                std::to_string(plane);
      }
    });
    if (!bad.empty()) fail(a, frame, "query/mesh mismatch: " + bad);
  }
  std::printf(
      "{\"frames\": %ld, \"edits\": %ld, \"edits_clipped\": %ld, \"checks\": %ld, "
      "\"converged_checks\": %ld, \"worst_measured_over_threshold\": %.4f, \"snap_turns\": %ld, "
      "\"settings_changes\": %ld, \"vertices_checked\": %ld, \"mean_triangles\": %.0f, "
      "\"peak_view_memory_bytes\": %zu, \"max_rss_kib\": %ld, \"seed\": %u, \"size\": %u}\n",
      a.frames, edits_done, edits_clipped, checks, converged_checks, worst_ratio, snap_turns,
      budget_changes, vertices_checked,
      a.frames > 0 ? static_cast<double>(total_triangles) / a.frames : 0.0, peak_view_memory,
      rss_kib(), a.seed, a.size);
  return 0;
}
