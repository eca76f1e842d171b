// Behaviour across the borders of the terrain's pages (256 x 256 cells, each with a six-sample
// apron of its neighbours' samples) and at the far edges, through the public API only
// (docs/reliability/planted_faults.md): batched queries, edits near a page border, the bounds
// an edit remakes on the far edge, the box an edit reports, and undoing edits by loading an
// earlier save. Each failure message names what went wrong.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <glm/geometric.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "ridgeline/edit.h"
#include "ridgeline/roam_view.h"
#include "roam_test_util.h"

using namespace ridgeline;
using namespace ridgeline::test;

namespace {

// The terrains here: `w` x `h` samples 1 m apart from the origin, height offset 0.
HeightfieldDesc unit_grid(std::uint32_t w, std::uint32_t h) {
  HeightfieldDesc d;
  d.width = w;
  d.height = h;
  d.spacing_x = d.spacing_z = 1.0;
  return d;
}

// A rolling surface with a rough ripple (float heights, not 16-bit values); with `relief` 0 a
// plane.
Heightfield wavy(std::uint32_t w, std::uint32_t h, double relief = 1.0) {
  std::vector<float> v(std::size_t(w) * h);
  for (std::uint32_t j = 0; j < h; ++j)
    for (std::uint32_t i = 0; i < w; ++i)
      v[i + std::size_t(j) * w] =
          float(relief * (6 * std::sin(0.045 * i + 0.3) * std::cos(0.037 * j) +
                          0.4 * std::sin(0.9 * i + 1.3 * j)) +
                0.013 * i);
  return Heightfield::create(unit_grid(w, h), v).value();
}

std::shared_ptr<Terrain> wavy_terrain(std::uint32_t w, std::uint32_t h, double relief = 1.0) {
  return Terrain::create(wavy(w, h, relief)).value();
}

std::vector<float> stored_heights(const Terrain& t) {
  const WorldInfo& w = t.info();
  std::vector<float> v(std::size_t(w.width) * w.height);
  EXPECT_TRUE(t.get_heights(0, 0, w.width, w.height, v, w.width));
  return v;
}

// A terrain made afresh from the stored heights of `t` (one of the terrains here): what every
// incremental structure of `t` must equal after edits.
std::shared_ptr<Terrain> rebuilt(const Terrain& t) {
  const WorldInfo& w = t.info();
  return Terrain::create(
             Heightfield::create(unit_grid(w.width, w.height), stored_heights(t)).value())
      .value();
}

// Points in the order a batch walks them: along rows `rows` forwards over the whole width and
// back, along columns `cols` down and up, then pairs 262 and 263 samples apart (the edge of a
// page's window of entries and one past it), all at the same fraction of a cell.
std::vector<glm::dvec2> walk(const WorldInfo& w, const std::vector<std::uint32_t>& rows,
                             const std::vector<std::uint32_t>& cols) {
  std::vector<glm::dvec2> p;
  const double f = 0.37, g = 0.61;
  for (std::uint32_t j : rows) {
    for (std::uint32_t i = 0; i + 1 < w.width; ++i) p.push_back({i + f, j + g});
    for (std::uint32_t i = w.width - 1; i-- > 0;) p.push_back({i + f, j + g});
  }
  for (std::uint32_t i : cols) {
    for (std::uint32_t j = 0; j + 1 < w.height; ++j) p.push_back({i + f, j + g});
    for (std::uint32_t j = w.height - 1; j-- > 0;) p.push_back({i + f, j + g});
  }
  for (std::uint32_t j : rows)
    for (std::uint32_t i = 0; i + 264 < w.width; i += 7) {
      p.push_back({i + f, j + g});
      p.push_back({i + 262 + f, j + g});
      p.push_back({i + f, j + g});
      p.push_back({i + 263 + f, j + g});
    }
  return p;
}

// "" when the batch answers every point as the single query does, else the count and the first.
std::string batch_differs(const Terrain& t, const std::vector<glm::dvec2>& pts) {
  std::vector<double> out(pts.size());
  t.heights(pts, out);
  std::size_t bad = 0;
  std::ostringstream first;
  for (std::size_t k = 0; k < pts.size(); ++k) {
    const double single = t.height(pts[k].x, pts[k].y).value_or(NAN);
    if (out[k] == single) continue;
    if (bad++ == 0)
      first << "point " << k << " (" << pts[k].x << ", " << pts[k].y << "): batch " << out[k]
            << " m, single query " << single << " m";
  }
  if (bad == 0) return "";
  return std::to_string(bad) + " of " + std::to_string(pts.size()) + " batched heights differ, " +
         first.str();
}

}  // namespace

// A batch keeps the page it read last and reads the next point from it while the point's
// samples lie in that page's entries (its cells and apron): one past the window is another
// page. On a 700 x 600 terrain (3 x 3 pages) every batched height equals the single query.
TEST(Behaviour, BatchedHeightsAcrossPageBordersEqualSingleQueries) {
  auto t = wavy_terrain(700, 600);
  const auto pts =
      walk(t->info(), {0, 5, 255, 256, 257, 300, 511, 512, 598}, {0, 255, 256, 263, 520});
  EXPECT_EQ(batch_differs(*t, pts), "")
      << "a batch read a point's samples from the wrong page (its page window is off)";
}

// An edit near a page border changes samples held by the neighbouring page too (its apron):
// afterwards the batched heights, the smooth normals and the mesh of a view must equal those of
// a terrain made afresh from the edited heights.
TEST(Behaviour, AnEditNearAPageBorderReachesTheNeighboursApron) {
  auto t = wavy_terrain(700, 600);
  // Samples 249..257 of x (page 1's apron holds 250..255), 505..513 of z, and a corner.
  const Edit edits[] = {{.brush = Brush::kRaise, .x = 253, .z = 100, .radius = 4, .depth = 3},
                        {.brush = Brush::kCrater, .x = 100, .z = 509, .radius = 4, .depth = 2},
                        {.brush = Brush::kLower, .x = 514, .z = 516, .radius = 5, .depth = 4}};
  for (const Edit& e : edits) ASSERT_TRUE(t->apply_edit(e));
  auto fresh = rebuilt(*t);
  EXPECT_EQ(batch_differs(*t, walk(t->info(), {98, 100, 102, 507, 509, 514}, {253, 100, 514})), "")
      << "the neighbouring page's apron kept the heights from before the edit";
  std::size_t bad = 0;
  std::string first;
  for (double z = 90; z < 525; z += 0.5)
    for (double x : {247.25, 250.5, 253.0, 255.75, 256.25, 258.5, 505.5, 512.0, 513.5, 517.0}) {
      for (const glm::dvec2 q : {glm::dvec2(x, z), glm::dvec2(z, x)}) {
        const glm::vec3 a = t->smooth_normal(q.x, q.y).value(),
                        b = fresh->smooth_normal(q.x, q.y).value();
        if (glm::length(a - b) <= 1e-5f) continue;
        if (bad++ == 0)
          first = "at (" + std::to_string(q.x) + ", " + std::to_string(q.y) + "): normal y " +
                  std::to_string(a.y) + ", afresh " + std::to_string(b.y);
      }
    }
  EXPECT_EQ(bad, 0u) << "smooth normals near the edited page borders differ from a terrain made "
                        "afresh, first "
                     << first;
  const RoamSettings settings{.threshold = 0.25};
  for (const glm::dvec3 eye :
       {glm::dvec3(240, 25, 90), glm::dvec3(90, 25, 500), glm::dvec3(500, 25, 500)}) {
    const Camera cam = camera_at(eye, eye + glm::dvec3(14, -20, 12));
    auto v1 = RoamView::create(Landscape::create(t, {}).value(), settings).value();
    auto v2 = RoamView::create(Landscape::create(fresh, {}).value(), settings).value();
    ASSERT_TRUE(v1->update(cam));
    ASSERT_TRUE(v2->update(cam));
    EXPECT_EQ(v1->mesh_hash(), v2->mesh_hash())
        << "looking from (" << eye.x << ", " << eye.z
        << "): the mesh over the edited terrain is not "
        << "the mesh over the same heights made afresh (the bounds near the page border are stale)";
  }
}

// An edit of samples on a page border alone (x = 256: the first column of page 1 and the last
// of page 0) changes the bounds page 0 holds for its diamonds beside the border: a view
// after the edit draws what a view over the same heights made afresh draws. On a plane (every
// bound 0 before the edit) a bound left as it was keeps the view from refining the peak.
TEST(Behaviour, AnEditOnAPageBorderRemakesTheBoundsOfThePageBeforeIt) {
  auto t = wavy_terrain(700, 300, 0.0);
  auto land = Landscape::create(t, {}).value();
  const RoamSettings settings{.threshold = 0.5};
  auto view = RoamView::create(land, settings).value();
  const Camera cam = camera_at({246, 12, 90}, {256, 0, 102});
  ASSERT_TRUE(view->update(cam));
  // A peak on column 256 alone (rows 100..104): the diamonds of page 0 whose squares end on
  // that column no longer lie on their planes.
  std::vector<float> peak(5);
  ASSERT_TRUE(t->get_heights(256, 100, 1, 5, peak, 1));
  for (int k = 0; k < 5; ++k) peak[std::size_t(k)] += float(3.0 - 1.2 * std::abs(k - 2));
  ASSERT_TRUE(t->set_heights(256, 100, 1, 5, peak, 1));
  ASSERT_TRUE(view->update(cam));
  auto fresh = rebuilt(*t);
  auto v2 = RoamView::create(Landscape::create(fresh, {}).value(), settings).value();
  ASSERT_TRUE(v2->update(cam));
  EXPECT_EQ(view->mesh_hash(), v2->mesh_hash())
      << "after an edit of column 256 the view does not draw the mesh of the same heights "
         "made afresh ("
      << view->triangle_count() << " triangles, afresh " << v2->triangle_count()
      << "): page 0's bounds beside the border were not remade";
}

// The box an edit reports holds every point whose height it changed, with both heights.
TEST(Behaviour, AnEditsChangeBoxHoldsEveryPointItMoved) {
  auto t = wavy_terrain(120, 90);
  std::vector<glm::dvec2> grid;
  for (double z = 0; z <= 89; z += 0.25)
    for (double x = 0; x <= 119; x += 0.25) grid.push_back({x, z});
  std::vector<double> before(grid.size()), after(grid.size());
  const Edit edits[] = {{.brush = Brush::kCrater, .x = 40.3, .z = 50.6, .radius = 6, .depth = 3},
                        {.brush = Brush::kRaise, .x = 117, .z = 87, .radius = 5, .depth = 2},
                        {.brush = Brush::kSmooth, .x = 2, .z = 3, .radius = 4, .strength = 1}};
  for (const Edit& e : edits) {
    t->heights(grid, before);
    auto r = t->apply_edit(e);
    ASSERT_TRUE(r) << r.error().message;
    ASSERT_GT(r->samples_changed, 0u);
    t->heights(grid, after);
    const Box& b = r->changed;
    std::size_t outside = 0, moved = 0;
    std::string first;
    for (std::size_t k = 0; k < grid.size(); ++k) {
      if (before[k] == after[k]) continue;
      ++moved;
      const glm::dvec2 q = grid[k];
      const double lo = std::min(before[k], after[k]), hi = std::max(before[k], after[k]);
      if (q.x >= b.min.x && q.x <= b.max.x && q.y >= b.min.z && q.y <= b.max.z &&
          lo >= b.min.y - 1e-4 && hi <= b.max.y + 1e-4)
        continue;
      if (outside++ == 0)
        first = "(" + std::to_string(q.x) + ", " + std::to_string(q.y) + ") moved from " +
                std::to_string(before[k]) + " to " + std::to_string(after[k]) + " m";
    }
    EXPECT_GT(moved, 0u);
    EXPECT_EQ(outside, 0u) << brush_name(e.brush) << " at (" << e.x << ", " << e.z
                           << "): " << outside << " of " << moved
                           << " moved points lie outside the box "
                           << "x " << b.min.x << ".." << b.max.x << ", z " << b.min.z << ".."
                           << b.max.z << ", y " << b.min.y << ".." << b.max.y << "; first "
                           << first;
  }
}

// Loading a save made before any edit undoes every edit, set_heights included, back to the
// original heights bit for bit; loading the later save onto a fresh terrain gives the edited
// heights. The terrain is 70 x 45 samples: its last chunk of 32 x 32 is partly outside it.
TEST(Behaviour, LoadingAnEarlierSaveUndoesEveryEditExactly) {
  auto t = wavy_terrain(70, 45);
  const std::vector<float> original = stored_heights(*t);
  const std::string pristine = save_edits_to_memory(*t);
  ASSERT_TRUE(
      t->apply_edit({.brush = Brush::kCrater, .x = 68.5, .z = 43.5, .radius = 4, .depth = 2}));
  const std::vector<float> block(5 * 4, 50.0f);
  ASSERT_TRUE(t->set_heights(3, 3, 5, 4, block, 5));
  const std::vector<float> edited = stored_heights(*t);
  const std::string saved = save_edits_to_memory(*t);
  auto first_difference = [&](const std::vector<float>& got, const std::vector<float>& want) {
    for (std::size_t k = 0; k < want.size(); ++k)
      if (got[k] != want[k])
        return "sample (" + std::to_string(k % 70) + ", " + std::to_string(k / 70) + ") is " +
               std::to_string(got[k]) + " m, should be " + std::to_string(want[k]) + " m";
    return std::string();
  };
  ASSERT_TRUE(load_edits_from_memory(*t, pristine));
  EXPECT_EQ(first_difference(stored_heights(*t), original), "")
      << "loading the save made before the edits did not restore the original heights (the "
         "edit layer lacks the original of an edited sample)";
  auto other = wavy_terrain(70, 45);
  ASSERT_TRUE(load_edits_from_memory(*other, saved));
  EXPECT_EQ(first_difference(stored_heights(*other), edited), "")
      << "the saved edits loaded onto a fresh terrain do not give the edited heights";
}
