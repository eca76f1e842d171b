// Two of the comparators the benchmarks measure ROAM against (techniques.h): a uniform grid and a
// CDLOD-like chunked quadtree (Strugar 2009), as drawn meshes (ridgeline/mesh_error.h), and a
// watertightness check for any drawn mesh.
//
// These live in Ridgeline::bench, not in Ridgeline::terrain: they exist to be measured against,
// not to be embedded. Everything here depends on the core library only (no image libraries), so
// the tests link it without OpenImageIO.
//
// Threading: every object here is used by one thread at a time; const methods may run
// concurrently.
#pragma once

#include <cstdint>
#include <glm/vec3.hpp>
#include <string>
#include <vector>

#include "ridgeline/camera.h"
#include "ridgeline/mesh_error.h"
#include "ridgeline/bench/grid.h"
#include "ridgeline/terrain.h"

namespace ridgeline::bench {

using ridgeline::DrawnMesh;


/// World height of the surface (piecewise linear over the diagonal rule, docs/surface.md) at
/// lattice coordinates (u, v), clamped into [0, W-1] x [0, H-1]. Exact sample heights at integer
/// (u, v).
double surface_height(const Grid& hf, double u, double v);

// ---- uniform grid -----------------------------------------------------------------------

/// A static regular grid of nx x nz quads over the whole sampled area (2 nx nz triangles), its
/// vertices evenly spaced (not necessarily on lattice vertices) at the surface's height there.
struct UniformGrid {
  std::uint32_t nx = 1, nz = 1;
  std::uint64_t triangles() const noexcept { return 2ull * nx * nz; }
  /// Vertex (x, y, z as floats) and 32-bit index buffer bytes a renderer would hold.
  std::uint64_t memory_bytes() const noexcept {
    return std::uint64_t(nx + 1) * (nz + 1) * 12 + triangles() * 12;
  }
  /// The grid closest to `triangles` triangles whose quads are as square as the terrain allows
  /// (at least 1 x 1, at most one quad per lattice cell... and beyond: never coarser than 1).
  static UniformGrid for_triangles(const Grid& hf, double triangles);
  DrawnMesh mesh(const Grid& hf) const { return mesh_of(vertices(hf)); }
  /// The (nx + 1) x (nz + 1) vertices, row by row, and the mesh over them.
  std::vector<glm::dvec3> vertices(const Grid& hf) const;
  DrawnMesh mesh_of(const std::vector<glm::dvec3>& vertices) const;
  /// Re-samples the heights of the vertices inside lattice range [u0, u1] x [v0, v1] (after an
  /// edit there); returns how many.
  std::size_t resample(const Grid& hf, std::vector<glm::dvec3>& vertices, double u0,
                       double v0, double u1, double v1) const;
};

// ---- CDLOD-like chunked quadtree --------------------------------------------------------

/// Continuous distance-dependent LOD (Strugar 2009): a quadtree of chunks; a chunk at level L
/// covers G * 2^L lattice cells with a G x G grid (step 2^L cells). The selection keeps a node
/// where it lies within range[L] = r0 * 2^L of the eye (sphere against the node's 3D box),
/// draws the quadrants whose children are out of their range, culls by frustum. Cracks are
/// avoided as CDLOD does, by morphing: a vertex of a level-L chunk whose grid index is odd slides
/// towards its even neighbour by morph * step, morph = clamp((d - start_L) / (range_L - start_L),
/// 0, 1) with d its unmorphed distance and start_L = range_{L-1} + 0.66 (range_L - range_{L-1});
/// at a border with a coarser chunk d >= range_L so the fine chunk has fully become the coarse
/// grid. That needs the coarser chunk's own morph to be 0 there, which holds when r0 >=
/// min_r0() (every node's 3D diagonal fits in the morph-free band); select() clamps r0 to it.
/// Heights are sampled from the surface at the morphed position (a height texture in CDLOD).
class Cdlod {
 public:
  /// `grid`: quads per chunk side, an even number >= 2.
  Cdlod(const Grid& hf, std::uint32_t grid);

  struct Chunk {
    std::uint32_t level;
    std::int64_t i0, j0;     ///< lattice cell of the node's lower corner
    std::uint8_t quadrants;  ///< bit q (q = qx + 2 qz) set: that quadrant is drawn
  };
  struct Selection {
    std::vector<Chunk> chunks;
    std::uint64_t triangles = 0;
    double r0 = 0;  ///< the range used (after clamping to min_r0)
  };
  /// Selects the chunks for `camera` with finest range r0 (metres). `cull`: frustum culling
  /// (the comparison runs with it; the coverage tests without).
  Selection select(const Camera& camera, double r0, bool cull = true) const;
  /// The drawn mesh of a selection, morphed (or not, to measure popping without geomorphs).
  DrawnMesh mesh(const Selection& s, const Camera& camera, bool morph) const;

  /// The range r0 (>= min_r0()) whose median triangle count over `frames` (every step-th frame)
  /// is closest to `target` (bisection in log r0), and that median.
  struct Match {
    double r0 = 0, median = 0;
  };
  Match match(const std::vector<Camera>& frames, double target, std::size_t step = 1) const;

  /// Recomputes the min/max heights of the nodes over lattice cells [i0, i1] x [j0, j1] after the
  /// heights there changed (an edit), and min_r0(). O(changed area + levels).
  void refresh(std::int64_t i0, std::int64_t j0, std::int64_t i1, std::int64_t j1);

  double min_r0() const noexcept { return min_r0_; }
  std::uint32_t grid() const noexcept { return grid_; }
  std::uint32_t levels() const noexcept { return levels_; }
  /// Quadtree min/max heights, the shared chunk grid's vertex and index buffers and the height
  /// texture (float per sample) a GPU implementation holds.
  std::uint64_t memory_bytes() const noexcept;

 private:
  struct Node {
    float lo, hi;
  };
  const Node& node(std::uint32_t level, std::int64_t i0, std::int64_t j0) const;
  Node compute(std::uint32_t level, std::int64_t a, std::int64_t b) const;
  void compute_min_r0();
  void box(std::uint32_t level, std::int64_t i0, std::int64_t j0, glm::dvec3* lo,
           glm::dvec3* hi) const;
  bool select_node(std::uint32_t level, std::int64_t i0, std::int64_t j0, const Frustum& f,
                   const std::vector<double>& range, bool cull, Selection& out) const;
  void emit_quadrant(const Chunk& c, int q, const Frustum& f, bool morph,
                     const std::vector<double>& range, DrawnMesh& out) const;

  Grid hf_;
  std::uint32_t grid_, levels_;  // levels_: number of levels (top = levels_ - 1)
  std::int64_t cells_x_, cells_z_;
  std::vector<std::vector<Node>> nodes_;  // per level, row-major
  std::vector<std::int64_t> per_row_;
  double min_r0_ = 0;
};

/// Checks a mesh is crack-free and covers the sampled area exactly: every edge inside the area is
/// shared by exactly two triangles (compared as exact 3D endpoints; triangles with two
/// coincident corners are skipped, triangles squeezed to zero xz area by a morph are kept, as they
/// join their neighbours like a skirt), and the triangles' xz areas add up to the area's.
/// Returns an empty string when they hold, else the first violation.
std::string check_watertight(const Grid& hf, const DrawnMesh& mesh);

}  // namespace ridgeline::bench
