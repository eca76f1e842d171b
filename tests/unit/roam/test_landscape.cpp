// The landscape's bounds and geometry (roam/landscape.cpp, roam/diamond.h): nested and honest
// bounds, the exact error against brute force, the O(1) geometry against the walk from the roots,
// and, in the view-independent mode, the minimal triangulation under the bound.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <tuple>

#include "ridgeline/roam_view.h"
#include "roam/diamond.h"
#include "roam/landscape_access.h"
#include "roam_landscapes.h"

using namespace ridgeline;
using namespace ridgeline::test;

TEST(Landscape, BoundsAreNestedAndHonest) {
  auto l = make_landscape(65, 4);
  for (std::uint32_t root = 0; root < l->root_count(); ++root) {
    for (std::uint64_t h = 1; h < (std::uint64_t{1} << l->max_level()); ++h) {
      const float b = l->bound(root, h);
      EXPECT_GE(b, test::exact_error(*l, root, h))
          << "root " << root << " node " << h << ": the bound is below the triangle's exact error";
      if (2 * h + 1 < (std::uint64_t{1} << l->max_level())) {
        EXPECT_GE(b, l->bound(root, 2 * h))
            << "root " << root << " node " << h << ": the bound is below its first child's";
        EXPECT_GE(b, l->bound(root, 2 * h + 1))
            << "root " << root << " node " << h << ": the bound is below its second child's";
      }
    }
  }
  EXPECT_EQ(l->bound(0, std::uint64_t{1} << l->max_level()), 0.0f);
}

TEST(Landscape, ExactErrorMatchesBruteForceOnABump) {
  // One raised vertex in a flat 5 x 5 field (one patch, k = 2): the root containing it has error
  // equal to the bump (the vertex is not a corner), a node not containing it has 0.
  HeightfieldDesc d;
  d.width = d.height = 5;
  std::vector<float> v(25, 0.0f);
  v[1 + 2 * 5] = 3.0f;  // (1, 2)
  auto t = Terrain::create(std::move(Heightfield::create(d, v)).value()).value();
  auto l = Landscape::create(t, {.patch_exponent = 2}).value();
  // Root 1 has apex (0, 4), hypotenuse (4,4)-(0,0): it holds (1, 2) (x < z).
  EXPECT_FLOAT_EQ(test::exact_error(*l, 1, 1), 3.0f);
  EXPECT_FLOAT_EQ(test::exact_error(*l, 0, 1), 0.0f);
}

TEST(Landscape, ConstantTimeGeometryMatchesThePathWalk) {
  auto l = make_landscape(129, 5);
  for (std::uint32_t root = 0; root < l->root_count(); ++root)
    for (std::uint64_t h = 1; h < (std::uint64_t{1} << (l->max_level() + 1)); ++h) {
      const LatticeTriangle a = l->triangle(root, h);
      const LatticeTriangle b = roam::LandscapeAccess::triangle_at(*l, a.ax, a.az, root, h);
      ASSERT_EQ(std::tie(a.lx, a.lz, a.rx, a.rz), std::tie(b.lx, b.lz, b.rx, b.rz))
          << "root " << root << " heap " << h;
      const Landscape::LatticeBox x = Landscape::box_of(b);
      ASSERT_EQ(x.i0, std::min({a.ax, a.lx, a.rx})) << "root " << root << " heap " << h;
      ASSERT_EQ(x.i1, std::max({a.ax, a.lx, a.rx})) << "root " << root << " heap " << h;
      ASSERT_EQ(x.j0, std::min({a.az, a.lz, a.rz})) << "root " << root << " heap " << h;
      ASSERT_EQ(x.j1, std::max({a.az, a.lz, a.rz})) << "root " << root << " heap " << h;
    }
}

// The diamond hierarchy (roam/diamond.h) in O(1) arithmetic agrees with the bintree walked from
// the roots: every node's hypotenuse midpoint is a diamond whose hypotenuse is the node's and one
// of whose apexes is the node's apex.
TEST(Diamond, GeometryMatchesTheBintree) {
  auto l = make_landscape(129, 4);
  const int K = l->patch_log2();
  for (std::uint32_t root = 0; root < l->root_count(); ++root)
    for (std::uint64_t h = 1; h < (std::uint64_t{1} << l->max_level()); ++h) {
      const LatticeTriangle t = l->triangle(root, h);
      const roam::Diamond d = roam::diamond_at((t.lx + t.rx) / 2, (t.lz + t.rz) / 2, K);
      ASSERT_FALSE(d.corner);
      ASSERT_EQ(d.depth(K), 63 - __builtin_clzll(h));
      std::int64_t ax, az, bx, bz, p0x, p0z, p1x, p1z;
      d.hypotenuse(ax, az, bx, bz);
      const bool same = (ax == t.lx && az == t.lz && bx == t.rx && bz == t.rz) ||
                        (ax == t.rx && az == t.rz && bx == t.lx && bz == t.lz);
      ASSERT_TRUE(same) << "root " << root << " heap " << h << " diamond (" << d.i << "," << d.j
                        << ") t " << d.t;
      d.apexes(p0x, p0z, p1x, p1z);
      ASSERT_TRUE((p0x == t.ax && p0z == t.az) || (p1x == t.ax && p1z == t.az))
          << "root " << root << " heap " << h;
    }
}

namespace {

// Brute-force reference for the view-independent mode: the unique minimal conforming bintree
// triangulation in which every leaf passes `ok`. Nodes are split top-down when they exist and
// fail, and the closure adds ancestors and diamond partners (found geometrically).
std::size_t minimal_triangulation(const Landscape& l,
                                  const std::function<bool(std::uint32_t, std::uint64_t)>& ok) {
  using Id = std::pair<std::uint32_t, std::uint64_t>;
  std::map<std::array<std::int64_t, 4>, std::vector<Id>> by_hyp;
  const std::uint64_t limit = std::uint64_t{1} << (l.max_level() + 1);
  for (std::uint32_t r = 0; r < l.root_count(); ++r)
    for (std::uint64_t h = 1; h < limit / 2; ++h) {
      const LatticeTriangle t = l.triangle(r, h);
      std::array<std::int64_t, 4> k{t.lx, t.lz, t.rx, t.rz};
      if (std::make_pair(k[0], k[1]) > std::make_pair(k[2], k[3])) k = {t.rx, t.rz, t.lx, t.lz};
      by_hyp[k].push_back({r, h});
    }
  auto partner = [&](Id n) -> std::optional<Id> {
    const LatticeTriangle t = l.triangle(n.first, n.second);
    std::array<std::int64_t, 4> k{t.lx, t.lz, t.rx, t.rz};
    if (std::make_pair(k[0], k[1]) > std::make_pair(k[2], k[3])) k = {t.rx, t.rz, t.lx, t.lz};
    for (const Id& o : by_hyp[k])
      if (o != n) return o;
    return std::nullopt;
  };
  std::set<Id> split;
  std::function<void(Id)> add = [&](Id n) {
    if (!split.insert(n).second) return;
    if (n.second > 1) add({n.first, n.second / 2});
    if (auto p = partner(n)) add(*p);
  };
  bool changed = true;
  while (changed) {
    changed = false;
    std::vector<Id> frontier;
    for (std::uint32_t r = 0; r < l.root_count(); ++r) frontier.push_back({r, 1});
    while (!frontier.empty()) {
      Id n = frontier.back();
      frontier.pop_back();
      if (split.count(n)) {
        if (n.second * 2 < limit / 2) {
          frontier.push_back({n.first, n.second * 2});
          frontier.push_back({n.first, n.second * 2 + 1});
        }
        continue;
      }
      if (n.second < limit / 2 && !ok(n.first, n.second)) {
        add(n);
        changed = true;
      }
    }
  }
  return l.root_count() + split.size();
}

}  // namespace

TEST(Roam, ToleranceModeGivesTheMinimalTriangulationUnderTheBound) {
  for (std::uint32_t size : {65u, 129u}) {
    auto l = make_landscape(size, 5, 0.0, 99);
    for (double tol : {0.25, 1.0, 4.0, 16.0}) {
      auto view =
          RoamView::create(l, {.metric = ErrorMetric::kWorldMetres, .threshold = tol}).value();
      auto st = view->update(Camera{});
      ASSERT_TRUE(st);
      ASSERT_EQ(check_crack_free(*view), "");
      const std::size_t ref = minimal_triangulation(
          *l, [&](std::uint32_t r, std::uint64_t h) { return l->bound(r, h) <= tol; });
      EXPECT_EQ(st->triangles, ref) << "size " << size << " tolerance " << tol;
      const std::size_t exact = minimal_triangulation(
          *l, [&](std::uint32_t r, std::uint64_t h) { return test::exact_error(*l, r, h) <= tol; });
      EXPECT_LE(exact, st->triangles);
      // The exact-bound target of the issue: within 1.1x of the exact minimal count.
      EXPECT_LE(double(st->triangles), 1.1 * double(exact)) << "size " << size << " tol " << tol;
      std::printf("size %u tolerance %.2f: %u triangles, exact minimal %zu (ratio %.3f)\n", size,
                  tol, st->triangles, exact, double(st->triangles) / double(exact));
    }
  }
}
