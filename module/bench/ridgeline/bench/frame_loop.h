// The one frame loop of Ridgeline's benchmarks (docs/benchmarks.md, "How the figures are
// measured"): techniques (technique.h) along a camera path, each frame's update timed in wall
// and thread-CPU time, and on chosen frames, untimed, the measurement of the mesh as drawn
// (MeshErrorMeter: error, screen error, triangles in view, and between two frames the per-vertex
// jump and the pop). `ridge bench lod`, `ridge report`, bench_roam_core and game_pop are front
// ends that set the options and write the figures.
//
// Threading: one thread; the techniques and the meter are used by the calling thread only.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "ridgeline/bench/technique.h"
#include "ridgeline/camera.h"
#include "ridgeline/mesh_error.h"

namespace ridgeline::bench {

/// How the loop runs a path.
struct LoopOptions {
  /// Untimed, unrecorded frames before the run (the path's frames 0, 1, ..., cycling).
  std::uint64_t warmup = 0;
  /// Laps of the path that are recorded (>= 1).
  std::uint64_t repeat = 1;
  /// Measure the mesh every K-th frame (0: never). Without pops the measured frames are 0, K,
  /// 2K, ...; with pops they are K, 2K, ... and the mesh of frames K - 1, 2K - 1, ... is captured
  /// for the jump and the pop (K is then at least 2).
  std::uint32_t error_every = 0;
  /// Also measure the per-vertex jump and the pop (docs/report.md), and the morphed mesh's
  /// error, jump and pop for techniques that geomorph.
  bool pops = false;
  /// Update only on the frames the measurement reads (a rebuild from the roots: its mesh
  /// depends on the current camera alone, so the other frames would repeat the same work).
  bool only_measured_frames = false;
  /// Other memory read and written before every update, MiB (OtherWork; 0: none).
  double flush_mb = 0;
  /// With several techniques: which one goes first rotates frame by frame (else in order).
  bool alternate = false;
  /// Keep every recorded frame's figures as JSON (Run::frames).
  bool keep_frames = false;
  /// Untimed, before every recorded frame k of every lap (before the techniques' updates, also
  /// on frames only_measured_frames skips): the deformation storm's crater.
  std::function<Status(std::size_t frame)> before_frame;
};

/// One technique's figures along the path: per-frame and per-measured-frame series, summarised
/// by summary.h.
struct Run {
  std::string technique;  ///< Technique::name()
  // Per recorded (updated) frame.
  std::vector<double> wall_ms, cpu_ms, faults, output_ms, output_cpu_ms;
  std::vector<double> triangles, changes, memory_bytes, data_bytes, upload_bytes, output_bytes;
  // Per measured frame: the mesh drawn without geomorphs, and with them where it morphs; the
  // per-vertex jump and the pop with pops (docs/report_method.md, "Definitions").
  std::vector<double> in_view, max_m, rms_m, max_px, p99_px, vertices, morph_max_px;
  std::vector<double> jump, jump_morph, pop, pop_morph;
  std::uint64_t uncovered = 0;  ///< measured vertices in view no triangle covered (holes)
  /// The numbers among the techniques' per-frame extras and diagnostics, by name.
  std::map<std::string, std::vector<double>> series;
  Json frames = Json::array();    ///< with LoopOptions::keep_frames
  Json summary = Json::object();  ///< Technique::summary() at the end
  bool has_morph = false;         ///< Technique::geomorphs()
  double wall_s = 0, measure_s = 0;  ///< the whole run, and the measurement in it

  /// A named series, empty when the technique never reported it.
  const std::vector<double>& named(const std::string& name) const;
};

/// Runs `techniques` along `path` (each technique's start() with the first camera, the
/// warm-up, then `repeat` laps; several techniques take turns frame by frame). `meter` (the
/// lattice the meshes are measured on) may be null when error_every is 0. Stops at the first
/// failing update or before_frame, returning its error.
Result<std::vector<Run>> run_path(const std::vector<Technique*>& techniques,
                                  const std::vector<Camera>& path, const MeshErrorMeter* meter,
                                  const LoopOptions& options);
/// The same for one technique.
Result<Run> run_path(Technique& technique, const std::vector<Camera>& path,
                     const MeshErrorMeter* meter, const LoopOptions& options);

}  // namespace ridgeline::bench
