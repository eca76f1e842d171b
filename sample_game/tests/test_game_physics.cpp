// The sample game on Bullet (Ridgeline::bullet): loose bodies (boulders, debris) land in craters
// and roll into vehicles, feel the procedural detail and the ground's material, wake when a
// crater opens under them; the Lua API for them; the default scenario is deterministic.
// Headless (ridgeline_game_core, no GL).
#include <btBulletDynamicsCommon.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "game.h"
#include "ridgeline/edit.h"

using game::BodyShape;
using game::BodySpec;
using game::Game;
using game::GameOptions;

namespace {

const std::string kScripts = RIDGELINE_GAME_SCRIPTS;

std::unique_ptr<Game> make_game() {
  GameOptions o;
  o.assets_dir = RIDGELINE_GAME_ASSETS;
  o.scripts_dir = kScripts;
  o.tessellate = false;
  auto g = Game::create(o);
  EXPECT_TRUE(g.ok()) << (g.ok() ? "" : g.error().message);
  return std::move(g).value();
}

int spawn(Game& g, BodyShape shape, glm::dvec3 size, glm::dvec3 at, glm::dvec3 velocity = {}) {
  BodySpec s;
  s.shape = shape;
  s.size = size;
  s.position = at;
  s.velocity = velocity;
  auto id = g.spawn_body(s);
  EXPECT_TRUE(id.ok()) << (id.ok() ? "" : id.error().message);
  return id.ok() ? *id : -1;
}

double ground(const Game& g, const glm::dvec3& p) {
  return *g.terrain().height(p.x, p.z);
}

}  // namespace

TEST(GamePhysics, ABoulderSpawnedOverAFreshCraterEndsInsideIt) {
  auto g = make_game();
  // Gently sloping ground north of the centre (71-75 m within 20 m).
  const double cx = 1010, cz = 1095, before = *g->terrain().height(cx, cz);
  ASSERT_TRUE(g->crater(cx, cz, 10, 4).ok());
  // Dropped over the rim's inner slope, 7 m from the centre: it rolls down into the bowl.
  const int id =
      spawn(*g, BodyShape::kSphere, glm::dvec3(0.6), {cx + 7, ground(*g, {cx + 7, 0, cz}) + 2, cz});
  for (int f = 0; f < 900; ++f) g->step();
  const game::LooseBody* b = g->body(id);
  ASSERT_NE(b, nullptr);
  const glm::dvec3 p = b->position();
  EXPECT_LT(std::hypot(p.x - cx, p.z - cz), 4.0) << "near the crater's floor";
  EXPECT_LT(p.y, before - 2.0) << "well below the ground that was there";
  // On the crater's surface: on the detail's bumps under it, not exactly above the point below
  // its centre; at most rocking a little in the bowl.
  EXPECT_GT(p.y - 0.6, ground(*g, p) - 0.02);
  EXPECT_LT(p.y - 0.6, ground(*g, p) + 0.15);
  EXPECT_LT(glm::length(b->velocity()), 0.5);
}

TEST(GamePhysics, ASleepingBoulderFallsIntoACraterOpenedUnderIt) {
  auto g = make_game();
  const double x = 1100, z = 950;
  const int box =
      spawn(*g, BodyShape::kBox, {0.4, 0.3, 0.4}, {x, *g->terrain().height(x, z) + 0.5, z});
  for (int f = 0; f < 600 && !g->body(box)->sleeping(); ++f) g->step();
  ASSERT_TRUE(g->body(box)->sleeping()) << "at rest, Bullet put it to sleep";
  const glm::dvec3 rest = g->body(box)->position();
  ASSERT_TRUE(g->crater(rest.x, rest.z, 8, 3).ok());
  for (int f = 0; f < 300; ++f) g->step();
  const glm::dvec3 p = g->body(box)->position();
  EXPECT_LT(p.y, rest.y - 2.0) << "woken by the edit (TerrainSync), it fell in";
  EXPECT_GT(p.y, ground(*g, p)) << "and lies on the crater's floor, not under it";
}

TEST(GamePhysics, ABoulderHurledAtATruckHitsAndShovesIt) {
  auto g = make_game();
  auto t = g->spawn("truck", 1024, 1024, 0, "target");
  ASSERT_TRUE(t.ok());
  game::VehicleEntry* truck = g->vehicle(*t);
  truck->body.controls = {0, 0, 1};
  const std::string script = std::string(RIDGELINE_TEST_TMP) + "/hits.lua";
  std::filesystem::create_directories(RIDGELINE_TEST_TMP);
  std::ofstream(script, std::ios::trunc)
      << "hits = {}\ngame.on('hit', function(v, b, speed) "
         "hits[#hits + 1] = {v = v, b = b, speed = speed} end)\n";
  ASSERT_TRUE(g->load_script(script).ok());
  for (int f = 0; f < 120; ++f) g->step();  // parked
  const glm::dvec3 at = truck->body.position();
  // A 0.8 m boulder (5 t) rolling in from 12 m to the truck's side at 10 m/s.
  const glm::dvec3 from(at.x + 12, 0, at.z);
  const int id = spawn(*g, BodyShape::kSphere, glm::dvec3(0.8),
                       {from.x, ground(*g, from) + 0.85, from.z}, {-10, 0, 0});
  for (int f = 0; f < 180; ++f) g->step();
  EXPECT_EQ(truck->body.body_hits, 1u);
  ASSERT_NE(g->body(id), nullptr);
  EXPECT_EQ(g->body(id)->vehicle_hits, 1u);
  EXPECT_GT(glm::length(truck->body.position() - at), 0.1) << "the truck was shoved";
  const auto st = g->host().run(
      "assert(#hits == 1, #hits); assert(hits[1].v == " + std::to_string(*t) +
          " and hits[1].b == " + std::to_string(id) + "); assert(hits[1].speed > 5, hits[1].speed)",
      "check");
  EXPECT_TRUE(st.ok()) << st.message();
}

TEST(GamePhysics, BodiesRestOnTheProceduralDetailNotOnTheStoredSamples) {
  // The game's world has one detail level (0.2 m bumps at 1 m). A 0.2 m box dropped on flat
  // ground rests on the detail surface: on the highest point of the finest triangles under it,
  // which differs from the stored 2 m surface there.
  auto g = make_game();
  const auto stored = ridgeline::Terrain::create(ridgeline::make_default_heightfield().value()).value();
  const ridgeline::Terrain& t = g->terrain();
  // A point where the detail lifts the ground by more than 5 cm.
  double x = 0, z = 0, best = 0;
  for (double px = 1000.25; px < 1060; px += 1.0)
    for (double pz = 980.25; pz < 1040; pz += 1.0) {
      const double d = *t.height(px, pz) - *stored->height(px, pz);
      const auto n = t.face_normal(px, pz);
      if (d > best && n->y > 0.995) best = d, x = px, z = pz;
    }
  ASSERT_GT(best, 0.05);
  const int id = spawn(*g, BodyShape::kBox, glm::dvec3(0.1), {x, *t.height(x, z) + 0.3, z});
  for (int f = 0; f < 240; ++f) g->step();
  const glm::dvec3 p = g->body(id)->position();
  double top = -1e9, stored_top = -1e9;
  for (double dx : {-0.1, 0.0, 0.1})
    for (double dz : {-0.1, 0.0, 0.1}) {
      top = std::max(top, *t.height(p.x + dx, p.z + dz));
      stored_top = std::max(stored_top, *stored->height(p.x + dx, p.z + dz));
    }
  EXPECT_NEAR(p.y - 0.1, top, 0.03) << "on the detail surface";
  EXPECT_GT(std::abs((p.y - 0.1) - stored_top), 0.04) << "not on the stored one";
}

TEST(GamePhysics, BodiesSlideFurtherOnSnowThanOnGrass) {
  // The terrain's triangles carry their material as Bullet's part id; the game's contact hook
  // scales friction by it (the tyres' factors). Boxes on a 20-degree slope: the combined
  // friction on grass (0.8 x 0.9 = 0.72 > tan 20 = 0.36) holds; on snow (x 0.4 = 0.29) it slides.
  ridgeline::HeightfieldDesc d;
  d.width = d.height = 129;
  std::vector<float> v(129 * 129);
  const double k = std::tan(20.0 * M_PI / 180.0);
  for (std::uint32_t j = 0; j < 129; ++j)
    for (std::uint32_t i = 0; i < 129; ++i) v[i + j * 129] = float(j * k);
  std::vector<std::uint8_t> m(128 * 128);
  for (std::uint32_t j = 0; j < 128; ++j)
    for (std::uint32_t i = 0; i < 128; ++i) m[i + j * 128] = i < 64 ? 0 : 3;
  auto terrain = ridgeline::Terrain::create(ridgeline::Heightfield::create(d, v, m).value()).value();
  auto physics = game::Physics::create(terrain).value();
  auto slide = [&](double x) {
    BodySpec s;
    s.shape = BodyShape::kBox;
    s.size = {0.4, 0.2, 0.4};
    s.position = {x, 64 * k + 0.25, 64};
    game::LooseBody box(*physics, 1, s);
    for (int f = 0; f < 240; ++f) physics->step(1.0 / 60);
    return glm::length(box.position() - s.position);
  };
  EXPECT_LT(slide(32), 0.2) << "holds on grass";
  EXPECT_GT(slide(96), 3.0) << "slides on snow";
}

TEST(GamePhysics, TheLuaApiSpawnsAndQueriesBodies) {
  auto g = make_game();
  auto ok = [&](const std::string& code) {
    const auto st = g->host().run(code, "bodies");
    EXPECT_TRUE(st.ok()) << st.message();
  };
  auto fails = [&](const std::string& code, const char* needle) {
    const auto st = g->host().run(code, "bodies");
    ASSERT_FALSE(st.ok()) << code;
    EXPECT_NE(st.message().find(needle), std::string::npos) << st.message();
  };
  ok("b = assert(game.spawn_body{x = 1000, z = 1000, radius = 0.5, velocity = {1, 2, 3}}); "
     "local s = b:state(); assert(s.shape == 'sphere' and s.radius == 0.5 and s.name == "
     "'boulder'); "
     "assert(math.abs(s.mass - 2400 * 4 / 3 * math.pi * 0.125) < 1e-6 * s.mass); "
     "assert(s.vy == 2 and not s.sleeping and s.hits == 0); "
     "local x, y, z = b:position(); assert(x == 1000 and z == 1000); "
     "assert(y > game.terrain:height(1000, 1000)); "
     "c = assert(game.spawn_body{shape = 'box', x = 1010, z = 1000, size = {1, 0.5, 2}, "
     "mass = 40, name = 'crate'}); assert(c:state().size[3] == 2 and c:state().mass == 40); "
     "assert(#game.bodies() == 2 and game.body(c:id()) == c and tostring(c):find('crate'))");
  ok("c:push{y = 400}; local _, vy = c:velocity(); assert(vy > 9, vy)");
  ok("assert(c:remove() and not c:alive() and game.body(c:id()) == nil and #game.bodies() == 1)");
  fails("c:position()", "attempt to use a removed body");
  fails("game.spawn_body{x = 1, z = 1, shape = 'cone'}", "'sphere' or 'box' expected, got 'cone'");
  fails("game.spawn_body{x = 1, z = 1, radius = 9}", "'radius': 0.05 .. 5 metres");
  fails("game.spawn_body{x = 1, z = 1, size = {1, 1, 1}}", "'size': for boxes");
  fails("game.spawn_body{x = 1, z = 1, shape = 'box', radius = 1}", "'radius': for spheres");
  fails("game.spawn_body{x = 1, z = 1, shape = 'box', size = {1, 0, 1}}", "0.1 .. 10 metres");
  fails("game.spawn_body{x = 1, z = 1, mass = -3}", "'mass': 0 < kg");
  fails("game.spawn_body{x = 1, z = 1, velocity = {0/0, 0, 0}}", "finite number expected");
  fails("game.spawn_body{x = 1, z = 1, velocity = {1e9, 0, 0}}", "'velocity': length");
  fails("game.spawn_body{x = 1}", "fields 'x' and 'z'");
  fails("game.spawn_body{x = 1, z = 1, colour = 'red'}", "unknown field 'colour'");
  fails("b:push{x = 0/0}", "finite number expected");
  ok("local r, err = game.spawn_body{x = -50, z = 1}; assert(r == nil and err:find('off the "
     "terrain'))");
}

TEST(GamePhysics, SpawningPastTheCapRemovesTheOldest) {
  auto g = make_game();
  std::vector<int> ids;
  for (std::size_t k = 0; k < game::kMaxBodies + 5; ++k)
    ids.push_back(spawn(*g, BodyShape::kSphere, glm::dvec3(0.3),
                        {900 + double(k % 20) * 2, 150, 900 + double(k / 20) * 2}));
  EXPECT_EQ(g->bodies().size(), game::kMaxBodies);
  for (int k = 0; k < 5; ++k) EXPECT_EQ(g->body(ids[std::size_t(k)]), nullptr) << "oldest gone";
  EXPECT_NE(g->body(ids.back()), nullptr);
}

TEST(GamePhysics, TheDefaultScenarioIsDeterministic) {
  // The convoy, the artillery's craters and their boulders, the earthworks: 400 fixed steps
  // twice give the same vehicles and bodies bit for bit.
  auto run = [] {
    auto g = make_game();
    for (const char* s : {"default.lua", "artillery.lua", "earthworks.lua"})
      EXPECT_TRUE(g->load_script(kScripts + "/" + s).ok());
    for (int f = 0; f < 400; ++f) g->step();
    std::uint64_t h = 1469598103934665603ull;
    auto mix = [&](const glm::dvec3& v) {
      for (int i = 0; i < 3; ++i) {
        std::uint64_t bits;
        std::memcpy(&bits, &v[i], sizeof bits);
        h = (h ^ bits) * 1099511628211ull;
      }
    };
    for (const auto& [id, e] : g->vehicles()) mix(e.body.position()), mix(e.body.velocity());
    for (const auto& [id, b] : g->bodies()) mix(b.position()), mix(b.velocity());
    EXPECT_GT(g->bodies().size(), 10u) << "the craters threw boulders";
    return h;
  };
  EXPECT_EQ(run(), run());
}
