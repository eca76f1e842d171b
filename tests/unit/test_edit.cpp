// Deformation: brush shapes against their analytic profiles, the incremental bounds against a
// rebuild, views crack-free and honest after edits on seams and corners, queries (rays included)
// on the new surface, limits, and the edit file's bytes in memory and through streams (round trip,
// undo, refusals that change nothing). Edit files on disk: test_edit_file.cpp (Ridgeline::io).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <glm/common.hpp>
#include <random>
#include <thread>

#include "ridgeline/detail.h"
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
                             .value()).value();
}

std::shared_ptr<Terrain> noise_terrain(std::uint32_t n, std::uint32_t seed = 7) {
  return Terrain::create(
      std::move(make_default_heightfield({.size = n, .spacing = 2.0, .seed = seed})).value()).value();
}

// Every bound of `l` (refreshed by the edits themselves) equals the one a fresh Landscape over
// the same heights computes.
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

TEST(EditFile, RoundTripUndoAndRefusals) {
  auto t = noise_terrain(129);
  auto l = Landscape::create(t, {.patch_exponent = 4}).value();
  const auto h0 = t->surface().heights_hash();
  const std::string a = save_edits_to_memory(*t);  // empty layer
  EXPECT_EQ(a.size(), 72u) << "header and checksum only";
  ASSERT_TRUE(t->apply_edit({.x = 40, .z = 60, .radius = 12, .depth = 4}));
  ASSERT_TRUE(
      t->apply_edit({.brush = Brush::kFlatten, .x = 200, .z = 250, .radius = 20, .height = 50}));
  const auto h1 = t->surface().heights_hash();
  ASSERT_NE(h0, h1);
  const std::string b = save_edits_to_memory(*t);
  ASSERT_TRUE(t->apply_edit({.x = 100, .z = 100, .radius = 30, .depth = 9}));
  // Undo by loading the earlier saves; bounds follow.
  auto r = load_edits_from_memory(*t, b);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(t->surface().heights_hash(), h1);
  expect_bounds_equal_rebuild(*l);
  ASSERT_TRUE(load_edits_from_memory(*t, a));
  EXPECT_EQ(t->surface().heights_hash(), h0);
  EXPECT_EQ(t->surface().edited_chunks(), 0u);
  ASSERT_TRUE(load_edits_from_memory(*t, b));
  EXPECT_EQ(t->surface().heights_hash(), h1);
  EXPECT_EQ(save_edits_to_memory(*t), b) << "loading and saving again gives the same bytes";
  // A fresh terrain with the same base loads it to the same hash.
  auto t2 = noise_terrain(129);
  ASSERT_TRUE(load_edits_from_memory(*t2, b));
  EXPECT_EQ(t2->surface().heights_hash(), h1);

  // Refusals change nothing.
  const std::string& bytes = b;
  ASSERT_TRUE(t->apply_edit({.x = 10, .z = 10, .radius = 5}));
  const auto h2 = t->surface().heights_hash();
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
  auto foreign = load_edits_from_memory(*other, b);
  ASSERT_FALSE(foreign);
  EXPECT_NE(foreign.error().message.find("another terrain"), std::string::npos);
  EXPECT_EQ(t->surface().heights_hash(), h2);
  expect_bounds_equal_rebuild(*l);
}

namespace {

// A sink that keeps what it gets, one write() at a time, and fails the write numbered `fail_at`.
struct RecordingSink final : EditSink {
  std::vector<std::string> writes;
  std::size_t fail_at = SIZE_MAX;
  Status write(std::string_view bytes) override {
    if (writes.size() == fail_at) return Error{"sink full"};
    writes.emplace_back(bytes);
    return {};
  }
  std::string all() const {
    std::string out;
    for (const std::string& w : writes) out += w;
    return out;
  }
};

// A source over `bytes` that hands out at most `step` bytes a read and fails after `fail_after`
// bytes; counts what it handed out.
struct ChunkedSource final : EditSource {
  std::string bytes;
  std::size_t step = 1, fail_after = SIZE_MAX, at = 0;
  Result<std::size_t> read(std::span<char> buffer) override {
    if (at >= fail_after) return Error{"source broke"};
    const std::size_t n = std::min({buffer.size(), step, bytes.size() - at});
    std::memcpy(buffer.data(), bytes.data() + at, n);
    at += n;
    return n;
  }
};

}  // namespace

TEST(EditFile, StreamsGiveTheBytesOfMemoryInBoundedWrites) {
  auto t = noise_terrain(257);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 512);
  for (int k = 0; k < 80; ++k)  // most of its 9 x 9 chunks: several 64 KiB writes
    ASSERT_TRUE(t->apply_edit({.x = u(rng), .z = u(rng), .radius = 20, .depth = 2}));
  const std::string bytes = save_edits_to_memory(*t);
  ASSERT_GT(bytes.size(), std::size_t{3} << 16);
  RecordingSink sink;
  ASSERT_TRUE(save_edits(*t, sink));
  EXPECT_EQ(sink.all(), bytes);
  EXPECT_GT(sink.writes.size(), 3u);
  for (const std::string& w : sink.writes) EXPECT_LE(w.size(), std::size_t{1} << 16);
  // A sink error stops the save and comes back unchanged.
  RecordingSink failing;
  failing.fail_at = 2;
  const Status s = save_edits(*t, failing);
  ASSERT_FALSE(s);
  EXPECT_EQ(s.message(), "sink full");
  EXPECT_EQ(failing.writes.size(), 2u) << "nothing written after the error";
  // Loaded through a source that gives a byte, or 7, or 64 KiB at a time: the same terrain.
  for (const std::size_t step : {std::size_t{1}, std::size_t{7}, std::size_t{1} << 16}) {
    auto fresh = noise_terrain(257);
    ChunkedSource src;
    src.bytes = bytes;
    src.step = step;
    auto r = load_edits(*fresh, src);
    ASSERT_TRUE(r) << "step " << step << ": " << r.error().message;
    EXPECT_EQ(fresh->surface().heights_hash(), t->surface().heights_hash()) << "step " << step;
  }
}

TEST(EditFile, ASourceErrorOrAnOversizedStreamChangesNothing) {
  auto t = noise_terrain(129);
  ASSERT_TRUE(t->apply_edit({.x = 40, .z = 60, .radius = 12, .depth = 4}));
  const std::string bytes = save_edits_to_memory(*t);
  auto target = noise_terrain(129);
  const auto h0 = target->surface().heights_hash();
  // The source fails half way: its error, unchanged; nothing applied.
  ChunkedSource broken;
  broken.bytes = bytes;
  broken.step = 100;
  broken.fail_after = bytes.size() / 2;
  auto r = load_edits(*target, broken);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().message, "source broke");
  EXPECT_EQ(target->surface().heights_hash(), h0);
  EXPECT_EQ(target->edit_version(), 0u);
  // A stream longer than any edit file of this terrain (5 x 5 chunks, 4 x 4 blocks of holes):
  // refused after reading one chunk past that size, not to its end.
  const std::size_t chunk = 8 + 4 * 32 * 32, largest = 64 + 25 * chunk + 16 * (8 + 128) + 8;
  ChunkedSource endless;
  endless.bytes = bytes + std::string(std::size_t{64} << 20, '\0');
  endless.step = std::size_t{1} << 16;
  r = load_edits(*target, endless);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("larger than any edit file of this terrain"), std::string::npos)
      << r.error().message;
  EXPECT_EQ(endless.at, largest + chunk + 1) << "read no further than needed";
  // The same length with a foreign header names the header's problem instead.
  endless.bytes[0] = 'X';
  endless.at = 0;
  r = load_edits(*target, endless);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("bad magic"), std::string::npos) << r.error().message;
  EXPECT_EQ(target->surface().heights_hash(), h0);
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

// ---- the change log (Terrain::changes_since) -------------------------------------------------

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

TEST(EditFile, EveryRegionOfTheHeaderAndBodyIsGuarded) {
  auto t = noise_terrain(129);
  ASSERT_TRUE(t->apply_edit({.x = 40, .z = 60, .radius = 12, .depth = 4}));
  ASSERT_TRUE(t->apply_edit({.brush = Brush::kRaise, .x = 200, .z = 230, .radius = 9, .depth = 3}));
  const std::string bytes = save_edits_to_memory(*t);
  const std::size_t chunk = 8 + 4 * 32 * 32;
  ASSERT_GE(t->surface().edited_chunks(), 2u);
  ASSERT_EQ(bytes.size(), 64 + t->surface().edited_chunks() * chunk + 8);
  // The fresh terrain the file is loaded onto; every refusal leaves it as it was.
  auto target = noise_terrain(129);
  const auto h0 = target->surface().heights_hash();
  ASSERT_TRUE(load_edits_from_memory(*target, bytes)) << "the intact file loads";
  ASSERT_EQ(target->surface().heights_hash(), t->surface().heights_hash());
  ASSERT_EQ(target->check_invariants(), "");
  target = noise_terrain(129);
  auto fnv = [](const std::string& b) {
    std::uint64_t h = 1469598103934665603ull;
    for (std::size_t k = 0; k + 8 < b.size(); ++k)
      h = (h ^ static_cast<unsigned char>(b[k])) * 1099511628211ull;
    return h;
  };
  auto reseal = [&](std::string b) {  // recompute the trailing checksum, little-endian
    const std::uint64_t h = fnv(b);
    std::memcpy(b.data() + b.size() - 8, &h, 8);
    return b;
  };
  auto refused = [&](const std::string& b, const std::string& why, std::size_t at) {
    auto r = load_edits_from_memory(*target, b);
    if (r) {
      ADD_FAILURE() << "byte " << at << ": accepted";
      return;
    }
    EXPECT_NE(r.error().message.find(why), std::string::npos)
        << "byte " << at << ": " << r.error().message << " (wanted '" << why << "')";
    EXPECT_EQ(r.error().message.rfind("edit file", 0), 0u) << r.error().message;
    EXPECT_EQ(target->surface().heights_hash(), h0) << "byte " << at << " changed the terrain";
    EXPECT_EQ(target->edit_version(), 0u);
  };
  // The header field each byte belongs to, and what a change there must say when the checksum is
  // left alone (fields checked before it) and when it is recomputed (the field's own check).
  struct Region {
    std::size_t from, to;
    const char *stale, *resealed;
  };
  const Region header[] = {
      {0, 8, "bad magic", "bad magic"},
      {8, 12, "version", "version"},
      {12, 16, "chunk size", "chunk size"},
      {16, 24, "another terrain", "another terrain"},
      {24, 32, "detail", "detail"},
      {32, 40, "terrain; this one is", "terrain; this one is"},
      {40, 48, "chunk", "chunk"},
      {48, 56, "hole block", "hole block"},  // the hole blocks' count (version 3)
      {56, 64, "checksum mismatch", "reserved header bytes"},
  };
  for (const Region& g : header)
    for (std::size_t at = g.from; at < g.to; ++at) {
      std::string c = bytes;
      c[at] = char(c[at] ^ 0x10);
      refused(c, g.stale, at);
      refused(reseal(c), g.resealed, at);
    }
  // The body: every chunk's indices and its first, a middle and its last value, and the checksum.
  for (std::size_t k = 0; k < t->surface().edited_chunks(); ++k) {
    const std::size_t base = 64 + k * chunk;
    for (std::size_t at = base; at < base + 8; ++at) {
      std::string c = bytes;
      c[at] = char(c[at] ^ 0x40);
      refused(c, "checksum mismatch", at);
      refused(reseal(c), "lies outside the terrain", at);  // 0x40 moves it off a 5 x 5 grid
    }
    for (std::size_t v : {std::size_t{0}, std::size_t{517}, std::size_t{1023}}) {
      const std::size_t at = base + 8 + 4 * v;
      std::string c = bytes;
      c[at + 1] = char(c[at + 1] ^ 0x01);
      refused(c, "checksum mismatch", at);
      for (float bad : {NAN, INFINITY, 3e5f}) {  // past the edit limits even when resealed
        std::memcpy(c.data() + at, &bad, 4);
        refused(reseal(c), "outside the edit limits", at);
      }
    }
  }
  for (std::size_t at = bytes.size() - 8; at < bytes.size(); ++at) {
    std::string c = bytes;
    c[at] = char(c[at] ^ 0x01);
    refused(c, "checksum mismatch", at);
  }
  // Chunks repeated or out of order (the second chunk's indices copied onto the first).
  {
    std::string c = bytes;
    std::memcpy(c.data() + 64, c.data() + 64 + chunk, 8);
    refused(reseal(c), "out of order or repeated", 64);
  }
  // Lengths: one byte short or long of what the chunk count says.
  refused(reseal(bytes.substr(0, bytes.size() - 1)), "truncated", bytes.size() - 1);
  refused(reseal(bytes + std::string(1, '\0')), "trailing bytes", bytes.size());
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
