// Private: what the tessellator reads of a Landscape: its geometry, and through a Reader (one
// per view update, over one snapshot of the terrain's pages) the height, bounds and shading of
// each vertex.
#pragma once

#include <array>
#include <cfloat>
#include <cmath>
#include <limits>
#include <memory>

#include "ridgeline/landscape.h"
#include "platform/memory_hints.h"
#include "ridgeline/terrain.h"
#include "roam/diamond.h"
#include "roam/records.h"
#include "world/page_store.h"

namespace ridgeline::roam {

/// What a vertex's shading needs besides its position: the smooth normal of the lattice at the
/// vertex's level (the finest for the vertices of level-0 pages and detail, every 4^k-th sample
/// for level k: docs/roam.md, "Output"), its geomorph offset (the hypotenuse midpoint's height
/// relative to its own; 0 for patch corners) and the material of the stored cell at it.
struct VertexShading {
  glm::vec3 normal{0, 1, 0};
  float morph_dy = 0;
  std::uint8_t material = 0;
};

}  // namespace ridgeline::roam

namespace ridgeline {

/// A landscape's private state (landscape.cpp).
struct Landscape::Impl {
  const world::PageStore* store = nullptr;
  int slot = -1;
  roam::RecordConfig config;  // the stored diamonds' bounds
  double morph_growth = 1.0;
  std::int64_t last_i = 0, last_j = 0;  // the last sampled finest-lattice index
  double origin_x = 0, origin_z = 0, spacing_x = 1, spacing_z = 1;  // finest lattice
  std::size_t bound_bytes = 0;
  // Per depth below the stored lattice (procedural detail): the growth factors the morph bound's
  // closed form needs (compute_detail()).
  std::vector<double> detail_amp_growth, detail_round_growth;
};

}  // namespace ridgeline

namespace ridgeline::roam {

struct LandscapeAccess {
  static const Landscape::Impl& impl(const Landscape& l) noexcept { return *l.impl_; }
  static double world_x(const Landscape& l, std::int64_t i) noexcept {
    return l.impl_->origin_x + double(i) * l.impl_->spacing_x;
  }
  static double world_z(const Landscape& l, std::int64_t j) noexcept {
    return l.impl_->origin_z + double(j) * l.impl_->spacing_z;
  }
  static double spacing_x(const Landscape& l) noexcept { return l.impl_->spacing_x; }
  static double spacing_z(const Landscape& l) noexcept { return l.impl_->spacing_z; }
  /// The last finest-lattice index inside the footprint along x and z.
  static std::int64_t last_i(const Landscape& l) noexcept { return l.impl_->last_i; }
  static std::int64_t last_j(const Landscape& l) noexcept { return l.impl_->last_j; }
  /// Largest magnitude, metres, of a lattice position or height relative to the landscape's
  /// origin and the height offset (padding included).
  static double local_extent(const Landscape& l) noexcept;
  /// Geometry of node `heap` of root `root` whose apex is (ax, az), in O(1).
  static LatticeTriangle triangle_at(const Landscape& l, std::int64_t ax, std::int64_t az,
                                     std::uint32_t root, std::uint64_t heap) noexcept;
  /// Bounds of a diamond below the stored resolution (procedural detail; finest coordinates).
  static DiamondBound compute_detail(const Landscape& l, std::int64_t i, std::int64_t j) noexcept;
  /// For vertices below the stored resolution: the bound of |detail| at the vertex, metres (what a
  /// sphere about a vertex whose detail is not known yet must add). 0 for stored vertices.
  static float detail_offset_bound(const Landscape& l, std::int64_t i, std::int64_t j) noexcept;
  /// Shading of a detail vertex (finest lattice, detail included).
  static VertexShading detail_shading(const Landscape& l, std::int64_t i, std::int64_t j) noexcept;
};

/// A view update's reads of the stored vertices: one snapshot of the terrain's pages.
class Reader {
 public:
  enum class Vertex : std::uint8_t {
    kResident,  ///< stored, its page (and bounds) resident: the values are exact
    kMissing,   ///< stored, its page not resident (or without bounds yet)
    kDetail,    ///< below the stored resolution (procedural detail)
  };

  Reader() = default;
  Reader(const Landscape& l, std::shared_ptr<const world::PageTable> table,
         std::shared_ptr<const HoleMask> holes = nullptr) noexcept
      : land_(&l),
        im_(&LandscapeAccess::impl(l)),
        table_(std::move(table)),
        holes_(std::move(holes)),
        grid_(&im_->store->grid()),
        L_(int(l.detail_levels())),
        K_(int(l.patch_exponent())),
        slot_(std::size_t(im_->slot)) {}

  const world::PageTable& table() const noexcept { return *table_; }
  /// The terrain's holes when this update began (null without holes).
  const HoleMask* holes() const noexcept { return holes_.get(); }
  const Landscape& landscape() const noexcept { return *land_; }

  /// The page of level k = min(t / 2, the coarsest level) holding stored vertex (si, sj) with
  /// size 2^t, and its entry. The last page found per level is remembered (a view's reads are
  /// coherent: most land in the page of the read before), so a Reader is one thread's.
  const world::Page* page_of(std::int64_t si, std::int64_t sj, int t, std::int32_t& a,
                             std::int32_t& b, PageKey& key) const noexcept {
    return lookup(si, sj, t, a, b, key).page;
  }

  /// Height and bounds of finest-lattice vertex (i, j), which is a diamond centre (not a patch
  /// corner). kResident fills both; the others fill nothing.
  Vertex stored(std::int64_t i, std::int64_t j, DiamondBound& bound, float& y,
                PageKey* missing = nullptr) const noexcept {
    if (L_ > 0) {
      const std::int64_t mask = (std::int64_t{1} << L_) - 1;
      if ((i & mask) != 0 || (j & mask) != 0) return Vertex::kDetail;
      i >>= L_, j >>= L_;
    }
    const Diamond d = diamond_at(i, j, K_);
    std::int32_t a, b;
    PageKey key;
    const Cached& c = lookup(i, j, d.t, a, b, key);
    if (c.records == nullptr || a < 0 || b < 0 || a > kPageCells || b > kPageCells) {
      if (missing) *missing = key;
      return Vertex::kMissing;
    }
    const world::Page& p = *c.page;
    y = p.local(a, b);
    if (d.t == 0 && !d.square && L_ == 0) {
      bound = edge(p, a, b, i, j);
    } else {
      bound = RecordBlock::at(c.records, RecordBlock::slot(key.level, a, b));
    }
    return Vertex::kResident;
  }

  /// The shading of stored vertex (si, sj) (stored coordinates) whose diamond has size 2^t (t =
  /// K for a patch corner), from the page of its level, and its height when `height` is given;
  /// false when that page is not resident.
  bool stored_shading(std::int64_t si, std::int64_t sj, const Diamond& d, int t,
                      VertexShading& out, float* height = nullptr) const noexcept;

  /// Hints the caches to fetch what stored() reads for vertex (i, j): its height and its bound
  /// (two lines: they live in the page's samples and in its bounds block); with `shading`, the
  /// rows above and below that stored_shading() reads too.
  void prefetch(std::int64_t i, std::int64_t j, bool shading = false) const noexcept {
    if (L_ > 0) {
      const std::int64_t mask = (std::int64_t{1} << L_) - 1;
      if ((i & mask) != 0 || (j & mask) != 0) return;
      i >>= L_, j >>= L_;
    }
    const int t = std::min(ctz64(i), ctz64(j));
    if (t >= K_) return;
    std::int32_t a, b;
    PageKey key;
    const Cached& c = lookup(i, j, t, a, b, key);
    if (c.records == nullptr || !RecordBlock::holds(a, b)) return;
    const world::Page& p = *c.page;
    auto sample = [&p](std::size_t e) {
      return p.f32 ? static_cast<const void*>(p.f32 + e) : static_cast<const void*>(p.u16 + e);
    };
    const std::size_t e = world::entry_index(a, b);
    detail::prefetch(sample(e));
    detail::prefetch(c.records + sizeof(std::uint32_t) * RecordBlock::slot(key.level, a, b));
    if (shading) {
      detail::prefetch(sample(e - std::size_t(kPageStride)));
      detail::prefetch(sample(e + std::size_t(kPageStride)));
    }
  }

  /// Address of what stored() reads for vertex (i, j) (null when unknown).
  const void* address(std::int64_t i, std::int64_t j) const noexcept {
    if (L_ > 0) i >>= L_, j >>= L_;
    const int t = std::min(ctz64(i), ctz64(j));
    if (t >= K_) return nullptr;
    std::int32_t a, b;
    PageKey key;
    const world::Page* p = page_of(i, j, t, a, b, key);
    if (p == nullptr || a < 0 || b < 0 || a > kPageCells || b > kPageCells) return nullptr;
    return p->f32 ? static_cast<const void*>(p->f32 + world::entry_index(a, b))
                  : static_cast<const void*>(p->u16 + world::entry_index(a, b));
  }

 private:
  // The bound of a size-1 edge diamond without detail (records.h): its midpoint's offset.
  DiamondBound edge(const world::Page& p, std::int32_t a, std::int32_t b, std::int64_t i,
                    std::int64_t j) const noexcept {
    const bool horizontal = (i & 1) != 0;
    const float hc = p.local(a, b);
    const float hl = horizontal ? p.local(a - 1, b) : p.local(a, b - 1);
    const float hr = horizontal ? p.local(a + 1, b) : p.local(a, b + 1);
    DiamondBound bound = edge_bound_of(im_->config, hc, hl, hr, i, j, horizontal);
    if (holes_ != nullptr && straddles_hole(*holes_, K_, im_->config.pad_i, im_->config.pad_j, i, j))
      bound.radius = std::numeric_limits<float>::infinity();  // as bound_of() gives it
    return bound;
  }

  // A page found for one level: its grid position, the page and its packed bounds for this
  // landscape's slot (null: the page is resident without them yet).
  struct Cached {
    std::int32_t px = -1, pz = -1;
    const world::Page* page = nullptr;
    const std::uint8_t* records = nullptr;
  };
  const Cached& lookup(std::int64_t si, std::int64_t sj, int t, std::int32_t& a, std::int32_t& b,
                       PageKey& key) const noexcept {
    static const Cached kAbsent{};
    const std::uint32_t k = std::min(std::uint32_t(t >> 1), grid_->levels - 1);
    key = grid_->page_of(k, si, sj);
    a = std::int32_t((si >> (2 * k)) - (std::int64_t(key.px) << 8));
    b = std::int32_t((sj >> (2 * k)) - (std::int64_t(key.pz) << 8));
    Cached& c = last_[k];
    if (c.px == key.px && c.pz == key.pz) return c;
    const world::Page* p = table_->find(key);
    if (p == nullptr) return kAbsent;
    const RecordBlock* r = p->records[slot_].get();
    c = {key.px, key.pz, p, r ? r->packed_values() : nullptr};
    return c;
  }

  const Landscape* land_ = nullptr;
  const Landscape::Impl* im_ = nullptr;
  std::shared_ptr<const world::PageTable> table_;
  std::shared_ptr<const HoleMask> holes_;
  const world::PageGrid* grid_ = nullptr;
  int L_ = 0, K_ = 6;
  std::size_t slot_ = 0;
  mutable std::array<Cached, world::kMaxLevels> last_{};
};

}  // namespace ridgeline::roam
