// Point queries on the surface of surface.h: height, face and smooth normals, batched versions.
#include "ridgeline/terrain.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "edit/edit_layer.h"
#include "edit/edit_log.h"
#include "surface/ray_hierarchy.h"
#include "ridgeline/detail.h"
#include "surface/surface_eval.h"
#include "terrain_fine.h"

namespace ridgeline {

namespace {

/// A point located on the lattice: cell (i, j) and the triangle under the point.
struct Located {
  std::uint32_t i, j;
  CellTriangle tri;
};

}  // namespace

std::shared_ptr<Terrain> Terrain::create(Heightfield heightfield) {
  return std::shared_ptr<Terrain>(new Terrain(std::move(heightfield)));
}

Terrain::Terrain(Heightfield heightfield)
    : heightfield_(std::move(heightfield)),
      rays_(std::make_unique<RayHierarchy>(heightfield_)),
      edits_(std::make_unique<EditLayer>()),
      log_(std::make_unique<ChangeLog>()),
      base_hash_(heightfield_.content_hash()),
      inv_spacing_x_(1.0 / heightfield_.spacing_x()),
      inv_spacing_z_(1.0 / heightfield_.spacing_z()) {}

Terrain::~Terrain() = default;

// Converts world (x, z) to a cell and a triangle. Written so that NaN fails the range test.
static inline bool locate(const Heightfield& hf, double inv_sx, double inv_sz, double x, double z,
                          Located& out) noexcept {
  const double u = (x - hf.origin_x()) * inv_sx;
  const double v = (z - hf.origin_z()) * inv_sz;
  const double max_u = hf.width() - 1, max_v = hf.height() - 1;
  if (!(u >= 0.0 && u <= max_u && v >= 0.0 && v <= max_v)) return false;
  std::uint32_t i = static_cast<std::uint32_t>(u), j = static_cast<std::uint32_t>(v);
  if (i >= hf.width() - 1) i = hf.width() - 2;
  if (j >= hf.height() - 1) j = hf.height() - 2;
  out.i = i;
  out.j = j;
  out.tri = locate_in_cell(i, j, static_cast<float>(u - i), static_cast<float>(v - j));
  return true;
}

static inline float local_height(const Heightfield& hf, const Located& p) noexcept {
  const CellTriangle& t = p.tri;
  return t.w[0] * hf.local(p.i + t.di[0], p.j + t.dj[0]) +
         t.w[1] * hf.local(p.i + t.di[1], p.j + t.dj[1]) +
         t.w[2] * hf.local(p.i + t.di[2], p.j + t.dj[2]);
}

std::optional<double> Terrain::height(double x, double z) const noexcept {
  if (detail_levels_ != 0) {
    FineLocated f;
    if (!locate_fine(x, z, f)) return std::nullopt;
    return fine_height_at(f);
  }
  Located p;
  if (!locate(heightfield_, inv_spacing_x_, inv_spacing_z_, x, z, p)) return std::nullopt;
  return heightfield_.height_offset() + double(local_height(heightfield_, p));
}

std::optional<glm::vec3> Terrain::face_normal(double x, double z) const noexcept {
  if (detail_levels_ != 0) {
    FineLocated f;
    if (!locate_fine(x, z, f)) return std::nullopt;
    return fine_face_normal(f);
  }
  Located p;
  if (!locate(heightfield_, inv_spacing_x_, inv_spacing_z_, x, z, p)) return std::nullopt;
  return detail::face_normal(heightfield_, inv_spacing_x_, inv_spacing_z_, p.i, p.j, p.tri);
}

// Barycentric blend of the area-weighted vertex normals of the triangle under the point.
static glm::vec3 smooth_normal_at(const Heightfield& hf, const Located& p) noexcept {
  glm::vec3 n(0.0f);
  for (int k = 0; k < 3; ++k)
    n += p.tri.w[k] * detail::vertex_normal(hf, p.i + p.tri.di[k], p.j + p.tri.dj[k]);
  return detail::unit(n);
}

std::optional<glm::vec3> Terrain::smooth_normal(double x, double z) const noexcept {
  if (detail_levels_ != 0) {
    FineLocated f;
    if (!locate_fine(x, z, f)) return std::nullopt;
    return fine_smooth_normal(f);
  }
  Located p;
  if (!locate(heightfield_, inv_spacing_x_, inv_spacing_z_, x, z, p)) return std::nullopt;
  return smooth_normal_at(heightfield_, p);
}

std::optional<HeightNormal> Terrain::height_normal(double x, double z) const noexcept {
  if (detail_levels_ != 0) {
    FineLocated f;
    if (!locate_fine(x, z, f)) return std::nullopt;
    return HeightNormal{fine_height_at(f), fine_face_normal(f), fine_material(f)};
  }
  Located p;
  if (!locate(heightfield_, inv_spacing_x_, inv_spacing_z_, x, z, p)) return std::nullopt;
  HeightNormal s;
  s.height = heightfield_.height_offset() + double(local_height(heightfield_, p));
  s.face_normal =
      detail::face_normal(heightfield_, inv_spacing_x_, inv_spacing_z_, p.i, p.j, p.tri);
  s.material = heightfield_.material(p.i, p.j);
  return s;
}

std::optional<SurfaceSample> Terrain::sample(double x, double z) const noexcept {
  if (detail_levels_ != 0) {
    FineLocated f;
    if (!locate_fine(x, z, f)) return std::nullopt;
    return SurfaceSample{fine_height_at(f), fine_face_normal(f), fine_smooth_normal(f),
                         fine_material(f)};
  }
  Located p;
  if (!locate(heightfield_, inv_spacing_x_, inv_spacing_z_, x, z, p)) return std::nullopt;
  SurfaceSample s;
  s.height = heightfield_.height_offset() + double(local_height(heightfield_, p));
  s.face_normal =
      detail::face_normal(heightfield_, inv_spacing_x_, inv_spacing_z_, p.i, p.j, p.tri);
  s.smooth_normal = smooth_normal_at(heightfield_, p);
  s.material = heightfield_.material(p.i, p.j);
  return s;
}

void Terrain::heights(std::span<const glm::dvec2> xz, std::span<double> out) const noexcept {
  const std::size_t n = std::min(xz.size(), out.size());
  if (detail_levels_ != 0) {
    for (std::size_t k = 0; k < n; ++k)
      out[k] = height(xz[k].x, xz[k].y).value_or(std::numeric_limits<double>::quiet_NaN());
    return;
  }
  for (std::size_t k = 0; k < n; ++k) {
    Located p;
    out[k] = locate(heightfield_, inv_spacing_x_, inv_spacing_z_, xz[k].x, xz[k].y, p)
                 ? heightfield_.height_offset() + double(local_height(heightfield_, p))
                 : std::numeric_limits<double>::quiet_NaN();
  }
}

void Terrain::samples(std::span<const glm::dvec2> xz, std::span<SurfaceSample> out,
                      std::span<std::uint8_t> valid) const noexcept {
  const std::size_t n = std::min({xz.size(), out.size(), valid.size()});
  for (std::size_t k = 0; k < n; ++k) {
    auto s = sample(xz[k].x, xz[k].y);
    valid[k] = s.has_value();
    out[k] = s ? *s : SurfaceSample{};
  }
}

std::size_t Terrain::memory_bytes() const noexcept {
  return sizeof(*this) + heightfield_.memory_bytes() + rays_->memory_bytes() +
         (detail_ ? detail_->memory_bytes() : 0);
}

std::size_t Terrain::ray_hierarchy_bytes() const noexcept {
  return rays_->memory_bytes();
}

}  // namespace ridgeline
