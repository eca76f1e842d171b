// RoamView: the ROAM mesh of one camera over a shared Landscape (Duchaineau et al. 1997).
#pragma once

#include <cstdint>
#include <functional>
#include <glm/vec3.hpp>
#include <memory>
#include <span>
#include <vector>

#include "ridgeline/camera.h"
#include "ridgeline/landscape.h"
#include "ridgeline/result.h"

namespace ridgeline {

/// How the mesh is refined.
enum class RoamMode {
  kCoherent,  ///< split and merge queues; each update starts from the previous mesh (default)
  kRebuild,   ///< throw the mesh away every update and refine top-down, split only (Turner 2000)
};

/// What the threshold measures.
enum class ErrorMetric {
  kScreenPixels,  ///< projected bound in pixels for the current camera; frustum culled (default)
  kWorldMetres,   ///< bound in metres, view independent, whole terrain, no culling (--tolerance)
};

/// Settings a game may change between any two updates.
struct RoamSettings {
  RoamMode mode = RoamMode::kCoherent;
  ErrorMetric metric = ErrorMetric::kScreenPixels;
  /// Detail threshold: pixels (kScreenPixels) or metres (kWorldMetres); finite, >= 0.
  double threshold = 2.0;
  /// Hard cap on leaf triangles of the whole landscape; 0 = none. A split (with its chain of
  /// forced splits) that would exceed it is not started (SPEC.md).
  std::uint32_t max_triangles = 0;
  /// Time budget per update, milliseconds; 0 = none. Checked every few operations.
  double budget_ms = 0.0;
  /// Lazy priorities: a node's priority is computed as the largest it can take while the eye
  /// stays within slack * distance of where it was computed, and recomputed when the eye has
  /// travelled that far. Larger slack: fewer recomputations, a few more triangles. 0.005..0.5.
  double slack = 0.05;
};

/// Why an update stopped.
enum class StopReason { kConverged, kTriangleBudget, kTimeBudget };

/// Statistics of one update.
struct RoamStats {
  std::uint32_t triangles = 0;      ///< leaves of the whole landscape after the update
  std::uint32_t splits = 0;         ///< diamond splits requested by priority
  std::uint32_t forced_splits = 0;  ///< splits forced to keep the mesh conforming
  std::uint32_t merges = 0;
  std::uint32_t priority_updates = 0;  ///< nodes whose priority was (re)computed ("visited")
  std::uint32_t expired = 0;  ///< queued keys recomputed because the camera left their window
  std::uint32_t expiry_records = 0;  ///< expiry records examined (including stale ones)
  double update_ms = 0;
  StopReason stop = StopReason::kConverged;
  bool rebuilt = false;  ///< the mesh was rebuilt top-down (rebuild mode, a teleport, a snap turn)
  /// Largest priority left in the split queue (pixels or metres; an upper bound of the projected
  /// error of any remaining triangle in view). <= threshold when converged.
  double max_remaining_error = 0;
  std::size_t memory_bytes = 0;     ///< node pool, queues and output buffers of this view
  std::uint32_t dirty_patches = 0;  ///< patches whose mesh changed in this update
  /// Leaves that should split but wait for a procedural-detail tile (requested, generated on the
  /// cache's workers): held at the coarser level, exempt from the converged bound, re-queued at
  /// the next update. max_remaining_error does not count them.
  std::uint32_t pending_splits = 0;
};

/// One output vertex: patch-local float position (x, height, z) relative to the patch origin,
/// the smooth vertex normal of the full-detail surface, and geomorph data.
struct MeshVertex {
  float x, y, z;
  float nx, ny, nz;
  /// Geomorph: height offset from the true height to the interpolated height of the edge the
  /// vertex splits (morphed y = y + (1 - t) * morph_dy), and the bound (metres) of the diamond
  /// that introduces the vertex, from which t follows (see morph_factor()). 0 for patch corners.
  float morph_dy;
  float morph_bound;
};

/// Mesh of one patch, in patch-local coordinates.
struct PatchMesh {
  double origin_x = 0, origin_y = 0, origin_z = 0;  ///< world position of the local origin
  std::vector<MeshVertex> vertices;
  std::vector<std::uint32_t> indices;  ///< three per triangle, counter-clockwise from above
  std::vector<std::uint8_t> padding;   ///< per triangle: 1 when its centre lies in the padding
  std::uint64_t version = 0;           ///< increases whenever this patch's mesh changes
};

/// Geomorph factor t in [0, 1] of a vertex: t = clamp(p / threshold - 1, 0, 1), p being the
/// vertex's diamond bound projected at the vertex's own distance. t is 0 when the diamond just
/// split (the vertex sits on the coarser edge: no pop) and reaches 1 when the projected bound is
/// twice the threshold; at a merge p <= threshold so t = 0 again. Shared vertices across a seam
/// have the same data and so the same t: a morph never opens a crack.
float morph_factor(float morph_bound, double distance_m, double projection_scale,
                   double threshold_px);

/// The ROAM mesh of one camera. Owns its node pool, queues and output buffers; reads the shared
/// Landscape. Two cameras are two RoamViews over one Landscape.
///
/// Threading: one thread updates a view; several views over one Landscape may update on
/// different threads at once. Output accessors must not run during update() of the same view.
///
/// Edits: update() pulls them. It first calls Landscape::sync() (the shared bounds), then asks
/// Terrain::changes_since() the version this view last saw, and over each change's
/// Landscape::changed_box() refreshes its nodes (bounds, boxes), requeues the queued ones with
/// fresh priorities and marks the patches whose vertices or normals changed dirty, before it
/// splits and merges. Until then the mesh and take_dirty_patches() show the surface of the
/// previous update. No view call may run during an edit.
class RoamView {
 public:
  static Result<std::unique_ptr<RoamView>> create(std::shared_ptr<const Landscape> landscape,
                                                  const RoamSettings& settings = {});
  ~RoamView();
  RoamView(const RoamView&) = delete;
  RoamView& operator=(const RoamView&) = delete;

  /// Changes settings; a mode or metric change resets the mesh on the next update.
  Status set_settings(const RoamSettings& settings);
  const RoamSettings& settings() const noexcept { return settings_; }

  /// Tessellates for `camera` (ignored with ErrorMetric::kWorldMetres): refines and coarsens until
  /// converged or a budget stops it; what is left continues on the next update. Fails only for an
  /// invalid camera (nothing changes then).
  Result<RoamStats> update(const Camera& camera);

  /// Converges fully for a static camera (no time budget): what `ridge mesh` uses.
  Result<RoamStats> converge(const Camera& camera);

  const Landscape& landscape() const noexcept { return *landscape_; }
  std::uint32_t triangle_count() const noexcept { return triangles_; }

  /// Patches whose mesh changed since the last call (each listed once), for re-upload.
  std::vector<std::uint32_t> take_dirty_patches();
  /// Mesh of one patch (0 .. patch_count-1), regenerated if it changed since it was last built.
  const PatchMesh& patch_mesh(std::uint32_t patch);

  /// Calls `fn(root, heap, triangle)` for every leaf, in a deterministic order (roots in order,
  /// depth first, child 0 first).
  void for_each_leaf(
      const std::function<void(std::uint32_t, std::uint64_t, const LatticeTriangle&)>& fn) const;

  /// 64-bit hash of the leaf set (for determinism checks).
  std::uint64_t mesh_hash() const;

  /// Measured error of the mesh (SPEC.md): |mesh height - surface height| at the lattice vertices
  /// inside `camera`'s frustum (every vertex with ErrorMetric::kWorldMetres), taking every
  /// `stride`-th vertex along each axis (1 = all; a fixed stratified sample otherwise), and the
  /// same error projected to pixels at each vertex's own distance.
  struct MeasuredError {
    double max_m = 0, rms_m = 0;     ///< metres
    double max_px = 0, p99_px = 0;   ///< pixels (0 with ErrorMetric::kWorldMetres)
    std::uint64_t vertices = 0;      ///< vertices measured
  };
  MeasuredError measure_error(const Camera& camera, std::uint32_t stride = 1) const;

  /// Checks the mesh's structural invariants (neighbour links symmetric, every leaf edge shared
  /// with exactly one other leaf or on the landscape border, no T-junctions). Returns an empty
  /// string when they hold, else a description of the first violation. O(triangles).
  std::string check_invariants() const;

  struct Impl;

 private:
  RoamView() = default;
  std::shared_ptr<const Landscape> landscape_;
  RoamSettings settings_;
  std::uint32_t triangles_ = 0;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ridgeline
