// The shared scenes (module/scenes/ridgeline/scenes.h): the noise field and its circle path equal
// the peers' definition (reference values taken from the output of the peers' own generator, a
// separate Python program: the FNV-1a hash of every sample, a few samples, exact path doubles),
// the synthetic shapes are what the report describes, and bad sizes are refused by name.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

#include "ridgeline/scenes.h"

namespace ridgeline::scenes {
namespace {

TEST(ScenesNoise, SamplesEqualThePeersGeneratorOutput) {
  const std::vector<std::uint16_t> v = noise_samples();
  ASSERT_EQ(v.size(), std::size_t(kNoiseSize) * kNoiseSize);
  std::uint64_t h = 0xcbf29ce484222325ull;  // FNV-1a over the samples, low byte first
  for (std::uint16_t s : v)
    for (std::uint8_t b : {std::uint8_t(s & 0xff), std::uint8_t(s >> 8)}) {
      h ^= b;
      h *= 0x100000001b3ull;
    }
  EXPECT_EQ(h, 0x39e3f401b34bf10aull);
  EXPECT_EQ(v[0], 21046);
  EXPECT_EQ(v[1], 20984);
  EXPECT_EQ(v[1025 * 512 + 512], 50287);
  EXPECT_EQ(v.back(), 38778);
  EXPECT_EQ(*std::min_element(v.begin(), v.end()), 6189);
  EXPECT_EQ(*std::max_element(v.begin(), v.end()), 59071);
  EXPECT_EQ(std::accumulate(v.begin(), v.end(), std::uint64_t{0}), 33523782149ull);
}

TEST(ScenesNoise, FieldIsPlacedAsTheFlagsSay) {
  auto hf = noise_field();
  ASSERT_TRUE(hf.ok()) << hf.error().message;
  EXPECT_EQ(hf->width(), 1025u);
  EXPECT_EQ(hf->spacing_x(), 1.0);
  EXPECT_NEAR(hf->world(0, 0), 21046 * 0.005, 1e-4);
  EXPECT_NEAR(hf->height_offset() + hf->max_local(), 295.355, 1e-3);
  EXPECT_NEAR(hf->height_offset() + hf->min_local(), 30.945, 1e-3);
}

TEST(ScenesNoise, CirclePathEqualsThePeersPathExactly) {
  const std::vector<Camera> p = noise_circle();
  ASSERT_EQ(p.size(), 360u);
  EXPECT_EQ(p[0].eye, glm::dvec3(812.0, 320.355, 512.0));
  EXPECT_EQ(p[0].target, glm::dvec3(812.0, 320.01210219254455, 512.9393727128473));
  EXPECT_EQ(p[137].eye, glm::dvec3(292.5938895142489, 320.355, 716.5995080187496));
  EXPECT_EQ(p[137].target, glm::dvec3(291.9532388645995, 320.01210219254455, 715.9124943080086));
  for (const Camera& c : p) {
    EXPECT_EQ(c.fov_y_deg, 90.0);
    EXPECT_EQ(c.viewport, glm::ivec2(1024, 1024));
    EXPECT_TRUE(validate_camera(c).ok());
    EXPECT_NEAR(std::hypot(c.eye.x - 512, c.eye.z - 512), 300.0, 1e-9);
  }
}

TEST(ScenesShapes, AreWhatTheReportDescribes) {
  auto flat = shaped(Shape::kFlat, 33, 2.0, 100.0, "flat");
  ASSERT_TRUE(flat.ok());
  EXPECT_EQ(flat->max_local(), 0.0f);
  EXPECT_EQ(flat->origin_x(), 100.0);
  EXPECT_EQ(flat->spacing_z(), 2.0);
  auto cliff = shaped(Shape::kCliff, 65, 4.0);
  ASSERT_TRUE(cliff.ok());
  EXPECT_GT(cliff->local(40, 10) - cliff->local(20, 10), 900.0f);   // the 1,000 m step at i = 32
  EXPECT_NEAR(shape_height(Shape::kHills, 65, 0, 0), 100.0, 1e-9);  // sin(0) terms vanish
  EXPECT_NEAR(shape_height(Shape::kCliff, 65, 32, 0),
              1000.0 + 0.05 * shape_height(Shape::kHills, 65, 32, 0), 1e-9);
}

TEST(ScenesField, BuildsFromAFunctionAndRefusesBadSizesByName) {
  auto hf = field({.width = 5, .height = 3, .spacing_x = 2, .spacing_z = 0.5, .height_offset = 10},
                  [](int i, int j) { return 2.0 * i + 3.0 * j; });
  ASSERT_TRUE(hf.ok()) << hf.error().message;
  EXPECT_EQ(hf->local(4, 2), 14.0f);
  EXPECT_EQ(hf->world(1, 1), 15.0);
  auto bad = field({.width = 1, .height = 3}, [](int, int) { return 0.0; });
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("1 x 3"), std::string::npos) << bad.error().message;
  auto nan =
      field({.width = 3, .height = 3}, [](int i, int) { return i == 1 ? std::nan("") : 0.0; });
  EXPECT_FALSE(nan.ok());
}

}  // namespace
}  // namespace ridgeline::scenes
