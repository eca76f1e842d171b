// Walks over a RoamView's bintrees from the roots: the leaves, the mesh hash, the measured error
// and the structural invariants.
#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <map>

#include "format.h"
#include "ridgeline/log.h"
#include "ridgeline/mesh_error.h"
#include "roam/view_impl.h"

namespace ridgeline {

using namespace roam;
using detail::fmt;

template <class Fn>
void RoamView::Impl::walk(Fn&& fn) const {
  struct Item {
    std::uint32_t n;
    std::uint64_t heap;
    LatticeTriangle t;
  };
  std::vector<Item> stack;
  for (std::uint32_t r = 0; r < land.root_count(); ++r) {
    stack.push_back({r, 1, land.triangle(r, 1)});
    while (!stack.empty()) {
      const Item it = stack.back();
      stack.pop_back();
      const Node& nd = nodes[it.n];
      fn(it.n, r, it.heap, it.t, nd.leaf());
      if (nd.leaf()) continue;
      stack.push_back({nd.a() + 1, 2 * it.heap + 1, Landscape::child_triangle(it.t, 1)});
      stack.push_back({nd.a(), 2 * it.heap, Landscape::child_triangle(it.t, 0)});
    }
  }
}

void RoamView::for_each_leaf(
    const std::function<void(std::uint32_t, std::uint64_t, const LatticeTriangle&)>& fn) const {
  impl_->walk([&](std::uint32_t, std::uint32_t root, std::uint64_t heap, const LatticeTriangle& t,
                  bool leaf) {
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

std::string RoamView::check_invariants() const {
  return impl_->check();
}

std::string RoamView::Impl::check() const {
  const Impl& m = *this;
  std::string err;
  std::uint32_t leaves = 0;
  std::vector<std::uint32_t> drawn(m.land.patch_count(), 0);
  std::vector<std::uint8_t> reached(m.nodes.size(), 0);
  m.walk([&](std::uint32_t n, std::uint32_t root, std::uint64_t heap, const LatticeTriangle& t,
             bool leaf) {
    if (!err.empty()) return;
    reached[n] = 1;
    const Node& nd = m.nodes[n];
    const std::int64_t ci = (t.lx + t.rx) / 2, cj = (t.lz + t.rz) / 2;
    if (!leaf) {
      // Its vertex slot holds its hypotenuse's midpoint in its patch's buffers.
      const std::uint32_t patch = m.patch_of(t), v = nd.b();
      if (v >= m.out.vertex_slots(patch) || !m.out.vertex_live(patch, v) ||
          m.out.coord(patch, v) != std::array<std::int64_t, 2>{ci, cj}) {
        err = fmt("node %u (root %u heap %llu): vertex slot %u of patch %u is not its midpoint", n,
                  root, static_cast<unsigned long long>(heap), v, patch);
        return;
      }
      // An interior node's diamond has an entry exactly when it is mergeable.
      const bool has = nd.entry() != kNoEntry;
      if (has != m.mergeable(n)) {
        err = fmt("node %u (root %u heap %llu): mergeable %d but front entry %d", n, root,
                  static_cast<unsigned long long>(heap), int(m.mergeable(n)), int(has));
        return;
      }
      if (has && nd.entry() >= m.front.size()) {
        err = fmt("node %u (root %u heap %llu): stale front entry %u (size %u)", n, root,
                  static_cast<unsigned long long>(heap), nd.entry(), m.front.size());
        return;
      }
      if (has) {
        const std::uint32_t e = nd.entry();
        if (m.front.ci(e) != ci || m.front.cj(e) != cj || !m.front.split(e))
          err = fmt("node %u: its front entry (%d, %d) is not its split diamond (%lld, %lld)", n,
                    m.front.ci(e), m.front.cj(e), static_cast<long long>(ci),
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
    if (!finest && nd.entry() >= m.front.size()) {
      err = fmt("leaf %u (root %u heap %llu) has no front entry", n, root,
                static_cast<unsigned long long>(heap));
      return;
    }
    if (!finest && (m.front.ci(nd.entry()) != ci || m.front.cj(nd.entry()) != cj ||
                    m.front.split(nd.entry()))) {
      err = fmt("leaf %u (root %u heap %llu): entry (%d, %d) split %d, diamond (%lld, %lld)", n,
                root, static_cast<unsigned long long>(heap), m.front.ci(nd.entry()),
                m.front.cj(nd.entry()), int(m.front.split(nd.entry())), static_cast<long long>(ci),
                static_cast<long long>(cj));
      return;
    }
    const LatticeTriangle g = m.leaf_triangle(n);
    if (g.ax != t.ax || g.az != t.az || g.lx != t.lx || g.lz != t.lz) {
      err = fmt("leaf %u: geometry from its entry differs from the tree's", n);
      return;
    }
    // Its output triangle: the corners' lattice positions are the triangle's.
    const std::uint32_t patch = m.patch_of(t);
    const auto& k = m.out.corners(patch, nd.slot());
    const std::int64_t want[3][2] = {{t.ax, t.az}, {t.lx, t.lz}, {t.rx, t.rz}};
    for (int q = 0; q < 3; ++q) {
      const auto pos = m.out.coord(patch, k[q]);
      if (!m.out.vertex_live(patch, k[q]) || pos[0] != want[q][0] || pos[1] != want[q][1]) {
        err = fmt("leaf %u: output corner %d is (%lld, %lld), want (%lld, %lld)", n, q,
                  (long long)pos[0], (long long)pos[1], static_cast<long long>(want[q][0]),
                  static_cast<long long>(want[q][1]));
        return;
      }
    }
    drawn[patch] += m.padding(t) ? 0 : 1;
    // Links: leaves that link back, through the link their link word names; levels differ by
    // at most one.
    for (std::uint32_t f = 0; f < 3; ++f) {
      const std::uint32_t w = nd.link[f];
      if (w == kNone) continue;
      const std::uint32_t nb = to(w);
      if (nb >= m.nodes.size() || !m.nodes[nb].leaf()) {
        err = fmt("leaf %u (root %u heap %llu) links to internal node %u", n, root,
                  static_cast<unsigned long long>(heap), nb);
        return;
      }
      if (m.nodes[nb].link[back(w)] != link_word(n, f)) {
        err = fmt("leaf %u links to %u (its link %u), which does not link back", n, nb, back(w));
        return;
      }
    }
    if (nd.base() != kNone) {
      const Node& o = m.nodes[to(nd.base())];
      const LatticeTriangle ot = m.leaf_triangle(to(nd.base()));
      auto len2 = [](const LatticeTriangle& x) {
        return (x.lx - x.rx) * (x.lx - x.rx) + (x.lz - x.rz) * (x.lz - x.rz);
      };
      const bool partner = to(o.base()) == n;
      // A partner shares the hypotenuse; a coarser base neighbour's is sqrt 2 longer.
      if (partner ? len2(ot) != len2(t) : len2(ot) != 2 * len2(t))
        err = fmt("leaf %u and its base neighbour %u differ by more than one level", n,
                  to(nd.base()));
    }
  });
  // Every entry's geometry is its diamond's: level and canonical half hypotenuse.
  for (std::uint32_t e = 0; e < m.front.size() && err.empty(); ++e) {
    std::int64_t hu, hw;
    half_hypotenuse(m.front.ci(e), m.front.cj(e), m.K, hu, hw);
    const auto t = std::uint32_t(std::min(ctz64(m.front.ci(e)), ctz64(m.front.cj(e))));
    if (hu != m.front.hu(e) || hw != m.front.hw(e) || t != m.front.t(e))
      err = fmt("front entry %u (%d, %d): half hypotenuse (%d, %d) level %u, want (%lld, %lld) %u",
                e, m.front.ci(e), m.front.cj(e), m.front.hu(e), m.front.hw(e), m.front.t(e),
                static_cast<long long>(hu), static_cast<long long>(hw), t);
  }
  // Every front entry points back at a node of its diamond that is in the trees.
  for (std::uint32_t e = 0; e < m.front.size() && err.empty(); ++e) {
    const std::uint32_t n = m.front.node(e);
    if (n >= m.nodes.size() || !reached[n] || m.nodes[n].entry() != e ||
        m.nodes[n].leaf() == m.front.split(e))
      err = fmt("front entry %u (%d, %d) points at node %u, which is not a %s of its diamond", e,
                m.front.ci(e), m.front.cj(e), n, m.front.split(e) ? "split node" : "leaf");
  }
  if (err.empty() && leaves != m.triangles)
    err = fmt("leaf count %u differs from the triangle counter %u", leaves, m.triangles);
  if (err.empty())
    for (std::uint32_t p = 0; p < m.land.patch_count() && err.empty(); ++p)
      if (m.out.mesh(p).triangles != drawn[p])
        err =
            fmt("patch %u draws %u triangles, its leaves %u", p, m.out.mesh(p).triangles, drawn[p]);
  return err;
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
