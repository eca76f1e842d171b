// The baked world's reader (io/world_reader.cpp, io/world_format.cpp) against what a damaged or
// misused file could make it do: the checksum that guards every page and the index sees every
// byte, and a page outside the world's grid is refused, never read from a neighbour's entry.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "io/world_format.h"
#include "ridgeline/world_file.h"

using namespace ridgeline;

namespace {

std::string tmp_world(const std::string& leaf) {
  const std::filesystem::path dir = std::filesystem::path(RIDGELINE_TEST_TMP) / "world_file";
  std::filesystem::create_directories(dir);
  return (dir / leaf).string();
}

}  // namespace

// Every byte of a block of any length counts: one flipped bit anywhere changes the checksum (a
// page or an index damaged there is refused instead of loaded).
TEST(WorldFile, TheChecksumSeesEveryByte) {
  std::mt19937 rng(5);
  for (std::size_t n = 1; n <= 40; ++n) {
    std::vector<std::uint8_t> b(n);
    for (auto& v : b) v = std::uint8_t(rng());
    const std::uint64_t good = io::world_file::checksum(b.data(), n);
    for (std::size_t k = 0; k < n; ++k)
      for (int bit : {0, 7}) {
        b[k] ^= std::uint8_t(1u << bit);
        EXPECT_NE(io::world_file::checksum(b.data(), n), good)
            << "the checksum of " << n << " bytes ignores bit " << bit << " of byte " << k
            << ": a world damaged there would load";
        b[k] ^= std::uint8_t(1u << bit);
      }
  }
}

// load() of a page past the grid of its level (one past the last column or row, a level above
// the top, negative) is refused naming the page; every page of the grid loads.
TEST(WorldFile, PagesOutsideTheGridAreRefused) {
  HeightfieldDesc d;
  d.width = 600;
  d.height = 300;
  std::vector<float> h(std::size_t(d.width) * d.height);
  for (std::size_t k = 0; k < h.size(); ++k)
    h[k] = float(std::sin(0.01 * double(k % d.width)) * 20);
  const std::string path = tmp_world("grid.tif");
  auto baked = io::bake_world(Heightfield::create(d, h).value(), path);
  ASSERT_TRUE(baked) << baked.error().message;
  auto source = io::open_world(path);
  ASSERT_TRUE(source) << source.error().message;
  // 600 x 300 samples: 3 x 2 pages of 256 cells at level 0, one page at level 1 (the top).
  const std::int32_t px = 3, pz = 2;
  PageData data;
  for (std::int32_t z = 0; z < pz; ++z)
    for (std::int32_t x = 0; x < px; ++x) {
      const Status st = (*source)->load({0, x, z}, data);
      EXPECT_TRUE(st) << "page (0, " << x << ", " << z << "): " << st.message();
    }
  EXPECT_TRUE((*source)->load({1, 0, 0}, data));
  for (const PageKey k : {PageKey{0, px, 0}, PageKey{0, 0, pz}, PageKey{0, px, pz - 1},
                          PageKey{0, px - 1, pz}, PageKey{1, 1, 0}, PageKey{1, 0, 1},
                          PageKey{2, 0, 0}, PageKey{0, -1, 0}, PageKey{0, 0, -1}}) {
    const Status st = (*source)->load(k, data);
    const std::string name = "page (" + std::to_string(k.level) + ", " + std::to_string(k.px) +
                             ", " + std::to_string(k.pz) + ")";
    EXPECT_FALSE(st) << name << " lies outside the 3 x 2 grid but loaded (another page's data)";
    if (!st) {
      EXPECT_NE(st.message().find("no page"), std::string::npos) << st.message();
    }
  }
}
