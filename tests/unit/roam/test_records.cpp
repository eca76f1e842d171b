// The packed bounds of roam/records.h: a bound stored in 32 bits must never come back below the
// bound it stores (the tessellator would stop refining where the surface is farther than the
// threshold), nor more than one step of its 6-bit mantissa above it.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <random>
#include <sstream>
#include <vector>

#include "roam/records.h"

using namespace ridgeline;
using namespace ridgeline::roam;

namespace {

// Values over the packed range (2^-30 .. 2^24 m; spheres twice that): random mantissas, and every
// mantissa whose top 6 bits are all set (the values that round up into the next power of two) with
// a few low bits, in every exponent.
std::vector<float> probe_values() {
  std::vector<float> v;
  std::mt19937 rng(11);
  std::uniform_int_distribution<std::uint32_t> mant(0, 0x7fffff);
  for (int e = -30; e <= 23; ++e) {
    for (std::uint32_t low : {0u, 1u, 0x1ffffu, 0x10000u})
      v.push_back(std::ldexp(std::bit_cast<float>(0x3f800000u | 0x7e0000u | low), e));
    for (int k = 0; k < 40; ++k)
      v.push_back(std::ldexp(std::bit_cast<float>(0x3f800000u | mant(rng)), e));
  }
  return v;
}

std::string describe(const char* part, float stored, float back) {
  std::ostringstream s;
  s.precision(9);
  s << part << " " << stored << " m unpacks to " << back << " m";
  return s.str();
}

}  // namespace

// Error, radius and morph bound each: at least what was packed, at most 1/64 above (the error
// and radius: one mantissa step; the morph bound over the error: one 2^(1/64) ratio step, on top
// of the error's own rounding).
TEST(Records, PackedBoundsNeverComeBackBelowWhatTheyStore) {
  std::size_t checked = 0;
  for (float v : probe_values()) {
    for (float morph_ratio : {1.0f, 1.3f, 7.5f}) {
      const DiamondBound b{v, v * morph_ratio, 2.0f * v};
      const DiamondBound q = quantized(b);
      ++checked;
      ASSERT_GE(q.error, b.error) << describe("error", b.error, q.error)
                                  << ": the packed bound is below the error it bounds";
      ASSERT_LE(q.error, b.error * (1.0f + 1.0f / 64.0f))
          << describe("error", b.error, q.error) << ": more than one mantissa step above";
      ASSERT_GE(q.radius, b.radius) << describe("radius", b.radius, q.radius)
                                    << ": the packed sphere is smaller than the one it bounds";
      ASSERT_LE(q.radius, b.radius * (1.0f + 1.0f / 64.0f))
          << describe("radius", b.radius, q.radius) << ": more than one mantissa step above";
      ASSERT_GE(q.morph, b.morph) << describe("morph bound", b.morph, q.morph)
                                  << ": the packed morph bound is below the one it bounds";
      ASSERT_LE(q.morph, b.morph * (1.0f + 1.0f / 64.0f) * std::exp2(1.0f / 64.0f) * 1.0001f)
          << describe("morph bound", b.morph, q.morph) << ": more than one step above";
    }
  }
  EXPECT_GT(checked, 5000u);
  // Zero stays zero, and past the range a bound becomes infinite (never smaller).
  EXPECT_EQ(quantized({0.0f, 0.0f, 0.0f}).error, 0.0f);
  EXPECT_TRUE(std::isinf(quantized({FLT_MAX, FLT_MAX, FLT_MAX}).error));
  EXPECT_TRUE(std::isinf(quantized({1.0f, 1.0f, FLT_MAX}).radius));
}
