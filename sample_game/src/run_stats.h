// Per-frame statistics (--stats FILE.json) and screenshots (--screenshot, through OpenImageIO).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "game.h"
#include "ridgeline/result.h"

namespace game {

struct FrameRecord {
  std::uint64_t frame = 0;
  double time_s = 0;
  /// Milliseconds: the whole frame (screenshots excluded), the simulation (scripts + physics),
  /// the view update, patch uploads (patch_mesh_ms of it: the core building the meshes), rendering
  /// (draw calls, the GPU's work up to glFinish, the panel's drawing, the window blit; uploads
  /// excluded), the panel's CPU side, artificial load.
  double frame_ms = 0, sim_ms = 0, scripts_ms = 0, physics_ms = 0, tess_ms = 0, upload_ms = 0,
         patch_mesh_ms = 0, render_ms = 0, panel_ms = 0, burn_ms = 0;
  /// Milliseconds spent reading back and writing screenshots after the frame (not in frame_ms).
  double screenshot_ms = 0;
  /// CPU milliseconds during the frame: every thread of the process, and the game's thread.
  double cpu_ms = 0, main_cpu_ms = 0;
  double threshold = 0, render_scale = 1;
  double wall_s = 0;            ///< wall clock (seconds since the Unix epoch) at the frame's end
  double smoothed_ms = 0;       ///< the controller's moving average after this frame
  std::uint64_t reversals = 0;  ///< the controller's direction reversals so far
  std::uint32_t triangles = 0, splits = 0, merges = 0, patches_uploaded = 0, pending_splits = 0;
  int stop = -1;                  ///< ridgeline::StopReason of the view update, -1 when none ran
  std::size_t contacts = 0;       ///< vehicle-vehicle pairs touching after the last step
  std::size_t body_contacts = 0;  ///< loose body-vehicle pairs touching after the last step
  std::size_t bodies = 0, bodies_awake = 0;  ///< loose bodies alive, and not asleep
  /// Vertex and index bytes the renderer sent to GL (dirty ranges, whole buffers when they grew),
  /// and the bytes the view's update changed (RoamStats::upload_bytes).
  std::uint64_t bytes_uploaded = 0, view_upload_bytes = 0;
  std::size_t tiles_resident = 0, tiles_pending = 0;
  std::uint64_t tiles_generated = 0;  ///< since the start
  struct VehicleRecord {
    int id;
    double x, y, z, speed;
    std::uint64_t reached;
    double min_gap, max_contact_gap;
    int contacts;
    int material;
    std::uint64_t collisions;
    std::uint64_t body_hits;
  };
  std::vector<VehicleRecord> vehicles;
};

class RunStats {
 public:
  void record(const Game& game, FrameRecord r);
  /// Writes {"mode":..., "summary": {...percentiles...}, "frames": [...]} to `path` (through a
  /// temporary file and a rename).
  ridgeline::Status write(const std::string& path, const std::string& mode, const Game& game,
                          std::uint64_t skip_frames) const;
  const std::vector<FrameRecord>& frames() const noexcept { return frames_; }

 private:
  std::vector<FrameRecord> frames_;
};

/// Writes RGBA8 pixels (top row first) as a PNG through OpenImageIO (temporary name + rename).
ridgeline::Status write_png(const std::string& path, int width, int height,
                            const std::vector<std::uint8_t>& rgba);

}  // namespace game
