// Helpers shared by the ROAM and deformation tests.
#pragma once

#include <gtest/gtest.h>

#include <map>
#include <string>
#include <vector>

#include "ridgeline/roam_view.h"
#include "ridgeline/surface.h"

namespace ridgeline::test {

// World x / z of a finest-lattice index of a landscape's terrain.
inline double world_x(const Landscape& l, std::int64_t i) {
  const SurfaceLattice& at = l.terrain().surface().lattice();
  return at.origin_x + double(i) * at.spacing_x;
}
inline double world_z(const Landscape& l, std::int64_t j) {
  const SurfaceLattice& at = l.terrain().surface().lattice();
  return at.origin_z + double(j) * at.spacing_z;
}
// Height of finest-lattice vertex (i, j) relative to the height offset, as the mesh draws it.
inline float lattice_height(const Landscape& l, std::int64_t i, std::int64_t j) {
  return float(l.terrain().surface().vertex_height(i, j));
}

// Exact (not nested) error of a node of the stored levels against the stored lattice, brute
// force: the largest |sample - plane| over every sample inside its triangle (0 for nodes below
// the stored levels and for triangles wholly over the padding).
inline float exact_error(const Landscape& l, std::uint32_t root, std::uint64_t heap) {
  const int level = 63 - __builtin_clzll(heap);
  if (level >= int(l.base_level())) return 0.0f;
  LatticeTriangle t = l.triangle(root, heap);
  const int d = int(l.detail_levels());
  t = {t.ax >> d, t.az >> d, t.lx >> d, t.lz >> d, t.rx >> d, t.rz >> d};
  const Surface& s = l.terrain().surface();
  const std::int64_t wi = s.info().width - 1, hj = s.info().height - 1;
  const Landscape::LatticeBox b = Landscape::box_of(t);
  if (b.i0 >= wi || b.j0 >= hj) return 0.0f;
  const double ha = s.stored_height(t.ax, t.az), hl = s.stored_height(t.lx, t.lz),
               hr = s.stored_height(t.rx, t.rz);
  const double w = double((t.lx - t.ax) * (t.rz - t.az) - (t.lz - t.az) * (t.rx - t.ax));
  double worst = 0;
  for (std::int64_t j = b.j0; j <= b.j1; ++j)
    for (std::int64_t i = b.i0; i <= b.i1; ++i) {
      const double wr = double((t.lx - t.ax) * (j - t.az) - (t.lz - t.az) * (i - t.ax)) / w;
      const double wa = double((t.rx - t.lx) * (j - t.lz) - (t.rz - t.lz) * (i - t.lx)) / w;
      const double wl = 1 - wr - wa;
      if (wr < -1e-12 || wa < -1e-12 || wl < -1e-12) continue;
      const double plane = wa * ha + wl * hl + wr * hr;
      worst = std::max(worst, std::abs(double(s.stored_height(i, j)) - plane));
    }
  return float(worst);
}

inline Camera camera_at(glm::dvec3 eye, glm::dvec3 target, double fov = 60.0) {
  Camera c;
  c.eye = eye;
  c.target = target;
  c.fov_y_deg = fov;
  c.viewport = {640, 480};
  return c;
}

struct EdgeKey {
  std::int64_t a, b;
  bool operator<(const EdgeKey& o) const { return a != o.a ? a < o.a : b < o.b; }
};

// Geometric crack check, independent of the view's neighbour links: every leaf edge is shared by
// exactly two leaves, unless it lies on the landscape border (then exactly one).
inline std::string check_crack_free(const RoamView& view) {
  const Landscape& l = view.landscape();
  const std::int64_t W = l.patches_x() * l.patch_cells(), H = l.patches_z() * l.patch_cells();
  std::map<EdgeKey, int> edges;
  auto id = [&](std::int64_t i, std::int64_t j) { return i + j * (W + 1); };
  view.for_each_leaf([&](std::uint32_t, std::uint64_t, const LatticeTriangle& t) {
    const std::int64_t v[3] = {id(t.ax, t.az), id(t.lx, t.lz), id(t.rx, t.rz)};
    for (int e = 0; e < 3; ++e) {
      std::int64_t a = v[e], b = v[(e + 1) % 3];
      if (a > b) std::swap(a, b);
      ++edges[{a, b}];
    }
  });
  for (const auto& [k, n] : edges) {
    const std::int64_t ai = k.a % (W + 1), aj = k.a / (W + 1), bi = k.b % (W + 1),
                       bj = k.b / (W + 1);
    const bool border = (ai == bi && (ai == 0 || ai == W)) || (aj == bj && (aj == 0 || aj == H));
    if (n != (border ? 1 : 2))
      return "edge (" + std::to_string(ai) + "," + std::to_string(aj) + ")-(" + std::to_string(bi) +
             "," + std::to_string(bj) + ") used by " + std::to_string(n) + " triangles";
  }
  return "";
}

// Checks every `stride`-th vertex of every patch mesh against the surface the queries see:
// its height equals terrain.height() there within `tol`. Returns the vertices checked.
inline std::size_t expect_mesh_on_surface(RoamView& view, const Terrain& terrain,
                                          std::size_t stride, double tol) {
  std::size_t checked = 0;
  for (std::uint32_t p = 0; p < view.landscape().patch_count(); ++p) {
    const PatchMesh& m = view.patch_mesh(p);
    // The vertices the drawn triangles use (a slot no triangle uses holds stale data).
    std::vector<char> used(m.vertices.size(), 0);
    for (std::size_t t = 0; t + 2 < m.indices.size(); t += 3)
      if (m.indices[t] != m.indices[t + 1])
        for (int q = 0; q < 3; ++q) used[m.indices[t + q]] = 1;
    for (std::size_t k = 0; k < m.vertices.size(); k += stride) {
      if (!used[k]) continue;
      const double x = m.origin_x + m.vertices[k].x, z = m.origin_z + m.vertices[k].z;
      if (auto h = terrain.height(x, z)) {
        EXPECT_NEAR(m.origin_y + m.vertices[k].y, *h, tol) << "vertex at " << x << ", " << z;
        ++checked;
      }
    }
  }
  return checked;
}

}  // namespace ridgeline::test
