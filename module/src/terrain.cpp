// Terrain (terrain.h): the surface over its pages, the ray and box queries, residency, and the
// edit transaction's state (version, change log), composed. The point queries are the surface's
// (surface/point_queries.cpp), rays and boxes surface/ray_queries.cpp, the transaction
// edit/edit.cpp.
#include "ridgeline/terrain.h"

#include <algorithm>
#include <cmath>

#include "change_log.h"
#include "format.h"
#include "ridgeline/detail.h"
#include "surface/edit_layer.h"
#include "surface/ray_queries.h"
#include "world/page_store.h"

namespace ridgeline {

Terrain::Terrain(std::shared_ptr<world::PageStore> store,
                 std::shared_ptr<const DetailField> detail, std::unique_ptr<DetailCache> cache)
    : surface_(std::move(store), std::move(detail), std::move(cache)),
      log_(std::make_unique<ChangeLog>()),
      base_hash_(surface_.info().content_hash) {}

Terrain::Terrain(const Terrain& o, Surface::CloneTag tag)
    : surface_(o.surface_, tag),
      log_(std::make_unique<ChangeLog>(*o.log_)),
      base_hash_(o.base_hash_),
      edit_version_(o.edit_version_),
      edit_limits_(o.edit_limits_) {}

Terrain::~Terrain() = default;

namespace {

WorldInfo info_of(const Heightfield& hf, bool u16) {
  WorldInfo i;
  i.width = hf.width(), i.height = hf.height();
  i.spacing_x = hf.spacing_x(), i.spacing_z = hf.spacing_z();
  i.origin_x = hf.origin_x(), i.origin_z = hf.origin_z();
  i.height_offset = hf.height_offset(), i.height_scale = hf.height_scale();
  i.format = u16 ? SampleFormat::kU16 : SampleFormat::kF32;
  i.min_local = hf.min_local(), i.max_local = hf.max_local();
  i.has_materials = hf.has_materials();
  i.filled_samples = hf.filled_samples();
  i.name = "terrain";
  return i;
}

}  // namespace

// The field's own holes (FillPolicy::kHole) as the terrain's first hole mask: part of what the
// terrain is made of, so no version and no change-log entry.
void Terrain::take_holes(const Heightfield& hf) {
  if (hf.hole_cells().empty()) return;
  auto mask = std::make_shared<HoleMask>();
  const std::uint64_t cells_x = hf.width() - 1;
  for (const std::uint64_t c : hf.hole_cells())
    mask->set(std::int64_t(c % cells_x), std::int64_t(c / cells_x), true);
  surface_.publish_holes(std::move(mask));
}

Result<std::shared_ptr<Terrain>> Terrain::create(Heightfield heightfield) {
  auto store =
      world::PageStore::from_heightfield(heightfield, info_of(heightfield, world::fits_u16(heightfield)));
  std::shared_ptr<Terrain> t(new Terrain(std::move(store), nullptr, nullptr));
  t->take_holes(heightfield);
  return t;
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
  auto store =
      world::PageStore::from_heightfield(heightfield, info_of(heightfield, world::fits_u16(heightfield)));
  std::shared_ptr<Terrain> t(new Terrain(std::move(store), std::move(*field), std::move(*c)));
  t->take_holes(heightfield);
  return t;
}

Result<std::shared_ptr<Terrain>> Terrain::open(std::shared_ptr<const PageSource> source,
                                               const WorldCacheDesc& cache) {
  auto store = world::PageStore::open(std::move(source), cache);
  if (!store) return store.error();
  // The world's own holes, as take_holes() makes a field's: the terrain's first hole mask, and
  // the one its baked bounds were made around.
  std::shared_ptr<HoleMask> holes;
  for (const HoleRun& r : (*store)->hole_runs()) {
    if (!holes) holes = std::make_shared<HoleMask>();
    holes->set_run(r.j, r.i0, r.i1);
  }
  std::shared_ptr<Terrain> t(new Terrain(std::move(*store), nullptr, nullptr));
  if (holes) {
    t->surface_.edits_->set_baked_holes(holes);
    t->surface_.publish_holes(holes);  // immutable: shared, not copied
  }
  return t;
}

std::shared_ptr<Terrain> Terrain::clone() const {
  return std::shared_ptr<Terrain>(new Terrain(*this, Surface::CloneTag{}));
}

EditLayer& Terrain::edit_layer() noexcept { return *surface_.edits_; }
const EditLayer& Terrain::edit_layer() const noexcept { return *surface_.edits_; }

std::optional<RayHit> Terrain::raycast(const glm::dvec3& origin, const glm::dvec3& direction,
                                       double max_distance) const noexcept {
  return RayQueries::raycast(surface_, origin, direction, max_distance);
}

std::size_t Terrain::triangles_in_box(const Box& box, std::vector<SurfaceTriangle>& out,
                                      std::size_t max_triangles) const {
  return RayQueries::triangles_in_box(surface_, box, out, max_triangles);
}

std::string Terrain::check_invariants() const {
  return RayQueries::check(*surface_.store_);
}

std::size_t Terrain::memory_bytes() const noexcept {
  return sizeof(*this) - sizeof(Surface) + surface_.memory_bytes() +
         surface_.edits_->memory_bytes();
}

// ---- residency ---------------------------------------------------------------------------------

namespace {

// The level-0 pages under the xz range of `b` (empty for an invalid box or one off the data).
std::vector<PageKey> pages_under(const world::PageStore& s, const Box& b) {
  std::vector<PageKey> keys;
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(b.min[a]) || !std::isfinite(b.max[a]) || !(b.min[a] <= b.max[a]))
      return keys;
  const WorldInfo& i = s.info();
  const double u0 = (b.min.x - i.origin_x) / i.spacing_x, u1 = (b.max.x - i.origin_x) / i.spacing_x;
  const double v0 = (b.min.z - i.origin_z) / i.spacing_z, v1 = (b.max.z - i.origin_z) / i.spacing_z;
  const double umax = double(i.width - 1), vmax = double(i.height - 1);
  if (u1 < 0.0 || v1 < 0.0 || u0 > umax || v0 > vmax) return keys;
  const world::PageGrid& g = s.grid();
  const PageKey a = g.page_of(0, std::int64_t(std::clamp(u0, 0.0, umax)),
                              std::int64_t(std::clamp(v0, 0.0, vmax)));
  const PageKey c = g.page_of(0, std::int64_t(std::clamp(u1, 0.0, umax)),
                              std::int64_t(std::clamp(v1, 0.0, vmax)));
  for (std::int32_t pz = a.pz; pz <= c.pz; ++pz)
    for (std::int32_t px = a.px; px <= c.px; ++px) keys.push_back({0, px, pz});
  return keys;
}

}  // namespace

RegionPin& RegionPin::operator=(RegionPin&& o) noexcept {
  if (this != &o) {
    reset();
    store_ = std::move(o.store_);
    keys_ = std::move(o.keys_);
  }
  return *this;
}

void RegionPin::reset() noexcept {
  if (store_) store_->unpin(keys_);
  store_.reset();
  keys_.clear();
}

RegionPin Terrain::pin(const Box& region) const {
  RegionPin p;
  const world::PageStore& s = *surface_.store_;
  if (!s.paged()) return p;
  p.keys_ = pages_under(s, region);
  s.pin(p.keys_);
  p.store_ = surface_.store_;
  return p;
}

void Terrain::prefetch(const Box& region) const {
  const world::PageStore& s = *surface_.store_;
  if (!s.paged()) return;
  const std::vector<PageKey> keys = pages_under(s, region);
  s.request(keys, false);
}

void Terrain::update_pages() const { surface_.store_->update(); }

WorldStats Terrain::world_stats() const { return surface_.store_->stats(); }

bool Terrain::paged() const noexcept { return surface_.store_->paged(); }

}  // namespace ridgeline
