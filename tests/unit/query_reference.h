// Shared by the surface query tests (test_point_queries.cpp, test_ray_queries.cpp,
// test_terrain.cpp): test fields, and an independent reference surface.
//
// The reference derives the triangulation from the diagonal rule's wording in docs/surface.md
// ("cell (i, j) is split along (i, j)-(i+1, j+1) when i + j is even, along (i+1, j)-(i, j+1) when
// it is odd") on its own; it does not call surface.h's rule, so a mistake there cannot hide itself.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <glm/geometric.hpp>
#include <limits>
#include <memory>
#include <vector>

#include "ridgeline/scenes.h"
#include "ridgeline/surface.h"
#include "ridgeline/terrain.h"

namespace ridgeline::test {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline constexpr double kInf = std::numeric_limits<double>::infinity();

struct FieldSpec {
  std::uint32_t w = 5, h = 5;
  double sx = 1, sz = 1, ox = 0, oz = 0, offset = 0;
};

inline std::shared_ptr<Terrain> make_editable_terrain(const FieldSpec& s,
                                               const std::function<double(int, int)>& f,
                                               std::vector<std::uint8_t> materials = {}) {
  auto hf = scenes::field({.width = s.w,
                           .height = s.h,
                           .spacing_x = s.sx,
                           .spacing_z = s.sz,
                           .origin_x = s.ox,
                           .origin_z = s.oz,
                           .height_offset = s.offset,
                           .name = "test"},
                          f, materials);
  EXPECT_TRUE(hf) << (hf ? "" : hf.error().message);
  return Terrain::create(std::move(hf).value()).value();
}

inline std::shared_ptr<const Terrain> make_terrain(const FieldSpec& s,
                                            const std::function<double(int, int)>& f,
                                            std::vector<std::uint8_t> materials = {}) {
  return make_editable_terrain(s, f, std::move(materials));
}

// ---- An independent reference surface ------------------------------------------------------

// One full-detail triangle in local coordinates: x, z in metres from sample (0, 0), y in metres
// above the height offset.
struct RefTri {
  glm::dvec3 p[3];
  int i, j;
};

// The two triangles of cell (i, j), straight from the diagonal rule's wording (docs/surface.md).
inline std::array<std::array<int, 6>, 2> spec_cell_corners(int i, int j) {
  if ((i + j) % 2 == 0)                                 // split along (i, j)-(i+1, j+1)
    return {{{0, 0, 1, 1, 1, 0}, {0, 0, 0, 1, 1, 1}}};  // (di, dj) pairs
  // split along (i+1, j)-(i, j+1)
  return {{{0, 0, 0, 1, 1, 0}, {1, 0, 0, 1, 1, 1}}};
}

struct Reference {
  const Heightfield* hf;
  double shift = 0;  // the surface raised by this much (metres)

  RefTri tri(int i, int j, int which) const {
    const auto c = spec_cell_corners(i, j)[which];
    RefTri t;
    for (int k = 0; k < 3; ++k) {
      const int vi = i + c[2 * k], vj = j + c[2 * k + 1];
      t.p[k] = {vi * hf->spacing_x(), double(hf->local(vi, vj)) + shift, vj * hf->spacing_z()};
    }
    t.i = i;
    t.j = j;
    return t;
  }
  static glm::dvec3 up_normal(const RefTri& t) {
    glm::dvec3 n = glm::cross(t.p[1] - t.p[0], t.p[2] - t.p[0]);
    return n.y < 0 ? -n : n;
  }
  // Height at local (x, z) by locating the cell and the triangle with SPEC's rule, interpolating
  // on the plane through its three corners.
  double height(double x, double z) const {
    const double u = x / hf->spacing_x(), v = z / hf->spacing_z();
    int i = std::min(int(std::floor(u)), int(hf->width()) - 2);
    int j = std::min(int(std::floor(v)), int(hf->height()) - 2);
    i = std::max(i, 0);
    j = std::max(j, 0);
    const double fu = u - i, fv = v - j;
    int which;
    if ((i + j) % 2 == 0)
      which = fu >= fv ? 0 : 1;
    else
      which = fu + fv <= 1 ? 0 : 1;
    const RefTri t = tri(i, j, which);
    const glm::dvec3 n = up_normal(t);
    return t.p[0].y - (n.x * (x - t.p[0].x) + n.z * (z - t.p[0].z)) / n.y;
  }

  // First t in [0, max_distance] where the ray is over the footprint and at or below the
  // surface; +inf when none. `o` is local, `d` unit.
  double raycast(glm::dvec3 o, glm::dvec3 d, double max_distance) const {
    const double ex = hf->extent_x(), ez = hf->extent_z();
    double t0 = 0, t1 = max_distance;
    auto clip = [&](double p, double dp, double lo, double hi) {
      if (dp == 0) return p >= lo && p <= hi;
      double a = (lo - p) / dp, b = (hi - p) / dp;
      if (a > b) std::swap(a, b);
      t0 = std::max(t0, a);
      t1 = std::min(t1, b);
      return t0 <= t1;
    };
    if (!clip(o.x, d.x, 0, ex) || !clip(o.z, d.z, 0, ez)) return kInf;
    const glm::dvec3 pe = o + d * t0;
    if (pe.y <= height(std::clamp(pe.x, 0.0, ex), std::clamp(pe.z, 0.0, ez))) return t0;
    double best = kInf;
    for_each_candidate(o, d, t0, t1, [&](const RefTri& t) {
      best = std::min(best, ray_triangle(t, o, d, t0, t1));
    });
    return best;
  }

  // Every triangle of every cell whose row the segment [t0, t1] crosses and whose column range
  // in that row (widened by a cell each way) holds the segment: conservative by construction.
  template <class F>
  void for_each_candidate(glm::dvec3 o, glm::dvec3 d, double t0, double t1, F&& f) const {
    const double sx = hf->spacing_x(), sz = hf->spacing_z();
    const int cw = int(hf->width()) - 1, ch = int(hf->height()) - 1;
    for (int j = 0; j < ch; ++j) {
      double a = t0, b = t1;
      if (d.z == 0) {
        if (o.z < j * sz - 1e-9 || o.z > (j + 1) * sz + 1e-9) continue;
      } else {
        double ta = (j * sz - 1e-9 - o.z) / d.z, tb = ((j + 1) * sz + 1e-9 - o.z) / d.z;
        if (ta > tb) std::swap(ta, tb);
        a = std::max(a, ta);
        b = std::min(b, tb);
        if (a > b) continue;
      }
      const double xa = o.x + d.x * a, xb = o.x + d.x * b;
      const int i0 = std::max(0, int(std::floor(std::min(xa, xb) / sx)) - 1);
      const int i1 = std::min(cw - 1, int(std::floor(std::max(xa, xb) / sx)) + 1);
      for (int i = i0; i <= i1; ++i)
        for (int which = 0; which < 2; ++which) f(tri(i, j, which));
    }
  }

  // Part [a, b] of [t0, t1] where the ray's xz lies in the triangle's footprint (closed, widened
  // by 1e-9 m). False when empty.
  static bool clip_to_footprint(const RefTri& t, glm::dvec3 o, glm::dvec3 d, double t0, double t1,
                                double& a, double& b) {
    a = t0;
    b = t1;
    for (int e = 0; e < 3; ++e) {
      const glm::dvec3 p = t.p[e], q = t.p[(e + 1) % 3], r = t.p[(e + 2) % 3];
      glm::dvec2 n(-(q.z - p.z), q.x - p.x);  // edge normal, turned inwards below
      if (n.x * (r.x - p.x) + n.y * (r.z - p.z) < 0) n = -n;
      n /= glm::length(n);
      // inside: n . (o + d t - p) >= -1e-9
      const double c0 = n.x * (o.x - p.x) + n.y * (o.z - p.z) + 1e-9;
      const double c1 = n.x * d.x + n.y * d.z;
      if (c1 == 0) {
        if (c0 < 0) return false;
      } else if (c1 > 0) {
        a = std::max(a, -c0 / c1);
      } else {
        b = std::min(b, -c0 / c1);
      }
    }
    return a <= b;
  }

  static double ray_triangle(const RefTri& t, glm::dvec3 o, glm::dvec3 d, double t0, double t1) {
    double a, b;
    if (!clip_to_footprint(t, o, d, t0, t1, a, b)) return kInf;
    const glm::dvec3 n = up_normal(t);
    auto f = [&](double s) { return glm::dot(n, o + d * s - t.p[0]) / n.y; };
    const double fa = f(a), fb = f(b);
    if (fa <= 0) return a;
    if (fb <= 0) return a + (b - a) * fa / (fa - fb);
    return kInf;
  }

  // Unit up normals of the triangles whose footprint (widened by `slack` metres) holds local
  // (x, z).
  std::vector<glm::dvec3> normals_at(double x, double z, double slack) const {
    std::vector<glm::dvec3> out;
    const int cw = int(hf->width()) - 1, ch = int(hf->height()) - 1;
    const int i0 = std::max(0, int(std::floor(x / hf->spacing_x())) - 1);
    const int j0 = std::max(0, int(std::floor(z / hf->spacing_z())) - 1);
    for (int j = j0; j <= std::min(ch - 1, j0 + 2); ++j)
      for (int i = i0; i <= std::min(cw - 1, i0 + 2); ++i)
        for (int w = 0; w < 2; ++w) {
          const RefTri t = tri(i, j, w);
          // Inside when on the inner side of all three edges, widened by `slack`.
          bool inside = true;
          for (int e = 0; e < 3 && inside; ++e) {
            const glm::dvec3 p = t.p[e], q = t.p[(e + 1) % 3], r = t.p[(e + 2) % 3];
            glm::dvec2 n(-(q.z - p.z), q.x - p.x);
            if (n.x * (r.x - p.x) + n.y * (r.z - p.z) < 0) n = -n;
            n /= glm::length(n);
            inside = n.x * (x - p.x) + n.y * (z - p.z) >= -slack;
          }
          if (inside) out.push_back(glm::normalize(up_normal(t)));
        }
    return out;
  }
};

inline glm::dvec3 local_of(const Heightfield& hf, glm::dvec3 w) {
  return {w.x - hf.origin_x(), w.y - hf.height_offset(), w.z - hf.origin_z()};
}

// A rough, deterministic field with flat patches, steps and smooth parts.
inline double rough(int i, int j) {
  std::uint32_t h = std::uint32_t(i) * 374761393u + std::uint32_t(j) * 668265263u;
  h = (h ^ (h >> 13)) * 1274126177u;
  const double r = double((h ^ (h >> 16)) & 0xffff) / 65535.0;
  double v = 6 * std::sin(i * 0.21) * std::cos(j * 0.17) + 3 * r;
  if (i > 40 && j > 40) v = 2.0;   // flat patch
  if (i == 20) v += 4.0;           // a wall along a column
  return std::round(v * 64) / 64;  // exactly representable heights
}

inline bool near_vec(glm::vec3 a, glm::dvec3 b, double tol) {
  return std::abs(a.x - b.x) <= tol && std::abs(a.y - b.y) <= tol && std::abs(a.z - b.z) <= tol;
}

}  // namespace ridgeline::test
