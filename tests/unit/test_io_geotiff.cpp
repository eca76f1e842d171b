// GeoTIFF placement (module/src/io/geotiff.cpp): projected metres and feet, PixelIsPoint, model
// transformations, degrees converted at the centre latitude, the caller's placement winning,
// unusable tags ignored with a warning, GeoDoubleParams read within bounds, and Debian's
// r-cran-terra rasters (elev.tif, meuse.tif) as real data.
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


// Real data: Debian's r-cran-terra ships elev.tif (Luxembourg, 1/120-degree cells, WGS 84) and
// meuse.tif (the Netherlands' RD New projection, 40 m cells). The ctest fixture fetch_terra_data
// fetches them into RIDGELINE_TEST_EXTERNAL_DATA (apt-get download r-cran-terra; dpkg -x); a
// missing file fails the test (it never skips).
std::string terra_file(const char* name) {
  return std::string(RIDGELINE_TEST_EXTERNAL_DATA) + "/terra/usr/lib/R/site-library/terra/ex/" +
         name;
}


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
