// The sample game's simulation: fixed steps, vehicles, cameras, the budget controller, scripts.
#include "game.h"

#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <lua.hpp>
#include <sstream>

#include "ridgeline/edit.h"
#include "ridgeline/io.h"
#include "ridgeline/world_file.h"
#include "ridgeline/bench/clock.h"

namespace game {

using ridgeline::Error;
using ridgeline::Result;
using ridgeline::Status;

const char* to_string(CameraMode mode) noexcept {
  switch (mode) {
    case CameraMode::kFree:
      return "free";
    case CameraMode::kFollow:
      return "follow";
    default:
      return "map";
  }
}

ridgeline::DetailParams default_world_detail() {
  ridgeline::DetailParams d;
  d.levels = 1;       // 2 m stored spacing -> 1 m finest spacing
  d.amplitude = 0.2;  // first octave, metres (0.1 x the stored spacing)
  d.gain = 0.5;
  d.seed = 17;
  return d;
}

Game::~Game() {
  scripts_.reset();  // Lua first: its userdata refer to the game
}

Result<std::unique_ptr<Game>> Game::create(const GameOptions& options) {
  std::unique_ptr<Game> g(new Game());
  g->options_ = options;
  if (!(options.dt > 0 && options.dt <= 0.1))
    return Error{"game: time step " + std::to_string(options.dt) + " s; need 0 < dt <= 0.1"};
  if (!options.world_path.empty()) {
    // A baked world: paged in on two workers; its own placement and heights, no detail.
    if (options.detail.levels > 0)
      return Error{"game: procedural detail over a baked world is not supported (--detail-levels 0)"};
    auto source = ridgeline::io::open_world(options.world_path);
    if (!source) return Error{"game: " + source.error().message};
    ridgeline::WorldCacheDesc wc;
    wc.budget_bytes = options.world_cache_bytes;
    auto t = ridgeline::Terrain::open(std::move(*source), wc);
    if (!t) return Error{"game: " + t.error().message};
    g->terrain_ = std::move(*t);
    return finish_create(std::move(g), options);
  }
  Result<ridgeline::Heightfield> hf = Error{""};
  if (!options.heightmap_path.empty()) {
    ridgeline::io::LoadOptions lo;
    lo.placement = options.heightmap_placement;
    hf = ridgeline::io::load_heightmap(options.heightmap_path, lo);
    if (!hf) return Error{"game: " + hf.error().message};
  } else {
    hf = ridgeline::make_default_heightfield();
    if (!hf) return Error{hf.error().message};
  }
  if (options.detail.levels > 0) {
    ridgeline::DetailCacheDesc cd;
    cd.worker_threads = options.detail_workers;
    cd.budget_bytes = options.detail_budget_bytes;
    auto t = ridgeline::Terrain::create(std::move(*hf), options.detail, cd);
    if (!t) return Error{"game: " + t.error().message};
    g->terrain_ = std::move(*t);
    ridgeline::DetailViewRule rule;
    rule.pixels = options.detail_stream_pixels;
    auto stream = ridgeline::DetailStream::create(g->terrain_->surface(), *g->terrain_->surface().detail_cache(), rule);
    if (!stream) return Error{"game: " + stream.error().message};
    g->stream_.emplace(std::move(*stream));
  } else {
    auto t = ridgeline::Terrain::create(std::move(*hf), ridgeline::DetailParams{},
                                        ridgeline::DetailCacheDesc{});
    if (!t) return Error{"game: " + t.error().message};
    g->terrain_ = std::move(*t);
  }
  return finish_create(std::move(g), options);
}

// The parts after the terrain: physics, the landscape and views, the controller, the vehicle
// models and the scripts.
Result<std::unique_ptr<Game>> Game::finish_create(std::unique_ptr<Game> g,
                                                  const GameOptions& options) {
  auto physics = Physics::create(g->terrain_);
  if (!physics) return Error{physics.error().message};
  g->physics_ = std::move(*physics);
  // A baked world's coarse bounds were made for one patch exponent: its own (0) is used.
  auto land = ridgeline::Landscape::create(
      g->terrain_, {.patch_exponent = g->terrain_->paged() ? 0u : options.patch_exponent});
  if (!land) return Error{land.error().message};
  g->landscape_ = *land;
  g->max_triangles_ = options.max_triangles;
  g->tess_budget_ms_ = options.tessellation_budget_ms;
  for (auto& v : g->views_) {
    ridgeline::RoamSettings s;
    s.threshold = 2;
    s.max_triangles = options.max_triangles;
    s.budget_ms = options.tessellation_budget_ms;
    auto view = ridgeline::RoamView::create(g->landscape_, s);
    if (!view) return Error{view.error().message};
    v = std::move(*view);
  }
  auto ctl = ridgeline::BudgetController::create(options.budget);
  if (!ctl) return Error{ctl.error().message};
  g->controller_ = *ctl;
  g->threshold_ = options.fixed_threshold > 0 ? options.fixed_threshold : ctl->threshold();
  g->render_scale_ = options.fixed_threshold > 0 && options.fixed_render_scale > 0
                         ? options.fixed_render_scale
                         : ctl->render_scale();
  g->controller_on_ = options.fixed_threshold <= 0;
  for (const char* name : {"truck", "buggy"}) {
    const std::string path = options.assets_dir + "/vehicles/" + name + ".glb";
    auto m = load_vehicle_model(path);
    if (!m) return Error{m.error().message};
    g->models_.emplace(name, std::move(*m));
  }
  ridgeline::lua::HostOptions ho;
  ho.instruction_limit = options.instruction_limit;
  ho.data_root = options.scripts_dir;
  auto runner = ScriptRunner::create(*g, ho, options.console);
  if (!runner) return Error{runner.error().message};
  g->scripts_ = std::move(*runner);
  return g;
}

ridgeline::Result<int> Game::spawn(const std::string& model, double x, double z, double heading,
                                   const std::string& name) {
  const VehicleModel* m = this->model(model);
  if (m == nullptr) return Error{"spawn: unknown model '" + model + "' (truck, buggy)"};
  const auto h = terrain_->height(x, z);
  if (!h)
    return Error{"spawn: (" + std::to_string(x) + ", " + std::to_string(z) +
                 ") is off the terrain"};
  if (vehicles_.size() >= 64) return Error{"spawn: 64 vehicles at most"};
  VehicleParams p = params_from_model(*m, model == "truck" ? 3000.0 : 1200.0);
  if (model == "buggy") p.max_speed = 30;
  const double start_y = *h + p.com_in_model.y + p.rest_length * 0.5;
  VehicleEntry e{next_vehicle_id_++,
                 name.empty() ? model : name,
                 model,
                 Vehicle(*physics_, p, {x, start_y, z}, heading),
                 {},
                 0};
  e.body.place_on_surface(x, z, heading);
  const int id = e.id;
  // The chassis carries its vehicle's id: contacts name the vehicles they involve.
  e.body.chassis()->setUserIndex(id);
  e.body.chassis()->setUserIndex2(1);
  vehicles_.emplace(id, std::move(e));
  return id;
}

VehicleEntry* Game::vehicle(int id) {
  auto it = vehicles_.find(id);
  return it == vehicles_.end() ? nullptr : &it->second;
}

bool Game::remove_vehicle(int id) {
  if (vehicles_.erase(id) == 0) return false;
  for (auto it = touching_.begin(); it != touching_.end();)
    it = it->first.first == id || it->first.second == id ? touching_.erase(it) : std::next(it);
  for (auto it = body_touching_.begin(); it != body_touching_.end();)
    it = it->first.first == id ? body_touching_.erase(it) : std::next(it);
  return true;
}

Result<int> Game::spawn_body(const BodySpec& spec) {
  if (!terrain_->height(spec.position.x, spec.position.z))
    return Error{"spawn_body: (" + std::to_string(spec.position.x) + ", " +
                 std::to_string(spec.position.z) + ") is off the terrain"};
  while (bodies_.size() >= kMaxBodies) remove_body(bodies_.begin()->first);  // the oldest
  const int id = next_body_id_++;
  LooseBody b(*physics_, id, spec);
  b.spawned_frame = frame_;
  auto* rb = const_cast<btRigidBody*>(b.rigid_body());
  rb->setUserIndex(id);
  rb->setUserIndex2(2);
  bodies_.emplace(id, std::move(b));
  return id;
}

LooseBody* Game::body(int id) {
  auto it = bodies_.find(id);
  return it == bodies_.end() ? nullptr : &it->second;
}

bool Game::remove_body(int id) {
  if (bodies_.erase(id) == 0) return false;
  for (auto it = body_touching_.begin(); it != body_touching_.end();)
    it = it->first.second == id ? body_touching_.erase(it) : std::next(it);
  return true;
}

const VehicleModel* Game::model(const std::string& name) const {
  auto it = models_.find(name);
  return it == models_.end() ? nullptr : &it->second;
}

std::vector<std::string> Game::model_names() const {
  std::vector<std::string> out;
  for (const auto& [k, v] : models_) out.push_back(k);
  return out;
}

void Game::clamp_to_terrain(VehicleEntry& e) {
  const ridgeline::WorldInfo& hf = terrain_->info();
  const double x0 = hf.origin_x + 3, z0 = hf.origin_z + 3;
  const double x1 = hf.origin_x + hf.extent_x() - 3, z1 = hf.origin_z + hf.extent_z() - 3;
  const glm::dvec3 p = e.body.position();
  if (p.x < x0 || p.x > x1 || p.z < z0 || p.z > z1) {
    // The edge of the world: the vehicle is stopped and put back inside.
    const double x = std::clamp(p.x, x0, x1), z = std::clamp(p.z, z0, z1);
    e.body.place_on_surface(x, z, e.body.heading());
  }
}

void Game::step() {
  burned_ms_ = 0;
  const double dt = options_.dt;
  const double scripts_before = scripts_->take_script_ms();
  // Craters made since the last step (from scripts: handlers do not nest inside a script call).
  for (; craters_emitted_ < craters_.size(); ++craters_emitted_) {
    const CraterRecord& c = craters_[craters_emitted_];
    double a[4] = {c.x, c.z, c.radius, c.depth};
    emit(
        "crater",
        [](lua_State* L, void* u) -> int {
          for (int i = 0; i < 4; ++i) lua_pushnumber(L, static_cast<const double*>(u)[i]);
          return 4;
        },
        a);
  }
  double args[2] = {dt, time()};
  emit(
      "tick",
      [](lua_State* L, void* u) -> int {
        const double* a = static_cast<const double*>(u);
        lua_pushnumber(L, a[0]);
        lua_pushnumber(L, a[1]);
        return 2;
      },
      args);
  const auto t_physics = ridgeline::bench::Clock::now();
  double waypoint_scripts_ms = 0;
  for (auto& [id, e] : vehicles_) {
    if (e.autopilot.drive(e.body)) {
      struct Arg {
        int id;
        std::size_t index;
      } arg{id, e.autopilot.next};
      const auto t0 = ridgeline::bench::Clock::now();
      emit(
          "waypoint",
          [](lua_State* L, void* u) -> int {
            const auto* a = static_cast<const Arg*>(u);
            lua_pushinteger(L, a->id);
            lua_pushinteger(L, static_cast<lua_Integer>(a->index) + 1);
            return 2;
          },
          &arg);
      waypoint_scripts_ms += ridgeline::bench::ms_since(t0);
    }
  }
  follow_terrain_edits();
  std::map<int, glm::dvec3> before;
  for (auto& [id, e] : vehicles_) {
    before[id] = e.body.position();
    pre_velocity_[{1, id}] = e.body.velocity();
  }
  for (auto& [id, b] : bodies_)
    if (!b.sleeping()) pre_velocity_[{2, id}] = b.velocity();
  physics_->step(dt);
  for (auto& [id, e] : vehicles_) {
    clamp_to_terrain(e);
    e.body.measure_contacts();
    const glm::dvec3 d = e.body.position() - before[id];
    e.distance_m += std::hypot(d.x, d.z);
  }
  count_touches();
  tidy_bodies();
  step_times_.physics_ms += ridgeline::bench::ms_since(t_physics) - waypoint_scripts_ms;
  // A body that started touching a vehicle: the "hit" event (after the physics, not inside it).
  for (const Hit& h : hits_) {
    emit(
        "hit",
        [](lua_State* L, void* u) -> int {
          const auto* a = static_cast<const Hit*>(u);
          lua_pushinteger(L, a->vehicle);
          lua_pushinteger(L, a->body);
          lua_pushnumber(L, a->speed);
          return 3;
        },
        const_cast<Hit*>(&h));
  }
  hits_.clear();
  step_times_.scripts_ms += scripts_->take_script_ms() + scripts_before;
  ++frame_;
}

StepTimes Game::take_step_times() noexcept {
  const StepTimes t = step_times_;
  step_times_ = {};
  return t;
}

Result<std::size_t> Game::crater(double x, double z, double radius, double depth) {
  if (!std::isfinite(x) || !std::isfinite(z) || !(radius > 0 && radius <= 200) ||
      !(depth > 0 && depth <= 100))
    return Error{"crater: radius in (0, 200] and depth in (0, 100] metres expected"};
  ridgeline::Edit edit;
  edit.brush = ridgeline::Brush::kCrater;
  edit.x = x;
  edit.z = z;
  edit.radius = radius;
  edit.depth = depth;
  edit.rim = 0.15;
  edit.strength = 1;
  auto r = terrain_->apply_edit(edit);
  if (!r) return Error{r.error().message};
  // The vehicles follow at the next step, through the change log like any other edit.
  craters_.push_back({x, z, radius, depth, frame_});
  return r->samples_changed;
}

void Game::count_touches() {
  // The pairs touching now, from the world's contact manifolds. A pair that had not touched for
  // kTouchGap steps counts a collision (vehicles) or a hit (a body on a vehicle): a boulder that
  // bounces off a truck twice in a moment hits it once.
  constexpr std::uint64_t kTouchGap = 30;
  std::map<std::pair<int, int>, bool> vv, vb;
  btDispatcher* d = physics_->world().getDispatcher();
  for (int k = 0; k < d->getNumManifolds(); ++k) {
    const btPersistentManifold* m = d->getManifoldByIndexInternal(k);
    bool touch = false;
    for (int c = 0; c < m->getNumContacts() && !touch; ++c)
      touch = m->getContactPoint(c).getDistance() < 0.01f;
    if (!touch) continue;
    const btCollisionObject* a = m->getBody0();
    const btCollisionObject* b = m->getBody1();
    if (a->getUserIndex2() == 2 && b->getUserIndex2() == 1) std::swap(a, b);
    if (a->getUserIndex2() != 1) continue;  // neither is a vehicle
    if (b->getUserIndex2() == 1)
      vv[{std::min(a->getUserIndex(), b->getUserIndex()),
          std::max(a->getUserIndex(), b->getUserIndex())}] = true;
    else if (b->getUserIndex2() == 2)
      vb[{a->getUserIndex(), b->getUserIndex()}] = true;
  }
  const auto fresh = [&](std::map<std::pair<int, int>, std::uint64_t>& last,
                         const std::pair<int, int>& key) {
    auto it = last.find(key);
    const bool is_new = it == last.end() || frame_ > it->second + kTouchGap;
    last[key] = frame_;
    return is_new;
  };
  for (const auto& [key, t] : vv) {
    if (!fresh(touching_, key)) continue;
    for (int id : {key.first, key.second})
      if (VehicleEntry* e = vehicle(id)) ++e->body.collisions;
  }
  for (const auto& [key, t] : vb) {
    if (!fresh(body_touching_, key)) continue;
    VehicleEntry* e = vehicle(key.first);
    LooseBody* b = body(key.second);
    if (e == nullptr || b == nullptr) continue;
    ++e->body.body_hits;
    ++b->vehicle_hits;
    // The speed at which they met: the velocities before the step (the impact changed them).
    const auto vel = [&](int kind, int id, const glm::dvec3& now) {
      auto it = pre_velocity_.find({kind, id});
      return it == pre_velocity_.end() ? now : it->second;
    };
    hits_.push_back(
        {key.first, key.second,
         glm::length(vel(2, key.second, b->velocity()) - vel(1, key.first, e->body.velocity()))});
  }
  for (auto* last : {&touching_, &body_touching_})
    for (auto it = last->begin(); it != last->end();)
      it = frame_ > it->second + kTouchGap ? last->erase(it) : std::next(it);
  contacts_ = vv.size();
  body_contacts_ = vb.size();
  pre_velocity_.clear();
}

void Game::tidy_bodies() {
  // A body that rolled off the terrain's edge, or fell through it (it cannot, but a game does not
  // keep what it could not see), is removed.
  std::vector<int> gone;
  for (const auto& [id, b] : bodies_) {
    const glm::dvec3 p = b.position();
    const auto h = terrain_->height(p.x, p.z);
    if (!h || p.y < *h - 20 || !std::isfinite(p.y)) gone.push_back(id);
  }
  for (int id : gone) remove_body(id);
}

void Game::follow_terrain_edits() {
  const ridgeline::TerrainChanges c = terrain_->changes_since(seen_edit_version_);
  seen_edit_version_ = c.version;
  if (c.empty()) return;
  for (auto& [id, e] : vehicles_) {
    const glm::dvec3 p = e.body.position();
    const double m = 6;  // a vehicle's half-length: bodies overlapping a box count
    for (const ridgeline::TerrainChange& ch : c.changes) {
      if (p.x >= ch.box.min.x - m && p.x <= ch.box.max.x + m && p.z >= ch.box.min.z - m &&
          p.z <= ch.box.max.z + m && p.y >= ch.box.min.y - m && p.y <= ch.box.max.y + m) {
        e.body.follow_ground();  // once: it compares with the ground it last saw
        break;
      }
    }
  }
}

ridgeline::Camera Game::camera() const {
  ridgeline::Camera c;
  c.viewport = options_.viewport;
  c.fov_y_deg = 60;
  c.near_m = 0.5;
  c.far_m = 6000;
  switch (rig_.mode) {
    case CameraMode::kFree: {
      c.eye = rig_.free_eye;
      const double cp = std::cos(rig_.free_pitch);
      c.target = c.eye + glm::dvec3(std::sin(rig_.free_yaw) * cp, std::sin(rig_.free_pitch),
                                    std::cos(rig_.free_yaw) * cp);
      break;
    }
    case CameraMode::kFollow: {
      const VehicleEntry* e = nullptr;
      auto it = vehicles_.find(rig_.follow_vehicle);
      if (it != vehicles_.end())
        e = &it->second;
      else if (!vehicles_.empty())
        e = &vehicles_.begin()->second;
      if (e == nullptr) {
        c.eye = rig_.free_eye;
        c.target = c.eye + glm::dvec3(0.5, -0.3, 0.5);
        break;
      }
      const glm::dvec3 p = e->body.position();
      const double h = e->body.heading();
      glm::dvec3 eye = p - glm::dvec3(std::sin(h), 0, std::cos(h)) * rig_.follow_distance;
      // At the vehicle's height plus the lift, but never closer than 2.5 m to the ground under
      // the eye (going downhill the ground behind is higher: the camera rises over it).
      const double ground = terrain_->height(eye.x, eye.z).value_or(p.y);
      eye.y = std::max(p.y + rig_.follow_height, ground + 2.5);
      c.eye = eye;
      c.target =
          p + glm::dvec3(std::sin(h), 0, std::cos(h)) * rig_.follow_ahead + glm::dvec3(0, 1.5, 0);
      break;
    }
    case CameraMode::kMap:
      c.eye = {rig_.map_centre.x, rig_.map_height, rig_.map_centre.y};
      c.target = {rig_.map_centre.x, 0, rig_.map_centre.y};
      c.up = {0, 0, 1};
      c.far_m = rig_.map_height + 2000;
      break;
  }
  return c;
}

ViewFrame Game::update_view(double frame_ms) {
  if (controller_on_ && frame_ms > 0) {
    threshold_ = controller_.update(frame_ms, frame_ms / 1000.0);
    render_scale_ = controller_.render_scale();
  }
  ViewFrame out;
  // The controller's threshold as it is: the view re-tests its whole split and merge front every
  // update, so any change, however small, moves the mesh both ways.
  const double view_threshold = threshold_;
  out.threshold = view_threshold;
  out.render_scale = render_scale_;
  if (!options_.tessellate) return last_view_ = out;
  ridgeline::RoamView& v = active_view();
  ridgeline::RoamSettings s = v.settings();
  s.threshold = view_threshold;
  s.max_triangles = max_triangles_;
  s.budget_ms = tess_budget_ms_;
  if (Status st = v.set_settings(s); !st) scripts_->log("view settings: " + st.message());
  const ridgeline::Camera cam = camera();
  const int vi = int(rig_.mode);
  if (stream_) {  // tiles for where the camera is going, ahead of the view's own requests
    auto f = stream_->frame(cam);
    if (f) detail_frame_ = *f;
  }
  auto r = v.update(cam);
  ridgeline::DetailCache* cache = terrain_->surface().detail_cache();
  // Prefill: wait for the tiles the splits asked for and go on refining, so the mesh does not
  // depend on when tiles arrive (bounded: each round completes the chains that waited).
  double tess_ms = r ? r->update_ms : 0;
  for (int round = 0; options_.prefill_detail && cache != nullptr && r && round < 64 &&
                      r->stop != ridgeline::StopReason::kTriangleBudget &&
                      (r->pending_splits > 0 || r->stop != ridgeline::StopReason::kConverged);
       ++round) {
    (void)cache->wait_idle(30.0);
    auto again = v.update(cam);
    if (!again) break;
    tess_ms += again->update_ms;
    r = again;
  }
  if (r) r->update_ms = tess_ms;
  if (r) {
    out.stats = *r;
    out.updated = true;
    morph_threshold_[vi] = r->morph_threshold;
  } else {
    scripts_->log("view update: " + r.error().message);
  }
  return last_view_ = out;
}

double Game::morph_threshold() const noexcept {
  const int vi = int(rig_.mode);
  return morph_threshold_[vi] > 0 ? morph_threshold_[vi] : views_[vi]->settings().threshold;
}

BudgetSettings Game::budget() const noexcept {
  return {controller_on_, threshold_, render_scale_, max_triangles_, tess_budget_ms_};
}

void Game::set_budget(const BudgetSettings& b) {
  controller_on_ = b.controller;
  threshold_ = b.threshold;
  render_scale_ = b.render_scale;
  max_triangles_ = b.max_triangles;
  tess_budget_ms_ = b.tessellation_ms;
}

std::optional<ridgeline::DetailCacheStats> Game::detail_stats() const {
  if (const ridgeline::DetailCache* c = terrain_->surface().detail_cache()) return c->stats();
  return std::nullopt;
}

}  // namespace game
