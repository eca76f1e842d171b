// `ridge bench queries`: nanoseconds per query on uniformly random points, medians over
// repetitions (docs/benchmarks.md).
#include "bench_queries.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <random>
#include <vector>

#include "cli_util.h"
#include "ridgeline/bench/clock.h"
#include "ridgeline/bench/stats.h"

namespace ridgeline::cli {

namespace {

using bench::median;

// Wall and thread-CPU nanoseconds per item of runs of a timed loop.
struct Timing {
  std::vector<double> wall, cpu;
  template <class F>
  void run(std::size_t items, F&& body) {
    const bench::Timing t = bench::timed(body);
    wall.push_back(t.wall_ms * 1e6 / double(items));
    cpu.push_back(t.cpu_ms * 1e6 / double(items));
  }
};

struct Ray {
  glm::dvec3 origin, direction;
  double max_distance;
};

}  // namespace

nlohmann::json bench_queries(const Terrain& terrain, const BenchQueriesOptions& options) {
  const WorldInfo& hf = terrain.info();
  const std::size_t n = std::max<std::size_t>(options.points, 1);
  const int reps = std::max(options.repetitions, 1);
  std::mt19937_64 rng(options.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);

  // Uniformly random points over the whole terrain.
  std::vector<glm::dvec2> points(n);
  for (auto& p : points)
    p = {hf.origin_x + unit(rng) * hf.extent_x(), hf.origin_z + unit(rng) * hf.extent_z()};

  const double top = hf.height_offset + double(hf.max_local) + 1.0;
  const double bottom = hf.height_offset + double(hf.min_local) - 1.0;

  // Vertical rays: straight down from above the highest sample, unbounded length.
  std::vector<Ray> vertical(n);
  for (std::size_t k = 0; k < n; ++k)
    vertical[k] = {{points[k].x, top, points[k].y}, {0, -1, 0}, HUGE_VAL};

  // Slanted rays: from above the highest sample at a random point of the middle half of the
  // field, 256 cells horizontally at a random azimuth, ending below the lowest sample.
  std::vector<Ray> slanted(n);
  constexpr double kCells = 256.0;
  constexpr double kTwoPi = 6.283185307179586;
  for (auto& r : slanted) {
    const double u = (0.25 + 0.5 * unit(rng)) * (hf.width - 1.0);
    const double v = (0.25 + 0.5 * unit(rng)) * (hf.height - 1.0);
    const double a = kTwoPi * unit(rng);
    r.origin = {hf.origin_x + u * hf.spacing_x, top, hf.origin_z + v * hf.spacing_z};
    r.direction = {kCells * std::cos(a) * hf.spacing_x, bottom - top,
                   kCells * std::sin(a) * hf.spacing_z};
    r.max_distance = glm::length(r.direction);
  }

  Timing t_height, t_batched, t_height_normal, t_sample, t_vertical, t_slanted;
  std::size_t hits_height = 0, hits_batched = 0, hits_height_normal = 0, hits_sample = 0,
              hits_vertical = 0, hits_slanted = 0;
  std::vector<double> batched(n);
  double checksum = 0;
  for (int rep = 0; rep < reps; ++rep) {
    std::size_t hits = 0;
    double sum = 0;
    t_height.run(n, [&] {
      for (const auto& p : points)
        if (auto h = terrain.height(p.x, p.y)) sum += *h, ++hits;
    });
    hits_height = hits;
    hits = 0;
    t_height_normal.run(n, [&] {
      for (const auto& p : points)
        if (auto s = terrain.height_normal(p.x, p.y)) sum += s->height + s->face_normal.x, ++hits;
    });
    hits_height_normal = hits;
    hits = 0;
    t_sample.run(n, [&] {
      for (const auto& p : points)
        if (auto s = terrain.sample(p.x, p.y)) sum += s->height + s->smooth_normal.x, ++hits;
    });
    hits_sample = hits;
    hits = 0;
    t_vertical.run(n, [&] {
      for (const auto& r : vertical)
        if (auto h = terrain.raycast(r.origin, r.direction, r.max_distance))
          sum += h->distance, ++hits;
    });
    hits_vertical = hits;
    hits = 0;
    t_slanted.run(n, [&] {
      for (const auto& r : slanted)
        if (auto h = terrain.raycast(r.origin, r.direction, r.max_distance))
          sum += h->distance, ++hits;
    });
    hits_slanted = hits;
    checksum += sum;
  }
  // Batched heights in repetitions of their own, after the others: its output array (8 bytes a
  // point) would otherwise evict the samples the next query kind finds in the cache.
  double batched_checksum = 0;
  for (int rep = 0; rep < reps; ++rep) {
    t_batched.run(n, [&] { terrain.heights(points, batched); });
    hits_batched = 0;
    for (double h : batched)
      if (!std::isnan(h)) batched_checksum += h, ++hits_batched;
  }

  const double samples = double(hf.width) * hf.height;
  // The pages' bytes: heights (2 or 4 bytes a sample plus aprons), materials and the ray
  // pyramid inside each page.
  const std::size_t height_bytes = terrain.world_stats().resident_bytes;
  nlohmann::json j;
  j["height_ns"] = median(t_height.wall);
  j["batched_height_ns"] = median(t_batched.wall);
  j["height_normal_ns"] = median(t_height_normal.wall);
  j["sample_ns"] = median(t_sample.wall);
  j["vertical_ray_ns"] = median(t_vertical.wall);
  j["slanted_ray_ns"] = median(t_slanted.wall);
  j["thread_cpu"] = {{"height_ns", median(t_height.cpu)},
                     {"batched_height_ns", median(t_batched.cpu)},
                     {"height_normal_ns", median(t_height_normal.cpu)},
                     {"sample_ns", median(t_sample.cpu)},
                     {"vertical_ray_ns", median(t_vertical.cpu)},
                     {"slanted_ray_ns", median(t_slanted.cpu)}};
  j["bytes_per_sample"] = double(height_bytes) / samples;
  j["page_bytes"] = height_bytes;
  j["memory_bytes"] = terrain.memory_bytes();
  j["width"] = hf.width;
  j["height"] = hf.height;
  j["points"] = n;
  j["repetitions"] = reps;
  j["seed"] = options.seed;
  j["slanted_ray_cells"] = kCells;
  j["hits"] = {{"height", hits_height},
               {"batched_height", hits_batched},
               {"height_normal", hits_height_normal},
               {"sample", hits_sample},
               {"vertical_ray", hits_vertical},
               {"slanted_ray", hits_slanted}};
  j["checksum"] = checksum;
  j["batched_checksum"] = batched_checksum;
  j["notes"] =
      "ns per query, median over repetitions of wall time (thread_cpu: of the thread's CPU time, "
      "which leaves out time spent waiting for a core); height_normal = height + face normal + "
      "material "
      "(Terrain::height_normal); batched_height = Terrain::heights over the same points in one "
      "call; sample = height + face and smooth normals + material; "
      "bytes_per_sample = (float heights + ray hierarchy) / samples";
  return j;
}

}  // namespace ridgeline::cli
