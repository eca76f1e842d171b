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

// Height and face normal are the whole arithmetic of the fast queries: always inlined, so that
// each query compiles to one straight function on the stored lattice.
template <class Lattice>
[[gnu::always_inline]] inline double height_at(const Lattice& g,
                                               const LatticePoint<Lattice>& p) noexcept {
  // In the lattice's own precision (float for the stored samples), as the mesh output does.
  return g.at.height_offset +
         double(p.tri.w[0] * p.h[0] + p.tri.w[1] * p.h[1] + p.tri.w[2] * p.h[2]);
}

template <class Lattice>
[[gnu::always_inline]] inline glm::vec3 face_normal_at(const Lattice& g,
                                                       const LatticePoint<Lattice>& p) noexcept {
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

// What each point query makes of the located point: Answer::at(lattice, point).
struct Height {
  template <class G>
  static double at(const G& g, const LatticePoint<G>& p) noexcept {
    return height_at(g, p);
  }
};
struct FaceNormal {
  template <class G>
  static glm::vec3 at(const G& g, const LatticePoint<G>& p) noexcept {
    return face_normal_at(g, p);
  }
};
struct SmoothNormal {
  template <class G>
  static glm::vec3 at(const G& g, const LatticePoint<G>& p) noexcept {
    return smooth_normal_at(g, p);
  }
};
struct Material {
  template <class G>
  static std::uint8_t at(const G& g, const LatticePoint<G>& p) noexcept {
    return g.material(p.i, p.j);
  }
};
struct HeightAndNormal {
  template <class G>
  static HeightNormal at(const G& g, const LatticePoint<G>& p) noexcept {
    return {height_at(g, p), face_normal_at(g, p), g.material(p.i, p.j)};
  }
};
struct Everything {
  template <class G>
  static SurfaceSample at(const G& g, const LatticePoint<G>& p) noexcept {
    return {height_at(g, p), face_normal_at(g, p), smooth_normal_at(g, p), g.material(p.i, p.j)};
  }
};

// The query on one view: locate, then answer; empty off the footprint.
template <class Answer, class G>
[[gnu::always_inline]] inline auto answer_on(const G& g, double x, double z) noexcept
    -> std::optional<decltype(Answer::at(g, LatticePoint<G>{}))> {
  LatticePoint<G> p;
  if (!detail::locate(g, x, z, p)) return std::nullopt;
  auto a = Answer::at(g, p);
  if (g.missing) return std::nullopt;  // a page that could not be loaded
  return a;
}

// With detail, out of line: such a query costs microseconds, while the stored path it would
// otherwise be inlined next to costs nanoseconds and would pay for every register it needs.
template <class Answer>
[[gnu::noinline]] auto answer_on_detail(const Surface& s, double x, double z) noexcept {
  return answer_on<Answer>(detail::detail_lattice(s), x, z);
}

// Point query `Answer` at world (x, z), on whichever view the surface has.
template <class Answer>
auto point_query(const Surface& s, double x, double z) noexcept {
  if (s.detail_levels() == 0) return answer_on<Answer>(detail::stored_lattice(s), x, z);
  return answer_on_detail<Answer>(s, x, z);
}

}  // namespace

std::optional<double> Surface::height(double x, double z) const noexcept {
  return point_query<Height>(*this, x, z);
}

std::optional<glm::vec3> Surface::face_normal(double x, double z) const noexcept {
  return point_query<FaceNormal>(*this, x, z);
}

std::optional<glm::vec3> Surface::smooth_normal(double x, double z) const noexcept {
  return point_query<SmoothNormal>(*this, x, z);
}

std::optional<std::uint8_t> Surface::material(double x, double z) const noexcept {
  return point_query<Material>(*this, x, z);
}

std::optional<HeightNormal> Surface::height_normal(double x, double z) const noexcept {
  return point_query<HeightAndNormal>(*this, x, z);
}

std::optional<SurfaceSample> Surface::sample(double x, double z) const noexcept {
  return point_query<Everything>(*this, x, z);
}

void Surface::heights(std::span<const glm::dvec2> xz, std::span<double> out) const noexcept {
  const std::size_t n = std::min(xz.size(), out.size());
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  if (detail_levels() != 0) {
    for (std::size_t k = 0; k < n; ++k)
      out[k] = answer_on_detail<Height>(*this, xz[k].x, xz[k].y).value_or(kNaN);
    return;
  }
  // A copy of the placement: the stores to `out` cannot then alias it, so it stays in registers.
  const SurfaceLattice at = lattice();
  const detail::StoredLattice g = detail::stored_lattice(*this);
  const double max_u = double(at.vertices_x - 2), max_v = double(at.vertices_z - 2);
  // Scattered points miss the cache once the samples outgrow it: then start fetching the cell of
  // the point kAhead places on while this one is evaluated (clamped into the lattice,
  // branch-free; NaN goes to 0: a hint only). On samples that fit in the cache the hint only
  // costs instructions (+13 % on a 4 MiB field, -16 % time on a 16 MiB one: docs/benchmarks.md).
  constexpr std::size_t kAhead = 8;
  constexpr double kPrefetchSamples = double(std::size_t{2} << 20);
  const bool prefetch = double(at.vertices_x) * double(at.vertices_z) > kPrefetchSamples;
  const std::size_t ahead = prefetch && n > kAhead ? n - kAhead : 0;
  for (std::size_t k = 0; k < n; ++k) {
    if (k < ahead) {
      const glm::dvec2 q = xz[k + kAhead];
      const double u = std::min(max_u, std::max(0.0, (q.x - at.origin_x) * at.inv_spacing_x));
      const double v = std::min(max_v, std::max(0.0, (q.y - at.origin_z) * at.inv_spacing_z));
      g.prefetch(static_cast<std::int64_t>(u), static_cast<std::int64_t>(v));
    }
    out[k] = answer_on<Height>(g, xz[k].x, xz[k].y).value_or(kNaN);
    g.missing = false;
  }
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
