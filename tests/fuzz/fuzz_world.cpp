// Fuzz target: the baked world reader (io::open_world, docs/worlds.md "The world file") and
// everything that reads its pages: Terrain::open under a 4 MiB cache with loads on this thread,
// heights over the whole footprint and past it, rays across it, the triangles of a box, and a
// view converged over it (the coarse levels' baked bounds). The input is written to a file (the
// reader takes a path). A refused file must be refused at open with a message; a damaged page
// is found when it loads and reads as "no data"; the terrain's invariants must hold whatever the
// file holds. Seeds: small worlds made by `ridge bake` (16-bit and float).
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "ridgeline/camera.h"
#include "ridgeline/landscape.h"
#include "ridgeline/roam_view.h"
#include "ridgeline/terrain.h"
#include "ridgeline/world_file.h"

namespace {

const std::string& scratch_path() {
  static const std::string path = "/tmp/ridgeline_fuzz_world_" + std::to_string(::getpid()) + ".tif";
  return path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace ridgeline;
  const std::string& path = scratch_path();
  if (std::FILE* f = std::fopen(path.c_str(), "wb")) {
    const bool written = std::fwrite(data, 1, size, f) == size;
    if (std::fclose(f) != 0 || !written) return 0;
  } else {
    return 0;
  }
  auto source = io::open_world(path);
  if (!source) {
    if (source.error().message.empty()) __builtin_trap();  // a refusal names its cause
    return 0;
  }
  WorldCacheDesc cache;
  cache.budget_bytes = std::size_t{4} << 20;
  cache.worker_threads = 0;
  auto opened = Terrain::open(*source, cache);
  if (!opened) return 0;
  const std::shared_ptr<Terrain>& t = *opened;
  const WorldInfo& w = t->info();
  for (int j = -1; j <= 9; ++j)
    for (int i = -1; i <= 9; ++i) {
      const auto h = t->height(w.origin_x + w.extent_x() * i / 8.0, w.origin_z + w.extent_z() * j / 8.0);
      if (h && !std::isfinite(*h)) __builtin_trap();
    }
  const glm::dvec3 o(w.origin_x - 1.0, w.height_offset + w.max_local + 5.0, w.origin_z - 1.0);
  (void)t->raycast(o, glm::dvec3(w.extent_x(), -(w.max_local - w.min_local) - 10.0, w.extent_z()),
                   INFINITY);
  std::vector<SurfaceTriangle> tris;
  (void)t->triangles_in_box(
      Box{{w.origin_x, -1e9, w.origin_z},
          {w.origin_x + 0.3 * w.extent_x(), 1e9, w.origin_z + 0.3 * w.extent_z()}},
      tris, 4096);
  if (auto land = Landscape::create(t)) {
    RoamSettings s;
    s.threshold = 4;
    if (auto view = RoamView::create(*land, s)) {
      Camera cam;
      cam.eye = {w.origin_x + 0.5 * w.extent_x(), w.height_offset + w.max_local + 20.0,
                 w.origin_z - 0.2 * w.extent_z()};
      cam.target = {w.origin_x + 0.5 * w.extent_x(), w.height_offset, w.origin_z + 0.5 * w.extent_z()};
      (void)(*view)->converge(cam);
      if (!(*view)->check_invariants().empty()) __builtin_trap();
    }
  }
  if (!t->check_invariants().empty()) __builtin_trap();
  return 0;
}
