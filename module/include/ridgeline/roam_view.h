// RoamView: the ROAM mesh of one camera over a shared Landscape (Duchaineau et al. 1997).
#pragma once

#include <cstdint>
#include <functional>
#include <glm/vec3.hpp>
#include <memory>
#include <string>
#include <vector>

#include "ridgeline/camera.h"
#include "ridgeline/landscape.h"
#include "ridgeline/result.h"
#include "ridgeline/roam_memory.h"

namespace ridgeline {

/// How the mesh is refined.
enum class RoamMode {
  /// Frame coherent (default): the mesh carries over; each update re-tests the diamonds on the
  /// border of the mesh (the split and merge front) and splits and merges only those that changed.
  kCoherent,
  /// Stateless: the mesh is rebuilt from the roots every update (for comparisons and tests; the
  /// same mesh as kCoherent once both have converged).
  kRebuild,
};

/// What the threshold measures.
enum class ErrorMetric {
  kScreenPixels,  ///< projected bound in pixels for the current camera; frustum culled (default)
  kWorldMetres,   ///< bound in metres, view independent, whole terrain, no culling
};

/// Settings a game may change between any two updates.
struct RoamSettings {
  RoamMode mode = RoamMode::kCoherent;
  ErrorMetric metric = ErrorMetric::kScreenPixels;
  /// Detail threshold: pixels (kScreenPixels) or metres (kWorldMetres); finite, >= 0. 0 with a
  /// triangle cap: the best mesh of at most max_triangles triangles.
  double threshold = 2.0;
  /// Hard cap on leaf triangles of the whole landscape; 0 = none. A split (with its chain of
  /// forced splits) that would exceed it is not started. The splits that make the mesh end on the
  /// border of the sampled data count against it too (docs/roam.md, "The data border").
  std::uint32_t max_triangles = 0;
  /// Time budget per update, milliseconds; 0 = none. The splits and merges that matter most go
  /// first; what is left continues on the next update.
  double budget_ms = 0.0;
};

/// Why an update stopped.
enum class StopReason {
  kConverged,       ///< every diamond in the front meets the threshold (or waits for detail)
  kTriangleBudget,  ///< the triangle cap stopped it ("triangle_budget")
  kTimeBudget,      ///< the time budget stopped it ("time_budget")
};

/// The name used for a stop reason in JSON, the CLI and Lua: "converged", "triangle_budget",
/// "time_budget".
const char* stop_reason_name(StopReason reason) noexcept;

/// Statistics of one update.
struct RoamStats {
  std::uint32_t triangles = 0;      ///< leaves of the whole landscape after the update
  std::uint32_t splits = 0;         ///< diamond splits the threshold asked for
  std::uint32_t forced_splits = 0;  ///< splits forced to keep the mesh conforming
  std::uint32_t merges = 0;
  std::uint32_t priority_updates = 0;  ///< diamonds whose split test ran (the front, plus new ones)
  std::uint32_t front_size = 0;        ///< diamonds in the split and merge front after the update
  double update_ms = 0;
  StopReason stop = StopReason::kConverged;
  bool rebuilt = false;  ///< the mesh was rebuilt from the roots (rebuild mode, a teleport, reset)
  /// Largest projected bound (pixels, or metres with kWorldMetres) of a diamond in view left
  /// unsplit, for every stop reason: <= threshold when converged. Distances are clamped to the
  /// camera's near plane, so the figure is finite even for a diamond around the eye.
  double max_remaining_error = 0;
  /// The threshold the mesh corresponds to (pixels): the threshold, or under a triangle cap the
  /// level at which the cap stopped the refinement. What a vertex shader's geomorph uses.
  double morph_threshold = 0;
  std::size_t memory_bytes = 0;     ///< view state: nodes, front, free lists (output not counted)
  std::size_t output_bytes = 0;     ///< patch meshes held for the engine
  std::uint32_t dirty_patches = 0;  ///< patches whose mesh changed in this update
  /// Bytes of vertex and index data this update changed: what an engine re-uploads (the dirty
  /// ranges of take_dirty_patches(), or whole buffers that were resized).
  std::uint64_t upload_bytes = 0;
  /// Patches whose buffers this update compacted (renumbered in tree order and shrunk to fit,
  /// resized: upload them whole) because their slots outnumbered their live triangles or vertices
  /// more than 2 to 1 (docs/roam.md, "Output for an engine").
  std::uint32_t compacted_patches = 0;
  /// Diamonds that should split but wait for data: a procedural-detail tile or a page of a paged
  /// world (requested; made or loaded on workers): held at the coarser level, exempt from the
  /// converged bound, tested again at the next update. max_remaining_error does not count them.
  std::uint32_t pending_splits = 0;
  /// Diamonds whose bound a detail tile's or a page's arrival tightened in this update (the
  /// measured or exact bound replacing the provisional one).
  std::uint32_t rebounded = 0;
  /// Pages of a paged world (Terrain::open) this update's splits wait for, requested urgently:
  /// those splits are counted in pending_splits and go ahead once the pages are resident.
  std::uint32_t requested_pages = 0;
};

/// One output vertex: patch-local float position (x, height, z) relative to the patch origin, the
/// smooth vertex normal of the full-detail surface, the material id of the cell at the vertex,
/// and what a vertex shader needs for geomorphs (docs/roam.md, "Geomorphs"): the drawn height is
/// y + (1 - t) * morph_dy with t = morph_factor(...).
struct MeshVertex {
  float x, y, z;
  float nx, ny, nz;
  /// Height offset from the true height to the midpoint of the edge the vertex splits (its
  /// diamond's hypotenuse); 0 for patch corners.
  float morph_dy;
  /// The vertex's diamond bound and bounding-sphere radius (metres, DiamondBound::morph and
  /// ::radius). FLT_MAX bound for patch corners and FLT_MAX radius for vertices on the data
  /// border: both never morph.
  float morph_bound;
  float morph_radius;
  std::uint32_t material;
};

/// A run of changed elements in a patch buffer: slots first .. first + count - 1.
struct MeshRange {
  std::uint32_t first = 0, count = 0;
};

/// Mesh of one patch, in patch-local coordinates, as buffers an engine uploads once and then
/// patches in place: slots are reused, so a split or merge rewrites a few of them.
///
/// Lifetime: the reference patch_mesh() returns and the arrays stay valid until the next
/// update(), set_settings() or edit; the dirty ranges until the next take_dirty_patches().
struct PatchMesh {
  double origin_x = 0, origin_y = 0, origin_z = 0;  ///< world position of the local origin
  /// Vertex slots. A slot no triangle uses holds stale data.
  std::vector<MeshVertex> vertices;
  /// Three indices per triangle slot, counter-clockwise seen from above. Unused slots and
  /// triangles over the padding beyond the sampled data are (0, 0, 0), degenerate: draw the whole
  /// array.
  std::vector<std::uint32_t> indices;
  /// Vertex and triangle slots changed up to the last take_dirty_patches() (sorted, disjoint).
  std::vector<MeshRange> dirty_vertices, dirty_triangles;
  /// The buffers were reallocated, or compacted (every slot renumbered, the arrays shorter):
  /// upload them whole.
  bool resized = false;
  std::uint32_t triangles = 0;  ///< triangles drawn (not degenerate)
  std::uint64_t version = 0;    ///< increases whenever this patch's mesh changes
};

/// Geomorph factor t in [0, 1] of a vertex (docs/roam.md, "Geomorphs"), what a vertex shader
/// computes: with d the distance (metres) from the eye to the vertex at its true position, and
/// rho = morph_bound * projection_scale / (threshold * max(d - morph_radius, 1e-6)),
/// t = clamp((rho - 1 - g.delay) / g.window, 0, 1) (1 when the window is 0), g the landscape's
/// geomorph(). `eye` is in the same patch-local frame as the vertex. t is 0 when the vertex's
/// diamond has just split (the vertex lies on the edge it splits, as drawn) and reaches 1 before
/// any vertex finer than it can start to move.
float morph_factor(const MeshVertex& v, const glm::vec3& eye, double projection_scale,
                   double threshold_px, const Geomorph& g) noexcept;
/// The drawn (morphed) height of a vertex: y + (1 - t) * morph_dy.
float morphed_height(const MeshVertex& v, const glm::vec3& eye, double projection_scale,
                     double threshold_px, const Geomorph& g) noexcept;

/// The ROAM mesh of one camera. Owns its bintree nodes, its front and its output buffers; reads
/// the shared Landscape. Two cameras are two RoamViews over one Landscape.
///
/// Threading: one thread updates a view; several views over one Landscape may update on
/// different threads at once. Output accessors must not run during update() of the same view.
///
/// Edits: update() first brings the landscape's bounds up to date (Landscape::sync()), then
/// pulls the regions changed since its last update (Landscape::changes_since()): it refreshes the
/// diamonds there and rewrites the vertices whose heights, normals or bounds changed. Nothing
/// runs inside the edit call; no view call may run during an edit.
///
/// Memory: the view's nodes and front live in arrays that grow as the mesh does (RoamMemory;
/// about 90 bytes per triangle, docs/roam.md); its patch buffers in ordinary allocations. When
/// an array cannot grow (past the RoamMemory's cap, past the address space reserved for it, or
/// refused by the system), update() returns an out-of-memory error; no exception leaves the
/// view.
class RoamView {
 public:
  /// A view of `landscape` (not null). `memory`: where its nodes and front live, shared with
  /// the other views created with it (RoamMemory); null gives the view memory of its own, given
  /// back to the system when the view is destroyed. Fails for a null landscape, invalid
  /// settings (set_settings()) or when even the root triangles find no memory.
  static Result<std::unique_ptr<RoamView>> create(std::shared_ptr<const Landscape> landscape,
                                                  const RoamSettings& settings = {},
                                                  std::shared_ptr<RoamMemory> memory = nullptr);
  ~RoamView();
  RoamView(const RoamView&) = delete;
  RoamView& operator=(const RoamView&) = delete;

  /// Changes settings; a mode or metric change rebuilds the mesh on the next update. Invalid
  /// settings are refused with a message and change nothing.
  Status set_settings(const RoamSettings& settings);
  const RoamSettings& settings() const noexcept { return settings_; }

  /// Tessellates for `camera` (ignored with ErrorMetric::kWorldMetres): splits and merges until
  /// converged or a budget stops it; what is left continues on the next update. Fails:
  /// - for an invalid camera (validate_camera()'s message): nothing changes;
  /// - when memory runs out ("roam view: out of memory: ..." naming the array, its size and
  ///   the limit reached): the mesh is reset to the root triangles (every patch comes out of
  ///   take_dirty_patches() resized) and the next update rebuilds it from the roots, so a view
  ///   whose RoamMemory cap was raised, or whose threshold was raised, carries on.
  /// Never throws.
  Result<RoamStats> update(const Camera& camera);

  /// Converges fully for a static camera (no time budget): what `ridge mesh` uses. On a paged
  /// world it waits for the pages the mesh needs (updating again until none is missing). Fails
  /// as update() does.
  Result<RoamStats> converge(const Camera& camera);

  const Landscape& landscape() const noexcept { return *landscape_; }
  std::uint32_t triangle_count() const noexcept;

  /// Patches whose mesh changed since the last call (each listed once, ascending), with their
  /// dirty ranges filled in (PatchMesh::dirty_vertices, dirty_triangles, resized).
  std::vector<std::uint32_t> take_dirty_patches();
  /// Mesh of one patch (0 .. patch_count-1): always current. Lifetime: see PatchMesh.
  const PatchMesh& patch_mesh(std::uint32_t patch) const;

  /// Calls `fn(root, heap, triangle)` for every leaf, padding included, in a deterministic order
  /// (roots in order, depth first, child 0 first).
  void for_each_leaf(
      const std::function<void(std::uint32_t, std::uint64_t, const LatticeTriangle&)>& fn) const;

  /// 64-bit hash of the leaf set (for determinism checks).
  std::uint64_t mesh_hash() const;

  /// Measured error of the mesh: |mesh height - surface height| at the lattice vertices inside
  /// `camera`'s frustum (every vertex with ErrorMetric::kWorldMetres), taking every `stride`-th
  /// vertex along each axis (1 = all; a fixed stratified sample otherwise), and the same error
  /// projected to pixels at each vertex's own distance.
  struct MeasuredError {
    double max_m = 0, rms_m = 0;    ///< metres
    double max_px = 0, p99_px = 0;  ///< pixels (0 with ErrorMetric::kWorldMetres)
    std::uint64_t vertices = 0;     ///< vertices measured
  };
  MeasuredError measure_error(const Camera& camera, std::uint32_t stride = 1) const;

  /// Checks the mesh's structural invariants: neighbour links symmetric and between leaves whose
  /// levels differ by at most one, every leaf's front entry and output slot consistent with its
  /// geometry, the triangle count. Returns an empty string when they hold, else a description of
  /// the first violation. O(triangles).
  std::string check_invariants() const;

 private:
  struct Impl;  // the view's parts (module/src/roam/view/view.h)
  RoamView() = default;
  std::shared_ptr<const Landscape> landscape_;
  RoamSettings settings_;
  std::unique_ptr<Impl> impl_;
};

struct DrawnMesh;  // mesh_error.h

/// The leaves of a ROAM view as drawn without geomorphs, straight from the bintree
/// (RoamView::for_each_leaf), in finest-lattice units of the view's terrain, each corner at its
/// lattice height (Surface::vertex_height as a float: base + detail + edits; the padding repeats
/// the edge samples): what a MeshErrorMeter measures (mesh_error.h). Needs no patch meshes. Not
/// during the view's update().
DrawnMesh leaves_mesh(const RoamView& view);

}  // namespace ridgeline
