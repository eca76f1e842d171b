// Camera paths (PATH.json version 1, docs/cli.md "Camera paths"). Part of Ridgeline::io.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "ridgeline/camera.h"
#include "ridgeline/result.h"

namespace ridgeline::io {

/// One frame of a camera path: the camera and the simulated time step (seconds).
struct PathFrame {
  Camera camera;
  double dt = 1.0 / 60.0;
};

/// Parses a PATH.json document:
/// {"version": 1, "frames": [{"eye": [x, y, z], "target": [x, y, z], "up": [0, 1, 0],
///   "fov_y": 60, "viewport": [1280, 720], "near": 0.5, "far": 50000, "dt": 0.016667}, ...]}
/// `up`, `near`, `far`, `dt` are optional with those defaults. Every frame is validated
/// (validate_camera()); errors name the frame and the field ("frame 12: 'fov_y' is 200; need
/// (0, 180)"). At most `max_frames` frames.
Result<std::vector<PathFrame>> parse_camera_path(std::string_view json,
                                                 std::size_t max_frames = 10000000);

/// Reads and parses a PATH.json file (at most 512 MiB).
Result<std::vector<PathFrame>> load_camera_path(const std::string& path);

}  // namespace ridgeline::io
