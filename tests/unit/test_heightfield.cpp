// Heightfield: placement, validation of every kind of bad input, fill policies, default terrain.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "ridgeline/heightfield.h"

using namespace ridgeline;

namespace {

HeightfieldDesc desc(std::uint32_t w, std::uint32_t h) {
  HeightfieldDesc d;
  d.width = w;
  d.height = h;
  d.name = "test";
  return d;
}

}  // namespace

TEST(Heightfield, PlacesSamplesAsSpecSays) {
  auto d = desc(3, 2);
  d.spacing_x = 2.0;
  d.spacing_z = 0.5;
  d.origin_x = 1e7;
  d.origin_z = -3.0;
  d.height_scale = 0.5;
  d.height_offset = 100.0;
  std::vector<float> v{0, 1, 2, 3, 4, 5};
  auto hf = Heightfield::create(d, v);
  ASSERT_TRUE(hf) << hf.error().message;
  EXPECT_EQ(hf->width(), 3u);
  EXPECT_EQ(hf->height(), 2u);
  EXPECT_DOUBLE_EQ(hf->world(2, 1), 100.0 + 0.5 * 5);
  EXPECT_FLOAT_EQ(hf->local(1, 0), 0.5f);
  EXPECT_DOUBLE_EQ(hf->extent_x(), 4.0);
  EXPECT_DOUBLE_EQ(hf->extent_z(), 0.5);
  EXPECT_FLOAT_EQ(hf->min_local(), 0.0f);
  EXPECT_FLOAT_EQ(hf->max_local(), 2.5f);
  EXPECT_FLOAT_EQ(hf->local_clamped(-5, 9), hf->local(0, 1));
}

// heightfield.h promises an assert on local()'s and material()'s indices: in builds where
// RIDGELINE_ASSERT is on (Debug, and the sanitizer build of scripts/test.sh) an index past the
// last sample aborts through the assertion handler, naming the check; valid indices up to the
// last sample and cell are fine. Without assertions there is nothing to test: the test is not
// built there (rather than skipped).
#if defined(RIDGELINE_ENABLE_ASSERTS) || !defined(NDEBUG)
TEST(HeightfieldDeathTest, LocalAndMaterialAssertTheirIndices) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  std::vector<float> v{0, 1, 2, 3, 4, 5};
  const std::vector<std::uint8_t> mats{7, 8};
  auto hf = Heightfield::create(desc(3, 2), v, mats);
  ASSERT_TRUE(hf) << hf.error().message;
  EXPECT_FLOAT_EQ(hf->local(2, 1), 5.0f);
  EXPECT_EQ(hf->material(1, 0), 8);
  EXPECT_DEATH((void)hf->local(3, 0), "assertion failed: i < width_ && j < height_");
  EXPECT_DEATH((void)hf->local(0, 2), "assertion failed: i < width_ && j < height_");
  EXPECT_DEATH((void)hf->material(2, 0), "assertion failed: i \\+ 1 < width_ && j \\+ 1 < height_");
  EXPECT_DEATH((void)hf->material(0, 1), "assertion failed: i \\+ 1 < width_");
}
#endif

TEST(Heightfield, RefusesTooSmall) {
  for (auto [w, h] : {std::pair{0u, 17u}, std::pair{1u, 5u}, std::pair{5u, 1u}}) {
    auto d = desc(w, h);
    std::vector<float> v(std::size_t{w} * h, 0.0f);
    auto hf = Heightfield::create(d, v);
    ASSERT_FALSE(hf);
    EXPECT_NE(hf.error().message.find("need at least 2 x 2"), std::string::npos)
        << hf.error().message;
  }
}

TEST(Heightfield, RefusesSizesAboveTheCapBeforeAllocating) {
  auto d = desc(1u << 20, 1u << 20);  // 2^40 samples: would be 4 TiB
  Status s = validate_heightfield_desc(d);
  ASSERT_FALSE(s);
  EXPECT_NE(s.message().find("exceeds the limit"), std::string::npos) << s.message();
  d = desc(100, 100);
  d.max_samples = 9999;
  EXPECT_FALSE(validate_heightfield_desc(d));
}

TEST(Heightfield, RefusesBadSpacingScaleAndOrigin) {
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<float> v(4, 0.0f);
  for (double bad : {0.0, -1.0, inf, nan}) {
    auto d = desc(2, 2);
    d.spacing_x = bad;
    auto hf = Heightfield::create(d, v);
    ASSERT_FALSE(hf);
    EXPECT_NE(hf.error().message.find("spacing x"), std::string::npos) << hf.error().message;
    d = desc(2, 2);
    d.height_scale = bad;
    hf = Heightfield::create(d, v);
    ASSERT_FALSE(hf);
    EXPECT_NE(hf.error().message.find("height scale"), std::string::npos);
  }
  auto d = desc(2, 2);
  d.origin_z = nan;
  EXPECT_FALSE(Heightfield::create(d, v));
  d = desc(2, 2);
  d.height_offset = -inf;
  EXPECT_FALSE(Heightfield::create(d, v));
}

TEST(Heightfield, RefusesNonFiniteSamplesNamingTheFirst) {
  auto d = desc(4, 3);
  std::vector<float> v(12, 1.0f);
  v[6] = std::numeric_limits<float>::quiet_NaN();  // (2, 1)
  v[9] = std::numeric_limits<float>::infinity();
  auto hf = Heightfield::create(d, v);
  ASSERT_FALSE(hf);
  EXPECT_NE(hf.error().message.find("sample (2, 1) is nan"), std::string::npos)
      << hf.error().message;
}

TEST(Heightfield, NoDataRefusedUnlessFilled) {
  auto d = desc(4, 1 + 2);
  d.nodata = -9999.0;
  std::vector<float> v{1, 2, 3, 4, 5, -9999, -9999, 8, 9, 10, 11, 12};
  auto hf = Heightfield::create(d, v);
  ASSERT_FALSE(hf);
  EXPECT_NE(hf.error().message.find("sample (1, 1)"), std::string::npos) << hf.error().message;
  EXPECT_NE(hf.error().message.find("no-data"), std::string::npos);

  d.fill = FillPolicy::kNearest;
  hf = Heightfield::create(d, v);
  ASSERT_TRUE(hf) << hf.error().message;
  EXPECT_EQ(hf->filled_samples(), 2u);
  EXPECT_FLOAT_EQ(hf->local(1, 1), 2.0f);  // nearest by BFS from scan order: (1,0) reaches first
  EXPECT_FLOAT_EQ(hf->local(2, 1), 3.0f);

  d.fill = FillPolicy::kConstant;
  d.fill_constant = 7;
  d.height_scale = 2;
  hf = Heightfield::create(d, v);
  ASSERT_TRUE(hf);
  EXPECT_FLOAT_EQ(hf->local(1, 1), 14.0f);
}

TEST(Heightfield, AllMissingIsAnError) {
  auto d = desc(2, 2);
  d.fill = FillPolicy::kNearest;
  std::vector<float> v(4, std::numeric_limits<float>::quiet_NaN());
  auto hf = Heightfield::create(d, v);
  ASSERT_FALSE(hf);
  EXPECT_NE(hf.error().message.find("every sample is missing"), std::string::npos);
}

TEST(Heightfield, WrongValueAndMaterialCounts) {
  auto d = desc(3, 3);
  std::vector<float> v(8, 0.0f);
  EXPECT_FALSE(Heightfield::create(d, v));
  v.resize(9);
  std::vector<std::uint8_t> m(5, 1);
  EXPECT_FALSE(Heightfield::create(d, v, m));
  m.assign(4, 3);  // per cell
  auto hf = Heightfield::create(d, v, m);
  ASSERT_TRUE(hf);
  EXPECT_EQ(hf->material(1, 1), 3);
  m.assign(9, 0);  // per sample
  m[4] = 9;
  hf = Heightfield::create(d, v, m);
  ASSERT_TRUE(hf);
  EXPECT_EQ(hf->material(1, 1), 9);
}

TEST(Heightfield, ScaledOverflowIsRefused) {
  auto d = desc(2, 2);
  d.height_scale = 1e30;
  std::vector<float> v{1e30f, 0, 0, 0};
  auto hf = Heightfield::create(d, v);
  ASSERT_FALSE(hf);
  EXPECT_NE(hf.error().message.find("overflows"), std::string::npos);
}

TEST(Heightfield, HeightsBeyondTheLimitAreRefused) {
  // The limit is on the height relative to the offset, after scaling: 1e5 m passes, more not.
  auto d = desc(2, 2);
  d.height_offset = 5e6;
  d.height_scale = 2;
  std::vector<float> v{5e4f, -5e4f, 0, 0};
  ASSERT_TRUE(Heightfield::create(d, v));
  v[3] = 50000.5f;
  auto hf = Heightfield::create(d, v);
  ASSERT_FALSE(hf);
  EXPECT_NE(hf.error().message.find("sample (1, 1) = 50000.5 gives a height of 100001 m"),
            std::string::npos)
      << hf.error().message;
  // A fill constant beyond it is refused too (only when something is filled).
  v = {1, 2, std::nanf(""), 4};
  d.fill = FillPolicy::kConstant;
  d.fill_constant = 1e6;
  auto filled = Heightfield::create(d, v);
  ASSERT_FALSE(filled);
  EXPECT_NE(filled.error().message.find("fill constant 1e+06 gives a height of 2e+06 m"), std::string::npos)
      << filled.error().message;
  v[2] = 3;
  EXPECT_TRUE(Heightfield::create(d, v));
}

TEST(DefaultTerrain, IsDeterministicAndDocumented) {
  auto a = make_default_heightfield();
  auto b = make_default_heightfield();
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->width(), 1025u);
  EXPECT_DOUBLE_EQ(a->spacing_x(), 2.0);
  EXPECT_EQ(a->content_hash(), b->content_hash());
  EXPECT_TRUE(a->has_materials());
  EXPECT_GT(a->max_local() - a->min_local(), 100.0f);
  auto c = make_default_heightfield({.size = 129, .spacing = 2.0, .seed = 7});
  ASSERT_TRUE(c);
  EXPECT_NE(c->content_hash(), a->content_hash());
}
