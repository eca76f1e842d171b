// Terrain (terrain.h): the surface, the ray hierarchy over it and the edit transaction's state
// (version, change log), composed. The queries are the surface's (surface/point_queries.cpp) and
// the ray hierarchy's (surface/ray_hierarchy.cpp); the transaction is in edit/edit.cpp.
#include "ridgeline/terrain.h"

#include <algorithm>

#include "edit/edit_layer.h"
#include "edit/edit_log.h"
#include "format.h"
#include "ridgeline/detail.h"
#include "surface/ray_hierarchy.h"

namespace ridgeline {

Terrain::Terrain(Heightfield heightfield, std::shared_ptr<const DetailField> detail,
                 std::unique_ptr<DetailCache> cache)
    : surface_(std::move(heightfield), std::move(detail), std::move(cache)),
      rays_(std::make_unique<RayHierarchy>(surface_.heightfield())),
      log_(std::make_unique<ChangeLog>()),
      base_hash_(surface_.heights_hash()) {}

Terrain::Terrain(const Terrain& o, Surface::CloneTag tag)
    : surface_(o.surface_, tag),
      rays_(std::make_unique<RayHierarchy>(*o.rays_)),
      log_(std::make_unique<ChangeLog>(*o.log_)),
      base_hash_(o.base_hash_),
      edit_version_(o.edit_version_) {}

Terrain::~Terrain() = default;

std::shared_ptr<Terrain> Terrain::create(Heightfield heightfield) {
  return std::shared_ptr<Terrain>(new Terrain(std::move(heightfield), nullptr, nullptr));
}

Result<std::shared_ptr<Terrain>> Terrain::create(Heightfield heightfield,
                                                 const DetailParams& detail,
                                                 const DetailCacheDesc& cache) {
  if (auto s = validate_detail_params(detail); !s) return Error{s.message()};
  const std::uint64_t fw = std::uint64_t(heightfield.width() - 1) << detail.levels;
  const std::uint64_t fh = std::uint64_t(heightfield.height() - 1) << detail.levels;
  if (std::max(fw, fh) >= (std::uint64_t{1} << 30))
    return Error{
        fmt("detail: %u levels over %u x %u samples make a finest lattice of %llu cells "
            "per side; at most 2^30 (use fewer levels)",
            detail.levels, heightfield.width(), heightfield.height(),
            static_cast<unsigned long long>(std::max(fw, fh)))};
  if (detail.levels == 0) return create(std::move(heightfield));
  auto field = DetailField::create(heightfield, detail);
  if (!field) return field.error();
  auto c = DetailCache::create(*field, cache);
  if (!c) return c.error();
  return std::shared_ptr<Terrain>(
      new Terrain(std::move(heightfield), std::move(*field), std::move(*c)));
}

std::shared_ptr<Terrain> Terrain::clone() const {
  return std::shared_ptr<Terrain>(new Terrain(*this, Surface::CloneTag{}));
}

std::optional<RayHit> Terrain::raycast(const glm::dvec3& origin, const glm::dvec3& direction,
                                       double max_distance) const noexcept {
  return rays_->raycast(surface_, origin, direction, max_distance);
}

std::size_t Terrain::triangles_in_box(const Box& box, std::vector<SurfaceTriangle>& out,
                                      std::size_t max_triangles) const {
  return rays_->triangles_in_box(surface_, box, out, max_triangles);
}

std::string Terrain::check_invariants() const {
  return rays_->compare(RayHierarchy(surface_.heightfield()));
}

std::size_t Terrain::memory_bytes() const noexcept {
  return sizeof(*this) - sizeof(Surface) + surface_.memory_bytes() + rays_->memory_bytes();
}

std::size_t Terrain::ray_hierarchy_bytes() const noexcept {
  return rays_->memory_bytes();
}

}  // namespace ridgeline
