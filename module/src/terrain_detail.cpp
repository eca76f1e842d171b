// A Terrain with procedural detail: the finest lattice (spacing / 2^L) whose vertex heights are
// base + detail (docs/surface.md, "Detail and edits"), and the point queries on it.
#include <algorithm>
#include <bit>
#include <cmath>

#include "edit/edit_layer.h"
#include "format.h"
#include "surface/ray_hierarchy.h"
#include "ridgeline/detail.h"
#include "ridgeline/terrain.h"
#include "surface/surface_eval.h"
#include "terrain_fine.h"

namespace ridgeline {

namespace {

std::uint64_t hash_params(const DetailParams& p) {
  std::uint64_t h = 1469598103934665603ull;
  auto mix = [&](const void* data, std::size_t n) {
    const auto* b = static_cast<const unsigned char*>(data);
    for (std::size_t k = 0; k < n; ++k) h = (h ^ b[k]) * 1099511628211ull;
  };
  mix(&p.levels, sizeof p.levels);
  mix(&p.seed, sizeof p.seed);
  for (double v : {p.amplitude, p.gain, p.flat_shape, p.steep_shape, p.flat_slope, p.steep_slope})
    mix(&v, sizeof v);
  mix(&p.blur_radius, sizeof p.blur_radius);
  return h == 0 ? 1 : h;  // 0 means "no detail" in save files
}

// The cache's current snapshot, kept per thread and refreshed only when the cache publishes a
// new one (one atomic load per call; no lock, no shared counter written).
const DetailSnapshot* current_snapshot(const DetailCache& cache) {
  thread_local std::uint64_t generation = 0;
  thread_local std::shared_ptr<const DetailSnapshot> snapshot;
  const std::uint64_t g = cache.generation();
  if (g != generation) {
    snapshot = cache.snapshot();
    generation = g;
  }
  return snapshot.get();
}

// A terrain's finest lattice seen as a grid, for the vertex-normal template of surface_eval.h.
struct FineGrid {
  const Terrain& t;
  double spacing_x() const {
    return std::ldexp(t.heightfield().spacing_x(), -int(t.detail_levels()));
  }
  double spacing_z() const {
    return std::ldexp(t.heightfield().spacing_z(), -int(t.detail_levels()));
  }
  std::int64_t width() const { return t.fine_width(); }
  std::int64_t height() const { return t.fine_height(); }
  double local(std::uint32_t i, std::uint32_t j) const { return t.fine_local_height(i, j); }
};

}  // namespace

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
  std::shared_ptr<Terrain> t = create(std::move(heightfield));
  if (detail.levels == 0) return t;
  auto field = DetailField::create_for(*t, detail);
  if (!field) return field.error();
  auto c = DetailCache::create(*field, cache);
  if (!c) return c.error();
  t->detail_ = std::move(*field);
  t->cache_ = std::move(*c);
  t->detail_levels_ = detail.levels;
  t->detail_hash_ = hash_params(detail);
  return t;
}

std::int64_t Terrain::fine_width() const noexcept {
  return (std::int64_t(heightfield_.width() - 1) << detail_levels_) + 1;
}
std::int64_t Terrain::fine_height() const noexcept {
  return (std::int64_t(heightfield_.height() - 1) << detail_levels_) + 1;
}

double Terrain::detail_at(std::int64_t i, std::int64_t j) const noexcept {
  if (detail_levels_ == 0) return 0.0;
  i = std::clamp<std::int64_t>(i, 0, fine_width() - 1);
  j = std::clamp<std::int64_t>(j, 0, fine_height() - 1);
  // The vertex first appears at level m = L - t; its detail there is its detail at every finer
  // level (docs/detail.md), so look in the level-m tile.
  const int L = int(detail_levels_);
  const int t = std::min({i ? std::countr_zero(std::uint64_t(i)) : 64,
                          j ? std::countr_zero(std::uint64_t(j)) : 64, L});
  const auto m = static_cast<std::uint32_t>(L - t);
  if (m == 0) return 0.0;
  const std::int64_t li = i >> t, lj = j >> t;
  if (const DetailSnapshot* s = current_snapshot(*cache_)) {
    const DetailTileKey key{m, std::int32_t(li / kDetailTileCells),
                            std::int32_t(lj / kDetailTileCells)};
    if (const DetailTile* tile = s->find(key))
      return tile->detail(std::int32_t(li - std::int64_t{key.tx} * kDetailTileCells),
                          std::int32_t(lj - std::int64_t{key.tz} * kDetailTileCells));
  }
  return detail_->detail(m, li, lj);
}

double Terrain::measured_detail_bound(std::uint32_t from_level, std::int64_t i0, std::int64_t j0,
                                      std::int64_t i1, std::int64_t j1) const noexcept {
  if (detail_levels_ == 0 || i0 < 0 || j0 < 0) return INFINITY;
  const std::int64_t tx = i0 / kDetailTileCells, tz = j0 / kDetailTileCells;
  if (i1 > (tx + 1) * kDetailTileCells || j1 > (tz + 1) * kDetailTileCells) return INFINITY;
  const DetailSnapshot* s = current_snapshot(*cache_);
  const DetailTile* tile =
      s ? s->find({detail_levels_, std::int32_t(tx), std::int32_t(tz)}) : nullptr;
  return tile ? tile->measured_contribution(from_level) : INFINITY;
}

double Terrain::fine_local_height(std::int64_t i, std::int64_t j) const noexcept {
  const Heightfield& hf = heightfield_;
  const int L = int(detail_levels_);
  i = std::clamp<std::int64_t>(i, 0, fine_width() - 1);
  j = std::clamp<std::int64_t>(j, 0, fine_height() - 1);
  if (L == 0) return hf.local(std::uint32_t(i), std::uint32_t(j));
  const std::int64_t mask = (std::int64_t{1} << L) - 1;
  std::int64_t k = i >> L, m = j >> L, fi = i & mask, fj = j & mask;
  // The far edge belongs to the last cell (fraction 1), as in the point queries.
  if (k == hf.width() - 1) --k, fi = mask + 1;
  if (m == hf.height() - 1) --m, fj = mask + 1;
  const float fu = std::ldexp(float(fi), -L), fv = std::ldexp(float(fj), -L);  // exact
  const detail::CellPlane plane =
      detail::cell_plane(hf, std::uint32_t(k), std::uint32_t(m), locate_in_cell(k, m, fu, fv));
  return plane.at(fu, fv) + detail_at(i, j);
}

bool Terrain::locate_fine(double x, double z, FineLocated& p) const noexcept {
  const int L = int(detail_levels_);
  const double u = std::ldexp((x - heightfield_.origin_x()) * inv_spacing_x_, L);
  const double v = std::ldexp((z - heightfield_.origin_z()) * inv_spacing_z_, L);
  const double max_u = double(fine_width() - 1), max_v = double(fine_height() - 1);
  if (!(u >= 0.0 && u <= max_u && v >= 0.0 && v <= max_v)) return false;  // NaN fails too
  p.i = std::min(static_cast<std::int64_t>(u), fine_width() - 2);
  p.j = std::min(static_cast<std::int64_t>(v), fine_height() - 2);
  p.tri = locate_in_cell(p.i, p.j, static_cast<float>(u - double(p.i)),
                         static_cast<float>(v - double(p.j)));
  for (int k = 0; k < 3; ++k) p.h[k] = fine_local_height(p.i + p.tri.di[k], p.j + p.tri.dj[k]);
  return true;
}

double Terrain::fine_height_at(const FineLocated& p) const noexcept {
  return heightfield_.height_offset() +
         (p.tri.w[0] * p.h[0] + p.tri.w[1] * p.h[1] + p.tri.w[2] * p.h[2]);
}

glm::vec3 Terrain::fine_face_normal(const FineLocated& p) const noexcept {
  const int L = int(detail_levels_);
  return detail::plane_normal(detail::plane_of(p.tri, p.h[0], p.h[1], p.h[2]),
                              std::ldexp(inv_spacing_x_, L), std::ldexp(inv_spacing_z_, L));
}

glm::vec3 Terrain::fine_smooth_normal(const FineLocated& p) const noexcept {
  const FineGrid grid{*this};
  glm::vec3 n(0.0f);
  for (int k = 0; k < 3; ++k)
    n += p.tri.w[k] * detail::vertex_normal(grid, std::uint32_t(p.i + p.tri.di[k]),
                                            std::uint32_t(p.j + p.tri.dj[k]));
  return detail::unit(n);
}

glm::vec3 Terrain::lattice_vertex_normal(std::int64_t i, std::int64_t j) const noexcept {
  i = std::clamp<std::int64_t>(i, 0, fine_width() - 1);
  j = std::clamp<std::int64_t>(j, 0, fine_height() - 1);
  if (detail_levels_ == 0)
    return detail::vertex_normal(heightfield_, std::uint32_t(i), std::uint32_t(j));
  return detail::vertex_normal(FineGrid{*this}, std::uint32_t(i), std::uint32_t(j));
}

std::uint8_t Terrain::fine_material(const FineLocated& p) const noexcept {
  const int L = int(detail_levels_);
  return heightfield_.material(std::min(std::uint32_t(p.i >> L), heightfield_.width() - 2),
                               std::min(std::uint32_t(p.j >> L), heightfield_.height() - 2));
}

}  // namespace ridgeline
