// The sample game's physics hears every edit: a truck parked on ground that an edit raises (from
// Lua's terrain:deform, from C++, from a loaded edit state) keeps resting on the new surface
// instead of being launched by its compressed suspension; a crater under it never lets it fall
// through. Headless (ridgeline_game_core, no GL).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>

#include "game.h"
#include "ridgeline/edit.h"
#include "ridgeline/edit_file.h"

using game::Game;
using game::GameOptions;

namespace {

const std::string kTmp = RIDGELINE_TEST_TMP;

std::unique_ptr<Game> make_game() {
  GameOptions o;
  o.assets_dir = RIDGELINE_GAME_ASSETS;
  o.scripts_dir = kTmp;
  o.tessellate = false;
  auto g = Game::create(o);
  EXPECT_TRUE(g.ok()) << (g.ok() ? "" : g.error().message);
  return std::move(g).value();
}

// Centre-of-mass height above the surface under it, metres.
double clearance(const Game& g, const game::VehicleEntry& e) {
  const glm::dvec3 p = e.body.position();
  return p.y - *g.terrain().height(p.x, p.z);
}

// A braked truck parked at (1000, 1000), settled; returns its id and resting clearance.
int park_truck(Game& g, double& resting) {
  auto id = g.spawn("truck", 1000, 1000, 0.0, "parked");
  EXPECT_TRUE(id.ok());
  g.vehicle(*id)->body.controls = {0, 0, 1};
  for (int f = 0; f < 180; ++f) g.step();
  resting = clearance(g, *g.vehicle(*id));
  return *id;
}

// Steps one second and checks the clearance stays within 0.5 m below and 1 m above `resting`.
void expect_rests_through_next_second(Game& g, int id, double resting, const char* what) {
  double lo = 1e9, hi = -1e9;
  for (int f = 0; f < 60; ++f) {
    g.step();
    const double c = clearance(g, *g.vehicle(id));
    lo = std::min(lo, c);
    hi = std::max(hi, c);
  }
  EXPECT_GE(lo, resting - 0.5) << what << ": clearance dropped to " << lo << " (resting " << resting
                               << ")";
  EXPECT_LE(hi, resting + 1.0) << what << ": clearance rose to " << hi << " (resting " << resting
                               << ")";
}

}  // namespace

TEST(GameEdits, LuaDeformRaisingTheGroundUnderATruckLeavesItResting) {
  auto g = make_game();
  double resting = 0;
  const int id = park_truck(*g, resting);
  ASSERT_GT(resting, 0.3);
  ASSERT_LT(resting, 2.0);
  const double before = g->vehicle(id)->body.position().y;
  auto st = g->host().run(
      "assert(game.terrain:deform{brush = 'raise', x = 1000, z = 1000, radius = 12, depth = 5, "
      "strength = 1})",
      "deform");
  ASSERT_TRUE(st.ok()) << st.message();
  expect_rests_through_next_second(*g, id, resting, "terrain:deform raise");
  // It sits about 5 m higher: on the new ground, not launched, not buried.
  EXPECT_NEAR(g->vehicle(id)->body.position().y - before, 5.0, 0.6);
  EXPECT_EQ(g->error_count(), 0u);
}

TEST(GameEdits, CppEditsRaisingTheGroundUnderATruckLeaveItResting) {
  auto g = make_game();
  double resting = 0;
  const int id = park_truck(*g, resting);
  // Two edits between two steps, one of them a smooth-edged mound off-centre: the game reacts
  // to both at its next step.
  ASSERT_TRUE(g->terrain_ptr()->apply_edit(
      {.brush = ridgeline::Brush::kRaise, .x = 1000, .z = 1000, .radius = 12, .depth = 3}));
  ASSERT_TRUE(g->terrain_ptr()->apply_edit(
      {.brush = ridgeline::Brush::kRaise, .x = 1002, .z = 999, .radius = 15, .depth = 2}));
  expect_rests_through_next_second(*g, id, resting, "apply_edit raise x2");
}

TEST(GameEdits, LoadingAnEditStateThatRaisesTheGroundLeavesTheTruckResting) {
  auto g = make_game();
  double resting = 0;
  const int id = park_truck(*g, resting);
  const std::string raised = kTmp + "/game_raised.bin", flat = kTmp + "/game_flat.bin";
  std::filesystem::create_directories(kTmp);
  ASSERT_TRUE(ridgeline::io::save_edits(g->terrain(), flat));
  // A raise elsewhere, saved, then undone: the state holds ground 5 m higher under the truck
  // once it is moved there.
  ASSERT_TRUE(g->terrain_ptr()->apply_edit(
      {.brush = ridgeline::Brush::kRaise, .x = 1000, .z = 1000, .radius = 12, .depth = 5}));
  ASSERT_TRUE(ridgeline::io::save_edits(g->terrain(), raised));
  auto st = g->host().run("assert(ridgeline.load_edits(game.terrain, 'game_flat.bin'))", "undo");
  ASSERT_TRUE(st.ok()) << st.message();
  for (int f = 0; f < 180; ++f) g->step();  // lifted, then lowered back: settles again
  EXPECT_NEAR(clearance(*g, *g->vehicle(id)), resting, 0.1);
  st = g->host().run("assert(ridgeline.load_edits(game.terrain, 'game_raised.bin'))", "load");
  ASSERT_TRUE(st.ok()) << st.message();
  expect_rests_through_next_second(*g, id, resting, "load_edits raise");
}

TEST(GameEdits, ACraterFromLuaUnderATruckNeverLetsItFallThrough) {
  auto g = make_game();
  double resting = 0;
  const int id = park_truck(*g, resting);
  const double before = g->vehicle(id)->body.position().y;
  for (const char* code : {"assert(game.crater{x = 1000, z = 1000, radius = 10, depth = 6})",
                           "assert(game.terrain:deform{brush = 'crater', x = 1001, z = 1000, "
                           "radius = 14, depth = 2})"}) {
    auto st = g->host().run(code, "crater");
    ASSERT_TRUE(st.ok()) << st.message();
    for (int f = 0; f < 240; ++f) {
      g->step();
      const auto& e = *g->vehicle(id);
      ASSERT_GT(clearance(*g, e), 0.0) << code << ", frame " << f;
      for (const auto& w : e.body.wheels()) ASSERT_GT(w.surface_gap, -0.05) << code;
    }
  }
  // It ended in the bowl, at rest.
  const auto& e = *g->vehicle(id);
  EXPECT_LT(e.body.position().y, before - 3.0);
  EXPECT_LT(glm::length(e.body.velocity()), 0.3);
}
