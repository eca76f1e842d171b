// Terrains and the bounds check the edit tests share (test_edit.cpp, test_edit_bytes.cpp,
// test_change_log.cpp).
#pragma once

#include <gtest/gtest.h>

#include <memory>

#include "ridgeline/landscape.h"
#include "ridgeline/scenes.h"
#include "ridgeline/terrain.h"
#include "roam_test_util.h"

namespace ridgeline::test {

inline std::shared_ptr<Terrain> flat_terrain(std::uint32_t n, double spacing = 1.0, double offset = 0.0) {
  return Terrain::create(std::move(scenes::field({.width = n,
                                                  .height = n,
                                                  .spacing_x = spacing,
                                                  .spacing_z = spacing,
                                                  .height_offset = offset},
                                                 [](int, int) { return 0.0; }))
                             .value()).value();
}

inline std::shared_ptr<Terrain> noise_terrain(std::uint32_t n, std::uint32_t seed = 7) {
  return Terrain::create(
      std::move(make_default_heightfield({.size = n, .spacing = 2.0, .seed = seed})).value()).value();
}

// Every bound of `l` (refreshed by the edits themselves) equals the one a fresh Landscape over
// the same heights computes.
inline void expect_bounds_equal_rebuild(const Landscape& l) {
  auto fresh = Landscape::create(l.terrain_ptr(), {.patch_exponent = l.patch_exponent()}).value();
  const std::uint64_t per_root = (std::uint64_t{1} << l.max_level()) - 1;
  std::uint64_t bad = 0;
  for (std::uint32_t r = 0; r < l.root_count(); ++r)
    for (std::uint64_t h = 1; h <= per_root; ++h)
      if (l.bound(r, h) != fresh->bound(r, h) && ++bad < 4)
        ADD_FAILURE() << "root " << r << " heap " << h << ": incremental " << l.bound(r, h)
                      << ", rebuilt " << fresh->bound(r, h);
  EXPECT_EQ(bad, 0u);
}

}  // namespace ridgeline::test
