// Deformation: brush shapes against their analytic profiles, the incremental bounds against a
// rebuild, views crack-free and honest after edits on seams and corners, queries (rays included)
// on the new surface, limits, and the edit file (round trip, undo, refusals that change nothing).
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>

#include "ridgeline/edit.h"
#include "ridgeline/roam_view.h"
#include "ridgeline/scenes.h"
#include "roam_test_util.h"

using namespace ridgeline;
using namespace ridgeline::test;

namespace {

std::shared_ptr<Terrain> flat_terrain(std::uint32_t n, double spacing = 1.0, double offset = 0.0) {
  return Terrain::create(std::move(scenes::field({.width = n,
                                                  .height = n,
                                                  .spacing_x = spacing,
                                                  .spacing_z = spacing,
                                                  .height_offset = offset},
                                                 [](int, int) { return 0.0; }))
                             .value());
}

std::shared_ptr<Terrain> noise_terrain(std::uint32_t n, std::uint32_t seed = 7) {
  return Terrain::create(
      std::move(make_default_heightfield({.size = n, .spacing = 2.0, .seed = seed})).value());
}

std::string tmp_path(const std::string& name) {
  return std::string(RIDGELINE_TEST_TMP) + "/" + name;
}

// Every stored bound of `l` equals the one a fresh Landscape over the same heights computes.
void expect_bounds_equal_rebuild(const Landscape& l) {
  auto fresh = Landscape::create(l.terrain_ptr(), {.patch_exponent = l.patch_exponent()}).value();
  const std::uint64_t per_root = (std::uint64_t{1} << l.max_level()) - 1;
  std::uint64_t bad = 0;
  for (std::uint32_t r = 0; r < l.root_count(); ++r)
    for (std::uint64_t h = 1; h <= per_root; ++h)
      if (l.bound(r, h) != fresh->bound(r, h) && ++bad < 4)
        ADD_FAILURE() << "root " << r << " heap " << h << ": incremental " << l.bound(r, h)
                      << ", rebuilt " << fresh->bound(r, h);
  EXPECT_EQ(bad, 0u);
}

}  // namespace

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
  const auto h0 = t->heights_hash();
  EXPECT_FALSE(t->apply_edit({.x = NAN, .z = 1}));
  EXPECT_FALSE(t->apply_edit({.x = 1, .z = 1, .radius = -1}));
  EXPECT_FALSE(t->apply_edit({.x = 1, .z = 1, .radius = INFINITY}));
  EXPECT_FALSE(t->apply_edit({.x = 1, .z = 1, .strength = 2}));
  EXPECT_FALSE(t->apply_edit({.x = 1, .z = 1, .radius = 1000}));  // larger than the terrain
  EXPECT_EQ(t->heights_hash(), h0);
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
    EXPECT_GT(r->view_nodes_updated, 0u);
    // The patch under the edit's centre is dirty.
    const auto dirty = v->take_dirty_patches();
    const std::uint32_t p =
        std::uint32_t(std::min(x / 64.0, 7.0)) + 8 * std::uint32_t(std::min(z / 64.0, 7.0));
    EXPECT_NE(std::find(dirty.begin(), dirty.end(), p), dirty.end());
    // Rays see the new surface (the pyramid was refreshed): straight down hits at height().
    auto hit = t->raycast({x, 1000, z}, {0, -1, 0}, 5000);
    ASSERT_TRUE(hit);
    EXPECT_NEAR(hit->point.y, *t->height(x, z), 1e-4);  // height() interpolates in float
    ASSERT_TRUE(v->converge(cam));
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

TEST(EditFile, RoundTripUndoAndRefusals) {
  auto t = noise_terrain(129);
  auto l = Landscape::create(t, {.patch_exponent = 4}).value();
  const std::string a = tmp_path("edits_a.bin"), b = tmp_path("edits_b.bin");
  const auto h0 = t->heights_hash();
  ASSERT_TRUE(save_edits(*t, a));  // empty layer
  ASSERT_TRUE(t->apply_edit({.x = 40, .z = 60, .radius = 12, .depth = 4}));
  ASSERT_TRUE(
      t->apply_edit({.brush = Brush::kFlatten, .x = 200, .z = 250, .radius = 20, .height = 50}));
  const auto h1 = t->heights_hash();
  ASSERT_NE(h0, h1);
  ASSERT_TRUE(save_edits(*t, b));
  ASSERT_TRUE(t->apply_edit({.x = 100, .z = 100, .radius = 30, .depth = 9}));
  // Undo by loading the earlier saves; bounds follow.
  auto r = load_edits(*t, b);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(t->heights_hash(), h1);
  expect_bounds_equal_rebuild(*l);
  ASSERT_TRUE(load_edits(*t, a));
  EXPECT_EQ(t->heights_hash(), h0);
  EXPECT_EQ(t->edited_chunks(), 0u);
  ASSERT_TRUE(load_edits(*t, b));
  EXPECT_EQ(t->heights_hash(), h1);
  // A fresh terrain with the same base loads it to the same hash.
  auto t2 = noise_terrain(129);
  ASSERT_TRUE(load_edits(*t2, b));
  EXPECT_EQ(t2->heights_hash(), h1);

  // Refusals change nothing.
  std::ifstream in(b, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_TRUE(t->apply_edit({.x = 10, .z = 10, .radius = 5}));
  const auto h2 = t->heights_hash();
  for (std::size_t cut : {std::size_t{0}, std::size_t{10}, std::size_t{63}, std::size_t{72},
                          bytes.size() / 2, bytes.size() - 1}) {
    auto bad = load_edits_from_memory(*t, std::string_view(bytes).substr(0, cut));
    ASSERT_FALSE(bad) << "truncated to " << cut;
    EXPECT_NE(bad.error().message.find("edit file"), std::string::npos);
  }
  for (std::size_t at : {std::size_t{0}, std::size_t{9}, std::size_t{20}, std::size_t{70},
                         bytes.size() / 2, bytes.size() - 3}) {
    std::string c = bytes;
    c[at] ^= 0x5a;
    EXPECT_FALSE(load_edits_from_memory(*t, c)) << "corrupted at " << at;
  }
  auto other = noise_terrain(129, 8);  // another base
  auto foreign = load_edits(*other, b);
  ASSERT_FALSE(foreign);
  EXPECT_NE(foreign.error().message.find("another terrain"), std::string::npos);
  EXPECT_FALSE(load_edits(*t, tmp_path("missing.bin")));
  EXPECT_EQ(t->heights_hash(), h2);
  expect_bounds_equal_rebuild(*l);
}

TEST(EditFile, FailedSaveKeepsThePreviousFile) {
  auto t = flat_terrain(65);
  const std::string dir = tmp_path("ro_dir");
  ::mkdir(dir.c_str(), 0755);
  const std::string f = dir + "/state.bin";
  ASSERT_TRUE(save_edits(*t, f));
  ASSERT_TRUE(t->apply_edit({.x = 32, .z = 32, .radius = 5}));
  ::chmod(dir.c_str(), 0555);          // the temporary file cannot be created
  const bool root = ::geteuid() == 0;  // root ignores the mode: nothing to prove then
  auto s = save_edits(*t, f);
  ::chmod(dir.c_str(), 0755);
  if (!root) {
    ASSERT_FALSE(s);
    EXPECT_NE(s.message().find("previous file"), std::string::npos) << s.message();
    auto fresh = flat_terrain(65);
    ASSERT_TRUE(load_edits(*fresh, f));  // the old (empty) state is intact
    EXPECT_EQ(fresh->edited_chunks(), 0u);
  }
  EXPECT_FALSE(save_edits(*t, tmp_path("no/such/dir/state.bin")));
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
