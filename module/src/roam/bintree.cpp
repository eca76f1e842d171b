// Bintree operations of a RoamView: diamond split with forced splits (Duchaineau et al. 1997,
// section 4; Turner 2000 for the neighbour links) and diamond merge, each keeping the front (the
// diamonds that may change next) and the patch buffers (what the engine draws) in step.
//
// These run ~1,000 times per update on a moving camera, so they do no more than they must:
// a triangle's corners follow from its diamond's centre and canonical half hypotenuse in a few
// additions (diamond.h, canonical_half()), a triangle's patch from its apex and centre in two
// shifts, and a new vertex takes its height and bounds from the front entry that split.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "ridgeline/detail.h"
#include "ridgeline/log.h"
#include "roam/landscape_access.h"
#include "roam/view_impl.h"

namespace ridgeline {

using namespace roam;

RoamView::Impl::Impl(const Landscape& l)
    : land(l),
      K(l.patch_log2()),
      cache(l.terrain().surface().detail_cache()),
      last_i(LandscapeAccess::last_i(l)),
      last_j(LandscapeAccess::last_j(l)),
      px_count(l.patches_x()),
      sx(float(LandscapeAccess::spacing_x(l))),
      sz(float(LandscapeAccess::spacing_z(l))) {
  // Padding exists only in the last row or column of patches (landscape.h).
  const std::int64_t P = l.patch_cells();
  may_pad = std::int64_t(l.patches_x()) * P > last_i || std::int64_t(l.patches_z()) * P > last_j;
}

// ---- geometry -----------------------------------------------------------------------------------

LatticeTriangle RoamView::Impl::leaf_triangle(std::uint32_t n) const {
  const Node& x = nodes[n];
  if (x.entry() == kNoEntry) {
    // A half-cell triangle of the finest lattice: no diamond of its own (it never splits); its
    // parent's diamond is always mergeable, so the parent has an entry.
    const Node& p = nodes[x.parent];
    return Landscape::child_triangle(entry_triangle(p.entry(), p.side()), int(n - p.a()));
  }
  return entry_triangle(x.entry(), x.side());
}

// ---- front entries
// --------------------------------------------------------------------------------

RoamView::Impl::EntryData RoamView::Impl::entry_data_slow(std::int64_t i,
                                                          std::int64_t j) const {
  DiamondBound b;
  float y;
  switch (reader.stored(i, j, b, y)) {
    case Reader::Vertex::kResident:
      return {float(i) * sx, y, float(j) * sz, cam.world ? b.error : b.morph, b.radius, false};
    case Reader::Vertex::kMissing: {
      // Its page is not resident: the sphere and bound of the nearest resident ancestor, which
      // hold this diamond's (nested), so the test stays conservative until the page arrives.
      std::int64_t ci = i, cj = j;
      for (;;) {
        const Diamond d = diamond_at(ci, cj, K);
        if (d.corner || d.top) break;
        std::int64_t ax, az, bx, bz;
        d.apexes(ax, az, bx, bz);
        for (const auto& p : {std::pair{ax, az}, std::pair{bx, bz}}) {
          if (p.first < 0 || p.second < 0 || diamond_at(p.first, p.second, K).corner) continue;
          DiamondBound pb;
          float py;
          if (reader.stored(p.first, p.second, pb, py) == Reader::Vertex::kResident) {
            const float mu = cam.world ? pb.error : pb.morph;
            return {float(p.first) * sx, py, float(p.second) * sz, mu, pb.radius, true};
          }
        }
        ci = ax, cj = az;  // one level up
        if (ci < 0 || cj < 0) ci = bx, cj = bz;
      }
      // Nothing resident above (cannot happen while the coarse levels are): always split.
      return {float(i) * sx, 0.0f, float(j) * sz, 0.0f, Front::kBorderRadius, true};
    }
    case Reader::Vertex::kDetail:
      break;
  }
  b = LandscapeAccess::compute_detail(land, i, j);
  EntryData v{float(i) * sx, 0.0f, float(j) * sz, cam.world ? b.error : b.morph, b.radius, false};
  if (snapshot != nullptr) {
    const int L = int(land.detail_levels());
    const int tz = std::min({ctz64(i), ctz64(j), L});
    if (tz < L) {
      const DetailTileKey key{std::uint32_t(L - tz), std::int32_t((i >> tz) / kDetailTileCells),
                              std::int32_t((j >> tz) / kDetailTileCells)};
      if (snapshot->find(key) == nullptr) {
        // Its height is the stored surface's plus an unknown detail: widen the sphere by the
        // detail's bound so that it holds every height the vertex may have.
        v.provisional = true;
        v.y = static_cast<float>(land.terrain().surface().vertex_base_height(i, j));
        if (v.r < Front::kBorderRadius) v.r += LandscapeAccess::detail_offset_bound(land, i, j);
        return v;
      }
    }
  }
  v.y = static_cast<float>(land.terrain().surface().vertex_height(i, j));
  return v;
}

std::uint32_t RoamView::Impl::add_entry(std::int64_t i, std::int64_t j, std::int64_t hu,
                                        std::int64_t hw, std::uint32_t n, std::uint32_t partner,
                                        bool split) {
  const EntryData v = entry_data(i, j);
  const std::uint32_t t = std::uint32_t(std::min(ctz64(i), ctz64(j)));
  // The centre's metres as the front's test computes them from lattice indices: float(i) * sx
  // (a provisional diamond's: its ancestor's).
  const std::uint32_t e = front.add(std::int32_t(i), std::int32_t(j), std::int32_t(hu),
                                    std::int32_t(hw), t, v.x, v.y, v.z, v.mu, v.r, n, split,
                                    v.provisional);
  nodes[n].set_entry(e);
  if (partner != kNone) nodes[partner].set_entry(e);
  return e;
}

void RoamView::Impl::remove_entry(std::uint32_t e) {
  const std::uint32_t moved = front.remove(e);
  if (moved == e) return;
  // The moved entry's nodes: its node, and the partner its base link names.
  const std::uint32_t n = front.node(e), w = nodes[n].base();
  nodes[n].set_entry(e);
  if (w != kNone && back(w) == 0) nodes[to(w)].set_entry(e);
}

void RoamView::Impl::refresh_entry(std::uint32_t e) {
  const EntryData v = entry_data(front.ci(e), front.cj(e));
  front.set_data(e, v.x, v.y, v.z, v.mu, v.r);
  front.set_provisional(e, v.provisional);
}

std::uint8_t RoamView::Impl::test_new(std::uint32_t e) {
  ++st.priority_updates;
  float p;
  const std::uint8_t t = front.test_one(e, cam, &p);
  if (t == kInView) fresh_worst = std::max(fresh_worst, p);
  return t;
}

// ---- links
// ----------------------------------------------------------------------------------------

void RoamView::Impl::relink(std::uint32_t w, std::uint32_t word) {
  if (w != kNone) nodes[to(w)].link[back(w)] = word;
}

bool RoamView::Impl::children_leaves(std::uint32_t n) const {
  const Node& x = nodes[n];
  return !x.leaf() && nodes[x.a()].leaf() && nodes[x.a() + 1].leaf();
}

bool RoamView::Impl::mergeable(std::uint32_t n) const {
  if (!children_leaves(n)) return false;
  // The base link says whether the neighbour is a partner (it links back with its own base).
  const std::uint32_t w = nodes[n].base();
  return w == kNone || (back(w) == 0 && children_leaves(to(w)));
}

std::uint32_t RoamView::Impl::split_cost(std::uint32_t n) const {
  std::uint32_t cost = 0;
  for (std::uint32_t x = n;;) {
    const std::uint32_t w = nodes[x].base();
    if (w == kNone) return cost + 1;
    if (back(w) == 0) return cost + 2;  // a partner
    cost += 2;
    x = to(w);
  }
}

// A new leaf `n` with triangle t = (A, L, R): its diamond is centred at the midpoint of L-R.
// It shares its partner's entry when the neighbour across its hypotenuse is a leaf of the same
// diamond; otherwise the diamond joins the front, is tested at once, and goes to `queue` when
// active.
void RoamView::Impl::attach_leaf(std::uint32_t n, const LatticeTriangle& t,
                                 std::vector<std::uint32_t>* queue) {
  const std::int64_t sx2 = t.lx + t.rx, sz2 = t.lz + t.rz;
  if ((sx2 | sz2) & 1) return;  // finest: no diamond (leaf_triangle())
  const std::int64_t ci = sx2 >> 1, cj = sz2 >> 1;
  Node& x = nodes[n];
  x.set_side(apex_side(t.ax, t.az, ci, cj));
  const std::uint32_t w = x.base();
  if (w != kNone && back(w) == 0) {  // a partner (a leaf: leaves link only leaves)
    const std::uint32_t b = to(w);
    const std::uint32_t e = nodes[b].entry();  // the partner's diamond: one entry for both
    x.set_entry(e);
    return;
  }
  std::int64_t hu = t.lx - ci, hw = t.lz - cj;
  canonical_half(hu, hw);
  const std::uint32_t e = add_entry(ci, cj, hu, hw, n, kNone, false);
  if ((test_new(e) & kActive) && queue != nullptr) queue->push_back(n);
}

// ---- detail tiles
// ---------------------------------------------------------------------------------

bool RoamView::Impl::chain_ready(std::uint32_t n) {
  bool ready = true;
  const int L = int(land.detail_levels());
  for (std::uint32_t x = n;;) {
    // The vertex this split creates: its diamond's centre. A stored vertex needs its page, a
    // detail vertex its tile.
    const std::uint32_t xe = nodes[x].entry();
    const std::int64_t ci = front.ci(xe), cj = front.cj(xe);
    const int tz = std::min({ctz64(ci), ctz64(cj), L});
    if (tz < L) {
      const DetailTileKey key{std::uint32_t(L - tz), std::int32_t((ci >> tz) / kDetailTileCells),
                              std::int32_t((cj >> tz) / kDetailTileCells)};
      // Request every missing tile of the chain at once.
      if (cache != nullptr && (snapshot == nullptr || snapshot->find(key) == nullptr))
        ready = cache->request(key) && ready;
    } else {
      DiamondBound b;
      float y;
      PageKey missing;
      if (reader.stored(ci, cj, b, y, &missing) == Reader::Vertex::kMissing) {
        page_requests.push_back(missing);
        ready = false;
      }
    }
    const std::uint32_t w = nodes[x].base();
    if (w == kNone || back(w) == 0) break;
    x = to(w);
  }
  return ready;
}

// ---- split
// ----------------------------------------------------------------------------------------

// Splits triangle p (its triangle t, in `patch`, whose new vertex has slot v there) into its two
// children: c0 = (M, A, L) takes p's triangle slot, c1 = (M, R, A) a new one. Returns c0.
std::uint32_t RoamView::Impl::split_triangle(std::uint32_t p, const LatticeTriangle& t,
                                             std::uint32_t patch, std::uint32_t v) {
  const std::uint32_t c = nodes.alloc_pair();
  Node& x = nodes[p];
  const std::array<std::uint32_t, 3> k = out.corners(patch, x.slot());  // (A, L, R)
  bool pad0 = false, pad1 = false;
  if (may_pad) {
    const LatticeTriangle c0 = Landscape::child_triangle(t, 0),
                          c1 = Landscape::child_triangle(t, 1);
    pad0 = padding(c0), pad1 = padding(c1);
  }
  out.set_triangle(patch, x.slot(), {v, k[0], k[1]}, pad0);
  const std::uint32_t s1 = out.add_triangle(patch, {v, k[2], k[0]}, pad1);
  Node& n0 = nodes[c];
  Node& n1 = nodes[c + 1];
  n0.parent = n1.parent = p;
  n0.set_slot(x.slot());
  n1.set_slot(s1);
  return c;
}

// Links after triangle p split into children c, c + 1 (its vertex slot v), pc the partner's
// children (kNone on the border): each child's base is the parent's outer neighbour on that side;
// across the split hypotenuse the children border the partner's children (c0.b is the partner's
// c1, whose a links back; c1.a is the partner's c0, whose b links back). Every link a store: the
// link words say which link of each neighbour points back.
void RoamView::Impl::link_children(std::uint32_t p, std::uint32_t c, std::uint32_t pc,
                                   std::uint32_t v) {
  Node& x = nodes[p];
  const std::uint32_t left = x.a(), right = x.b();
  Node& n0 = nodes[c];
  Node& n1 = nodes[c + 1];
  n0.base() = left;
  n0.a() = link_word(c + 1, 2);
  n0.b() = pc != kNone ? link_word(pc + 1, 1) : kNone;
  n1.base() = right;
  n1.a() = pc != kNone ? link_word(pc, 2) : kNone;
  n1.b() = link_word(c, 1);
  relink(left, link_word(c, 0));
  relink(right, link_word(c + 1, 0));
  x.a() = c;
  x.b() = v;
  x.set_interior();
}

bool RoamView::Impl::split(std::uint32_t n, bool forced, std::vector<std::uint32_t>* queue) {
  // Make the base neighbour a diamond partner first (forced splits): it is coarser, and its
  // split gives n a partner sharing n's hypotenuse.
  for (std::uint32_t w = nodes[n].base(); w != kNone && back(w) != 0; w = nodes[n].base())
    if (!split(to(w), true, queue)) return false;
  const std::uint32_t e = nodes[n].entry();
  if (front.provisional(e)) {
    // The new vertex's detail tile or page is not resident: request it and wait (the split is
    // tested again next update).
    if (!chain_ready(n)) return false;
    refresh_entry(e);
  }
  // A stored vertex's shading comes from its page when the split writes it: a page evicted
  // since the entry was made is requested again.
  const std::int64_t vi = front.ci(e), vj = front.cj(e);
  if (!front.provisional(e) && reader.address(vi, vj) == nullptr &&
      land.detail_levels() == 0) {
    DiamondBound b;
    float y;
    PageKey missing;
    if (reader.stored(vi, vj, b, y, &missing) == Reader::Vertex::kMissing) {
      page_requests.push_back(missing);
      return false;
    }
  }
  if (forced)
    ++st.forced_splits;
  else
    ++st.splits;
  const std::uint32_t T = n, B = to(nodes[n].base());
  const std::int64_t ci = front.ci(e), cj = front.cj(e), hu = front.hu(e), hw = front.hw(e);
  const std::uint32_t sideT = nodes[T].side();
  const LatticeTriangle tT = diamond_triangle(ci, cj, hu, hw, sideT);
  const std::uint32_t pT = patch_of(tT);
  // The new vertex: height and bounds from the entry; in the tolerance mode the entry holds the
  // error bound, so the output looks its bounds up. An entry still provisional after the
  // refresh above waited on a tile this update's snapshot does not hold yet (a synchronous
  // cache made it resident during the request): its true height comes from the surface.
  if (front.provisional(e)) {
    DiamondBound b;
    float y;
    if (reader.stored(ci, cj, b, y) == Reader::Vertex::kMissing) return false;  // its page
  }
  const float vy = front.provisional(e)
                       ? static_cast<float>(land.terrain().surface().vertex_height(ci, cj))
                       : front.y(e);
  const float vmu = front.mu(e), vr = front.radius(e);
  auto add_vertex = [&](std::uint32_t patch) {
    return cam.world ? out.add_vertex(patch, ci, cj) : out.add_vertex(patch, ci, cj, vy, vmu, vr);
  };
  const std::uint32_t vT = add_vertex(pT);
  LatticeTriangle tB{};
  std::uint32_t pB = pT, vB = vT;
  if (B != kNone) {
    tB = diamond_triangle(ci, cj, hu, hw, sideT ^ 1u);
    pB = patch_of(tB);
    if (pB != pT) vB = add_vertex(pB);
  }
  const std::uint32_t cT = split_triangle(T, tT, pT, vT);
  const std::uint32_t cB = B != kNone ? split_triangle(B, tB, pB, vB) : kNone;
  link_children(T, cT, cB, vT);
  if (B != kNone) link_children(B, cB, cT, vB);
  triangles += B != kNone ? 2 : 1;
  // Front: the diamond is now split and mergeable; its parents' diamonds no longer are; the
  // children's diamonds join the front.
  front.set_split(e, true);
  for (std::uint32_t p : {nodes[T].parent, B != kNone ? nodes[B].parent : kNone}) {
    if (p == kNone || nodes[p].entry() == kNoEntry) continue;
    const std::uint32_t pe = nodes[p].entry();
    // The parent diamond's nodes: p and its partner (its base link's, when a partner).
    const std::uint32_t w = nodes[p].base();
    remove_entry(pe);
    nodes[p].set_entry(kNoEntry);
    if (w != kNone && back(w) == 0) nodes[to(w)].set_entry(kNoEntry);
  }
  attach_leaf(cT, Landscape::child_triangle(tT, 0), queue);
  attach_leaf(cT + 1, Landscape::child_triangle(tT, 1), queue);
  if (B != kNone) {
    attach_leaf(cB, Landscape::child_triangle(tB, 0), queue);
    attach_leaf(cB + 1, Landscape::child_triangle(tB, 1), queue);
  }
  return true;
}

// ---- merge
// ----------------------------------------------------------------------------------------

void RoamView::Impl::merge(std::uint32_t n, std::vector<std::uint32_t>* queue) {
  ++st.merges;
  const std::uint32_t T = n, B = to(nodes[n].base());
  const std::uint32_t e = nodes[T].entry();
  const std::int64_t ci = front.ci(e), cj = front.cj(e), hu = front.hu(e), hw = front.hw(e);
  // A child's diamond is shared with the neighbour across its hypotenuse, or the child's alone.
  auto detach = [&](std::uint32_t c) {
    const std::uint32_t ce = nodes[c].entry();
    if (ce == kNoEntry) return;  // finest
    const std::uint32_t w = nodes[c].base();
    if (w == kNone || back(w) != 0)
      remove_entry(ce);
    else
      front.set_node(ce, to(w));  // shared with a partner: the partner's alone now
  };
  std::uint32_t vM = kNone, pM = kNone;
  LatticeTriangle tT{};
  auto collapse = [&](std::uint32_t p) {
    Node& x = nodes[p];
    const std::uint32_t c0 = x.a(), c1 = c0 + 1, vslot = x.b();
    const std::uint32_t left = nodes[c0].base(), right = nodes[c1].base();
    const LatticeTriangle whole = diamond_triangle(ci, cj, hu, hw, x.side());
    if (p == T) tT = whole;
    const std::uint32_t patch = patch_of(whole);
    const std::array<std::uint32_t, 3> k0 = out.corners(patch, nodes[c0].slot());  // (M, A, L)
    const std::array<std::uint32_t, 3> k1 = out.corners(patch, nodes[c1].slot());  // (M, R, A)
    detach(c0);
    detach(c1);
    relink(left, link_word(p, 1));
    relink(right, link_word(p, 2));
    out.set_triangle(patch, nodes[c0].slot(), {k0[1], k0[2], k1[1]}, may_pad && padding(whole));
    out.remove_triangle(patch, nodes[c1].slot());
    if (!(vslot == vM && patch == pM)) out.remove_vertex(patch, vslot);
    vM = vslot, pM = patch;
    x.set_slot(nodes[c0].slot());
    x.a() = left;
    x.b() = right;
    nodes.free_pair(c0);
  };
  collapse(T);
  if (B != kNone) collapse(B);
  triangles -= B != kNone ? 2 : 1;
  // Removing the children's entries may have moved this diamond's: read it again.
  front.set_split(nodes[T].entry(), false);
  // Parents whose children are now all leaves become mergeable: their diamond is centred at
  // the apex of their children.
  for (std::uint32_t k = 0; k < 2; ++k) {
    const std::uint32_t c = k == 0 ? T : B;
    if (c == kNone) continue;
    const std::uint32_t p = nodes[c].parent;
    if (p == kNone || nodes[p].entry() != kNoEntry || !mergeable(p)) continue;
    const LatticeTriangle t = k == 0 ? tT : diamond_triangle(ci, cj, hu, hw, nodes[B].side());
    // c is (M, A_p, L_p) when it is child 0 of p, (M, R_p, A_p) when child 1; p's half
    // hypotenuse runs from M to L_p (child 0) or R_p (child 1), and A_p sets p's side.
    const bool first = nodes[p].a() == c;
    [[maybe_unused]] const std::int64_t ax = first ? t.lx : t.rx, az = first ? t.lz : t.rz;  // A_p
    std::int64_t phu = first ? t.rx - t.ax : t.lx - t.ax, phw = first ? t.rz - t.az : t.lz - t.az;
    canonical_half(phu, phw);
    const std::uint32_t pb = to(nodes[p].base());
    RIDGELINE_ASSERT(nodes[p].side() == apex_side(ax, az, t.ax, t.az));
    const std::uint32_t pe = add_entry(t.ax, t.az, phu, phw, p, pb, true);
    if (!(test_new(pe) & kActive) && queue != nullptr) queue->push_back(p);
  }
}

// ---- reset
// ------------------------------------------------------------------------------------------

void RoamView::Impl::reset() {
  const std::uint32_t px = land.patches_x(), pz = land.patches_z();
  nodes.reset(land.root_count());
  front.clear();
  out.reset(land, reader);
  const std::int64_t P = land.patch_cells();
  for (std::uint32_t z = 0; z < pz; ++z) {
    for (std::uint32_t x = 0; x < px; ++x) {
      const std::uint32_t p = x + z * px;
      Node& r0 = nodes[2 * p];
      Node& r1 = nodes[2 * p + 1];
      r0.base() = link_word(2 * p + 1, 0);
      r1.base() = link_word(2 * p, 0);
      // root 0: apex (P, 0), left edge z = 0 (towards -z), right edge x = P (towards +x)
      r0.a() = z > 0 ? link_word(2 * (p - px) + 1, 1) : kNone;
      r0.b() = x + 1 < px ? link_word(2 * (p + 1) + 1, 2) : kNone;
      // root 1: apex (0, P), left edge z = P (towards +z), right edge x = 0 (towards -x)
      r1.a() = z + 1 < pz ? link_word(2 * (p + px), 1) : kNone;
      r1.b() = x > 0 ? link_word(2 * (p - 1), 2) : kNone;
      r0.set_slot(0);
      r1.set_slot(1);
      const std::int64_t ci = std::int64_t(x) * P + P / 2, cj = std::int64_t(z) * P + P / 2;
      const LatticeTriangle t0 = land.triangle(2 * p, 1);
      std::int64_t hu, hw;
      half_hypotenuse(ci, cj, K, hu, hw);
      add_entry(ci, cj, hu, hw, 2 * p, 2 * p + 1, false);
      r0.set_side(apex_side(t0.ax, t0.az, ci, cj));
      r1.set_side(r0.side() ^ 1u);
    }
  }
  triangles = land.root_count();
  st.rebuilt = true;
}

}  // namespace ridgeline
