// The image loader and what every loader shares (module/src/io/image_loader.cpp): round trips of
// PNG, TIFF and EXR through OpenImageIO, placement, dispatch by name, materials, channels, and one
// case per kind of bad input (missing files, not images, truncated files, sizes, non-finite and
// no-data samples with the fill policies, heights beyond the limit, mostly filled maps). Test
// images are written with OpenImageIO at test time into RIDGELINE_TEST_TMP.
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

// A file is read by the reader its extension names, or by the one its first bytes name when the
// extension names none of the accepted formats or that reader refuses it.
TEST(IoFormats, AFileIsReadByItsSignatureWhenItsNameSaysNothingOrLies) {
  const std::vector<std::uint16_t> px = {0, 1, 500, 65535, 7, 8};
  const auto png = tmp_path("as_png.png");
  write_image(png, 3, 2, 1, OIIO::TypeDesc::UINT16, px);
  const auto tif = tmp_path("as_tif.tif");
  write_image(tif, 3, 2, 1, OIIO::TypeDesc::UINT16, px);
  const auto pgm = tmp_path("as_pgm.pgm");
  write_image(pgm, 3, 2, 1, OIIO::TypeDesc::UINT16, px);
  const struct {
    std::string from, to;
  } cases[] = {{png, tmp_path("png_named_tif.tif")},
               {tif, tmp_path("tif_named_png.png")},
               {tif, tmp_path("tif_without_extension")},
               {pgm, tmp_path("pgm_named.dat")},
               {png, tmp_path("png_named.RLA")}};
  // The PNG and TIFF give the 16-bit values written (the PGM as OpenImageIO wrote it: 8-bit).
  for (const auto& path : {png, tif}) {
    auto hf = io::load_image(path, options());
    ASSERT_TRUE(hf) << hf.error().message;
    for (std::size_t k = 0; k < px.size(); ++k) EXPECT_EQ(locals(*hf)[k], float(px[k])) << path;
  }
  for (const auto& c : cases) {
    fs::copy_file(c.from, c.to, fs::copy_options::overwrite_existing);
    auto by_name = io::load_image(c.from, options());
    ASSERT_TRUE(by_name) << c.from << ": " << by_name.error().message;
    auto hf = io::load_image(c.to, options());
    ASSERT_TRUE(hf) << c.to << ": " << hf.error().message;
    EXPECT_EQ(locals(*hf), locals(*by_name)) << c.to;
    ASSERT_EQ(locals(*hf).size(), px.size()) << c.to;
  }
}

// OpenImageIO reads some 28 formats; a heightmap is read only by the readers of the listed ones, so
// an image another reader would take (here an RLA file OpenImageIO writes and reads) is refused with
// the list, whatever its name. Debian's OpenImageIO aborts the process in that reader on a crafted
// file (tests/fuzz/corpus/fuzz_image/crash-rla-channel-type-assert).
TEST(IoFormats, OnlyTheListedFormatsReachAReader) {
  const std::vector<std::uint8_t> px = {1, 2, 3, 4, 5, 6};
  const auto rla = tmp_path("h.rla");
  write_image(rla, 3, 2, 1, OIIO::TypeDesc::UINT8, px);
  {
    auto direct = OIIO::ImageInput::open(rla);
    ASSERT_TRUE(direct) << "OpenImageIO cannot read back its own RLA file";
  }
  const auto bare = tmp_path("rla_without_extension");
  fs::copy_file(rla, bare, fs::copy_options::overwrite_existing);
  for (const auto& path : {rla, bare}) {
    auto hf = io::load_image(path, options());
    ASSERT_FALSE(hf) << path;
    EXPECT_EQ(hf.error().message,
              "heightmap '" + path +
                  "': not a readable image: neither its name nor its first bytes are those of a "
                  "PNG, TIFF, OpenEXR, PNM, Radiance HDR, BMP, TGA or JPEG image (a headerless "
                  "raw file needs --raw-size W,H)");
  }
  // JPEG is one of them (8-bit: the raw integers, as PNG).
  const auto jpg = tmp_path("h.jpg");
  const std::vector<std::uint8_t> flat(16 * 16, 200);
  write_image(jpg, 16, 16, 1, OIIO::TypeDesc::UINT8, flat);
  auto hf = io::load_image(jpg, options());
  ASSERT_TRUE(hf) << hf.error().message;
  for (float v : locals(*hf)) EXPECT_NEAR(v, 200.0f, 1.0f);
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

TEST(IoImage, AlphaZeroMarksMissingSamplesThatTheFillPolicyMakesHoles) {
  // 3 x 3 grey + alpha, alpha 0 at the centre sample: the four cells around it are holes.
  std::vector<std::uint8_t> px;
  for (int k = 0; k < 9; ++k) px.insert(px.end(), {std::uint8_t(10 + k), std::uint8_t(k == 4 ? 0 : 255)});
  const auto path = tmp_path("holes_ya.png");
  write_image(path, 3, 3, 2, OIIO::TypeDesc::UINT8, px);
  io::LoadOptions o = options();
  o.alpha_nodata = true;
  o.placement.fill = FillPolicy::kHole;
  auto hf = io::load_image(path, o);
  ASSERT_TRUE(hf) << hf.error().message;
  EXPECT_EQ(hf->hole_cells().size(), 4u);
  EXPECT_EQ(hf->filled_samples(), 1u);
  // Without a fill policy the alpha-marked sample is refused, naming it; without alpha_nodata
  // alpha is ignored; a grey image has no alpha to use.
  o.placement.fill = FillPolicy::kRefuse;
  auto refused = io::load_image(path, o);
  ASSERT_FALSE(refused);
  EXPECT_TRUE(contains(refused.error().message, "sample (1, 1)")) << refused.error().message;
  EXPECT_TRUE(io::load_image(path, options())->hole_cells().empty());
  const auto grey = tmp_path("holes_y.png");
  write_image(grey, 2, 2, 1, OIIO::TypeDesc::UINT8, std::vector<std::uint8_t>{1, 2, 3, 4});
  auto none = io::load_image(grey, o);
  ASSERT_FALSE(none);
  EXPECT_TRUE(contains(none.error().message, "no alpha channel")) << none.error().message;
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
