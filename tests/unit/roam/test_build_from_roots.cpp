// The mesh built from the roots (roam/view/build_from_roots.cpp): the same mesh, front and buffers
// as the incremental splits make, and the rebuild a teleport or snap turn triggers.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>

#include "ridgeline/roam_view.h"
#include "roam_landscapes.h"

using namespace ridgeline;
using namespace ridgeline::test;

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
