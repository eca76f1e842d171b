// Deformation: brush shapes against their analytic profiles, the incremental bounds against a
// rebuild, views crack-free and honest after edits on seams and corners, queries (rays included)
// on the new surface, limits, snapshots, and heights over a rectangle. The edit file's bytes:
// test_edit_bytes.cpp; the change log: test_change_log.cpp; edit files on disk:
// test_edit_file.cpp (Ridgeline::io).
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

TEST(Brushes, CraterMatchesItsProfile) {
  auto t = flat_terrain(257);
  Edit e{.brush = Brush::kCrater, .x = 128, .z = 128, .radius = 40, .depth = 5, .rim = 0.3};
  auto r = t->apply_edit(e);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_FALSE(r->empty());
  for (int i = 60; i <= 196; i += 4) {
    const double rn = std::abs(i - 128.0) / 40.0;
    double want = 0;
    if (rn <= 1)
      want = 5 * ((rn * rn - 1) + 0.3 * rn * rn);
    else if (rn < 1.5)
      want = 5 * 0.3 * std::pow(1 - std::pow((rn - 1) / 0.5, 2), 2);
    EXPECT_NEAR(*t->height(i, 128), want, 1e-5) << "x = " << i;
  }
  EXPECT_NEAR(*t->height(128, 128), -5.0, 1e-6);  // bowl bottom
  EXPECT_NEAR(*t->height(168, 128), 1.5, 1e-5);   // rim crest: rim x depth
  EXPECT_EQ(*t->height(128 + 61, 128), 0.0);      // beyond 1.5 radius: untouched
  // The changed box holds the whole rim and the height range.
  EXPECT_LE(r->changed.min.x, 128 - 60 + 1.0);
  EXPECT_GE(r->changed.max.x, 128 + 60 - 1.0);
  EXPECT_NEAR(r->changed.min.y, -5.0, 1e-6);
  EXPECT_NEAR(r->changed.max.y, 1.5, 1e-5);
}

TEST(Brushes, RaiseLowerFlattenSmooth) {
  auto t = flat_terrain(129);
  ASSERT_TRUE(t->apply_edit(
      {.brush = Brush::kRaise, .x = 64, .z = 64, .radius = 20, .strength = 0.5, .depth = 4}));
  EXPECT_NEAR(*t->height(64, 64), 2.0, 1e-6);
  EXPECT_NEAR(*t->height(74, 64), 2.0 * std::pow(1 - 0.25, 2), 1e-5);  // r = 0.5
  ASSERT_TRUE(t->apply_edit(
      {.brush = Brush::kLower, .x = 64, .z = 64, .radius = 20, .strength = 0.5, .depth = 4}));
  EXPECT_NEAR(*t->height(64, 64), 0.0, 1e-6);
  ASSERT_TRUE(
      t->apply_edit({.brush = Brush::kFlatten, .x = 64, .z = 64, .radius = 20, .height = 7}));
  EXPECT_NEAR(*t->height(64, 64), 7.0, 1e-6);
  EXPECT_NEAR(*t->height(73, 64), 7.0, 1e-6);    // r = 0.45: full weight
  EXPECT_NEAR(*t->height(84.5, 64), 0.0, 1e-6);  // past the radius
  // Smooth lowers the variance of a rough patch.
  auto n = noise_terrain(129, 3);
  auto variance = [&] {
    double s = 0, s2 = 0;
    int c = 0;
    for (int j = 50; j <= 78; ++j)
      for (int i = 50; i <= 78; ++i) {
        const double h = *n->height(2.0 * i, 2.0 * j);
        const double lap =
            h - 0.25 * (*n->height(2.0 * i - 2, 2.0 * j) + *n->height(2.0 * i + 2, 2.0 * j) +
                        *n->height(2.0 * i, 2.0 * j - 2) + *n->height(2.0 * i, 2.0 * j + 2));
        s += lap, s2 += lap * lap, ++c;
      }
    return s2 / c - (s / c) * (s / c);
  };
  const double before = variance();
  for (int k = 0; k < 3; ++k)
    ASSERT_TRUE(n->apply_edit({.brush = Brush::kSmooth, .x = 128, .z = 128, .radius = 60}));
  EXPECT_LT(variance(), 0.5 * before);
}

TEST(Limits, DefinedAnswers) {
  auto t = flat_terrain(65);
  const auto h0 = t->surface().heights_hash();
  EXPECT_FALSE(t->apply_edit({.x = NAN, .z = 1}));
  EXPECT_FALSE(t->apply_edit({.x = 1, .z = 1, .radius = -1}));
  EXPECT_FALSE(t->apply_edit({.x = 1, .z = 1, .radius = INFINITY}));
  EXPECT_FALSE(t->apply_edit({.x = 1, .z = 1, .strength = 2}));
  EXPECT_FALSE(t->apply_edit({.x = 1, .z = 1, .radius = 1000}));  // larger than the terrain
  EXPECT_EQ(t->surface().heights_hash(), h0);
  // Wholly outside: a no-op with an empty region.
  auto r = t->apply_edit({.x = 500, .z = 500, .radius = 10});
  ASSERT_TRUE(r);
  EXPECT_TRUE(r->empty());
  EXPECT_EQ(t->edit_version(), 0u);
  // Height limit: clamped and reported.
  EditLimits lim;
  lim.min_height_rel = -1;
  ASSERT_TRUE(t->set_edit_limits(lim));
  r = t->apply_edit({.x = 32, .z = 32, .radius = 10, .depth = 5});
  ASSERT_TRUE(r);
  EXPECT_TRUE(r->clamped);
  EXPECT_EQ(*t->height(32, 32), -1.0);
  // Area cap: clipped (and said), or refused.
  lim.max_area_m2 = 100;
  ASSERT_TRUE(t->set_edit_limits(lim));
  r = t->apply_edit({.brush = Brush::kRaise, .x = 32, .z = 32, .radius = 20});
  ASSERT_TRUE(r);
  EXPECT_TRUE(r->clipped);
  EXPECT_NEAR(r->radius_used, std::sqrt(100 / M_PI), 1e-9);
  lim.refuse_oversize = true;
  ASSERT_TRUE(t->set_edit_limits(lim));
  EXPECT_FALSE(t->apply_edit({.brush = Brush::kRaise, .x = 32, .z = 32, .radius = 20}));
  EXPECT_FALSE(t->set_edit_limits({.max_area_m2 = NAN}));
  EXPECT_FALSE(t->set_edit_limits({.min_height_rel = 5, .max_height_rel = 1}));
}

TEST(Transaction, BoundsEqualRebuildOnSeamsCornersAndEdges) {
  auto t = noise_terrain(129);
  auto l = Landscape::create(t, {.patch_exponent = 4}).value();
  // Patch corners (multiples of 16 samples = 32 m), the terrain's edges and corner (padding).
  const double spots[][2] = {{32, 32},   {64, 0},   {0, 0},  {256, 256},
                             {256, 100}, {96, 160}, {3, 255}};
  for (const auto& s : spots)
    ASSERT_TRUE(
        t->apply_edit({.brush = Brush::kCrater, .x = s[0], .z = s[1], .radius = 9, .depth = 6}));
  expect_bounds_equal_rebuild(*l);
}

TEST(Transaction, ViewsStayCrackFreeAndHonestAndQueriesSeeTheEdit) {
  auto t = noise_terrain(257);
  auto l = Landscape::create(t, {.patch_exponent = 5}).value();
  auto v = RoamView::create(l, {.metric = ErrorMetric::kWorldMetres, .threshold = 0.25}).value();
  const Camera cam = camera_at({256, 300, -50}, {256, 0, 256});
  ASSERT_TRUE(v->converge(cam));
  (void)v->take_dirty_patches();
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0, 512);
  for (int k = 0; k < 24; ++k) {
    const double x = u(rng), z = u(rng);
    auto r = t->apply_edit({.brush = k % 2 ? Brush::kCrater : Brush::kRaise,
                            .x = x,
                            .z = z,
                            .radius = 6.0 + k % 13,
                            .depth = 3});
    ASSERT_TRUE(r);
    if (r->empty()) continue;
    // Pulled, not pushed: the view hears of the edit at its next update.
    EXPECT_TRUE(v->take_dirty_patches().empty());
    // Rays see the new surface (the pyramid was refreshed): straight down hits at height().
    auto hit = t->raycast({x, 1000, z}, {0, -1, 0}, 5000);
    ASSERT_TRUE(hit);
    EXPECT_NEAR(hit->point.y, *t->height(x, z), 1e-4);  // height() interpolates in float
    ASSERT_TRUE(v->converge(cam));
    // The patch under the edit's centre is dirty.
    const auto dirty = v->take_dirty_patches();
    const std::uint32_t p = std::uint32_t(std::min(x / 64.0, 7.0)) + 8 * std::uint32_t(std::min(z / 64.0, 7.0));
    EXPECT_NE(std::find(dirty.begin(), dirty.end(), p), dirty.end());
    ASSERT_EQ(v->check_invariants(), "");
    ASSERT_EQ(check_crack_free(*v), "");
    const auto err = v->measure_error(cam);
    EXPECT_LE(err.max_m, 0.25 + 1e-5) << "after edit " << k;
  }
  expect_bounds_equal_rebuild(*l);
  // The mesh's vertices carry the edited heights.
  EXPECT_GT(expect_mesh_on_surface(*v, *t, 7, 1e-3), 100u);
}

TEST(Transaction, TenThousandRandomEditsWhileTheCameraMoves) {
  auto t = noise_terrain(129, 11);
  auto l = Landscape::create(t, {.patch_exponent = 4}).value();
  auto v = RoamView::create(l, {.threshold = 1.5, .max_triangles = 20000}).value();
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-20, 276), ur(1, 12), ud(-3, 3);
  const Brush brushes[] = {Brush::kCrater, Brush::kRaise, Brush::kLower, Brush::kFlatten,
                           Brush::kSmooth};
  for (int k = 0; k < 10000; ++k) {
    Edit e{.brush = brushes[k % 5],
           .x = u(rng),
           .z = u(rng),
           .radius = ur(rng),
           .depth = ud(rng),
           .height = 100 + 10 * ud(rng)};
    ASSERT_TRUE(t->apply_edit(e));
    if (k % 10 == 0) {
      const double a = k * 0.002;
      const Camera cam =
          camera_at({128 + 200 * std::cos(a), 180, 128 + 200 * std::sin(a)}, {128, 60, 128});
      ASSERT_TRUE(v->update(cam));
    }
    if (k % 100 == 99) {
      ASSERT_EQ(v->check_invariants(), "") << "after edit " << k;
      ASSERT_EQ(check_crack_free(*v), "") << "after edit " << k;
    }
  }
  expect_bounds_equal_rebuild(*l);
}


TEST(Transaction, CloneIsASnapshot) {
  auto t = noise_terrain(65);
  auto snap = t->clone();
  const double before = *snap->height(64, 64);
  ASSERT_TRUE(t->apply_edit({.x = 64, .z = 64, .radius = 10, .depth = 5}));
  EXPECT_EQ(*snap->height(64, 64), before);
  EXPECT_NE(*t->height(64, 64), before);
  EXPECT_EQ(snap->base_hash(), t->base_hash());
}

TEST(Brushes, KeepDetailFalseIsRefusedOverDetailAndNeedsNothingWithout) {
  // With detail: refused with the reason, and nothing changes (heights, version, log).
  auto hf = make_default_heightfield({.size = 65, .spacing = 4.0, .seed = 3});
  DetailParams p;
  p.levels = 2;
  DetailCacheDesc cache;
  cache.worker_threads = 0;
  cache.budget_bytes = std::size_t{16} << 20;
  auto t = Terrain::create(std::move(hf).value(), p, cache).value();
  const auto h0 = t->surface().heights_hash();
  const double y0 = *t->height(100, 80);
  for (Brush b : {Brush::kFlatten, Brush::kSmooth, Brush::kCrater}) {
    auto r = t->apply_edit(
        {.brush = b, .x = 100, .z = 80, .radius = 20, .height = 10, .keep_detail = false});
    ASSERT_FALSE(r) << brush_name(b);
    EXPECT_NE(r.error().message.find("keep_detail = false is not supported"), std::string::npos)
        << r.error().message;
    EXPECT_NE(r.error().message.find("2 levels"), std::string::npos) << r.error().message;
  }
  EXPECT_EQ(t->surface().heights_hash(), h0);
  EXPECT_EQ(*t->height(100, 80), y0);
  EXPECT_EQ(t->edit_version(), 0u);
  EXPECT_TRUE(t->changes_since(0).empty());
  // keep_detail = true there: the detail rides on top of the flattened site.
  ASSERT_TRUE(
      t->apply_edit({.brush = Brush::kFlatten, .x = 100, .z = 80, .radius = 20, .height = 10}));
  const double fs = 1.0;  // finest spacing: 4 m / 2^2
  double spread = 0;
  for (int k = 1; k < 8; ++k)
    spread = std::max(spread, std::abs(*t->height(100 + k * fs * 0.5, 80) - 10));
  EXPECT_GT(spread, 1e-3) << "detail shows through a flattened site";
  // Without detail there is nothing to replace: false and true give the same surface.
  auto a = noise_terrain(65), b = noise_terrain(65);
  const Edit flat{.brush = Brush::kFlatten, .x = 60, .z = 60, .radius = 15, .height = 30};
  Edit flat_false = flat;
  flat_false.keep_detail = false;
  ASSERT_TRUE(a->apply_edit(flat));
  ASSERT_TRUE(b->apply_edit(flat_false));
  EXPECT_EQ(a->surface().heights_hash(), b->surface().heights_hash());
}

// ---- heights over a rectangle ------------------------------------------------------------------

// set_heights writes exactly the given heights (row stride honoured, the rest untouched) as one
// edit: one version and one change-log entry covering the rectangle, bounds equal to a rebuild,
// a view over it crack-free, queries at the samples exact, and get_heights and a save / load
// round trip give them back.
TEST(HeightsOverARectangle, SetThenGetWithAStride) {
  auto t = noise_terrain(129);
  auto land = Landscape::create(t).value();
  auto view = RoamView::create(land, {.threshold = 1.0}).value();
  const WorldInfo& w = t->info();
  const std::uint32_t i0 = 40, j0 = 50, cw = 17, ch = 9, stride = 20;
  std::vector<float> in(std::size_t(ch) * stride, -1.0f);
  for (std::uint32_t r = 0; r < ch; ++r)
    for (std::uint32_t c = 0; c < cw; ++c) in[r * stride + c] = 300.0f + 0.5f * float(c) - 1.25f * float(r);
  std::vector<float> outside_before(4);
  ASSERT_TRUE(t->get_heights(i0 - 1, j0, 1, 4, outside_before, 1));
  const std::uint64_t v0 = t->edit_version();
  auto r = t->set_heights(i0, j0, cw, ch, in, stride);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->samples_changed, std::size_t(cw) * ch);
  EXPECT_EQ(t->edit_version(), v0 + 1);
  const TerrainChanges changes = t->changes_since(v0);
  ASSERT_EQ(changes.changes.size(), 1u);
  EXPECT_LE(changes.changes[0].box.min.x, w.origin_x + i0 * w.spacing_x);
  EXPECT_GE(changes.changes[0].box.max.x, w.origin_x + (i0 + cw - 1) * w.spacing_x);
  for (std::uint32_t r2 = 0; r2 < ch; ++r2)
    for (std::uint32_t c = 0; c < cw; ++c) {
      const auto h = t->height(w.origin_x + (i0 + c) * w.spacing_x, w.origin_z + (j0 + r2) * w.spacing_z);
      ASSERT_TRUE(h);
      EXPECT_EQ(float(*h), in[r2 * stride + c]) << "sample " << c << ", " << r2;
    }
  std::vector<float> back(std::size_t(ch) * 31, 0.0f);
  ASSERT_TRUE(t->get_heights(i0, j0, cw, ch, back, 31));
  for (std::uint32_t r2 = 0; r2 < ch; ++r2)
    for (std::uint32_t c = 0; c < cw; ++c) EXPECT_EQ(back[r2 * 31 + c], in[r2 * stride + c]);
  std::vector<float> outside_after(4);
  ASSERT_TRUE(t->get_heights(i0 - 1, j0, 1, 4, outside_after, 1));
  EXPECT_EQ(outside_after, outside_before) << "the column left of the rectangle is untouched";
  expect_bounds_equal_rebuild(*land);
  ASSERT_TRUE(view->converge(camera_at({w.origin_x + 30, 500, w.origin_z + 30},
                                       {w.origin_x + (i0 + 8) * w.spacing_x, 300,
                                        w.origin_z + (j0 + 4) * w.spacing_z})));
  EXPECT_EQ(check_crack_free(*view), "");
  // Saved with the edits.
  const std::string saved = save_edits_to_memory(*t);
  auto fresh = noise_terrain(129);
  ASSERT_TRUE(load_edits_from_memory(*fresh, saved));
  std::vector<float> loaded(std::size_t(cw) * ch);
  ASSERT_TRUE(fresh->get_heights(i0, j0, cw, ch, loaded, cw));
  for (std::uint32_t r2 = 0; r2 < ch; ++r2)
    for (std::uint32_t c = 0; c < cw; ++c) EXPECT_EQ(loaded[r2 * cw + c], in[r2 * stride + c]);
}

TEST(HeightsOverARectangle, BadRectanglesAndHeightsChangeNothing) {
  auto t = noise_terrain(65);
  std::vector<float> v(64 * 64, 100.0f);
  auto msg = [](const Status& s) { return s ? std::string() : s.message(); };
  EXPECT_EQ(msg(t->get_heights(0, 0, 0, 4, v, 4)), "get_heights: an empty rectangle (0 x 4 samples)");
  EXPECT_EQ(msg(t->get_heights(60, 0, 6, 2, v, 6)), "get_heights: samples 60..65 x 0..1 pass the stored 65 x 65");
  EXPECT_EQ(msg(t->get_heights(0, 0, 8, 2, v, 7)), "get_heights: stride 7 is below the width 8");
  EXPECT_EQ(msg(t->get_heights(0, 0, 8, 3, std::span<float>(v).first(20), 8)),
            "get_heights: 20 values given; the rectangle needs 24");
  const std::uint64_t v0 = t->edit_version();
  v[9] = std::nanf("");
  auto r = t->set_heights(2, 3, 8, 2, v, 8);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().message, "set_heights: the height of sample (3, 4) is nan; need a finite value");

  EditLimits lim = t->edit_limits();
  lim.max_area_m2 = 100;  // 2 m spacing: 4 m^2 a sample
  ASSERT_TRUE(t->set_edit_limits(lim));
  v[9] = 1.0f;
  r = t->set_heights(0, 0, 6, 5, v, 6);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("EditLimits::max_area_m2"), std::string::npos) << r.error().message;
  EXPECT_EQ(t->edit_version(), v0) << "nothing changed";
}
