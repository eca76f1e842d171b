// Walks over a view's bintrees from the roots: the leaves, the mesh hash, the measured error and
// the structural invariants.
#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <map>

#include "format.h"
#include "ridgeline/log.h"
#include "ridgeline/mesh_error.h"
#include "roam/view/refiner.h"
#include "roam/view/view.h"

namespace ridgeline {

using namespace roam;
using detail::fmt;

namespace roam {

template <class Fn>
void Refiner::walk(Fn&& fn) const {
  struct Item {
    std::uint32_t n;
    std::uint64_t heap;
    LatticeTriangle t;
  };
  std::vector<Item> stack;
  for (std::uint32_t r = 0; r < landscape_.root_count(); ++r) {
    stack.push_back({r, 1, landscape_.triangle(r, 1)});
    while (!stack.empty()) {
      const Item it = stack.back();
      stack.pop_back();
      const Node& nd = nodes_[it.n];
      fn(it.n, r, it.heap, it.t, nd.leaf());
      if (nd.leaf()) continue;
      stack.push_back({nd.first_child() + 1, 2 * it.heap + 1, Landscape::child_triangle(it.t, 1)});
      stack.push_back({nd.first_child(), 2 * it.heap, Landscape::child_triangle(it.t, 0)});
    }
  }
}

void Refiner::rehide(std::int64_t i0, std::int64_t j0, std::int64_t i1, std::int64_t j1) {
  // Down the trees of the patches over the range, into the triangles whose box meets it.
  const std::int64_t cells = landscape_.patch_cells();
  const std::int64_t px0 = std::max<std::int64_t>(0, (i0 - 1) / cells),
                     px1 = std::min<std::int64_t>(landscape_.patches_x() - 1, (i1 + 1) / cells),
                     pz0 = std::max<std::int64_t>(0, (j0 - 1) / cells),
                     pz1 = std::min<std::int64_t>(landscape_.patches_z() - 1, (j1 + 1) / cells);
  std::vector<std::pair<std::uint32_t, LatticeTriangle>> stack;
  for (std::int64_t pz = pz0; pz <= pz1; ++pz)
    for (std::int64_t px = px0; px <= px1; ++px)
      for (std::uint32_t k = 0; k < 2; ++k) {
        const auto root = std::uint32_t(2 * (px + pz * landscape_.patches_x()) + k);
        stack.push_back({root, landscape_.triangle(root, 1)});
        while (!stack.empty()) {
          const auto [n, t] = stack.back();
          stack.pop_back();
          if (std::max({t.ax, t.lx, t.rx}) < i0 || std::min({t.ax, t.lx, t.rx}) > i1 ||
              std::max({t.az, t.lz, t.rz}) < j0 || std::min({t.az, t.lz, t.rz}) > j1)
            continue;
          const Node& nd = nodes_[n];
          if (!nd.leaf()) {
            stack.push_back({nd.first_child(), Landscape::child_triangle(t, 0)});
            stack.push_back({nd.first_child() + 1, Landscape::child_triangle(t, 1)});
            continue;
          }
          const std::uint32_t patch = patch_of(t);
          const bool hide = hidden(t);
          if (hide != output_.hidden(patch, nd.slot()))
            output_.set_triangle(patch, nd.slot(), output_.corners(patch, nd.slot()), hide);
        }
      }
}

}  // namespace roam

void RoamView::for_each_leaf(
    const std::function<void(std::uint32_t, std::uint64_t, const LatticeTriangle&)>& fn) const {
  impl_->refiner.walk([&](std::uint32_t, std::uint32_t root, std::uint64_t heap,
                          const LatticeTriangle& t, bool leaf) {
    if (leaf) fn(root, heap, t);
  });
}

std::uint64_t RoamView::mesh_hash() const {
  std::uint64_t h = 1469598103934665603ull;
  for_each_leaf([&](std::uint32_t root, std::uint64_t heap, const LatticeTriangle&) {
    for (std::uint64_t v : {std::uint64_t(root), heap}) {
      h ^= v;
      h *= 1099511628211ull;
    }
  });
  return h;
}

namespace roam {

std::string Refiner::check_invariants() const {
  std::string err;
  std::uint32_t leaves = 0;
  std::vector<std::uint32_t> drawn(landscape_.patch_count(), 0);
  std::vector<std::uint8_t> reached(nodes_.size(), 0);
  walk([&](std::uint32_t n, std::uint32_t root, std::uint64_t heap, const LatticeTriangle& t,
             bool leaf) {
    if (!err.empty()) return;
    reached[n] = 1;
    const Node& nd = nodes_[n];
    const std::int64_t ci = (t.lx + t.rx) / 2, cj = (t.lz + t.rz) / 2;
    if (!leaf) {
      // Its vertex slot holds its hypotenuse's midpoint in its patch's buffers.
      const std::uint32_t patch = patch_of(t), v = nd.midpoint_slot();
      if (v >= output_.vertex_slots(patch) || !output_.vertex_live(patch, v) ||
          output_.coord(patch, v) != std::array<std::int64_t, 2>{ci, cj}) {
        err = fmt("node %u (root %u heap %llu): vertex slot %u of patch %u is not its midpoint", n,
                  root, static_cast<unsigned long long>(heap), v, patch);
        return;
      }
      // An interior node's diamond has an entry exactly when it is mergeable.
      const bool has = nd.entry() != kNoEntry;
      if (has != mergeable(n)) {
        err = fmt("node %u (root %u heap %llu): mergeable %d but front entry %d", n, root,
                  static_cast<unsigned long long>(heap), int(mergeable(n)), int(has));
        return;
      }
      if (has && nd.entry() >= front_.size()) {
        err = fmt("node %u (root %u heap %llu): stale front entry %u (size %u)", n, root,
                  static_cast<unsigned long long>(heap), nd.entry(), front_.size());
        return;
      }
      if (has) {
        const std::uint32_t e = nd.entry();
        if (front_.ci(e) != ci || front_.cj(e) != cj || !front_.split(e))
          err = fmt("node %u: its front entry (%d, %d) is not its split diamond (%lld, %lld)", n,
                    front_.ci(e), front_.cj(e), static_cast<long long>(ci),
                    static_cast<long long>(cj));
      }
      return;
    }
    ++leaves;
    const bool finest = ((t.lx + t.rx) | (t.lz + t.rz)) & 1;
    if (finest != (nd.entry() == kNoEntry)) {
      err = fmt("leaf %u (root %u heap %llu): finest %d, entry %u", n, root,
                static_cast<unsigned long long>(heap), int(finest), nd.entry());
      return;
    }
    // The leaf's entry is its diamond, unsplit, and its geometry follows from it.
    if (!finest && nd.entry() >= front_.size()) {
      err = fmt("leaf %u (root %u heap %llu) has no front entry", n, root,
                static_cast<unsigned long long>(heap));
      return;
    }
    if (!finest && (front_.ci(nd.entry()) != ci || front_.cj(nd.entry()) != cj ||
                    front_.split(nd.entry()))) {
      err = fmt("leaf %u (root %u heap %llu): entry (%d, %d) split %d, diamond (%lld, %lld)", n,
                root, static_cast<unsigned long long>(heap), front_.ci(nd.entry()),
                front_.cj(nd.entry()), int(front_.split(nd.entry())), static_cast<long long>(ci),
                static_cast<long long>(cj));
      return;
    }
    const LatticeTriangle g = leaf_triangle(n);
    if (g.ax != t.ax || g.az != t.az || g.lx != t.lx || g.lz != t.lz) {
      err = fmt("leaf %u: geometry from its entry differs from the tree's", n);
      return;
    }
    // Its output triangle: the corners' lattice positions are the triangle's.
    const std::uint32_t patch = patch_of(t);
    const auto& k = output_.corners(patch, nd.slot());
    const std::int64_t want[3][2] = {{t.ax, t.az}, {t.lx, t.lz}, {t.rx, t.rz}};
    for (int q = 0; q < 3; ++q) {
      const auto pos = output_.coord(patch, k[q]);
      if (!output_.vertex_live(patch, k[q]) || pos[0] != want[q][0] || pos[1] != want[q][1]) {
        err = fmt("leaf %u: output corner %d is (%lld, %lld), want (%lld, %lld)", n, q,
                  (long long)pos[0], (long long)pos[1], static_cast<long long>(want[q][0]),
                  static_cast<long long>(want[q][1]));
        return;
      }
    }
    drawn[patch] += hidden(t) ? 0 : 1;
    // Links: leaves that link back, through the link their link word names; levels differ by
    // at most one.
    for (std::uint32_t f = 0; f < 3; ++f) {
      const std::uint32_t w = nd.link[f];
      if (w == kNone) continue;
      const std::uint32_t nb = linked_node(w);
      if (nb >= nodes_.size() || !nodes_[nb].leaf()) {
        err = fmt("leaf %u (root %u heap %llu) links to internal node %u", n, root,
                  static_cast<unsigned long long>(heap), nb);
        return;
      }
      if (nodes_[nb].link[back_link(w)] != link_word(n, f)) {
        err = fmt("leaf %u links to %u (its link %u), which does not link back", n, nb, back_link(w));
        return;
      }
    }
    if (nd.base() != kNone) {
      const Node& o = nodes_[linked_node(nd.base())];
      const LatticeTriangle ot = leaf_triangle(linked_node(nd.base()));
      auto len2 = [](const LatticeTriangle& x) {
        return (x.lx - x.rx) * (x.lx - x.rx) + (x.lz - x.rz) * (x.lz - x.rz);
      };
      const bool partner = linked_node(o.base()) == n;
      // A partner shares the hypotenuse; a coarser base neighbour's is sqrt 2 longer.
      if (partner ? len2(ot) != len2(t) : len2(ot) != 2 * len2(t))
        err = fmt("leaf %u and its base neighbour %u differ by more than one level", n,
                  linked_node(nd.base()));
    }
  });
  // Every entry's geometry is its diamond's: level and canonical half hypotenuse.
  for (std::uint32_t e = 0; e < front_.size() && err.empty(); ++e) {
    std::int64_t hu, hw;
    half_hypotenuse(front_.ci(e), front_.cj(e), patch_log2_, hu, hw);
    const auto t = std::uint32_t(std::min(ctz64(front_.ci(e)), ctz64(front_.cj(e))));
    if (hu != front_.hu(e) || hw != front_.hw(e) || t != front_.t(e))
      err = fmt("front entry %u (%d, %d): half hypotenuse (%d, %d) level %u, want (%lld, %lld) %u",
                e, front_.ci(e), front_.cj(e), front_.hu(e), front_.hw(e), front_.t(e),
                static_cast<long long>(hu), static_cast<long long>(hw), t);
  }
  // Every front entry points back at a node of its diamond that is in the trees.
  for (std::uint32_t e = 0; e < front_.size() && err.empty(); ++e) {
    const std::uint32_t n = front_.node(e);
    if (n >= nodes_.size() || !reached[n] || nodes_[n].entry() != e ||
        nodes_[n].leaf() == front_.split(e))
      err = fmt("front entry %u (%d, %d) points at node %u, which is not a %s of its diamond", e,
                front_.ci(e), front_.cj(e), n, front_.split(e) ? "split node" : "leaf");
  }
  if (err.empty() && leaves != triangles_)
    err = fmt("leaf count %u differs from the triangle counter %u", leaves, triangles_);
  if (err.empty())
    for (std::uint32_t p = 0; p < landscape_.patch_count() && err.empty(); ++p)
      if (output_.mesh(p).triangles != drawn[p])
        err =
            fmt("patch %u draws %u triangles, its leaves %u", p, output_.mesh(p).triangles, drawn[p]);
  return err;
}

}  // namespace roam

std::string RoamView::check_invariants() const {
  return impl_->refiner.check_invariants();
}

RoamView::MeasuredError RoamView::measure_error(const Camera& camera, std::uint32_t stride) const {
  // One measurement for tests, `bench lod` and `ridge report` (mesh_error.h).
  const MeshErrorMeter meter(landscape_->terrain(), stride);
  const DrawnHeights drawn = meter.rasterize(leaves_mesh(*this));
  const MeshError e = settings_.metric == ErrorMetric::kScreenPixels ? meter.measure(drawn, camera)
                                                                     : meter.measure_all(drawn);
  return {e.max_m, e.rms_m, e.max_px, e.p99_px, e.vertices - e.uncovered};
}

}  // namespace ridgeline
