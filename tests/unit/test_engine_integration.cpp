// docs/engine_integration.md's example, compiled as written (tests/CMakeLists.txt extracts its
// ```cpp blocks into engine_integration_snippet.h) and run: an engine's height field collider
// polled with Terrain::changes_since follows every edit (brushes, a loaded edit state, more edits
// than the log holds), sample for sample equal to the surface, and exactly the bodies over
// changed ground wake; with and without procedural detail.
#include "engine_integration_snippet.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <memory>
#include <string>

#include "ridgeline/detail.h"
#include "ridgeline/edit.h"

namespace {

using ridgeline::Edit;
using ridgeline::Terrain;

// A collider over the whole footprint and a little past it (those samples stay 0), at a spacing
// unrelated to the terrain's, filled from the surface.
HeightfieldCollider make_collider(const Terrain& t) {
  const ridgeline::Heightfield hf = t.surface().to_heightfield().value();
  HeightfieldCollider c;
  c.origin_x = hf.origin_x() - 3;
  c.origin_z = hf.origin_z() - 3;
  c.spacing = 1.5;
  c.size_x = int(hf.extent_x() / c.spacing) + 6;
  c.size_z = int(hf.extent_z() / c.spacing) + 6;
  c.heights.assign(std::size_t(c.size_x) * std::size_t(c.size_z), 0.0f);
  for (int z = 0; z < c.size_z; ++z)
    for (int x = 0; x < c.size_x; ++x)
      if (auto h = t.height(c.origin_x + x * c.spacing, c.origin_z + z * c.spacing))
        c.heights[std::size_t(x) + std::size_t(z) * std::size_t(c.size_x)] = float(*h);
  return c;
}

// Bodies resting 0.5 m above the ground every 20 m.
std::vector<Body> make_bodies(const Terrain& t) {
  std::vector<Body> bodies;
  const ridgeline::Heightfield hf = t.surface().to_heightfield().value();
  for (double z = hf.origin_z() + 10; z < hf.origin_z() + hf.extent_z(); z += 20)
    for (double x = hf.origin_x() + 10; x < hf.origin_x() + hf.extent_x(); x += 20)
      bodies.push_back({x, *t.height(x, z) + 0.5, z, false});
  return bodies;
}

// Every collider sample equals a fresh fill from the surface, bit for bit.
void expect_collider_matches(const Terrain& t, const HeightfieldCollider& c) {
  const HeightfieldCollider fresh = make_collider(t);
  std::size_t differ = 0;
  for (std::size_t k = 0; k < c.heights.size(); ++k) differ += c.heights[k] != fresh.heights[k];
  EXPECT_EQ(differ, 0u) << "collider samples stale after the poll";
}

struct World {
  std::shared_ptr<Terrain> terrain;
  HeightfieldCollider collider;
  std::vector<Body> bodies;
  std::uint64_t seen = 0;

  explicit World(std::shared_ptr<Terrain> t)
      : terrain(std::move(t)),
        collider(make_collider(*terrain)),
        bodies(make_bodies(*terrain)),
        seen(terrain->edit_version()) {}
  // Puts every body to sleep, polls, and returns how many woke.
  int poll() {
    for (Body& b : bodies) b.awake = false;
    follow_terrain(*terrain, seen, collider, bodies);
    int awake = 0;
    for (const Body& b : bodies) awake += b.awake;
    return awake;
  }
};

std::shared_ptr<Terrain> plain_terrain() {
  auto hf = ridgeline::make_default_heightfield({.size = 257, .spacing = 2.0, .seed = 5});
  return Terrain::create(std::move(hf).value()).value();
}

std::shared_ptr<Terrain> detail_terrain() {
  auto hf = ridgeline::make_default_heightfield({.size = 129, .spacing = 4.0, .seed = 5});
  ridgeline::DetailParams p;
  p.levels = 2;
  p.amplitude = 1.5;
  ridgeline::DetailCacheDesc cache;
  cache.worker_threads = 0;
  auto t = Terrain::create(std::move(hf).value(), p, cache);
  EXPECT_TRUE(t.ok());
  return std::move(t).value();
}

Edit brush(ridgeline::Brush b, double x, double z, double radius, double depth) {
  Edit e;
  e.brush = b;
  e.x = x;
  e.z = z;
  e.radius = radius;
  e.depth = depth;
  return e;
}

void follows_brushes(std::shared_ptr<Terrain> terrain) {
  World w(std::move(terrain));
  const ridgeline::Heightfield hf = w.terrain->surface().to_heightfield().value();
  // Nothing changed: nothing to do.
  const std::vector<float> before = w.collider.heights;
  EXPECT_EQ(w.poll(), 0);
  EXPECT_EQ(w.collider.heights, before);

  // One edit at a time: the collider follows, and the bodies over the crater wake, not the rest.
  const double cx = hf.origin_x() + 0.3 * hf.extent_x(), cz = hf.origin_z() + 0.4 * hf.extent_z();
  ASSERT_TRUE(w.terrain->apply_edit(brush(ridgeline::Brush::kCrater, cx, cz, 12, 4)));
  const int woke = w.poll();
  EXPECT_GT(woke, 0);
  EXPECT_LT(woke, int(w.bodies.size()) / 10);
  for (const Body& b : w.bodies) {
    const double d = std::hypot(b.x - cx, b.z - cz);
    if (d < 12) {
      EXPECT_TRUE(b.awake) << "a body in the crater sleeps";
    }
    // Beyond the crater's reach, the cells around it and the margin: asleep.
    if (d > 1.5 * 12 + 2 * hf.spacing_x() + 3) {
      EXPECT_FALSE(b.awake) << d << " m away";
    }
  }
  expect_collider_matches(*w.terrain, w.collider);

  // Several brushes between two polls, one of them over the footprint's edge.
  ASSERT_TRUE(w.terrain->apply_edit(brush(ridgeline::Brush::kRaise, hf.origin_x() + 2, cz, 20, 6)));
  Edit flat = brush(ridgeline::Brush::kFlatten, cx + 60, cz, 15, 0);
  flat.height = *w.terrain->height(cx + 60, cz) + 3;
  ASSERT_TRUE(w.terrain->apply_edit(flat));
  ASSERT_TRUE(w.terrain->apply_edit(brush(ridgeline::Brush::kSmooth, cx, cz, 10, 0)));
  EXPECT_GT(w.poll(), 0);
  expect_collider_matches(*w.terrain, w.collider);
  EXPECT_EQ(w.seen, w.terrain->edit_version());
}

TEST(EngineIntegration, ColliderFollowsEveryBrush) { follows_brushes(plain_terrain()); }

TEST(EngineIntegration, ColliderFollowsEveryBrushWithDetail) { follows_brushes(detail_terrain()); }

TEST(EngineIntegration, ColliderFollowsALoadedEditState) {
  World w(plain_terrain());
  ASSERT_TRUE(w.terrain->apply_edit(brush(ridgeline::Brush::kCrater, 200, 300, 15, 5)));
  // What an engine keeps in its own save game.
  const std::string saved = ridgeline::save_edits_to_memory(*w.terrain);
  w.poll();
  ASSERT_TRUE(w.terrain->apply_edit(brush(ridgeline::Brush::kRaise, 400, 100, 25, 8)));
  w.poll();
  // Loading undoes the raise: its ground moves back, and the collider with it.
  ASSERT_TRUE(ridgeline::load_edits_from_memory(*w.terrain, saved));
  EXPECT_GT(w.poll(), 0);
  expect_collider_matches(*w.terrain, w.collider);
}

TEST(EngineIntegration, ColliderFollowsMoreEditsThanTheLogHolds) {
  World w(plain_terrain());
  const ridgeline::Heightfield hf = w.terrain->surface().to_heightfield().value();
  // More changes than the log keeps one by one: the poll gets one merged box (trimmed).
  for (std::size_t k = 0; k < ridgeline::kChangeLogCapacity + 40; ++k) {
    const double x = hf.origin_x() + 20 + double(k % 40) * 11;
    const double z = hf.origin_z() + 30 + double(k / 40) * 15;
    ASSERT_TRUE(w.terrain->apply_edit(brush(ridgeline::Brush::kRaise, x, z, 4, 0.2)));
  }
  EXPECT_TRUE(w.terrain->changes_since(w.seen).trimmed);
  EXPECT_GT(w.poll(), 0);
  expect_collider_matches(*w.terrain, w.collider);
  EXPECT_TRUE(w.terrain->changes_since(w.seen).empty());
}

}  // namespace
