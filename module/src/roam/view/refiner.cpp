// The refiner's changes to a view's mesh: diamond split with forced splits (Duchaineau et al.
// 1997, section 4; Turner 2000 for the neighbour links) and diamond merge, each keeping the
// front (the diamonds that may change next) and the patch buffers (what the engine draws) in
// step; and the reset to the roots.
//
// These run ~1,000 times per update on a moving camera, so they do no more than they must:
// a triangle's corners follow from its diamond's centre and canonical half hypotenuse in a few
// additions (diamond.h, canonical_half()), a triangle's patch from its apex and centre in two
// shifts, and a new vertex takes its height and bounds from the front entry that split.
#include "roam/view/refiner.h"

#include <algorithm>
#include <cmath>

#include "ridgeline/log.h"
#include "roam/landscape_access.h"

namespace ridgeline::roam {

FrontCamera screen_camera(const Landscape& landscape, const Camera& camera, double threshold_px) {
  return FrontCamera::screen(camera, threshold_px, LandscapeAccess::world_x(landscape, 0),
                             landscape.terrain().info().height_offset,
                             LandscapeAccess::world_z(landscape, 0),
                             LandscapeAccess::local_extent(landscape));
}

Refiner::Refiner(const Landscape& landscape, DiamondSource& source, RangePool* pool)
    : landscape_(landscape),
      source_(source),
      patch_log2_(landscape.patch_log2()),
      patches_x_(landscape.patches_x()),
      last_i_(LandscapeAccess::last_i(landscape)),
      last_j_(LandscapeAccess::last_j(landscape)),
      detail_levels_(int(landscape.detail_levels())),
      nodes_(pool),
      front_(pool) {
  // Padding exists only in the last row or column of patches (landscape.h).
  const std::int64_t cells = landscape.patch_cells();
  may_pad_ = std::int64_t(landscape.patches_x()) * cells > last_i_ ||
             std::int64_t(landscape.patches_z()) * cells > last_j_;
}

// ---- geometry -----------------------------------------------------------------------------------

LatticeTriangle Refiner::leaf_triangle(std::uint32_t n) const {
  const Node& x = nodes_[n];
  if (x.entry() == kNoEntry) {
    // A half-cell triangle of the finest lattice: no diamond of its own (it never splits); its
    // parent's diamond is always mergeable, so the parent has an entry.
    const Node& p = nodes_[x.parent];
    return Landscape::child_triangle(entry_triangle(p.entry(), p.side()),
                                     int(n - p.first_child()));
  }
  return entry_triangle(x.entry(), x.side());
}

// ---- front entries ------------------------------------------------------------------------------

std::uint32_t Refiner::add_entry(std::int64_t i, std::int64_t j, std::int64_t hu, std::int64_t hw,
                                 std::uint32_t n, std::uint32_t partner, bool split) {
  const EntryData v = source_.read(i, j);
  const std::uint32_t t = std::uint32_t(std::min(ctz64(i), ctz64(j)));
  // The centre's metres as the front's test computes them from lattice indices: float(i) * step
  // (a provisional diamond's: its ancestor's).
  const std::uint32_t e = front_.add(std::int32_t(i), std::int32_t(j), std::int32_t(hu),
                                     std::int32_t(hw), t, v.x, v.y, v.z, v.bound, v.radius, n,
                                     split, v.provisional);
  nodes_[n].set_entry(e);
  if (partner != kNone) nodes_[partner].set_entry(e);
  return e;
}

void Refiner::remove_entry(std::uint32_t e) {
  const std::uint32_t moved = front_.remove(e);
  if (moved == e) return;
  // The moved entry's nodes: its node, and the partner its base link names.
  const std::uint32_t n = front_.node(e), w = nodes_[n].base();
  nodes_[n].set_entry(e);
  if (is_partner(w)) nodes_[linked_node(w)].set_entry(e);
}

void Refiner::remove_parent_entries(std::uint32_t node, std::uint32_t partner) {
  for (const std::uint32_t p : {nodes_[node].parent, partner != kNone ? nodes_[partner].parent
                                                                        : kNone}) {
    if (p == kNone || nodes_[p].entry() == kNoEntry) continue;
    // The parent diamond's nodes: p and its partner (its base link's, when a partner).
    const std::uint32_t w = nodes_[p].base();
    remove_entry(nodes_[p].entry());
    nodes_[p].set_entry(kNoEntry);
    if (is_partner(w)) nodes_[linked_node(w)].set_entry(kNoEntry);
  }
}

void Refiner::refresh_entry(std::uint32_t e) {
  const EntryData v = source_.read(front_.ci(e), front_.cj(e));
  front_.set_data(e, v.x, v.y, v.z, v.bound, v.radius);
  front_.set_provisional(e, v.provisional);
}

void Refiner::test_front() {
  worst_failing_ = front_.evaluate(camera_);
  stats_.priority_updates += front_.size();
}

std::uint8_t Refiner::test_new_entry(std::uint32_t e) {
  ++stats_.priority_updates;
  float p;
  const std::uint8_t t = front_.test_one(e, camera_, &p);
  if (t == kInView) worst_failing_ = std::max(worst_failing_, p);
  return t;
}

// ---- candidates ---------------------------------------------------------------------------------

bool Refiner::split_candidate(std::uint32_t n) const {
  const std::uint32_t e = nodes_[n].entry();
  if (!nodes_[n].leaf() || e == kNoEntry) return false;  // interior, freed, or finest
  return !front_.split(e) && (front_.result(e) & kActive);
}

bool Refiner::merge_candidate(std::uint32_t n) const {
  if (nodes_[n].leaf() || nodes_[n].entry() == kNoEntry) return false;
  const std::uint32_t e = nodes_[n].entry();
  return front_.split(e) && !(front_.result(e) & kActive) && mergeable(n);
}

bool Refiner::children_are_leaves(std::uint32_t n) const {
  const Node& x = nodes_[n];
  return !x.leaf() && nodes_[x.first_child()].leaf() && nodes_[x.first_child() + 1].leaf();
}

bool Refiner::mergeable(std::uint32_t n) const {
  if (!children_are_leaves(n)) return false;
  // The base link says whether the neighbour is a partner (it links back with its own base).
  const std::uint32_t w = nodes_[n].base();
  return w == kNone || (is_partner(w) && children_are_leaves(linked_node(w)));
}

std::uint32_t Refiner::split_cost(std::uint32_t n) const {
  std::uint32_t cost = 0;
  for (std::uint32_t x = n;;) {
    const std::uint32_t w = nodes_[x].base();
    if (w == kNone) return cost + 1;
    if (is_partner(w)) return cost + 2;
    cost += 2;
    x = linked_node(w);
  }
}

// ---- links ----------------------------------------------------------------------------------------

void Refiner::relink(std::uint32_t w, std::uint32_t word) {
  if (w != kNone) nodes_[linked_node(w)].link[back_link(w)] = word;
}

// A new leaf `n` with triangle t = (A, L, R): its diamond is centred at the midpoint of L-R.
// It shares its partner's entry when the neighbour across its hypotenuse is a leaf of the same
// diamond; otherwise the diamond joins the front, is tested at once, and goes to `queue` when
// active.
void Refiner::attach_leaf(std::uint32_t n, const LatticeTriangle& t,
                          std::vector<std::uint32_t>* queue) {
  const std::int64_t twice_ci = t.lx + t.rx, twice_cj = t.lz + t.rz;
  if ((twice_ci | twice_cj) & 1) return;  // finest: no diamond (leaf_triangle())
  const std::int64_t ci = twice_ci >> 1, cj = twice_cj >> 1;
  Node& x = nodes_[n];
  x.set_side(apex_side(t.ax, t.az, ci, cj));
  const std::uint32_t w = x.base();
  if (is_partner(w)) {  // a leaf: leaves link only leaves
    x.set_entry(nodes_[linked_node(w)].entry());  // the partner's diamond: one entry for both
    return;
  }
  std::int64_t hu = t.lx - ci, hw = t.lz - cj;
  canonical_half(hu, hw);
  const std::uint32_t e = add_entry(ci, cj, hu, hw, n, kNone, false);
  if ((test_new_entry(e) & kActive) && queue != nullptr) queue->push_back(n);
}

// Splits triangle p (its triangle t, in `patch`, whose new vertex has slot v there) into its two
// children: c0 = (M, A, L) takes p's triangle slot, c1 = (M, R, A) a new one. Returns c0.
std::uint32_t Refiner::split_triangle(std::uint32_t p, const LatticeTriangle& t,
                                      std::uint32_t patch, std::uint32_t v) {
  const std::uint32_t c = nodes_.alloc_pair();  // before any reference into the nodes
  const Node& x = nodes_[p];
  const std::array<std::uint32_t, 3> k = output_.corners(patch, x.slot());  // (A, L, R)
  bool pad0 = false, pad1 = false;
  if (may_hide()) {
    pad0 = hidden(Landscape::child_triangle(t, 0));
    pad1 = hidden(Landscape::child_triangle(t, 1));
  }
  output_.set_triangle(patch, x.slot(), {v, k[0], k[1]}, pad0);
  const std::uint32_t s1 = output_.add_triangle(patch, {v, k[2], k[0]}, pad1);
  Node& n0 = nodes_[c];
  Node& n1 = nodes_[c + 1];
  n0.parent = n1.parent = p;
  n0.set_slot(x.slot());
  n1.set_slot(s1);
  return c;
}

// Links after triangle p split into children c, c + 1 (its vertex slot v), pc the partner's
// children (kNone on the border): each child's base is the parent's outer neighbour on that side;
// across the split hypotenuse the children border the partner's children (c0's right is the
// partner's c1, whose left links back; c1's left is the partner's c0, whose right links back).
// Every link a store: the link words say which link of each neighbour points back.
void Refiner::link_children(std::uint32_t p, std::uint32_t c, std::uint32_t pc, std::uint32_t v) {
  Node& x = nodes_[p];
  const std::uint32_t left = x.left(), right = x.right();
  Node& n0 = nodes_[c];
  Node& n1 = nodes_[c + 1];
  n0.base() = left;
  n0.left() = link_word(c + 1, kRightLink);
  n0.right() = pc != kNone ? link_word(pc + 1, kLeftLink) : kNone;
  n1.base() = right;
  n1.left() = pc != kNone ? link_word(pc, kRightLink) : kNone;
  n1.right() = link_word(c, kLeftLink);
  relink(left, link_word(c, kBaseLink));
  relink(right, link_word(c + 1, kBaseLink));
  x.make_interior(c, v);
}

// ---- split ------------------------------------------------------------------------------------------

bool Refiner::chain_ready(std::uint32_t n) {
  bool ready = true;
  for (std::uint32_t x = n;;) {
    // The vertex this split creates: its diamond's centre. Every missing tile or page of the
    // chain is requested at once.
    const std::uint32_t e = nodes_[x].entry();
    ready = source_.request_vertex(front_.ci(e), front_.cj(e)) && ready;
    const std::uint32_t w = nodes_[x].base();
    if (!is_coarser(w)) break;
    x = linked_node(w);
  }
  return ready;
}

bool Refiner::split(std::uint32_t n, bool forced, std::vector<std::uint32_t>* queue) {
  // Make the base neighbour a diamond partner first (forced splits): it is coarser, and its
  // split gives n a partner sharing n's hypotenuse.
  for (std::uint32_t w = nodes_[n].base(); is_coarser(w); w = nodes_[n].base())
    if (!split(linked_node(w), true, queue)) return false;
  const std::uint32_t e = nodes_[n].entry();
  if (front_.provisional(e)) {
    // The new vertex's detail tile or page is not resident: request it and wait (the split is
    // tested again next update).
    if (!chain_ready(n)) return false;
    refresh_entry(e);
  }
  const std::int64_t ci = front_.ci(e), cj = front_.cj(e), hu = front_.hu(e), hw = front_.hw(e);
  // A stored vertex's shading comes from its page when the split writes it: a page evicted
  // since the entry was made is requested again.
  if (!front_.provisional(e) && !source_.request_shading(ci, cj)) return false;
  if (forced)
    ++stats_.forced_splits;
  else
    ++stats_.splits;
  const std::uint32_t node = n, partner = linked_node(nodes_[n].base());
  const std::uint32_t node_side = nodes_[node].side();
  const LatticeTriangle node_triangle = triangle_of_diamond(ci, cj, hu, hw, node_side);
  const std::uint32_t node_patch = patch_of(node_triangle);
  // The new vertex: height and bounds from the entry; in the tolerance mode the entry holds the
  // error bound, so the output looks its bounds up. An entry still provisional after the
  // refresh above waited on a tile this update's snapshot does not hold yet (a synchronous
  // cache made it resident during the request): its true height comes from the surface.
  if (front_.provisional(e)) {
    DiamondBound b;
    float y;
    if (source_.reader().stored(ci, cj, b, y) == Reader::Vertex::kMissing) return false;
  }
  const float vertex_y = front_.provisional(e)
                             ? static_cast<float>(landscape_.terrain().surface().vertex_height(ci, cj))
                             : front_.y(e);
  const float vertex_bound = front_.mu(e), vertex_radius = front_.radius(e);
  auto add_vertex = [&](std::uint32_t patch) {
    return camera_.world ? output_.add_vertex(patch, ci, cj)
                         : output_.add_vertex(patch, ci, cj, vertex_y, vertex_bound, vertex_radius);
  };
  const std::uint32_t node_vertex = add_vertex(node_patch);
  LatticeTriangle partner_triangle{};
  std::uint32_t partner_patch = node_patch, partner_vertex = node_vertex;
  if (partner != kNone) {
    partner_triangle = triangle_of_diamond(ci, cj, hu, hw, node_side ^ 1u);
    partner_patch = patch_of(partner_triangle);
    if (partner_patch != node_patch) partner_vertex = add_vertex(partner_patch);
  }
  const std::uint32_t node_children = split_triangle(node, node_triangle, node_patch, node_vertex);
  const std::uint32_t partner_children =
      partner != kNone ? split_triangle(partner, partner_triangle, partner_patch, partner_vertex)
                       : kNone;
  link_children(node, node_children, partner_children, node_vertex);
  if (partner != kNone) link_children(partner, partner_children, node_children, partner_vertex);
  triangles_ += partner != kNone ? 2 : 1;
  // Front: the diamond is now split and mergeable; its parents' diamonds no longer are; the
  // children's diamonds join the front.
  front_.set_split(e, true);
  remove_parent_entries(node, partner);
  attach_leaf(node_children, Landscape::child_triangle(node_triangle, 0), queue);
  attach_leaf(node_children + 1, Landscape::child_triangle(node_triangle, 1), queue);
  if (partner != kNone) {
    attach_leaf(partner_children, Landscape::child_triangle(partner_triangle, 0), queue);
    attach_leaf(partner_children + 1, Landscape::child_triangle(partner_triangle, 1), queue);
  }
  return true;
}

void Refiner::split_border_diamonds(std::vector<std::uint32_t>& work) {
  work.clear();
  for (std::uint32_t e = 0; e < front_.size(); ++e)
    if (!front_.split(e) && (front_.result(e) & kActive) &&
        front_.radius(e) >= Front::kBorderRadius)
      work.push_back(front_.node(e));
  while (!work.empty()) {
    const std::uint32_t n = work.back();
    work.pop_back();
    // The children a split makes that are active go to `work`; only the border's are forced.
    if (split_candidate(n) && front_.radius(nodes_[n].entry()) >= Front::kBorderRadius &&
        !split(n, false, &work))
      ++stats_.pending_splits;
  }
}

// ---- merge ------------------------------------------------------------------------------------------

void Refiner::merge(std::uint32_t n, std::vector<std::uint32_t>* queue) {
  ++stats_.merges;
  const std::uint32_t node = n, partner = linked_node(nodes_[n].base());
  const std::uint32_t e = nodes_[node].entry();
  const std::int64_t ci = front_.ci(e), cj = front_.cj(e), hu = front_.hu(e), hw = front_.hw(e);
  // A child's diamond is shared with the neighbour across its hypotenuse, or the child's alone.
  auto detach = [&](std::uint32_t c) {
    const std::uint32_t ce = nodes_[c].entry();
    if (ce == kNoEntry) return;  // finest
    const std::uint32_t w = nodes_[c].base();
    if (!is_partner(w))
      remove_entry(ce);
    else
      front_.set_node(ce, linked_node(w));  // shared with a partner: the partner's alone now
  };
  // The vertex slot removed last, so that a diamond whose two triangles share a patch removes
  // its vertex once.
  std::uint32_t removed_vertex = kNone, removed_patch = kNone;
  LatticeTriangle node_triangle{};
  auto collapse = [&](std::uint32_t p) {
    Node& x = nodes_[p];
    const std::uint32_t c0 = x.first_child(), c1 = c0 + 1, vertex = x.midpoint_slot();
    const std::uint32_t left = nodes_[c0].base(), right = nodes_[c1].base();
    const LatticeTriangle whole = triangle_of_diamond(ci, cj, hu, hw, x.side());
    if (p == node) node_triangle = whole;
    const std::uint32_t patch = patch_of(whole);
    const auto k0 = output_.corners(patch, nodes_[c0].slot());  // (M, A, L)
    const auto k1 = output_.corners(patch, nodes_[c1].slot());  // (M, R, A)
    detach(c0);
    detach(c1);
    relink(left, link_word(p, kLeftLink));
    relink(right, link_word(p, kRightLink));
    output_.set_triangle(patch, nodes_[c0].slot(), {k0[1], k0[2], k1[1]},
                         may_hide() && hidden(whole));
    output_.remove_triangle(patch, nodes_[c1].slot());
    if (!(vertex == removed_vertex && patch == removed_patch)) output_.remove_vertex(patch, vertex);
    removed_vertex = vertex, removed_patch = patch;
    x.make_leaf(nodes_[c0].slot(), left, right);
    nodes_.free_pair(c0);
  };
  collapse(node);
  if (partner != kNone) collapse(partner);
  triangles_ -= partner != kNone ? 2 : 1;
  // Removing the children's entries may have moved this diamond's: read it again.
  front_.set_split(nodes_[node].entry(), false);
  // Parents whose children are now all leaves become mergeable: their diamond is centred at
  // the apex of their children.
  for (std::uint32_t k = 0; k < 2; ++k) {
    const std::uint32_t c = k == 0 ? node : partner;
    if (c == kNone) continue;
    const std::uint32_t p = nodes_[c].parent;
    if (p == kNone || nodes_[p].entry() != kNoEntry || !mergeable(p)) continue;
    const LatticeTriangle t =
        k == 0 ? node_triangle : triangle_of_diamond(ci, cj, hu, hw, nodes_[partner].side());
    // c is (M, A_p, L_p) when it is child 0 of p, (M, R_p, A_p) when child 1; p's half
    // hypotenuse runs from M to L_p (child 0) or R_p (child 1), and A_p sets p's side.
    const bool first = nodes_[p].first_child() == c;
    [[maybe_unused]] const std::int64_t ax = first ? t.lx : t.rx, az = first ? t.lz : t.rz;
    std::int64_t phu = first ? t.rx - t.ax : t.lx - t.ax, phw = first ? t.rz - t.az : t.lz - t.az;
    canonical_half(phu, phw);
    RIDGELINE_ASSERT(nodes_[p].side() == apex_side(ax, az, t.ax, t.az));
    const std::uint32_t pe = add_entry(t.ax, t.az, phu, phw, p, linked_node(nodes_[p].base()), true);
    if (!(test_new_entry(pe) & kActive) && queue != nullptr) queue->push_back(p);
  }
}

// ---- reset --------------------------------------------------------------------------------------------

void Refiner::reset_to_roots() {
  const std::uint32_t px = landscape_.patches_x(), pz = landscape_.patches_z();
  nodes_.reset(landscape_.root_count());
  front_.clear();
  output_.reset(landscape_, source_.reader());
  const std::int64_t cells = landscape_.patch_cells();
  for (std::uint32_t z = 0; z < pz; ++z) {
    for (std::uint32_t x = 0; x < px; ++x) {
      const std::uint32_t p = x + z * px;
      Node& r0 = nodes_[2 * p];
      Node& r1 = nodes_[2 * p + 1];
      r0.set_slot(0);
      r1.set_slot(1);
      r0.base() = link_word(2 * p + 1, kBaseLink);
      r1.base() = link_word(2 * p, kBaseLink);
      // root 0: apex (P, 0), left edge z = 0 (towards -z), right edge x = P (towards +x)
      r0.left() = z > 0 ? link_word(2 * (p - px) + 1, kLeftLink) : kNone;
      r0.right() = x + 1 < px ? link_word(2 * (p + 1) + 1, kRightLink) : kNone;
      // root 1: apex (0, P), left edge z = P (towards +z), right edge x = 0 (towards -x)
      r1.left() = z + 1 < pz ? link_word(2 * (p + px), kLeftLink) : kNone;
      r1.right() = x > 0 ? link_word(2 * (p - 1), kRightLink) : kNone;
      const std::int64_t ci = std::int64_t(x) * cells + cells / 2;
      const std::int64_t cj = std::int64_t(z) * cells + cells / 2;
      const LatticeTriangle t0 = landscape_.triangle(2 * p, 1);
      std::int64_t hu, hw;
      half_hypotenuse(ci, cj, patch_log2_, hu, hw);
      add_entry(ci, cj, hu, hw, 2 * p, 2 * p + 1, false);
      r0.set_side(apex_side(t0.ax, t0.az, ci, cj));
      r1.set_side(r0.side() ^ 1u);
    }
  }
  triangles_ = landscape_.root_count();
  stats_.rebuilt = true;
}

}  // namespace ridgeline::roam
