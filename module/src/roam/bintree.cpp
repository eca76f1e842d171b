// Bintree operations of a RoamView: diamond split with forced splits (Duchaineau et al. 1997,
// section 4; Turner 2000 for the neighbour links) and diamond merge, each keeping the front (the
// diamonds that may change next) and the patch buffers (what the engine draws) in step.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "ridgeline/detail.h"
#include "ridgeline/log.h"
#include "roam/view_impl.h"

namespace ridgeline {

using namespace roam;

RoamView::Impl::Impl(const Landscape& l)
    : land(l), K(l.patch_log2()), cache(l.terrain().detail_cache()) {}

// ---- geometry -----------------------------------------------------------------------------------

LatticeTriangle RoamView::Impl::diamond_triangle(std::int64_t i, std::int64_t j,
                                                 std::uint32_t side) const {
  const Diamond d = diamond_at(i, j, K);
  std::int64_t h0x, h0z, h1x, h1z;
  d.hypotenuse(h0x, h0z, h1x, h1z);
  // The apexes lie a half hypotenuse from the centre, perpendicular to it.
  const std::int64_t dx = h1x - i, dz = h1z - j;
  std::int64_t ax = i - dz, az = j + dx;
  if (apex_side(ax, az, i, j) != side) ax = i + dz, az = j - dx;
  // (apex, left, right) counter-clockwise seen from above (landscape.h's convention).
  const std::int64_t cross = (h0z - az) * (h1x - ax) - (h0x - ax) * (h1z - az);
  if (cross > 0) return {ax, az, h0x, h0z, h1x, h1z};
  return {ax, az, h1x, h1z, h0x, h0z};
}

std::uint32_t RoamView::Impl::side_of(const LatticeTriangle& t) const {
  return apex_side(t.ax, t.az, (t.lx + t.rx) / 2, (t.lz + t.rz) / 2);
}

LatticeTriangle RoamView::Impl::leaf_triangle(std::uint32_t n) const {
  const Node& x = nodes[n];
  if (x.entry() == kNoEntry) {
    // A half-cell triangle of the finest lattice: no diamond of its own (it never splits); its
    // parent's diamond is always mergeable, so the parent has an entry.
    const Node& p = nodes[x.parent];
    const std::uint32_t pe = p.entry();
    return Landscape::child_triangle(diamond_triangle(front.ci(pe), front.cj(pe), p.side()),
                                     int(n - p.a));
  }
  const std::uint32_t e = x.entry();
  return diamond_triangle(front.ci(e), front.cj(e), x.side());
}

std::uint32_t RoamView::Impl::patch_of(const LatticeTriangle& t) const {
  // The centroid's patch (coordinates are never negative; a constant divisor and a shift).
  const std::int64_t px =
      std::min<std::int64_t>(((t.ax + t.lx + t.rx) / 3) >> K, land.patches_x() - 1);
  const std::int64_t pz =
      std::min<std::int64_t>(((t.az + t.lz + t.rz) / 3) >> K, land.patches_z() - 1);
  return std::uint32_t(px + pz * land.patches_x());
}

bool RoamView::Impl::padding(const LatticeTriangle& t) const {
  return std::min({t.ax, t.lx, t.rx}) >= land.last_i() ||
         std::min({t.az, t.lz, t.rz}) >= land.last_j();
}

// ---- front entries
// --------------------------------------------------------------------------------

void RoamView::Impl::entry_data(std::int64_t i, std::int64_t j, float& y, float& mu, float& r,
                                bool& provisional) const {
  const DiamondBound b = land.diamond(i, j);
  mu = cam.world ? b.error : b.morph;
  r = b.radius;
  provisional = false;
  if (snapshot != nullptr) {
    const int L = int(land.detail_levels());
    const int tz = std::min({ctz64(i), ctz64(j), L});
    if (tz < L) {
      const DetailTileKey key{std::uint32_t(L - tz), std::int32_t((i >> tz) / kDetailTileCells),
                              std::int32_t((j >> tz) / kDetailTileCells)};
      if (snapshot->find(key) == nullptr) {
        // Its height is the stored surface's plus an unknown detail: widen the sphere by the
        // detail's bound so that it holds every height the vertex may have.
        provisional = true;
        y = land.base_lattice_height(i, j);
        if (r < 3.0e38f) r += land.detail_offset_bound(i, j);
        return;
      }
    }
  }
  y = land.lattice_height(i, j);
}

std::uint32_t RoamView::Impl::add_entry(std::int64_t i, std::int64_t j, std::uint32_t n,
                                        std::uint32_t partner, bool split) {
  float y, mu, r;
  bool prov;
  entry_data(i, j, y, mu, r, prov);
  const std::uint32_t t = std::uint32_t(std::min(ctz64(i), ctz64(j)));
  const std::uint32_t e = front.add(std::int32_t(i), std::int32_t(j), t, y, mu, r, n, split, prov);
  nodes[n].set_entry(e);
  if (partner != kNone) nodes[partner].set_entry(e);
  return e;
}

std::array<std::uint32_t, 2> RoamView::Impl::entry_nodes(std::uint32_t e) const {
  const std::uint32_t n = front.node(e);
  const std::uint32_t b = nodes[n].base;
  if (b != kNone && nodes[b].base == n) return {n, b};  // partners share a diamond
  return {n, kNone};
}

void RoamView::Impl::remove_entry(std::uint32_t e) {
  const std::uint32_t moved = front.remove(e);
  if (moved == e) return;
  for (std::uint32_t n : entry_nodes(e))
    if (n != kNone) nodes[n].set_entry(e);
}

void RoamView::Impl::refresh_entry(std::uint32_t e) {
  float y, mu, r;
  bool prov;
  entry_data(front.ci(e), front.cj(e), y, mu, r, prov);
  front.set_data(e, y, mu, r);
  front.set_provisional(e, prov);
}

// ---- links
// ----------------------------------------------------------------------------------------

void RoamView::Impl::replace_link(std::uint32_t n, std::uint32_t from, std::uint32_t to) {
  if (n == kNone) return;
  Node& x = nodes[n];
  if (x.base == from)
    x.base = to;
  else if (x.a == from)
    x.a = to;
  else if (x.b == from)
    x.b = to;
  else
    RIDGELINE_ASSERT(false && "neighbour link not found");
}

bool RoamView::Impl::children_leaves(std::uint32_t n) const {
  const Node& x = nodes[n];
  return !x.leaf() && nodes[x.a].leaf() && nodes[x.a + 1].leaf();
}

bool RoamView::Impl::mergeable(std::uint32_t n) const {
  if (!children_leaves(n)) return false;
  const std::uint32_t b = nodes[n].base;
  return b == kNone || (nodes[b].base == n && children_leaves(b));
}

std::uint32_t RoamView::Impl::split_cost(std::uint32_t n) const {
  std::uint32_t cost = 0;
  for (std::uint32_t x = n;;) {
    const std::uint32_t b = nodes[x].base;
    if (b == kNone) return cost + 1;
    if (nodes[b].base == x) return cost + 2;
    cost += 2;
    x = b;
  }
}

void RoamView::Impl::attach_leaf(std::uint32_t n, const LatticeTriangle& t) {
  if (((t.lx + t.rx) | (t.lz + t.rz)) & 1) return;  // finest: no diamond (leaf_triangle())
  const std::uint32_t b = nodes[n].base;
  nodes[n].set_side(side_of(t));
  if (b != kNone && nodes[b].leaf() && nodes[b].base == n) {
    nodes[n].set_entry(nodes[b].entry());  // the partner's diamond: one entry for both
    return;
  }
  add_entry((t.lx + t.rx) / 2, (t.lz + t.rz) / 2, n, kNone, false);
}

// ---- detail tiles
// ---------------------------------------------------------------------------------

bool RoamView::Impl::chain_ready(std::uint32_t n) {
  if (cache == nullptr) return true;
  bool ready = true;
  const int L = int(land.detail_levels());
  for (std::uint32_t x = n;;) {
    // The vertex this split creates: its diamond's centre. A stored vertex needs no tile.
    const std::uint32_t xe = nodes[x].entry();
    const std::int64_t ci = front.ci(xe), cj = front.cj(xe);
    const int tz = std::min({ctz64(ci), ctz64(cj), L});
    if (tz < L) {
      const DetailTileKey key{std::uint32_t(L - tz), std::int32_t((ci >> tz) / kDetailTileCells),
                              std::int32_t((cj >> tz) / kDetailTileCells)};
      // Request every missing tile of the chain at once.
      if (snapshot == nullptr || snapshot->find(key) == nullptr)
        ready = cache->request(key) && ready;
    }
    const std::uint32_t b = nodes[x].base;
    if (b == kNone || nodes[b].base == x) break;
    x = b;
  }
  return ready;
}

// ---- split
// ----------------------------------------------------------------------------------------

bool RoamView::Impl::split(std::uint32_t n, bool forced, std::vector<std::uint32_t>* queue) {
  // Make the base neighbour a diamond partner first (forced splits): it is coarser, and its
  // split gives n a partner sharing n's hypotenuse.
  while (nodes[n].base != kNone && nodes[nodes[n].base].base != n)
    if (!split(nodes[n].base, true, queue)) return false;
  const std::uint32_t e = nodes[n].entry();
  if (front.provisional(e)) {
    // The new vertex's detail tile is not resident: request it and wait (the split is tested
    // again next update).
    if (!chain_ready(n)) return false;
    refresh_entry(e);
  }
  if (forced)
    ++st.forced_splits;
  else
    ++st.splits;
  const std::uint32_t T = n, B = nodes[n].base;
  const LatticeTriangle tT = leaf_triangle(T);
  const std::int64_t mx = (tT.lx + tT.rx) / 2, mz = (tT.lz + tT.rz) / 2;
  const std::uint32_t pT = patch_of(tT);
  // The new vertex's bounds: the entry holds them in the screen metric (refreshed above when
  // they were provisional).
  DiamondBound vb;
  const DiamondBound* known = nullptr;
  if (!cam.world) {
    vb.morph = front.mu(e);
    vb.radius = front.radius(e);
    known = &vb;
  }
  const std::uint32_t vT = out.add_vertex(pT, mx, mz, known);
  LatticeTriangle tB{};
  std::uint32_t pB = pT, vB = vT;
  if (B != kNone) {
    // The partner is T turned half a turn about the midpoint: (A', R, L), A' = 2M - A.
    tB = {2 * mx - tT.ax, 2 * mz - tT.az, tT.rx, tT.rz, tT.lx, tT.lz};
    pB = patch_of(tB);
    if (pB != pT) vB = out.add_vertex(pB, mx, mz, known);
  }
  // Children: c0 = (M, A, L) takes the parent's triangle slot, c1 = (M, R, A) a new one.
  auto make = [&](std::uint32_t p, const LatticeTriangle& t, std::uint32_t patch, std::uint32_t v,
                  LatticeTriangle ct[2]) {
    const std::uint32_t c = nodes.alloc_pair();
    const std::array<std::uint32_t, 3> k = out.corners(patch, nodes[p].tri);  // (A, L, R)
    ct[0] = Landscape::child_triangle(t, 0);
    ct[1] = Landscape::child_triangle(t, 1);
    out.set_triangle(patch, nodes[p].tri, {v, k[0], k[1]}, padding(ct[0]));
    const std::uint32_t s1 = out.add_triangle(patch, {v, k[2], k[0]}, padding(ct[1]));
    nodes[c].parent = nodes[c + 1].parent = p;
    nodes[c].tri = nodes[p].tri;
    nodes[c + 1].tri = s1;
    return c;
  };
  LatticeTriangle ctT[2], ctB[2];
  const std::uint32_t cT = make(T, tT, pT, vT, ctT);
  const std::uint32_t cB = B != kNone ? make(B, tB, pB, vB, ctB) : kNone;
  // Links: each child's base is the parent's outer neighbour on that side; across the split
  // hypotenuse the children border the partner's children.
  auto link = [&](std::uint32_t p, std::uint32_t c, std::uint32_t right_of_c0,
                  std::uint32_t left_of_c1, std::uint32_t vslot) {
    Node& x = nodes[p];
    const std::uint32_t left = x.a, right = x.b;
    nodes[c].base = left;
    nodes[c].a = c + 1;
    nodes[c].b = right_of_c0;
    nodes[c + 1].base = right;
    nodes[c + 1].a = left_of_c1;
    nodes[c + 1].b = c;
    replace_link(left, p, c);
    replace_link(right, p, c + 1);
    x.a = c;
    x.b = vslot;
    x.tri = kInterior;
  };
  link(T, cT, cB != kNone ? cB + 1 : kNone, cB, vT);
  if (B != kNone) link(B, cB, cT + 1, cT, vB);
  triangles += B != kNone ? 2 : 1;
  // Front: the diamond is now split and mergeable; its parents' diamonds no longer are; the
  // children's diamonds join the front.
  front.set_split(e, true);
  for (std::uint32_t p : {nodes[T].parent, B != kNone ? nodes[B].parent : kNone}) {
    if (p == kNone || nodes[p].entry() == kNoEntry) continue;
    const std::uint32_t pe = nodes[p].entry();
    const auto pn = entry_nodes(pe);
    remove_entry(pe);
    for (std::uint32_t q : pn)
      if (q != kNone) nodes[q].set_entry(kNoEntry);
  }
  const std::uint32_t kids[4] = {cT, cT + 1, cB, cB + 1};
  const LatticeTriangle* kt[4] = {&ctT[0], &ctT[1], &ctB[0], &ctB[1]};
  for (int k = 0; k < (B != kNone ? 4 : 2); ++k) {
    const std::uint32_t c = kids[k];
    const std::uint32_t before = front.size();
    attach_leaf(c, *kt[k]);
    if (front.size() != before) {  // a new diamond: test it now
      const std::uint32_t ce = nodes[c].entry();
      ++st.priority_updates;
      const std::uint8_t t = front.test_one(ce, cam);
      if (t == kInView) fresh_worst = std::max(fresh_worst, front.priority(ce, cam));
      if ((t & kActive) && queue != nullptr) queue->push_back(c);
    }
  }
  return true;
}

// ---- merge
// ----------------------------------------------------------------------------------------

void RoamView::Impl::merge(std::uint32_t n, std::vector<std::uint32_t>* queue) {
  ++st.merges;
  const std::uint32_t T = n, B = nodes[n].base;
  // A child's diamond is shared with the neighbour across its hypotenuse, or the child's alone.
  auto detach = [&](std::uint32_t c) {
    const std::uint32_t ce = nodes[c].entry();
    if (ce == kNoEntry) return;  // finest
    const std::uint32_t b = nodes[c].base;
    const bool shared = b != kNone && nodes[b].leaf() && nodes[b].base == c;
    if (!shared) {
      remove_entry(ce);
    } else if (front.node(ce) == c) {
      front.set_node(ce, b);
    }
  };
  std::uint32_t vM = kNone, pM = kNone;
  auto collapse = [&](std::uint32_t p) {
    Node& x = nodes[p];
    const std::uint32_t c0 = x.a, c1 = c0 + 1, vslot = x.b;
    const std::uint32_t left = nodes[c0].base, right = nodes[c1].base;
    // Geometry and corners first: the children's entries go below.
    const LatticeTriangle t0 = leaf_triangle(c0);  // (M, A, L); the parent is (A, L, 2M - L)
    const LatticeTriangle whole{t0.lx, t0.lz, t0.rx, t0.rz, 2 * t0.ax - t0.rx, 2 * t0.az - t0.rz};
    const std::uint32_t patch = patch_of(t0);
    const std::array<std::uint32_t, 3> k0 = out.corners(patch, nodes[c0].tri);
    const std::array<std::uint32_t, 3> k1 = out.corners(patch, nodes[c1].tri);
    detach(c0);
    detach(c1);
    replace_link(left, c0, p);
    replace_link(right, c1, p);
    out.set_triangle(patch, nodes[c0].tri, {k0[1], k0[2], k1[1]}, padding(whole));
    out.remove_triangle(patch, nodes[c1].tri);
    if (!(vslot == vM && patch == pM)) out.remove_vertex(patch, vslot);
    vM = vslot, pM = patch;
    x.tri = nodes[c0].tri;
    x.a = left;
    x.b = right;
    nodes.free_pair(c0);
  };
  collapse(T);
  if (B != kNone) collapse(B);
  triangles -= B != kNone ? 2 : 1;
  // Removing the children's entries may have moved this diamond's: read it again.
  front.set_split(nodes[T].entry(), false);
  // Parents whose children are now all leaves become mergeable.
  for (std::uint32_t p : {nodes[T].parent, B != kNone ? nodes[B].parent : kNone}) {
    if (p == kNone || nodes[p].entry() != kNoEntry || !mergeable(p)) continue;
    const std::uint32_t pb = nodes[p].base;
    // The parent's diamond is centred at its hypotenuse midpoint: its children's apex.
    const LatticeTriangle ct = leaf_triangle(p == nodes[T].parent ? T : B);
    const std::uint32_t pe = add_entry(ct.ax, ct.az, p, pb, true);
    ++st.priority_updates;
    const std::uint8_t t = front.test_one(pe, cam);
    if (t == kInView) fresh_worst = std::max(fresh_worst, front.priority(pe, cam));
    if (!(t & kActive) && queue != nullptr) queue->push_back(p);
  }
}

// ---- reset
// ------------------------------------------------------------------------------------------

void RoamView::Impl::reset() {
  const std::uint32_t px = land.patches_x(), pz = land.patches_z();
  nodes.reset(land.root_count());
  front.clear();
  out.reset(land);
  const std::int64_t P = land.patch_cells();
  for (std::uint32_t z = 0; z < pz; ++z) {
    for (std::uint32_t x = 0; x < px; ++x) {
      const std::uint32_t p = x + z * px;
      Node& r0 = nodes[2 * p];
      Node& r1 = nodes[2 * p + 1];
      r0.base = 2 * p + 1;
      r1.base = 2 * p;
      // root 0: apex (P, 0), left edge z = 0 (towards -z), right edge x = P (towards +x)
      r0.a = z > 0 ? 2 * (p - px) + 1 : kNone;
      r0.b = x + 1 < px ? 2 * (p + 1) + 1 : kNone;
      // root 1: apex (0, P), left edge z = P (towards +z), right edge x = 0 (towards -x)
      r1.a = z + 1 < pz ? 2 * (p + px) : kNone;
      r1.b = x > 0 ? 2 * (p - 1) : kNone;
      r0.tri = 0;
      r1.tri = 1;
      const std::int64_t ci = std::int64_t(x) * P + P / 2, cj = std::int64_t(z) * P + P / 2;
      const LatticeTriangle t0 = land.triangle(2 * p, 1), t1 = land.triangle(2 * p + 1, 1);
      add_entry(ci, cj, 2 * p, 2 * p + 1, false);
      r0.set_side(side_of(t0));
      r1.set_side(side_of(t1));
    }
  }
  triangles = land.root_count();
  st.rebuilt = true;
}

}  // namespace ridgeline
