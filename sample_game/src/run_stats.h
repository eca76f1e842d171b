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
  double frame_ms = 0, sim_ms = 0, tess_ms = 0, render_ms = 0, burn_ms = 0;
  double threshold = 0;
  std::uint32_t triangles = 0, splits = 0, merges = 0, patches_uploaded = 0;
  struct VehicleRecord {
    int id;
    double x, y, z, speed;
    std::uint64_t reached;
    double min_gap, max_contact_gap;
    int contacts;
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
