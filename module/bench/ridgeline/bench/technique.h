// What the frame loop (frame_loop.h) runs: a level-of-detail technique behind one interface, so
// that ROAM, its rebuild from the roots, SOAR, CDLOD and a uniform grid are timed and measured
// by the same code (docs/benchmarks.md). The techniques themselves are in techniques.h.
//
// Threading: a technique is used by one thread at a time.
#pragma once

#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>

#include "ridgeline/camera.h"
#include "ridgeline/mesh_error.h"
#include "ridgeline/result.h"

namespace ridgeline::bench {

using Json = nlohmann::ordered_json;

/// A technique's mesh as captured after one frame, drawable later for any camera, geomorphed
/// (`morph`) or not, in lattice units of the meter it was captured for: the pop compares the
/// previous frame's mesh and the current one drawn for the current camera.
using Drawable = std::function<DrawnMesh(const Camera& camera, bool morph)>;

/// Lattice cells [i0, i1] x [j0, j1] an edit changed (stored lattice of the technique's terrain).
struct CellBox {
  std::int64_t i0 = 0, j0 = 0, i1 = 0, j1 = 0;
};

/// What a technique reports about its last update (not its time: the loop measures that).
struct FrameFigures {
  static constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
  double triangles = 0;        ///< triangles the technique holds (ROAM: every leaf)
  double changes = kNone;      ///< splits + merges (CDLOD: quadrants in or out); kNone: not counted
  double memory_bytes = 0;     ///< the per-view state (SOAR: its vertex data and strip)
  double data_bytes = 0;       ///< shared data besides the heightfield (ROAM: the landscape's bounds)
  double upload_bytes = kNone; ///< bytes an engine re-uploads after this frame; kNone: not measured
  double output_bytes = kNone; ///< bytes of the buffers an engine draws from; kNone: not reported
  /// The technique's own per-frame fields (bench lod's "frames"); numbers among them are kept as
  /// named series of the run (Run::series).
  Json extra = Json::object();
};

class Technique {
 public:
  virtual ~Technique() = default;

  /// The name in the figures: roam_coherent, roam_rebuild, soar, cdlod, uniform_grid.
  virtual std::string name() const = 0;
  /// Untimed, once before the first frame (warm-up included) with the path's first camera:
  /// where a technique gets to the state a game has after loading (ROAM: converged, tiles in).
  virtual Status start(const Camera& /*first*/) { return {}; }
  /// Untimed, before every update: per-frame work that is not the technique's (the detail tile
  /// cache's once-per-frame update, which ROAM times itself into its summary).
  virtual void before_update() {}
  /// The frame's work, timed by the loop in wall and thread-CPU time.
  virtual Status update(const Camera& camera) = 0;
  /// True when the frame has no work (a static mesh): the loop records 0 ms without calling
  /// update().
  virtual bool idle() const { return false; }
  /// True when the technique has an output step apart from its update (ROAM: taking the dirty
  /// patches an engine re-uploads); the loop times output() apart, and records 0 ms otherwise.
  virtual bool has_output() const { return false; }
  virtual void output() {}
  /// Figures of the last update.
  virtual FrameFigures figures() const = 0;
  /// The mesh as it stands (untimed; on measured frames only).
  virtual Drawable capture(const MeshErrorMeter& meter) = 0;
  /// Untimed diagnostics on measured frames, after the measurement (SOAR: its refinement again
  /// without emission); returned fields go into the frame's JSON, numbers into Run::series.
  virtual Json diagnose(const Camera& /*camera*/) { return Json::object(); }
  /// The technique's own summary fields, at the end of a run.
  virtual Json summary() const { return Json::object(); }
  /// The mesh is drawn with geomorphs (the morphed error, jump and pop are measured too).
  virtual bool geomorphs() const { return false; }
  /// The mesh does not depend on the camera (ROAM with a tolerance in metres): its error is
  /// measured at every lattice vertex, no frustum, no pixels.
  virtual bool view_independent() const { return false; }
  /// The terrain under the technique changed in `box` (the deformation storm): taken into
  /// account inside the next timed update.
  virtual void terrain_changed(const CellBox& /*box*/) {}
};

}  // namespace ridgeline::bench
