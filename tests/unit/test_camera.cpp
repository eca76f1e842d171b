// Camera validation and the one Frustum every culling and measurement path uses.
#include <gtest/gtest.h>

#include <cmath>
#include <glm/geometric.hpp>

#include "ridgeline/camera.h"

namespace ridgeline {
namespace {

Camera looking_down_x() {
  Camera c;
  c.eye = {0, 0, 0};
  c.target = {10, 0, 0};
  c.fov_y_deg = 90;         // tan_v = 1
  c.viewport = {200, 100};  // tan_h = 2
  c.far_m = 100;
  return c;
}

TEST(Frustum, ContainsPointsInsideTheSidePlanesAndFar) {
  const Frustum f(looking_down_x());
  EXPECT_NEAR(f.tan_v, 1.0, 1e-12);
  EXPECT_NEAR(f.tan_h, 2.0, 1e-12);
  double d = 0;
  EXPECT_TRUE(f.contains({10, 9.9, 0}, &d));  // just below the top plane (y = x)
  EXPECT_NEAR(d, std::sqrt(100 + 9.9 * 9.9), 1e-12);
  EXPECT_FALSE(f.contains({10, 10.1, 0}));  // just above it
  EXPECT_TRUE(f.contains({10, 0, 19.9}));   // inside the wider horizontal half-angle
  EXPECT_FALSE(f.contains({10, 0, 20.1}));
  EXPECT_FALSE(f.contains({-1, 0, 0}));  // behind the eye
  EXPECT_TRUE(f.contains({99.9, 0, 0}));
  EXPECT_FALSE(f.contains({100.1, 0, 0}));  // beyond far
  // Borders count as inside.
  EXPECT_TRUE(f.contains({10, 10 * f.tan_v, 0}));
}

TEST(Frustum, PlanesAreUnitAndInward) {
  const Frustum f(looking_down_x());
  for (const glm::dvec3& n : f.planes) {
    EXPECT_NEAR(glm::length(n), 1.0, 1e-12);
    EXPECT_GT(glm::dot(n, f.forward), 0.0);  // a point straight ahead is inside every plane
  }
}

TEST(Frustum, ClassifiesBoxesConservatively) {
  const Frustum f(looking_down_x());
  using C = Frustum::Cull;
  EXPECT_EQ(f.classify_box({9, -1, -1}, {11, 1, 1}), C::kIn);
  EXPECT_EQ(f.classify_box({9, 8, -1}, {11, 12, 1}), C::kPartial);  // straddles the top plane
  EXPECT_EQ(f.classify_box({9, 12, -1}, {11, 14, 1}), C::kOut);     // wholly above it
  EXPECT_EQ(f.classify_box({-5, -1, -1}, {-2, 1, 1}), C::kOut);     // behind the eye
  EXPECT_EQ(f.classify_box({-1, -1, -1}, {1, 1, 1}), C::kPartial);  // holds the eye
  EXPECT_EQ(f.classify_box({150, -1, -1}, {160, 1, 1}), C::kOut);   // beyond far
  EXPECT_EQ(f.classify_box({95, -1, -1}, {105, 1, 1}), C::kPartial);
  // Every box holding a contained point is not out (sampled).
  for (int k = 0; k < 2000; ++k) {
    const double x = (k * 37 % 211) - 50.0, y = (k * 53 % 97) - 48.0, z = (k * 71 % 151) - 75.0;
    if (!f.contains({x, y, z})) continue;
    EXPECT_NE(f.classify_box({x - 0.5, y - 0.5, z - 0.5}, {x + 0.5, y + 0.5, z + 0.5}), C::kOut);
    EXPECT_NE(f.classify_sphere({x + 0.3, y, z}, 0.31), C::kOut);
  }
}

TEST(Frustum, ClassifiesSpheres) {
  const Frustum f(looking_down_x());
  using C = Frustum::Cull;
  EXPECT_EQ(f.classify_sphere({10, 0, 0}, 1), C::kIn);
  EXPECT_EQ(f.classify_sphere({10, 10, 0}, 1), C::kPartial);
  EXPECT_EQ(f.classify_sphere({10, 13, 0}, 1), C::kOut);  // 3/sqrt(2) = 2.1 m above the plane
  EXPECT_EQ(f.classify_sphere({-3, 0, 0}, 2), C::kOut);
  EXPECT_EQ(f.classify_sphere({102, 0, 0}, 1), C::kOut);
  EXPECT_EQ(f.classify_sphere({100, 0, 0}, 1), C::kPartial);
}

TEST(Frustum, FarFromTheOriginKeepsItsPrecision) {
  Camera c = looking_down_x();
  c.eye = {1e7, 200, -1e7};
  c.target = c.eye + glm::dvec3(10, 0, 0);
  const Frustum f(c);
  EXPECT_TRUE(f.contains(c.eye + glm::dvec3(10, 9.9, 0)));
  EXPECT_FALSE(f.contains(c.eye + glm::dvec3(10, 10.1, 0)));
}

TEST(Camera, ValidationNamesTheProblem) {
  Camera c;
  c.fov_y_deg = 180;
  EXPECT_NE(validate_camera(c).message().find("fov_y"), std::string::npos);
  c = Camera{};
  c.target = c.eye;
  EXPECT_NE(validate_camera(c).message().find("same point"), std::string::npos);
  c = Camera{};
  c.eye.x = NAN;
  EXPECT_FALSE(validate_camera(c));
  EXPECT_TRUE(validate_camera(Camera{}));
}

}  // namespace
}  // namespace ridgeline
