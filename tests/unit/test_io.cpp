// Ridgeline::io: round trips for every supported format, placement, and one case per kind of bad
// input. Test images are written with OpenImageIO at test time into RIDGELINE_TEST_TMP.
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
#include "ridgeline/io.h"
#include "ridgeline/log.h"

using namespace ridgeline;
namespace fs = std::filesystem;

namespace {

/// A file name unique to the running test (ctest runs each test in its own process, in parallel).
std::string tmp_path(const std::string& leaf) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const fs::path dir = fs::path(RIDGELINE_TEST_TMP) / "io";
  fs::create_directories(dir);
  return (dir / (std::string(info->test_suite_name()) + "_" + info->name() + "_" + leaf)).string();
}

template <class T>
void write_image(const std::string& path, int w, int h, int channels, OIIO::TypeDesc type,
                 const std::vector<T>& pixels) {
  ASSERT_EQ(pixels.size(), static_cast<std::size_t>(w) * h * channels);
  auto out = OIIO::ImageOutput::create(path);
  ASSERT_TRUE(out) << OIIO::geterror();
  OIIO::ImageSpec spec(w, h, channels, type);
  if (channels == 2) {
    spec.channelnames = {"Y", "A"};
    spec.alpha_channel = 1;
    spec.attribute("oiio:UnassociatedAlpha", 1);  // store grey as given, not divided by alpha
  }
  ASSERT_TRUE(out->open(path, spec)) << out->geterror();
  ASSERT_TRUE(out->write_image(type, pixels.data())) << out->geterror();
  ASSERT_TRUE(out->close());
}

std::vector<char> read_bytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

void write_bytes(const std::string& path, const std::vector<char>& bytes) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

io::LoadOptions options() {
  io::LoadOptions o;
  return o;
}

/// Every sample's local height (relative to the offset), row-major.
std::vector<float> locals(const Heightfield& hf) {
  return {hf.local_heights().begin(), hf.local_heights().end()};
}

bool contains(const std::string& haystack, const std::string& needle) {
  return haystack.find(needle) != std::string::npos;
}

/// A deterministic pseudo-random pattern of `n` values in [0, range).
std::vector<std::uint32_t> pattern(std::size_t n, std::uint32_t range, std::uint32_t seed = 7) {
  std::vector<std::uint32_t> v(n);
  std::uint32_t s = seed;
  for (auto& x : v) {
    s = s * 1664525u + 1013904223u;
    x = (s >> 8) % range;
  }
  return v;
}

std::uint32_t crc32(const unsigned char* p, std::size_t n) {
  std::uint32_t c = 0xffffffffu;
  for (std::size_t k = 0; k < n; ++k) {
    c ^= p[k];
    for (int b = 0; b < 8; ++b) c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1u)));
  }
  return c ^ 0xffffffffu;
}

void put_be32(std::vector<char>& b, std::size_t at, std::uint32_t v) {
  b[at] = static_cast<char>(v >> 24);
  b[at + 1] = static_cast<char>(v >> 16);
  b[at + 2] = static_cast<char>(v >> 8);
  b[at + 3] = static_cast<char>(v);
}

/// Captures log messages for the duration of a test.
struct LogCapture {
  std::vector<std::string> messages;
  LogCapture() {
    set_log_sink([](LogLevel, std::string_view m,
                    void* user) { static_cast<LogCapture*>(user)->messages.emplace_back(m); },
                 this);
  }
  ~LogCapture() { set_log_sink(nullptr); }
};

}  // namespace

// ---- round trips --------------------------------------------------------------------------------

TEST(IoRoundTrip, Png8GivesTheRawIntegers) {
  const std::vector<std::uint8_t> px = {0, 1, 2, 127, 128, 200, 254, 255, 17, 42, 99, 3};
  const auto path = tmp_path("h.png");
  write_image(path, 4, 3, 1, OIIO::TypeDesc::UINT8, px);
  auto hf = io::load_image(path, options());
  ASSERT_TRUE(hf) << hf.error().message;
  EXPECT_EQ(hf->width(), 4u);
  EXPECT_EQ(hf->height(), 3u);
  for (std::size_t k = 0; k < px.size(); ++k) EXPECT_EQ(locals(*hf)[k], float(px[k])) << k;
  EXPECT_EQ(hf->max_local(), 255.0f);
  EXPECT_FALSE(hf->has_materials());
}

TEST(IoRoundTrip, Png16GivesTheRawIntegers) {
  auto values = pattern(37 * 23, 65536);
  values[0] = 0;
  values[1] = 65535;
  std::vector<std::uint16_t> px(values.begin(), values.end());
  const auto path = tmp_path("h.png");
  write_image(path, 37, 23, 1, OIIO::TypeDesc::UINT16, px);
  auto hf = io::load_image(path, options());
  ASSERT_TRUE(hf) << hf.error().message;
  ASSERT_EQ(hf->width(), 37u);
  ASSERT_EQ(hf->height(), 23u);
  const auto l = locals(*hf);
  for (std::size_t k = 0; k < px.size(); ++k) ASSERT_EQ(l[k], float(px[k])) << k;
  EXPECT_EQ(hf->max_local(), 65535.0f);
  EXPECT_EQ(hf->min_local(), 0.0f);
}

TEST(IoRoundTrip, Tiff16GivesTheRawIntegers) {
  auto values = pattern(19 * 31, 65536, 11);
  std::vector<std::uint16_t> px(values.begin(), values.end());
  const auto path = tmp_path("h.tif");
  write_image(path, 19, 31, 1, OIIO::TypeDesc::UINT16, px);
  auto hf = io::load_image(path, options());
  ASSERT_TRUE(hf) << hf.error().message;
  const auto l = locals(*hf);
  for (std::size_t k = 0; k < px.size(); ++k) ASSERT_EQ(l[k], float(px[k])) << k;
}

TEST(IoRoundTrip, FloatTiffAndExrAreBitExact) {
  std::vector<float> px(13 * 9);
  for (std::size_t k = 0; k < px.size(); ++k)
    px[k] = std::ldexp(float(pattern(px.size(), 1u << 20)[k]) - 5e5f, -7) + 1e-3f * float(k);
  px[5] = -1234.5678f;
  px[6] = 8848.86f;
  px[7] = std::numeric_limits<float>::denorm_min();
  for (const char* ext : {"h.tif", "h.exr"}) {
    const auto path = tmp_path(ext);
    write_image(path, 13, 9, 1, OIIO::TypeDesc::FLOAT, px);
    auto hf = io::load_image(path, options());
    ASSERT_TRUE(hf) << hf.error().message;
    const auto l = locals(*hf);
    for (std::size_t k = 0; k < px.size(); ++k)
      ASSERT_EQ(std::memcmp(&l[k], &px[k], sizeof(float)), 0) << ext << " " << k;
  }
}

TEST(IoRoundTrip, RawU16AndF32AreLittleEndian) {
  // u16: bytes 0x34 0x12 are 0x1234.
  const std::vector<char> u16 = {0x34, 0x12, 0, 0, char(0xff), char(0xff), 1, 0};
  const auto p16 = tmp_path("h.r16");
  write_bytes(p16, u16);
  auto a = io::load_raw(p16, {2, 2, io::RawType::kU16}, options());
  ASSERT_TRUE(a) << a.error().message;
  EXPECT_EQ(locals(*a), (std::vector<float>{4660, 0, 65535, 1}));

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

TEST(IoRoundTrip, PlacementIsApplied) {
  const std::vector<std::uint16_t> px = {0, 100, 200, 300, 400, 500};
  const auto path = tmp_path("h.png");
  write_image(path, 3, 2, 1, OIIO::TypeDesc::UINT16, px);
  auto o = options();
  o.placement.spacing_x = 30.0;
  o.placement.spacing_z = 45.5;
  o.placement.origin_x = 1e6;
  o.placement.origin_z = -250.0;
  o.placement.height_scale = 0.25;
  o.placement.height_offset = -100.0;
  o.placement.width = 999;  // ignored: the size comes from the file
  o.placement.name = "ignored";
  auto hf = io::load_image(path, o);
  ASSERT_TRUE(hf) << hf.error().message;
  EXPECT_EQ(hf->width(), 3u);
  EXPECT_EQ(hf->spacing_x(), 30.0);
  EXPECT_EQ(hf->spacing_z(), 45.5);
  EXPECT_EQ(hf->origin_x(), 1e6);
  EXPECT_EQ(hf->origin_z(), -250.0);
  EXPECT_DOUBLE_EQ(hf->extent_x(), 60.0);
  EXPECT_DOUBLE_EQ(hf->extent_z(), 45.5);
  for (std::uint32_t j = 0; j < 2; ++j)
    for (std::uint32_t i = 0; i < 3; ++i)
      EXPECT_DOUBLE_EQ(hf->world(i, j), -100.0 + 0.25 * px[i + 3 * j]) << i << "," << j;
}

TEST(IoRoundTrip, LoadHeightmapDispatches) {
  const auto png = tmp_path("h.png");
  write_image(png, 2, 2, 1, OIIO::TypeDesc::UINT8, std::vector<std::uint8_t>{1, 2, 3, 4});
  auto a = io::load_heightmap(png, options());
  ASSERT_TRUE(a) << a.error().message;
  EXPECT_EQ(locals(*a), (std::vector<float>{1, 2, 3, 4}));

  const auto raw = tmp_path("h.raw");
  write_bytes(raw, {5, 0, 6, 0, 7, 0, 8, 0});
  auto no_size = io::load_heightmap(raw, options());
  ASSERT_FALSE(no_size);
  EXPECT_TRUE(contains(no_size.error().message, "heightmap '" + raw + "'"));
  EXPECT_TRUE(contains(no_size.error().message, "--raw-size"));
  const io::RawFormat fmt{2, 2, io::RawType::kU16};
  auto b = io::load_heightmap(raw, options(), &fmt);
  ASSERT_TRUE(b) << b.error().message;
  EXPECT_EQ(locals(*b), (std::vector<float>{5, 6, 7, 8}));
}

TEST(IoRoundTrip, ParseRawType) {
  EXPECT_EQ(*io::parse_raw_type("u16"), io::RawType::kU16);
  EXPECT_EQ(*io::parse_raw_type("f32"), io::RawType::kF32);
  auto bad = io::parse_raw_type("f64");
  ASSERT_FALSE(bad);
  EXPECT_TRUE(contains(bad.error().message, "'f64'"));
}

// ---- materials ----------------------------------------------------------------------------------

TEST(IoMaterials, PerSampleIdsBecomePerCellIds) {
  const auto h = tmp_path("h.png"), m = tmp_path("m.png");
  write_image(h, 3, 3, 1, OIIO::TypeDesc::UINT8, std::vector<std::uint8_t>(9, 10));
  const std::vector<std::uint8_t> ids = {0, 1, 2, 3, 4, 5, 6, 7, 255};
  write_image(m, 3, 3, 1, OIIO::TypeDesc::UINT8, ids);
  auto o = options();
  o.materials_path = m;
  auto hf = io::load_image(h, o);
  ASSERT_TRUE(hf) << hf.error().message;
  ASSERT_TRUE(hf->has_materials());
  EXPECT_EQ(hf->material(0, 0), 0);
  EXPECT_EQ(hf->material(1, 0), 1);
  EXPECT_EQ(hf->material(0, 1), 3);
  EXPECT_EQ(hf->material(1, 1), 4);

  // The raw loader takes the same layer.
  const auto raw = tmp_path("h.raw");
  write_bytes(raw, std::vector<char>(18, 0));
  auto r = io::load_raw(raw, {3, 3, io::RawType::kU16}, o);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->material(1, 1), 4);
}

TEST(IoMaterials, BadMaterialImagesAreRefused) {
  const auto h = tmp_path("h.png");
  write_image(h, 3, 3, 1, OIIO::TypeDesc::UINT8, std::vector<std::uint8_t>(9, 10));
  struct Case {
    int w, h, channels;
    OIIO::TypeDesc type;
    const char* expect;
  };
  const Case cases[] = {
      {4, 3, 1, OIIO::TypeDesc::UINT8, "4 x 3 pixels; the heightmap has 3 x 3 samples"},
      {3, 3, 3, OIIO::TypeDesc::UINT8, "3 channels"},
      {3, 3, 1, OIIO::TypeDesc::UINT16, "need 8-bit unsigned material ids"},
  };
  int n = 0;
  for (const auto& c : cases) {
    std::string leaf = "m";
    leaf += std::to_string(n++);
    leaf += ".png";
    const auto m = tmp_path(leaf);
    if (c.type == OIIO::TypeDesc::UINT16)
      write_image(m, c.w, c.h, c.channels, c.type,
                  std::vector<std::uint16_t>(std::size_t(c.w) * c.h * c.channels, 1));
    else
      write_image(m, c.w, c.h, c.channels, c.type,
                  std::vector<std::uint8_t>(std::size_t(c.w) * c.h * c.channels, 1));
    auto o = options();
    o.materials_path = m;
    auto hf = io::load_image(h, o);
    ASSERT_FALSE(hf) << m;
    EXPECT_TRUE(contains(hf.error().message, "material image '" + m + "'")) << hf.error().message;
    EXPECT_TRUE(contains(hf.error().message, c.expect)) << hf.error().message;
  }
  auto o = options();
  o.materials_path = tmp_path("missing.png");
  auto hf = io::load_image(h, o);
  ASSERT_FALSE(hf);
  EXPECT_TRUE(contains(hf.error().message, "no such file")) << hf.error().message;
}

// ---- bad input ----------------------------------------------------------------------------------

TEST(IoBadInput, MissingFileAndDirectory) {
  const auto path = tmp_path("does_not_exist.png");
  auto a = io::load_image(path, options());
  ASSERT_FALSE(a);
  EXPECT_EQ(a.error().message, "heightmap '" + path + "': no such file");
  auto b = io::load_raw(path, {2, 2, io::RawType::kU16}, options());
  ASSERT_FALSE(b);
  EXPECT_EQ(b.error().message, "heightmap '" + path + "': no such file");
  auto c = io::load_image(RIDGELINE_TEST_TMP, options());
  ASSERT_FALSE(c);
  EXPECT_TRUE(contains(c.error().message, "is a directory")) << c.error().message;
}

TEST(IoBadInput, NotAnImage) {
  const auto path = tmp_path("garbage.png");
  write_bytes(path, std::vector<char>(300, 'x'));
  auto hf = io::load_image(path, options());
  ASSERT_FALSE(hf);
  EXPECT_TRUE(contains(hf.error().message, "heightmap '" + path + "': not a readable image"))
      << hf.error().message;
  const auto empty = tmp_path("empty.tif");
  write_bytes(empty, {});
  auto e = io::load_image(empty, options());
  ASSERT_FALSE(e);
  EXPECT_TRUE(contains(e.error().message, "heightmap '" + empty + "'")) << e.error().message;
}

TEST(IoBadInput, TruncatedFilesAreRefused) {
  // Noise does not compress, so cutting the file in half removes pixel data, not just padding.
  const int w = 64, h = 64;
  auto values = pattern(std::size_t(w) * h, 65536, 3);
  std::vector<std::uint16_t> px16(values.begin(), values.end());
  std::vector<float> pxf(values.begin(), values.end());
  for (const char* ext : {"png", "tif", "exr"}) {
    const auto path = tmp_path(std::string("t.") + ext);
    if (std::string(ext) == "exr")
      write_image(path, w, h, 1, OIIO::TypeDesc::FLOAT, pxf);
    else
      write_image(path, w, h, 1, OIIO::TypeDesc::UINT16, px16);
    auto bytes = read_bytes(path);
    ASSERT_GT(bytes.size(), 4000u) << ext;
    bytes.resize(bytes.size() / 2);
    write_bytes(path, bytes);
    auto hf = io::load_image(path, options());
    ASSERT_FALSE(hf) << ext << ": a truncated file loaded";
    EXPECT_TRUE(contains(hf.error().message, "heightmap '" + path + "'")) << hf.error().message;
  }
}

TEST(IoBadInput, CorruptPngDataIsRefused) {
  const int w = 64, h = 64;
  auto values = pattern(std::size_t(w) * h, 65536, 5);
  std::vector<std::uint16_t> px(values.begin(), values.end());
  const auto path = tmp_path("c.png");
  write_image(path, w, h, 1, OIIO::TypeDesc::UINT16, px);
  auto bytes = read_bytes(path);
  for (std::size_t k = bytes.size() / 2; k < bytes.size() / 2 + 64; ++k) bytes[k] ^= 0x5a;
  write_bytes(path, bytes);
  testing::internal::CaptureStderr();
  auto hf = io::load_image(path, options());
  const std::string printed = testing::internal::GetCapturedStderr();
  ASSERT_FALSE(hf) << "a corrupt PNG loaded";
  EXPECT_TRUE(contains(hf.error().message,
                       "heightmap '" + path + "': corrupt PNG file: chunk 'IDAT' at byte "))
      << hf.error().message;
  EXPECT_TRUE(contains(hf.error().message, "fails its CRC check")) << hf.error().message;
  EXPECT_EQ(printed, "") << "printed beside the error";
}

// A PNG cut short anywhere is refused with one message naming the chunk where it ends, and
// nothing is printed beside it (libpng prints its own line for a read error it meets).
TEST(IoBadInput, ATruncatedPngIsOneMessageAndNothingPrinted) {
  const auto full = read_bytes(std::string(RIDGELINE_TEST_DATA) + "/ramp16.png");
  ASSERT_GT(full.size(), 60u);
  for (std::size_t n = 8; n < full.size(); ++n) {
    const auto path = tmp_path("cut.png");
    write_bytes(path, std::vector<char>(full.begin(), full.begin() + std::ptrdiff_t(n)));
    testing::internal::CaptureStderr();
    auto hf = io::load_image(path, options());
    const std::string printed = testing::internal::GetCapturedStderr();
    ASSERT_FALSE(hf) << n << " of " << full.size() << " bytes loaded";
    const std::string& m = hf.error().message;
    EXPECT_EQ(m.rfind("heightmap '" + path + "': truncated PNG file: ", 0), 0u) << m;
    EXPECT_EQ(m.find("truncated", m.find("truncated") + 1), std::string::npos) << m;
    EXPECT_EQ(printed, "") << n << " bytes: printed beside the error";
  }
}

TEST(IoBadInput, ColourImageNeedsAChannel) {
  // RGB: R = k, G = 1000 + k, B = 2000 + k.
  const int w = 3, h = 2;
  std::vector<std::uint16_t> px;
  for (int k = 0; k < w * h; ++k)
    for (int c = 0; c < 3; ++c) px.push_back(static_cast<std::uint16_t>(1000 * c + k));
  const auto path = tmp_path("rgb.png");
  write_image(path, w, h, 3, OIIO::TypeDesc::UINT16, px);
  auto refused = io::load_image(path, options());
  ASSERT_FALSE(refused);
  EXPECT_TRUE(contains(refused.error().message, "heightmap '" + path + "': 3 channels (R, G, B)"))
      << refused.error().message;

  auto o = options();
  o.channel = 1;
  auto g = io::load_image(path, o);
  ASSERT_TRUE(g) << g.error().message;
  for (int k = 0; k < w * h; ++k) EXPECT_EQ(locals(*g)[k], float(1000 + k));

  o.channel = 3;
  auto bad = io::load_image(path, o);
  ASSERT_FALSE(bad);
  EXPECT_TRUE(contains(bad.error().message, "channel 3 requested but the image has 3 channels"))
      << bad.error().message;
}

TEST(IoBadInput, GreyAlphaUsesGreyAndSaysSo) {
  // Alpha 0 on some pixels: the grey values must come through unpremultiplied.
  const std::vector<std::uint8_t> px = {10, 255, 20, 0, 30, 128, 40, 0};
  const auto path = tmp_path("ya.png");
  write_image(path, 2, 2, 2, OIIO::TypeDesc::UINT8, px);
  LogCapture log;
  auto hf = io::load_image(path, options());
  ASSERT_TRUE(hf) << hf.error().message;
  EXPECT_EQ(locals(*hf), (std::vector<float>{10, 20, 30, 40}));
  ASSERT_EQ(log.messages.size(), 1u);
  EXPECT_TRUE(contains(log.messages[0], "alpha")) << log.messages[0];
  EXPECT_TRUE(contains(log.messages[0], path)) << log.messages[0];
}

TEST(IoBadInput, TooNarrowImages) {
  for (auto [w, h] : {std::pair{1, 5}, std::pair{5, 1}}) {
    const auto path = tmp_path(std::to_string(w) + "x" + std::to_string(h) + ".png");
    write_image(path, w, h, 1, OIIO::TypeDesc::UINT8, std::vector<std::uint8_t>(5, 1));
    auto hf = io::load_image(path, options());
    ASSERT_FALSE(hf);
    EXPECT_EQ(hf.error().message, "heightmap '" + path + "': " + std::to_string(w) + " x " +
                                      std::to_string(h) + " samples; need at least 2 x 2");
  }
  auto r = io::parse_raw({}, {0, 7, io::RawType::kU16}, options(), "raw");
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().message, "raw: 0 x 7 samples; need at least 2 x 2");
}

TEST(IoBadInput, SizeCapIsCheckedBeforeReading) {
  const auto path = tmp_path("h.png");
  write_image(path, 11, 10, 1, OIIO::TypeDesc::UINT8, std::vector<std::uint8_t>(110, 1));
  auto o = options();
  o.placement.max_samples = 109;
  auto hf = io::load_image(path, o);
  ASSERT_FALSE(hf);
  EXPECT_TRUE(contains(hf.error().message, "11 x 10 = 110 samples exceeds the limit of 109"))
      << hf.error().message;
  o.placement.max_samples = 110;
  EXPECT_TRUE(io::load_image(path, o));
}

TEST(IoBadInput, HugeDeclaredPngSizeIsRefusedWithoutAllocating) {
  // A valid 2 x 2 PNG whose IHDR claims 200000 x 150000 pixels (CRC fixed so the header parses).
  // Allocating that would need 60 GB; the sanitizer build would abort on the attempt.
  const auto path = tmp_path("huge.png");
  write_image(path, 2, 2, 1, OIIO::TypeDesc::UINT16, std::vector<std::uint16_t>{1, 2, 3, 4});
  auto bytes = read_bytes(path);
  ASSERT_EQ(std::string(bytes.begin() + 12, bytes.begin() + 16), "IHDR");
  put_be32(bytes, 16, 200000);
  put_be32(bytes, 20, 150000);
  put_be32(bytes, 29, crc32(reinterpret_cast<const unsigned char*>(bytes.data()) + 12, 17));
  write_bytes(path, bytes);
  auto hf = io::load_image(path, options());
  ASSERT_FALSE(hf);
  EXPECT_TRUE(contains(hf.error().message, "heightmap '" + path +
                                               "': 200000 x 150000 = 30000000000 samples exceeds "
                                               "the limit of 268468225 samples (HeightfieldDesc::max_samples)"))
      << hf.error().message;
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

TEST(IoBadInput, NonFiniteSamplesAreRefusedOrFilled) {
  std::vector<float> px = {1, 2, 3, 4, 5, 6, 7, 8, 9};
  px[4] = std::numeric_limits<float>::quiet_NaN();  // sample (1, 1)
  px[8] = std::numeric_limits<float>::infinity();   // sample (2, 2)
  for (const char* ext : {"h.tif", "h.exr"}) {
    const auto path = tmp_path(ext);
    write_image(path, 3, 3, 1, OIIO::TypeDesc::FLOAT, px);
    auto refused = io::load_image(path, options());
    ASSERT_FALSE(refused) << ext;
    EXPECT_TRUE(contains(refused.error().message, "heightmap '" + path + "': sample (1, 1) is nan"))
        << refused.error().message;

    auto o = options();
    o.placement.fill = FillPolicy::kNearest;
    auto filled = io::load_image(path, o);
    ASSERT_TRUE(filled) << filled.error().message;
    EXPECT_EQ(filled->filled_samples(), 2u);
    const auto l = locals(*filled);
    for (float v : l) EXPECT_TRUE(std::isfinite(v));
    // (1, 1) takes its first 4-neighbour in breadth-first order from the valid samples: (1, 0).
    EXPECT_EQ(l[4], 2.0f);
    EXPECT_TRUE(l[8] == 6.0f || l[8] == 8.0f) << l[8];
  }
}

TEST(IoBadInput, NoDataIsRefusedOrFilled) {
  const std::vector<std::uint16_t> px = {100, 200, 0, 400, 500, 0};  // 0 = no data
  const auto path = tmp_path("h.png");
  write_image(path, 3, 2, 1, OIIO::TypeDesc::UINT16, px);
  auto o = options();
  o.placement.nodata = 0.0;
  auto refused = io::load_image(path, o);
  ASSERT_FALSE(refused);
  EXPECT_TRUE(contains(refused.error().message,
                       "heightmap '" + path + "': sample (2, 0) is 0 (the no-data value)"))
      << refused.error().message;

  o.placement.fill = FillPolicy::kConstant;
  o.placement.fill_constant = 7.0;
  o.placement.height_scale = 2.0;
  auto filled = io::load_image(path, o);
  ASSERT_TRUE(filled) << filled.error().message;
  EXPECT_EQ(filled->filled_samples(), 2u);
  EXPECT_EQ(locals(*filled), (std::vector<float>{200, 400, 14, 800, 1000, 14}));

  // Raw files go through the same policy.
  const auto raw = tmp_path("h.raw");
  write_bytes(raw, {100, 0, 0, 0, 50, 0, 60, 0});
  o.placement.fill = FillPolicy::kNearest;
  o.placement.height_scale = 1.0;
  auto r = io::load_raw(raw, {2, 2, io::RawType::kU16}, o);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(locals(*r), (std::vector<float>{100, 100, 50, 60}));
}

TEST(IoBadInput, BadPlacementIsRefused) {
  const auto path = tmp_path("h.png");
  write_image(path, 2, 2, 1, OIIO::TypeDesc::UINT8, std::vector<std::uint8_t>{1, 2, 3, 4});
  auto o = options();
  o.placement.spacing_z = std::numeric_limits<double>::quiet_NaN();
  auto hf = io::load_image(path, o);
  ASSERT_FALSE(hf);
  EXPECT_EQ(hf.error().message,
            "heightmap '" + path + "': spacing z is nan; need a finite value > 0");
  o = options();
  o.placement.height_scale = 0.0;
  auto raw = io::parse_raw(std::vector<std::byte>(8), {2, 2, io::RawType::kU16}, o, "r");
  ASSERT_FALSE(raw);
  EXPECT_EQ(raw.error().message, "r: height scale is 0; need a finite value > 0");
}

// ---- GeoTIFF no-data tag and the height limit ---------------------------------------------------

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

TEST(IoBadInput, HeightsBeyondTheLimitAreRefusedNamingTheSample) {
  auto f32 = [](const std::vector<float>& f) {
    std::vector<char> b;
    for (float v : f) {
      std::uint32_t u;
      std::memcpy(&u, &v, 4);
      for (int k = 0; k < 4; ++k) b.push_back(static_cast<char>(u >> (8 * k)));
    }
    return b;
  };
  const auto path = tmp_path("huge.r32");
  write_bytes(path, f32({1, 2, 3e38f, -3e38f}));
  auto r = io::load_raw(path, {2, 2, io::RawType::kF32}, options());
  ASSERT_FALSE(r);
  EXPECT_TRUE(contains(r.error().message, "sample (0, 1) = 3e+38")) << r.error().message;
  EXPECT_TRUE(contains(r.error().message, "+-100000 m limit")) << r.error().message;

  // The limit applies after scaling, relative to the offset: 99,999 m passes, 100,001 m not.
  write_bytes(path, f32({1, 2, 9999.9f, 0}));
  auto o = options();
  o.placement.height_scale = 10;
  o.placement.height_offset = 1e6;
  auto ok = io::load_raw(path, {2, 2, io::RawType::kF32}, o);
  ASSERT_TRUE(ok) << ok.error().message;
  write_bytes(path, f32({1, 2, -10000.1f, 0}));
  auto bad = io::load_raw(path, {2, 2, io::RawType::kF32}, o);
  ASSERT_FALSE(bad);
  EXPECT_TRUE(contains(bad.error().message, "sample (0, 1)")) << bad.error().message;

  // GDAL's float no-data value (-FLT_MAX) is missing data, not a height: filled, then fine.
  write_bytes(path, f32({1, 2, -3.4028234663852886e+38f, 4}));
  o = options();
  o.placement.nodata = -3.4028234663852886e+38;
  o.placement.fill = FillPolicy::kNearest;
  auto filled = io::load_raw(path, {2, 2, io::RawType::kF32}, o);
  ASSERT_TRUE(filled) << filled.error().message;
  EXPECT_EQ(locals(*filled), (std::vector<float>{1, 2, 1, 4}));
}

TEST(IoBadInput, MapsMostlyFilledFromNoDataAreWarnedAbout) {
  // 20 samples, value 0 = no-data: one filled (5 %) is quiet, two (10 %) are warned about.
  auto raw = [](int missing) {
    std::vector<std::byte> b;
    for (int k = 0; k < 20; ++k) {
      const int v = k < missing ? 0 : 100 + k;
      b.push_back(std::byte(v & 0xff));
      b.push_back(std::byte(v >> 8));
    }
    return b;
  };
  auto o = options();
  o.placement.nodata = 0;
  o.placement.fill = FillPolicy::kNearest;
  {
    LogCapture log;
    io::LoadReport report;
    auto hf = io::parse_raw(raw(1), {5, 4, io::RawType::kU16}, o, "r", &report);
    ASSERT_TRUE(hf) << hf.error().message;
    EXPECT_EQ(hf->filled_samples(), 1u);
    EXPECT_TRUE(log.messages.empty()) << log.messages[0];
    EXPECT_TRUE(report.warnings.empty());
    EXPECT_EQ(report.pixel_type, "u16");
  }
  LogCapture log;
  io::LoadReport report;
  auto hf = io::parse_raw(raw(2), {5, 4, io::RawType::kU16}, o, "r", &report);
  ASSERT_TRUE(hf) << hf.error().message;
  ASSERT_EQ(log.messages.size(), 1u);
  EXPECT_EQ(log.messages[0],
            "r: 2 of 20 samples (10.0 %) are filled from no-data by the nearest fill policy: that "
            "part of the terrain is invented, not measured");
  ASSERT_EQ(report.warnings.size(), 1u);
  EXPECT_TRUE(contains(report.warnings[0], "2 of 20 samples")) << report.warnings[0];
}

// ---- GeoTIFF placement
// ---------------------------------------------------------------------------

namespace {

/// A TIFF tag for tiff_with_tags: numbers of a numeric type (3 SHORT, 4 LONG, 12 DOUBLE) or the
/// text of an ASCII one (type 2).
struct Tag {
  std::uint16_t tag, type;
  std::vector<double> values;
  std::string text = {};
  std::uint32_t offset_override = 0;  ///< nonzero: written as the value's offset instead
};

Tag pixel_scale(double sx, double sy) {
  return {33550, 12, {sx, sy, 0}};
}
Tag tiepoint(double i, double j, double x, double y) {
  return {33922, 12, {i, j, 0, x, y, 0}};
}
/// A GeoKeyDirectory of keys whose values sit in the directory itself (location 0).
Tag geokeys(const std::vector<std::pair<int, int>>& keys) {
  Tag t{34735, 3, {1, 1, 0, double(keys.size())}};
  for (auto [k, v] : keys) t.values.insert(t.values.end(), {double(k), 0, 1, double(v)});
  return t;
}

/// An uncompressed single-strip int16 TIFF of w x h samples, little- or big-endian, written byte
/// by byte with the baseline tags plus `extra` (OpenImageIO cannot write GeoTIFF tags).
std::vector<char> tiff_with_tags(int w, int h, const std::vector<std::int16_t>& v,
                                 std::vector<Tag> extra, bool big_endian = false) {
  const std::uint32_t bytes = static_cast<std::uint32_t>(v.size() * 2);
  std::vector<Tag> tags = {
      {256, 3, {double(w)}}, {257, 3, {double(h)}}, {258, 3, {16}},
      {259, 3, {1}},         {262, 3, {1}},         {273, 4, {0}},  // strip offset: set below
      {277, 3, {1}},         {278, 3, {double(h)}}, {279, 4, {double(bytes)}},
      {339, 3, {2}}};
  tags.insert(tags.end(), extra.begin(), extra.end());
  std::sort(tags.begin(), tags.end(), [](const Tag& a, const Tag& b) { return a.tag < b.tag; });
  auto size_of = [](const Tag& t) {
    const std::size_t n = t.type == 2 ? t.text.size() + 1 : t.values.size();
    return n * (t.type == 2 ? 1 : t.type == 3 ? 2 : t.type == 4 ? 4 : 8);
  };
  std::vector<char> b;
  auto put = [&](std::uint64_t x, int n) {
    for (int k = 0; k < n; ++k) b.push_back(char(x >> (8 * (big_endian ? n - 1 - k : k)) & 0xff));
  };
  auto put_value = [&](const Tag& t, std::size_t k) {
    if (t.type == 3) put(std::uint64_t(t.values[k]), 2);
    if (t.type == 4) put(std::uint64_t(t.values[k]), 4);
    if (t.type == 12) {
      std::uint64_t u;
      std::memcpy(&u, &t.values[k], 8);
      put(u, 8);
    }
  };
  // Data blocks after the IFD, then the pixels.
  const std::uint32_t ifd_end = 8 + 2 + 12 * std::uint32_t(tags.size()) + 4;
  std::vector<std::uint32_t> at(tags.size());
  std::uint32_t next = ifd_end;
  for (std::size_t k = 0; k < tags.size(); ++k) {
    if (size_of(tags[k]) > 4) {
      at[k] = next;
      next = (next + std::uint32_t(size_of(tags[k])) + 1) & ~1u;
    }
  }
  const std::uint32_t pixels_at = next;
  for (Tag& t : tags)
    if (t.tag == 273) t.values = {double(pixels_at)};
  b = big_endian ? std::vector<char>{'M', 'M'} : std::vector<char>{'I', 'I'};
  put(42, 2);
  put(8, 4);
  put(tags.size(), 2);
  for (std::size_t k = 0; k < tags.size(); ++k) {
    const Tag& t = tags[k];
    put(t.tag, 2);
    put(t.type, 2);
    put(t.type == 2 ? t.text.size() + 1 : t.values.size(), 4);
    if (size_of(t) > 4) {
      put(t.offset_override ? t.offset_override : at[k], 4);
    } else {
      const std::size_t start = b.size();
      if (t.type == 2) {
        for (char c : t.text) b.push_back(c);
        b.push_back(0);
      } else {
        for (std::size_t i = 0; i < t.values.size(); ++i) put_value(t, i);
      }
      b.resize(start + 4, 0);
    }
  }
  put(0, 4);  // no next IFD
  for (std::size_t k = 0; k < tags.size(); ++k) {
    if (size_of(tags[k]) <= 4) continue;
    b.resize(at[k], 0);
    if (tags[k].type == 2) {
      for (char c : tags[k].text) b.push_back(c);
      b.push_back(0);
    } else {
      for (std::size_t i = 0; i < tags[k].values.size(); ++i) put_value(tags[k], i);
    }
  }
  b.resize(pixels_at, 0);
  for (std::int16_t s : v) put(static_cast<std::uint16_t>(s), 2);
  return b;
}

const std::vector<std::int16_t> kSix = {10, 20, 30, 40, 50, 60};  // 3 x 2 samples

io::LoadOptions from_file() {
  io::LoadOptions o;
  o.spacing_from_file = true;
  o.origin_from_file = true;
  return o;
}

}  // namespace

TEST(IoGeoTiff, ProjectedMetresGiveSpacingAndOrigin) {
  // UTM 33N (EPSG 32633), 30 m pixels, the tie point at the corner of pixel (0, 0), PixelIsArea.
  const std::vector<Tag> geo = {pixel_scale(30, 30), tiepoint(0, 0, 500000, 4100000),
                                geokeys({{1024, 1}, {1025, 1}, {3072, 32633}, {3076, 9001}})};
  for (bool big_endian : {false, true}) {
    const auto path = tmp_path(big_endian ? "utm_be.tif" : "utm.tif");
    write_bytes(path, tiff_with_tags(3, 2, kSix, geo, big_endian));
    LogCapture log;
    io::LoadReport report;
    auto hf = io::load_image(path, from_file(), &report);
    ASSERT_TRUE(hf) << hf.error().message;
    EXPECT_EQ(locals(*hf), (std::vector<float>{10, 20, 30, 40, 50, 60}));
    EXPECT_EQ(hf->spacing_x(), 30.0);
    EXPECT_EQ(hf->spacing_z(), 30.0);
    // Sample (0, 0) is the centre of pixel (0, 0): 15 m east and 15 m south of the tie point;
    // z = -northing.
    EXPECT_EQ(hf->origin_x(), 500015.0);
    EXPECT_EQ(hf->origin_z(), -4099985.0);
    EXPECT_EQ(report.pixel_type, "int16");
    ASSERT_TRUE(report.file_placement);
    EXPECT_FALSE(report.file_placement->geographic);
    EXPECT_TRUE(report.spacing_from_file);
    EXPECT_TRUE(report.origin_from_file);
    EXPECT_TRUE(report.warnings.empty());
    ASSERT_EQ(log.messages.size(), 1u);
    EXPECT_TRUE(contains(log.messages[0], "GeoTIFF projected (EPSG 32633), metres, PixelIsArea"))
        << log.messages[0];
    EXPECT_TRUE(contains(log.messages[0], "spacing and origin taken from the file"))
        << log.messages[0];
  }
}

TEST(IoGeoTiff, PixelIsPointTiesTheSampleItselfAtAnyRasterPoint) {
  // The tie point at raster (2, 1) = sample (2, 1): sample (0, 0) lies 2 columns west and one
  // row north of it.
  const auto path = tmp_path("point.tif");
  write_bytes(path, tiff_with_tags(3, 2, kSix,
                                   {pixel_scale(10, 20), tiepoint(2, 1, 1000, 5000),
                                    geokeys({{1024, 1}, {1025, 2}, {3076, 9001}})}));
  auto hf = io::load_image(path, from_file());
  ASSERT_TRUE(hf) << hf.error().message;
  EXPECT_EQ(hf->spacing_x(), 10.0);
  EXPECT_EQ(hf->spacing_z(), 20.0);
  EXPECT_EQ(hf->origin_x(), 980.0);
  EXPECT_EQ(hf->origin_z(), -5020.0);
}

TEST(IoGeoTiff, FeetAreConvertedToMetres) {
  const auto path = tmp_path("feet.tif");
  for (auto [code, metres] : {std::pair{9002, 0.3048}, std::pair{9003, 1200.0 / 3937.0}}) {
    write_bytes(path, tiff_with_tags(3, 2, kSix,
                                     {pixel_scale(100, 50), tiepoint(0, 0, 1000, 2000),
                                      geokeys({{1024, 1}, {1025, 2}, {3076, code}})}));
    auto hf = io::load_image(path, from_file());
    ASSERT_TRUE(hf) << hf.error().message;
    EXPECT_DOUBLE_EQ(hf->spacing_x(), 100 * metres);
    EXPECT_DOUBLE_EQ(hf->spacing_z(), 50 * metres);
    EXPECT_DOUBLE_EQ(hf->origin_x(), 1000 * metres);
    EXPECT_DOUBLE_EQ(hf->origin_z(), -2000 * metres);
  }
}

TEST(IoGeoTiff, AnAxisAlignedModelTransformationIsAPixelScaleAndTiePoint) {
  const auto path = tmp_path("xform.tif");
  // x = 5 u + 100, y = -8 v + 900 (rows run south).
  const Tag m{34264, 12, {5, 0, 0, 100, 0, -8, 0, 900, 0, 0, 0, 0, 0, 0, 0, 1}};
  write_bytes(path, tiff_with_tags(3, 2, kSix, {m, geokeys({{1024, 1}, {1025, 1}})}));
  LogCapture log;
  auto hf = io::load_image(path, from_file());
  ASSERT_TRUE(hf) << hf.error().message;
  EXPECT_EQ(hf->spacing_x(), 5.0);
  EXPECT_EQ(hf->spacing_z(), 8.0);
  EXPECT_EQ(hf->origin_x(), 102.5);
  EXPECT_EQ(hf->origin_z(), -896.0);
  ASSERT_EQ(log.messages.size(), 1u);
  EXPECT_TRUE(contains(log.messages[0], "metres assumed (no ProjLinearUnitsGeoKey)"))
      << log.messages[0];
}

TEST(IoGeoTiff, TheGivenPlacementWinsWhereTheOptionsSaySo) {
  const auto path = tmp_path("given.tif");
  write_bytes(path, tiff_with_tags(3, 2, kSix,
                                   {pixel_scale(30, 30), tiepoint(0, 0, 500000, 4100000),
                                    geokeys({{1024, 1}, {3076, 9001}})}));
  {  // The defaults: the file's placement is reported, not used.
    LogCapture log;
    io::LoadReport report;
    auto o = options();
    o.placement.spacing_x = 2;
    o.placement.spacing_z = 3;
    auto hf = io::load_image(path, o, &report);
    ASSERT_TRUE(hf) << hf.error().message;
    EXPECT_EQ(hf->spacing_x(), 2.0);
    EXPECT_EQ(hf->spacing_z(), 3.0);
    EXPECT_EQ(hf->origin_x(), 0.0);
    ASSERT_TRUE(report.file_placement);
    EXPECT_EQ(report.file_placement->spacing_x, 30.0);
    EXPECT_FALSE(report.spacing_from_file);
    EXPECT_FALSE(report.origin_from_file);
    ASSERT_EQ(log.messages.size(), 1u);
    EXPECT_TRUE(contains(log.messages[0], "not used: the given spacing 2 x 3 m and origin 0, 0"))
        << log.messages[0];
  }
  // The origin from the file, the spacing as given.
  auto o = from_file();
  o.spacing_from_file = false;
  o.placement.spacing_x = o.placement.spacing_z = 7;
  io::LoadReport report;
  auto hf = io::load_image(path, o, &report);
  ASSERT_TRUE(hf) << hf.error().message;
  EXPECT_EQ(hf->spacing_x(), 7.0);
  EXPECT_EQ(hf->origin_x(), 500015.0);
  EXPECT_FALSE(report.spacing_from_file);
  EXPECT_TRUE(report.origin_from_file);
}

TEST(IoGeoTiff, GeographicDegreesBecomeMetresAtTheCentreLatitude) {
  // WGS 84's radii of curvature in the meridian (M) and the prime vertical (N), as tables give
  // them: at 45 degrees 6,367,381.816 m and 6,388,838.290 m; at the equator 6,335,439.327 m and
  // 6,378,137 m. A degree is M * pi / 180 of latitude and N cos(lat) * pi / 180 of longitude.
  const double rad = std::acos(-1.0) / 180;
  struct Case {
    double centre, lat_m, lon_m;
  } cases[] = {{45, 6367381.816 * rad, 6388838.290 * std::sqrt(0.5) * rad},
               {0, 6335439.327 * rad, 6378137.0 * rad}};
  for (const Case& c : cases) {
    // Two rows of 1/120-degree pixels whose centres straddle c.centre (PixelIsArea: the tie
    // point is the top edge, one pixel above the centre line).
    const double d = 1.0 / 120;
    const auto path = tmp_path("geographic.tif");
    write_bytes(path,
                tiff_with_tags(3, 2, kSix,
                               {pixel_scale(d, d), tiepoint(0, 0, 6, c.centre + d),
                                geokeys({{1024, 2}, {1025, 1}, {2048, 4326}, {2054, 9102}})}));
    LogCapture log;
    io::LoadReport report;
    auto hf = io::load_image(path, from_file(), &report);
    ASSERT_TRUE(hf) << hf.error().message;
    EXPECT_NEAR(hf->spacing_x(), c.lon_m * d, 1e-7 * c.lon_m * d) << c.centre;
    EXPECT_NEAR(hf->spacing_z(), c.lat_m * d, 1e-7 * c.lat_m * d) << c.centre;
    // Degrees give no origin in metres: it stays where the caller put it.
    EXPECT_EQ(hf->origin_x(), 0.0);
    EXPECT_EQ(hf->origin_z(), 0.0);
    ASSERT_TRUE(report.file_placement);
    EXPECT_TRUE(report.file_placement->geographic);
    EXPECT_FALSE(report.file_placement->has_origin);
    EXPECT_TRUE(report.spacing_from_file);
    EXPECT_FALSE(report.origin_from_file);
    ASSERT_EQ(log.messages.size(), 1u);
    EXPECT_TRUE(contains(log.messages[0], "GeoTIFF geographic (EPSG 4326)")) << log.messages[0];
    EXPECT_TRUE(contains(log.messages[0],
                         c.centre == 0 ? "centre latitude 0.000 N" : "centre latitude 45.000 N"))
        << log.messages[0];
    EXPECT_TRUE(contains(log.messages[0], "degrees give no origin in metres")) << log.messages[0];
  }
}

TEST(IoGeoTiff, UnusablePlacementTagsAreIgnoredWithAWarning) {
  const Tag keys = geokeys({{1024, 1}, {3076, 9001}});
  struct Case {
    const char* what;
    std::vector<Tag> tags;
    const char* expect;
  } cases[] = {
      {"no geo keys", {pixel_scale(30, 30), tiepoint(0, 0, 0, 0)}, "the units are unknown"},
      {"rotated",
       {Tag{34264, 12, {5, 1, 0, 0, 1, -5, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1}}, keys},
       "rotates or shears"},
      {"short transformation", {Tag{34264, 12, {5, 0, 0}}, keys}, "holds 3 values (need 16)"},
      {"scale alone", {pixel_scale(30, 30), keys}, "without ModelTiepoint"},
      {"tie points alone", {tiepoint(0, 0, 0, 0), keys}, "a grid of tie points"},
      {"negative scale", {pixel_scale(30, -30), tiepoint(0, 0, 0, 0), keys}, "need positive"},
      {"zero scale", {pixel_scale(0, 30), tiepoint(0, 0, 0, 0), keys}, "need positive"},
      {"pixels below a micrometre",
       {pixel_scale(30, 1e-7), tiepoint(0, 0, 0, 0), keys},
       "pixel size 30 x 1e-07 m is below 1e-6 m"},
      {"short tie point",
       {pixel_scale(30, 30), Tag{33922, 12, {0, 0, 0, 1}}, keys},
       "holds 4 values (need 6 per tie point)"},
      {"unknown unit",
       {pixel_scale(30, 30), tiepoint(0, 0, 0, 0), geokeys({{1024, 1}, {3076, 9999}})},
       "linear unit EPSG 9999 is not known"},
      {"geocentric",
       {pixel_scale(30, 30), tiepoint(0, 0, 0, 0), geokeys({{1024, 3}})},
       "geocentric"},
      {"no model type",
       {pixel_scale(30, 30), tiepoint(0, 0, 0, 0), geokeys({{1025, 1}})},
       "no model type"},
      {"bad raster type",
       {pixel_scale(30, 30), tiepoint(0, 0, 0, 0), geokeys({{1024, 1}, {1025, 7}})},
       "GTRasterTypeGeoKey 7"},
      {"latitude beyond the pole",
       {pixel_scale(1, 1), tiepoint(0, 0, 0, 95), geokeys({{1024, 2}})},
       "outside -90 .. 90"},
      {"keys claimed but absent",
       {pixel_scale(30, 30), tiepoint(0, 0, 0, 0), Tag{34735, 3, {1, 1, 0, 5, 1024, 0, 1, 1}}},
       "claims 5 keys but holds 8 values"},
      {"key in missing double parameters",
       {pixel_scale(30, 30), tiepoint(0, 0, 0, 0),
        Tag{34735, 3, {1, 1, 0, 2, 1024, 0, 1, 1, 3076, 34736, 1, 4}}},
       "refers to GeoDoubleParams entry 4"},
      {"directory of doubles",
       {pixel_scale(30, 30), tiepoint(0, 0, 0, 0), Tag{34735, 12, {1, 1, 0, 1, 1024, 0, 1, 1}}},
       "need 3, SHORT"},
      {"scale outside the file",
       {Tag{33550, 12, {30, 30, 0}, "", 1u << 30}, tiepoint(0, 0, 0, 0), keys},
       "lies outside the file"},
  };
  for (const Case& c : cases) {
    const auto path = tmp_path("bad.tif");
    write_bytes(path, tiff_with_tags(3, 2, kSix, c.tags));
    LogCapture log;
    io::LoadReport report;
    auto o = from_file();
    o.placement.spacing_x = o.placement.spacing_z = 2;
    auto hf = io::load_image(path, o, &report);
    ASSERT_TRUE(hf) << c.what << ": " << hf.error().message;
    EXPECT_EQ(hf->spacing_x(), 2.0) << c.what;
    EXPECT_EQ(hf->origin_x(), 0.0) << c.what;
    EXPECT_FALSE(report.file_placement) << c.what;
    ASSERT_EQ(log.messages.size(), 1u) << c.what;
    EXPECT_TRUE(contains(log.messages[0], "GeoTIFF placement ignored: ")) << log.messages[0];
    EXPECT_TRUE(contains(log.messages[0], c.expect)) << c.what << ": " << log.messages[0];
    EXPECT_TRUE(contains(log.messages[0], "spacing stays 2 x 2 m")) << log.messages[0];
    ASSERT_EQ(report.warnings.size(), 1u) << c.what;
  }
}

// A key whose value sits in GeoDoubleParams (location 34736) names an index into that tag's
// doubles: the last one is read, one past it is refused (never read: the doubles end there).
// Projected metres in a user-defined unit (ProjLinearUnitsGeoKey 32767) whose size in metres
// (ProjLinearUnitSizeGeoKey 3077) is the double at `index` of {1.5, 2.0, 0.25}.
TEST(IoGeoTiff, GeoDoubleParamsAreReadUpToTheirLastEntryAndNoFurther) {
  auto file = [](double index) {
    const Tag dir{34735, 3, {1, 1, 0, 3, 1024, 0, 1, 1, 3076, 0, 1, 32767, 3077, 34736, 1, index}};
    const Tag doubles{34736, 12, {1.5, 2.0, 0.25}};
    return tiff_with_tags(3, 2, kSix,
                          {pixel_scale(30, 20), tiepoint(0, 0, 1000, 2000), dir, doubles});
  };
  {  // The last entry: 0.25 m per unit.
    const auto path = tmp_path("doubles_last.tif");
    write_bytes(path, file(2));
    io::LoadReport report;
    LogCapture log;
    auto hf = io::load_image(path, from_file(), &report);
    ASSERT_TRUE(hf) << hf.error().message;
    ASSERT_TRUE(report.file_placement) << (log.messages.empty() ? "" : log.messages[0]);
    EXPECT_EQ(hf->spacing_x(), 7.5) << "30 units of the double at index 2 (0.25 m)";
    EXPECT_EQ(hf->spacing_z(), 5.0);
    EXPECT_EQ(hf->origin_x(), 253.75);  // (1000 + 15) * 0.25
    EXPECT_EQ(hf->origin_z(), -497.5);  // -(2000 - 10) * 0.25
    EXPECT_TRUE(report.warnings.empty());
  }
  for (const double index : {3.0, 4.0, 65535.0}) {  // one past the last, and further
    const auto path = tmp_path("doubles_past.tif");
    write_bytes(path, file(index));
    io::LoadReport report;
    LogCapture log;
    auto o = from_file();
    o.placement.spacing_x = o.placement.spacing_z = 2;
    auto hf = io::load_image(path, o, &report);
    ASSERT_TRUE(hf) << hf.error().message;
    EXPECT_FALSE(report.file_placement) << "index " << index << " of 3 doubles was read";
    EXPECT_EQ(hf->spacing_x(), 2.0) << "index " << index;
    ASSERT_EQ(log.messages.size(), 1u);
    EXPECT_TRUE(contains(log.messages[0], "geo key 3077 refers to GeoDoubleParams entry " +
                                              std::to_string(int(index)) +
                                              ", which the file lacks"))
        << log.messages[0];
  }
}

TEST(IoGeoTiff, APlacementBeyondTheLimitsIsRefused) {
  // Metres from the file pass the same checks as given ones: a spacing whose extent overflows.
  const auto path = tmp_path("huge.tif");
  write_bytes(path, tiff_with_tags(3, 2, kSix,
                                   {pixel_scale(1e308, 1), tiepoint(0, 0, 0, 0),
                                    geokeys({{1024, 1}, {3076, 9001}})}));
  auto hf = io::load_image(path, from_file());
  ASSERT_FALSE(hf);
  EXPECT_TRUE(contains(hf.error().message, "heightmap '" + path + "'")) << hf.error().message;
}

TEST(IoGeoTiff, ReaderIsBoundedOnEveryTruncation) {
  const std::vector<char> full =
      tiff_with_tags(3, 2, kSix,
                     {pixel_scale(30, 30), tiepoint(0, 0, 500000, 4100000),
                      geokeys({{1024, 1}, {1025, 1}, {3076, 9001}}), Tag{42113, 2, {}, "-9999"}});
  const std::vector<std::uint16_t> wanted = {33550, 33922, 34264, 34735, 34736, 42113};
  for (std::size_t n = 0; n <= full.size(); ++n) {
    io::detail::ReadAt read = [&](std::uint64_t off, std::size_t k, unsigned char* out) {
      EXPECT_LE(off + k, n);
      if (off + k > n) return false;
      std::memcpy(out, full.data() + off, k);
      return true;
    };
    auto r = io::detail::read_tiff_tags(read, n, wanted, io::detail::kMaxTagValues);
    if (n == full.size()) {
      ASSERT_TRUE(r) << r.error().message;
      ASSERT_TRUE(*r);
      ASSERT_EQ((*r)->size(), 4u);
      for (const io::detail::TiffTag& t : **r) EXPECT_TRUE(t.error.empty()) << t.error;
      auto text = io::detail::gdal_nodata_text(**r);
      ASSERT_TRUE(text && *text);
      EXPECT_EQ(**text, "-9999");
    }
  }
}

// Real data: Debian's r-cran-terra ships elev.tif (Luxembourg, 1/120-degree cells, WGS 84) and
// meuse.tif (the Netherlands' RD New projection, 40 m cells). The ctest fixture fetch_terra_data
// fetches them into RIDGELINE_TEST_EXTERNAL_DATA (apt-get download r-cran-terra; dpkg -x); a
// missing file fails the test (it never skips).
std::string terra_file(const char* name) {
  return std::string(RIDGELINE_TEST_EXTERNAL_DATA) + "/terra/usr/lib/R/site-library/terra/ex/" +
         name;
}

TEST(IoGeoTiff, RealGeographicDem) {
  const std::string path = terra_file("elev.tif");
  ASSERT_TRUE(fs::exists(path))
      << path << " is missing: the ctest fixture fetch_terra_data fetches it (apt-get download "
      << "r-cran-terra, dpkg -x into " << RIDGELINE_TEST_EXTERNAL_DATA << "/terra)";
  io::LoadReport report;
  auto o = from_file();
  o.placement.fill = FillPolicy::kNearest;
  LogCapture log;
  auto hf = io::load_image(path, o, &report);
  ASSERT_TRUE(hf) << hf.error().message;
  EXPECT_EQ(hf->width(), 95u);
  EXPECT_EQ(hf->height(), 90u);
  // 1/120 degree at 49.8 N: about 598.8 x 926.7 m.
  EXPECT_NEAR(hf->spacing_x(), 598.8, 0.01 * 598.8);
  EXPECT_NEAR(hf->spacing_z(), 926.7, 0.01 * 926.7);
  EXPECT_EQ(hf->origin_x(), 0.0);
  EXPECT_EQ(hf->origin_z(), 0.0);
  EXPECT_EQ(report.pixel_type, "int16");
  ASSERT_TRUE(report.file_placement);
  EXPECT_TRUE(report.file_placement->geographic);
  // 3,942 of its 8,550 samples are no-data outside the country's border.
  EXPECT_EQ(hf->filled_samples(), 3942u);
  ASSERT_EQ(report.warnings.size(), 1u);
  EXPECT_TRUE(contains(report.warnings[0], "3942 of 8550 samples (46.1 %) are filled"))
      << report.warnings[0];
  EXPECT_EQ(hf->min_local(), 141.0f);
  EXPECT_EQ(hf->max_local(), 547.0f);
}

TEST(IoGeoTiff, RealProjectedDem) {
  const std::string path = terra_file("meuse.tif");
  ASSERT_TRUE(fs::exists(path))
      << path << " is missing: the ctest fixture fetch_terra_data fetches it (apt-get download "
      << "r-cran-terra, dpkg -x into " << RIDGELINE_TEST_EXTERNAL_DATA << "/terra)";
  io::LoadReport report;
  auto o = from_file();
  o.placement.fill = FillPolicy::kNearest;
  auto hf = io::load_image(path, o, &report);
  ASSERT_TRUE(hf) << hf.error().message;
  EXPECT_EQ(hf->width(), 80u);
  EXPECT_EQ(hf->height(), 115u);
  EXPECT_EQ(hf->spacing_x(), 40.0);
  EXPECT_EQ(hf->spacing_z(), 40.0);
  // Tie point (178400, 334000) at the corner of pixel (0, 0); its centre 20 m east and south.
  EXPECT_EQ(hf->origin_x(), 178420.0);
  EXPECT_EQ(hf->origin_z(), -333980.0);
  EXPECT_TRUE(report.origin_from_file);
}
