// GameApi: what game scripts may see and do (the `game` Lua table, lua_game.cpp and
// lua_vehicles.cpp). The Game implements it; the Lua side knows the game only through it.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "ridgeline/budget_controller.h"
#include "ridgeline/camera.h"
#include "ridgeline/result.h"
#include "ridgeline/roam_view.h"
#include "ridgeline/terrain.h"
#include "vehicle.h"

namespace game {

enum class CameraMode { kFree, kFollow, kMap };
const char* to_string(CameraMode mode) noexcept;

/// The three cameras; each one has its own RoamView.
struct CameraRig {
  CameraMode mode = CameraMode::kFollow;
  glm::dvec3 free_eye{300, 400, 300};
  double free_yaw = 0.8, free_pitch = -0.35;  ///< radians; yaw 0 = +z
  int follow_vehicle = -1;                    ///< vehicle id; -1: the first vehicle
  /// Follow camera: metres behind the vehicle, above it (or above the ground under the eye),
  /// and ahead of it where it looks (the road ahead, where the artillery's craters land).
  double follow_distance = 22, follow_height = 7, follow_ahead = 12;
  glm::dvec2 map_centre{1024, 1024};
  double map_height = 1500;
};

/// One vehicle in play.
struct VehicleEntry {
  int id = 0;
  std::string name, model;
  Vehicle body;
  Autopilot autopilot;
  double distance_m = 0;  ///< path length driven
};

/// Loose bodies alive at once: the oldest is removed when another is spawned.
inline constexpr std::size_t kMaxBodies = 160;

/// A deformation the game applied (for stats and the renderer).
struct CraterRecord {
  double x = 0, z = 0, radius = 0, depth = 0;
  std::uint64_t frame = 0;
};

/// Per-frame statistics of the active view and the controller.
struct ViewFrame {
  ridgeline::RoamStats stats{};
  double threshold = 0;
  double render_scale = 1;  ///< fraction of the output resolution the scene renders at
  bool updated = false;
};

/// Player input from the window (keys), read by scripts through game.input().
struct Input {
  bool up = false, down = false, left = false, right = false, brake = false;
};

/// The LOD budget as scripts see and set it (game.budget(), game.set_budget{}).
struct BudgetSettings {
  bool controller = true;           ///< the frame-time controller moves threshold and scale
  double threshold = 2;             ///< pixels (the controller's output when it is on)
  double render_scale = 1;          ///< (0, 1] (the controller's output when it is on)
  std::uint32_t max_triangles = 0;  ///< the views' triangle budget
  double tessellation_ms = 0;       ///< the views' time budget (0: none)
};

/// Threading: one thread (the game's).
class GameApi {
 public:
  virtual ~GameApi() = default;

  // ---- time ---------------------------------------------------------------------------------
  virtual std::uint64_t frame() const noexcept = 0;  ///< steps taken
  virtual double time() const noexcept = 0;          ///< seconds of game time
  virtual double dt() const noexcept = 0;            ///< seconds per step
  virtual const Input& input() const noexcept = 0;
  /// Wall-clock time of the last rendered frame, milliseconds.
  virtual double last_frame_ms() const noexcept = 0;
  /// Records `ms` of artificial load a script spent (game.burn_ms), for the stats.
  virtual void add_burn(double ms) noexcept = 0;

  // ---- vehicles -------------------------------------------------------------------------------
  virtual ridgeline::Result<int> spawn(const std::string& model, double x, double z, double heading,
                                       const std::string& name) = 0;
  /// The vehicle, or null when there is none with that id (removed).
  virtual VehicleEntry* vehicle(int id) = 0;
  virtual const std::map<int, VehicleEntry>& vehicles() const noexcept = 0;
  virtual bool remove_vehicle(int id) = 0;
  virtual std::vector<std::string> model_names() const = 0;

  // ---- loose bodies (boulders, debris) ------------------------------------------------------
  /// Spawns a loose body (the caller has checked the spec: finite, sizes 0.05 .. 5 m, mass >= 0).
  /// Fails off the terrain. At most kMaxBodies live at once: spawning another removes the oldest.
  virtual ridgeline::Result<int> spawn_body(const BodySpec& spec) = 0;
  /// The body, or null when there is none with that id (removed, or despawned).
  virtual LooseBody* body(int id) = 0;
  virtual const std::map<int, LooseBody>& bodies() const noexcept = 0;
  virtual bool remove_body(int id) = 0;

  // ---- terrain ------------------------------------------------------------------------------
  virtual const std::shared_ptr<ridgeline::Terrain>& terrain_ptr() const noexcept = 0;
  /// Opens a crater (vehicles follow it at the next step, through the terrain's change log).
  /// Samples changed.
  virtual ridgeline::Result<std::size_t> crater(double x, double z, double radius,
                                                double depth) = 0;
  virtual std::size_t crater_count() const noexcept = 0;

  // ---- cameras and the budget ---------------------------------------------------------------
  virtual CameraRig& rig() noexcept = 0;
  /// The camera of the current mode.
  virtual ridgeline::Camera camera() const = 0;
  virtual ridgeline::BudgetController& controller() noexcept = 0;
  virtual BudgetSettings budget() const noexcept = 0;
  /// Applies every field (the caller has checked them): the threshold and render scale matter
  /// only with the controller off (with it on they restart it there).
  virtual void set_budget(const BudgetSettings& settings) = 0;
  virtual const ViewFrame& last_view_frame() const noexcept = 0;
  /// The views' root triangles: the smallest triangle budget a view accepts.
  virtual std::uint32_t root_triangles() const noexcept = 0;
};

}  // namespace game
