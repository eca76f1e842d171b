// Frame-coherent ROAM (Duchaineau et al. 1997) driven by a front that is tested in full every
// update: the update's phases.
//
//   1. pull edits (Landscape::changes_since) and tile arrivals: refresh the diamonds they reach
//   2. test the front: one vectorised pass over every diamond that could split or merge
//   3. merge the split diamonds whose test failed, split the unsplit ones whose test passed,
//      and test each diamond that appears on the way (so one update goes as deep as it must)
//   4. under a time budget, 3 goes in priority order instead: the dual split and merge queues
//      of D97 section 5, over the candidates of this update only. Under a triangle cap alone
//      the view searches the threshold that fills the cap instead (converge_capped())
//
// With nested bounds and spheres (landscape.h) a diamond's test never passes when a parent's
// fails, so the converged mesh is the unique one the threshold asks for, whatever the camera's
// history: the same as a rebuild from the roots (RoamMode::kRebuild) and, for the same bounds,
// as Lindstrom & Pascucci's stateless SOAR refinement.
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <tuple>
#include <unordered_set>

#include "format.h"
#include "ridgeline/detail.h"
#include "ridgeline/log.h"
#include "roam/landscape_access.h"
#include "roam/view_impl.h"
#include "surface/lattice.h"

namespace ridgeline {

using namespace roam;
using detail::fmt;
using detail::num;

const char* stop_reason_name(StopReason r) noexcept {
  switch (r) {
    case StopReason::kConverged:
      return "converged";
    case StopReason::kTriangleBudget:
      return "triangle_budget";
    case StopReason::kTimeBudget:
      return "time_budget";
  }
  return "converged";
}

float morph_factor(const MeshVertex& v, const glm::vec3& eye, double projection_scale,
                   double threshold_px, const Geomorph& g) noexcept {
  if (!(g.window > 0.0) || !(threshold_px > 0.0)) return 1.0f;
  const double dx = double(v.x) - eye.x, dy = double(v.y) - eye.y, dz = double(v.z) - eye.z;
  const double d = std::sqrt(dx * dx + dy * dy + dz * dz) - double(v.morph_radius);
  const double rho = double(v.morph_bound) * projection_scale / (threshold_px * std::max(d, 1e-6));
  return static_cast<float>(std::clamp((rho - 1.0 - g.delay) / g.window, 0.0, 1.0));
}

float morphed_height(const MeshVertex& v, const glm::vec3& eye, double projection_scale,
                     double threshold_px, const Geomorph& g) noexcept {
  return v.y + (1.0f - morph_factor(v, eye, projection_scale, threshold_px, g)) * v.morph_dy;
}

// ---- creation and settings --------------------------------------------------------------------

Result<std::unique_ptr<RoamView>> RoamView::create(std::shared_ptr<const Landscape> landscape,
                                                   const RoamSettings& settings) {
  if (!landscape) return Error{"roam view: no landscape given"};
  std::unique_ptr<RoamView> v(new RoamView());
  v->landscape_ = std::move(landscape);
  v->impl_ = std::make_unique<Impl>(*v->landscape_);
  if (auto s = v->set_settings(settings); !s) return Error{s.message()};
  v->impl_->reader = roam::Reader(
      *v->landscape_, detail::SurfaceAccess::store(v->landscape_->terrain().surface()).snapshot());
  v->impl_->reset();
  v->impl_->synced_version = v->landscape_->terrain().edit_version();
  return v;
}

RoamView::~RoamView() = default;

std::uint32_t RoamView::triangle_count() const noexcept {
  return impl_->triangles;
}

Status RoamView::set_settings(const RoamSettings& s) {
  if (!std::isfinite(s.threshold) || s.threshold < 0.0)
    return Error{
        fmt("roam view: threshold %s; need a finite value >= 0", num(s.threshold).c_str())};
  if (!std::isfinite(s.budget_ms) || s.budget_ms < 0.0)
    return Error{
        fmt("roam view: time budget %s ms; need a finite value >= 0", num(s.budget_ms).c_str())};
  if (s.max_triangles != 0 && s.max_triangles < landscape_->root_count())
    return Error{fmt("roam view: triangle budget %u is below the %u root triangles",
                     s.max_triangles, landscape_->root_count())};
  if (impl_ && (s.mode != settings_.mode || s.metric != settings_.metric))
    impl_->reset_pending = true;
  if (impl_ && s.max_triangles != settings_.max_triangles) impl_->cap_threshold = 0;
  settings_ = s;
  return {};
}

Result<RoamStats> RoamView::converge(const Camera& camera) {
  const RoamSettings saved = settings_;
  RoamSettings s = settings_;
  s.budget_ms = 0;
  (void)set_settings(s);
  auto r = update(camera);
  // On a paged world, splits that waited for pages go on once the pages are loaded.
  const world::PageStore& store = detail::SurfaceAccess::store(landscape_->terrain().surface());
  for (int round = 0; r && r->requested_pages > 0 && round < 256; ++round) {
    store.wait_idle(60.0);
    auto next = update(camera);
    if (next) next->update_ms += r->update_ms;
    r = next;
  }
  (void)set_settings(saved);
  return r;
}

std::vector<std::uint32_t> RoamView::take_dirty_patches() {
  return impl_->out.take_dirty();
}

const PatchMesh& RoamView::patch_mesh(std::uint32_t patch) const {
  RIDGELINE_ASSERT(patch < landscape_->patch_count());
  return impl_->out.mesh(std::min(patch, landscape_->patch_count() - 1));
}

// ---- phase 1: edits and tiles -------------------------------------------------------------------

namespace {

// True when the range of lattice vertices, widened by `grow`, holds (i, j).
bool reaches(const LatticeRange& c, std::int64_t i, std::int64_t j, std::int64_t grow) {
  return i >= c.i0 - grow && i <= c.i1 + grow && j >= c.j0 - grow && j <= c.j1 + grow;
}

}  // namespace

// Refreshes what the terrain's edits since the last update reach (its change log): the front's
// diamonds (bounds, positions) and the output vertices (heights, normals, bounds). A diamond's
// bound depends on everything within its reach, a vertex's normal and geomorph offset on the
// vertices of its level around it.
void RoamView::Impl::pull_changes() {
  Impl& m = *this;
  const TerrainChanges pulled = m.land.terrain().changes_since(m.synced_version);
  m.synced_version = pulled.version;
  if (pulled.empty()) return;
  for (const TerrainChange& ch : pulled.changes) {
    const LatticeRange& c = ch.vertices;
    if (c.empty()) continue;
    for (std::uint32_t e = 0; e < m.front.size(); ++e) {
      const std::int64_t s = std::int64_t{1} << m.front.t(e);
      if (reaches(c, m.front.ci(e), m.front.cj(e), 3 * s + 1)) m.refresh_entry(e);
    }
    const std::int64_t P = m.land.patch_cells();
    const std::int64_t px0 = std::max<std::int64_t>(0, (c.i0 - 2 * P) / P),
                       px1 = std::min<std::int64_t>(m.land.patches_x() - 1, (c.i1 + 2 * P) / P),
                       pz0 = std::max<std::int64_t>(0, (c.j0 - 2 * P) / P),
                       pz1 = std::min<std::int64_t>(m.land.patches_z() - 1, (c.j1 + 2 * P) / P);
    for (std::int64_t pz = pz0; pz <= pz1; ++pz)
      for (std::int64_t px = px0; px <= px1; ++px) {
        const auto p = std::uint32_t(px + pz * m.land.patches_x());
        for (std::uint32_t v = 0; v < m.out.vertex_slots(p); ++v) {
          if (!m.out.vertex_live(p, v)) continue;
          const auto q = m.out.coord(p, v);
          const Diamond d = diamond_at(q[0], q[1], m.K);
          const std::int64_t grow = d.corner ? P + 1 : std::max<std::int64_t>(1, d.reach()) + 1;
          if (reaches(c, q[0], q[1], grow)) m.out.refresh_vertex(p, v);
        }
      }
  }
}

void RoamView::Impl::pull_pages() {
  Impl& m = *this;
  const std::uint64_t g = m.reader.table().generation();
  if (g == m.pages_generation) return;
  m.pages_generation = g;
  if (!m.land.terrain().paged()) return;
  for (std::uint32_t e = 0; e < m.front.size(); ++e) {
    if (!m.front.provisional(e)) continue;
    const std::int64_t ki = m.front.ci(e), kj = m.front.cj(e);
    DiamondBound b;
    float y;
    if (m.reader.stored(ki, kj, b, y) == Reader::Vertex::kResident) {
      const float before = m.front.mu(e);
      m.refresh_entry(e);
      if (m.front.mu(e) < before) ++m.st.rebounded;
    }
  }
}

// Detail tiles that became resident since the last update: the diamonds whose vertex waited for
// one get their true position and the measured bounds (tighter than the analytic ones); the
// vertices of the mesh over them too.
void RoamView::Impl::pull_tiles() {
  Impl& m = *this;
  if (m.cache == nullptr) return;
  const std::uint64_t g = m.cache->generation();
  if (g == m.tiles_generation) return;
  m.tiles_generation = g;
  const DetailSnapshot& snap = *m.snapshot;
  const std::uint32_t L = m.land.detail_levels();
  // Finest tiles new since the last look (their areas: measured bounds apply inside).
  std::vector<DetailTileKey> arrived;
  std::unordered_set<std::uint64_t> now;
  now.reserve(snap.size());
  for (std::size_t k = 0; k < snap.size(); ++k) {
    const DetailTileKey& key = snap.tile(k).key();
    if (key.level != L) continue;
    const std::uint64_t id = (std::uint64_t(std::uint32_t(key.tx)) << 32) | std::uint32_t(key.tz);
    now.insert(id);
    if (!m.known_tiles.count(id)) arrived.push_back(key);
  }
  m.known_tiles.swap(now);
  const std::int64_t cells = kDetailTileCells;
  for (std::uint32_t e = 0; e < m.front.size(); ++e) {
    const std::uint32_t kt = m.front.t(e);
    const std::int64_t ki = m.front.ci(e), kj = m.front.cj(e);
    if (kt >= L) continue;  // stored vertices: no detail
    bool refresh = m.front.provisional(e);
    if (!refresh) {
      const std::int64_t reach = std::int64_t{3} << kt;  // Diamond::reach(), at most
      for (const DetailTileKey& key : arrived) {
        const std::int64_t i0 = std::int64_t(key.tx) * cells, j0 = std::int64_t(key.tz) * cells;
        if (ki - reach >= i0 && ki + reach <= i0 + cells && kj - reach >= j0 &&
            kj + reach <= j0 + cells) {
          refresh = true;
          break;
        }
      }
    }
    if (!refresh) continue;
    const float before = m.front.mu(e);
    m.refresh_entry(e);
    if (m.front.mu(e) < before) ++m.st.rebounded;
  }
  if (arrived.empty()) return;
  // The mesh's vertices over the new tiles carry the measured bounds too.
  for (std::uint32_t p = 0; p < m.out.patch_count(); ++p)
    for (std::uint32_t v = 0; v < m.out.vertex_slots(p); ++v) {
      if (!m.out.vertex_live(p, v)) continue;
      const auto q = m.out.coord(p, v);
      const Diamond d = diamond_at(q[0], q[1], m.K);
      if (d.corner || d.t >= int(L)) continue;
      for (const DetailTileKey& key : arrived) {
        const std::int64_t i0 = std::int64_t(key.tx) * cells, j0 = std::int64_t(key.tz) * cells;
        if (q[0] >= i0 && q[0] <= i0 + cells && q[1] >= j0 && q[1] <= j0 + cells) {
          m.out.refresh_vertex(p, v);
          break;
        }
      }
    }
}

// ---- phase 3: splits and merges
// --------------------------------------------------------------------

bool RoamView::Impl::split_candidate(std::uint32_t n) const {
  if (!nodes[n].leaf()) return false;
  const std::uint32_t e = nodes[n].entry();
  return !front.split(e) && (front.result(e) & kActive);
}

bool RoamView::Impl::merge_candidate(std::uint32_t n) const {
  if (nodes[n].leaf() || nodes[n].entry() == kNoEntry) return false;
  const std::uint32_t e = nodes[n].entry();
  return front.split(e) && !(front.result(e) & kActive) && mergeable(n);
}

// Unbudgeted: every merge the test asks for (cascading up), then every split (cascading down).
void RoamView::Impl::collect() {
  to_merge.clear();
  to_split.clear();
  // Few entries change per update: the blocks' masks say which.
  const std::uint32_t nb = front.blocks();
  for (std::uint32_t b = 0; b < nb; ++b) {
    for (std::uint32_t c = front.changed(b); c != 0; c &= c - 1) {
      const std::uint32_t e = b * Front::kLanes + std::uint32_t(__builtin_ctz(c));
      (front.split(e) ? to_merge : to_split).push_back(front.node(e));
    }
  }
}

// The changes are memory walks (node, entry, neighbours, the landscape's records, the patch
// buffers) that depend on each other within one change but not across changes. So the next
// changes' data is fetched in stages while this one runs: a node 32 changes ahead, what the node
// points at 16 ahead, what its entry points at 8 ahead; the misses overlap instead of stalling
// one change at a time.
void RoamView::Impl::prefetch_change(const std::vector<std::uint32_t>& list, bool split) const {
  auto prefetch_record = [&](std::int64_t i, std::int64_t j) {
    if (const void* a = reader.address(i, j)) detail::prefetch(a);
  };
  constexpr std::size_t D1 = 32, D2 = 16, D3 = 8;  // measured: 16/8/4 was ~10 % slower
  const std::size_t n = list.size();
  if (n > D1) nodes.prefetch(list[n - D1 - 1]);
  if (n > D2) {
    const Node& x = nodes[list[n - D2 - 1]];
    front.prefetch(x.entry());
    nodes.prefetch(to(x.base()));
    nodes.prefetch(x.parent);
    nodes.prefetch(split ? to(x.a()) : x.a());  // a leaf's neighbour, an interior node's children
    if (split) nodes.prefetch(to(x.b()));
  }
  if (n <= D3) return;
  const Node& x = nodes[list[n - D3 - 1]];
  const std::uint32_t e = x.entry();
  if (e >= front.size() || x.leaf() != split) return;  // no longer a candidate
  const std::int64_t i = front.ci(e), j = front.cj(e), hu = front.hu(e), hw = front.hw(e);
  if (!split) {
    // A merge removes its children's entries and may make a parent mergeable (its partner's
    // children are read, its record too: the parents are centred at the two apexes c +- p).
    front.prefetch(nodes[x.a()].entry());
    front.prefetch(nodes[x.a() + 1].entry());
    if (x.parent != kNone) nodes.prefetch(to(nodes[x.parent].base()));
    prefetch_record(i - hw, j + hu);
    prefetch_record(i + hw, j - hu);
    return;
  }
  // A split removes its parents' entries (when mergeable), writes its vertex (its record) and
  // adds its children's diamonds (centres c +- (p +- h) / 2, p = (-hw, hu)). A base neighbour
  // that is not its partner is split first (a forced split): its entry and parent next.
  if (x.parent != kNone) front.prefetch(nodes[x.parent].entry());
  if (x.base() != kNone && back(x.base()) != 0) {
    const Node& f = nodes[to(x.base())];
    front.prefetch(f.entry());
    nodes.prefetch(f.parent);
    nodes.prefetch(to(f.a()));
    nodes.prefetch(to(f.b()));
  }
  prefetch_record(i, j);
  if (((hu - hw) | (hu + hw)) & 1) return;  // finest: no child diamonds
  const std::int64_t au = (hu - hw) / 2, aw = (hu + hw) / 2, bu = (hu + hw) / 2, bw = (hw - hu) / 2;
  prefetch_record(i + au, j + aw);
  prefetch_record(i - au, j - aw);
  prefetch_record(i + bu, j + bw);
  prefetch_record(i - bu, j - bw);
}

// Breadth first: the changes a wave of changes asks for (parents that became mergeable and
// inactive, children that are active) make the next wave, so each wave's list is known before
// it starts and the next changes' data can be fetched ahead (prefetch_change()); and coarser
// diamonds split before finer ones, so few splits need forcing.
void RoamView::Impl::converge_all() {
  Impl& m = *this;
#ifdef RIDGELINE_ROAM_PARANOID
  if (auto e = m.check(); !e.empty()) {
    std::fprintf(stderr, "before converge_all: %s\n", e.c_str());
    std::abort();
  }
#endif
  std::vector<std::uint32_t>& next = m.next_wave;
  for (std::vector<std::uint32_t>* list : {&m.to_merge, &m.to_split}) {
    const bool split = list == &m.to_split;
    next.clear();
    while (!list->empty()) {
      while (!list->empty()) {
        m.prefetch_change(*list, split);
        const std::uint32_t n = list->back();
        list->pop_back();
        if (split) {
          if (m.split_candidate(n) && !m.split(n, false, &next)) ++m.st.pending_splits;
        } else if (m.merge_candidate(n)) {
          m.merge(n, &next);
        }
#ifdef RIDGELINE_ROAM_PARANOID
        if (auto e = m.check(); !e.empty()) {
          std::fprintf(stderr, "after %s of %u: %s\n", split ? "split" : "merge", n, e.c_str());
          std::abort();
        }
#endif
      }
      list->swap(next);
    }
  }
}

namespace {

// Keeps `keep` of the items with the largest keys (all of them when there are no more), in any
// order; returns the largest key dropped (0 when none). nth_element over all of them cost
// ~30 ns an item (a mispredicted branch per comparison of random keys; and the out-of-view
// merges, thousands of them, share one key): 0.1-0.4 ms for 5,000-15,000 candidates, most of
// a 0.5 ms budget. Instead a cutoff comes from a sample of 256 keys, the items above it are
// moved to the front (a branch nearly always taken the same way), then those equal to it, and
// only when more than `keep` are above it are those selected exactly (by key alone).
float keep_largest(std::vector<std::pair<float, std::uint32_t>>& v, std::size_t keep,
                   std::vector<float>& sample) {
  using Item = std::pair<float, std::uint32_t>;
  const std::size_t n = v.size();
  if (n <= keep) return 0.0f;
  const std::size_t stride = std::max<std::size_t>(1, n / 256);
  sample.clear();
  for (std::size_t i = 0; i < n; i += stride) sample.push_back(v[i].first);
  // The sample's key with keep's share of the sample above it, and a little more.
  const std::size_t rank = std::min(sample.size() - 1, (keep * sample.size() + n - 1) / n + 2);
  std::nth_element(sample.begin(), sample.begin() + std::ptrdiff_t(rank), sample.end(),
                   std::greater<>());
  const float cut = sample[rank];
  auto above = std::partition(v.begin(), v.end(), [cut](const Item& x) { return x.first > cut; });
  auto end = above;
  if (std::size_t(above - v.begin()) < keep)  // then the ties, as many as fit
    end = std::partition(above, v.end(), [cut](const Item& x) { return x.first == cut; });
  end = v.begin() + std::ptrdiff_t(std::min<std::size_t>(keep, std::size_t(end - v.begin())));
  if (std::size_t(above - v.begin()) > keep)  // a skewed sample: select among those above
    std::nth_element(v.begin(), end, above,
                     [](const Item& a, const Item& b) { return a.first > b.first; });
  float dropped = 0.0f;
  for (auto it = end; it != v.end(); ++it) dropped = std::max(dropped, it->first);
  v.erase(end, v.end());
  return dropped;
}

}  // namespace

// Under a triangle cap or a time budget: the most important change first (D97's dual queues:
// split the highest priority, merge the lowest; under a cap, trade a merge for a split while the
// split matters more). Keys are this update's priorities; out-of-view diamonds merge first.
float RoamView::Impl::converge_budgeted(double threshold, std::uint32_t cap) {
  Impl& m = *this;
  using Item = Impl::QueueItem;
  // The queues are members: an update allocates nothing once they have grown (an allocation
  // after other code gave memory back to the system faults pages in: ~0.5 ms spikes).
  std::vector<Item>& splits = m.split_queue;
  std::vector<Item>& merges = m.merge_queue;
  splits.clear();
  merges.clear();
  auto split_key = [&](std::uint32_t e) { return m.front.priority(e, m.cam); };
  auto merge_key = [&](std::uint32_t e) {
    return (m.front.result(e) & kInView) ? m.front.priority(e, m.cam) : -1.0f;
  };
  float held_back = 0;  // the largest priority of a split candidate left out of the queue
  if (cap == 0) {
    // Without a cap the candidates are the entries whose test disagrees with their state, with
    // the priorities the pass computed (keyed). Far from convergence there are thousands while
    // the budget allows a few hundred changes: only the most important go in the queues (the
    // rest is found again by the next update's pass), so building them costs little.
    // The pass marked which entries are split, so the lists are sorted out by entry and only
    // the kept ones' nodes are read (a record each, which the pass did not touch, fetched
    // ahead: reading them for all the candidates cost up to 0.5 ms for 20,000 of them on a
    // front the rest of the frame had evicted).
    const std::size_t keep = std::max<std::size_t>(1024, 4 * std::size_t(m.budget_ops));
    for (const Front::Keyed& k : m.keyed) {
      if (k.entry & Front::kKeyedSplit)
        merges.push_back({-k.key, k.entry & ~Front::kKeyedSplit});
      else
        splits.push_back({k.key, k.entry});
    }
    auto trim = [&](std::vector<Item>& v, bool is_split) {
      const float dropped = keep_largest(v, keep, m.key_sample);
      if (is_split) held_back = std::max(held_back, dropped);
      constexpr std::size_t kAhead = 16;
      for (std::size_t i = 0; i < v.size(); ++i) {  // entry -> node
        if (i + kAhead < v.size()) m.front.prefetch_record(v[i + kAhead].second);
        v[i].second = m.front.node(v[i].second);
      }
    };
    trim(splits, true);
    trim(merges, false);
  } else {
    for (std::uint32_t e = 0; e < m.front.size(); ++e) {
      if (m.front.split(e)) {
        // Under a cap every mergeable diamond may be traded, except those that keep the mesh
        // on the data's border (forced, like the splits that keep it crack-free).
        if (m.front.radius(e) < Front::kBorderRadius)
          merges.push_back({-merge_key(e), m.front.node(e)});
      } else if (m.front.result(e) & kActive) {
        splits.push_back({split_key(e), m.front.node(e)});
      }
    }
  }
  std::make_heap(splits.begin(), splits.end());
  std::make_heap(merges.begin(), merges.end());  // max of -key: the lowest key on top
  std::vector<std::uint32_t>& fresh = m.fresh_nodes;
  fresh.clear();
  auto push_fresh = [&] {
    for (std::uint32_t n : fresh) {
      const std::uint32_t e = m.nodes[n].entry();
      if (e == kNoEntry) continue;
      if (m.nodes[n].leaf()) {
        if (!m.front.split(e) && (m.front.result(e) & kActive)) {
          splits.push_back({split_key(e), n});
          std::push_heap(splits.begin(), splits.end());
        }
      } else if (m.front.split(e) && (cap == 0 || m.front.radius(e) < Front::kBorderRadius)) {
        merges.push_back({-merge_key(e), n});
        std::push_heap(merges.begin(), merges.end());
      }
    }
    fresh.clear();
  };
  auto top_split = [&]() -> const Item* {
    while (!splits.empty() && !m.split_candidate(splits.front().second)) {
      std::pop_heap(splits.begin(), splits.end());
      splits.pop_back();
    }
    return splits.empty() ? nullptr : &splits.front();
  };
  auto top_merge = [&]() -> const Item* {
    while (!merges.empty()) {
      const std::uint32_t n = merges.front().second;
      if (!m.nodes[n].leaf() && m.nodes[n].entry() != kNoEntry &&
          m.front.split(m.nodes[n].entry()) && m.mergeable(n))
        break;
      std::pop_heap(merges.begin(), merges.end());
      merges.pop_back();
    }
    return merges.empty() ? nullptr : &merges.front();
  };
  auto do_merge = [&] {
    const std::uint32_t n = merges.front().second;
    std::pop_heap(merges.begin(), merges.end());
    merges.pop_back();
    m.merge(n, nullptr);
#ifdef RIDGELINE_ROAM_PARANOID
    if (auto e = m.check(); !e.empty()) {
      std::fprintf(stderr, "after budgeted merge of %u: %s\n", n, e.c_str());
      std::abort();
    }
#endif
    // The merged diamond may split again later (a trade back); its parents may merge next.
    fresh.push_back(n);
    for (std::uint32_t p :
         {m.nodes[n].parent,
          m.nodes[n].base() != kNone ? m.nodes[to(m.nodes[n].base())].parent : kNone})
      if (p != kNone) fresh.push_back(p);
    push_fresh();
  };
  std::uint64_t ops = 0;
  bool alternate = false;
  const std::uint32_t splits0 = m.st.splits, merges0 = m.st.merges;
  for (;;) {
    if (++ops > 16ull * (m.triangles + 4096)) break;  // a safety net against a trade cycle
    if (m.out_of_time()) {
      m.st.stop = StopReason::kTimeBudget;
      break;
    }
    const Item* s = top_split();
    const Item* g = top_merge();
    const float sp = s ? s->first : -INFINITY;
    const float gp = g ? -g->first : INFINITY;
    if (cap != 0 && m.triangles > cap) {
      if (!g) break;
      do_merge();
      continue;
    }
    // Under a time budget a merge the test asks for goes first every other operation: splits
    // alone would take the whole budget while the camera moves, and the mesh would keep every
    // triangle it no longer needs.
    alternate = !alternate;
    if (g && gp <= threshold && (!s || alternate || cap != 0) &&
        !(m.front.result(m.nodes[g->second].entry()) & kActive)) {
      do_merge();
      continue;
    }
    if (s) {
      const std::uint32_t n = s->second;
      // A split on the data's border is forced: it goes past the cap (docs/roam.md).
      const bool border = m.front.radius(m.nodes[n].entry()) >= Front::kBorderRadius;
      if (cap != 0 && !border && m.triangles + m.split_cost(n) > cap) {
        // Trade a lower-priority diamond for this split, unless it is the leaf's own parent.
        if (g && gp < sp && g->second != m.nodes[n].parent &&
            to(m.nodes[g->second].base()) != m.nodes[n].parent) {
          do_merge();
          continue;
        }
        m.st.stop = StopReason::kTriangleBudget;
        break;
      }
      std::pop_heap(splits.begin(), splits.end());
      splits.pop_back();
      const bool done = m.split(n, false, &fresh);
#ifdef RIDGELINE_ROAM_PARANOID
      if (auto e = m.check(); !e.empty()) {
        std::fprintf(stderr, "after budgeted split of %u: %s\n", n, e.c_str());
        std::abort();
      }
#endif
      if (!done)
        ++m.st.pending_splits;
      else {
        // The split diamond is mergeable now; its children may split next.
        fresh.push_back(n);
        for (std::uint32_t k = 0; k < 2; ++k) fresh.push_back(m.nodes[n].a() + k);
        if (m.nodes[n].base() != kNone)
          for (std::uint32_t k = 0; k < 2; ++k)
            fresh.push_back(m.nodes[to(m.nodes[n].base())].a() + k);
      }
      push_fresh();
      continue;
    }
    if (g && gp <= threshold && !(m.front.result(m.nodes[g->second].entry()) & kActive)) {
      do_merge();
      continue;
    }
    break;
  }
  // What stays unsplit in view: the splits left in the queue (active), and the tests that failed
  // (fresh_worst: this update's pass and every diamond tested since).
  const Item* s = top_split();
  const float left = std::max({m.fresh_worst, s ? s->first : 0.0f, held_back});
  m.budget_ops = (m.st.splits - splits0) + (m.st.merges - merges0);
  // Under a cap, the splits that end the mesh on the data's border are forced, as crack fixes
  // are: every one the cap held back is made now, past the cap (docs/roam.md).
  if (cap != 0 && m.may_pad && !m.out_of_time()) m.split_border();
  return left;
}

void RoamView::Impl::split_border() {
  std::vector<std::uint32_t>& work = next_wave;  // free here (converge_all()'s), kept memory
  work.clear();
  for (std::uint32_t e = 0; e < front.size(); ++e)
    if (!front.split(e) && (front.result(e) & kActive) && front.radius(e) >= Front::kBorderRadius)
      work.push_back(front.node(e));
  while (!work.empty()) {
    const std::uint32_t n = work.back();
    work.pop_back();
    // The children a split makes that are active go to `work`; only the border's are forced.
    if (split_candidate(n) && front.radius(nodes[n].entry()) >= Front::kBorderRadius &&
        !split(n, false, &work))
      ++st.pending_splits;
  }
}

roam::FrontCamera RoamView::Impl::front_camera(const Camera& camera, double px) const {
  return FrontCamera::screen(camera, px, LandscapeAccess::world_x(land, 0),
                             land.terrain().info().height_offset, LandscapeAccess::world_z(land, 0),
                             LandscapeAccess::spacing_x(land), LandscapeAccess::spacing_z(land),
                             LandscapeAccess::local_extent(land));
}

// Under a triangle cap alone. Splitting the highest priority first until the cap is reached
// (the dual queues) ends in the mesh of one threshold: the priority of the last split. So the
// view looks for that threshold instead of ordering every change: it converges at the last
// update's threshold (the unbudgeted path: a pass over the front and only the changes), raises
// the threshold while the mesh exceeds the cap (merges, the cheap direction), and when the mesh
// ends well under the cap, starts the next update lower. The mesh then follows the camera at
// the cost of an unbudgeted update, where ordering the whole front by priority each update cost
// ~2x. The first update (and any that does not fit after a few raises) uses the queues, which
// hit the cap exactly; their remaining priority seeds the search.
double RoamView::Impl::converge_capped(const Camera& camera, double threshold, std::uint32_t cap) {
  Impl& m = *this;
  if (m.cap_threshold <= 0.0) {
    m.fresh_worst = converge_budgeted(threshold, cap);
    const double reached = m.st.stop == StopReason::kTriangleBudget
                               ? std::max(threshold, double(m.fresh_worst))
                               : threshold;
    m.cap_threshold = reached;
    return reached;
  }
  // N(tau) falls roughly as tau^-1.5 on terrain: steps of the ratio^(2/3), at least 1 %.
  constexpr double kExponent = 2.0 / 3.0, kTarget = 0.99, kLowerBelow = 0.985;
  double tau = std::max(threshold, m.cap_threshold);
  for (int pass = 0;; ++pass) {
    if (pass > 0) {
      m.cam = front_camera(camera, tau);
      m.fresh_worst = m.front.evaluate(m.cam);
      m.st.priority_updates += m.front.size();
      m.collect();
    }
    converge_all();
    if (m.triangles <= cap) break;
    if (pass == 4) {
      // Still over: let the queues trade down to the cap at this threshold.
      m.fresh_worst = converge_budgeted(tau, cap);
      tau = std::max(tau, double(m.fresh_worst));
      break;
    }
    tau *= std::clamp(std::pow(double(m.triangles) / (kTarget * cap), kExponent), 1.01, 4.0);
  }
  // Where the next update starts: lower when this mesh ended well under the cap.
  double next = tau;
  if (m.triangles < kLowerBelow * cap && tau > threshold)
    next = std::max(
        threshold,
        tau * std::clamp(std::pow(double(m.triangles) / (kTarget * cap), kExponent), 0.25, 0.99));
  m.cap_threshold = next;
  m.st.stop = tau > threshold ? StopReason::kTriangleBudget : StopReason::kConverged;
  return tau;
}

// ---- output compaction
// ---------------------------------------------------------------------------

// A patch's slots are renumbered in the depth-first order of its two trees (child 0 first): the
// leaves' order is a space-filling curve over the patch, so neighbouring triangles sit side by
// side in the index buffer and share vertices nearby, what a GPU's vertex cache likes.
void RoamView::Impl::compact_output(const std::chrono::steady_clock::time_point* until) {
  std::vector<std::uint32_t>& pending = out.compact_pending();
  std::size_t kept = 0;  // patches left listed for a later update, moved to the front
  for (std::size_t q = 0; q < pending.size(); ++q) {
    const std::uint32_t p = pending[q];
    if (until != nullptr &&
        std::chrono::steady_clock::now() +
                std::chrono::nanoseconds(kCompactNsPerTriangle * out.live_triangles(p)) >
            *until) {
      pending[kept++] = p;
      continue;
    }
    out.unlist_compact(p);
    if (!out.oversized(p)) continue;  // grew back since it was listed
    compact_nodes.clear();
    compact_order.clear();
    compact_stack.assign({2 * p + 1, 2 * p});
    while (!compact_stack.empty()) {
      const std::uint32_t n = compact_stack.back();
      compact_stack.pop_back();
      compact_nodes.push_back(n);
      const Node& x = nodes[n];
      if (x.leaf()) {
        compact_order.push_back(x.slot());
      } else {
        compact_stack.push_back(x.a() + 1);
        compact_stack.push_back(x.a());
      }
    }
    out.compact(p, compact_order, compact_vmap);
    std::uint32_t k = 0;
    for (const std::uint32_t n : compact_nodes) {
      Node& x = nodes[n];
      if (x.leaf())
        x.set_slot(k++);
      else
        x.b() = compact_vmap[x.b()];
    }
    ++st.compacted_patches;
  }
  pending.resize(kept);
}

// ---- the update
// ------------------------------------------------------------------------------------

Result<RoamStats> RoamView::update(const Camera& camera) {
  const bool screen = settings_.metric == ErrorMetric::kScreenPixels;
  if (screen)
    if (auto s = validate_camera(camera); !s) return Error{s.message()};
  const auto t0 = std::chrono::steady_clock::now();
  Impl& m = *impl_;
  m.st = RoamStats{};
  const Landscape& l = *landscape_;
  const double threshold = settings_.threshold;
  const std::uint32_t cap = settings_.max_triangles;
  // Under a cap alone, the test starts at the threshold the last update's search ended at.
  const bool capped =
      cap != 0 && !(settings_.budget_ms > 0.0) && screen && settings_.mode == RoamMode::kCoherent;
  const double start_px = capped ? std::max(threshold, m.cap_threshold) : threshold;
  m.cam = screen ? m.front_camera(camera, start_px) : FrontCamera::world_metres(threshold);
  m.has_deadline = settings_.budget_ms > 0.0;
  m.deadline = t0 + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                        std::chrono::duration<double, std::milli>(settings_.budget_ms));
  m.clock_checks = 0;

  // 1. Edits, pages and detail tiles.
  if (m.cache != nullptr) {
    m.cache->update();  // integrate tiles generated since the last frame
    m.snapshot = m.cache->snapshot();
  }
  l.terrain().update_pages();  // integrate pages loaded since the last frame, evict to budget
  m.reader = Reader(l, detail::SurfaceAccess::store(l.terrain().surface()).snapshot());
  m.out.set_reader(m.reader);
  m.page_requests.clear();
  // A mesh made from the roots is built top down when nothing orders the changes (no time
  // budget, no queues of a cap's first update): build.cpp.
  const bool whole = !m.has_deadline && (cap == 0 || (capped && m.cap_threshold > 0.0));
  if (m.reset_pending || settings_.mode == RoamMode::kRebuild) {
    m.reset_pending = false;
    m.synced_version = l.terrain().edit_version();
    m.reset();
    if (whole) m.build();
  } else {
    m.pull_changes();
  }
  m.pull_tiles();
  m.pull_pages();

#ifdef RIDGELINE_ROAM_PARANOID
  if (auto e = m.check(); !e.empty()) {
    std::fprintf(stderr, "before the test (rebuilt %d): %s\n", int(m.st.rebuilt), e.c_str());
    std::abort();
  }
#endif
  // 2. The test (with the changes' priorities when a time budget alone orders them).
  if (m.has_deadline) {
    // Under a time budget the pass takes about 40 % of it at most, in whole chunks, and the
    // next update goes on where it stopped: on a large front far from convergence a whole pass
    // with its change list took 0.3-0.4 ms of a 0.5 ms budget, leaving time for a few changes
    // a frame, so the mesh fell further behind (more changes to list, a slower pass).
    std::uint32_t tested = 0;
    m.fresh_worst =
        m.front.evaluate_until(m.cam, cap == 0 ? &m.keyed : nullptr,
                               t0 + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                        (m.deadline - t0) * Impl::kPassShare),
                               &m.pass_cursor, &tested);
    m.st.priority_updates += tested;
  } else {
    m.fresh_worst = m.front.evaluate(m.cam);
    m.st.priority_updates += m.front.size();
  }
  // Under a time budget the queues come from the pass's keyed list (or, with a cap, from the
  // front itself): the change lists are not needed, and collecting them reads every changed
  // entry's record before the first deadline check (0.2-0.4 ms on a 130,000-entry front that the
  // rest of the frame has evicted, most of a 0.5 ms budget).
  if (!m.has_deadline) m.collect();
  // Coherence loses when much of the mesh must go at once (a teleport, a snap turn): a rebuild
  // from the roots then costs less than merging it away first. The merge candidates tell (each
  // cascades up its ancestors); splits alone never do (a threshold drop keeps the whole mesh).
  // Not under a budget: a budgeted update keeps the mesh and improves it in priority order.
  if (settings_.mode == RoamMode::kCoherent && !m.st.rebuilt && (cap == 0 || capped) &&
      !m.has_deadline && m.to_merge.size() > std::max<std::size_t>(512, m.front.size() / 8)) {
    m.reset();
    if (whole) m.build();
    m.fresh_worst = m.front.evaluate(m.cam);
    m.st.priority_updates += m.front.size();
    m.collect();
  }

  if (m.has_deadline && !m.out.compact_pending().empty()) {
    const auto until = std::chrono::steady_clock::now() +
                       std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                           (m.deadline - t0) * Impl::kCompactShare);
    m.compact_output(&until);
  }

  // 3-4. Splits and merges.
  double reached_px = threshold;
  if (capped)
    reached_px = m.converge_capped(camera, threshold, cap);
  else if (cap != 0 || m.has_deadline)
    m.fresh_worst = m.converge_budgeted(threshold, cap);
  else
    m.converge_all();

  // 5. Output: patches whose buffers hold many more slots than live triangles are compacted
  // (under a time budget before the changes, in a share of the budget).
  if (!m.has_deadline) m.compact_output(nullptr);

  // Pages the splits wait for, urgent (loaded by the terrain's workers; resident from a later
  // update on).
  if (!m.page_requests.empty()) {
    std::sort(m.page_requests.begin(), m.page_requests.end(), [](const PageKey& a, const PageKey& b) {
      return std::tie(a.level, a.pz, a.px) < std::tie(b.level, b.pz, b.px);
    });
    m.page_requests.erase(std::unique(m.page_requests.begin(), m.page_requests.end()),
                          m.page_requests.end());
    detail::SurfaceAccess::store(l.terrain().surface()).request(m.page_requests, true);
    m.st.requested_pages = std::uint32_t(m.page_requests.size());
  }

  // Statistics.
  m.st.triangles = m.triangles;
  m.st.front_size = m.front.size();
  // Unbudgeted, every diamond whose test fails ends unsplit and every other one split (or
  // waiting for a tile): the largest failing priority seen is the remaining error. Under a budget
  // the splits left in the queue are added (converge_budgeted()).
  const float remaining = m.fresh_worst;
  m.st.max_remaining_error = remaining;
  m.st.morph_threshold = capped ? reached_px
                         : m.st.stop == StopReason::kTriangleBudget
                             ? std::max(threshold, double(remaining))
                             : threshold;
  m.front.trim();
  m.nodes.trim();
  m.st.memory_bytes = m.nodes.memory_bytes() + m.front.memory_bytes() +
                      (m.to_merge.capacity() + m.to_split.capacity() + m.next_wave.capacity()) *
                          sizeof(std::uint32_t) +
                      m.keyed.capacity() * sizeof(Front::Keyed);
  m.st.output_bytes = m.out.memory_bytes();
  m.st.upload_bytes = m.out.take_upload_bytes();
  m.st.dirty_patches = m.out.dirty_patch_count();
  m.st.update_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return m.st;
}

}  // namespace ridgeline
