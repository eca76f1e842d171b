// The sample game's simulation without GL: the default scenario for 600 fixed steps, vehicle
// physics on analytic ground, bad scripts, hot reload, the game API's error answers.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <thread>

#include "game.h"

using game::Game;
using game::GameOptions;

namespace {

const std::string kScripts = RIDGELINE_GAME_SCRIPTS;
const std::string kTmp = RIDGELINE_TEST_TMP;

std::unique_ptr<Game> make_game(bool tessellate = false) {
  GameOptions o;
  o.assets_dir = RIDGELINE_GAME_ASSETS;
  o.scripts_dir = kScripts;
  o.tessellate = tessellate;
  // Tiles arrive before each mesh is judged: the meshes the tests compare do not depend on when
  // the detail cache's workers (below the test's priority) get a core.
  o.prefill_detail = tessellate;
  o.instruction_limit = 2'000'000;
  auto g = Game::create(o);
  EXPECT_TRUE(g.ok()) << (g.ok() ? "" : g.error().message);
  return std::move(g).value();
}

std::string write_script(const std::string& name, const std::string& text) {
  std::filesystem::create_directories(kTmp);
  const std::string path = kTmp + "/" + name;
  std::ofstream(path, std::ios::trunc) << text;
  return path;
}

}  // namespace

TEST(Game, DefaultScenarioRuns600FramesWithWheelsOnTheSurface) {
  auto g = make_game();
  for (const char* s : {"default.lua", "artillery.lua", "budget.lua", "earthworks.lua"})
    ASSERT_TRUE(g->load_script(kScripts + "/" + s).ok()) << s;
  ASSERT_EQ(g->vehicles().size(), 4u);
  std::map<int, glm::dvec3> start;
  for (auto& [id, e] : g->vehicles()) start[id] = e.body.position();
  double worst_sink = 0, worst_contact = 0;
  std::uint64_t contacts = 0;
  for (int f = 0; f < 600; ++f) {
    g->step();
    for (auto& [id, e] : g->vehicles()) {
      for (const auto& w : e.body.wheels()) {
        // No wheel sinks into the surface, and a wheel in contact touches it.
        worst_sink = std::min(worst_sink, w.surface_gap);
        if (w.contact) {
          ++contacts;
          worst_contact = std::max(worst_contact, std::abs(w.surface_gap));
        }
      }
      // The body's centre stays above the surface.
      const glm::dvec3 p = e.body.position();
      const auto h = g->terrain().height(p.x, p.z);
      ASSERT_TRUE(h.has_value());
      ASSERT_GT(p.y, *h) << "vehicle " << id << " fell through at frame " << f;
    }
  }
  EXPECT_EQ(g->error_count(), 0u) << (g->errors().empty() ? "" : g->errors().back().message);
  EXPECT_GT(worst_sink, -0.05) << "a wheel sank into the surface";
  EXPECT_LT(worst_contact, 0.05) << "a wheel in contact floats or sinks";
  EXPECT_GT(contacts, 600u * 16 / 2) << "wheels are mostly on the ground";
  for (auto& [id, e] : g->vehicles()) {
    // Waypoints are 50 m apart and the convoy drives at about 10 m/s.
    EXPECT_GE(e.autopilot.reached, 1u) << e.name << " made no progress along its waypoints";
    EXPECT_GT(e.distance_m, 60.0) << e.name;
    EXPECT_TRUE(e.autopilot.active);
  }
  EXPECT_GE(g->craters().size(), 4u) << "the artillery made craters";
}

TEST(Game, AVehicleAtRestSettlesOnItsWheels) {
  auto g = make_game();
  auto id = g->spawn("truck", 1024, 1024, 0.3, "t");
  ASSERT_TRUE(id.ok());
  auto* e = g->vehicle(*id);
  e->body.controls = {0, 0, 1};
  for (int f = 0; f < 240; ++f) g->step();
  int contacts = 0;
  for (const auto& w : e->body.wheels()) {
    contacts += w.contact;
    EXPECT_NEAR(w.surface_gap, 0.0, 0.05);
    EXPECT_GT(w.suspension_length, 0.0) << "bottomed out";
    EXPECT_LT(w.suspension_length, e->body.params().rest_length) << "not loaded";
  }
  EXPECT_EQ(contacts, 4);
  EXPECT_LT(glm::length(e->body.velocity()), 0.5) << "a braked vehicle comes to rest";
}

TEST(Game, ACraterUnderAVehicleNeverLetsItFallThrough) {
  auto g = make_game();
  auto id = g->spawn("buggy", 900, 900, 0, "b");
  ASSERT_TRUE(id.ok());
  for (int f = 0; f < 60; ++f) g->step();
  auto* e = g->vehicle(*id);
  const glm::dvec3 p = e->body.position();
  auto r = g->crater(p.x, p.z, 10, 6);
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_GT(*r, 0u);
  for (int f = 0; f < 240; ++f) {
    g->step();
    const glm::dvec3 q = e->body.position();
    ASSERT_GT(q.y, *g->terrain().height(q.x, q.z));
    for (const auto& w : e->body.wheels()) ASSERT_GT(w.surface_gap, -0.05) << "frame " << f;
  }
  // It ended in the crater's bowl, below where it stood.
  EXPECT_LT(e->body.position().y, p.y - 2.0);
}

TEST(Game, BadScriptsAreReportedAndTheGameGoesOn) {
  auto g = make_game();
  const auto syntax = write_script("bad_syntax.lua", "game.on('tick', function( end\n");
  const auto runtime =
      write_script("bad_runtime.lua",
                   "game.on('tick', function(dt, t) if t > 0.1 then local x = nil; "
                   "return x.field end end)\n");
  const auto loop =
      write_script("bad_loop.lua", "game.on('tick', function() while true do end end)\n");
  const auto good = write_script("good.lua",
                                 "ticks = 0\ngame.on('tick', function() ticks = "
                                 "ticks + 1 end)\n");
  EXPECT_FALSE(g->load_script(syntax).ok());
  EXPECT_TRUE(g->load_script(runtime).ok());
  EXPECT_TRUE(g->load_script(loop).ok());
  EXPECT_TRUE(g->load_script(good).ok());
  ASSERT_TRUE(g->load_script(kScripts + "/default.lua").ok());
  for (int f = 0; f < 120; ++f) g->step();
  ASSERT_EQ(g->error_count(), 3u);
  EXPECT_NE(g->errors()[0].message.find("bad_syntax.lua:1"), std::string::npos)
      << g->errors()[0].message;
  bool runtime_seen = false, loop_seen = false;
  for (const auto& e : g->errors()) {
    if (e.script == "bad_runtime.lua") {
      runtime_seen = true;
      EXPECT_NE(e.message.find("attempt to index"), std::string::npos) << e.message;
      EXPECT_NE(e.message.find("stack traceback"), std::string::npos) << e.message;
    }
    if (e.script == "bad_loop.lua") {
      loop_seen = true;
      EXPECT_NE(e.message.find("instruction"), std::string::npos) << e.message;
    }
  }
  EXPECT_TRUE(runtime_seen);
  EXPECT_TRUE(loop_seen);
  // The good script and the vehicles kept running.
  lua_State* L = g->host().state();
  ASSERT_TRUE(g->host().run("assert(ticks == 120, 'ticks ' .. tostring(ticks))", "check").ok());
  (void)L;
  for (auto& [id, e] : g->vehicles()) EXPECT_GT(e.distance_m, 5.0);
}

TEST(Game, ScriptsReloadWithoutRestarting) {
  auto g = make_game();
  const auto path = write_script("reload.lua",
                                 "value = 1\ngame.on('tick', function() "
                                 "hits = (hits or 0) + 1 end)\n");
  ASSERT_TRUE(g->load_script(path).ok());
  g->step();
  EXPECT_EQ(g->reload_changed_scripts(), 0);
  // A broken edit: reported, the game goes on; fixing it brings the script back.
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  write_script("reload.lua", "value = = 2\n");
  std::filesystem::last_write_time(path, std::filesystem::file_time_type::clock::now());
  EXPECT_EQ(g->reload_changed_scripts(), 1);
  EXPECT_EQ(g->error_count(), 1u);
  g->step();
  write_script("reload.lua", "value = 3\ngame.on('tick', function() hits = 100 end)\n");
  std::filesystem::last_write_time(
      path, std::filesystem::file_time_type::clock::now() + std::chrono::seconds(1));
  EXPECT_EQ(g->reload_changed_scripts(), 1);
  g->step();
  ASSERT_TRUE(g->host()
                  .run("assert(value == 3 and hits == 100, 'value ' .. tostring(value) .. "
                       "', hits ' .. tostring(hits))",
                       "check")
                  .ok());
  // Only one tick handler is live after the reloads (the old ones were dropped).
  ASSERT_TRUE(g->host().run("hits = 0", "reset").ok());
  g->step();
  ASSERT_TRUE(g->host().run("assert(hits == 100)", "check2").ok());
}

TEST(Game, ApiErrorsNameTheProblem) {
  auto g = make_game();
  auto expect_error = [&](const char* code, const char* needle) {
    const auto st = g->host().run(code, "api");
    ASSERT_FALSE(st.ok()) << code;
    EXPECT_NE(st.message().find(needle), std::string::npos) << st.message();
  };
  expect_error(
      "game.spawn{model='tank', x=1, z=1} error(select(2, game.spawn{model='tank', x=1, z=1}))",
      "unknown model 'tank'");
  expect_error("error(select(2, game.spawn{x=-50, z=1}))", "off the terrain");
  expect_error("game.spawn{x=1}", "fields 'x' and 'z'");
  expect_error("game.spawn{x=1, z=2, colour='red'}", "unknown field 'colour'");
  expect_error("local v = game.spawn{x=500, z=500}; v:set_controls{throttle=2}",
               "'throttle': -1 .. 1");
  expect_error("local v = game.spawn{x=500, z=500}; v:follow{waypoints={{1, 'a'}}}", "waypoint 1");
  expect_error("local v = game.spawn{x=500, z=500}; v:remove(); v:position()", "removed vehicle");
  expect_error("game.on('explode', print)", "invalid option 'explode'");
  expect_error("game.set_budget{threshold=-1}", "'threshold': 0.25 .. 256");
  expect_error("game.set_budget{min=8, max=2}", "0.25 <= min <= max");
  expect_error("game.set_budget{deadband=0.5}", "'deadband': 0 .. 0.5");
  expect_error("game.set_budget{deadband='x'}", "deadband");
  expect_error("game.set_budget{headroom=-1}", "'headroom': 0 .. 100");
  expect_error("game.burn_ms(1000)", "0 .. 100 milliseconds");
  expect_error("game.camera{mode='orbit'}", "'free', 'follow' or 'map' expected, got 'orbit'");
  expect_error("game.crater{x=1, z=1, radius=0}", "'radius'");
  // Nothing half-applied: the budget is unchanged after the failed calls.
  EXPECT_DOUBLE_EQ(g->controller().desc().min_threshold, 1.0);
  EXPECT_TRUE(g->controller_on());
  // The terrain the scripts see is the game's.
  ASSERT_TRUE(g->host()
                  .run("local h = game.terrain:height(1024, 1024); "
                       "assert(math.abs(h - " +
                           std::to_string(*g->terrain().height(1024, 1024)) + ") < 1e-6)",
                       "terrain")
                  .ok());
}

TEST(Game, SetBudgetAndTheController) {
  auto g = make_game(true);
  ASSERT_TRUE(
      g->host().run("game.set_budget{controller=false, threshold=6, triangles=20000}", "b").ok());
  EXPECT_FALSE(g->controller_on());
  EXPECT_EQ(g->threshold(), 6);
  auto f = g->update_view(50);
  EXPECT_EQ(f.threshold, 6) << "a fixed threshold ignores frame times";
  EXPECT_LE(f.stats.triangles, 20000u);
  ASSERT_TRUE(
      g->host()
          .run("game.set_budget{controller=true, target_ms=20, deadband=0.04, headroom=2}", "b")
          .ok());
  EXPECT_DOUBLE_EQ(g->controller().desc().deadband, 0.04);
  EXPECT_DOUBLE_EQ(g->controller().desc().headroom_gain, 2.0);
  for (int i = 0; i < 60; ++i) f = g->update_view(60);
  EXPECT_GT(f.threshold, 6) << "slow frames raise the threshold";
}

// ---- the detail world, materials, collisions, the console (issue: the whole mission) --------

#include <btBulletDynamicsCommon.h>

#include "materials.h"
#include "physics.h"
#include "ridgeline/lua/host.h"

TEST(Game, TheDefaultWorldCarriesDetailBelowTheStoredSpacingNearTheVehicles) {
  GameOptions o;
  o.assets_dir = RIDGELINE_GAME_ASSETS;
  o.scripts_dir = kScripts;
  o.prefill_detail = true;  // tiles arrive before the mesh is judged
  o.fixed_threshold = 2;
  o.max_triangles = 400000;
  o.tessellation_budget_ms = 0;
  auto made = Game::create(o);
  ASSERT_TRUE(made.ok()) << made.error().message;
  Game& g = **made;
  ASSERT_GE(g.terrain().surface().detail_levels(), 1u);
  ASSERT_NE(g.terrain().surface().detail_cache(), nullptr);
  ASSERT_TRUE(g.load_script(kScripts + "/default.lua").ok());
  for (int f = 0; f < 30; ++f) g.step();
  const auto vf = g.update_view(0);
  ASSERT_TRUE(vf.updated);
  EXPECT_EQ(vf.stats.stop, ridgeline::StopReason::kConverged);
  EXPECT_EQ(vf.stats.pending_splits, 0u) << "prefill waits for every tile";
  auto ds = g.detail_stats();
  ASSERT_TRUE(ds.has_value());
  EXPECT_GT(ds->resident_tiles, 0u);
  // Leaves within 30 m of the followed vehicle whose longest edge is shorter than the stored
  // spacing: the mesh refines into the detail there.
  const ridgeline::Heightfield hf = g.terrain().surface().to_heightfield().value();
  const double fine = hf.spacing_x() / double(1u << g.terrain().surface().detail_levels());
  const glm::dvec3 p = g.vehicles().begin()->second.body.position();
  std::size_t near = 0, below = 0;
  g.active_view().for_each_leaf([&](std::uint32_t, std::uint64_t,
                                    const ridgeline::LatticeTriangle& t) {
    const double x = hf.origin_x() + double(t.ax) * fine, z = hf.origin_z() + double(t.az) * fine;
    if (std::hypot(x - p.x, z - p.z) > 30) return;
    ++near;
    const double hyp = std::hypot(double(t.lx - t.rx), double(t.lz - t.rz)) * fine;
    below += hyp < hf.spacing_x() - 1e-9;
  });
  EXPECT_GT(near, 100u);
  EXPECT_GT(below, near / 4) << below << " of " << near << " leaves near the vehicle are finer "
                             << "than the stored 2 m";
  // Vehicles drive on the detail surface: their wheels touch what queries (with detail) return.
  for (int f = 0; f < 120; ++f) g.step();
  for (const auto& [id, e] : g.vehicles())
    for (const auto& w : e.body.wheels())
      if (w.contact) {
        EXPECT_NEAR(w.surface_gap, 0.0, 0.05) << e.name;
      }
}

TEST(Game, TheDefaultWorldHasAMaterialMap) {
  auto g = make_game();
  const ridgeline::Heightfield hf = g->terrain().surface().to_heightfield().value();
  ASSERT_TRUE(hf.has_materials());
  std::size_t count[256] = {};
  for (std::uint32_t j = 0; j + 1 < hf.height(); ++j)
    for (std::uint32_t i = 0; i + 1 < hf.width(); ++i) ++count[hf.material(i, j)];
  const double cells = double(hf.width() - 1) * double(hf.height() - 1);
  for (int m = 0; m < game::kMaterialCount; ++m)
    EXPECT_GT(count[m] / cells, 0.005) << game::material(std::uint8_t(m)).name << " is missing";
  EXPECT_GT(count[0] / cells, 0.3) << "grass covers most of the world";
  // Queries return it: what the tyres and the renderer read.
  EXPECT_EQ(g->terrain().sample(1.0, 1.0)->material, hf.material(0, 0));
}

namespace {

// A 128 m x 128 m plane rising along z at `slope`, grass for x < 64 m and `right` beyond.
std::shared_ptr<ridgeline::Terrain> slope_terrain(double slope, std::uint8_t right) {
  ridgeline::HeightfieldDesc d;
  d.width = d.height = 129;
  std::vector<float> v(129 * 129);
  for (std::uint32_t j = 0; j < 129; ++j)
    for (std::uint32_t i = 0; i < 129; ++i) v[i + j * 129] = float(j * slope);
  std::vector<std::uint8_t> m(128 * 128);
  for (std::uint32_t j = 0; j < 128; ++j)
    for (std::uint32_t i = 0; i < 128; ++i) m[i + j * 128] = i < 64 ? 0 : right;
  return ridgeline::Terrain::create(ridgeline::Heightfield::create(d, v, m).value()).value();
}

}  // namespace

TEST(Game, TyreGripFollowsTheMaterial) {
  // A braked truck parked across a 25-degree slope (tan = 0.466): on grass (friction 1.1) it
  // holds; on snow (1.1 x 0.4 = 0.44 < 0.466) it slides down. Before materials were physical
  // both held.
  auto terrain = slope_terrain(std::tan(25.0 * M_PI / 180.0), 3);
  auto model = game::load_vehicle_model(std::string(RIDGELINE_GAME_ASSETS) + "/vehicles/truck.glb");
  ASSERT_TRUE(model.ok());
  auto settle = [&](double x) {
    auto physics = game::Physics::create(terrain).value();
    game::Vehicle v(*physics, game::params_from_model(*model, 3000), {x, 0, 64}, M_PI / 2);
    EXPECT_TRUE(v.place_on_surface(x, 64, M_PI / 2));
    v.controls = {0, 0, 1};
    for (int f = 0; f < 60; ++f) physics->step(1.0 / 60);  // settle on the suspension
    v.measure_contacts();
    const glm::dvec3 start = v.position();
    const std::uint8_t under = v.ground_material();
    for (int f = 0; f < 240; ++f) physics->step(1.0 / 60);
    return std::make_pair(glm::length(v.position() - start), under);
  };
  const auto [grass_m, grass_id] = settle(32);
  const auto [snow_m, snow_id] = settle(96);
  EXPECT_EQ(grass_id, 0);
  EXPECT_EQ(snow_id, 3);
  EXPECT_LT(grass_m, 0.3) << "a braked truck holds on grass";
  EXPECT_GT(snow_m, 2.0) << "and slides on snow";
  EXPECT_LT(game::material(4).friction, game::material(0).friction) << "mud is slippery too";
}

TEST(Game, VehiclesCollideInsteadOfPassingThrough) {
  auto g = make_game();
  // Two trucks 30 m apart on level ground north of the centre (72-75 m), driving at each other.
  // (South of the centre, at z = 1200, they met on a 16-degree hump, where with Bullet's 3D
  // contacts the one coming downhill rides up over the other's bevelled nose: real, but not what
  // this test is about.)
  auto a = g->spawn("truck", 1000, 1100, M_PI / 2, "a");
  auto b = g->spawn("truck", 1030, 1100, -M_PI / 2, "b");
  ASSERT_TRUE(a.ok() && b.ok());
  auto* ea = g->vehicle(*a);
  auto* eb = g->vehicle(*b);
  double worst_overlap = 0;
  bool touched = false;
  for (int f = 0; f < 360; ++f) {
    const double throttle = f < 200 ? 1.0 : 0.0;
    ea->body.controls = {throttle, 0, f < 200 ? 0.0 : 1.0};
    eb->body.controls = {throttle, 0, f < 200 ? 0.0 : 1.0};
    g->step();
    // Bullet's contacts between the two chassis: how deep they went into each other.
    if (g->physics().touching(ea->body.chassis(), eb->body.chassis())) touched = true;
    worst_overlap =
        std::max(worst_overlap, g->physics().penetration(ea->body.chassis(), eb->body.chassis()));
    // They never swap sides along x (passing through each other would).
    ASSERT_LT(ea->body.position().x, eb->body.position().x) << "frame " << f;
  }
  EXPECT_TRUE(touched) << "they met";
  EXPECT_LT(worst_overlap, 0.1) << "the bodies stay apart (a few centimetres of contact at most)";
  EXPECT_GE(ea->body.collisions, 1u);
  EXPECT_EQ(ea->body.collisions, eb->body.collisions);
  EXPECT_GE(g->contacts(), 0u);
  // Stable: braked and pressed together, they come to rest instead of jittering apart.
  EXPECT_LT(glm::length(ea->body.velocity()), 0.5);
  EXPECT_LT(glm::length(eb->body.velocity()), 0.5);
  for (const auto& w : ea->body.wheels()) EXPECT_TRUE(w.contact) << "no wheel lifted off";
}

TEST(Game, AnOverlapIsPushedApartAlongTheShortestAxis) {
  // Two buggies placed overlapping by 0.3 m side by side: Bullet pushes them apart sideways (the
  // shortest way out), not along their length.
  auto g = make_game();
  auto a = g->spawn("buggy", 1024, 1024, 0, "a");
  ASSERT_TRUE(a.ok());
  const game::VehicleParams& p = g->vehicle(*a)->body.params();
  const double width = p.chassis_max.x - p.chassis_min.x;
  auto b = g->spawn("buggy", 1024 + width - 0.3, 1024, 0, "b");
  ASSERT_TRUE(b.ok());
  auto* ea = g->vehicle(*a);
  auto* eb = g->vehicle(*b);
  const glm::dvec3 a0 = ea->body.position(), b0 = eb->body.position();
  for (auto* e : {ea, eb}) e->body.controls = {0, 0, 1};
  for (int f = 0; f < 30; ++f) g->step();
  const glm::dvec3 da = ea->body.position() - a0, db = eb->body.position() - b0;
  EXPECT_GT((eb->body.position().x - ea->body.position().x) - (b0.x - a0.x), 0.25)
      << "pushed apart along x";
  EXPECT_LT(std::abs(da.z), 0.1);
  EXPECT_LT(std::abs(db.z), 0.1);
  EXPECT_GE(ea->body.collisions, 1u);
}

TEST(Game, ScriptOutputReachesTheConsoleInEveryMode) {
  // game.log printed nothing headless or offscreen (it went to the core's log at info level).
  // The game's own console gets every line and every error.
  std::vector<std::string> lines;
  GameOptions o;
  o.assets_dir = RIDGELINE_GAME_ASSETS;
  o.scripts_dir = kScripts;
  o.tessellate = false;
  o.console = [&lines](const std::string& l) { lines.push_back(l); };
  auto g = Game::create(o).value();
  const auto path = write_script("hello.lua",
                                 "game.log('hello', 42)\n"
                                 "game.on('tick', function() error('boom') end)\n");
  ASSERT_TRUE(g->load_script(path).ok());
  g->step();
  auto has = [&](const std::string& needle) {
    for (const auto& l : lines)
      if (l.find(needle) != std::string::npos) return true;
    return false;
  };
  EXPECT_TRUE(has("[hello.lua] hello 42"));
  EXPECT_TRUE(has("loaded hello.lua"));
  EXPECT_TRUE(has("script error in hello.lua (frame 0)"));
  EXPECT_TRUE(has("boom"));
  // A script file that does not exist is an error (main turns it into exit code 1).
  EXPECT_FALSE(g->load_script(kTmp + "/missing.lua").ok());
  EXPECT_TRUE(has("missing.lua': no such file"));
}

TEST(Game, ArgumentErrorsUseTheBindingsMessages) {
  // The game's argument checks are the binding's (ridgeline/lua/check.h): one message for one
  // mistake (the copies had drifted: "finite number expected" without the value).
  auto g = make_game();
  auto expect_error = [&](const std::string& code, const char* needle) {
    const auto st = g->host().run(code, "api");
    ASSERT_FALSE(st.ok()) << code;
    EXPECT_NE(st.message().find(needle), std::string::npos) << st.message();
  };
  const std::string v = "local v = assert(game.spawn{x=500, z=500}); ";
  expect_error(v + "v:place(0/0, 1)", "finite number expected, got nan");
  expect_error(v + "v:place(1, 1/0)", "finite number expected, got inf");
  expect_error(v + "v:follow{waypoints={{1, 2}}, speed='fast'}",
               "field 'speed': number expected, got string");
  expect_error(v + "v:follow{waypoints={{1, 2}}, loop=1}",
               "field 'loop': boolean expected, got number");
  expect_error("game.spawn{x=1, z=1, model=3}", "field 'model': string expected, got number");
  expect_error("game.camera{eye={1, 2}}", "field 'eye': array of 3 numbers expected");
  expect_error("game.set_budget{controller='yes'}", "field 'controller': boolean expected");
  expect_error("game.set_budget{render_scale=0.1}", "'render_scale': 0.25 .. 1");
  // Below the views' root triangles (2 per patch: 2,048 with the default 64 m patches).
  const std::string roots =
      "field 'triangles': " + std::to_string(g->root_triangles()) + " .. 4000000 expected";
  EXPECT_EQ(g->root_triangles(), 2048u);
  expect_error("game.set_budget{triangles=1000}", roots.c_str());
  // The same mistake in the binding's own functions gives the same text.
  expect_error("game.terrain:height(0/0, 1)", "finite number expected, got nan");
}

TEST(Game, RenderScaleThroughTheBudget) {
  auto g = make_game(true);
  ASSERT_TRUE(g->host()
                  .run("game.set_budget{controller=true, target_ms=20, min=1, max=8, "
                       "min_scale=0.5, scale_from=3}",
                       "b")
                  .ok());
  for (int i = 0; i < 240; ++i) g->update_view(80);  // far too slow: every lever moves
  EXPECT_EQ(g->threshold(), 8.0);
  EXPECT_EQ(g->render_scale(), 0.5);
  EXPECT_EQ(g->last_view_frame().render_scale, 0.5);
  ASSERT_TRUE(g->host()
                  .run("local b = game.budget(); assert(b.render_scale == 0.5, "
                       "b.render_scale); assert(b.min_scale == 0.5 and b.scale_from == 3)",
                       "check")
                  .ok());
  ASSERT_TRUE(g->host()
                  .run("game.set_budget{controller=false, threshold=2, render_scale=0.75}", "fixed")
                  .ok());
  for (int i = 0; i < 30; ++i) g->update_view(80);
  EXPECT_EQ(g->threshold(), 2.0);
  EXPECT_EQ(g->render_scale(), 0.75);
}

TEST(Game, TimesOfScriptsAndPhysicsAreMeasured) {
  auto g = make_game();
  ASSERT_TRUE(g->load_script(kScripts + "/default.lua").ok());
  const auto path = write_script("burn.lua", "game.on('tick', function() game.burn_ms(2) end)\n");
  ASSERT_TRUE(g->load_script(path).ok());
  (void)g->take_step_times();
  for (int i = 0; i < 10; ++i) g->step();
  const game::StepTimes t = g->take_step_times();
  EXPECT_GE(t.scripts_ms, 20.0) << "10 steps with 2 ms of script work each";
  EXPECT_GT(t.physics_ms, 0.0);
  EXPECT_EQ(g->take_step_times().scripts_ms, 0.0) << "taken";
}

// Triangles of the default scenario's view after 30 updates at a fixed 6 px (no budgets).
std::uint32_t triangles_of_a_fresh_view_at_6px() {
  auto h = make_game(true);
  EXPECT_TRUE(h->load_script(kScripts + "/default.lua").ok());
  EXPECT_TRUE(h->host()
                  .run("game.set_budget{controller=false, threshold=6, triangles=400000, "
                       "tess_ms=0}",
                       "b")
                  .ok());
  game::ViewFrame f;
  for (int i = 0; i < 30; ++i) f = h->update_view(0);
  return f.stats.triangles;
}

TEST(Game, ASlowlyRisingThresholdStillCoarsensTheMesh) {
  // The controller raises the threshold by well under 1 % per frame. The old ROAM core re-keyed
  // its merges only for a larger rise and kept the triangles of the lower threshold (40,000 at
  // 6 px instead of 13,000) unless the game handed it the threshold on a 2 % grid; the new core
  // re-tests its whole front every update and needs no help.
  auto g = make_game(true);
  ASSERT_TRUE(g->load_script(kScripts + "/default.lua").ok());
  ASSERT_TRUE(g->host()
                  .run("game.set_budget{controller=false, threshold=2, triangles=400000, "
                       "tess_ms=0}",
                       "b")
                  .ok());
  for (int i = 0; i < 30; ++i) g->update_view(0);
  const std::uint32_t fixed6 = triangles_of_a_fresh_view_at_6px();
  // The controller on, fed frames a little too slow: it creeps from 2 px towards its maximum.
  ASSERT_TRUE(g->host()
                  .run("game.set_budget{controller=true, threshold=2, min=1, max=6, "
                       "target_ms=33}",
                       "b")
                  .ok());
  game::ViewFrame f;
  // 10 % too slow: 2 % outside the dead band, about 0.2 % per frame.
  for (int i = 0; i < 3000 && g->threshold() < 6; ++i) f = g->update_view(33 * 1.1);
  for (int i = 0; i < 30; ++i) f = g->update_view(33 * 1.1);
  EXPECT_NEAR(f.threshold, 6.0, 0.13);
  EXPECT_LT(f.stats.triangles, fixed6 * 1.1) << "the mesh coarsened as the threshold rose";
}

TEST(Game, AFallingThresholdDoesNotOverRefineTheMesh) {
  // The controller lowers the threshold step by step after a load. The old ROAM core kept split
  // keys sized for the higher threshold and over-refined (59,000 triangles at 6 px instead of
  // 13,000) unless the game made it re-key on every step down (a far-plane nudge); the new core
  // re-tests its whole front every update and needs no help.
  const std::uint32_t fixed6 = triangles_of_a_fresh_view_at_6px();
  auto g = make_game(true);
  ASSERT_TRUE(g->load_script(kScripts + "/default.lua").ok());
  ASSERT_TRUE(g->host()
                  .run("game.set_budget{controller=true, threshold=12, min=6, max=12, "
                       "triangles=400000, tess_ms=0, target_ms=33}",
                       "b")
                  .ok());
  game::ViewFrame f;
  // Frames 15 % faster than the target: the threshold falls by about 0.4 % per frame.
  for (int i = 0; i < 3000 && g->threshold() > 6; ++i) f = g->update_view(33 * 0.85);
  for (int i = 0; i < 30; ++i) f = g->update_view(33 * 0.85);
  EXPECT_NEAR(f.threshold, 6.0, 0.13);
  EXPECT_LT(f.stats.triangles, fixed6 * 1.15) << "fixed 6 px: " << fixed6;
}
