// ROAM invariants: crack-free, converged bounds, honest bounds, minimal triangulation in the
// view-independent mode, coherent == rebuild quality, budgets, determinism, multiple views.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <new>
#include <functional>
#include <glm/geometric.hpp>
#include <map>
#include <optional>
#include <chrono>
#include <random>
#include <set>
#include <thread>
#include <tuple>

#include "ridgeline/roam_view.h"
#include "roam/diamond.h"
#include "roam/front.h"
#include "roam/reserved.h"
#include "roam/landscape_access.h"
#include "roam_test_util.h"

using namespace ridgeline;
using namespace ridgeline::test;

namespace {

std::shared_ptr<const Landscape> make_landscape(std::uint32_t size, std::uint32_t k = 5,
                                                double origin = 0.0, std::uint32_t seed = 1337) {
  auto hf = make_default_heightfield({.size = size, .spacing = 2.0, .seed = seed});
  EXPECT_TRUE(hf);
  if (origin != 0.0) {
    // Same heights, moved far away.
    HeightfieldDesc d;
    d.width = hf->width();
    d.height = hf->height();
    d.spacing_x = d.spacing_z = 2.0;
    d.origin_x = origin;
    d.origin_z = -origin;
    std::vector<float> v(hf->local_heights().begin(), hf->local_heights().end());
    hf = Heightfield::create(d, v);
  }
  auto terrain = Terrain::create(std::move(hf).value()).value();
  auto l = Landscape::create(terrain, {.patch_exponent = k});
  EXPECT_TRUE(l) << (l ? "" : l.error().message);
  return l.value();
}

// A field whose size is not 2^k + 1, nor square (83 x 57 samples, 2 m apart): its last patches
// extend past the samples.
constexpr std::uint32_t kPaddedW = 83, kPaddedH = 57;
std::shared_ptr<const Landscape> make_padded_landscape(std::uint32_t k) {
  HeightfieldDesc d;
  d.width = kPaddedW;
  d.height = kPaddedH;
  d.spacing_x = d.spacing_z = 2.0;
  std::vector<float> h(std::size_t(d.width) * d.height);
  for (std::uint32_t j = 0; j < d.height; ++j)
    for (std::uint32_t i = 0; i < d.width; ++i)
      h[i + j * d.width] = float(10 * std::sin(0.3 * i) * std::cos(0.21 * j) + 0.05 * i * j);
  auto terrain = Terrain::create(Heightfield::create(d, h).value()).value();
  return Landscape::create(terrain, {.patch_exponent = k}).value();
}

// A leaf's projected bound as the tessellator defines it (landscape.h, docs/roam.md): its
// diamond's morph bound projected at the distance from the eye to the diamond's bounding sphere
// (centred at the diamond's vertex at its true height). Recomputed here in double precision from
// the landscape's public data; `in_view` approximates the frustum from the triangle's corners.
double projected_bound(const Landscape& l, const LatticeTriangle& t, const Camera& c,
                       bool* in_view) {
  *in_view = false;
  if (((t.lx + t.rx) | (t.lz + t.rz)) & 1) return 0.0;  // finest triangles never split
  const std::int64_t ci = (t.lx + t.rx) / 2, cj = (t.lz + t.rz) / 2;
  const DiamondBound b = l.diamond(ci, cj);
  const double off = l.terrain().info().height_offset;
  const glm::dvec3 centre(test::world_x(l, ci), off + test::lattice_height(l, ci, cj),
                          test::world_z(l, cj));
  // In view: the sphere meets the frustum (the lattice vertices that carry error are inside it;
  // the triangle's corners carry none).
  *in_view = Frustum(c).classify_sphere(centre, double(b.radius)) != Frustum::Cull::kOut;
  const double d = glm::length(centre - c.eye) - double(b.radius);
  return d > 0 ? double(b.morph) * projection_scale(c) / d : (b.morph > 0 ? INFINITY : 0.0);
}

void expect_converged(const RoamView& view, const Camera& c, double threshold) {
  const Landscape& l = view.landscape();
  int checked = 0;
  view.for_each_leaf([&](std::uint32_t root, std::uint64_t heap, const LatticeTriangle& t) {
    bool in = false;
    const double p = projected_bound(l, t, c, &in);
    if (!in) return;
    ++checked;
    EXPECT_LE(p, threshold * (1 + 1e-5)) << "root " << root << " heap " << heap;
  });
  EXPECT_GT(checked, 0);
}

}  // namespace

TEST(Landscape, BoundsAreNestedAndHonest) {
  auto l = make_landscape(65, 4);
  for (std::uint32_t root = 0; root < l->root_count(); ++root) {
    for (std::uint64_t h = 1; h < (std::uint64_t{1} << l->max_level()); ++h) {
      const float b = l->bound(root, h);
      EXPECT_GE(b, test::exact_error(*l, root, h));
      if (2 * h + 1 < (std::uint64_t{1} << l->max_level())) {
        EXPECT_GE(b, l->bound(root, 2 * h));
        EXPECT_GE(b, l->bound(root, 2 * h + 1));
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

TEST(Roam, CrackFreeAlongARandomWalkWithChangingThresholdsAndBudgets) {
  auto l = make_landscape(257, 5);
  auto view = RoamView::create(l).value();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(0, 1);
  glm::dvec3 eye(100, 200, 100);
  double yaw = 0.6;
  for (int frame = 0; frame < 150; ++frame) {
    eye += glm::dvec3(std::cos(yaw), 0, std::sin(yaw)) * (U(rng) * 20.0);
    eye.x = std::clamp(eye.x, -100.0, 612.0);
    eye.z = std::clamp(eye.z, -100.0, 612.0);
    eye.y = 80 + 200 * U(rng);
    yaw += (U(rng) - 0.5) * (frame % 37 == 0 ? 6.0 : 0.4);
    const Camera c =
        camera_at(eye, eye + glm::dvec3(std::cos(yaw), -0.4, std::sin(yaw)), 40 + 50 * U(rng));
    RoamSettings s = view->settings();
    if (frame % 10 == 0) s.threshold = 0.5 + 8 * U(rng);
    if (frame % 25 == 5) s.max_triangles = frame % 50 == 5 ? 3000 : 0;
    if (frame % 30 == 7) s.budget_ms = frame % 60 == 7 ? 0.2 : 0.0;
    ASSERT_TRUE(view->set_settings(s));
    auto st = view->update(c);
    ASSERT_TRUE(st);
    ASSERT_EQ(view->check_invariants(), "") << "frame " << frame;
    ASSERT_EQ(check_crack_free(*view), "") << "frame " << frame;
    if (s.max_triangles) {
      EXPECT_LE(st->triangles, s.max_triangles);
    }
  }
}

TEST(Roam, ConvergedMeshMeetsTheThresholdInView) {
  auto l = make_landscape(257, 5);
  auto view = RoamView::create(l, {.threshold = 2.0}).value();
  const Camera c = camera_at({20, 180, 30}, {300, 60, 260});
  auto st = view->update(c);
  ASSERT_TRUE(st);
  EXPECT_EQ(st->stop, StopReason::kConverged);
  EXPECT_LE(st->max_remaining_error, 2.0);
  expect_converged(*view, c, 2.0);
  // Move a little and update again: still converged (the front is tested afresh every update).
  for (int k = 1; k <= 20; ++k) {
    Camera c2 = c;
    c2.eye += glm::dvec3(3.0 * k, -1.0 * k, 2.0 * k);
    c2.target += glm::dvec3(3.0 * k, 0, -4.0 * k);
    st = view->update(c2);
    ASSERT_TRUE(st);
    EXPECT_EQ(st->stop, StopReason::kConverged);
    expect_converged(*view, c2, 2.0);
  }
}

TEST(Roam, MeasuredErrorNeverExceedsTheBound) {
  auto l = make_landscape(129, 5);
  auto view = RoamView::create(l, {.metric = ErrorMetric::kWorldMetres, .threshold = 1.5}).value();
  ASSERT_TRUE(view->update(Camera{}));
  const Heightfield hf = l->terrain().surface().to_heightfield().value();
  double worst = 0;
  view->for_each_leaf([&](std::uint32_t root, std::uint64_t heap, const LatticeTriangle& t) {
    // Measure: every lattice vertex under the triangle against the triangle's plane.
    const double b = l->bound(root, heap);
    const std::int64_t i0 = std::min({t.ax, t.lx, t.rx}), i1 = std::max({t.ax, t.lx, t.rx});
    const std::int64_t j0 = std::min({t.az, t.lz, t.rz}), j1 = std::max({t.az, t.lz, t.rz});
    const double w = double((t.lx - t.ax) * (t.rz - t.az) - (t.lz - t.az) * (t.rx - t.ax));
    for (std::int64_t j = j0; j <= j1; ++j)
      for (std::int64_t i = i0; i <= i1; ++i) {
        const double wr = double((t.lx - t.ax) * (j - t.az) - (t.lz - t.az) * (i - t.ax)) / w;
        const double wa = double((t.rx - t.lx) * (j - t.lz) - (t.rz - t.lz) * (i - t.lx)) / w;
        const double wl = 1 - wr - wa;
        if (wr < -1e-12 || wa < -1e-12 || wl < -1e-12) continue;
        if (i >= hf.width() || j >= hf.height()) continue;
        const double plane = wa * test::lattice_height(*l, t.ax, t.az) +
                             wl * test::lattice_height(*l, t.lx, t.lz) +
                             wr * test::lattice_height(*l, t.rx, t.rz);
        const double err = std::abs(plane - hf.local(std::uint32_t(i), std::uint32_t(j)));
        EXPECT_LE(err, b + 1e-4);
        EXPECT_LE(err, 1.5 + 1e-4);
        worst = std::max(worst, err);
      }
  });
  EXPECT_GT(worst, 0.1);  // the test saw real error
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

// With nested bounds and spheres the mesh a threshold asks for is unique: a coherent view that
// got there along a path and a rebuild from the roots hold the same leaves.
TEST(Roam, CoherentAndRebuildConvergeToTheSameMesh) {
  auto l = make_landscape(257, 5);
  auto coherent = RoamView::create(l, {.threshold = 3.0}).value();
  auto rebuild = RoamView::create(l, {.mode = RoamMode::kRebuild, .threshold = 3.0}).value();
  Camera c = camera_at({10, 150, 10}, {200, 50, 200});
  for (int k = 0; k < 40; ++k) {
    c.eye += glm::dvec3(4, 0, 3);
    c.target += glm::dvec3(4, 0, 3);
    ASSERT_TRUE(coherent->update(c));
  }
  // The camera stops: both converge, both meet the threshold.
  auto a = coherent->update(c);
  auto b = rebuild->update(c);
  ASSERT_TRUE(a && b);
  EXPECT_TRUE(b->rebuilt);
  EXPECT_LE(a->max_remaining_error, 3.0);
  EXPECT_LE(b->max_remaining_error, 3.0);
  expect_converged(*coherent, c, 3.0);
  expect_converged(*rebuild, c, 3.0);
  EXPECT_EQ(a->triangles, b->triangles);
  EXPECT_EQ(coherent->mesh_hash(), rebuild->mesh_hash());
}

// A mesh made from the roots without a budget is built top down (build.cpp: patch by patch,
// level by level, no front entry made and taken back per split). It must be the mesh the
// incremental splits make (reached here under a generous time budget, which never builds), with
// the same front, links and buffers (check_invariants()), on a landscape of many patches and on
// one whose edge patches extend past the samples; and the coherent updates must carry on from it
// as from the other, along a path with turns, in both metrics.
TEST(Roam, TheTopDownBuildIsTheMeshTheSplitsMake) {
  const std::shared_ptr<const Landscape> landscapes[] = {make_landscape(257, 4),
                                                         make_padded_landscape(3)};
  for (const auto& l : landscapes) {
    for (const RoamSettings& base :
         {RoamSettings{.threshold = 1.5},
          RoamSettings{.metric = ErrorMetric::kWorldMetres, .threshold = 0.5}}) {
      auto built = RoamView::create(l, base).value();
      RoamSettings slow = base;
      slow.budget_ms = 1e4;
      auto split = RoamView::create(l, slow).value();
      Camera c = camera_at({-10, 90, -20}, {150, 20, 120});
      for (int k = 0; k < 12; ++k) {
        auto a = built->update(c);
        ASSERT_TRUE(a);
        if (k == 0) {
          EXPECT_TRUE(a->rebuilt);
          EXPECT_EQ(a->forced_splits, 0u);
          EXPECT_GT(a->splits, 100u);
        } else {
          EXPECT_FALSE(a->rebuilt) << "step " << k;  // the coherent updates carry on
        }
        std::optional<Result<RoamStats>> b;
        for (int n = 0; n < 50; ++n) {
          b = split->update(c);
          ASSERT_TRUE(*b);
          EXPECT_FALSE((*b)->rebuilt && n + k > 0);
          if ((*b)->stop == StopReason::kConverged) break;
        }
        ASSERT_EQ((*b)->stop, StopReason::kConverged);
        ASSERT_EQ(built->check_invariants(), "") << "step " << k;
        ASSERT_EQ(split->check_invariants(), "") << "step " << k;
        EXPECT_EQ(a->triangles, (*b)->triangles) << "step " << k;
        EXPECT_EQ(a->front_size, (*b)->front_size) << "step " << k;
        EXPECT_EQ(built->mesh_hash(), split->mesh_hash()) << "step " << k;
        EXPECT_EQ(check_crack_free(*built), "");
        // Forward and turning.
        const glm::dvec3 step(9, -3, 7);
        c.eye += step;
        c.target += step + glm::dvec3(k % 3 == 0 ? 40 : 0, 0, k % 4 == 0 ? -30 : 0);
      }
    }
  }
}

TEST(Roam, TriangleBudgetIsAHardCap) {
  auto l = make_landscape(257, 5);
  auto view = RoamView::create(l, {.threshold = 0.1, .max_triangles = 5000}).value();
  const Camera c = camera_at({20, 120, 30}, {300, 60, 260});
  auto st = view->update(c);
  ASSERT_TRUE(st);
  EXPECT_EQ(st->stop, StopReason::kTriangleBudget);
  EXPECT_LE(st->triangles, 5000u);
  EXPECT_GT(st->triangles, 4900u);  // the budget is used, not wasted
  EXPECT_EQ(check_crack_free(*view), "");
  // Lower the cap: the mesh merges down to it.
  RoamSettings s = view->settings();
  s.max_triangles = 2000;
  ASSERT_TRUE(view->set_settings(s));
  st = view->update(c);
  ASSERT_TRUE(st);
  EXPECT_LE(st->triangles, 2000u);
  EXPECT_EQ(check_crack_free(*view), "");
}

// Under a cap alone the view follows a moving camera at the threshold that fills the cap: every
// update fits the cap and uses most of it, and its mesh is exactly the converged mesh of the
// threshold it reports (morph_threshold): what a fresh view at that threshold builds.
TEST(Roam, TriangleCapFollowsTheCameraAtOneThreshold) {
  auto l = make_landscape(257, 5);
  const std::uint32_t cap = 6000;
  auto view = RoamView::create(l, {.threshold = 0.0, .max_triangles = cap}).value();
  Camera c = camera_at({10, 150, 10}, {200, 50, 200});
  int searched = 0;
  for (int k = 0; k < 40; ++k) {
    c.eye += glm::dvec3(4, 0.3, 3);
    c.target += glm::dvec3(2, 0, 5);
    auto st = view->update(c);
    ASSERT_TRUE(st);
    EXPECT_LE(st->triangles, cap) << "update " << k;
    EXPECT_EQ(check_crack_free(*view), "") << "update " << k;
    if (k < 5) continue;  // the search settles
    EXPECT_GT(st->triangles, 0.9 * cap) << "update " << k;
    EXPECT_EQ(st->stop, StopReason::kTriangleBudget);
    EXPECT_LE(st->max_remaining_error, st->morph_threshold * (1 + 1e-6)) << "update " << k;
    if (k % 8 == 0) {
      auto fresh = RoamView::create(l, {.threshold = st->morph_threshold}).value();
      ASSERT_TRUE(fresh->update(c));
      EXPECT_EQ(fresh->mesh_hash(), view->mesh_hash()) << "update " << k;
      ++searched;
    }
  }
  EXPECT_GT(searched, 3);
  // A threshold above what the cap needs: the cap does not bind and the view converges.
  RoamSettings s = view->settings();
  s.threshold = 20.0;
  ASSERT_TRUE(view->set_settings(s));
  auto st = view->update(c);
  ASSERT_TRUE(st);
  EXPECT_EQ(st->stop, StopReason::kConverged);
  EXPECT_DOUBLE_EQ(st->morph_threshold, 20.0);
  auto fresh = RoamView::create(l, {.threshold = 20.0}).value();
  ASSERT_TRUE(fresh->update(c));
  EXPECT_EQ(fresh->mesh_hash(), view->mesh_hash());
}

TEST(Roam, DeterministicMeshHash) {
  auto l = make_landscape(257, 5);
  auto run = [&] {
    auto view = RoamView::create(l, {.threshold = 2.0}).value();
    Camera c = camera_at({10, 150, 10}, {200, 50, 200});
    for (int k = 0; k < 30; ++k) {
      c.eye += glm::dvec3(5, 0.5, 2);
      c.target += glm::dvec3(3, 0, 6);
      EXPECT_TRUE(view->update(c));
    }
    return view->mesh_hash();
  };
  EXPECT_EQ(run(), run());
}

TEST(Roam, TwoViewsOverOneLandscapeAreIndependent) {
  auto l = make_landscape(257, 5);
  auto a = RoamView::create(l, {.threshold = 2.0}).value();
  auto b = RoamView::create(l, {.threshold = 2.0}).value();
  const Camera ca = camera_at({20, 120, 30}, {300, 60, 260});
  const Camera cb = camera_at({500, 120, 500}, {100, 60, 100});
  ASSERT_TRUE(a->update(ca));
  const auto ha = a->mesh_hash();
  ASSERT_TRUE(b->update(cb));
  EXPECT_EQ(a->mesh_hash(), ha);
  EXPECT_NE(a->mesh_hash(), b->mesh_hash());
}

TEST(Roam, TeleportAndSnapTurnRebuild) {
  auto l = make_landscape(257, 5);
  auto view = RoamView::create(l, {.threshold = 2.0}).value();
  Camera c = camera_at({20, 120, 30}, {300, 60, 260});
  ASSERT_TRUE(view->update(c));
  c.eye += glm::dvec3(1, 0, 1);
  c.target += glm::dvec3(1, 0, 1);
  auto st = view->update(c);
  ASSERT_TRUE(st);
  EXPECT_FALSE(st->rebuilt);
  // Snap turn by 180 degrees and teleport.
  c = camera_at({480, 150, 480}, {480 - 280, 60, 480 - 230});
  st = view->update(c);
  ASSERT_TRUE(st);
  EXPECT_TRUE(st->rebuilt);
  expect_converged(*view, c, 2.0);
}

TEST(Roam, OutputBuffersMatchTheLeavesAndSeamsShareHeightBits) {
  auto l = make_landscape(257, 5);
  auto view = RoamView::create(l, {.threshold = 1.0}).value();
  const Camera c = camera_at({20, 120, 30}, {300, 60, 260});
  ASSERT_TRUE(view->update(c));
  auto dirty = view->take_dirty_patches();
  EXPECT_EQ(dirty.size(), l->patch_count());
  std::size_t tris = 0;
  std::map<std::pair<std::int64_t, std::int64_t>, std::uint32_t> height_bits;
  for (std::uint32_t p = 0; p < l->patch_count(); ++p) {
    const PatchMesh& m = view->patch_mesh(p);
    tris += m.indices.size() / 3;
    for (std::size_t k = 0; k < m.indices.size(); k += 3) {
      const MeshVertex& a = m.vertices[m.indices[k]];
      const MeshVertex& b = m.vertices[m.indices[k + 1]];
      const MeshVertex& cc = m.vertices[m.indices[k + 2]];
      // Counter-clockwise from above: cross product's y > 0 in (x, y, z).
      const double cy = double(b.z - a.z) * (cc.x - a.x) - double(b.x - a.x) * (cc.z - a.z);
      EXPECT_GT(cy, 0.0);
    }
    for (const MeshVertex& v : m.vertices) {
      const auto i = std::llround((m.origin_x + v.x) / 2.0),
                 j = std::llround((m.origin_z + v.z) / 2.0);
      std::uint32_t bits;
      std::memcpy(&bits, &v.y, 4);
      auto [it, fresh] = height_bits.emplace(std::make_pair(i, j), bits);
      if (!fresh) {
        EXPECT_EQ(it->second, bits) << "vertex " << i << "," << j;
      }
      EXPECT_NEAR(glm::length(glm::vec3(v.nx, v.ny, v.nz)), 1.0f, 1e-4f);
    }
  }
  EXPECT_EQ(tris, view->triangle_count());
  // A small move changes only some patches.
  Camera c2 = c;
  c2.eye += glm::dvec3(2, 0, 2);
  c2.target += glm::dvec3(2, 0, 2);
  ASSERT_TRUE(view->update(c2));
  dirty = view->take_dirty_patches();
  EXPECT_LT(dirty.size(), l->patch_count());
}

// What an engine keeps: a copy of every patch's buffers, brought up to date after each update
// from take_dirty_patches() the way docs/roam.md says (whole when resized, else the dirty ranges),
// equals the view's buffers at every step; and a patch's buffers hold at most about twice the
// slots it uses (compaction), while the camera dives close to the ground and climbs away again,
// through threshold changes, a triangle cap and a time budget.
TEST(Roam, OutputStaysCompactAndAnEngineCopyFollowsIt) {
  auto l = make_landscape(257, 5);  // no padding: every live triangle is drawn
  auto view = RoamView::create(l, {.threshold = 0.5}).value();
  struct Copy {
    std::vector<MeshVertex> vertices;
    std::vector<std::uint32_t> indices;
  };
  std::vector<Copy> gpu(l->patch_count());
  std::uint32_t compacted = 0, checked_bounds = 0;
  for (int frame = 0; frame < 120; ++frame) {
    // Down to 12 m over the south-west corner looking north-east, then up to 400 m and away.
    const double t = frame / 119.0, up = t < 0.3 ? 1.0 - t / 0.3 : (t - 0.3) / 0.7;
    const glm::dvec3 eye(30 + 300 * t, 12 + 390 * up, 30 + 120 * t);
    RoamSettings s = view->settings();
    s.threshold = frame < 60 ? 0.5 : frame < 90 ? 3.0 : 1.0;
    s.max_triangles = frame >= 70 && frame < 80 ? 6000 : 0;
    s.budget_ms = frame >= 100 && frame < 105 ? 0.05 : 0.0;
    ASSERT_TRUE(view->set_settings(s));
    const auto st = view->update(camera_at(eye, eye + glm::dvec3(1, -0.5, 1)));
    ASSERT_TRUE(st);
    ASSERT_EQ(view->check_invariants(), "") << "frame " << frame;
    compacted += st->compacted_patches;
    for (const std::uint32_t p : view->take_dirty_patches()) {
      const PatchMesh& m = view->patch_mesh(p);
      Copy& g = gpu[p];
      if (m.resized) {
        g.vertices = m.vertices;
        g.indices = m.indices;
        continue;
      }
      g.vertices.resize(m.vertices.size());
      g.indices.resize(m.indices.size());
      for (const MeshRange& r : m.dirty_vertices)
        std::copy_n(m.vertices.begin() + r.first, r.count, g.vertices.begin() + r.first);
      for (const MeshRange& r : m.dirty_triangles)
        std::copy_n(m.indices.begin() + 3 * std::size_t(r.first), 3 * std::size_t(r.count),
                    g.indices.begin() + 3 * std::size_t(r.first));
    }
    for (std::uint32_t p = 0; p < l->patch_count(); ++p) {
      const PatchMesh& m = view->patch_mesh(p);
      const Copy& g = gpu[p];
      ASSERT_EQ(g.indices, m.indices) << "frame " << frame << " patch " << p;
      std::set<std::uint32_t> used;
      for (std::size_t k = 0; k < m.indices.size(); k += 3)
        if (m.indices[k] != m.indices[k + 1]) used.insert(&m.indices[k], &m.indices[k + 3]);
      for (const std::uint32_t v : used)
        ASSERT_EQ(std::memcmp(&g.vertices[v], &m.vertices[v], sizeof(MeshVertex)), 0)
            << "frame " << frame << " patch " << p << " vertex " << v;
      // Without a time budget every oversized patch is compacted before the update returns.
      if (s.budget_ms == 0.0) {
        EXPECT_LE(m.indices.size() / 3, 2 * std::size_t(m.triangles) + 64)
            << "frame " << frame << " patch " << p;
        EXPECT_LE(m.vertices.size(), 2 * used.size() + 64) << "frame " << frame << " patch " << p;
        ++checked_bounds;
      }
    }
  }
  EXPECT_GT(compacted, 10u);  // the climb empties the patches the dive filled
  EXPECT_GT(checked_bounds, 0u);
}

// Hierarchical geomorphs (docs/roam.md, "Geomorphs"), checked on the output an engine draws:
// every vertex whose diamond's ratio (what the split test compares with 1) is at least 1 has the
// two ends of the edge it splits at t = 1, at their true heights, so the vertex starts on its
// parent edge as drawn; and at t = 0 it is drawn at that edge's midpoint (its morph offset).
// Along a flyover at several thresholds, morph windows and delays.
TEST(Roam, AVertexStartsOnItsParentEdgeAsDrawn) {
  for (const Geomorph g : {Geomorph{}, Geomorph{0.5, 0.0}, Geomorph{1.0, 0.3}}) {
    auto hf = make_default_heightfield({.size = 257, .spacing = 2.0, .seed = 1337});
    ASSERT_TRUE(hf);
    auto l = Landscape::create(Terrain::create(std::move(hf).value()).value(),
                               {.patch_exponent = 5, .morph_window = g.window,
                                .morph_delay = g.delay})
                 .value();
    ASSERT_EQ(l->geomorph().window, g.window);
    ASSERT_EQ(l->geomorph().delay, g.delay);
    for (const double tau : {1.0, 3.0}) {
      auto v = RoamView::create(l, {.threshold = tau}).value();
      std::size_t active = 0, ends = 0;
      for (int k = 0; k < 12; ++k) {
        const double a = 0.3 * k;
        const glm::dvec3 eye(256 + 150 * std::cos(a), 140, 256 + 150 * std::sin(a));
        const Camera cam = camera_at(eye, {256, 40, 256});
        auto st = v->update(cam);
        ASSERT_TRUE(st);
        const double K = projection_scale(cam);
        for (std::uint32_t p = 0; p < l->patch_count(); ++p) {
          const PatchMesh& m = v->patch_mesh(p);
          const glm::vec3 e(float(eye.x - m.origin_x), float(eye.y - m.origin_y),
                            float(eye.z - m.origin_z));
          // The drawn vertices by lattice position.
          std::map<std::pair<std::int64_t, std::int64_t>, const MeshVertex*> at;
          for (std::size_t t = 0; t + 2 < m.indices.size(); t += 3) {
            if (m.indices[t] == m.indices[t + 1]) continue;
            for (int q = 0; q < 3; ++q) {
              const MeshVertex& mv = m.vertices[m.indices[t + q]];
              at[{std::llround((m.origin_x + mv.x) / 2.0),
                  std::llround((m.origin_z + mv.z) / 2.0)}] = &mv;
            }
          }
          auto rho = [&](const MeshVertex& mv) {
            const double dx = mv.x - e.x, dy = mv.y - e.y, dz = mv.z - e.z;
            const double d = std::sqrt(dx * dx + dy * dy + dz * dz) - mv.morph_radius;
            return mv.morph_bound * K / (st->morph_threshold * std::max(d, 1e-6));
          };
          for (const auto& [ij, mv] : at) {
            if (mv->morph_bound >= 3e38f || mv->morph_radius >= 3e38f) continue;  // never morph
            if (rho(*mv) < 1.0) continue;  // split for the frustum's sake, not its ratio
            ++active;
            std::int64_t hu, hw;
            roam::half_hypotenuse(ij.first, ij.second, l->patch_log2(), hu, hw);
            float ends_y = 0;
            for (const int s : {-1, 1}) {
              const auto it = at.find({ij.first + s * hu, ij.second + s * hw});
              ASSERT_NE(it, at.end()) << "an end of the edge vertex (" << ij.first << ", "
                                      << ij.second << ") splits is not drawn";
              const MeshVertex& end = *it->second;
              ends_y += end.y;
              EXPECT_EQ(morph_factor(end, e, K, st->morph_threshold, g), 1.0f)
                  << "vertex (" << ij.first << ", " << ij.second << ") at ratio " << rho(*mv)
                  << ": an end of its edge is still morphing (ratio " << rho(end) << ")";
              ++ends;
            }
            // At t = 0 the vertex sits on the edge between its ends' true heights.
            EXPECT_NEAR(mv->y + mv->morph_dy, 0.5f * ends_y, 1e-4f * (1 + std::abs(mv->y)));
          }
        }
      }
      EXPECT_GT(active, 1000u) << "w " << g.window << " delay " << g.delay << " threshold " << tau;
      EXPECT_EQ(ends, 2 * active);
    }
  }
}

// On a field whose size is not 2^k + 1 (and not square) the drawn mesh covers exactly the data:
// no vertex beyond the last sample, and the drawn triangles' areas add up to the data's area, so
// there is neither a gap nor an overhang; at a fine threshold and at the coarsest tolerance.
TEST(Roam, MeshEndsExactlyOnTheDataBorder) {
  auto l = make_padded_landscape(4);
  const double w = (kPaddedW - 1) * 2.0, hz = (kPaddedH - 1) * 2.0;
  // At a fine threshold, at the coarsest tolerance, and under a triangle cap far below what the
  // threshold asks for (the border's splits are forced: they go past the cap, as crack fixes do).
  const std::uint32_t roots = l->root_count();
  for (const RoamSettings& s :
       {RoamSettings{.threshold = 1.0},
        RoamSettings{.metric = ErrorMetric::kWorldMetres, .threshold = 1000.0},
        RoamSettings{.threshold = 1.0, .max_triangles = roots},
        RoamSettings{.threshold = 0.0, .max_triangles = roots + 40}}) {
    auto view = RoamView::create(l, s).value();
    ASSERT_TRUE(view->converge(camera_at({-20, 60, -30}, {80, 0, 60})));
    double area = 0;
    for (std::uint32_t p = 0; p < l->patch_count(); ++p) {
      const PatchMesh& m = view->patch_mesh(p);
      for (std::size_t k = 0; k + 2 < m.indices.size(); k += 3) {
        if (m.indices[k] == m.indices[k + 1]) continue;  // an unused or padding slot
        const MeshVertex* v[3] = {&m.vertices[m.indices[k]], &m.vertices[m.indices[k + 1]],
                                  &m.vertices[m.indices[k + 2]]};
        for (const MeshVertex* x : v) {
          EXPECT_LE(m.origin_x + x->x, w + 1e-4) << "overhang past the last column";
          EXPECT_LE(m.origin_z + x->z, hz + 1e-4) << "overhang past the last row";
        }
        area += 0.5 * (double(v[1]->z - v[0]->z) * (v[2]->x - v[0]->x) -
                       double(v[1]->x - v[0]->x) * (v[2]->z - v[0]->z));
      }
    }
    EXPECT_NEAR(area, w * hz, 1e-6 * w * hz)
        << "threshold " << s.threshold << " cap " << s.max_triangles;
    EXPECT_EQ(check_crack_free(*view), "");
    EXPECT_EQ(view->check_invariants(), "");
  }
}

TEST(Roam, BadSettingsAndCamerasAreRefused) {
  auto l = make_landscape(65, 4);
  EXPECT_FALSE(RoamView::create(l, {.threshold = -1.0}));
  EXPECT_FALSE(RoamView::create(l, {.threshold = NAN}));
  EXPECT_FALSE(RoamView::create(l, {.budget_ms = INFINITY}));
  EXPECT_FALSE(RoamView::create(l, {.max_triangles = 3}));
  EXPECT_FALSE(RoamView::create(nullptr));
  auto view = RoamView::create(l).value();
  Camera c;
  c.eye = {0, NAN, 0};
  EXPECT_FALSE(view->update(c));
  c = camera_at({0, 10, 0}, {0, 10, 0});
  EXPECT_FALSE(view->update(c));
  c = camera_at({0, 10, 0}, {0, 0, 0});  // straight down with up parallel
  EXPECT_FALSE(view->update(c));
  c.up = {0, 0, 1};
  EXPECT_TRUE(view->update(c));
  EXPECT_FALSE(Landscape::create(l->terrain_ptr(), {.patch_exponent = 1}));
  for (const double w : {-0.1, 4.5, double(NAN), double(INFINITY)}) {
    auto bad = Landscape::create(l->terrain_ptr(), {.morph_window = w});
    ASSERT_FALSE(bad);
    EXPECT_NE(bad.error().message.find("morph window"), std::string::npos);
  }
  for (const double d : {-0.1, 1.5, double(NAN)}) {
    auto bad = Landscape::create(l->terrain_ptr(), {.morph_delay = d});
    ASSERT_FALSE(bad);
    EXPECT_NE(bad.error().message.find("morph delay"), std::string::npos);
  }
  // Without a window there is no morph, and no delay either.
  auto flat = Landscape::create(l->terrain_ptr(), {.morph_window = 0, .morph_delay = 0.5});
  ASSERT_TRUE(flat);
  EXPECT_EQ(flat.value()->geomorph().delay, 0.0);
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

TEST(Roam, MeasuredErrorAgreesWithTheBoundsAndTheThreshold) {
  auto l = make_landscape(257, 5);
  auto view = RoamView::create(l, {.threshold = 2.0}).value();
  const Camera c = camera_at({20, 120, 30}, {300, 60, 260});
  ASSERT_TRUE(view->update(c));
  const auto e = view->measure_error(c);
  EXPECT_GT(e.vertices, 10000u);
  EXPECT_GT(e.max_m, 0.0);
  EXPECT_LE(e.rms_m, e.max_m);
  // Converged: the measured screen error at each vertex is at most the threshold, since each
  // vertex is at least as far as its leaf's bounding box and under its leaf's bound.
  EXPECT_LE(e.max_px, 2.0 * (1 + 1e-6));
  // A stratified sample sees fewer vertices and no larger error.
  const auto s = view->measure_error(c, 4);
  EXPECT_LT(s.vertices, e.vertices / 8);
  EXPECT_LE(s.max_m, e.max_m);
  // World-metre mode: every vertex, error within the tolerance.
  auto w = RoamView::create(l, {.metric = ErrorMetric::kWorldMetres, .threshold = 3.0}).value();
  ASSERT_TRUE(w->update(Camera{}));
  const auto we = w->measure_error(Camera{});
  EXPECT_EQ(we.vertices, 257u * 257u);
  EXPECT_LE(we.max_m, 3.0);
  EXPECT_GT(we.max_m, 1.0);
}

TEST(Roam, TimeBudgetStopsTheUpdateAndTheRestContinuesNextUpdate) {
  auto l = make_landscape(257, 5);
  // A budget far below what converging takes: the first clock check (after 8 operations) stops
  // it.
  auto view = RoamView::create(l, {.threshold = 1.0, .budget_ms = 1e-6}).value();
  const Camera c = camera_at({20, 120, 30}, {300, 60, 260});
  auto st = view->update(c);
  ASSERT_TRUE(st);
  EXPECT_EQ(st->stop, StopReason::kTimeBudget);
  EXPECT_GT(st->max_remaining_error, 1.0);
  EXPECT_EQ(check_crack_free(*view), "");
  // Lift the budget: the same camera converges from where it stopped, without a rebuild.
  RoamSettings s = view->settings();
  s.budget_ms = 0;
  ASSERT_TRUE(view->set_settings(s));
  st = view->update(c);
  ASSERT_TRUE(st);
  EXPECT_EQ(st->stop, StopReason::kConverged);
  EXPECT_FALSE(st->rebuilt);
  expect_converged(*view, c, 1.0);
}

// The threshold may change every update: the front is tested against the current one, so the
// mesh goes straight to what a fresh view of that threshold draws, both ways.
TEST(Roam, ThresholdChangesGoStraightToTheFreshMesh) {
  auto l = make_landscape(257, 5);
  auto view = RoamView::create(l, {.threshold = 4.0}).value();
  const Camera c = camera_at({20, 120, 30}, {300, 60, 260});
  auto fresh_hash = [&](double t) {
    auto v = RoamView::create(l, {.threshold = t}).value();
    EXPECT_TRUE(v->update(c));
    return v->mesh_hash();
  };
  auto coarse = view->update(c);
  ASSERT_TRUE(coarse);
  RoamSettings s = view->settings();
  s.threshold = 1.0;
  ASSERT_TRUE(view->set_settings(s));
  auto fine = view->update(c);
  ASSERT_TRUE(fine);
  EXPECT_GT(fine->triangles, coarse->triangles);
  EXPECT_FALSE(fine->rebuilt);  // refining keeps every triangle: no reason to start over
  EXPECT_GT(fine->splits, 0u);
  expect_converged(*view, c, 1.0);
  EXPECT_EQ(view->mesh_hash(), fresh_hash(1.0));
  s.threshold = 4.0;
  ASSERT_TRUE(view->set_settings(s));
  auto back = view->update(c);
  ASSERT_TRUE(back);
  EXPECT_TRUE(back->merges > 0 || back->rebuilt);
  EXPECT_EQ(back->triangles, coarse->triangles);
  EXPECT_EQ(view->mesh_hash(), fresh_hash(4.0));
  expect_converged(*view, c, 4.0);
}

TEST(Roam, DetailThatTurnsOutOfViewIsMergedBack) {
  auto l = make_landscape(257, 5);
  auto view = RoamView::create(l, {.threshold = 1.0}).value();
  const glm::dvec3 eye(256, 140, 256);
  auto look = [&](double yaw) {
    return camera_at(eye, eye + glm::dvec3(std::cos(yaw), -0.5, std::sin(yaw)), 50.0);
  };
  // Turn on the spot by 180 degrees in 5-degree steps (no translation: only the frustum moves).
  RoamStats st{};
  for (int k = 0; k <= 36; ++k) {
    auto r = view->update(look(k * M_PI / 36));
    ASSERT_TRUE(r);
    st = *r;
  }
  EXPECT_EQ(check_crack_free(*view), "");
  expect_converged(*view, look(M_PI), 1.0);
  // A fresh view for the final camera: the turned view must not carry much more detail.
  auto fresh = RoamView::create(l, {.threshold = 1.0}).value();
  auto f = fresh->update(look(M_PI));
  ASSERT_TRUE(f);
  // What turned out of view merged back: the turned view holds exactly the fresh view's mesh.
  EXPECT_EQ(st.triangles, f->triangles);
  EXPECT_EQ(view->mesh_hash(), fresh->mesh_hash());
}

TEST(Roam, ViewsUpdateOnDifferentThreadsOverOneLandscape) {
  auto l = make_landscape(257, 5);
  auto run = [&](glm::dvec3 eye, std::uint64_t* hash) {
    auto view = RoamView::create(l, {.threshold = 2.0}).value();
    for (int k = 0; k < 40; ++k) {
      eye += glm::dvec3(3, 0, 2);
      ASSERT_TRUE(view->update(camera_at(eye, eye + glm::dvec3(50, -20, 40))));
    }
    *hash = view->mesh_hash();
  };
  std::uint64_t a1 = 0, b1 = 0, a2 = 0, b2 = 0;
  run({10, 150, 10}, &a1);  // reference, one thread
  run({400, 150, 60}, &b1);
  std::thread ta(run, glm::dvec3(10, 150, 10), &a2), tb(run, glm::dvec3(400, 150, 60), &b2);
  ta.join();
  tb.join();
  EXPECT_EQ(a1, a2);
  EXPECT_EQ(b1, b2);
}

TEST(Roam, ATightTimeBudgetStillSplitsAndMerges) {
  // A camera moving fast under a tiny budget: splits and merges still happen every frame and the
  // mesh follows the camera (with the old core's lazy keys it froze: every frame's budget went to
  // re-keying). A budget of 0.1 us is spent before the first change on any machine: the first
  // operations of an update run regardless (docs/roam.md, "Budgets"), so the mesh still moves.
  auto l = make_landscape(257, 5);
  for (const double budget : {0.02, 1e-4}) {
    auto view = RoamView::create(l, {.threshold = 1.0, .budget_ms = budget}).value();
    std::uint64_t changes = 0;
    std::uint32_t frames_with_changes = 0;
    for (int f = 0; f < 120; ++f) {
      const double a = f * 0.05;
      const Camera c =
          camera_at({256 + 200 * std::cos(a), 90, 256 + 200 * std::sin(a)}, {256, 40, 256});
      auto st = view->update(c);
      ASSERT_TRUE(st);
      if (f >= 20) {
        changes += st->splits + st->merges;
        frames_with_changes += st->splits + st->merges > 0;
      }
    }
    EXPECT_GT(changes, 0u) << "budget " << budget;
    EXPECT_GT(frames_with_changes, 50u) << "budget " << budget;
    EXPECT_EQ(check_crack_free(*view), "") << "budget " << budget;
    EXPECT_EQ(view->check_invariants(), "") << "budget " << budget;
  }
}

// A zoom (field of view) changes every projected bound: the front is tested with the new one, so
// each zoom converges to exactly the mesh a fresh view of that camera draws, without cracks.
TEST(Roam, ZoomInAndOutStaysConvergedAndUnique) {
  auto l = make_landscape(257, 5);
  auto view = RoamView::create(l, {.threshold = 1.0}).value();
  const glm::dvec3 eye(60, 150, 60), target(200, 20, 220);
  for (double fov : {60.0, 20.0, 10.0, 90.0, 120.0, 45.0}) {
    const Camera c = camera_at(eye, target, fov);
    auto st = view->update(c);
    ASSERT_TRUE(st) << st.error().message;
    EXPECT_EQ(st->stop, StopReason::kConverged);
    EXPECT_EQ(check_crack_free(*view), "") << "fov " << fov;
    EXPECT_EQ(view->check_invariants(), "") << "fov " << fov;
    expect_converged(*view, c, 1.0);
    auto fresh = RoamView::create(l, {.threshold = 1.0}).value();
    ASSERT_TRUE(fresh->update(c));
    EXPECT_EQ(view->mesh_hash(), fresh->mesh_hash()) << "fov " << fov;
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

// The front's storage, chunk by chunk: entries added and removed (the last moved into the hole)
// across several chunk boundaries keep their data and state, the pass agrees with the test of one
// entry, and trimming gives back the chunks a peak left.
TEST(Front, ChunkedStorageKeepsEntriesAcrossChunks) {
  struct Ref {
    std::int32_t i, j;
    float x, y, z, mu, r;
    std::uint32_t node;
    bool split;
  };
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> pos(-500.0f, 500.0f), bound(0.0f, 4.0f);
  roam::Front f;
  std::vector<Ref> ref;
  auto add = [&] {
    const Ref e{std::int32_t(rng() % 4096),
                std::int32_t(rng() % 4096),
                pos(rng),
                pos(rng) * 0.1f,
                pos(rng),
                bound(rng),
                bound(rng) * 8.0f,
                std::uint32_t(ref.size()),
                (rng() & 1) != 0};
    ASSERT_EQ(f.add(e.i, e.j, 4, 0, 3, e.x, e.y, e.z, e.mu, e.r, e.node, e.split, false),
              ref.size());
    ref.push_back(e);
  };
  auto remove = [&](std::uint32_t e) {
    const std::uint32_t moved = f.remove(e);
    ASSERT_EQ(moved, ref.size() - 1);
    ref[e] = ref.back();
    ref.pop_back();
  };
  const std::uint32_t chunk = roam::Front::kChunkBlocks * roam::Front::kLanes;
  for (std::uint32_t k = 0; k < 3 * chunk + 77; ++k) add();
  const std::size_t peak_bytes = f.memory_bytes();
  for (std::uint32_t k = 0; k < 2 * chunk; ++k) remove(std::uint32_t(rng() % ref.size()));
  for (std::uint32_t k = 0; k < 300; ++k) add();
  ASSERT_EQ(f.size(), ref.size());
  Camera cam;
  cam.eye = {10.0, 80.0, -30.0};
  cam.target = {40.0, 20.0, 70.0};
  const roam::FrontCamera c = roam::FrontCamera::screen(cam, 1.0, 0, 0, 0, 1, 1, 5000);
  f.evaluate(c);
  for (std::uint32_t e = 0; e < f.size(); ++e) {
    const Ref& r = ref[e];
    ASSERT_EQ(f.ci(e), r.i) << e;
    ASSERT_EQ(f.cj(e), r.j) << e;
    ASSERT_EQ(f.node(e), r.node) << e;
    ASSERT_EQ(f.split(e), r.split) << e;
    ASSERT_EQ(f.y(e), r.y) << e;
    ASSERT_EQ(f.mu(e), r.mu) << e;
    ASSERT_EQ(f.radius(e), r.r) << e;
    const std::uint8_t pass = f.result(e);
    ASSERT_EQ(f.test_one(e, c), pass) << e;  // bit for bit, in whichever chunk
  }
  // Under a time budget the pass goes chunk by chunk: with the time already up, one chunk per
  // call, resuming where the last call stopped, and the calls together test every entry once
  // with the same results as the whole pass.
  {
    Camera moved = cam;
    moved.eye = {-40.0, 60.0, 10.0};
    const roam::FrontCamera c2 = roam::FrontCamera::screen(moved, 2.0, 0, 0, 0, 1, 1, 5000);
    f.evaluate(c2);
    std::vector<std::uint8_t> whole(f.size());
    for (std::uint32_t e = 0; e < f.size(); ++e) whole[e] = f.result(e);
    f.evaluate(c);  // other results again
    std::uint32_t cursor = 1, tested = 0, total = 0;
    const std::uint32_t chunks = (f.size() + chunk - 1) / chunk;
    std::vector<roam::Front::Keyed> changed;
    for (std::uint32_t k = 0; k < chunks; ++k) {
      f.evaluate_until(c2, &changed, std::chrono::steady_clock::now(), &cursor, &tested);
      EXPECT_EQ(cursor, (k + 2) % chunks);
      EXPECT_LE(tested, chunk);
      for (const roam::Front::Keyed& x : changed) {
        const std::uint32_t e = x.entry & ~roam::Front::kKeyedSplit;
        EXPECT_EQ(e / chunk, (k + 1) % chunks) << "a changed entry outside the chunk tested";
        EXPECT_NE(bool(f.result(e) & roam::kActive), f.split(e));
      }
      total += tested;
    }
    EXPECT_EQ(total, f.size());
    for (std::uint32_t e = 0; e < f.size(); ++e) ASSERT_EQ(f.result(e), whole[e]) << e;
    // With time to spare, one call tests everything.
    f.evaluate_until(c, &changed, std::chrono::steady_clock::now() + std::chrono::hours(1),
                     &cursor, &tested);
    EXPECT_EQ(tested, f.size());
  }
  // A chunk's blocks and records (the front may have started on a range an earlier view left,
  // with more committed: so the sizes come from the layout, not from the peak).
  const std::size_t chunk_bytes =
      chunk / roam::Front::kLanes * sizeof(roam::Front::Hot) + chunk * sizeof(roam::Front::Cold);
  auto chunks_for = [&](std::size_t n) { return (n + chunk - 1) / chunk; };
  EXPECT_GE(peak_bytes, 4 * chunk_bytes);  // 3 chunks and 77 entries at the peak
  f.trim();
  EXPECT_LT(f.memory_bytes(), peak_bytes);
  // A spare chunk is kept; everything else beyond the entries in use is given back.
  EXPECT_LE(f.memory_bytes(), (chunks_for(ref.size()) + 1) * chunk_bytes);
  // Growing again past what was given back: the entries in use are intact and the new ones
  // read back as written.
  for (std::uint32_t k = 0; k < 2 * chunk; ++k) add();
  EXPECT_GE(f.memory_bytes(), chunks_for(ref.size()) * chunk_bytes);
  for (std::uint32_t e = 0; e < f.size(); ++e) {
    ASSERT_EQ(f.ci(e), ref[e].i) << e;
    ASSERT_EQ(f.mu(e), ref[e].mu) << e;
    ASSERT_EQ(f.node(e), ref[e].node) << e;
    ASSERT_EQ(f.split(e), ref[e].split) << e;
  }
}

// The storage of the node and front arrays: address space reserved once, pages committed as the
// array grows, given back on request, zero when committed again; a request past the range is
// refused like a failed allocation, and what was committed stays usable. A destroyed
// reservation's range and pages go to the next reservation of the same size.
TEST(Reservation, GrowsInPlaceGivesBackAndRefusesPastItsRange) {
  constexpr std::size_t kStep = 64 << 10, kMax = (64 << 20) + (12 << 10);  // a size of its own
  const void* base = nullptr;
  {
    roam::Reservation r;
    EXPECT_EQ(r.data(), nullptr);
    r.grow_to(1, kStep, kMax);
    ASSERT_NE(r.data(), nullptr);
    EXPECT_GE(r.committed(), kStep);  // more when an earlier run of this test left its range
    auto* bytes = static_cast<unsigned char*>(r.data());
    base = r.data();
    std::memset(bytes, 0xab, kStep);
    r.grow_to(5 * kStep + 1, kStep, kMax);
    EXPECT_EQ(r.data(), base) << "the array moved";
    EXPECT_GE(r.committed(), 6 * kStep);
    EXPECT_EQ(bytes[kStep - 1], 0xab);
    std::memset(bytes, 0xcd, 6 * kStep);
    r.shrink_to(kStep + 1);  // keeps whole pages
    EXPECT_GE(r.committed(), kStep + 1);
    EXPECT_LT(r.committed(), 2 * kStep);
    r.grow_to(3 * kStep, kStep, kMax);
    EXPECT_EQ(r.committed(), 3 * kStep);
    EXPECT_EQ(bytes[kStep], 0xcd);       // kept
    EXPECT_EQ(bytes[3 * kStep - 1], 0);  // given back, then fresh
    EXPECT_THROW(r.grow_to(kMax + 1, kStep, kMax), std::bad_alloc);
    EXPECT_EQ(r.committed(), 3 * kStep);
    EXPECT_EQ(bytes[0], 0xcd);
    r.grow_to(kMax, kStep, kMax);  // up to the last byte of the range
    bytes[kMax - 1] = 1;
    EXPECT_EQ(r.committed(), kMax);
    r.shrink_to(4 * kStep);
    bytes[4 * kStep - 1] = 0xef;
  }
  // The next reservation of that size gets the range back with its pages (no new faults);
  // another size gets a range of its own.
  roam::Reservation again, other;
  again.grow_to(kStep, kStep, kMax);
  EXPECT_EQ(again.data(), base);
  EXPECT_EQ(again.committed(), 4 * kStep);
  EXPECT_EQ(static_cast<unsigned char*>(again.data())[4 * kStep - 1], 0xef);
  other.grow_to(kStep, kStep, kMax + kStep);
  EXPECT_NE(other.data(), base);
}

// A view created after a bigger one was destroyed takes over its node and front ranges with
// their pages (no new faults), but holds and reports only what its own mesh needs after its
// first update: the same memory as the same view made first in a fresh range, within the spare
// steps each array keeps (384 KiB of nodes, 40 KiB of front).
TEST(Roam, AViewTakingOverABiggerViewsMemoryKeepsOnlyWhatItNeeds) {
  auto l = make_landscape(257, 5);
  const Camera c = camera_at({128, 60, -40}, {128, 20, 128}, 60);
  auto coarse_memory = [&] {
    RoamSettings s;
    s.threshold = 16;
    auto v = RoamView::create(l, s).value();
    const auto st = v->update(c);
    EXPECT_TRUE(st);
    return st ? st->memory_bytes : 0;
  };
  const std::size_t alone = coarse_memory();
  std::size_t big = 0;
  {
    RoamSettings s;
    s.threshold = 0.5;
    auto v = RoamView::create(l, s).value();
    const auto st = v->update(c);
    ASSERT_TRUE(st);
    big = st->memory_bytes;
  }
  ASSERT_GT(big, alone + 2 * 384 * 1024) << "the fine view is not big enough to tell";
  const std::size_t after = coarse_memory();
  EXPECT_LE(after, alone + 384 * 1024 + 40 * 1024) << "fine view " << big << " bytes";
}
