// Queries on the surface (being extended).
#include <gtest/gtest.h>

#include "ridgeline/terrain.h"

using namespace ridgeline;

TEST(Queries, PlaneHeight) {
  HeightfieldDesc d;
  d.width = d.height = 5;
  std::vector<float> v(25);
  for (int j = 0; j < 5; ++j)
    for (int i = 0; i < 5; ++i) v[i + j * 5] = float(2 * i + 3 * j);
  auto t = Terrain::create(std::move(Heightfield::create(d, v)).value());
  EXPECT_NEAR(*t->height(1.25, 2.5), 2 * 1.25 + 3 * 2.5, 1e-5);
  EXPECT_FALSE(t->height(-0.1, 1.0));
}
