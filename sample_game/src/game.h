// Game: the sample game's simulation (terrain with procedural detail, vehicles, cameras,
// scripts, the LOD budget), with no GL: the window, offscreen and headless modes all drive this
// one class. Scripts see it through GameApi (game_api.h).
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "game_api.h"
#include "physics.h"
#include "ridgeline/budget_controller.h"
#include "ridgeline/camera.h"
#include "ridgeline/detail.h"
#include "ridgeline/detail_stream.h"
#include "ridgeline/landscape.h"
#include "ridgeline/roam_view.h"
#include "ridgeline/terrain.h"
#include "script_runner.h"
#include "vehicle.h"
#include "vehicle_model.h"

namespace game {

/// The default world's procedural detail (docs/game.md, "The world"): one level below the 2 m
/// stored spacing (1 m finest spacing) with a 0.2 m octave (0.1 x the base spacing).
ridgeline::DetailParams default_world_detail();

/// Settings from the command line (main.cpp) or a test.
struct GameOptions {
  std::string assets_dir;   ///< folder with vehicles/*.glb
  std::string scripts_dir;  ///< folder scripts may name relatively (game.load_script)
  double dt = 1.0 / 60.0;   ///< fixed simulation step, seconds
  glm::ivec2 viewport{1280, 720};
  /// > 0: the threshold stays at this value (the controller is off): reproducible pictures.
  double fixed_threshold = 0;
  /// > 0 (with fixed_threshold): the render scale stays at this value, else 1.
  double fixed_render_scale = 0;
  /// Target 33 ms; 30 warm-up frames: the game's first frames build every patch's mesh while
  /// the view refines from its roots under the tessellation budget (about 20 frames of 50-140
  /// ms in the default scenario), which must not steer the controller.
  ridgeline::BudgetControllerDesc budget{.warmup_frames = 30};
  std::uint32_t max_triangles = 60000;  ///< triangle budget of every view
  double tessellation_budget_ms = 8;    ///< time budget of one view update
  bool tessellate = true;  ///< update the active view each frame (off: pure simulation)
  std::uint64_t instruction_limit = 20'000'000;  ///< per script call (an infinite loop ends)
  /// ROAM patches of 2^k stored cells per side. 5 (64 m patches, 1,024 of them): the core patches
  /// meshes in place and the renderer uploads the dirty ranges, so the patch size no longer sets
  /// the upload cost (0.2-0.35 ms per frame for k = 4..6 at 2 px, 1280 x 720); k = 5 had the
  /// lowest game-thread CPU time and 6 % fewer triangles than k = 4 (docs/game.md, "Where the
  /// frame goes").
  std::uint32_t patch_exponent = 5;
  /// Procedural detail of the world (levels 0: none).
  ridgeline::DetailParams detail = default_world_detail();
  std::uint32_t detail_workers = 2;                          ///< the tile cache's worker threads
  std::size_t detail_budget_bytes = std::size_t{128} << 20;  ///< resident tiles, bytes
  /// Tiles streamed ahead of the view's own requests (DetailStream, the request rule of
  /// docs/detail.md): where a level's spacing projects to at least this many pixels.
  double detail_stream_pixels = 1.0;
  /// Each view update waits until every tile its splits asked for has arrived (and updates
  /// again): the mesh does not depend on when tiles arrive (render tests, reference pictures).
  bool prefill_detail = false;
  /// The world: empty for the built-in terrain; `world_path`, a baked world (ridge bake) paged in
  /// under `world_cache_bytes`; or `heightmap_path`, a heightmap file (any io::load_heightmap
  /// format) at `heightmap_placement` (spacing, height scale and offset, origin).
  std::string world_path;
  std::size_t world_cache_bytes = std::size_t{192} << 20;
  std::string heightmap_path;
  ridgeline::HeightfieldDesc heightmap_placement;
  /// Where script lines and errors go in every mode (null: stderr).
  std::function<void(const std::string&)> console;
};

/// Milliseconds one frame's simulation spent, by part.
struct StepTimes {
  double scripts_ms = 0;  ///< Lua chunks and handlers (game.burn_ms load included)
  /// Bullet and around it: autopilots, the edit sync, the world's step (vehicles, loose bodies,
  /// contacts), wheel states, collision counts.
  double physics_ms = 0;
};

/// Threading: one thread.
class Game final : public GameApi {
 public:
  static ridgeline::Result<std::unique_ptr<Game>> create(const GameOptions& options);
  ~Game() override;

  // ---- scripts (script_runner.h) ------------------------------------------------------------
  ScriptRunner& scripts() noexcept { return *scripts_; }
  const ScriptRunner& scripts() const noexcept { return *scripts_; }
  ridgeline::Status load_script(const std::string& path) { return scripts_->load(path); }
  int reload_changed_scripts() { return scripts_->reload_changed(); }
  int reload_all_scripts() { return scripts_->reload_all(); }
  const std::deque<ScriptError>& errors() const noexcept { return scripts_->errors(); }
  std::uint64_t error_count() const noexcept { return scripts_->error_count(); }
  ridgeline::lua::Host& host() noexcept { return scripts_->host(); }

  // ---- simulation ----------------------------------------------------------------------------
  /// One fixed step: scripts' tick handlers, autopilots, the vehicles' reaction to every terrain
  /// edit since the last step (from any brush, C++ or Lua, or a loaded edit state: the terrain's
  /// change log is polled here, and by the Bullet world's TerrainSync), the Bullet step
  /// (vehicles, loose bodies, their contacts), then wheel states and collision counts.
  void step();
  /// Times of the steps since the last call (a frame may take several steps), and resets them.
  StepTimes take_step_times() noexcept;
  /// Milliseconds of load scripts asked for in the last step with game.burn_ms (already spent).
  double burned_ms() const noexcept { return burned_ms_; }
  void set_input(const Input& in) noexcept { input_ = in; }
  void set_last_frame_ms(double ms) noexcept { last_frame_ms_ = ms; }
  std::map<int, VehicleEntry>& vehicles() noexcept { return vehicles_; }
  const VehicleModel* model(const std::string& name) const;
  const std::vector<CraterRecord>& craters() const noexcept { return craters_; }
  /// Vehicle-vehicle pairs touching after the last step.
  std::size_t contacts() const noexcept { return contacts_; }
  /// Loose body-vehicle pairs touching after the last step.
  std::size_t body_contacts() const noexcept { return body_contacts_; }
  /// The Bullet world (vehicles, loose bodies, the terrain shape).
  Physics& physics() noexcept { return *physics_; }
  const Physics& physics() const noexcept { return *physics_; }
  std::map<int, LooseBody>& bodies() noexcept { return bodies_; }

  // ---- views, cameras, budget ----------------------------------------------------------------
  /// Feeds the last frame's time to the controller (when on) and updates the active view (with
  /// prefill_detail: until no split waits for a tile).
  ViewFrame update_view(double frame_ms);
  ridgeline::RoamView& view(CameraMode mode) noexcept { return *views_[int(mode)]; }
  ridgeline::RoamView& active_view() noexcept { return view(rig_.mode); }
  /// The threshold the active view's mesh corresponds to (RoamStats::morph_threshold of its last
  /// update; its settings' threshold before any): what the renderer's geomorph uses.
  double morph_threshold() const noexcept;
  const ridgeline::BudgetController& controller() const noexcept { return controller_; }
  bool controller_on() const noexcept { return controller_on_; }
  void set_controller_on(bool on) noexcept { controller_on_ = on; }
  double threshold() const noexcept { return threshold_; }
  void set_threshold(double px) noexcept { threshold_ = px; }
  /// Fraction of the output resolution (per axis) the scene renders at.
  double render_scale() const noexcept { return render_scale_; }
  void set_render_scale(double s) noexcept { render_scale_ = s; }
  std::uint32_t max_triangles() const noexcept { return max_triangles_; }
  void set_max_triangles(std::uint32_t n) noexcept { max_triangles_ = n; }
  double tessellation_budget_ms() const noexcept { return tess_budget_ms_; }
  void set_tessellation_budget_ms(double ms) noexcept { tess_budget_ms_ = ms; }
  /// The tile cache's statistics (empty without detail).
  std::optional<ridgeline::DetailCacheStats> detail_stats() const;
  /// The streaming figures of the last frame (empty without detail).
  const std::optional<ridgeline::DetailFrameStats>& detail_frame() const noexcept {
    return detail_frame_;
  }

  const ridgeline::Terrain& terrain() const noexcept { return *terrain_; }
  const GameOptions& options() const noexcept { return options_; }

  // ---- GameApi (what scripts reach) -----------------------------------------------------------
  std::uint64_t frame() const noexcept override { return frame_; }
  double time() const noexcept override { return double(frame_) * options_.dt; }
  double dt() const noexcept override { return options_.dt; }
  const Input& input() const noexcept override { return input_; }
  double last_frame_ms() const noexcept override { return last_frame_ms_; }
  void add_burn(double ms) noexcept override { burned_ms_ += ms; }
  ridgeline::Result<int> spawn(const std::string& model, double x, double z, double heading,
                               const std::string& name) override;
  VehicleEntry* vehicle(int id) override;
  const std::map<int, VehicleEntry>& vehicles() const noexcept override { return vehicles_; }
  bool remove_vehicle(int id) override;
  std::vector<std::string> model_names() const override;
  ridgeline::Result<int> spawn_body(const BodySpec& spec) override;
  LooseBody* body(int id) override;
  const std::map<int, LooseBody>& bodies() const noexcept override { return bodies_; }
  bool remove_body(int id) override;
  const std::shared_ptr<ridgeline::Terrain>& terrain_ptr() const noexcept override {
    return terrain_;
  }
  /// Deforms the terrain with a crater (the edit layer); bodies inside the changed box are lifted
  /// out of the surface. Returns the number of lattice samples changed.
  ridgeline::Result<std::size_t> crater(double x, double z, double radius, double depth) override;
  std::size_t crater_count() const noexcept override { return craters_.size(); }
  CameraRig& rig() noexcept override { return rig_; }
  ridgeline::Camera camera() const override;
  ridgeline::BudgetController& controller() noexcept override { return controller_; }
  BudgetSettings budget() const noexcept override;
  void set_budget(const BudgetSettings& settings) override;
  const ViewFrame& last_view_frame() const noexcept override { return last_view_; }
  std::uint32_t root_triangles() const noexcept override { return 2 * landscape_->patch_count(); }

 private:
  static ridgeline::Result<std::unique_ptr<Game>> finish_create(std::unique_ptr<Game> g,
                                                                const GameOptions& options);
  Game() = default;
  void clamp_to_terrain(VehicleEntry& e);
  void emit(const char* event, int (*push)(lua_State*, void*), void* user) {
    scripts_->emit(event, push, user);
  }
  // Pulls the terrain's change log: vehicles near a changed box follow the new ground.
  void follow_terrain_edits();
  // Counts the vehicle-vehicle and vehicle-body touches of the last Bullet step.
  void count_touches();
  // Removes loose bodies that left the terrain or fell through it.
  void tidy_bodies();

  GameOptions options_;
  std::shared_ptr<ridgeline::Terrain> terrain_;
  std::unique_ptr<Physics> physics_;  // before the vehicles and bodies: destroyed after them
  std::shared_ptr<const ridgeline::Landscape> landscape_;
  std::unique_ptr<ridgeline::RoamView> views_[3];
  std::map<std::string, VehicleModel> models_;
  std::map<int, VehicleEntry> vehicles_;
  int next_vehicle_id_ = 1;
  std::vector<CraterRecord> craters_;
  std::size_t craters_emitted_ = 0;
  std::map<int, LooseBody> bodies_;
  int next_body_id_ = 1;
  // The step at which each vehicle pair, and each (vehicle, body) pair, last touched.
  std::map<std::pair<int, int>, std::uint64_t> touching_, body_touching_;
  std::size_t contacts_ = 0, body_contacts_ = 0;
  struct Hit {
    int vehicle, body;
    double speed;  // relative speed when they met (before the step), m/s
  };
  std::vector<Hit> hits_;  // new body-vehicle touches of this step, for the "hit" event
  // Velocities before this step's Bullet step, by (1 vehicle | 2 body, id): the hits' speeds.
  std::map<std::pair<int, int>, glm::dvec3> pre_velocity_;
  CameraRig rig_;
  ridgeline::BudgetController controller_ = ridgeline::BudgetController::create().value();
  bool controller_on_ = true;
  double threshold_ = 2;
  double render_scale_ = 1;
  std::uint32_t max_triangles_ = 60000;
  double tess_budget_ms_ = 8;
  ViewFrame last_view_;
  double morph_threshold_[3] = {0, 0, 0};  // per camera mode: its last morph_threshold
  std::optional<ridgeline::DetailStream> stream_;
  std::optional<ridgeline::DetailFrameStats> detail_frame_;
  std::uint64_t frame_ = 0;
  std::uint64_t seen_edit_version_ = 0;  // the terrain edit version the vehicles have followed
  double burned_ms_ = 0;
  double last_frame_ms_ = 0;
  Input input_;
  StepTimes step_times_;
  std::unique_ptr<ScriptRunner> scripts_;  // last: destroyed first (its Lua state refers to us)
};

}  // namespace game
