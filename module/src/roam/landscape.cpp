// Landscape (landscape.h): patches, bintree geometry, and the tessellator's bounds held with the
// terrain's pages (records.h): made here for a terrain in memory, decoded and completed as pages
// arrive for a baked world, refreshed by edits (Terrain::apply_edit calls the record maker).
// Below the stored resolution (procedural detail) the bounds come from closed forms over the
// detail field's amplitude bounds (compute_detail()).
#include "ridgeline/landscape.h"

#include <algorithm>
#include <bit>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <thread>

#include "format.h"
#include "ridgeline/detail.h"
#include "ridgeline/log.h"
#include "ridgeline/surface.h"
#include "roam/diamond.h"
#include "roam/landscape_access.h"
#include "roam/records.h"
#include "surface/edit_layer.h"
#include "surface/lattice.h"
#include "world/page_store.h"

namespace ridgeline {

using detail::fmt;
using roam::Diamond;
using roam::diamond_at;
using roam::LandscapeAccess;
using roam::RecordBlock;

namespace {

// Bits set in x, inline (without -mpopcnt the builtin is a libgcc call).
constexpr int popcount64(std::uint64_t x) noexcept {
  x -= (x >> 1) & 0x5555555555555555ull;
  x = (x & 0x3333333333333333ull) + ((x >> 2) & 0x3333333333333333ull);
  x = (x + (x >> 4)) & 0x0f0f0f0f0f0f0f0full;
  return int((x * 0x0101010101010101ull) >> 56);
}

// The heights of a store's level-0 pages by stored index (clamped into the data), reading the
// current snapshot and loading what is missing.
roam::Heights paged_heights(const world::PageStore& store) {
  roam::Heights h;
  h.last_i = store.grid().last_i, h.last_j = store.grid().last_j;
  h.fn = [&store](std::int64_t i, std::int64_t j) {
    const detail::StoredLattice g(store, SurfaceLattice{});
    return g.local(i, j);
  };
  return h;
}

// Makes the bounds of one configuration for pages as they arrive, and after edits.
class Maker final : public world::RecordMaker {
 public:
  Maker(const world::PageStore& store, roam::RecordConfig cfg, int slot_hint)
      : store_(store), cfg_(std::move(cfg)), slot_(slot_hint) {}
  void set_slot(int s) { slot_ = s; }

  std::shared_ptr<const RecordBlock> make(const world::Page& page) const override {
    if (page.key.level > 0) {
      if (!page.baked) return nullptr;
      auto b = RecordBlock::decode(page.key.level, page.baked);
      if (!b)
        log_message(LogLevel::kError,
            fmt("%s: page (%u, %d, %d): its tessellator bounds are damaged",
                store_.info().name.c_str(), page.key.level, page.key.px, page.key.pz));
      return b;
    }
    return roam::level0_block(cfg_, page);
  }
  std::size_t bytes(const RecordBlock& b) const noexcept override { return b.bytes(); }
  std::vector<std::pair<PageKey, std::shared_ptr<const RecordBlock>>> remake(
      const world::PageStore& store, std::int64_t i0, std::int64_t j0, std::int64_t i1,
      std::int64_t j1) const override {
    const std::shared_ptr<const world::PageTable> t = store.snapshot();
    const int slot = slot_;
    return roam::remake(
        cfg_, store.grid(), paged_heights(store),
        [&](const PageKey& k) -> const world::Page* {
          std::shared_ptr<const world::PageTable> keep;
          return store.require(k, keep);
        },
        [&, slot](const PageKey& k) -> const RecordBlock* {
          std::shared_ptr<const world::PageTable> keep;
          const world::Page* p = store.require(k, keep);
          return p ? p->records[std::size_t(slot)].get() : nullptr;
        },
        i0, j0, i1, j1);
  }

 private:
  const world::PageStore& store_;
  roam::RecordConfig cfg_;
  int slot_;
};

}  // namespace

Landscape::~Landscape() {
  if (impl_ && impl_->slot >= 0)
    const_cast<world::PageStore*>(impl_->store)->remove_slot(impl_->slot);
}

// ---- geometry -------------------------------------------------------------------------------

LatticeTriangle Landscape::triangle(std::uint32_t root, std::uint64_t heap) const noexcept {
  const std::uint32_t patch = root / 2;
  const std::int64_t p = patch_cells();
  const std::int64_t ox = std::int64_t(patch % patches_x_) * p;
  const std::int64_t oz = std::int64_t(patch / patches_x_) * p;
  LatticeTriangle t = (root & 1) == 0 ? LatticeTriangle{ox + p, oz, ox, oz, ox + p, oz + p}
                                      : LatticeTriangle{ox, oz + p, ox + p, oz + p, ox, oz};
  const int depth = int(std::bit_width(heap)) - 1;
  for (int bit = depth - 1; bit >= 0; --bit) t = child_triangle(t, int((heap >> bit) & 1));
  return t;
}

LatticeTriangle LandscapeAccess::triangle_at(const Landscape& l, std::int64_t ax,
                                             std::int64_t az, std::uint32_t root,
                                             std::uint64_t heap) noexcept {
  // The direction from the apex to the hypotenuse midpoint turns by 135 degrees per level and
  // back by 90 for every child 1 on the path: an index into eight compass directions.
  static constexpr int kUx[8] = {1, 1, 0, -1, -1, -1, 0, 1};
  static constexpr int kUz[8] = {0, 1, 1, 1, 0, -1, -1, -1};
  const int level = int(std::bit_width(heap)) - 1;
  const int k = (((root & 1) ? 7 : 3) + 3 * level + 2 * (popcount64(heap) - 1)) & 7;
  const std::int64_t s2 = l.patch_cells() >> (level / 2);  // twice the apex-midpoint distance
  const std::int64_t ux = kUx[k], uz = kUz[k], px = -uz, pz = ux;  // p: u turned +90 degrees
  return {ax,
          az,
          ax + (ux + px) * s2 / 2,
          az + (uz + pz) * s2 / 2,
          ax + (ux - px) * s2 / 2,
          az + (uz - pz) * s2 / 2};
}

Landscape::LatticeBox Landscape::box_of(const LatticeTriangle& t) noexcept {
  return {std::min({t.ax, t.lx, t.rx}), std::max({t.ax, t.lx, t.rx}), std::min({t.az, t.lz, t.rz}),
          std::max({t.az, t.lz, t.rz})};
}

double LandscapeAccess::local_extent(const Landscape& l) noexcept {
  const WorldInfo& hf = l.terrain().info();
  const Surface& s = l.terrain().surface();
  const double h = std::max(std::abs(double(hf.min_local)), std::abs(double(hf.max_local))) +
                   (l.detail_levels() > 0 ? s.detail()->contribution_bound(1) : 0.0);
  return std::max({double(l.patches_x() * l.patch_cells()) * l.impl_->spacing_x,
                   double(l.patches_z() * l.patch_cells()) * l.impl_->spacing_z, h});
}

// ---- bounds ----------------------------------------------------------------------------------

DiamondBound Landscape::diamond(std::int64_t i, std::int64_t j) const noexcept {
  if (diamond_at(i, j, patch_log2()).corner) return {};
  const roam::Reader r(*this, impl_->store->snapshot());
  DiamondBound b;
  float y;
  PageKey missing;
  switch (r.stored(i, j, b, y, &missing)) {
    case roam::Reader::Vertex::kResident:
      return b;
    case roam::Reader::Vertex::kDetail:
      return LandscapeAccess::compute_detail(*this, i, j);
    case roam::Reader::Vertex::kMissing: {
      std::shared_ptr<const world::PageTable> keep;
      if (impl_->store->require(missing, keep) == nullptr) return {};
      const roam::Reader again(*this, impl_->store->snapshot());
      return again.stored(i, j, b, y) == roam::Reader::Vertex::kResident ? b : DiamondBound{};
    }
  }
  return {};
}

float Landscape::bound(std::uint32_t root, std::uint64_t heap) const noexcept {
  const int level = int(std::bit_width(heap)) - 1;
  if (level >= int(max_level())) return 0.0f;
  const LatticeTriangle t = triangle(root, heap);
  return diamond((t.lx + t.rx) / 2, (t.lz + t.rz) / 2).error;
}

std::size_t Landscape::bound_bytes() const noexcept { return impl_->bound_bytes; }

float LandscapeAccess::detail_offset_bound(const Landscape& l, std::int64_t i,
                                           std::int64_t j) noexcept {
  if (l.detail_levels() == 0) return 0.0f;
  const int L = int(l.detail_levels());
  const std::int64_t mask = (std::int64_t{1} << L) - 1;
  if ((i & mask) == 0 && (j & mask) == 0) return 0.0f;  // stored vertices carry no detail
  return roam::round_up(
      l.terrain().surface().detail()->contribution_bound(1, std::uint32_t(L), i, j, i, j));
}

DiamondBound LandscapeAccess::compute_detail(const Landscape& l, std::int64_t i,
                                             std::int64_t j) noexcept {
  const Landscape::Impl& m = *l.impl_;
  const int patch_log2 = l.patch_log2(), L = int(l.detail_levels());
  const Diamond d = diamond_at(i, j, patch_log2);
  const int depth = d.depth(patch_log2);
  const int base = int(l.base_level());
  const int from = (depth - base) / 2 + 1;  // the first detail level not resolved
  const Surface& surface = l.terrain().surface();
  const DetailField& f = *surface.detail();
  const std::int64_t r = d.reach();
  const std::int64_t i0 = std::max<std::int64_t>(i - r, 0), i1 = i + r;
  const std::int64_t j0 = std::max<std::int64_t>(j - r, 0), j1 = j + r;
  const double smax = f.shape_max_q15(std::uint32_t(L), i0, j0, i1, j1);
  const std::size_t k = std::size_t(depth - base);
  auto analytic = [&](std::uint32_t lv) {
    return (double(f.amplitude_sum(lv)) * smax / 32768.0 + double(f.rounding_terms(lv))) *
           kDetailUnit;
  };
  // Error: twice the bound of the contribution of the levels not resolved (docs/detail.md,
  // "Bounds"), over the diamond's reach (which nests); a resident finest tile's measured
  // contribution replaces the analytic one where it is smaller.
  double err = 2.0 * analytic(std::uint32_t(from));
  double morph =
      2.0 * (smax * m.detail_amp_growth[k] / 32768.0 + m.detail_round_growth[k]) * kDetailUnit;
  const double measured = surface.measured_detail_bound(std::uint32_t(from), i0, j0, i1, j1);
  if (measured < err / 2.0) {
    err = 2.0 * measured;
    // The morph bound's growth over the levels below, from the same tile's measurements.
    double mm = 0, g = 1;
    for (int dd = depth; dd <= int(l.max_level()) - 1; ++dd, g *= m.morph_growth) {
      const int fr = (dd - base) / 2 + 1;
      mm = std::max(mm, g * surface.measured_detail_bound(std::uint32_t(fr), i0, j0, i1, j1));
    }
    morph = std::min(morph, 2.0 * mm);
  }
  // Radius: the xz part nests by construction; the height part bounds |y_child - y_parent| by
  // the height range H of the reach (stored range plus twice the detail amplitude) once per
  // level below, so a parent's radius exceeds a child's by at least their distance.
  const world::PageGrid& g = m.store->grid();
  const std::int64_t si0 = std::clamp<std::int64_t>(i0 >> L, 0, g.last_i),
                     si1 = std::clamp<std::int64_t>((i1 >> L) + 1, 0, g.last_i),
                     sj0 = std::clamp<std::int64_t>(j0 >> L, 0, g.last_j),
                     sj1 = std::clamp<std::int64_t>((j1 >> L) + 1, 0, g.last_j);
  float lo = INFINITY, hi = -INFINITY;
  const detail::StoredLattice stored = detail::stored_lattice(surface);
  for (std::int64_t sj = sj0; sj <= sj1; ++sj)
    for (std::int64_t si = si0; si <= si1; ++si) {
      const float h = stored.local(si, sj);
      lo = std::min(lo, h), hi = std::max(hi, h);
    }
  const double height_range = double(hi - lo) + 2.0 * analytic(1);
  const int below = int(l.max_level()) - 1 - depth;  // levels of diamonds under this one
  const double unit = double(d.s) * std::hypot(m.spacing_x, m.spacing_z);
  const double radius = (d.square ? 3.0 : 2.0) * unit + double(below + 1) * height_range;
  return {roam::round_up(err), roam::round_up(std::max(morph, err)), roam::round_up(radius)};
}

// ---- shading -------------------------------------------------------------------------------

namespace {

// Area-weighted normal at a vertex of a lattice of spacing (spacing_x, spacing_z) metres from the
// 3 x 3 heights around it, h[dz + 1][dx + 1]: every triangle has the same area, so it is the
// normalised sum of the up normals (-dh/dx, 1, -dh/dz) of the triangles around the vertex, 4 or 8 of them by the
// diagonal rule (in the lattice's own indices ci, cj of the cell whose low corner is the
// vertex). `inside(cx, cz)` says whether cell (cx, cz) of the 2 x 2 around counts.
template <class Inside>
glm::vec3 area_normal(const float (&h)[3][3], std::int64_t ci, std::int64_t cj, double spacing_x,
                      double spacing_z, const Inside& inside) {
  const double per_x = 1.0 / spacing_x, per_z = 1.0 / spacing_z;
  double gx = 0, gz = 0;
  int count = 0;
  for (int cz = -1; cz <= 0; ++cz)
    for (int cx = -1; cx <= 0; ++cx) {
      if (!inside(cx, cz)) continue;
      const double h00 = h[cz + 1][cx + 1], h10 = h[cz + 1][cx + 2], h01 = h[cz + 2][cx + 1],
                   h11 = h[cz + 2][cx + 2];
      const int du = -cx, dv = -cz;  // the vertex's corner in the cell
      if (cell_has_main_diagonal(ci + cx, cj + cz)) {
        // (00, 10, 11) and (00, 11, 01): the vertex is in both when on the diagonal.
        if (!(du == 0 && dv == 1)) gx += (h10 - h00) * per_x, gz += (h11 - h10) * per_z, ++count;
        if (!(du == 1 && dv == 0)) gx += (h11 - h01) * per_x, gz += (h01 - h00) * per_z, ++count;
      } else {
        // (00, 10, 01) and (10, 11, 01).
        if (!(du == 1 && dv == 1)) gx += (h10 - h00) * per_x, gz += (h01 - h00) * per_z, ++count;
        if (!(du == 0 && dv == 0)) gx += (h11 - h01) * per_x, gz += (h11 - h10) * per_z, ++count;
      }
    }
  if (count == 0) return {0, 1, 0};
  const double len = std::sqrt(gx * gx + double(count) * double(count) + gz * gz);
  return glm::vec3(float(-gx / len), float(double(count) / len), float(-gz / len));
}

}  // namespace

bool roam::Reader::stored_shading(std::int64_t si, std::int64_t sj, const Diamond& d, int t,
                                  VertexShading& out, float* height) const noexcept {
  // A vertex's shading is its level's (t / 2, capped at the coarsest level): patch corners pass
  // t = patch_log2, the coarsest level holding them, which is always resident.
  std::int32_t a = 0, b = 0;
  PageKey key;
  const int level_t = std::min(t, 2 * (int(im_->store->grid().levels) - 1) + 1);
  const world::Page* p = page_of(si, sj, level_t, a, b, key);
  if (p == nullptr) return false;
  const int k = int(key.level);
  const std::int64_t stride = std::int64_t{1} << (2 * k);
  float h[3][3];
  for (int dz = -1; dz <= 1; ++dz)
    for (int dx = -1; dx <= 1; ++dx) h[dz + 1][dx + 1] = p->local(a + dx, b + dz);
  const std::int64_t ci = si >> (2 * k), cj = sj >> (2 * k);
  const world::PageGrid& g = im_->store->grid();
  out.normal = area_normal(h, ci, cj, double(stride) * im_->config.spacing_x,
                           double(stride) * im_->config.spacing_z, [&](int cx, int cz) {
                             const std::int64_t x = (ci + cx) * stride, z = (cj + cz) * stride;
                             return x >= 0 && z >= 0 && x < g.last_i && z < g.last_j;
                           });
  out.morph_dy = 0;
  if (!d.corner) {
    // The ends of the hypotenuse: s = 2^t away, 1 or 2 entries at this level's stride.
    std::int64_t ax, az, bx, bz;
    d.hypotenuse(ax, az, bx, bz);
    const std::int32_t ea = std::int32_t((ax >> (2 * k)) - (si >> (2 * k))) + a;
    const std::int32_t eb = std::int32_t((az >> (2 * k)) - (sj >> (2 * k))) + b;
    const std::int32_t fa = std::int32_t((bx >> (2 * k)) - (si >> (2 * k))) + a;
    const std::int32_t fb = std::int32_t((bz >> (2 * k)) - (sj >> (2 * k))) + b;
    out.morph_dy = 0.5f * (p->local(ea, eb) + p->local(fa, fb)) - p->local(a, b);
  }
  out.material = p->material(a, b);
  if (height) *height = p->local(a, b);
  return true;
}

roam::VertexShading LandscapeAccess::detail_shading(const Landscape& l, std::int64_t i,
                                              std::int64_t j) noexcept {
  const Surface& s = l.terrain().surface();
  VertexShading out;
  const Landscape::Impl& m = *l.impl_;
  const std::int64_t ci0 = std::clamp<std::int64_t>(i, 0, m.last_i),
                     cj0 = std::clamp<std::int64_t>(j, 0, m.last_j);
  float h[3][3];
  for (int dz = -1; dz <= 1; ++dz)
    for (int dx = -1; dx <= 1; ++dx)
      h[dz + 1][dx + 1] = static_cast<float>(s.vertex_height(ci0 + dx, cj0 + dz));
  out.normal = area_normal(h, ci0, cj0, m.spacing_x, m.spacing_z, [&](int cx, int cz) {
    const std::int64_t ci = ci0 + cx, cj = cj0 + cz;
    return ci >= 0 && cj >= 0 && ci < m.last_i && cj < m.last_j;
  });
  const Diamond d = diamond_at(i, j, l.patch_log2());
  if (!d.corner) {
    std::int64_t ax, az, bx, bz;
    d.hypotenuse(ax, az, bx, bz);
    out.morph_dy = 0.5f * (static_cast<float>(s.vertex_height(ax, az)) +
                           static_cast<float>(s.vertex_height(bx, bz))) -
                   static_cast<float>(s.vertex_height(i, j));
  }
  out.material = s.cell_material(i, j);
  return out;
}

// ---- creation -------------------------------------------------------------------------------

Result<std::shared_ptr<const Landscape>> Landscape::create(std::shared_ptr<const Terrain> terrain,
                                                           const LandscapeDesc& desc) {
  if (!terrain) return Error{"landscape: no terrain given"};
  if (desc.patch_exponent != 0 && (desc.patch_exponent < 2 || desc.patch_exponent > 10))
    return Error{fmt("landscape: patch exponent %u; need 2..10 (patches of 5 .. 1025 samples), "
                     "or 0 for the world's",
                     desc.patch_exponent)};
  if (!(desc.morph_window >= 0.0 && desc.morph_window <= 4.0))
    return Error{fmt("landscape: morph window %s; need 0..4", num(desc.morph_window).c_str())};
  if (!(desc.morph_delay >= 0.0 && desc.morph_delay <= 1.0))
    return Error{fmt("landscape: morph delay %s; need 0..1", num(desc.morph_delay).c_str())};
  const auto t0 = std::chrono::steady_clock::now();
  const Surface& surface = terrain->surface();
  auto& store = const_cast<world::PageStore&>(detail::SurfaceAccess::store(surface));
  const WorldInfo& info = store.info();
  const BakedRecords baked = store.source() ? store.source()->baked_records() : BakedRecords{};
  std::uint32_t exponent = desc.patch_exponent;
  if (store.paged()) {
    if (baked.patch_exponent == 0)
      return Error{fmt("landscape: world '%s' carries no tessellator bounds (bake it with "
                       "ridge bake)",
                       info.name.c_str())};
    if (exponent == 0) exponent = baked.patch_exponent;
    if (exponent != baked.patch_exponent || desc.morph_window != baked.morph_window ||
        (desc.morph_window > 0.0 && desc.morph_delay != baked.morph_delay))
      return Error{fmt("landscape: %s was baked for patch exponent %u, morph window %s "
                       "and delay %s; this landscape asks for %u, %s and %s (bake it again "
                       "with ridge bake --patch-exponent / --morph-window / --morph-delay)",
                       info.name.c_str(), baked.patch_exponent, num(baked.morph_window).c_str(),
                       num(baked.morph_delay).c_str(), exponent, num(desc.morph_window).c_str(),
                       num(desc.morph_delay).c_str())};
  }
  if (exponent == 0) exponent = roam::default_patch_exponent(info.width, info.height);
  std::shared_ptr<Landscape> l(new Landscape());
  l->terrain_ = std::move(terrain);
  l->exponent_ = exponent;
  l->detail_ = surface.detail_levels();
  l->geomorph_ = {desc.morph_window, desc.morph_window > 0.0 ? desc.morph_delay : 0.0};
  const std::int64_t p = std::int64_t{1} << exponent;  // stored cells per patch
  l->patches_x_ = static_cast<std::uint32_t>((info.width - 1 + p - 1) / p);
  l->patches_z_ = static_cast<std::uint32_t>((info.height - 1 + p - 1) / p);
  if (std::uint64_t{l->patches_x_} * l->patches_z_ > (std::uint64_t{1} << 26))
    return Error{fmt("landscape: %u x %u patches; too many (use a larger patch exponent)",
                     l->patches_x_, l->patches_z_)};
  auto im = std::make_unique<Impl>();
  im->store = &store;
  im->morph_growth = std::sqrt(1.0 + l->geomorph_.delay + l->geomorph_.window);
  im->origin_x = info.origin_x, im->origin_z = info.origin_z;
  im->spacing_x = std::ldexp(info.spacing_x, -int(l->detail_));
  im->spacing_z = std::ldexp(info.spacing_z, -int(l->detail_));
  im->last_i = std::int64_t(info.width - 1) << l->detail_;
  im->last_j = std::int64_t(info.height - 1) << l->detail_;
  // Growth of the morph bound's closed form below the stored resolution, per depth: the largest
  // g^n times the amplitude sum (and rounding terms) of the first level not resolved n levels
  // further down.
  if (l->detail_ > 0) {
    const DetailField& f = *surface.detail();
    const int base = int(l->base_level()), top = int(l->max_level());
    im->detail_amp_growth.assign(std::size_t(top - base), 0.0);
    im->detail_round_growth.assign(std::size_t(top - base), 0.0);
    for (int d = base; d < top; ++d) {
      double ga = 0, gr = 0, g = 1;
      for (int dd = d; dd < top; ++dd, g *= im->morph_growth) {
        const auto from = std::uint32_t((dd - base) / 2 + 1);
        ga = std::max(ga, g * double(f.amplitude_sum(from)));
        gr = std::max(gr, g * double(f.rounding_terms(from)));
      }
      im->detail_amp_growth[std::size_t(d - base)] = ga;
      im->detail_round_growth[std::size_t(d - base)] = gr;
    }
  }
  roam::RecordConfig& c = im->config;
  c.patch_log2 = int(exponent);
  c.growth = im->morph_growth;
  c.last_i = info.width - 1, c.last_j = info.height - 1;
  c.pad_i = std::int64_t(l->patches_x_) << exponent, c.pad_j = std::int64_t(l->patches_z_) << exponent;
  c.spacing_x = info.spacing_x, c.spacing_z = info.spacing_z;
  c.L = l->detail_;
  if (c.L > 0) {
    const Landscape* raw = l.get();
    c.detail = surface.detail();
    c.detail_child = [raw](std::int64_t i, std::int64_t j) {
      return LandscapeAccess::compute_detail(*raw, i, j);
    };
    c.detail_offset = [raw](std::int64_t i, std::int64_t j) {
      return LandscapeAccess::detail_offset_bound(*raw, i, j);
    };
  }
  {
    // Holes change the bounds (records.h): every remake and page made later reads them anew.
    const EditLayer* layer = &detail::SurfaceAccess::edits(surface);
    c.hole_source = [layer] { return layer->hole_snapshot(); };
  }
  l->impl_ = std::move(im);
  Impl& m = *l->impl_;

  auto maker = std::make_shared<Maker>(store, c, 0);
  m.slot = store.add_slot(maker);
  if (m.slot < 0)
    return Error{"landscape: the terrain's pages already carry the bounds of four other "
                 "landscape configurations; destroy one first"};
  maker->set_slot(m.slot);
  const unsigned threads = std::max(1u, std::min(8u, std::thread::hardware_concurrency()));
  std::vector<std::pair<PageKey, std::shared_ptr<const RecordBlock>>> blocks;
  if (!store.paged()) {
    // Every page resident: every block at once, from a dense copy of the heights.
    const world::PageGrid& g = store.grid();
    std::vector<float> dense(std::size_t(info.width) * info.height);
    {
      const detail::StoredLattice stored(store, SurfaceLattice{});
      for (std::int64_t j = 0; j <= g.last_j; ++j)
        for (std::int64_t i = 0; i <= g.last_i; ++i)
          dense[std::size_t(i) + std::size_t(j) * info.width] = stored.local(i, j);
    }
    roam::Heights h;
    h.f32 = dense.data(), h.stride = info.width, h.last_i = g.last_i, h.last_j = g.last_j;
    const std::shared_ptr<const world::PageTable> table = store.snapshot();
    std::mutex mu;
    roam::build_all(
        c, g, h,
        [&](const PageKey& k) { return table->find(k); },
        [&](const PageKey& k, std::shared_ptr<RecordBlock> b) {
          std::lock_guard lock(mu);
          m.bound_bytes += b->bytes();
          blocks.emplace_back(k, std::move(b));
        },
        threads);
  } else {
    // The pages resident now; those that arrive later get theirs on arrival.
    for (int k = int(store.grid().levels) - 1; k >= 0; --k) {
      std::shared_ptr<const world::PageTable> table = store.snapshot();
      std::vector<std::pair<PageKey, std::shared_ptr<const RecordBlock>>> level;
      for (std::size_t n = 0; n < table->size(); ++n) {
        const world::Page& pg = table->page(n);
        if (int(pg.key.level) != k) continue;
        auto b = maker->make(pg);
        if (b) {
          m.bound_bytes += b->bytes();
          level.emplace_back(pg.key, std::move(b));
        }
      }
      store.set_records(m.slot, level);
    }
    // The baked bounds predate the terrain's edits: remade around every edited page (its cells;
    // remake() reaches the coarser diamonds over them).
    const std::shared_ptr<const world::PageTable> table = store.snapshot();
    for (std::size_t n = 0; n < table->size(); ++n) {
      const world::Page& pg = table->page(n);
      if (pg.key.level != 0 || !pg.edited) continue;
      const std::int64_t i0 = std::int64_t(pg.key.px) << 8, j0 = std::int64_t(pg.key.pz) << 8;
      store.set_records(m.slot,
                        maker->remake(store, i0, j0, std::min(i0 + kPageCells, store.grid().last_i),
                                      std::min(j0 + kPageCells, store.grid().last_j)),
                        true);
    }
    // So do the holes (records.h): remade around every block of them that differs from the
    // holes the world was baked with (none when the terrain's mask is still the world's own).
    const std::shared_ptr<const HoleMask> holes = c.hole_source();
    const std::shared_ptr<const HoleMask>& world_holes =
        detail::SurfaceAccess::edits(surface).baked_holes();
    if (holes != world_holes) {
      std::vector<std::pair<std::uint64_t, HoleMask::Bits>> now, then;
      if (holes) now = holes->sorted_blocks();
      if (world_holes) then = world_holes->sorted_blocks();
      // Both in ascending key order: the keys held by one only, or with other bits.
      std::vector<std::uint64_t> differ;
      std::size_t a = 0, b = 0;
      while (a < now.size() || b < then.size()) {
        if (b == then.size() || (a < now.size() && now[a].first < then[b].first)) {
          differ.push_back(now[a++].first);
        } else if (a == now.size() || then[b].first < now[a].first) {
          differ.push_back(then[b++].first);
        } else {
          if (now[a].second != then[b].second) differ.push_back(now[a].first);
          ++a, ++b;
        }
      }
      for (const std::uint64_t k : differ) {
        const std::int64_t i0 = std::int64_t(k & 0xffffffffu) << HoleMask::kShift;
        const std::int64_t j0 = std::int64_t(k >> 32) << HoleMask::kShift;
        store.set_records(
            m.slot,
            maker->remake(store, i0, j0, std::min(i0 + HoleMask::kBlock, store.grid().last_i),
                          std::min(j0 + HoleMask::kBlock, store.grid().last_j)),
            true);
      }
    }
  }
  store.set_records(m.slot, blocks);
  l->build_ms_ =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return std::shared_ptr<const Landscape>(std::move(l));
}

}  // namespace ridgeline
