// Where a view reads its diamonds from (diamond_source.h): the landscape's records in resident
// pages, detail tiles, and conservative stand-ins with requests for what is not resident.
#include "roam/view/diamond_source.h"

#include <algorithm>
#include <tuple>

#include "ridgeline/detail.h"
#include "surface/edit_layer.h"
#include "surface/lattice.h"

namespace ridgeline::roam {

DiamondSource::DiamondSource(const Landscape& landscape)
    : landscape_(landscape),
      patch_log2_(landscape.patch_log2()),
      step_x_m_(float(LandscapeAccess::spacing_x(landscape))),
      step_z_m_(float(LandscapeAccess::spacing_z(landscape))),
      cache_(landscape.terrain().surface().detail_cache()) {}

void DiamondSource::open_pages() {
  const Surface& s = landscape_.terrain().surface();
  reader_ = Reader(landscape_, detail::SurfaceAccess::store(s).snapshot(),
                   detail::SurfaceAccess::edits(s).hole_snapshot());
}

void DiamondSource::begin_update(bool world_metric) {
  world_metric_ = world_metric;
  if (cache_ != nullptr) {
    cache_->update();  // integrate tiles generated since the last frame
    snapshot_ = cache_->snapshot();
  }
  landscape_.terrain().update_pages();  // integrate pages loaded since the last frame, evict
  open_pages();
  page_requests_.clear();
}

bool DiamondSource::detail_tile_of(std::int64_t i, std::int64_t j,
                                   DetailTileKey& key) const noexcept {
  const int levels = int(landscape_.detail_levels());
  const int t = std::min({ctz64(i), ctz64(j), levels});
  if (t >= levels) return false;
  key = DetailTileKey{std::uint32_t(levels - t), std::int32_t((i >> t) / kDetailTileCells),
                      std::int32_t((j >> t) / kDetailTileCells)};
  return true;
}

EntryData DiamondSource::read_not_resident(std::int64_t i, std::int64_t j) const {
  DiamondBound b;
  float y;
  switch (reader_.stored(i, j, b, y)) {
    case Reader::Vertex::kResident:
      return {float(i) * step_x_m_, y, float(j) * step_z_m_, world_metric_ ? b.error : b.morph,
              b.radius, false};
    case Reader::Vertex::kMissing: {
      // Its page is not resident: the sphere and bound of the nearest resident ancestor, which
      // hold this diamond's (nested), so the test stays conservative until the page arrives.
      std::int64_t ci = i, cj = j;
      for (;;) {
        const Diamond d = diamond_at(ci, cj, patch_log2_);
        if (d.corner || d.top) break;
        std::int64_t ax, az, bx, bz;
        d.apexes(ax, az, bx, bz);
        for (const auto& p : {std::pair{ax, az}, std::pair{bx, bz}}) {
          if (p.first < 0 || p.second < 0 || diamond_at(p.first, p.second, patch_log2_).corner)
            continue;
          DiamondBound pb;
          float py;
          if (reader_.stored(p.first, p.second, pb, py) == Reader::Vertex::kResident) {
            const float bound = world_metric_ ? pb.error : pb.morph;
            return {float(p.first) * step_x_m_, py, float(p.second) * step_z_m_, bound,
                    pb.radius, true};
          }
        }
        ci = ax, cj = az;  // one level up
        if (ci < 0 || cj < 0) ci = bx, cj = bz;
      }
      // Nothing resident above (cannot happen while the coarse levels are): always split.
      return {float(i) * step_x_m_, 0.0f, float(j) * step_z_m_, 0.0f, Front::kBorderRadius, true};
    }
    case Reader::Vertex::kDetail:
      break;
  }
  b = LandscapeAccess::compute_detail(landscape_, i, j);
  EntryData v{float(i) * step_x_m_, 0.0f,     float(j) * step_z_m_,
              world_metric_ ? b.error : b.morph, b.radius, false};
  DetailTileKey key;
  if (snapshot_ != nullptr && detail_tile_of(i, j, key) && snapshot_->find(key) == nullptr) {
    // Its height is the stored surface's plus an unknown detail: widen the sphere by the
    // detail's bound so that it holds every height the vertex may have.
    v.provisional = true;
    v.y = static_cast<float>(landscape_.terrain().surface().vertex_base_height(i, j));
    if (v.radius < Front::kBorderRadius)
      v.radius += LandscapeAccess::detail_offset_bound(landscape_, i, j);
    return v;
  }
  v.y = static_cast<float>(landscape_.terrain().surface().vertex_height(i, j));
  return v;
}

bool DiamondSource::request_vertex(std::int64_t i, std::int64_t j) {
  DetailTileKey key;
  if (detail_tile_of(i, j, key)) {
    if (cache_ == nullptr || (snapshot_ != nullptr && snapshot_->find(key) != nullptr))
      return true;
    return cache_->request(key);
  }
  DiamondBound b;
  float y;
  PageKey missing;
  if (reader_.stored(i, j, b, y, &missing) == Reader::Vertex::kMissing) {
    page_requests_.push_back(missing);
    return false;
  }
  return true;
}

bool DiamondSource::request_shading(std::int64_t i, std::int64_t j) {
  if (reader_.address(i, j) != nullptr || landscape_.detail_levels() != 0) return true;
  DiamondBound b;
  float y;
  PageKey missing;
  if (reader_.stored(i, j, b, y, &missing) == Reader::Vertex::kMissing) {
    page_requests_.push_back(missing);
    return false;
  }
  return true;
}

std::uint32_t DiamondSource::send_page_requests() {
  if (page_requests_.empty()) return 0;
  std::sort(page_requests_.begin(), page_requests_.end(), [](const PageKey& a, const PageKey& b) {
    return std::tie(a.level, a.pz, a.px) < std::tie(b.level, b.pz, b.px);
  });
  page_requests_.erase(std::unique(page_requests_.begin(), page_requests_.end()),
                       page_requests_.end());
  detail::SurfaceAccess::store(landscape_.terrain().surface()).request(page_requests_, true);
  return std::uint32_t(page_requests_.size());
}

}  // namespace ridgeline::roam
