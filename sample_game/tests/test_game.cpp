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
  for (const char* s : {"default.lua", "artillery.lua", "budget.lua"})
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
  const auto runtime = write_script(
      "bad_runtime.lua", "game.on('tick', function(dt, t) if t > 0.1 then local x = nil; "
                         "return x.field end end)\n");
  const auto loop = write_script("bad_loop.lua",
                                 "game.on('tick', function() while true do end end)\n");
  const auto good = write_script("good.lua", "ticks = 0\ngame.on('tick', function() ticks = "
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
  const auto path = write_script("reload.lua", "value = 1\ngame.on('tick', function() "
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
  std::filesystem::last_write_time(path, std::filesystem::file_time_type::clock::now() +
                                             std::chrono::seconds(1));
  EXPECT_EQ(g->reload_changed_scripts(), 1);
  g->step();
  ASSERT_TRUE(g->host().run("assert(value == 3 and hits == 100, 'value ' .. tostring(value) .. "
                            "', hits ' .. tostring(hits))", "check").ok());
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
  expect_error("game.spawn{model='tank', x=1, z=1} error(select(2, game.spawn{model='tank', x=1, z=1}))",
               "unknown model 'tank'");
  expect_error("error(select(2, game.spawn{x=-50, z=1}))", "off the terrain");
  expect_error("game.spawn{x=1}", "fields 'x' and 'z'");
  expect_error("game.spawn{x=1, z=2, colour='red'}", "unknown field 'colour'");
  expect_error("local v = game.spawn{x=500, z=500}; v:set_controls{throttle=2}",
               "'throttle': -1 .. 1");
  expect_error("local v = game.spawn{x=500, z=500}; v:follow{waypoints={{1, 'a'}}}",
               "waypoint 1");
  expect_error("local v = game.spawn{x=500, z=500}; v:remove(); v:position()",
               "removed vehicle");
  expect_error("game.on('explode', print)", "invalid option 'explode'");
  expect_error("game.set_budget{threshold=-1}", "'threshold': 0.25 .. 256");
  expect_error("game.set_budget{min=8, max=2}", "0.25 <= min <= max");
  expect_error("game.burn_ms(1000)", "0 .. 100 milliseconds");
  expect_error("game.camera{mode='orbit'}", "'free', 'follow' or 'map' expected, got 'orbit'");
  expect_error("game.crater{x=1, z=1, radius=0}", "'radius'");
  // Nothing half-applied: the budget is unchanged after the failed calls.
  EXPECT_DOUBLE_EQ(g->controller().desc().min_threshold, 1.0);
  EXPECT_TRUE(g->controller_on());
  // The terrain the scripts see is the game's.
  ASSERT_TRUE(g->host().run("local h = game.terrain:height(1024, 1024); "
                            "assert(math.abs(h - " + std::to_string(*g->terrain().height(1024, 1024)) +
                            ") < 1e-6)", "terrain").ok());
}

TEST(Game, SetBudgetAndTheController) {
  auto g = make_game(true);
  ASSERT_TRUE(g->host().run("game.set_budget{controller=false, threshold=6, triangles=5000}",
                            "b").ok());
  EXPECT_FALSE(g->controller_on());
  EXPECT_EQ(g->threshold(), 6);
  auto f = g->update_view(50);
  EXPECT_EQ(f.threshold, 6) << "a fixed threshold ignores frame times";
  EXPECT_LE(f.stats.triangles, 5000u);
  ASSERT_TRUE(g->host().run("game.set_budget{controller=true, target_ms=20}", "b").ok());
  for (int i = 0; i < 60; ++i) f = g->update_view(60);
  EXPECT_GT(f.threshold, 6) << "slow frames raise the threshold";
}
