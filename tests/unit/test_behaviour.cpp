// Behaviour of the tessellator and the change log through the public API only (Terrain,
// Landscape::create, RoamView, Terrain::changes_since): what an engine sees. Each test names the
// fault it guards against in its failure message; none reads a private class, so they hold
// whatever the storage and the view look like inside (docs/reliability/planted_faults.md, "Behaviour tests").
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <exception>
#include <random>
#include <string>
#include <vector>

#include "ridgeline/edit.h"
#include "ridgeline/roam_view.h"
#include "roam_test_util.h"

using namespace ridgeline;
using namespace ridgeline::test;

namespace {

std::shared_ptr<Terrain> noise_terrain(std::uint32_t n, std::uint32_t seed = 1337) {
  return Terrain::create(
      std::move(make_default_heightfield({.size = n, .spacing = 2.0, .seed = seed})).value())
      .value();
}

// 83 x 57 samples, 2 m apart (along z `spacing_z`), the first at `origin`: neither a power of
// two plus one nor square, so the last column and row of patches extend past the samples
// (padding that is not terrain).
std::shared_ptr<Terrain> padded_terrain(double spacing_z = 2.0, glm::dvec2 origin = {0, 0}) {
  HeightfieldDesc d;
  d.width = 83;
  d.height = 57;
  d.spacing_x = 2.0;
  d.spacing_z = spacing_z;
  d.origin_x = origin.x;
  d.origin_z = origin.y;
  std::vector<float> h(std::size_t(d.width) * d.height);
  for (std::uint32_t j = 0; j < d.height; ++j)
    for (std::uint32_t i = 0; i < d.width; ++i)
      h[i + j * d.width] = float(10 * std::sin(0.3 * i) * std::cos(0.21 * j) + 0.05 * i * j);
  return Terrain::create(Heightfield::create(d, h).value()).value();
}

// What an engine draws: every corner of every non-degenerate triangle, at its patch's origin plus
// its local position, must lie on the surface the queries see (within float rounding). Returns
// the corners checked; `off` receives how many were not on it (or off the terrain: drawn over
// the padding), `first` a description of the first.
struct DrawnCheck {
  std::size_t corners = 0, off = 0;
  std::string first;
};
DrawnCheck check_drawn_on_surface(const RoamView& view, const Terrain& terrain, double tol = 1e-3) {
  DrawnCheck c;
  for (std::uint32_t p = 0; p < view.landscape().patch_count(); ++p) {
    const PatchMesh& m = view.patch_mesh(p);
    for (std::size_t t = 0; t + 2 < m.indices.size(); t += 3) {
      if (m.indices[t] == m.indices[t + 1]) continue;  // unused or over the padding
      for (int q = 0; q < 3; ++q) {
        const MeshVertex& v = m.vertices[m.indices[t + q]];
        const double x = m.origin_x + v.x, z = m.origin_z + v.z, y = m.origin_y + v.y;
        const std::optional<double> h = terrain.height(x, z);
        ++c.corners;
        if (h && std::abs(*h - y) <= tol) continue;
        if (c.off++ == 0)
          c.first = "patch " + std::to_string(p) + " corner at (" + std::to_string(x) + ", " +
                    std::to_string(z) + "): drawn at " + std::to_string(y) + " m, surface " +
                    (h ? std::to_string(*h) + " m" : std::string("off the terrain"));
      }
    }
  }
  return c;
}

// The mesh a fresh landscape and view over an independent copy of `terrain` build for the same
// camera and settings: what an incremental view must equal once converged.
std::uint64_t fresh_mesh_hash(const Terrain& terrain, std::uint32_t patch_exponent,
                              const RoamSettings& settings, const Camera& camera) {
  auto land = Landscape::create(terrain.clone(), {.patch_exponent = patch_exponent}).value();
  auto view = RoamView::create(land, settings).value();
  EXPECT_TRUE(view->update(camera));
  return view->mesh_hash();
}

// `edits` random raises and craters of 3-9 m radius over a square terrain of `extent` metres.
std::vector<Edit> random_edits(std::size_t count, double extent, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, extent), r(3, 9), d(0.5, 2.5);
  std::vector<Edit> out;
  for (std::size_t k = 0; k < count; ++k) {
    Edit e;
    e.brush = k % 3 == 0 ? Brush::kCrater : Brush::kRaise;
    e.x = u(rng);
    e.z = u(rng);
    e.radius = r(rng);
    e.depth = d(rng);
    out.push_back(e);
  }
  return out;
}

}  // namespace

// ---- output compaction over the padding ------------------------------------------------------

// A patch whose buffers hold far more slots than live triangles is compacted (its slots
// renumbered). Triangles over the padding are drawn degenerate and keep their corners aside;
// compaction must carry those corners to the triangle's new slot. On a padded field, with the
// camera diving, climbing and diving again at a fine threshold (many patches fill and empty),
// every update must succeed, the mesh stay consistent, every drawn corner lie on the surface,
// and the converged mesh equal a fresh view's.
TEST(Behaviour, CompactionOnAPaddedFieldKeepsTheTrianglesOverThePadding) {
  auto terrain = padded_terrain();
  const std::uint32_t k = 4;  // 16-cell patches: 6 x 4 patches, the last column and row padded
  auto land = Landscape::create(terrain, {.patch_exponent = k}).value();
  const RoamSettings settings{.threshold = 0.3};
  auto view = RoamView::create(land, settings).value();
  std::uint32_t compacted = 0;
  Camera cam;
  for (int frame = 0; frame < 90; ++frame) {
    // Down from 120 m to 3 m over the field, up again, and down again, moving across it.
    const int leg = frame / 30, f = frame % 30;
    const double s = f / 29.0, down = leg == 1 ? s : 1.0 - s;
    const double x = 10 + 140 * (frame / 89.0), z = 10 + 90 * std::abs(std::sin(frame * 0.07));
    const glm::dvec3 eye(x, 3 + 117 * down, z);
    cam = camera_at(eye, eye + glm::dvec3(8, -3, 5));
    // An exception out of the view (a lost slot in a lookup) is reported as such.
    std::string what;
    try {
      auto st = view->update(cam);
      ASSERT_TRUE(st) << st.error().message;
      compacted += st->compacted_patches;
      what = view->check_invariants();
    } catch (const std::exception& e) {
      what = std::string("threw '") + e.what() + "'";
    }
    ASSERT_EQ(what, "") << "frame " << frame << " after " << compacted
                        << " patch compactions: compaction lost or mixed up the corners of a "
                           "triangle over the padding";
    const DrawnCheck drawn = check_drawn_on_surface(*view, *terrain);
    ASSERT_EQ(drawn.off, 0u) << "frame " << frame << ": " << drawn.off << " of " << drawn.corners
                             << " drawn corners are not on the surface, first " << drawn.first;
  }
  EXPECT_GT(compacted, 20u) << "the flight must empty the patches the dives filled";
  EXPECT_EQ(view->mesh_hash(), fresh_mesh_hash(*terrain, k, settings, cam))
      << "after the flight the mesh differs from a fresh view's";
}

// ---- output over unequal spacings ------------------------------------------------------------

// Cells 2 m along x and 0.75 m along z, placed away from the origin: every corner a view draws
// lies on the surface the queries see (each axis of the output takes its own spacing).
TEST(Behaviour, AViewOverUnequalSpacingsDrawsOnTheSurface) {
  auto terrain = padded_terrain(0.75, {-40, 300});
  auto land = Landscape::create(terrain, {.patch_exponent = 4}).value();
  auto view = RoamView::create(land, {.threshold = 0.5}).value();
  ASSERT_TRUE(view->update(camera_at({0, 30, 310}, {60, 0, 330})));
  EXPECT_EQ(view->check_invariants(), "") << "the mesh over cells 2 m x 0.75 m is inconsistent";
  const DrawnCheck drawn = check_drawn_on_surface(*view, *terrain);
  EXPECT_GT(drawn.corners, 1000u);
  EXPECT_EQ(drawn.off, 0u) << drawn.off << " of " << drawn.corners
                           << " drawn corners are not on the surface (cells 2 m x 0.75 m), first "
                           << drawn.first;
}

// ---- a triangle cap while the camera climbs ----------------------------------------------------

// Under a triangle cap the view searches the threshold that fills the cap, starting from where
// the last update ended. When the camera climbs, fewer triangles are needed at that threshold:
// the next start must come down, or the mesh falls ever further below the cap while the
// threshold stays high. Every update after the first few must use most of the cap, and its mesh
// must be the one a fresh view builds at the threshold it reports.
TEST(Behaviour, TriangleCapStaysFilledWhileTheCameraClimbs) {
  auto terrain = noise_terrain(257);
  const std::uint32_t k = 5, cap = 6000;
  auto land = Landscape::create(terrain, {.patch_exponent = k}).value();
  auto view = RoamView::create(land, {.threshold = 0.0, .max_triangles = cap}).value();
  // Looking north-east and down over the field, rising 8 m an update: the same view from ever
  // higher up needs fewer triangles at any one threshold.
  Camera cam = camera_at({10, 150, 10}, {200, 50, 200});
  double first_threshold = 0, last_threshold = 0;
  for (int u = 0; u < 40; ++u) {
    cam.eye.y += 8;
    cam.target.y += 8;
    auto st = view->update(cam);
    ASSERT_TRUE(st);
    ASSERT_LE(st->triangles, cap) << "update " << u;
    if (u == 0) first_threshold = st->morph_threshold;
    last_threshold = st->morph_threshold;
    if (u < 2) continue;  // the search settles
    EXPECT_GT(st->triangles, 0.9 * cap)
        << "update " << u << " (eye at " << cam.eye.y << " m): the mesh fell to " << st->triangles
        << " triangles at " << st->morph_threshold << " px under a cap of " << cap
        << ": the threshold did not come down as the camera climbed";
    EXPECT_EQ(st->stop, StopReason::kTriangleBudget) << "update " << u;
    if (u % 6 == 0) {
      RoamSettings fresh{.threshold = st->morph_threshold};
      EXPECT_EQ(view->mesh_hash(), fresh_mesh_hash(*terrain, k, fresh, cam))
          << "update " << u << ": the mesh is not the converged mesh of the threshold it reports ("
          << st->morph_threshold << " px)";
    }
  }
  EXPECT_LT(last_threshold, 0.8 * first_threshold)
      << "climbing from 158 m to 470 m the cap's threshold went from " << first_threshold
      << " px only to " << last_threshold << " px";
}

// ---- the change log past its capacity ----------------------------------------------------------

// More edits than the log holds: the oldest are merged into one entry whose vertex range must
// cover every vertex any of them moved. A consumer that keeps its own copy of the heights (what a
// physics engine's collider does) and refreshes it over the ranges it pulls must end equal to
// the terrain, whether it asks from the start, from somewhere in the merged part, or from within
// the log.
TEST(Behaviour, ATrimmedChangeCoversEveryVertexTheMergedEditsMoved) {
  auto terrain = noise_terrain(129);
  const std::int64_t n = 129;
  auto sample_height = [&](const Terrain& t, std::int64_t i, std::int64_t j) {
    return *t.height(2.0 * double(i), 2.0 * double(j));
  };
  const std::vector<Edit> edits = random_edits(kChangeLogCapacity + 50, 256.0, 11);
  // Consumers that last saw versions 0, 30 and (within the log) edits.size() - 100.
  const std::uint64_t since[] = {0, 30, edits.size() - 100};
  std::vector<std::vector<double>> copies;
  for (std::size_t e = 0; e < edits.size(); ++e) {
    for (const std::uint64_t s : since)
      if (terrain->edit_version() == s) {
        copies.emplace_back();
        for (std::int64_t j = 0; j < n; ++j)
          for (std::int64_t i = 0; i < n; ++i)
            copies.back().push_back(sample_height(*terrain, i, j));
      }
    ASSERT_TRUE(terrain->apply_edit(edits[e]));
  }
  ASSERT_EQ(copies.size(), 3u);
  for (std::size_t c = 0; c < copies.size(); ++c) {
    const TerrainChanges pulled = terrain->changes_since(since[c]);
    EXPECT_EQ(pulled.trimmed, c < 2) << "consumer since version " << since[c];
    ASSERT_FALSE(pulled.empty());
    for (const TerrainChange& ch : pulled.changes)
      for (std::int64_t j = std::max<std::int64_t>(ch.vertices.j0, 0);
           j <= std::min(ch.vertices.j1, n - 1); ++j)
        for (std::int64_t i = std::max<std::int64_t>(ch.vertices.i0, 0);
             i <= std::min(ch.vertices.i1, n - 1); ++i)
          copies[c][std::size_t(i + j * n)] = sample_height(*terrain, i, j);
    std::size_t stale = 0;
    std::string first;
    for (std::int64_t j = 0; j < n; ++j)
      for (std::int64_t i = 0; i < n; ++i)
        if (copies[c][std::size_t(i + j * n)] != sample_height(*terrain, i, j) && stale++ == 0)
          first = std::to_string(i) + ", " + std::to_string(j);
    EXPECT_EQ(stale, 0u) << "consumer since version " << since[c] << ": " << stale
                         << " vertices moved outside the ranges changes_since() returned (first at "
                         << first << "; " << pulled.changes.size() << " entries, trimmed "
                         << pulled.trimmed << ", first range i " << pulled.changes[0].vertices.i0
                         << ".." << pulled.changes[0].vertices.i1 << ", j "
                         << pulled.changes[0].vertices.j0 << ".." << pulled.changes[0].vertices.j1
                         << ")";
  }
}

// A view whose landscape is more edits behind than the terrain's log holds pulls the merged
// change: its bounds and mesh must come out as a fresh landscape and view over a copy of the
// edited terrain build them, every drawn corner on the edited surface.
TEST(Behaviour, AViewThatPullsAMergedChangeEqualsAFreshView) {
  auto terrain = noise_terrain(129);
  const std::uint32_t k = 4;
  auto land = Landscape::create(terrain, {.patch_exponent = k}).value();
  const RoamSettings settings{.threshold = 1.0};
  auto view = RoamView::create(land, settings).value();
  const Camera cam = camera_at({-20, 90, -30}, {128, 0, 128});
  ASSERT_TRUE(view->update(cam));
  for (const Edit& e : random_edits(1074, 256.0, 5)) ASSERT_TRUE(terrain->apply_edit(e));
  ASSERT_GT(terrain->edit_version(), kChangeLogCapacity);
  ASSERT_TRUE(terrain->changes_since(0).trimmed);
  ASSERT_TRUE(view->update(cam));
  EXPECT_EQ(view->check_invariants(), "") << "the mesh over cells 2 m x 0.75 m is inconsistent";
  const DrawnCheck drawn = check_drawn_on_surface(*view, *terrain);
  EXPECT_GT(drawn.corners, 1000u);
  EXPECT_EQ(drawn.off, 0u) << drawn.off << " of " << drawn.corners
                           << " drawn corners are not on the edited surface after pulling a "
                              "merged change, first "
                           << drawn.first;
  EXPECT_EQ(view->mesh_hash(), fresh_mesh_hash(*terrain, k, settings, cam))
      << "the mesh after pulling a merged change differs from a fresh view's (stale bounds)";
}

// Two views over one landscape: one updated after every edit (so the landscape's own log of
// regions fills and drops its oldest entries), the other only after 1,100 edits. The lagging
// view asks for changes older than the log still holds; it must be told so (the whole landscape
// changed) rather than get the recent entries alone, and end on the surface and equal to a fresh
// view.
TEST(Behaviour, AViewFallingBehindTheLandscapesLogCatchesUp) {
  auto terrain = noise_terrain(257, 3);
  const std::uint32_t k = 5;
  auto land = Landscape::create(terrain, {.patch_exponent = k}).value();
  const RoamSettings settings{.threshold = 1.0};
  auto eager = RoamView::create(land, settings).value();
  auto lagging = RoamView::create(land, settings).value();
  const Camera cam = camera_at({-30, 160, -30}, {256, 0, 256});
  ASSERT_TRUE(eager->update(cam));
  ASSERT_TRUE(lagging->update(cam));
  // The first 100 edits on the western half (near the camera), the next 1,000 on the eastern
  // half: what the oldest edits changed is not changed again.
  std::vector<Edit> edits = random_edits(1100, 256.0, 17);
  for (std::size_t e = 100; e < edits.size(); ++e) edits[e].x += 256.0;
  for (const Edit& e : edits) {
    ASSERT_TRUE(terrain->apply_edit(e));
    ASSERT_TRUE(eager->update(cam));
  }
  ASSERT_TRUE(lagging->update(cam));
  ASSERT_EQ(lagging->check_invariants(), "");
  const DrawnCheck drawn = check_drawn_on_surface(*lagging, *terrain);
  EXPECT_GT(drawn.corners, 10000u);
  EXPECT_EQ(drawn.off, 0u) << drawn.off << " of " << drawn.corners
                           << " drawn corners of the view that fell behind the landscape's log "
                              "are not on the surface, first "
                           << drawn.first;
  const std::uint64_t fresh = fresh_mesh_hash(*terrain, k, settings, cam);
  EXPECT_EQ(lagging->mesh_hash(), fresh) << "the view that fell behind differs from a fresh view";
  EXPECT_EQ(eager->mesh_hash(), fresh)
      << "the view updated after every edit differs from a fresh view";
  EXPECT_EQ(check_drawn_on_surface(*eager, *terrain).off, 0u);
}
