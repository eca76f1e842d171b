// Terrain (module/src/terrain.cpp): what composing the surface, its pages and the ray pyramid
// costs in memory.
#include <gtest/gtest.h>

#include "query_reference.h"
#include "ridgeline/terrain.h"

using namespace ridgeline;
using namespace ridgeline::test;

TEST(Terrain, PagesTakeUnderSixBytesASampleAndMemoryBytesCountsThem) {
  // A field of many pages (a single-page one pays for its coarse levels' padding).
  FieldSpec s{1025, 1025};
  auto t = make_terrain(s, rough);
  const double samples = 1025.0 * 1025.0;
  // Pages: heights (4 bytes a float sample, with the apron), materials and the ray pyramid.
  const double bytes = double(t->world_stats().resident_bytes);
  EXPECT_LE(bytes / samples, 6.0);
  EXPECT_GE(t->memory_bytes(), std::size_t(bytes));
}
