// The change log (Terrain::changes_since, docs/deformation.md): every brush and load recorded under
// the version it produced with a range and box that cover what changed, detail lattices, a bounded
// log that merges what it drops, and views on several threads pulling the same edits.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <glm/common.hpp>
#include <random>
#include <thread>

#include "edit_test_util.h"
#include "ridgeline/detail.h"
#include "ridgeline/edit.h"
#include "ridgeline/roam_view.h"
#include "ridgeline/scenes.h"
#include "roam_test_util.h"

using namespace ridgeline;
using namespace ridgeline::test;

namespace {

// Every finest-lattice vertex height, row-major.
std::vector<double> lattice_heights(const Terrain& t) {
  std::vector<double> h;
  h.reserve(std::size_t(t.surface().lattice().vertices_x * t.surface().lattice().vertices_z));
  for (std::int64_t j = 0; j < t.surface().lattice().vertices_z; ++j)
    for (std::int64_t i = 0; i < t.surface().lattice().vertices_x; ++i) h.push_back(t.surface().vertex_height(i, j));
  return h;
}

// `c` describes the difference between lattices `before` and `after` of `t`: every changed vertex
// is inside c.vertices, every cell touching one is inside c.box's x/z, and c.box's y spans the
// surface at every vertex under the box, before and after. Returns the vertices that changed.
std::size_t expect_change_describes(const Terrain& t, const TerrainChange& c,
                                    const std::vector<double>& before,
                                    const std::vector<double>& after) {
  const Heightfield hf = t.surface().to_heightfield().value();
  const double fs_x = std::ldexp(hf.spacing_x(), -int(t.surface().detail_levels()));
  const double fs_z = std::ldexp(hf.spacing_z(), -int(t.surface().detail_levels()));
  const double off = hf.height_offset(), eps = 1e-6;
  const std::int64_t w = t.surface().lattice().vertices_x, h = t.surface().lattice().vertices_z;
  std::size_t changed = 0, outside = 0, uncovered = 0;
  std::int64_t ci0 = w, cj0 = h, ci1 = -1, cj1 = -1;
  for (std::int64_t j = 0; j < h; ++j)
    for (std::int64_t i = 0; i < w; ++i) {
      const std::size_t k = std::size_t(i + j * w);
      const double x = hf.origin_x() + i * fs_x, z = hf.origin_z() + j * fs_z;
      if (x >= c.box.min.x - eps && x <= c.box.max.x + eps && z >= c.box.min.z - eps &&
          z <= c.box.max.z + eps) {
        for (double y : {before[k], after[k]})
          if (off + y < c.box.min.y - eps || off + y > c.box.max.y + eps) ++uncovered;
      }
      if (before[k] == after[k]) continue;
      ++changed;
      ci0 = std::min(ci0, i), cj0 = std::min(cj0, j), ci1 = std::max(ci1, i),
      cj1 = std::max(cj1, j);
      if (i < c.vertices.i0 || i > c.vertices.i1 || j < c.vertices.j0 || j > c.vertices.j1)
        ++outside;
      // The cells around a changed vertex changed shape: inside the box (clamped to the footprint).
      const double xa = hf.origin_x() + std::max<std::int64_t>(i - 1, 0) * fs_x;
      const double xb = hf.origin_x() + std::min<std::int64_t>(i + 1, w - 1) * fs_x;
      const double za = hf.origin_z() + std::max<std::int64_t>(j - 1, 0) * fs_z;
      const double zb = hf.origin_z() + std::min<std::int64_t>(j + 1, h - 1) * fs_z;
      if (xa < c.box.min.x - eps || xb > c.box.max.x + eps || za < c.box.min.z - eps ||
          zb > c.box.max.z + eps)
        ++outside;
    }
  EXPECT_EQ(outside, 0u) << "changed vertices outside the change's range or box";
  EXPECT_EQ(uncovered, 0u) << "surface heights under the box outside its y range";
  if (changed > 0) {
    // Tight: the range is the changed vertices' bounding range, widened by at most one stored
    // cell (an edit of stored samples moves the detail lattice in the cells around them).
    const std::int64_t slack = (std::int64_t{1} << t.surface().detail_levels()) - 1;
    EXPECT_GE(ci0, c.vertices.i0);
    EXPECT_LE(ci0 - c.vertices.i0, slack);
    EXPECT_LE(c.vertices.i1 - ci1, slack);
    EXPECT_LE(cj0 - c.vertices.j0, slack);
    EXPECT_LE(c.vertices.j1 - cj1, slack);
  }
  return changed;
}

}  // namespace

TEST(ChangeLog, EveryBrushAndEveryLoadIsRecordedUnderTheVersionItProduced) {
  auto t = noise_terrain(129);
  const std::string empty = save_edits_to_memory(*t);
  EXPECT_EQ(t->edit_version(), 0u);
  EXPECT_TRUE(t->changes_since(0).empty());
  EXPECT_FALSE(t->changes_since(0).trimmed);
  const Edit edits[] = {
      {.brush = Brush::kCrater, .x = 60, .z = 70, .radius = 9, .depth = 4},
      {.brush = Brush::kRaise, .x = 0, .z = 128, .radius = 12, .depth = 3},   // on the edge
      {.brush = Brush::kLower, .x = 256, .z = 256, .radius = 7, .depth = 2},  // the far corner
      {.brush = Brush::kFlatten, .x = 150, .z = 40, .radius = 15, .height = 80},
      {.brush = Brush::kSmooth, .x = 200, .z = 190, .radius = 20},
  };
  std::uint64_t v = 0;
  for (const Edit& e : edits) {
    const auto before = lattice_heights(*t);
    auto r = t->apply_edit(e);
    ASSERT_TRUE(r) << r.error().message;
    ASSERT_FALSE(r->empty()) << brush_name(e.brush);
    const auto after = lattice_heights(*t);
    const TerrainChanges c = t->changes_since(v);
    EXPECT_EQ(c.version, v + 1);
    EXPECT_EQ(t->edit_version(), v + 1);
    ASSERT_EQ(c.changes.size(), 1u);
    EXPECT_FALSE(c.trimmed);
    EXPECT_EQ(c.changes[0].version, v + 1);
    EXPECT_EQ(c.changes[0].box.min, r->changed.min) << "the result's box is the log's";
    EXPECT_EQ(c.changes[0].box.max, r->changed.max);
    EXPECT_EQ(expect_change_describes(*t, c.changes[0], before, after), r->samples_changed)
        << brush_name(e.brush);
    v = c.version;
  }
  const std::string saved = save_edits_to_memory(*t);
  // A load that changes heights is one change too: back to the empty state, then forward.
  for (const std::string* file : {&empty, &saved}) {
    const auto before = lattice_heights(*t);
    auto r = load_edits_from_memory(*t, *file);
    ASSERT_TRUE(r) << r.error().message;
    const auto after = lattice_heights(*t);
    const TerrainChanges c = t->changes_since(v);
    ASSERT_EQ(c.changes.size(), 1u) << (file == &empty ? "empty" : "saved");
    EXPECT_EQ(c.version, v + 1);
    EXPECT_GT(expect_change_describes(*t, c.changes[0], before, after), 0u);
    EXPECT_EQ(t->check_invariants(), "") << "the ray pyramid after a load";
    v = c.version;
  }
  // The whole history, in order; nothing after the current version.
  const TerrainChanges all = t->changes_since(0);
  ASSERT_EQ(all.changes.size(), 7u);
  for (std::size_t k = 0; k < all.changes.size(); ++k) EXPECT_EQ(all.changes[k].version, k + 1);
  EXPECT_TRUE(t->changes_since(v).empty());
  EXPECT_EQ(t->changes_since(v).version, v);
  // Loading the state already in place, a brush outside, a zero-strength brush: no change, no
  // version, no entry.
  ASSERT_TRUE(load_edits_from_memory(*t, saved));
  ASSERT_TRUE(t->apply_edit({.x = 5000, .z = 5000, .radius = 10}));
  ASSERT_TRUE(
      t->apply_edit({.brush = Brush::kRaise, .x = 50, .z = 50, .radius = 10, .strength = 0}));
  EXPECT_EQ(t->edit_version(), v);
  EXPECT_TRUE(t->changes_since(v).empty());
  // A version this terrain never had: the whole footprint, flagged.
  const TerrainChanges future = t->changes_since(v + 5);
  ASSERT_EQ(future.changes.size(), 1u);
  EXPECT_TRUE(future.trimmed);
  EXPECT_EQ(future.version, v);
  EXPECT_EQ(future.changes[0].vertices.i0, 0);
  EXPECT_EQ(future.changes[0].vertices.i1, 128);
  EXPECT_EQ(future.changes[0].vertices.j1, 128);
  EXPECT_EQ(future.changes[0].box.max.x, 256.0);
  EXPECT_LE(future.changes[0].box.min.y, t->info().min_local);
  EXPECT_GE(future.changes[0].box.max.y, t->info().max_local);
}

TEST(ChangeLog, ADetailLatticeMovesAroundTheEditedSamples) {
  auto hf = make_default_heightfield({.size = 65, .spacing = 4.0, .seed = 3});
  DetailParams p;
  p.levels = 2;
  p.amplitude = 1.5;
  DetailCacheDesc cache;
  cache.budget_bytes = std::size_t{16} << 20;
  cache.worker_threads = 0;
  auto t = Terrain::create(std::move(hf).value(), p, cache).value();
  std::uint64_t v = 0;
  for (const Edit& e : {Edit{.brush = Brush::kCrater, .x = 100, .z = 80, .radius = 14, .depth = 5},
                        Edit{.brush = Brush::kRaise, .x = 256, .z = 3, .radius = 10, .depth = 3},
                        Edit{.brush = Brush::kSmooth, .x = 30, .z = 200, .radius = 20}}) {
    const auto before = lattice_heights(*t);
    ASSERT_TRUE(t->apply_edit(e));
    const auto after = lattice_heights(*t);
    const TerrainChanges c = t->changes_since(v);
    ASSERT_EQ(c.changes.size(), 1u);
    EXPECT_GT(expect_change_describes(*t, c.changes[0], before, after), 0u);
    EXPECT_EQ(t->check_invariants(), "");
    v = c.version;
  }
}

TEST(ChangeLog, IsBoundedAndMergesWhatItNoLongerHolds) {
  auto t = flat_terrain(257);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(10, 246);
  Box all{{1e9, 1e9, 1e9}, {-1e9, -1e9, -1e9}};
  const std::size_t n = kChangeLogCapacity + 100;
  std::vector<Box> boxes;
  for (std::size_t k = 0; k < n; ++k) {
    auto r = t->apply_edit({.brush = k % 2 ? Brush::kRaise : Brush::kLower,
                            .x = u(rng),
                            .z = u(rng),
                            .radius = 4,
                            .depth = 1});
    ASSERT_TRUE(r);
    ASSERT_FALSE(r->empty());
    boxes.push_back(r->changed);
    all.min = glm::min(all.min, r->changed.min);
    all.max = glm::max(all.max, r->changed.max);
  }
  ASSERT_EQ(t->edit_version(), n);
  // The last kChangeLogCapacity changes one by one.
  const TerrainChanges recent = t->changes_since(n - kChangeLogCapacity);
  EXPECT_FALSE(recent.trimmed) << "the last kChangeLogCapacity changes came back merged";
  ASSERT_EQ(recent.changes.size(), kChangeLogCapacity)
      << "the last kChangeLogCapacity changes are not listed one by one";
  for (std::size_t k = 0; k < kChangeLogCapacity; ++k) {
    EXPECT_EQ(recent.changes[k].version, n - kChangeLogCapacity + k + 1);
    EXPECT_EQ(recent.changes[k].box.min, boxes[n - kChangeLogCapacity + k].min);
  }
  // Further back: one merged entry covering every change since then.
  for (std::uint64_t since :
       {std::uint64_t{0}, std::uint64_t{50}, std::uint64_t{n - kChangeLogCapacity - 1}}) {
    const TerrainChanges old = t->changes_since(since);
    EXPECT_TRUE(old.trimmed) << since;
    ASSERT_EQ(old.changes.size(), 1u);
    EXPECT_EQ(old.version, n);
    EXPECT_EQ(old.changes[0].version, n);
    for (std::size_t k = since; k < n; ++k) {
      EXPECT_LE(old.changes[0].box.min.x, boxes[k].min.x);
      EXPECT_LE(old.changes[0].box.min.y, boxes[k].min.y);
      EXPECT_GE(old.changes[0].box.max.z, boxes[k].max.z);
      EXPECT_GE(old.changes[0].box.max.y, boxes[k].max.y);
    }
    EXPECT_EQ(old.changes[0].box.min, all.min) << "the merged box is the union, no larger";
  }
  // A clone keeps the version and the log: pulling from it answers the same.
  auto c = t->clone();
  EXPECT_EQ(c->edit_version(), n);
  EXPECT_EQ(c->changes_since(n - 3).changes.size(), 3u);
}

TEST(ChangeLog, ViewsOnSeveralThreadsPullTheSameEditsThroughOneLandscape) {
  auto t = noise_terrain(257, 4);
  auto l = Landscape::create(t, {.patch_exponent = 5}).value();
  const Camera cams[] = {camera_at({256, 260, -60}, {256, 0, 256}),
                         camera_at({-40, 200, 300}, {300, 0, 200}),
                         camera_at({500, 150, 500}, {200, 0, 220})};
  std::vector<std::unique_ptr<RoamView>> views;
  for (int k = 0; k < 3; ++k) {
    views.push_back(RoamView::create(l, {.threshold = 1.0}).value());
    ASSERT_TRUE(views.back()->converge(cams[k]));
  }
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(0, 512);
  for (int round = 0; round < 12; ++round) {
    // Edits from this thread while no view runs (they refresh the landscape's bounds), then the
    // views update at once on three threads, each pulling the terrain's change log.
    for (int k = 0; k < 4; ++k)
      ASSERT_TRUE(t->apply_edit({.brush = k % 2 ? Brush::kRaise : Brush::kCrater, .x = u(rng),
                                 .z = u(rng), .radius = 5.0 + 3 * k, .depth = 4}));
    std::vector<std::thread> threads;
    std::atomic<int> failures{0};
    for (int k = 0; k < 3; ++k)
      threads.emplace_back([&, k] {
        if (!views[k]->converge(cams[k])) ++failures;
      });
    for (auto& th : threads) th.join();
    ASSERT_EQ(failures.load(), 0);
    for (int k = 0; k < 3; ++k) {
      ASSERT_EQ(views[k]->check_invariants(), "") << "view " << k << ", round " << round;
      ASSERT_EQ(check_crack_free(*views[k]), "");
      EXPECT_LE(views[k]->measure_error(cams[k], 3).max_px, 1.0 + 1e-3);
    }
  }
  expect_bounds_equal_rebuild(*l);
  // A landscape and a view made after the edits start from the current surface.
  auto late = Landscape::create(t, {.patch_exponent = 5}).value();
  auto v = RoamView::create(late, {.threshold = 1.0}).value();
  ASSERT_TRUE(v->converge(cams[0]));
  ASSERT_EQ(v->check_invariants(), "");
  EXPECT_LE(v->measure_error(cams[0], 3).max_px, 1.0 + 1e-3);
}
