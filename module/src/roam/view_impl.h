// Private: the state of one RoamView and the operations its update is made of.
//
//   nodes.h         bintree nodes (24 bytes) in one array that grows in place, sibling pairs
//   reserved.h      address space reserved once, committed as the node and front arrays grow
//   front.h         the split and merge front: every diamond that may change, tested per update
//   patch_output.h  per-patch buffers the engine uploads, patched slot by slot
//   bintree.cpp     split (with forced splits) and merge of diamonds, links, front and output
//                   kept in step
//   build.cpp       the mesh built from the roots in one top-down pass (first update, rebuilds)
//   roam_view.cpp   the update's phases: edits, detail tiles, the test, merges, splits, budgets
//   mesh_walk.cpp   walks from the roots: leaves, hash, measurement, invariants
#pragma once

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <string>
#include <unordered_set>
#include <vector>

#include "ridgeline/roam_view.h"
#include "roam/diamond.h"
#include "roam/front.h"
#include "roam/landscape_access.h"
#include "roam/nodes.h"
#include "roam/patch_output.h"

namespace ridgeline {

class DetailCache;
class DetailSnapshot;

struct RoamView::Impl {
  explicit Impl(const Landscape& l);

  const Landscape& land;
  const int K;  // log2 of patch cells (finest lattice)
  roam::NodePool nodes;
  roam::Front front;
  roam::PatchOutput out;
  roam::FrontCamera cam;
  std::uint32_t triangles = 0;
  // Procedural detail: the terrain's tile cache (null without detail).
  DetailCache* cache = nullptr;
  std::shared_ptr<const DetailSnapshot> snapshot;  // the cache's tiles for this update
  // The terrain's pages for this update (heights, bounds, shading), and the generation of the
  // snapshot the front's provisional entries were last checked against.
  roam::Reader reader;
  std::uint64_t pages_generation = 0;
  std::vector<PageKey> page_requests;  // pages this update's splits wait for (urgent)
  std::uint64_t synced_version = 0;  // the terrain's edit_version() this view has applied
  std::uint64_t tiles_generation = ~std::uint64_t{0};  // the cache's snapshot last seen
  bool reset_pending = true;
  std::unordered_set<std::uint64_t> known_tiles;  // finest tiles resident at the last look

  // Per update.
  RoamStats st;
  float fresh_worst = 0;  // largest priority of a failing test in view seen this update
  std::vector<std::uint32_t> to_merge, to_split;  // nodes (worklists)
  std::vector<std::uint32_t> next_wave;           // converge_all()'s next wave
  std::vector<roam::Front::Keyed> keyed;  // the pass's changed entries and priorities (budgets)
  using QueueItem = std::pair<float, std::uint32_t>;  // priority, node
  std::vector<QueueItem> split_queue, merge_queue;    // converge_budgeted()'s queues
  std::vector<float> key_sample;                      // their cutoff's sample
  std::vector<std::uint32_t> fresh_nodes;             // nodes a budgeted change made or freed
  std::uint32_t budget_ops = 0;                       // changes the last budgeted update made
  bool has_deadline = false;
  std::chrono::steady_clock::time_point deadline;
  std::uint32_t clock_checks = 0;
  /// Operations (splits and merges) an update under a time budget makes before it first reads
  /// the clock (out_of_time()).
  static constexpr std::uint32_t kMinOps = 2;
  // Under a time budget: the share of the budget the front's pass may take, and the chunk the
  // next pass starts at (Front::evaluate_until()).
  static constexpr double kPassShare = 0.4;
  std::uint32_t pass_cursor = 0;
  // Under a triangle cap: the threshold the last update ended at (0: none yet).
  double cap_threshold = 0;

  // Constants of the landscape the hot paths read.
  const std::int64_t last_i, last_j;  // the last sampled lattice index per axis
  const std::uint32_t px_count;       // patches along x
  const float sx, sz;    // metres per finest-lattice step, as the front's test has them
  bool may_pad = false;  // some patch extends past the samples

  // ---- geometry (diamond.h: a triangle from its diamond's centre, half hypotenuse and side) --

  // (Inline: called per split, merge and built diamond from several files; out of line, the
  // returned triangle went through memory and its 16-byte reloads missed store forwarding.)
  static LatticeTriangle diamond_triangle(std::int64_t i, std::int64_t j, std::int64_t hu,
                                          std::int64_t hw, std::uint32_t side) noexcept {
    // sigma = +1 for side 1: A = c + sigma p, L = c + sigma h, R = c - sigma h, p = (-hw, hu).
    const std::int64_t su = side ? hu : -hu, sw = side ? hw : -hw;
    return {i - sw, j + su, i + su, j + sw, i - su, j - sw};
  }
  /// The triangle of side `side` of entry e's diamond.
  LatticeTriangle entry_triangle(std::uint32_t e, std::uint32_t side) const noexcept {
    return diamond_triangle(front.ci(e), front.cj(e), front.hu(e), front.hw(e), side);
  }
  /// The lattice triangle of a leaf (from its entry, or its parent's for the finest level).
  LatticeTriangle leaf_triangle(std::uint32_t n) const;
  /// The patch holding a triangle.
  std::uint32_t patch_of(const LatticeTriangle& t) const noexcept {
    // The midpoint of the median from the apex to the hypotenuse's midpoint is inside the
    // triangle, hence strictly inside its patch: floor((A + M) / 2P) per axis.
    const std::int64_t px = (2 * t.ax + t.lx + t.rx) >> (K + 2);
    const std::int64_t pz = (2 * t.az + t.lz + t.rz) >> (K + 2);
    return std::uint32_t(px + pz * std::int64_t(px_count));
  }
  /// True when every corner of t lies on or past the last sampled row or column: t is over the
  /// padding (not drawn).
  bool padding(const LatticeTriangle& t) const noexcept {
    return std::min(std::min(t.ax, t.lx), t.rx) >= last_i ||
           std::min(std::min(t.az, t.lz), t.rz) >= last_j;
  }

  // ---- front ---------------------------------------------------------------------------------

  /// Adds the entry of the diamond centred at (i, j) with canonical half hypotenuse (hu, hw)
  /// for node `n` (split or not) and points the diamond's nodes at it; returns it. The node's
  /// partner, when given, is pointed at it too.
  std::uint32_t add_entry(std::int64_t i, std::int64_t j, std::int64_t hu, std::int64_t hw,
                          std::uint32_t n, std::uint32_t partner, bool split);
  /// Removes an entry; re-points the nodes of the entry moved into its place.
  void remove_entry(std::uint32_t e);
  /// Recomputes an entry's bounds and position from the landscape.
  void refresh_entry(std::uint32_t e);
  /// What the front's test reads of a diamond: the sphere's centre (its vertex, or for a
  /// provisional diamond one that holds every position the vertex may take) and radius, and its
  /// bound (morph, or error in the tolerance mode). Provisional: its detail tile or its page is
  /// not resident.
  struct EntryData {
    float x, y, z, mu, r;
    bool provisional;
  };
  EntryData entry_data(std::int64_t i, std::int64_t j) const {
    DiamondBound b;
    float y;
    if (reader.stored(i, j, b, y) == roam::Reader::Vertex::kResident)  // stored: one page
      return {float(i) * sx, y, float(j) * sz, cam.world ? b.error : b.morph, b.radius, false};
    return entry_data_slow(i, j);
  }
  /// entry_data() of a vertex without a resident page (procedural detail, or a page to load).
  EntryData entry_data_slow(std::int64_t i, std::int64_t j) const;
  /// Tests a new entry now (counted, and its priority kept for the remaining error).
  std::uint8_t test_new(std::uint32_t e);

  // ---- bintree ---------------------------------------------------------------------------------

  /// Splits leaf n's diamond (after forcing its base neighbour to be its partner). `queue`:
  /// where the new children whose test is active go. Returns false when a detail tile the split
  /// needs is not resident (requested; nothing changed).
  bool split(std::uint32_t n, bool forced, std::vector<std::uint32_t>* queue);
  /// Merges the mergeable diamond of interior node n. `queue`: where parent diamonds that become
  /// mergeable and inactive go.
  void merge(std::uint32_t n, std::vector<std::uint32_t>* queue);
  bool mergeable(std::uint32_t n) const;
  bool children_leaves(std::uint32_t n) const;
  /// Triangles a split of leaf n adds, counting the forced splits it needs.
  std::uint32_t split_cost(std::uint32_t n) const;
  /// True when the vertices a split of n (and its forced chain) creates have their detail
  /// tiles and pages (the missing ones are requested, urgent).
  bool chain_ready(std::uint32_t n);
  /// Points the link of the neighbour that link word w names (the link that pointed back) at
  /// link word `word`; nothing for kNone.
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
  void reset();
  /// A diamond of build(): node T (its side set), partner B (kNone on the border or when
  /// alone), centre and canonical half hypotenuse.
  struct BuildItem {
    std::uint32_t T, B;
    std::int32_t ci, cj, hu, hw;
    EntryData data{};  // a split diamond's entry data (kept for its entry)
  };
  /// After reset(): the mesh the camera's test asks for, built top down, level by level, with
  /// the front and the output (build.cpp). Leaves to the update's pass only what the nesting
  /// does not give (a detail tile to wait for, a rounding case).
  void build();
  void build_children(std::uint32_t c, const LatticeTriangle& t, std::vector<BuildItem>& wave,
                      std::vector<BuildItem>& lonely);
  std::vector<BuildItem> build_wave, build_next, build_split, build_lonely;  // empty between builds
  bool split_candidate(std::uint32_t n) const;
  bool merge_candidate(std::uint32_t n) const;

  // ---- the update's phases (roam_view.cpp) ------------------------------------------------------

  void pull_changes();
  void pull_tiles();
  /// Pages that became resident since the last update: the provisional stored diamonds over
  /// them get their true data.
  void pull_pages();
  /// The front's entries whose test disagrees with their state, into to_merge and to_split.
  void collect();
  void converge_all();
  /// Fetches what the next changes of a worklist (its back is next) will read.
  void prefetch_change(const std::vector<std::uint32_t>& list, bool split) const;
  /// Returns the largest priority in view left unsplit.
  float converge_budgeted(double threshold, std::uint32_t cap);
  /// Splits every active diamond on the data's border still unsplit (and those its splits make),
  /// whatever the triangle cap: the mesh ends on the border like it stays crack-free.
  void split_border();
  /// Under a triangle cap alone: converges at the smallest threshold (>= `threshold`) found
  /// whose mesh fits the cap, starting from the last update's; returns that threshold.
  double converge_capped(const Camera& camera, double threshold, std::uint32_t cap);
  /// Compacts the output of the patches listed as oversized (PatchOutput::compact_pending()),
  /// renumbering their leaves' triangle slots and their interior nodes' vertex slots. With
  /// `until`, only the patches whose estimated cost ends before it (the rest stay listed).
  void compact_output(const std::chrono::steady_clock::time_point* until);
  // Under a time budget: the share of the budget compaction may take (before the changes), and
  // its estimated cost per live triangle of a patch (measured: ~80 ns on the noise flyover).
  static constexpr double kCompactShare = 0.1;
  static constexpr std::int64_t kCompactNsPerTriangle = 100;
  std::vector<std::uint32_t> compact_stack, compact_nodes, compact_order, compact_vmap;  // its
  /// The camera of the front's test at threshold `px`.
  roam::FrontCamera front_camera(const Camera& camera, double px) const;

  // ---- walks (mesh_walk.cpp)
  // ---------------------------------------------------------------------

  /// Depth first over every root's tree, child 0 first: fn(node, root, heap, triangle, leaf).
  template <class Fn>
  void walk(Fn&& fn) const;
  /// RoamView::check_invariants().
  std::string check() const;

  bool out_of_time() {
#ifdef RIDGELINE_ROAM_PARANOID
    // Deterministic budgets for debugging: ROAM_OPS=N stops after N operations.
    static const long ops = std::getenv("ROAM_OPS") ? std::atol(std::getenv("ROAM_OPS")) : 0;
    if (ops > 0) return has_deadline && ++clock_checks > std::uint32_t(ops);
#endif
    // The first kMinOps operations of an update always run, so the mesh keeps moving however
    // small the budget and however slow the machine (a pass that used the whole budget left
    // none: under AddressSanitizer a 0.02 ms budget made no change at all). Then the clock is
    // read at the next check and every eighth after it.
    if (!has_deadline) return false;
    const std::uint32_t k = clock_checks++;
    if (k < kMinOps || ((k - kMinOps) & 7) != 0) return false;
    return std::chrono::steady_clock::now() >= deadline;
  }
};

}  // namespace ridgeline
