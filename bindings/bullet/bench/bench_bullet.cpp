// bench_bullet: Ridgeline::bullet's TerrainShape against Bullet's own btHeightfieldTerrainShape
// built from the same stored samples, in one run: per-step times of 100 and 1,000 bodies
// (spheres and boxes) resting and sliding, their contacts, the shapes' memory, the cost of the
// triangle query alone, and rays (btCollisionWorld::rayTest) through both shapes (the heightfield
// with its ray accelerator, buildAccelerator). JSON on stdout; no time is asserted anywhere.
//
//   bench_bullet [--quick] [--steps N] [--rays N] [--field noise|default_stored|default|all]
//                [--no-generic] [--rays-only]
//
// --quick: 100 bodies, 30 steps, 2,000 rays (a smoke run); --no-generic: skip Bullet's generic
// concave ray path (milliseconds per long ray); --rays-only: no bodies.
//
// Fields: the peers' 1025 x 1025 noise field (Ridgeline::scenes, 1 m spacing, no detail) and the
// built-in default terrain (1025 x 1025 at 2 m) without detail ("default_stored"): on both the
// two shapes have the same triangles (Bullet's heightfield with diamond subdivision splits cells
// for contacts as docs/surface.md does; its ray accelerator splits them the other way, which the
// "vs_accelerator" distances show and the generic path, "vs_generic", does not); then the default
// terrain with the game's procedural detail ("default": one level, 0.2 m), where the Ridgeline
// shape collides with the 1 m detail lattice while Bullet's heightfield only knows the stored 2 m
// samples.
#include <BulletCollision/CollisionShapes/btHeightfieldTerrainShape.h>
#include <BulletCollision/NarrowPhaseCollision/btRaycastCallback.h>
#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "ridgeline/bench/clock.h"
#include "ridgeline/bench/stats.h"
#include "ridgeline/bullet/dynamics_world.h"
#include "ridgeline/bullet/terrain_shape.h"
#include "ridgeline/bullet/terrain_sync.h"
#include "ridgeline/detail.h"
#include "ridgeline/scenes.h"
#include "ridgeline/terrain.h"

namespace {

using ridgeline::bench::Clock;
using ridgeline::bench::ms_since;
using ridgeline::bullet::DynamicsWorld;
using ridgeline::bullet::TerrainShape;

std::string load_average() {
  std::ifstream f("/proc/loadavg");
  std::string a, b, c;
  f >> a >> b >> c;
  return a + " " + b + " " + c;
}

std::string cpu_model() {
  std::ifstream f("/proc/cpuinfo");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  return "unknown";
}

// Bullet's heightfield with the size of its ray accelerator readable.
class Heightfield final : public btHeightfieldTerrainShape {
 public:
  using btHeightfieldTerrainShape::btHeightfieldTerrainShape;
  std::size_t accelerator_bytes() const {
    return std::size_t(m_vboundsGrid.capacity()) * sizeof(Range);
  }
};

struct Field {
  std::string name;
  std::shared_ptr<ridgeline::Terrain> terrain;
  glm::dvec3 centre{0};        // the shapes' local origin: the middle of the footprint
  std::vector<float> samples;  // world heights - centre.y, for Bullet's heightfield
  float min_h = 0, max_h = 0;  // of `samples`
};

Field make_field(const std::string& which) {
  Field f;
  f.name = which;
  if (which == "noise") {
    f.terrain = ridgeline::Terrain::create(ridgeline::scenes::noise_field().value()).value();
  } else if (which == "default_stored") {
    f.terrain = ridgeline::Terrain::create(ridgeline::make_default_heightfield().value()).value();
  } else {
    ridgeline::DetailParams d;  // the sample game's world (docs/game.md, "The world")
    d.levels = 1;
    d.amplitude = 0.2;
    d.gain = 0.5;
    d.seed = 17;
    ridgeline::DetailCacheDesc cache;
    cache.worker_threads = 0;
    f.terrain =
        ridgeline::Terrain::create(ridgeline::make_default_heightfield().value(), d, cache).value();
  }
  const ridgeline::WorldInfo& info = f.terrain->info();
  f.centre = {info.origin_x + info.extent_x() / 2, info.height_offset,
              info.origin_z + info.extent_z() / 2};
  const ridgeline::Heightfield hf = f.terrain->surface().to_heightfield().value();
  const auto local = hf.local_heights();
  f.samples.assign(local.begin(), local.end());
  f.min_h = *std::min_element(f.samples.begin(), f.samples.end());
  f.max_h = *std::max_element(f.samples.begin(), f.samples.end());
  return f;
}

// One Bullet world with the ground (either shape) and bodies.
struct World {
  DynamicsWorld dynamics;
  btDiscreteDynamicsWorld& world = dynamics.world();
  std::unique_ptr<btCollisionShape> ground_shape;
  btCollisionObject ground;

  World(const Field& f, bool ridgeline_shape) {
    const ridgeline::WorldInfo& hf = f.terrain->info();
    btTransform t;
    t.setIdentity();
    if (ridgeline_shape) {
      ground_shape = TerrainShape::create(f.terrain, {.origin = f.centre}).value();
    } else {
      auto h = std::make_unique<Heightfield>(int(hf.width), int(hf.height), f.samples.data(),
                                             f.min_h, f.max_h, 1, false);
      h->setUseDiamondSubdivision(true);  // Ridgeline's diagonal rule (docs/surface.md)
      h->setLocalScaling(btVector3(btScalar(hf.spacing_x), 1, btScalar(hf.spacing_z)));
      h->buildAccelerator();
      // Bullet centres the field on its box: put that centre where the samples' is.
      t.setOrigin(btVector3(0, 0.5f * (f.min_h + f.max_h), 0));
      ground_shape = std::move(h);
    }
    ground.setCollisionShape(ground_shape.get());
    ground.setWorldTransform(t);
    ground.setFriction(0.8f);
    world.addCollisionObject(&ground, btBroadphaseProxy::StaticFilter,
                             btBroadphaseProxy::AllFilter ^ btBroadphaseProxy::StaticFilter);
  }
  ~World() {
    dynamics.remove_bodies();
    world.removeCollisionObject(&ground);
  }
  void add(std::unique_ptr<btCollisionShape> s, const btVector3& p, double mass) {
    btRigidBody* b =
        dynamics.add_body(std::move(s), btTransform(btQuaternion::getIdentity(), p), mass, 0.6);
    b->setActivationState(DISABLE_DEACTIVATION);  // measure contacts, not sleep
  }
  std::size_t contact_points() const { return dynamics.contact_points(); }
};

// The same bodies for both shapes: half spheres, half boxes, over the middle 400 m of the field,
// dropped from 1 m above the surface (Ridgeline's height: with detail the heightfield lies up to
// 0.2 m lower or higher).
struct BodySpec {
  bool sphere;
  glm::dvec3 size;  // radius, or half extents
  glm::dvec3 pos;   // world
};
std::vector<BodySpec> bodies_for(const Field& f, int n) {
  std::mt19937 rng(1234 + n);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<BodySpec> out;
  for (int k = 0; k < n; ++k) {
    BodySpec b;
    b.sphere = k % 2 == 0;
    b.size = b.sphere ? glm::dvec3(0.3 + 0.3 * u(rng))
                      : glm::dvec3(0.25 + 0.25 * u(rng), 0.2 + 0.2 * u(rng), 0.25 + 0.25 * u(rng));
    const double x = f.centre.x - 200 + 400 * u(rng), z = f.centre.z - 200 + 400 * u(rng);
    b.pos = {x, *f.terrain->height(x, z) + 1.0 + b.size.y, z};
    out.push_back(b);
  }
  return out;
}

struct PhaseResult {
  double median_ms = 0, p90_ms = 0, mean_contacts = 0;
};

PhaseResult measure(World& w, int steps) {
  std::vector<double> times;
  double contacts = 0;
  for (int s = 0; s < steps; ++s) {
    const auto t0 = Clock::now();
    w.world.stepSimulation(1.0f / 60.0f, 0);
    times.push_back(ms_since(t0));
    contacts += double(w.contact_points());
  }
  return {ridgeline::bench::quantile_or(times, 0.5, 0), ridgeline::bench::quantile_or(times, 0.9, 0),
          contacts / steps};
}

std::string json(const PhaseResult& r) {
  char buf[160];
  std::snprintf(buf, sizeof buf,
                "{\"step_ms_median\": %.4f, \"step_ms_p90\": %.4f, \"contact_points\": %.1f}",
                r.median_ms, r.p90_ms, r.mean_contacts);
  return buf;
}

// Bodies resting (after settling) and sliding (every body pushed at 6 m/s sideways).
std::string bodies_run(const Field& f, bool ridgeline_shape, int n, int steps) {
  World w(f, ridgeline_shape);
  const glm::dvec3& c = f.centre;
  for (const BodySpec& b : bodies_for(f, n)) {
    const btVector3 p(btScalar(b.pos.x - c.x), btScalar(b.pos.y - c.y), btScalar(b.pos.z - c.z));
    if (b.sphere)
      w.add(std::make_unique<btSphereShape>(btScalar(b.size.x)), p, 50);
    else
      w.add(std::make_unique<btBoxShape>(
                btVector3(btScalar(b.size.x), btScalar(b.size.y), btScalar(b.size.z))),
            p, 50);
  }
  const auto t0 = Clock::now();
  for (int s = 0; s < 180; ++s) w.world.stepSimulation(1.0f / 60.0f, 0);  // land and settle
  const double settle_ms = ms_since(t0) / 180;
  const PhaseResult resting = measure(w, steps);
  std::mt19937 rng(99);
  std::uniform_real_distribution<float> angle(0, 6.2831853f);
  for (btRigidBody* b : w.dynamics.bodies()) {
    const float a = angle(rng);
    b->setLinearVelocity(btVector3(6 * std::cos(a), 0, 6 * std::sin(a)));
  }
  const PhaseResult sliding = measure(w, steps);
  // Where the bodies ended: above the ground (none fell through).
  int below = 0;
  for (btRigidBody* b : w.dynamics.bodies()) {
    const btVector3 p = b->getWorldTransform().getOrigin();
    const auto h = f.terrain->height(c.x + p.x(), c.z + p.z());
    if (h && double(p.y()) + c.y < *h - 0.5) ++below;
  }
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "{\"settling_step_ms_mean\": %.4f, \"resting\": %s, \"sliding\": %s, "
                "\"bodies_below_ground\": %d}",
                settle_ms, json(resting).c_str(), json(sliding).c_str(), below);
  return buf;
}

// The triangle query alone: processAllTriangles over body-sized boxes, counting the triangles.
struct Count final : btTriangleCallback {
  std::size_t n = 0;
  void processTriangle(btVector3*, int, int) override { ++n; }
};
std::string query_run(const Field& f, bool ridgeline_shape, int boxes) {
  World w(f, ridgeline_shape);
  const auto* shape = static_cast<const btConcaveShape*>(w.ground_shape.get());
  const btTransform inv = w.ground.getWorldTransform().inverse();
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<std::pair<btVector3, btVector3>> q;
  for (int k = 0; k < boxes; ++k) {
    const double x = f.centre.x - 200 + 400 * u(rng), z = f.centre.z - 200 + 400 * u(rng);
    const double h = *f.terrain->height(x, z), r = 0.3 + 0.3 * u(rng);
    const btVector3 lo(btScalar(x - f.centre.x - r), btScalar(h - f.centre.y - r),
                       btScalar(z - f.centre.z - r));
    q.push_back(
        {inv * lo, inv * (lo + btVector3(btScalar(2 * r), btScalar(2 * r), btScalar(2 * r)))});
  }
  Count c;
  const auto t0 = Clock::now();
  for (const auto& [lo, hi] : q) shape->processAllTriangles(&c, lo, hi);
  const double ms = ms_since(t0);
  char buf[200];
  std::snprintf(buf, sizeof buf,
                "{\"ns_per_box\": %.1f, \"triangles_per_box\": %.2f, \"ns_per_triangle\": %.2f}",
                ms * 1e6 / boxes, double(c.n) / boxes,
                ms * 1e6 / double(std::max<std::size_t>(c.n, 1)));
  return buf;
}

// Rays through btCollisionWorld::rayTest: short wheel rays straight down and long sight lines.
struct RaySet {
  std::string name;
  std::vector<std::pair<glm::dvec3, glm::dvec3>> rays;  // world from, to
};
std::vector<RaySet> ray_sets(const Field& f, int n) {
  std::mt19937 rng(77);
  std::uniform_real_distribution<double> u(0, 1);
  RaySet wheel{"wheel_down_2m", {}}, sight{"sight_line_500m", {}}, pick{"pick_down_300m", {}};
  for (int k = 0; k < n; ++k) {
    const double x = f.centre.x - 400 + 800 * u(rng), z = f.centre.z - 400 + 800 * u(rng);
    const double h = *f.terrain->height(x, z);
    // A suspension ray from 1.2 m above the ground, 2 m long (hits).
    wheel.rays.push_back({{x, h + 1.2, z}, {x, h - 0.8, z}});
    // A line of sight from 2 m above the ground, 500 m, slightly down (mostly hits far away).
    const double a = 6.2831853 * u(rng), s = -0.02 - 0.05 * u(rng);
    const glm::dvec3 d = glm::dvec3(std::cos(a), s, std::sin(a));
    sight.rays.push_back(
        {{x, h + 2, z}, glm::dvec3(x, h + 2, z) + d * (500 / std::sqrt(1 + s * s))});
    // A pick from 150 m above, steeply down (a mouse pick or a shell's path).
    const glm::dvec3 p(x, h + 150, z), e(std::cos(a) * 0.4, -1, std::sin(a) * 0.4);
    pick.rays.push_back({p, p + e * (300 / std::sqrt(1.16))});
  }
  return {wheel, sight, pick};
}

struct RayTimes {
  double world_ns = 0;   // per ray through btCollisionWorld::rayTest (broadphase included)
  double single_ns = 0;  // per ray through btCollisionWorld::rayTestSingle on the ground alone
  std::size_t hits = 0;
  std::vector<double> distance;  // NaN for a miss
};
// `flags`: btTriangleRaycastCallback flags (kF_DisableHeightfieldAccelerator: Bullet's generic
// concave path, processAllTriangles over the ray's box).
RayTimes rays_run(const Field& f, bool ridgeline_shape, const RaySet& set, unsigned flags = 0) {
  World w(f, ridgeline_shape);
  const glm::dvec3& c = f.centre;
  const auto local = [&](const glm::dvec3& p) {
    return btVector3(btScalar(p.x - c.x), btScalar(p.y - c.y), btScalar(p.z - c.z));
  };
  std::vector<std::pair<btVector3, btVector3>> rays;
  for (const auto& [a, b] : set.rays) rays.push_back({local(a), local(b)});
  RayTimes r;
  r.distance.reserve(rays.size());
  auto t0 = Clock::now();
  for (const auto& [a, b] : rays) {
    btCollisionWorld::ClosestRayResultCallback cb(a, b);
    cb.m_flags = flags;
    w.world.rayTest(a, b, cb);
    r.hits += cb.hasHit();
    r.distance.push_back(cb.hasHit() ? double(cb.m_closestHitFraction) * double((b - a).length())
                                     : NAN);
  }
  r.world_ns = ms_since(t0) * 1e6 / double(rays.size());
  t0 = Clock::now();
  std::size_t hits = 0;
  for (const auto& [a, b] : rays) {
    btCollisionWorld::ClosestRayResultCallback cb(a, b);
    cb.m_flags = flags;
    btCollisionWorld::rayTestSingle(btTransform(btQuaternion::getIdentity(), a),
                                    btTransform(btQuaternion::getIdentity(), b), &w.ground,
                                    w.ground.getCollisionShape(), w.ground.getWorldTransform(), cb);
    hits += cb.hasHit();
  }
  r.single_ns = ms_since(t0) * 1e6 / double(rays.size());
  if (hits != r.hits) std::fprintf(stderr, "rayTestSingle and rayTest disagree\n");
  return r;
}

// Largest distance difference between two runs' hits, and how many rays hit in one only.
std::pair<double, std::size_t> compare(const RayTimes& a, const RayTimes& b) {
  double worst = 0;
  std::size_t disagree = 0;
  for (std::size_t k = 0; k < a.distance.size(); ++k) {
    if (std::isnan(a.distance[k]) != std::isnan(b.distance[k]))
      ++disagree;
    else if (!std::isnan(a.distance[k]))
      worst = std::max(worst, std::abs(a.distance[k] - b.distance[k]));
  }
  return {worst, disagree};
}

}  // namespace

int main(int argc, char** argv) {
  int steps = 120, rays = 20000;
  bool quick = false, generic = true, bodies = true;
  std::string which = "all";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--quick") {
      quick = true;
    } else if (a == "--steps" && i + 1 < argc) {
      steps = std::max(10, std::atoi(argv[++i]));
    } else if (a == "--rays" && i + 1 < argc) {
      rays = std::max(100, std::atoi(argv[++i]));
    } else if (a == "--no-generic") {
      generic = false;
    } else if (a == "--rays-only") {
      bodies = false;
    } else if (a == "--field" && i + 1 < argc) {
      which = argv[++i];
    } else {
      std::fprintf(stderr,
                   "usage: bench_bullet [--quick] [--steps N] [--rays N] "
                   "[--field noise|default_stored|default|all] [--no-generic] [--rays-only]\n");
      return 2;
    }
  }
  if (quick) steps = 30, rays = 2000;
  const std::vector<int> counts = quick ? std::vector<int>{100} : std::vector<int>{100, 1000};
  std::vector<std::string> fields;
  if (which == "all" || which == "noise") fields.push_back("noise");
  if (which == "all" || which == "default_stored") fields.push_back("default_stored");
  if (which == "all" || which == "default") fields.push_back("default");
  std::printf("{\n  \"machine\": {\"cpu\": \"%s\", \"load_before\": \"%s\"},\n",
              cpu_model().c_str(), load_average().c_str());
  std::printf("  \"steps_per_phase\": %d, \"rays_per_set\": %d,\n  \"fields\": [\n", steps, rays);
  for (std::size_t fi = 0; fi < fields.size(); ++fi) {
    const Field f = make_field(fields[fi]);
    const ridgeline::WorldInfo& hf = f.terrain->info();
    std::fprintf(stderr, "field %s\n", f.name.c_str());
    std::printf(
        "    {\"field\": \"%s\", \"samples\": [%u, %u], \"spacing_m\": %.3f, "
        "\"detail_levels\": %u,\n",
        f.name.c_str(), hf.width, hf.height, hf.spacing_x, f.terrain->surface().detail_levels());
    // Memory the physics route needs beyond the terrain the engine holds anyway.
    const std::size_t bullet_bytes = sizeof(Heightfield) + f.samples.size() * sizeof(float);
    World hw(f, false);
    const std::size_t accel =
        static_cast<const Heightfield*>(hw.ground_shape.get())->accelerator_bytes();
    std::printf(
        "     \"memory_bytes\": {\"terrain_shared\": %zu, \"ridgeline_shape\": %zu, "
        "\"ridgeline_scratch_per_thread_max\": %zu, \"bullet_heightfield_copy\": %zu, "
        "\"bullet_accelerator\": %zu},\n",
        f.terrain->memory_bytes(), sizeof(TerrainShape),
        std::size_t(33 * 33 * 2) * sizeof(ridgeline::SurfaceTriangle), bullet_bytes, accel);
    if (ridgeline::DetailCache* cache = f.terrain->surface().detail_cache()) {
      // With detail: the triangle query once with the detail evaluated directly (no tile
      // resident), then the detail tiles over the middle 800 m made resident, as a game's
      // streaming keeps them around its camera (docs/detail.md); everything below runs on them.
      std::printf("     \"triangle_query_detail_evaluated\": {\"ridgeline\": %s},\n",
                  query_run(f, true, 20000).c_str());
      const double tile_m = ridgeline::kDetailTileCells * hf.spacing_x / 2;  // level 1
      std::vector<ridgeline::DetailTileKey> keys;
      for (double z = f.centre.z - 400; z < f.centre.z + 400 + tile_m; z += tile_m)
        for (double x = f.centre.x - 400; x < f.centre.x + 400 + tile_m; x += tile_m)
          keys.push_back({1, std::int32_t((x - hf.origin_x) / tile_m),
                          std::int32_t((z - hf.origin_z) / tile_m)});
      (void)cache->request_many(keys.data(), keys.size());
      (void)cache->wait_idle(60);
      cache->update();
      std::printf("     \"detail_tiles_resident\": %zu,\n", cache->stats().resident_tiles);
    }
    std::printf("     \"triangle_query\": {\"ridgeline\": %s, \"bullet\": %s},\n",
                query_run(f, true, 20000).c_str(), query_run(f, false, 20000).c_str());
    std::printf("     \"bodies\": [\n");
    for (std::size_t ci = 0; bodies && ci < counts.size(); ++ci) {
      std::fprintf(stderr, "  %d bodies\n", counts[ci]);
      const std::string r = bodies_run(f, true, counts[ci], steps);
      const std::string b = bodies_run(f, false, counts[ci], steps);
      std::printf("       {\"count\": %d, \"ridgeline\": %s,\n        \"bullet\": %s}%s\n",
                  counts[ci], r.c_str(), b.c_str(), ci + 1 < counts.size() ? "," : "");
    }
    std::printf("     ],\n     \"rays\": [\n");
    const auto sets = ray_sets(f, rays);
    for (std::size_t si = 0; si < sets.size(); ++si) {
      const RayTimes r = rays_run(f, true, sets[si]);
      const RayTimes b = rays_run(f, false, sets[si]);
      // Bullet without its accelerator (the generic concave path): slower, but it splits cells
      // along the diagonals its contacts use, which the accelerator does not (docs).
      // (On the first 500 rays: a 500 m sight line costs it milliseconds.)
      RaySet few = sets[si];
      few.rays.resize(std::min<std::size_t>(few.rays.size(), 500));
      const RayTimes rf = rays_run(f, true, few);
      const RayTimes g =
          generic
              ? rays_run(f, false, few, btTriangleRaycastCallback::kF_DisableHeightfieldAccelerator)
              : rf;
      const auto [worst_b, disagree_b] = compare(r, b);
      const auto [worst_g, disagree_g] = compare(rf, g);
      std::printf(
          "       {\"set\": \"%s\", \"ridgeline_ns\": {\"rayTest\": %.1f, \"rayTestSingle\": "
          "%.1f}, "
          "\"bullet_accelerator_ns\": {\"rayTest\": %.1f, \"rayTestSingle\": %.1f}, "
          "\"bullet_generic_ns\": {\"rayTest\": %.1f, \"rayTestSingle\": %.1f},\n"
          "        \"speedup_vs_accelerator\": {\"rayTest\": %.2f, \"rayTestSingle\": %.2f}, "
          "\"hits\": {\"ridgeline\": %zu, \"bullet_accelerator\": %zu, \"bullet_generic\": %zu},\n"
          "        \"vs_accelerator\": {\"hit_miss_disagreements\": %zu, "
          "\"max_distance_difference_m\": %.6f}, "
          "\"vs_generic\": {\"hit_miss_disagreements\": %zu, \"max_distance_difference_m\": "
          "%.6f}}%s\n",
          sets[si].name.c_str(), r.world_ns, r.single_ns, b.world_ns, b.single_ns, g.world_ns,
          g.single_ns, b.world_ns / r.world_ns, b.single_ns / r.single_ns, r.hits, b.hits, g.hits,
          disagree_b, worst_b, disagree_g, worst_g, si + 1 < sets.size() ? "," : "");
    }
    std::printf("     ]}%s\n", fi + 1 < fields.size() ? "," : "");
  }
  std::printf("  ],\n  \"load_after\": \"%s\"\n}\n", load_average().c_str());
  return 0;
}
