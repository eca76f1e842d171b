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
// which runs after it (RoamView::update()).
#include <algorithm>

#include "roam/landscape_access.h"
#include "roam/view/refiner.h"

namespace ridgeline::roam {

// A diamond's entry from data already read: node, and its partner when there is one.
// (Defined here, its one caller's file, so that it inlines into the build's loop.)
void Refiner::add_entry(const BuildDiamond& d, const EntryData& v, bool split) {
  const std::uint32_t t = std::uint32_t(std::min(ctz64(d.ci), ctz64(d.cj)));
  const std::uint32_t e = front_.add(d.ci, d.cj, d.hu, d.hw, t, v.x, v.y, v.z, v.bound, v.radius,
                                     d.node, split, v.provisional);
  nodes_[d.node].set_entry(e);
  if (d.partner != kNone) nodes_[d.partner].set_entry(e);
}

// The leaves a split made whose diamond became complete (both triangles present, or one on the
// landscape's border) go to `wave` as the next level's diamonds; the others to `lonely`.
void Refiner::build_children(std::uint32_t c, const LatticeTriangle& t,
                             std::vector<BuildDiamond>& wave, std::vector<BuildDiamond>& lonely) {
  for (std::uint32_t k = 0; k < 2; ++k) {
    const std::uint32_t n = c + k;
    const LatticeTriangle ct = Landscape::child_triangle(t, int(k));
    const std::int64_t twice_ci = ct.lx + ct.rx, twice_cj = ct.lz + ct.rz;
    if ((twice_ci | twice_cj) & 1) continue;  // finest: no diamond (leaf_triangle())
    const std::int64_t ci = twice_ci >> 1, cj = twice_cj >> 1;
    nodes_[n].set_side(apex_side(ct.ax, ct.az, ci, cj));
    std::int64_t hu = ct.lx - ci, hw = ct.lz - cj;
    canonical_half(hu, hw);
    const std::uint32_t w = nodes_[n].base();
    const bool coarser = is_coarser(w);  // the neighbour is coarser (for now)
    (coarser ? lonely : wave)
        .push_back({n, coarser ? kNone : linked_node(w), std::int32_t(ci), std::int32_t(cj),
                    std::int32_t(hu), std::int32_t(hw)});
    // Its height is read when the next level is built (after the rest of this one), or at the
    // patch's end when it stays alone: fetched now, so that the misses overlap the work in
    // between (and again a few items ahead, build_from_roots()).
    source_.prefetch(ci, cj);
  }
}

void Refiner::build_from_roots() {
  const std::int64_t cells = landscape_.patch_cells();
  const std::uint32_t px = landscape_.patches_x(), pz = landscape_.patches_z();
  // reset_to_roots() made the roots and their entries; entries come back below, for the final
  // diamonds.
  front_.clear();
  // This level's diamonds, the next level's, the split ones (mergeable at the end when their
  // children stay unsplit) and the lonely triangles (a diamond of one triangle: its neighbour
  // across the hypotenuse stayed coarser). As long as the largest patch's levels (100-300 KiB
  // near the eye): made per build, not kept in the view between builds.
  std::vector<BuildDiamond> wave, next, split_diamonds, lonely;
  // A level's lists are thousands of diamonds long in the patches near the eye: the records
  // fetched when an item was pushed (build_children()) may be gone from the caches by the time
  // it is built, so they are fetched again a few items ahead (measured: 8 ahead, 11 % off a
  // rebuild; 16 the same; also fetching the parent's triangle slot cost 10 %).
  constexpr std::size_t kAhead = 8;
  // One level of diamonds: each tested, split when active; the next level's complete diamonds
  // to `next`.
  auto build_level = [&]() {
    for (std::size_t k = 0; k < wave.size(); ++k) {
      if (k + kAhead < wave.size()) source_.prefetch(wave[k + kAhead].ci, wave[k + kAhead].cj);
      const BuildDiamond& d = wave[k];
      // A diamond whose first triangle an earlier patch's build left alone (and entered as a
      // diamond of one triangle): that entry goes; the diamond is entered again below, or split.
      // (A move of that entry inside the front may have pointed the node at it too: its partner
      // link names the partner since the pairing.)
      if (d.partner != kNone && nodes_[d.partner].entry() != kNoEntry) {
        remove_entry(nodes_[d.partner].entry());
        nodes_[d.partner].set_entry(kNoEntry);
        nodes_[d.node].set_entry(kNoEntry);
      }
      const EntryData v = source_.read(d.ci, d.cj);
      ++stats_.priority_updates;
      const std::uint8_t test = Front::test_values(v.x, v.y, v.z, v.bound, v.radius, camera_);
      // Waiting for a detail tile or a page: left to the update's pass (split(), chain_ready()).
      if (!(test & kActive) || v.provisional) {
        add_entry(d, v, false);
        continue;
      }
      ++stats_.splits;
      const std::uint32_t node = d.node, partner = d.partner;
      const std::uint32_t node_side = nodes_[node].side();
      const LatticeTriangle node_triangle = triangle_of_diamond(d.ci, d.cj, d.hu, d.hw, node_side);
      const std::uint32_t node_patch = patch_of(node_triangle);
      auto add_vertex = [&](std::uint32_t patch) {
        return camera_.world ? output_.add_vertex(patch, d.ci, d.cj)
                             : output_.add_vertex(patch, d.ci, d.cj, v.y, v.bound, v.radius);
      };
      const std::uint32_t node_vertex = add_vertex(node_patch);
      LatticeTriangle partner_triangle{};
      std::uint32_t partner_patch = node_patch, partner_vertex = node_vertex;
      if (partner != kNone) {
        partner_triangle = triangle_of_diamond(d.ci, d.cj, d.hu, d.hw, node_side ^ 1u);
        partner_patch = patch_of(partner_triangle);
        if (partner_patch != node_patch) partner_vertex = add_vertex(partner_patch);
      }
      // A parent an earlier patch's build entered as mergeable no longer is.
      remove_parent_entries(node, partner);
      const std::uint32_t node_children =
          split_triangle(node, node_triangle, node_patch, node_vertex);
      const std::uint32_t partner_children =
          partner != kNone
              ? split_triangle(partner, partner_triangle, partner_patch, partner_vertex)
              : kNone;
      link_children(node, node_children, partner_children, node_vertex);
      if (partner != kNone) link_children(partner, partner_children, node_children, partner_vertex);
      triangles_ += partner != kNone ? 2 : 1;
      split_diamonds.push_back(d);
      split_diamonds.back().data = v;
      build_children(node_children, node_triangle, next, lonely);
      if (partner != kNone) build_children(partner_children, partner_triangle, next, lonely);
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
      nodes_[2 * p].set_entry(kNoEntry);
      nodes_[2 * p + 1].set_entry(kNoEntry);
      const std::int64_t ci = std::int64_t(x) * cells + cells / 2;
      const std::int64_t cj = std::int64_t(z) * cells + cells / 2;
      std::int64_t hu, hw;
      half_hypotenuse(ci, cj, patch_log2_, hu, hw);
      wave.assign(1, {2 * p, 2 * p + 1, std::int32_t(ci), std::int32_t(cj), std::int32_t(hu),
                      std::int32_t(hw)});
      split_diamonds.clear();
      lonely.clear();
      while (!wave.empty()) {
        next.clear();
        build_level();
        wave.swap(next);
      }
      // Leaves whose neighbour across the hypotenuse stayed coarser: a diamond of one triangle
      // in the mesh (a split of it would be forced), unless a later split paired it (those are
      // dropped first, so that the records are fetched kAhead entries ahead).
      lonely.erase(std::remove_if(lonely.begin(), lonely.end(),
                                  [&](const BuildDiamond& d) {
                                    return is_partner(nodes_[d.node].base());  // paired, built
                                  }),
                   lonely.end());
      for (std::size_t k = 0; k < lonely.size(); ++k) {
        if (k + kAhead < lonely.size()) source_.prefetch(lonely[k + kAhead].ci, lonely[k + kAhead].cj);
        const BuildDiamond& d = lonely[k];
        add_entry(d, source_.read(d.ci, d.cj), false);
      }
      // A split diamond whose children all stayed unsplit may merge: it joins the front.
      for (const BuildDiamond& d : split_diamonds)
        if (children_are_leaves(d.node) && (d.partner == kNone || children_are_leaves(d.partner)))
          add_entry(d, d.data, true);
    }
  stats_.rebuilt = true;
}

}  // namespace ridgeline::roam
