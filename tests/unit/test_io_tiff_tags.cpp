// The bounded TIFF tag reader (module/src/io/tiff_tags.cpp): GDAL's no-data tag as the default
// no-data value, malformed tags ignored with a warning, every truncation read within bounds.
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

namespace {

/// A little-endian, uncompressed, single-strip int16 TIFF of w x h samples written byte by byte
/// (OpenImageIO cannot write GDAL's private tag), with a GDAL_NODATA tag (42113, ASCII) holding
/// `nodata` unless it is empty. `tag_offset` replaces the offset of the tag's text when nonzero.
std::vector<char> int16_tiff(int w, int h, const std::vector<std::int16_t>& v,
                             const std::string& nodata, std::uint32_t tag_offset = 0) {
  struct Entry {
    std::uint16_t tag, type;
    std::uint32_t count, value;
  };
  const std::uint32_t n_entries = nodata.empty() ? 10 : 11;
  const std::uint32_t text_at = 8 + 2 + 12 * n_entries + 4;
  const std::uint32_t text_len = static_cast<std::uint32_t>(nodata.size()) + 1;
  const std::uint32_t pixels_at = (text_at + (nodata.empty() ? 0 : text_len) + 1) & ~1u;
  const std::uint32_t bytes = static_cast<std::uint32_t>(v.size() * 2);
  std::vector<Entry> e = {{256, 3, 1, std::uint32_t(w)},
                          {257, 3, 1, std::uint32_t(h)},
                          {258, 3, 1, 16},
                          {259, 3, 1, 1},
                          {262, 3, 1, 1},
                          {273, 4, 1, pixels_at},
                          {277, 3, 1, 1},
                          {278, 3, 1, std::uint32_t(h)},
                          {279, 4, 1, bytes},
                          {339, 3, 1, 2}};
  if (!nodata.empty()) e.push_back({42113, 2, text_len, tag_offset ? tag_offset : text_at});
  std::vector<char> b;
  auto u16 = [&](std::uint32_t x) {
    b.push_back(char(x & 0xff));
    b.push_back(char(x >> 8 & 0xff));
  };
  auto u32 = [&](std::uint32_t x) {
    u16(x & 0xffff);
    u16(x >> 16);
  };
  b = {'I', 'I'};
  u16(42);
  u32(8);
  u16(n_entries);
  for (const Entry& x : e) {
    u16(x.tag);
    u16(x.type);
    u32(x.count);
    if (x.type == 3) {
      u16(x.value);
      u16(0);
    } else {
      u32(x.value);
    }
  }
  u32(0);  // no next IFD
  if (!nodata.empty()) b.insert(b.end(), nodata.c_str(), nodata.c_str() + text_len);
  b.resize(pixels_at, 0);
  for (std::int16_t s : v) u16(static_cast<std::uint16_t>(s));
  return b;
}

}  // namespace


TEST(IoNoDataTag, GdalNodataTagIsTheDefaultNoDataValue) {
  const auto path = tmp_path("elev.tif");
  write_bytes(path, int16_tiff(3, 2, {100, -32768, 200, 300, 400, 500}, "-32768"));
  {  // No --nodata: the tag's value is used and said; the sample equal to it is refused.
    LogCapture log;
    auto hf = io::load_image(path, options());
    ASSERT_FALSE(hf);
    EXPECT_TRUE(contains(hf.error().message, "sample (1, 0) is -32768 (the no-data value)"))
        << hf.error().message;
    ASSERT_EQ(log.messages.size(), 1u);
    EXPECT_TRUE(contains(log.messages[0], "no-data value -32768 from the file's GDAL_NODATA tag"))
        << log.messages[0];
  }
  {  // With a fill policy it loads, filling that sample.
    auto o = options();
    o.placement.fill = FillPolicy::kNearest;
    auto hf = io::load_image(path, o);
    ASSERT_TRUE(hf) << hf.error().message;
    EXPECT_EQ(hf->filled_samples(), 1u);
    EXPECT_EQ(locals(*hf), (std::vector<float>{100, 100, 200, 300, 400, 500}));
  }
  {  // A value the user gives wins, and the disagreement is said.
    LogCapture log;
    auto o = options();
    o.placement.nodata = 500.0;
    o.placement.fill = FillPolicy::kConstant;
    auto hf = io::load_image(path, o);
    ASSERT_TRUE(hf) << hf.error().message;
    EXPECT_EQ(locals(*hf), (std::vector<float>{100, -32768, 200, 300, 400, 0}));
    ASSERT_EQ(log.messages.size(), 2u);
    EXPECT_TRUE(contains(log.messages[0], "GDAL_NODATA tag says '-32768'")) << log.messages[0];
    // One of six samples filled: more than 5 %, so the loader warns.
    EXPECT_TRUE(contains(log.messages[1], "1 of 6 samples (16.7 %) are filled")) << log.messages[1];
  }
  {  // Without the tag nothing is assumed: -32768 is a height like any other.
    const auto plain = tmp_path("plain.tif");
    write_bytes(plain, int16_tiff(3, 2, {100, -32768, 200, 300, 400, 500}, ""));
    LogCapture log;
    auto hf = io::load_image(plain, options());
    ASSERT_TRUE(hf) << hf.error().message;
    EXPECT_EQ(hf->min_local(), -32768.0f);
    EXPECT_TRUE(log.messages.empty());
  }
}

TEST(IoNoDataTag, MalformedTagsAreIgnoredWithAWarning) {
  const auto path = tmp_path("bad.tif");
  // The tag's text offset points past the end of the file.
  write_bytes(path, int16_tiff(2, 2, {1, 2, 3, 4}, "-32768", 1u << 30));
  LogCapture log;
  auto hf = io::load_image(path, options());
  ASSERT_TRUE(hf) << hf.error().message;
  EXPECT_EQ(locals(*hf), (std::vector<float>{1, 2, 3, 4}));
  ASSERT_EQ(log.messages.size(), 1u);
  EXPECT_TRUE(contains(log.messages[0], "GDAL_NODATA tag ignored")) << log.messages[0];
  EXPECT_TRUE(contains(log.messages[0], "outside the file")) << log.messages[0];

  // Not a number.
  write_bytes(path, int16_tiff(2, 2, {1, 2, 3, 4}, "none"));
  LogCapture log2;
  auto hf2 = io::load_image(path, options());
  ASSERT_TRUE(hf2) << hf2.error().message;
  ASSERT_EQ(log2.messages.size(), 1u);
  EXPECT_TRUE(contains(log2.messages[0], "'none' is not a number")) << log2.messages[0];
}

TEST(IoNoDataTag, ReaderIsBoundedOnEveryTruncation) {
  // Every prefix of a valid file: no tag found or a precise error, never a read past the end.
  const std::vector<char> full = int16_tiff(2, 2, {1, 2, 3, 4}, "-9999");
  for (std::size_t n = 0; n <= full.size(); ++n) {
    std::uint64_t furthest = 0;
    io::detail::ReadAt read = [&](std::uint64_t off, std::size_t k, unsigned char* out) {
      EXPECT_LE(off + k, n);
      furthest = std::max<std::uint64_t>(furthest, off + k);
      if (off + k > n) return false;
      std::memcpy(out, full.data() + off, k);
      return true;
    };
    auto r = io::detail::read_gdal_nodata(read, n);
    if (n == full.size()) {
      ASSERT_TRUE(r) << r.error().message;
      ASSERT_TRUE(*r);
      EXPECT_EQ(**r, "-9999");
    } else if (r && *r) {
      EXPECT_EQ(**r, "-9999");  // the tag's text was complete in the prefix
    }
  }
  // Not a TIFF, and a TIFF claiming a huge IFD.
  auto from = [](std::vector<char> b) {
    io::detail::ReadAt read = [b](std::uint64_t off, std::size_t k, unsigned char* out) {
      if (off + k > b.size()) return false;
      std::memcpy(out, b.data() + off, k);
      return true;
    };
    return io::detail::read_gdal_nodata(read, b.size());
  };
  auto png = from({char(0x89), 'P', 'N', 'G', 13, 10, 26, 10});
  ASSERT_TRUE(png);
  EXPECT_FALSE(*png);
  auto huge = from({'I', 'I', 42, 0, 8, 0, 0, 0, char(0xff), char(0xff), 0, 0});
  ASSERT_FALSE(huge);
  EXPECT_TRUE(contains(huge.error().message, "65535 entries")) << huge.error().message;
  EXPECT_EQ(io::detail::parse_nodata_text("-32768"), -32768.0);
  EXPECT_EQ(io::detail::parse_nodata_text("-3.4028234663852886e+38"), -3.4028234663852886e+38);
  EXPECT_FALSE(io::detail::parse_nodata_text("12 m"));
  EXPECT_FALSE(io::detail::parse_nodata_text("1e999"));
}
