// Holes under real Bullet bodies (docs/deformation.md, "Holes"): the Ridgeline shape gives Bullet
// no triangle over a hole, so a body over a hole falls through while one beside it rests, a
// sleeping body falls through a hole dug under it once TerrainSync has run, and Bullet's rays
// pass through the hole as Ridgeline's own raycast does.
#include <gtest/gtest.h>

#include <cmath>
#include <glm/geometric.hpp>

#include "bullet_test_util.h"
#include "ridgeline/bullet/terrain_sync.h"
#include "ridgeline/edit.h"
#include "ridgeline/scenes.h"

using ridgeline::Brush;
using ridgeline::bullet::TerrainSync;
using ridgeline::bullet::test::World;

namespace {

constexpr double kGround = 20.0, kR = 0.5;

// 129 x 129 samples 1 m apart, flat at kGround.
std::shared_ptr<ridgeline::Terrain> flat_ground() {
  auto hf = ridgeline::scenes::field({.width = 129, .height = 129}, [](int, int) { return kGround; });
  return ridgeline::Terrain::create(std::move(hf).value()).value();
}

}  // namespace

TEST(BulletHoles, ABodyOverAHoleFallsThroughAndOneBesideItRests) {
  auto terrain = flat_ground();
  // Cells whose centre lies within 4 m of (40.5, 40.5): about 7 x 7 cells.
  ASSERT_TRUE(terrain->apply_edit({.brush = Brush::kHole, .x = 40.5, .z = 40.5, .radius = 4}));
  World w(terrain, {.origin = {64, 0, 64}});
  btRigidBody* over = w.sphere(kR, {40.5, kGround + 1, 40.5});
  btRigidBody* beside = w.sphere(kR, {47.5, kGround + 1, 40.5});  // a cell past the hole's edge
  btRigidBody* box = w.box({0.5, 0.25, 0.5}, {40.5, kGround + 1, 30.5});
  w.step(300);  // 5 s: time to settle, and a free fall of 120 m
  EXPECT_LT(w.position(over).y, kGround - 20) << "through the hole";
  EXPECT_NEAR(w.position(beside).y - kR, kGround, 1e-3) << "on the ground beside it";
  // (A box this size settles about a centimetre into the ground: its collision margin.)
  EXPECT_NEAR(w.position(box).y - 0.25, kGround, 0.02) << "on the ground beside it";
  EXPECT_NEAR(w.position(beside).x, 47.5, 1e-3) << "not drawn into the hole";
}

TEST(BulletHoles, ASleepingBodyFallsThroughAHoleDugUnderIt) {
  auto terrain = flat_ground();
  World w(terrain, {.origin = {64, 0, 64}});
  auto sync = TerrainSync::create(&w.world, &w.ground).value();
  btRigidBody* s = w.sphere(kR, {60.5, kGround + 1, 61.5});
  btRigidBody* far_away = w.sphere(kR, {10.5, kGround + 1, 10.5});
  for (int i = 0; i < 1200 && (s->isActive() || far_away->isActive()); ++i) w.step(1);
  ASSERT_FALSE(s->isActive()) << "the body went to sleep";
  EXPECT_NEAR(w.position(s).y - kR, kGround, 1e-3);

  ASSERT_TRUE(terrain->apply_edit({.brush = Brush::kHole, .x = 60.5, .z = 61.5, .radius = 3}));
  const auto stats = sync.update();
  EXPECT_EQ(stats.changes, 1u);
  EXPECT_EQ(stats.bodies_woken, 1u) << "only the body over the hole";
  w.step(180);
  EXPECT_LT(w.position(s).y, kGround - 20) << "it fell through";
  EXPECT_NEAR(w.position(far_away).y - kR, kGround, 1e-3);
  // Filled again, a body dropped there rests on the ground it had.
  ASSERT_TRUE(terrain->apply_edit({.brush = Brush::kFillHole, .x = 60.5, .z = 61.5, .radius = 3}));
  EXPECT_EQ(sync.update().changes, 1u);
  btRigidBody* again = w.sphere(kR, {60.5, kGround + 1, 61.5});
  w.step(180);
  EXPECT_NEAR(w.position(again).y - kR, kGround, 1e-3);
}

TEST(BulletHoles, RaysPassThroughTheHoleAsRidgelinesDo) {
  auto terrain = flat_ground();
  ASSERT_TRUE(terrain->apply_edit({.brush = Brush::kHole, .x = 40.5, .z = 40.5, .radius = 4}));
  World w(terrain, {.origin = {64, 0, 64}});
  auto trace = [&](const glm::dvec3& a, const glm::dvec3& b) {
    const btVector3 from = w.shape->to_local(a), to = w.shape->to_local(b);
    btCollisionWorld::ClosestRayResultCallback cb(from, to);
    w.world.rayTest(from, to, cb);
    return cb;
  };
  // Straight down the hole: no hit; beside it: the ground.
  EXPECT_FALSE(trace({40.5, 30, 40.5}, {40.5, -30, 40.5}).hasHit());
  const auto down = trace({50.5, 30, 40.5}, {50.5, -30, 40.5});
  ASSERT_TRUE(down.hasHit());
  EXPECT_NEAR(w.shape->to_world(down.m_hitPointWorld).y, kGround, 1e-4);
  // Slanted across the hole (cells 36..44 of row 40): it would land at x = 40 without it, and
  // hits the hole's far wall at x = 45 instead, where Ridgeline's raycast does.
  const glm::dvec3 a(30, kGround + 1, 40.5), b(60, kGround - 2, 40.5);
  const auto slanted = trace(a, b);
  ASSERT_TRUE(slanted.hasHit());
  const auto hit = terrain->raycast(a, b - a, glm::length(b - a));
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->point.x, 45.0, 1e-9);
  EXPECT_NEAR(w.shape->to_world(slanted.m_hitPointWorld).x, 45.0, 1e-3);
}
