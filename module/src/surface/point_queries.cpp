// The point queries of surface.h, each written once over the finest lattice (lattice.h): height,
// face and smooth normals, material, and their batched forms.
#include <algorithm>
#include <limits>

#include "ridgeline/surface.h"
#include "surface/lattice.h"
#include "surface/surface_eval.h"

namespace ridgeline {

namespace {

using detail::LatticePoint;

template <class Lattice>
double height_at(const Lattice& g, const LatticePoint<Lattice>& p) noexcept {
  // In the lattice's own precision (float for the stored samples), as the mesh output does.
  return g.at.height_offset +
         double(p.tri.w[0] * p.h[0] + p.tri.w[1] * p.h[1] + p.tri.w[2] * p.h[2]);
}

template <class Lattice>
glm::vec3 face_normal_at(const Lattice& g, const LatticePoint<Lattice>& p) noexcept {
  return detail::plane_normal(detail::plane_of(p.tri, p.h[0], p.h[1], p.h[2]), g.at.inv_spacing_x,
                              g.at.inv_spacing_z);
}

// Barycentric blend of the area-weighted vertex normals of the triangle under the point.
template <class Lattice>
glm::vec3 smooth_normal_at(const Lattice& g, const LatticePoint<Lattice>& p) noexcept {
  glm::vec3 n(0.0f);
  for (int k = 0; k < 3; ++k)
    n += p.tri.w[k] * detail::vertex_normal(g, p.i + p.tri.di[k], p.j + p.tri.dj[k]);
  return detail::unit(n);
}

// Locates (x, z) and, when on the footprint, returns what `answer` makes of the point.
template <class T, class Answer>
std::optional<T> at_point(const Surface& s, double x, double z, Answer&& answer) noexcept {
  return detail::with_lattice(s, [&](const auto& g) -> std::optional<T> {
    LatticePoint<std::remove_cvref_t<decltype(g)>> p;
    if (!detail::locate(g, x, z, p)) return std::nullopt;
    return answer(g, p);
  });
}

}  // namespace

std::optional<double> Surface::height(double x, double z) const noexcept {
  return at_point<double>(*this, x, z,
                          [](const auto& g, const auto& p) { return height_at(g, p); });
}

std::optional<glm::vec3> Surface::face_normal(double x, double z) const noexcept {
  return at_point<glm::vec3>(*this, x, z,
                             [](const auto& g, const auto& p) { return face_normal_at(g, p); });
}

std::optional<glm::vec3> Surface::smooth_normal(double x, double z) const noexcept {
  return at_point<glm::vec3>(*this, x, z,
                             [](const auto& g, const auto& p) { return smooth_normal_at(g, p); });
}

std::optional<std::uint8_t> Surface::material(double x, double z) const noexcept {
  return at_point<std::uint8_t>(*this, x, z,
                                [](const auto& g, const auto& p) { return g.material(p.i, p.j); });
}

std::optional<HeightNormal> Surface::height_normal(double x, double z) const noexcept {
  return at_point<HeightNormal>(*this, x, z, [](const auto& g, const auto& p) {
    return HeightNormal{height_at(g, p), face_normal_at(g, p), g.material(p.i, p.j)};
  });
}

std::optional<SurfaceSample> Surface::sample(double x, double z) const noexcept {
  return at_point<SurfaceSample>(*this, x, z, [](const auto& g, const auto& p) {
    return SurfaceSample{height_at(g, p), face_normal_at(g, p), smooth_normal_at(g, p),
                         g.material(p.i, p.j)};
  });
}

void Surface::heights(std::span<const glm::dvec2> xz, std::span<double> out) const noexcept {
  const std::size_t n = std::min(xz.size(), out.size());
  detail::with_lattice(*this, [&](const auto& g) {
    // Scattered points miss the cache on every lookup: start fetching the cell of the point
    // kAhead places on while this one is evaluated.
    constexpr std::size_t kAhead = 8;
    const SurfaceLattice& at = g.at;
    const double max_u = double(at.vertices_x - 2), max_v = double(at.vertices_z - 2);
    LatticePoint<std::remove_cvref_t<decltype(g)>> p;
    for (std::size_t k = 0; k < n; ++k) {
      if (k + kAhead < n) {
        const double u = (xz[k + kAhead].x - at.origin_x) * at.inv_spacing_x;
        const double v = (xz[k + kAhead].y - at.origin_z) * at.inv_spacing_z;
        if (u >= 0.0 && u <= max_u && v >= 0.0 && v <= max_v)
          g.prefetch(static_cast<std::int64_t>(u), static_cast<std::int64_t>(v));
      }
      out[k] = detail::locate(g, xz[k].x, xz[k].y, p) ? height_at(g, p)
                                                      : std::numeric_limits<double>::quiet_NaN();
    }
  });
}

void Surface::samples(std::span<const glm::dvec2> xz, std::span<SurfaceSample> out,
                      std::span<std::uint8_t> valid) const noexcept {
  const std::size_t n = std::min({xz.size(), out.size(), valid.size()});
  for (std::size_t k = 0; k < n; ++k) {
    const std::optional<SurfaceSample> s = sample(xz[k].x, xz[k].y);
    valid[k] = s.has_value();
    out[k] = s.value_or(SurfaceSample{});
  }
}

}  // namespace ridgeline
