// RoamView's public calls (roam/view/roam_view.cpp): bad settings and cameras refused, views over
// one landscape independent, also on different threads.
#include <gtest/gtest.h>

#include <cmath>
#include <thread>

#include "ridgeline/roam_view.h"
#include "roam_landscapes.h"

using namespace ridgeline;
using namespace ridgeline::test;

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
