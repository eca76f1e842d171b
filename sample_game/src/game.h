// Game: the sample game's simulation (terrain, vehicles, cameras, scripts, the LOD budget), with
// no GL: the window, offscreen and headless modes all drive this one class.
#pragma once

#include <cstdint>
#include <deque>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "ridgeline/budget_controller.h"
#include "ridgeline/camera.h"
#include "ridgeline/landscape.h"
#include "ridgeline/lua/host.h"
#include "ridgeline/roam_view.h"
#include "ridgeline/terrain.h"
#include "vehicle.h"
#include "vehicle_model.h"

struct lua_State;

namespace game {

/// Settings from the command line (main.cpp) or a test.
struct GameOptions {
  std::string assets_dir;  ///< folder with vehicles/*.glb
  std::string scripts_dir; ///< folder scripts may name relatively (game.load_script)
  double dt = 1.0 / 60.0;  ///< fixed simulation step, seconds
  glm::ivec2 viewport{1280, 720};
  /// > 0: the threshold stays at this value (the controller is off): reproducible pictures.
  double fixed_threshold = 0;
  ridgeline::BudgetControllerDesc budget{};  ///< target 33 ms by default
  std::uint32_t max_triangles = 60000;       ///< triangle budget of every view
  double tessellation_budget_ms = 8;         ///< time budget of one view update
  bool tessellate = true;  ///< update the active view each frame (off: pure simulation)
  std::uint64_t instruction_limit = 20'000'000;  ///< per script call (an infinite loop ends)
  std::uint32_t patch_exponent = 6;
};

enum class CameraMode { kFree, kFollow, kMap };
const char* to_string(CameraMode mode) noexcept;

/// The three cameras; each one has its own RoamView.
struct CameraRig {
  CameraMode mode = CameraMode::kFollow;
  glm::dvec3 free_eye{300, 400, 300};
  double free_yaw = 0.8, free_pitch = -0.35;  ///< radians; yaw 0 = +z
  int follow_vehicle = -1;   ///< vehicle id; -1: the first vehicle
  double follow_distance = 22, follow_height = 9;
  glm::dvec2 map_centre{1024, 1024};
  double map_height = 1500;
};

struct ScriptError {
  std::string script;
  std::string message;  ///< error and traceback
  std::uint64_t frame = 0;
};

/// One vehicle in play.
struct VehicleEntry {
  int id = 0;
  std::string name, model;
  Vehicle body;
  Autopilot autopilot;
  double distance_m = 0;  ///< path length driven
};

/// A deformation the game applied (for stats and the renderer).
struct CraterRecord {
  double x = 0, z = 0, radius = 0, depth = 0;
  std::uint64_t frame = 0;
};

/// Per-frame statistics of the active view and the controller.
struct ViewFrame {
  ridgeline::RoamStats stats{};
  double threshold = 0;
  bool updated = false;
};

/// Player input from the window (keys), read by scripts through game.input().
struct Input {
  bool up = false, down = false, left = false, right = false, brake = false;
};

/// Threading: one thread.
class Game {
 public:
  static ridgeline::Result<std::unique_ptr<Game>> create(const GameOptions& options);
  ~Game();

  // ---- scripts -----------------------------------------------------------------------------
  /// Loads and runs a script file; it stays registered for reload. A failing script is recorded
  /// in errors() and logged; the game goes on (the Status says what failed).
  ridgeline::Status load_script(const std::string& path);
  /// Re-runs every script whose file changed since it was loaded (its event handlers are
  /// replaced). Returns how many were reloaded.
  int reload_changed_scripts();
  /// Re-runs every script (the panel's Reload button, F5).
  int reload_all_scripts();
  const std::deque<ScriptError>& errors() const noexcept { return errors_; }
  std::uint64_t error_count() const noexcept { return error_count_; }
  std::vector<std::string> script_names() const;

  // ---- simulation ----------------------------------------------------------------------------
  /// One fixed step: scripts' tick handlers, autopilots, the vehicles' reaction to every terrain
  /// edit since the last step (from any brush, C++ or Lua, or a loaded edit state: the terrain's
  /// change log is polled once here), vehicle physics.
  void step();
  std::uint64_t frame() const noexcept { return frame_; }  ///< steps taken
  double time() const noexcept { return double(frame_) * options_.dt; }
  double dt() const noexcept { return options_.dt; }
  /// Milliseconds of load scripts asked for this frame with game.burn_ms (already spent).
  double burned_ms() const noexcept { return burned_ms_; }

  ridgeline::Result<int> spawn(const std::string& model, double x, double z, double heading,
                               const std::string& name);
  VehicleEntry* vehicle(int id);
  std::map<int, VehicleEntry>& vehicles() noexcept { return vehicles_; }
  bool remove_vehicle(int id);
  const VehicleModel* model(const std::string& name) const;
  std::vector<std::string> model_names() const;

  /// Deforms the terrain with a crater (the edit layer). Vehicles follow it at the next step(),
  /// as they follow every edit. Returns the number of lattice samples changed.
  ridgeline::Result<std::size_t> crater(double x, double z, double radius, double depth);
  const std::vector<CraterRecord>& craters() const noexcept { return craters_; }

  // ---- views, cameras, budget ----------------------------------------------------------------
  CameraRig& rig() noexcept { return rig_; }
  /// The camera of the current mode, for the given viewport.
  ridgeline::Camera camera() const;
  /// Feeds the last frame's time to the controller (when on) and updates the active view.
  ViewFrame update_view(double frame_ms);
  ridgeline::RoamView& view(CameraMode mode) noexcept { return *views_[int(mode)]; }
  ridgeline::RoamView& active_view() noexcept { return view(rig_.mode); }
  ridgeline::BudgetController& controller() noexcept { return controller_; }
  const ridgeline::BudgetController& controller() const noexcept { return controller_; }
  bool controller_on() const noexcept { return controller_on_; }
  void set_controller_on(bool on) noexcept { controller_on_ = on; }
  double threshold() const noexcept { return threshold_; }
  void set_threshold(double px) noexcept { threshold_ = px; }
  std::uint32_t max_triangles() const noexcept { return max_triangles_; }
  void set_max_triangles(std::uint32_t n) noexcept { max_triangles_ = n; }
  double tessellation_budget_ms() const noexcept { return tess_budget_ms_; }
  void set_tessellation_budget_ms(double ms) noexcept { tess_budget_ms_ = ms; }
  const ViewFrame& last_view_frame() const noexcept { return last_view_; }

  const ridgeline::Terrain& terrain() const noexcept { return *terrain_; }
  const std::shared_ptr<ridgeline::Terrain>& terrain_ptr() const noexcept { return terrain_; }
  const GameOptions& options() const noexcept { return options_; }
  Input input;
  /// Wall-clock time of the last rendered frame, milliseconds (set by the frame loop).
  double last_frame_ms = 0;
  /// Messages scripts printed with game.log (last 200), for the panel.
  std::deque<std::string> log_lines;

  // Used by the Lua API (scripting.cpp).
  struct Script {
    std::string name, path;
    std::filesystem::file_time_type mtime{};
    bool failed = false;  ///< its handlers are off until it is reloaded
  };
  ridgeline::lua::Host& host() noexcept { return *host_; }
  int current_script = -1;  ///< script whose chunk or handler is running
  std::vector<Script> scripts;
  void record_error(int script, const std::string& message);
  void log(const std::string& line);
  void add_burn(double ms) noexcept { burned_ms_ += ms; }

 private:
  Game() = default;
  ridgeline::Status run_script(int index);
  void clamp_to_terrain(VehicleEntry& e);
  // Pulls the terrain's change log: vehicles near a changed box follow the new ground.
  void follow_terrain_edits();

  GameOptions options_;
  std::shared_ptr<ridgeline::Terrain> terrain_;
  std::shared_ptr<const ridgeline::Landscape> landscape_;
  std::unique_ptr<ridgeline::RoamView> views_[3];
  std::map<std::string, VehicleModel> models_;
  std::map<int, VehicleEntry> vehicles_;
  int next_vehicle_id_ = 1;
  std::vector<CraterRecord> craters_;
  std::size_t craters_emitted_ = 0;
  CameraRig rig_;
  ridgeline::BudgetController controller_ = ridgeline::BudgetController::create().value();
  bool controller_on_ = true;
  double threshold_ = 2;
  std::uint32_t max_triangles_ = 60000;
  double tess_budget_ms_ = 8;
  ViewFrame last_view_;
  std::uint64_t frame_ = 0;
  std::uint64_t seen_edit_version_ = 0;  // the terrain edit version the vehicles have followed
  double burned_ms_ = 0;
  std::unique_ptr<ridgeline::lua::Host> host_;
  std::deque<ScriptError> errors_;
  std::uint64_t error_count_ = 0;
};

/// Installs the `game` table in the host's script environment (scripting.cpp).
ridgeline::Status install_game_api(Game& game);
/// Calls the handlers of `event` (scripting.cpp); args are pushed by the callback.
void emit_event(Game& game, const char* event, int (*push)(lua_State*, void*), void* user);

}  // namespace game
