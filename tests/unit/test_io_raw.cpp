// The headerless raw loader (module/src/io/raw_loader.cpp): little-endian u16 and f32, the type
// names, sizes that do not match the file. What every loader shares (fill policies, limits,
// materials) is test_io_image.cpp's.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "io/oiio_lsan_suppressions.h"
#include "io/tiff_tags.h"
#include "io_test_util.h"
#include "ridgeline/io.h"
#include "ridgeline/log.h"

using namespace ridgeline;
using namespace ridgeline::test;
namespace fs = std::filesystem;

TEST(IoRoundTrip, RawU16AndF32AreLittleEndian) {
  // u16: bytes 0x34 0x12 are 0x1234.
  const std::vector<char> u16 = {0x34, 0x12, 0, 0, char(0xff), char(0xff), 1, 0};
  const auto p16 = tmp_path("h.r16");
  write_bytes(p16, u16);
  auto a = io::load_raw(p16, {2, 2, io::RawType::kU16}, options());
  ASSERT_TRUE(a) << a.error().message;
  EXPECT_EQ(locals(*a), (std::vector<float>{4660, 0, 65535, 1}))
      << "16-bit raw samples are little-endian: bytes 34 12 are 0x1234";

  const std::vector<float> f = {1.5f, -2.25f, 9.9e4f, 0.1f, -0.0f, 7.0f};
  std::vector<char> f32;
  for (float v : f) {
    std::uint32_t u;
    std::memcpy(&u, &v, 4);
    for (int b = 0; b < 4; ++b) f32.push_back(static_cast<char>(u >> (8 * b)));
  }
  const auto p32 = tmp_path("h.r32");
  write_bytes(p32, f32);
  auto b = io::load_raw(p32, {3, 2, io::RawType::kF32}, options());
  ASSERT_TRUE(b) << b.error().message;
  EXPECT_EQ(locals(*b), f);
  EXPECT_EQ(b->width(), 3u);
  EXPECT_EQ(b->height(), 2u);
}

TEST(IoRoundTrip, ParseRawType) {
  EXPECT_EQ(*io::parse_raw_type("u16"), io::RawType::kU16);
  EXPECT_EQ(*io::parse_raw_type("f32"), io::RawType::kF32);
  auto bad = io::parse_raw_type("f64");
  ASSERT_FALSE(bad);
  EXPECT_TRUE(contains(bad.error().message, "'f64'"));
}

TEST(IoBadInput, RawSizeMismatchNamesBothSizes) {
  const auto path = tmp_path("h.raw");
  write_bytes(path, std::vector<char>(10, 0));
  auto a = io::load_raw(path, {2, 3, io::RawType::kU16}, options());
  ASSERT_FALSE(a);
  EXPECT_EQ(a.error().message,
            "heightmap '" + path + "': file is 10 bytes but 2 x 3 u16 samples need 12 bytes");
  auto b = io::load_raw(path, {2, 2, io::RawType::kF32}, options());
  ASSERT_FALSE(b);
  EXPECT_EQ(b.error().message,
            "heightmap '" + path + "': file is 10 bytes but 2 x 2 f32 samples need 16 bytes");
  // A size over the cap is reported as such, not as a mismatch (and nothing is read).
  auto c = io::load_raw(path, {100000, 100000, io::RawType::kF32}, options());
  ASSERT_FALSE(c);
  EXPECT_TRUE(contains(c.error().message, "exceeds the limit")) << c.error().message;
  // In memory, the same checks.
  std::vector<std::byte> mem(7);
  auto d = io::parse_raw(mem, {2, 2, io::RawType::kU16}, options(), "mem");
  ASSERT_FALSE(d);
  EXPECT_EQ(d.error().message, "mem: file is 7 bytes but 2 x 2 u16 samples need 8 bytes");
}
