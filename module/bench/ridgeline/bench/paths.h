// The six camera paths of `ridge report` and the benchmarks, generated for any terrain from its extent and heights
// (the same kinds as tests/data/paths/make_paths.py writes for the default terrain).
#pragma once

#include <string>
#include <vector>

#include "ridgeline/camera.h"
#include "ridgeline/terrain.h"

namespace ridgeline::bench {

struct NamedPath {
  std::string name;
  std::vector<Camera> frames;
};

/// flyover (a circle of radius 0.3 x the smaller extent, 1 degree per frame, above the highest
/// sample, looking ahead and down), drive (2 m above the ground at 20 m/s, winding), fast_yaw (40 m
/// above the ground, 3 degrees per frame), zoom (slow flight, 0.002 x extent per frame, field of
/// view 70 -> 8 degrees at a third of the path, back at two thirds), down (straight down,
/// descending from 0.7 x extent above the top to 60 m above the ground over the path), fast_pass
/// (1,000 km/h, 4.63 m per frame at 60 Hz, 40 m above the highest sample). `frames` per path (>=
/// 3), 1280 x 720, 60 Hz.
std::vector<NamedPath> make_paths(const Terrain& terrain, int frames);

}  // namespace ridgeline::bench
