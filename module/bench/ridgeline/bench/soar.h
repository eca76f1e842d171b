// A stateless SOAR refinement (Lindstrom & Pascucci, "Visualization of Large Terrains Made Easy",
// IEEE Visualization 2001, and "Terrain Simplification Simplified", IEEE TVCG 2002): the strongest
// stateless comparator for ROAM. Longest-edge bisection over the 4-8 hierarchy of a (2^n + 1)^2
// vertex grid; each vertex carries a world-space error and a bounding-sphere radius made nested
// in a preprocess (a vertex's values are at least those of every descendant), so one top-down
// pass per frame, testing (kappa e + r)^2 > d^2, yields a conforming mesh without neighbour links
// or forced splits, and emits it as one generalised triangle strip while it recurses. The nested
// spheres also cull against the view frustum: a vertex whose sphere is outside is not refined.
//
// kappa is the inverse of the error tolerance in radians (the nu of SOAR implementations such as
// Cafu's TerrainT): kappa = projection_scale(camera) / threshold_px, so a threshold in pixels means
// what it means for ROAM (a world error e at distance d projects to e * projection_scale / d px).
//
// A yardstick, not a feature: it lives in Ridgeline::bench (docs/report_method.md, "SOAR").
#pragma once

#include <cstdint>
#include <vector>

#include "ridgeline/camera.h"
#include "ridgeline/heightfield.h"
#include "ridgeline/bench/grid.h"
#include "ridgeline/mesh_error.h"

namespace ridgeline::bench {

class Soar {
 public:
  /// Largest lattice side the comparator takes (vertex indices are 32-bit; 8193^2 vertices hold
  /// 1.3 GB of vertex records).
  static constexpr std::uint32_t kMaxSide = 8193;

  /// Builds the vertex data of `hf` (or of a terrain's finest lattice baked into one): a grid of
  /// (2^n + 1)^2 vertices covering it (the smallest such; samples beyond the heightfield repeat
  /// its edge samples, the padding rule), their heights, and the nested errors and radii.
  /// Precondition: both sides of `hf` at most kMaxSide (callers check: SoarTechnique::create).
  explicit Soar(const Grid& hf);

  /// Result of one refinement.
  struct Frame {
    std::uint64_t triangles = 0;  ///< leaf triangles of the whole grid (non-degenerate in strip)
    double kappa = 0;             ///< the kappa used, 1/radians
  };
  /// Refines for `camera` with tolerance kappa (1/radians; +infinity: to the finest level) and
  /// writes the mesh as a generalised triangle strip of vertex indices (index = x + y * size())
  /// into `strip` (its storage reused). `cull`: nested-sphere frustum culling (the comparison
  /// runs with it). This is the timed per-frame work: refinement and emission in one pass.
  Frame refine(const Camera& camera, double kappa, std::vector<std::uint32_t>& strip,
               bool cull = true) const;
  /// Leaf triangles only, no strip (for calibrating kappa).
  std::uint64_t count(const Camera& camera, double kappa, bool cull = true) const;

  /// kappa for a threshold in pixels: projection_scale(camera) / threshold (+infinity at 0).
  static double kappa_for(const Camera& camera, double threshold_px);
  /// The kappa whose median triangle count over `frames` (every step-th) is closest to
  /// `target` (bisection in log kappa) and that median: how `--triangles N` picks kappa, once per
  /// path.
  struct Match {
    double kappa = 0, median = 0;
  };
  Match match(const std::vector<Camera>& frames, double target, std::size_t step = 1) const;

  /// The strip's triangles (degenerate ones skipped) in lattice units of `hf`'s samples.
  DrawnMesh mesh(const std::vector<std::uint32_t>& strip) const;

  std::uint32_t size() const noexcept { return size_; }  ///< vertices per side: 2^n + 1
  /// Bytes of the vertex data (positions, errors, radii) a renderer and the refinement hold.
  std::uint64_t memory_bytes() const noexcept { return vertices_.size() * sizeof(Vertex); }

 private:
  struct Vertex {
    float x, y, z;  // position relative to the heightfield's origin (x, z) and offset (y), metres
    float e, r;     // nested error (metres) and bounding-sphere radius (metres)
  };
  struct Pass;
  void nest(std::uint32_t level, std::uint32_t apex, std::uint32_t left, std::uint32_t right,
            std::uint32_t depth);

  std::uint32_t size_ = 0, levels_ = 0;  // levels_: bisection levels below a root
  double origin_x_ = 0, origin_z_ = 0, offset_ = 0, spacing_x_ = 1, spacing_z_ = 1;
  std::vector<Vertex> vertices_;
};

}  // namespace ridgeline::bench
