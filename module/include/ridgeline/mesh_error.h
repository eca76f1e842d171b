// Measured error of a drawn triangle mesh against the true surface, and popping between two drawn
// meshes: the one measurement that tests, `ridge bench lod` and `ridge report` share
// (docs/report_method.md, "Measured error").
#pragma once

#include <cstdint>
#include <glm/vec3.hpp>
#include <vector>

#include "ridgeline/camera.h"
#include "ridgeline/heightfield.h"
#include "ridgeline/terrain.h"

namespace ridgeline {

/// A triangle mesh as drawn, in the lattice frame of the surface it is measured against: each
/// corner is (u, y, v), with u and v in lattice units of that surface (world x = origin_x + u *
/// spacing_x, z likewise; for a terrain with procedural detail, its finest lattice) and y the
/// drawn world height in metres. Any winding; triangles of zero xz area are ignored. A ROAM view's
/// leaves as a DrawnMesh: leaves_mesh() (roam_view.h).
struct DrawnMesh {
  std::vector<glm::dvec3> corners;  ///< three per triangle
  std::size_t triangles() const noexcept { return corners.size() / 3; }
  void add(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
    corners.push_back(a);
    corners.push_back(b);
    corners.push_back(c);
  }
};

/// Measured error over the sampled lattice vertices (docs/report_method.md).
struct MeshError {
  double max_m = 0;             ///< largest |drawn height - surface height|, metres
  double rms_m = 0;             ///< root mean square of the same over the covered vertices, metres
  double max_px = 0;            ///< largest error projected at the vertex's own distance, pixels
  double p99_px = 0;            ///< 99th percentile of the projected error, pixels
  std::uint64_t vertices = 0;   ///< sampled vertices measured (in the frustum, or all)
  std::uint64_t uncovered = 0;  ///< of those, vertices no drawn triangle covers (holes)
};

/// A drawn mesh's height at every sampled lattice vertex of a MeshErrorMeter (row-major, NaN
/// where no triangle covers the vertex). Made by MeshErrorMeter::rasterize().
struct DrawnHeights {
  std::vector<double> heights;  ///< world metres, columns() * rows() of the meter
};

/// The true surface at a fixed set of lattice vertices, and the measurements made against it.
///
/// The sampled vertices are every `stride`-th lattice vertex along each axis, starting at 0 (all
/// of them with stride 1; a fixed stratified sample otherwise): vertex (k, l) of the sample is
/// lattice vertex (k * stride, l * stride). The lattice is a heightfield's samples, or a
/// terrain's finest lattice (spacing / 2^L with L detail levels; heights base + detail + edits as
/// Surface::vertex_height gives them).
///
/// The meter copies the surface heights when built (and when refresh() is called after an edit);
/// it keeps a pointer to the terrain or heightfield it was built from, which must outlive it.
/// Const methods may run concurrently; refresh() needs exclusive access. Bad input has defined
/// answers: a stride of 0 is taken as 1; a camera that fails validate_camera() sees no vertex
/// (every figure 0).
class MeshErrorMeter {
 public:
  /// The finest lattice of `terrain`.
  explicit MeshErrorMeter(const Terrain& terrain, std::uint32_t stride = 1);
  /// The samples of `heightfield`.
  explicit MeshErrorMeter(const Heightfield& heightfield, std::uint32_t stride = 1);

  std::uint32_t stride() const noexcept { return stride_; }
  std::uint32_t columns() const noexcept { return nx_; }  ///< sampled vertices along x
  std::uint32_t rows() const noexcept { return nz_; }     ///< sampled vertices along z
  /// Lattice vertices along x and z (the sample's lattice, before the stride).
  std::int64_t lattice_width() const noexcept { return width_; }
  std::int64_t lattice_height() const noexcept { return height_; }
  /// Metres between lattice vertices and the world position of vertex (0, 0).
  double spacing_x() const noexcept { return spacing_x_; }
  double spacing_z() const noexcept { return spacing_z_; }
  double origin_x() const noexcept { return origin_x_; }
  double origin_z() const noexcept { return origin_z_; }
  /// World position of sampled vertex (k, l) on the true surface. k < columns(), l < rows().
  glm::dvec3 position(std::uint32_t k, std::uint32_t l) const noexcept;
  /// World position of a mesh corner given in lattice units (u, y, v).
  glm::dvec3 to_world(const glm::dvec3& corner) const noexcept {
    return {origin_x_ + corner.x * spacing_x_, corner.y, origin_z_ + corner.z * spacing_z_};
  }

  /// Re-reads the surface at the sampled vertices inside lattice box [i0, i1] x [j0, j1]
  /// (clamped to the lattice), after an edit changed heights there.
  void refresh(std::int64_t i0, std::int64_t j0, std::int64_t i1, std::int64_t j1);

  /// The mesh's height at every sampled vertex: the plane of a triangle covering the vertex
  /// (borders included; on a shared edge the first triangle's value, identical on a crack-free
  /// mesh), NaN where none does. O(triangles + covered vertices).
  DrawnHeights rasterize(const DrawnMesh& mesh) const;
  /// The same into `out` (reusing its storage).
  void rasterize(const DrawnMesh& mesh, DrawnHeights& out) const;

  /// Measured error of `drawn` at the sampled vertices whose true position lies in `camera`'s
  /// Frustum, and its projection to pixels at each vertex's own distance.
  MeshError measure(const DrawnHeights& drawn, const Camera& camera) const;
  /// Measured error at every sampled vertex (no frustum, no projection: the pixel figures are
  /// 0), for view-independent meshes.
  MeshError measure_all(const DrawnHeights& drawn) const;

  /// Largest |now - before| over the sampled vertices inside `camera`'s frustum, projected in
  /// pixels at the vertex's distance in `camera`; vertices either mesh leaves uncovered are
  /// skipped. With `before_camera`, only vertices also inside that frustum count (a vertex that
  /// was out of view cannot visibly jump as it comes into view). Used for the per-vertex jump
  /// (two frames, each drawn for its own camera) and for the pop (two meshes drawn for the same
  /// camera: docs/report_method.md, "Popping").
  double jump_px(const DrawnHeights& before, const DrawnHeights& now, const Camera& camera,
                 const Camera* before_camera = nullptr) const;

  /// Triangles of `mesh` whose world bounding box is not certainly outside `camera`'s frustum
  /// (Frustum::classify_box): the triangles a renderer would not cull. Triangles of zero xz
  /// area (a renderer's unused slots) and triangles wholly beyond the lattice (over the
  /// padding) are not drawn and not counted. The one in-view count of every benchmark.
  std::uint64_t triangles_in_view(const DrawnMesh& mesh, const Camera& camera) const;

 private:
  void init(std::int64_t width, std::int64_t height, double sx, double sz, double ox, double oz,
            double offset);
  void read(std::uint32_t k0, std::uint32_t l0, std::uint32_t k1, std::uint32_t l1);
  MeshError finish(std::vector<float>& px, double sum2, MeshError out) const;

  const Terrain* terrain_ = nullptr;
  const Heightfield* heightfield_ = nullptr;
  std::uint32_t stride_ = 1, nx_ = 0, nz_ = 0;
  std::int64_t width_ = 0, height_ = 0;
  double spacing_x_ = 1, spacing_z_ = 1, origin_x_ = 0, origin_z_ = 0, offset_ = 0;
  std::vector<double> surface_;  // world heights of the sampled vertices, row-major
};

}  // namespace ridgeline
