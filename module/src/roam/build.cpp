// The mesh of a view built from its roots in one top-down pass (a cold start, a rebuild, a
// teleport): Lindstrom & Pascucci's stateless refinement (SOAR, 2001) writing the view's own
// state, so that the coherent updates carry on from it.
//
// With nested bounds and spheres (landscape.h) the diamonds the test asks to split are closed
// under the hierarchy: a diamond is active only when both its parents are, so both its
// triangles exist by the time its level is reached, and no split ever needs forcing. The build
// goes patch by patch, each patch's tree level by level; a diamond is tested once, from its
// record, and split at once when active.
// What the incremental splits do per split and undo a level later is left out: the front gets
// entries for the final diamonds only (the unsplit ones, and the split ones whose children all
// stay unsplit), with no search for partners (a diamond's two triangles are found as the second
// of them is made). Whatever the build leaves (a diamond waiting for a detail tile, a test that
// float rounding made non-nested) is an ordinary split or merge of the update's usual pass,
// which runs after it (update()).
#include <algorithm>

#include "roam/landscape_access.h"
#include "roam/view_impl.h"

namespace ridgeline {

using namespace roam;

// The leaves a split made whose diamond became complete (both triangles present, or one on the
// landscape's border) go to `wave` as the next level's diamonds; the others to `lonely`.
void RoamView::Impl::build_children(std::uint32_t c, const LatticeTriangle& t,
                                    std::vector<BuildItem>& wave, std::vector<BuildItem>& lonely) {
  for (std::uint32_t k = 0; k < 2; ++k) {
    const std::uint32_t n = c + k;
    const LatticeTriangle ct = Landscape::child_triangle(t, int(k));
    const std::int64_t sx2 = ct.lx + ct.rx, sz2 = ct.lz + ct.rz;
    if ((sx2 | sz2) & 1) continue;  // finest: no diamond (leaf_triangle())
    const std::int64_t ci = sx2 >> 1, cj = sz2 >> 1;
    nodes[n].set_side(apex_side(ct.ax, ct.az, ci, cj));
    std::int64_t hu = ct.lx - ci, hw = ct.lz - cj;
    canonical_half(hu, hw);
    const std::uint32_t w = nodes[n].base();
    const bool coarser = w != kNone && back(w) != 0;  // the neighbour is coarser (for now)
    (coarser ? lonely : wave)
        .push_back({n, coarser ? kNone : to(w), std::int32_t(ci), std::int32_t(cj),
                    std::int32_t(hu), std::int32_t(hw)});
    // Its height is read when the next level is built (after the rest of this one), or at the
    // patch's end when it stays alone: fetched now, so that the misses overlap the work in
    // between (and again a few items ahead, build()).
    if (const void* a = reader.address(ci, cj)) detail::prefetch(a);
  }
}

void RoamView::Impl::build() {
  const std::int64_t P = land.patch_cells();
  const std::uint32_t px = land.patches_x(), pz = land.patches_z();
  // reset() made the roots and their entries; entries come back below, for the final diamonds.
  front.clear();
  std::vector<BuildItem>& wave = build_wave;
  std::vector<BuildItem>& next = build_next;
  std::vector<BuildItem>& splits = build_split;
  std::vector<BuildItem>& lonely = build_lonely;
  // A level's lists are thousands of diamonds long in the patches near the eye: the records
  // fetched when an item was pushed (build_children()) may be gone from the caches by the time
  // it is built, so they are fetched again a few items ahead (measured: 8 ahead, 11 % off a
  // rebuild; 16 the same; also fetching the parent's triangle slot cost 10 %).
  constexpr std::size_t kAhead = 8;
  auto prefetch_record = [&](const BuildItem& d) {
    if (const void* a = reader.address(d.ci, d.cj)) detail::prefetch(a);
  };
  // A diamond's entry: node T, and its partner B when there is one.
  auto enter = [&](const BuildItem& d, const EntryData& v, bool split) {
    const std::uint32_t t = std::uint32_t(std::min(ctz64(d.ci), ctz64(d.cj)));
    const std::uint32_t e = front.add(d.ci, d.cj, d.hu, d.hw, t, v.x, v.y, v.z, v.mu, v.r, d.T,
                                      split, v.provisional);
    nodes[d.T].set_entry(e);
    if (d.B != kNone) nodes[d.B].set_entry(e);
  };
  // One level of diamonds: each tested, split when active; the next level's complete diamonds
  // to `next`.
  auto level = [&]() {
    for (std::size_t k = 0; k < wave.size(); ++k) {
      if (k + kAhead < wave.size()) prefetch_record(wave[k + kAhead]);
      const BuildItem& d = wave[k];
      // A diamond whose first triangle an earlier patch's build left alone (and entered as a
      // diamond of one triangle): that entry goes; the diamond is entered again below, or split.
      // (A move of that entry inside the front may have pointed T at it too: T's partner link
      // names B since the pairing.)
      if (d.B != kNone && nodes[d.B].entry() != kNoEntry) {
        remove_entry(nodes[d.B].entry());
        nodes[d.B].set_entry(kNoEntry);
        nodes[d.T].set_entry(kNoEntry);
      }
      const EntryData v = entry_data(d.ci, d.cj);
      ++st.priority_updates;
      const std::uint8_t test = Front::test_values(v.x, v.y, v.z, v.mu, v.r, cam);
      // Waiting for a detail tile or a page: left to the update's pass (split(), chain_ready()).
      if (!(test & kActive) || v.provisional) {
        enter(d, v, false);
        continue;
      }
      ++st.splits;
      const std::uint32_t T = d.T, B = d.B;
      const std::uint32_t sideT = nodes[T].side();
      const LatticeTriangle tT = diamond_triangle(d.ci, d.cj, d.hu, d.hw, sideT);
      const std::uint32_t pT = patch_of(tT);
      auto add_vertex = [&](std::uint32_t patch) {
        return cam.world ? out.add_vertex(patch, d.ci, d.cj)
                         : out.add_vertex(patch, d.ci, d.cj, v.y, v.mu, v.r);
      };
      const std::uint32_t vT = add_vertex(pT);
      LatticeTriangle tB{};
      std::uint32_t pB = pT, vB = vT;
      if (B != kNone) {
        tB = diamond_triangle(d.ci, d.cj, d.hu, d.hw, sideT ^ 1u);
        pB = patch_of(tB);
        if (pB != pT) vB = add_vertex(pB);
      }
      // A parent an earlier patch's build entered as mergeable no longer is.
      for (const std::uint32_t q : {nodes[T].parent, B != kNone ? nodes[B].parent : kNone}) {
        if (q == kNone || nodes[q].entry() == kNoEntry) continue;
        const std::uint32_t w = nodes[q].base();
        remove_entry(nodes[q].entry());
        nodes[q].set_entry(kNoEntry);
        if (w != kNone && back(w) == 0) nodes[to(w)].set_entry(kNoEntry);
      }
      const std::uint32_t cT = split_triangle(T, tT, pT, vT);
      const std::uint32_t cB = B != kNone ? split_triangle(B, tB, pB, vB) : kNone;
      link_children(T, cT, cB, vT);
      if (B != kNone) link_children(B, cB, cT, vB);
      triangles += B != kNone ? 2 : 1;
      splits.push_back(d);
      splits.back().data = v;
      build_children(cT, tT, next, lonely);
      if (B != kNone) build_children(cB, tB, next, lonely);
    }
  };
  // Patch by patch, each one's tree level by level, so that a patch's records, nodes and
  // buffers stay in the caches while it is built, and the lists stay as short as a patch's
  // levels. A diamond across a patch edge is complete when the second patch makes its other
  // triangle: it is then a diamond of that patch's build (whose lists it joins at the right
  // level), and so are its descendants on either side; what the first patch's build entered
  // for it (its lonely triangle, its parents as mergeable) is taken back then.
  for (std::uint32_t z = 0; z < pz; ++z)
    for (std::uint32_t x = 0; x < px; ++x) {
      const std::uint32_t p = x + z * px;
      nodes[2 * p].set_entry(kNoEntry);
      nodes[2 * p + 1].set_entry(kNoEntry);
      const std::int64_t ci = std::int64_t(x) * P + P / 2, cj = std::int64_t(z) * P + P / 2;
      std::int64_t hu, hw;
      half_hypotenuse(ci, cj, K, hu, hw);
      wave.assign(1, {2 * p, 2 * p + 1, std::int32_t(ci), std::int32_t(cj), std::int32_t(hu),
                      std::int32_t(hw)});
      splits.clear();
      lonely.clear();
      while (!wave.empty()) {
        next.clear();
        level();
        wave.swap(next);
      }
      // Leaves whose neighbour across the hypotenuse stayed coarser: a diamond of one triangle
      // in the mesh (a split of it would be forced), unless a later split paired it (those are
      // dropped first, so that the records are fetched kAhead entries ahead).
      lonely.erase(std::remove_if(lonely.begin(), lonely.end(),
                                  [&](const BuildItem& d) {
                                    const std::uint32_t w = nodes[d.T].base();
                                    return w != kNone && back(w) == 0;  // paired (and built)
                                  }),
                   lonely.end());
      for (std::size_t k = 0; k < lonely.size(); ++k) {
        if (k + kAhead < lonely.size()) prefetch_record(lonely[k + kAhead]);
        const BuildItem& d = lonely[k];
        enter(d, entry_data(d.ci, d.cj), false);
      }
      // A split diamond whose children all stayed unsplit may merge: it joins the front.
      for (const BuildItem& d : splits)
        if (children_leaves(d.T) && (d.B == kNone || children_leaves(d.B)))
          enter(d, d.data, true);
    }
  // The lists are as long as the largest patch's levels (100-300 KiB near the eye): given back,
  // not kept in the view's state between builds.
  for (std::vector<BuildItem>* v : {&wave, &next, &splits, &lonely})
    std::vector<BuildItem>().swap(*v);
  st.rebuilt = true;
}

}  // namespace ridgeline
