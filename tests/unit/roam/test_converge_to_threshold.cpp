// An unbudgeted update (roam/view/converge_to_threshold.cpp): converged meshes meet the threshold,
// and the mesh a threshold asks for is unique whatever the camera's history.
#include <gtest/gtest.h>

#include <cmath>

#include "ridgeline/roam_view.h"
#include "roam_landscapes.h"

using namespace ridgeline;
using namespace ridgeline::test;

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
