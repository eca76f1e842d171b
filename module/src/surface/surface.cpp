// The Surface (surface.h): the finest lattice over a terrain's stored samples, its edit layer and
// its procedural detail, vertex by vertex. The point queries are in point_queries.cpp.
#include "ridgeline/surface.h"

#include <algorithm>
#include <bit>
#include <cmath>

#include "ridgeline/detail.h"
#include "ridgeline/log.h"
#include "surface/edit_layer.h"
#include "surface/lattice.h"
#include "world/page_store.h"

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
const DetailSnapshot* current_snapshot(const DetailCache* cache) {
  if (!cache) return nullptr;
  thread_local std::uint64_t generation = 0;
  thread_local std::shared_ptr<const DetailSnapshot> snapshot;
  const std::uint64_t g = cache->generation();
  if (g != generation) {
    snapshot = cache->snapshot();
    generation = g;
  }
  return snapshot.get();
}

SurfaceLattice lattice_of(const WorldInfo& hf, std::uint32_t levels) {
  SurfaceLattice at;
  const int L = int(levels);
  at.levels = levels;
  at.vertices_x = (std::int64_t(hf.width - 1) << L) + 1;
  at.vertices_z = (std::int64_t(hf.height - 1) << L) + 1;
  at.spacing_x = std::ldexp(hf.spacing_x, -L);
  at.spacing_z = std::ldexp(hf.spacing_z, -L);
  at.inv_spacing_x = std::ldexp(1.0 / hf.spacing_x, L);
  at.inv_spacing_z = std::ldexp(1.0 / hf.spacing_z, L);
  at.origin_x = hf.origin_x;
  at.origin_z = hf.origin_z;
  at.height_offset = hf.height_offset;
  return at;
}

}  // namespace

Surface::Surface(std::shared_ptr<world::PageStore> store,
                 std::shared_ptr<const DetailField> detail, std::unique_ptr<DetailCache> cache)
    : store_(std::move(store)),
      edits_(std::make_unique<EditLayer>()),
      lattice_(lattice_of(store_->info(), detail ? detail->levels() : 0)),
      stored_at_(lattice_of(store_->info(), 0)),
      detail_(std::move(detail)),
      cache_(std::move(cache)),
      detail_hash_(detail_ ? hash_params(detail_->params()) : 0),
      detail_bound_(detail_ ? detail_->contribution_bound(1) : 0.0) {}

Surface::Surface(const Surface& o, CloneTag)
    : store_(o.store_->clone()),
      edits_(std::make_unique<EditLayer>(*o.edits_)),
      holes_(edits_->holes()),
      lattice_(o.lattice_),
      stored_at_(o.stored_at_),
      detail_(o.detail_),  // immutable, and bound to no terrain: shared
      detail_hash_(o.detail_hash_),
      detail_bound_(o.detail_bound_) {
  if (!detail_) return;
  // A cache of its own (the original's belongs to its owner's frame loop): synchronous, so that
  // a snapshot's queries never wait for workers it does not drive.
  DetailCacheDesc desc;
  desc.budget_bytes = std::size_t{64} << 20;
  desc.worker_threads = 0;
  auto c = DetailCache::create(detail_, desc);
  RIDGELINE_ASSERT(c.ok());       // 64 MiB holds the tiles of every level
  if (c) cache_ = std::move(*c);  // without one, detail is evaluated directly (same values)
}

Surface::~Surface() = default;

const WorldInfo& Surface::info() const noexcept { return store_->info(); }

bool Surface::hole(std::int64_t i, std::int64_t j) const noexcept {
  return holes_ != nullptr && holes_->hole(i, j);
}

std::uint64_t Surface::hole_cells() const noexcept { return holes_ ? holes_->cells() : 0; }

void Surface::publish_holes(std::shared_ptr<const HoleMask> mask) {
  edits_->set_holes(std::move(mask));
  holes_ = edits_->holes();
}

std::size_t Surface::edited_chunks() const noexcept {
  return edits_->chunks();
}

std::size_t Surface::memory_bytes() const noexcept {
  return sizeof(*this) + store_->stats().resident_bytes +
         (detail_ ? detail_->memory_bytes() : 0);
}

std::uint64_t Surface::heights_hash() const {
  const world::PageGrid& g = store_->grid();
  std::vector<std::uint64_t> pages(g.count(0));
  std::shared_ptr<const world::PageTable> keep;
  for (std::int32_t pz = 0; pz < g.pz[0]; ++pz)
    for (std::int32_t px = 0; px < g.px[0]; ++px) {
      const world::Page* p = store_->require({0, px, pz}, keep);
      pages[std::size_t(px) + std::size_t(pz) * std::size_t(g.px[0])] =
          p ? world::hash_page(*p, g, info().has_materials) : 0;
    }
  return world::combine_hashes(world::hash_header(info()), pages);
}

float Surface::stored_height(std::int64_t i, std::int64_t j) const noexcept {
  const detail::StoredLattice g = detail::stored_lattice(*this);
  return g.local(std::clamp<std::int64_t>(i, 0, g.store.grid().last_i),
                 std::clamp<std::int64_t>(j, 0, g.store.grid().last_j));
}

Result<Heightfield> Surface::to_heightfield(std::uint64_t max_samples) const {
  const WorldInfo& w = info();
  HeightfieldDesc d;
  d.width = w.width, d.height = w.height;
  d.spacing_x = w.spacing_x, d.spacing_z = w.spacing_z;
  d.origin_x = w.origin_x, d.origin_z = w.origin_z;
  d.height_offset = w.height_offset;
  d.height_scale = 1.0;
  d.max_samples = max_samples;
  d.name = w.name;
  if (auto s = validate_heightfield_desc(d); !s) return Error{s.message()};
  std::vector<float> values(std::size_t(w.width) * w.height);
  std::vector<std::uint8_t> materials;
  if (w.has_materials) materials.resize(std::size_t(w.width - 1) * (w.height - 1));
  const detail::StoredLattice g = detail::stored_lattice(*this);
  for (std::uint32_t j = 0; j < w.height; ++j)
    for (std::uint32_t i = 0; i < w.width; ++i) {
      values[i + std::size_t(j) * w.width] = g.local(i, j);
      if (!materials.empty() && i + 1 < w.width && j + 1 < w.height)
        materials[i + std::size_t(j) * (w.width - 1)] = g.material(i, j);
    }
  return Heightfield::create(d, values, materials);
}

double Surface::vertex_height(std::int64_t i, std::int64_t j) const noexcept {
  i = std::clamp<std::int64_t>(i, 0, lattice_.vertices_x - 1);
  j = std::clamp<std::int64_t>(j, 0, lattice_.vertices_z - 1);
  return detail::with_lattice(*this, [&](const auto& g) { return double(g.local(i, j)); });
}

glm::vec3 Surface::vertex_normal(std::int64_t i, std::int64_t j) const noexcept {
  i = std::clamp<std::int64_t>(i, 0, lattice_.vertices_x - 1);
  j = std::clamp<std::int64_t>(j, 0, lattice_.vertices_z - 1);
  return detail::with_lattice(*this, [&](const auto& g) { return detail::vertex_normal(g, i, j); });
}

std::uint8_t Surface::cell_material(std::int64_t i, std::int64_t j) const noexcept {
  i = std::clamp<std::int64_t>(i, 0, lattice_.vertices_x - 2);
  j = std::clamp<std::int64_t>(j, 0, lattice_.vertices_z - 2);
  return detail::with_lattice(*this, [&](const auto& g) { return g.material(i, j); });
}

double Surface::vertex_base_height(std::int64_t i, std::int64_t j) const noexcept {
  i = std::clamp<std::int64_t>(i, 0, lattice_.vertices_x - 1);
  j = std::clamp<std::int64_t>(j, 0, lattice_.vertices_z - 1);
  return detail::with_lattice(*this, [&](const auto& g) { return double(g.base(i, j)); });
}

double Surface::vertex_detail(std::int64_t i, std::int64_t j) const noexcept {
  if (!detail_) return 0.0;
  i = std::clamp<std::int64_t>(i, 0, lattice_.vertices_x - 1);
  j = std::clamp<std::int64_t>(j, 0, lattice_.vertices_z - 1);
  // The vertex first appears at level m = L - t; its detail there is its detail at every finer
  // level (docs/detail.md), so look in the level-m tile.
  const int L = int(lattice_.levels);
  const int t = std::min({i ? std::countr_zero(std::uint64_t(i)) : 64,
                          j ? std::countr_zero(std::uint64_t(j)) : 64, L});
  const auto m = static_cast<std::uint32_t>(L - t);
  if (m == 0) return 0.0;
  const std::int64_t li = i >> t, lj = j >> t;
  if (const DetailSnapshot* s = current_snapshot(cache_.get())) {
    const DetailTileKey key{m, std::int32_t(li / kDetailTileCells),
                            std::int32_t(lj / kDetailTileCells)};
    if (const DetailTile* tile = s->find(key))
      return tile->detail(std::int32_t(li - std::int64_t{key.tx} * kDetailTileCells),
                          std::int32_t(lj - std::int64_t{key.tz} * kDetailTileCells));
  }
  return detail_->detail(m, li, lj);
}

double Surface::measured_detail_bound(std::uint32_t from_level, std::int64_t i0, std::int64_t j0,
                                      std::int64_t i1, std::int64_t j1) const noexcept {
  if (!detail_ || i0 < 0 || j0 < 0) return INFINITY;
  const std::int64_t tx = i0 / kDetailTileCells, tz = j0 / kDetailTileCells;
  if (i1 > (tx + 1) * kDetailTileCells || j1 > (tz + 1) * kDetailTileCells) return INFINITY;
  const DetailSnapshot* s = current_snapshot(cache_.get());
  const DetailTile* tile =
      s ? s->find({lattice_.levels, std::int32_t(tx), std::int32_t(tz)}) : nullptr;
  return tile ? tile->measured_contribution(from_level) : INFINITY;
}

}  // namespace ridgeline
