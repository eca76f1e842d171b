// GeoTIFF placement (geotiff.h). Tag and key numbers from the OGC GeoTIFF standard 1.1
// (ModelPixelScale 33550, ModelTiepoint 33922, ModelTransformation 34264, GeoKeyDirectory 34735,
// GeoDoubleParams 34736; GTModelTypeGeoKey 1024, GTRasterTypeGeoKey 1025, GeographicTypeGeoKey
// 2048, GeogAngularUnitsGeoKey 2054, ProjectedCSTypeGeoKey 3072, ProjLinearUnitsGeoKey 3076,
// ProjLinearUnitSizeGeoKey 3077); unit codes from EPSG.
#include "io/geotiff.h"

#include <cmath>
#include <numbers>

#include "format.h"

namespace ridgeline::io::detail {

namespace {

constexpr int kModelProjected = 1, kModelGeographic = 2, kModelGeocentric = 3;
constexpr int kRasterPixelIsArea = 1, kRasterPixelIsPoint = 2;
constexpr std::uint16_t kKeyModelType = 1024, kKeyRasterType = 1025, kKeyGeographicType = 2048,
                        kKeyAngularUnits = 2054, kKeyProjectedType = 3072, kKeyLinearUnits = 3076,
                        kKeyLinearUnitSize = 3077;
constexpr double kUserDefined = 32767;

// A number for messages: up to 10 significant digits, no exponent for ordinary values.
std::string g(double v) {
  return fmt("%.10g", v);
}

// The keys of a GeoKeyDirectory with their (first) numeric value.
struct GeoKeys {
  std::vector<std::pair<std::uint16_t, double>> keys;
  std::optional<double> get(std::uint16_t id) const {
    for (const auto& [k, v] : keys)
      if (k == id) return v;
    return std::nullopt;
  }
};

// Parses the directory: header (version, revision, minor, count), then count entries of (key,
// location, count, value or index). Location 0: the value itself; 34736: an index into the
// double parameters; 34735: an index into the directory. ASCII keys (34737) are skipped.
Result<GeoKeys> parse_keys(const TiffTag& dir, const TiffTag* doubles) {
  const std::vector<double>& d = dir.numbers;
  if (!dir.error.empty()) return Error{"GeoKeyDirectory tag's " + dir.error};
  // SHORTs, as the standard requires: every value below is then a whole number in 0..65535.
  if (dir.type != 3)
    return Error{"GeoKeyDirectory has TIFF type " + std::to_string(dir.type) + " (need 3, SHORT)"};
  if (d.size() < 4) return Error{"GeoKeyDirectory holds " + std::to_string(d.size()) + " values"};
  if (d[0] != 1) return Error{"GeoKeyDirectory version " + g(d[0]) + " (need 1)"};
  const std::size_t n = static_cast<std::size_t>(d[3]);
  if (4 + 4 * n > d.size())
    return Error{fmt("GeoKeyDirectory claims %zu keys but holds %zu values", n, d.size())};
  GeoKeys out;
  for (std::size_t k = 0; k < n; ++k) {
    const double* e = &d[4 + 4 * k];
    const auto id = static_cast<std::uint16_t>(e[0]);
    const double location = e[1], index = e[3];
    if (location == 0) {
      out.keys.push_back({id, index});
    } else if (location == kTagGeoDoubleParams) {
      if (doubles == nullptr || !doubles->error.empty() || index >= double(doubles->numbers.size()))
        return Error{fmt("geo key %u refers to GeoDoubleParams entry %s, which the file lacks",
                         unsigned(id), g(index).c_str())};
      out.keys.push_back({id, doubles->numbers[std::size_t(index)]});
    } else if (location == kTagGeoKeyDirectory) {
      if (index >= double(d.size()))
        return Error{fmt("geo key %u refers to directory entry %s of %zu", unsigned(id),
                         g(index).c_str(), d.size())};
      out.keys.push_back({id, d[std::size_t(index)]});
    }
  }
  return out;
}

std::string epsg(const char* what, std::optional<double> code) {
  if (!code) return what;
  if (*code == kUserDefined) return std::string(what) + " (user-defined CRS)";
  return fmt("%s (EPSG %s)", what, g(*code).c_str());
}

// Metres per unit for EPSG linear unit codes (those GeoTIFF writers use).
std::optional<double> linear_unit(double code, std::optional<double> custom_size) {
  if (code == 9001) return 1.0;              // metre
  if (code == 9002) return 0.3048;           // international foot
  if (code == 9003) return 1200.0 / 3937.0;  // US survey foot
  if (code == 9036) return 1000.0;           // kilometre
  if (code == kUserDefined && custom_size && std::isfinite(*custom_size) && *custom_size > 0)
    return *custom_size;
  return std::nullopt;
}

// Degrees per unit for EPSG angular unit codes.
std::optional<double> angular_unit(double code) {
  if (code == 9102 || code == 9122) return 1.0;       // degree (9122: supplier to define)
  if (code == 9101) return 180.0 / std::numbers::pi;  // radian
  if (code == 9105) return 0.9;                       // grad
  return std::nullopt;
}

}  // namespace

GeoTiffPlacement geotiff_placement(const std::vector<TiffTag>& tags, std::uint32_t height) {
  GeoTiffPlacement out;
  const TiffTag* scale = find_tag(tags, kTagModelPixelScale);
  const TiffTag* tie = find_tag(tags, kTagModelTiepoint);
  const TiffTag* xform = find_tag(tags, kTagModelTransformation);
  if (scale == nullptr && tie == nullptr && xform == nullptr) return out;
  auto fail = [&](std::string why) {
    out.problem = std::move(why);
    return out;
  };
  for (const TiffTag* t : {scale, tie, xform})
    if (t != nullptr && !t->error.empty())
      return fail(fmt("GeoTIFF tag %u's ", unsigned(t->tag)) + t->error);

  // Model position of raster point (u, v): (X + (u - I) * sx, Y - (v - J) * sy).
  double sx = 0, sy = 0, ti = 0, tj = 0, tx = 0, ty = 0;
  if (scale != nullptr && tie != nullptr) {
    if (scale->numbers.size() < 2)
      return fail(fmt("ModelPixelScale holds %zu values (need 3)", scale->numbers.size()));
    if (tie->numbers.size() < 6 || tie->numbers.size() % 6 != 0)
      return fail(
          fmt("ModelTiepoint holds %zu values (need 6 per tie point)", tie->numbers.size()));
    sx = scale->numbers[0], sy = scale->numbers[1];
    ti = tie->numbers[0], tj = tie->numbers[1], tx = tie->numbers[3], ty = tie->numbers[4];
  } else if (xform != nullptr) {
    const std::vector<double>& m = xform->numbers;
    if (m.size() != 16)
      return fail(fmt("ModelTransformation holds %zu values (need 16)", m.size()));
    if (m[1] != 0 || m[4] != 0)
      return fail("ModelTransformation rotates or shears the raster (not supported)");
    sx = m[0], sy = -m[5], tx = m[3], ty = m[7];
  } else if (tie != nullptr) {
    return fail("ModelTiepoint without ModelPixelScale (a grid of tie points is not supported)");
  } else {
    return fail("ModelPixelScale without ModelTiepoint: the position is unknown");
  }
  for (double v : {ti, tj, tx, ty})
    if (!std::isfinite(v)) return fail("the tie point is not finite");
  if (!std::isfinite(sx) || !std::isfinite(sy) || sx <= 0 || sy <= 0)
    return fail("pixel size " + g(sx) + " x " + g(sy) +
                " (need positive and finite; rows running north are not supported)");

  const TiffTag* dir = find_tag(tags, kTagGeoKeyDirectory);
  if (dir == nullptr)
    return fail("pixel size and tie point without a GeoKeyDirectory: the units are unknown");
  auto keys = parse_keys(*dir, find_tag(tags, kTagGeoDoubleParams));
  if (!keys) return fail(keys.error().message);
  std::optional<double> model = keys->get(kKeyModelType);
  const std::optional<double> projected = keys->get(kKeyProjectedType);
  const std::optional<double> geographic = keys->get(kKeyGeographicType);
  if (!model) {
    if (projected)
      model = kModelProjected;
    else if (geographic)
      model = kModelGeographic;
    else
      return fail("the GeoKeyDirectory gives no model type (GTModelTypeGeoKey)");
  }
  const double raster = keys->get(kKeyRasterType).value_or(kRasterPixelIsArea);
  if (raster != kRasterPixelIsArea && raster != kRasterPixelIsPoint)
    return fail("GTRasterTypeGeoKey " + g(raster) + " (need 1 PixelIsArea or 2 PixelIsPoint)");
  // Model position of sample (0, 0): the centre of pixel (0, 0) when pixels are areas (the tie
  // point is then the pixel's corner), the raster point (0, 0) itself when they are points.
  const double c = raster == kRasterPixelIsArea ? 0.5 : 0.0;
  const double x0 = tx + (c - ti) * sx, y0 = ty - (c - tj) * sy;
  const char* raster_name = raster == kRasterPixelIsArea ? "PixelIsArea" : "PixelIsPoint";

  FilePlacement p;
  if (*model == kModelProjected) {
    const std::optional<double> code = keys->get(kKeyLinearUnits);
    double f = 1.0;
    std::string unit = "metres";
    if (code) {
      const auto u = linear_unit(*code, keys->get(kKeyLinearUnitSize));
      if (!u) return fail("linear unit EPSG " + g(*code) + " is not known");
      f = *u;
      if (*code != 9001) unit = "units of " + g(f) + " m";
    } else {
      unit = "metres assumed (no ProjLinearUnitsGeoKey)";
    }
    p.spacing_x = sx * f;
    p.spacing_z = sy * f;
    p.has_origin = true;
    p.origin_x = x0 * f;
    p.origin_z = -(y0 * f);
    if (!std::isfinite(p.origin_x) || !std::isfinite(p.origin_z) || !std::isfinite(p.spacing_x) ||
        !std::isfinite(p.spacing_z) || p.spacing_x <= 0 || p.spacing_z <= 0)
      return fail("the placement in metres is not finite");
    // The smallest spacing the tools accept (docs/data_model.md, "Placement"); a spacing too
    // large for the coordinates is refused with the placement's extent.
    if (p.spacing_x < 1e-6 || p.spacing_z < 1e-6)
      return fail("pixel size " + g(p.spacing_x) + " x " + g(p.spacing_z) + " m is below 1e-6 m");
    p.description =
        fmt("GeoTIFF %s, %s, %s: %s x %s m pixels, sample (0, 0) at easting %s, northing %s (world "
            "x %s, z %s: z = -northing)",
            epsg("projected", projected).c_str(), unit.c_str(), raster_name, g(p.spacing_x).c_str(),
            g(p.spacing_z).c_str(), g(x0).c_str(), g(y0).c_str(), g(p.origin_x).c_str(),
            g(p.origin_z).c_str());
  } else if (*model == kModelGeographic) {
    const std::optional<double> code = keys->get(kKeyAngularUnits);
    double f = 1.0;
    if (code) {
      const auto u = angular_unit(*code);
      if (!u) return fail("angular unit EPSG " + g(*code) + " is not known");
      f = *u;
    }
    const double sx_deg = sx * f, sy_deg = sy * f;
    const double lat_top = y0 * f, lat_bottom = (y0 - double(height - 1) * sy) * f;
    const double lat = 0.5 * (lat_top + lat_bottom);
    if (!(lat_top <= 90.0 + 1e-9 && lat_bottom >= -90.0 - 1e-9))
      return fail(fmt("latitudes %s .. %s degrees are outside -90 .. 90", g(lat_bottom).c_str(),
                      g(lat_top).c_str()));
    // WGS 84: radii of curvature in the meridian (M) and the prime vertical (N) at `lat`.
    constexpr double a = 6378137.0, inv_f = 298.257223563;
    constexpr double e2 = (2.0 - 1.0 / inv_f) / inv_f;
    const double phi = lat * std::numbers::pi / 180.0, s = std::sin(phi);
    const double w = 1.0 - e2 * s * s;
    const double m = a * (1.0 - e2) / (w * std::sqrt(w)), n = a / std::sqrt(w);
    const double rad = std::numbers::pi / 180.0;
    p.spacing_x = sx_deg * rad * n * std::cos(phi);
    p.spacing_z = sy_deg * rad * m;
    if (!std::isfinite(p.spacing_x) || !std::isfinite(p.spacing_z) || p.spacing_x < 1e-6 ||
        p.spacing_z <= 0)
      return fail("the raster's centre lies at a pole: no east-west spacing in metres");
    p.geographic = true;
    p.description = fmt(
        "GeoTIFF %s: %s x %s degree pixels = %.1f x %.1f m at the centre latitude %.3f %s (WGS 84 "
        "ellipsoid)",
        epsg("geographic", geographic).c_str(), g(sx_deg).c_str(), g(sy_deg).c_str(), p.spacing_x,
        p.spacing_z, std::fabs(lat), lat >= 0 ? "N" : "S");
  } else if (*model == kModelGeocentric) {
    return fail("a geocentric model (GTModelTypeGeoKey 3) is not supported");
  } else {
    return fail("GTModelTypeGeoKey " + g(*model) + " is not known");
  }
  out.placement = std::move(p);
  return out;
}

}  // namespace ridgeline::io::detail
