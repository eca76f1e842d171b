// Private: the refiner: one view's mesh (bintree nodes, the split and merge front, the patch
// buffers) and the only operations that change it: split (with the forced splits that keep it
// conforming), merge, the mesh built from the roots, and the entries, links and buffer slots
// that each keeps in step. The policies that end a frame (converge_to_threshold.h,
// time_budget.h, triangle_cap.h) choose which diamonds change; the refiner changes them.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "ridgeline/roam_view.h"
#include "roam/diamond.h"
#include "roam/front.h"
#include "roam/nodes.h"
#include "roam/patch_output.h"
#include "roam/view/diamond_source.h"

namespace ridgeline::roam {

class RangePool;

/// The camera of the front's test at `threshold_px` pixels, in the landscape-local frame.
FrontCamera screen_camera(const Landscape& landscape, const Camera& camera, double threshold_px);

class Refiner {
 public:
  /// `source` (read, and asked for the data a split waits for) and `pool` (may be null) must
  /// outlive the refiner.
  Refiner(const Landscape& landscape, DiamondSource& source, RangePool* pool);

  // ---- state -------------------------------------------------------------------------------

  NodePool& nodes() noexcept { return nodes_; }
  const NodePool& nodes() const noexcept { return nodes_; }
  Front& front() noexcept { return front_; }
  const Front& front() const noexcept { return front_; }
  PatchOutput& output() noexcept { return output_; }
  const PatchOutput& output() const noexcept { return output_; }
  const DiamondSource& source() const noexcept { return source_; }
  const Landscape& landscape() const noexcept { return landscape_; }
  /// Leaf triangles of the whole landscape.
  std::uint32_t triangles() const noexcept { return triangles_; }
  /// True when some patch extends past the samples (landscape.h): the border's splits apply.
  bool may_pad() const noexcept { return may_pad_; }

  /// The camera of the front's test (and of every diamond tested on the way).
  const FrontCamera& camera() const noexcept { return camera_; }
  void set_camera(const FrontCamera& c) noexcept { camera_ = c; }
  /// This update's statistics: the refiner counts splits, forced splits, merges and tests into
  /// them; the policies and phases add the rest.
  RoamStats& stats() noexcept { return stats_; }
  /// The largest priority of a diamond in view whose test failed, seen this update (the front's
  /// pass and every diamond tested since): the remaining error of a converged update.
  float worst_failing() const noexcept { return worst_failing_; }
  void set_worst_failing(float p) noexcept { worst_failing_ = p; }

  // ---- the front's test ---------------------------------------------------------------------

  /// Tests every entry of the front for camera() (Front::evaluate()); the largest failing
  /// priority in view becomes worst_failing().
  void test_front();
  /// Recomputes an entry's sphere and bound from the source (an edit, a page's or tile's arrival).
  void refresh_entry(std::uint32_t e);

  // ---- candidates --------------------------------------------------------------------------

  /// Leaf n's diamond is unsplit and its last test says split.
  bool split_candidate(std::uint32_t n) const;
  /// Interior node n's diamond is mergeable and its last test says merge.
  bool merge_candidate(std::uint32_t n) const;
  /// Interior node n's diamond may merge: its children and its partner's are leaves.
  bool mergeable(std::uint32_t n) const;
  /// Triangles a split of leaf n adds, counting the forced splits it needs.
  std::uint32_t split_cost(std::uint32_t n) const;

  // ---- changes -----------------------------------------------------------------------------

  /// Splits leaf n's diamond, after forcing its base neighbour to be its partner (forced
  /// splits, D97 section 4). `queue`: where the new children whose test is active go. Returns
  /// false when a detail tile or page the split needs is not resident (requested; the mesh is
  /// conforming but the split did not happen).
  bool split(std::uint32_t n, bool forced, std::vector<std::uint32_t>* queue);
  /// Merges the mergeable diamond of interior node n. `queue`: where parent diamonds that become
  /// mergeable and whose test fails go.
  void merge(std::uint32_t n, std::vector<std::uint32_t>* queue);
  /// Splits every active diamond on the data's border still unsplit, and those its splits make,
  /// whatever a triangle cap says: the mesh ends on the border as it stays crack-free.
  /// `scratch` is a work list (its contents are lost).
  void split_border_diamonds(std::vector<std::uint32_t>& scratch);

  /// Back to the two root triangles of every patch (nodes, front and buffers); sets
  /// stats().rebuilt.
  void reset_to_roots();
  /// After reset_to_roots(): the mesh the camera's test asks for, built top down, patch by
  /// patch and level by level, with its front and buffers (build_from_roots.cpp). Leaves to the
  /// update's pass only what the nesting of the bounds does not give (a tile or page to wait
  /// for, a rounding case).
  void build_from_roots();

  // ---- geometry ----------------------------------------------------------------------------

  /// The lattice triangle of a leaf (from its entry, or its parent's at the finest level).
  LatticeTriangle leaf_triangle(std::uint32_t n) const;
  /// The triangle of side `side` of entry e's diamond.
  LatticeTriangle entry_triangle(std::uint32_t e, std::uint32_t side) const noexcept {
    return triangle_of_diamond(front_.ci(e), front_.cj(e), front_.hu(e), front_.hw(e), side);
  }
  /// The patch holding a triangle.
  std::uint32_t patch_of(const LatticeTriangle& t) const noexcept {
    // The midpoint of the median from the apex to the hypotenuse's midpoint is inside the
    // triangle, hence strictly inside its patch: floor((A + M) / 2P) per axis.
    const std::int64_t px = (2 * t.ax + t.lx + t.rx) >> (patch_log2_ + 2);
    const std::int64_t pz = (2 * t.az + t.lz + t.rz) >> (patch_log2_ + 2);
    return std::uint32_t(px + pz * std::int64_t(patches_x_));
  }
  /// True when every corner of t lies on or past the last sampled row or column: t is over the
  /// padding (not drawn).
  bool over_padding(const LatticeTriangle& t) const noexcept {
    return std::min(std::min(t.ax, t.lx), t.rx) >= last_i_ ||
           std::min(std::min(t.az, t.lz), t.rz) >= last_j_;
  }
  /// True when t is not drawn: over the padding, or wholly over hole cells (the holes of this
  /// update's reader). A triangle over a hole's edge is never a leaf once converged: its
  /// diamond's sphere is infinite (records.h), so it splits down to half-cells that are wholly
  /// hole or wholly ground, and dropping the hole's leaves leaves a conforming mesh.
  bool hidden(const LatticeTriangle& t) const noexcept {
    if (may_pad_ && over_padding(t)) return true;
    const HoleMask* h = source_.reader().holes();
    return h != nullptr && h->all_holes(t.ax, t.az, t.lx, t.lz, t.rx, t.rz, detail_levels_);
  }
  /// Whether hidden() may be true for some triangle in this update (padding or holes).
  bool may_hide() const noexcept { return may_pad_ || source_.reader().holes() != nullptr; }
  /// After holes changed over finest-lattice vertices [i0, i1] x [j0, j1]: draws or hides every
  /// leaf over them as hidden() now says (its patch's buffers patched).
  void rehide(std::int64_t i0, std::int64_t j0, std::int64_t i1, std::int64_t j1);

  // ---- walks (mesh_walk.cpp) ---------------------------------------------------------------

  /// Depth first over every root's tree, child 0 first: fn(node, root, heap, triangle, leaf).
  template <class Fn>
  void walk(Fn&& fn) const;
  /// RoamView::check_invariants(): "" when they hold.
  std::string check_invariants() const;

  std::size_t memory_bytes() const noexcept {
    return nodes_.memory_bytes() + front_.memory_bytes();
  }

 private:
  /// A diamond of build_from_roots(): its node (side set), its partner (kNone on the border or
  /// while alone), its centre and canonical half hypotenuse, and, once split, its entry data.
  struct BuildDiamond {
    std::uint32_t node, partner;
    std::int32_t ci, cj, hu, hw;
    EntryData data{};
  };

  /// Adds the entry of the diamond centred at (i, j) with canonical half hypotenuse (hu, hw)
  /// for node `n` (split or not) and points n (and `partner`, when given) at it; returns it.
  std::uint32_t add_entry(std::int64_t i, std::int64_t j, std::int64_t hu, std::int64_t hw,
                          std::uint32_t n, std::uint32_t partner, bool split);
  /// Adds a diamond's entry from data already read (the build).
  void add_entry(const BuildDiamond& d, const EntryData& v, bool split);
  /// Removes an entry; re-points the nodes of the entry moved into its place.
  void remove_entry(std::uint32_t e);
  /// Takes a split diamond's parent diamonds out of the front: they are no longer mergeable.
  void remove_parent_entries(std::uint32_t node, std::uint32_t partner);
  /// Tests a new entry now (counted, and its priority kept for worst_failing()).
  std::uint8_t test_new_entry(std::uint32_t e);
  /// True when the vertices a split of n and its forced chain creates have their detail tiles
  /// and pages (every missing one is requested, urgent).
  bool chain_ready(std::uint32_t n);
  bool children_are_leaves(std::uint32_t n) const;
  /// Points the link that link word w names (the neighbour's link back) at link word `word`;
  /// nothing for kNone.
  void relink(std::uint32_t w, std::uint32_t word);
  /// Splits triangle p (t, in `patch`; its new vertex's slot v) into a child pair; returns the
  /// first child.
  std::uint32_t split_triangle(std::uint32_t p, const LatticeTriangle& t, std::uint32_t patch,
                               std::uint32_t v);
  /// Links after triangle p split into children c, c + 1 (new vertex slot v); pc: the
  /// partner's children (kNone on the border).
  void link_children(std::uint32_t p, std::uint32_t c, std::uint32_t pc, std::uint32_t v);
  /// A new leaf's entry: joins its partner's, or a new one (tested; to `queue` when active).
  void attach_leaf(std::uint32_t n, const LatticeTriangle& t, std::vector<std::uint32_t>* queue);
  /// The children of a node split by the build whose diamond is complete go to `wave` (the
  /// next level), the others to `lonely`.
  void build_children(std::uint32_t c, const LatticeTriangle& t, std::vector<BuildDiamond>& wave,
                      std::vector<BuildDiamond>& lonely);

  const Landscape& landscape_;
  DiamondSource& source_;
  // Constants of the landscape the hot paths read.
  const int patch_log2_;               // log2 of a patch's finest-lattice cells
  const std::uint32_t patches_x_;      // patches along x
  const std::int64_t last_i_, last_j_;  // the last sampled lattice index per axis
  const int detail_levels_;             // finest-lattice levels below the stored samples
  bool may_pad_ = false;

  NodePool nodes_;
  Front front_;
  PatchOutput output_;
  std::uint32_t triangles_ = 0;
  FrontCamera camera_;
  RoamStats stats_;
  float worst_failing_ = 0;
};

}  // namespace ridgeline::roam
