// Worlds made of several heightmap files (io.h, load_tiles): the files placed side by side by
// their georeferencing or an explicit grid, checked, and joined into one Heightfield, so that one
// surface (and one mesh, one set of queries) spans the file borders.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "format.h"
#include "ridgeline/io.h"
#include "ridgeline/log.h"

namespace ridgeline::io {

using detail::fmt;
using detail::num;

namespace {

struct Placed {
  Heightfield hf;
  std::string path;
  std::int64_t i0 = 0, j0 = 0;  // sample offset in the joined field
};

}  // namespace

Result<Heightfield> load_tiles(const std::vector<std::string>& paths, const LoadOptions& options,
                               const TileLayout& layout, const RawFormat* raw,
                               LoadReport* report) {
  if (paths.empty()) return Error{"tiles: no heightmap files given"};
  if (paths.size() == 1 && layout.columns <= 1 && layout.rows <= 1)
    return load_heightmap(paths[0], options, raw, report);
  const bool grid = layout.columns > 0 || layout.rows > 0;
  if (grid && std::uint64_t(layout.columns) * layout.rows != paths.size())
    return Error{fmt("tiles: a %u x %u layout needs %llu files; %zu given (--layout COLSxROWS, "
                     "files row by row)",
                     layout.columns, layout.rows,
                     static_cast<unsigned long long>(std::uint64_t(layout.columns) * layout.rows),
                     paths.size())};
  // Every file, placed as the options say (a GeoTIFF's own placement when they allow it); the
  // size cap applies to the joined field, not to each file.
  LoadOptions each = options;
  each.placement.max_samples = options.placement.max_samples;
  std::vector<Placed> tiles;
  tiles.reserve(paths.size());
  for (const std::string& p : paths) {
    LoadReport r;
    auto hf = load_heightmap(p, each, raw, &r);
    if (!hf) return hf.error();
    if (report != nullptr) {
      if (report->pixel_type.empty()) report->pixel_type = r.pixel_type;
      for (auto& w : r.warnings) report->warnings.push_back(p + ": " + w);
    }
    tiles.push_back({std::move(*hf), p, 0, 0});
  }
  const Heightfield& first = tiles[0].hf;
  const std::int64_t overlap = layout.shared_edges ? 1 : 0;
  for (const Placed& t : tiles) {
    if (t.hf.spacing_x() != first.spacing_x() || t.hf.spacing_z() != first.spacing_z())
      return Error{fmt("tiles: '%s' has a spacing of %s x %s m, '%s' %s x %s m; the files of one "
                       "world need one spacing",
                       t.path.c_str(), num(t.hf.spacing_x()).c_str(),
                       num(t.hf.spacing_z()).c_str(), tiles[0].path.c_str(),
                       num(first.spacing_x()).c_str(), num(first.spacing_z()).c_str())};
    if (t.hf.height_offset() != first.height_offset() ||
        t.hf.height_scale() != first.height_scale())
      return Error{fmt("tiles: '%s' has another height scale or offset than '%s'",
                       t.path.c_str(), tiles[0].path.c_str())};
    if (t.hf.has_materials() != first.has_materials())
      return Error{"tiles: some files have a material layer and others not"};
  }
  if (grid) {
    // Columns share widths, rows share heights; neighbours share an edge of samples or not.
    const std::uint32_t C = layout.columns, R = layout.rows;
    for (std::uint32_t r = 0; r < R; ++r)
      for (std::uint32_t c = 0; c < C; ++c) {
        const Placed& t = tiles[r * C + c];
        const Placed& row0 = tiles[r * C], &col0 = tiles[c];
        if (t.hf.height() != row0.hf.height() || t.hf.width() != col0.hf.width())
          return Error{fmt("tiles: '%s' is %u x %u samples; in a %u x %u layout the files of a "
                           "row need one height and those of a column one width",
                           t.path.c_str(), t.hf.width(), t.hf.height(), C, R)};
      }
    std::int64_t j = 0;
    for (std::uint32_t r = 0; r < R; ++r) {
      std::int64_t i = 0;
      for (std::uint32_t c = 0; c < C; ++c) {
        Placed& t = tiles[r * C + c];
        t.i0 = i, t.j0 = j;
        i += std::int64_t(t.hf.width()) - overlap;
      }
      j += std::int64_t(tiles[r * C].hf.height()) - overlap;
    }
  } else {
    // By georeferencing: every file needs an origin, on the common sample grid.
    double ox = INFINITY, oz = INFINITY;
    for (const Placed& t : tiles) ox = std::min(ox, t.hf.origin_x()), oz = std::min(oz, t.hf.origin_z());
    for (Placed& t : tiles) {
      const double u = (t.hf.origin_x() - ox) / first.spacing_x();
      const double v = (t.hf.origin_z() - oz) / first.spacing_z();
      if (!(std::abs(u - std::nearbyint(u)) <= 1e-6) || !(std::abs(v - std::nearbyint(v)) <= 1e-6))
        return Error{fmt("tiles: '%s' lies %s x %s samples from the others' grid, not a whole "
                         "number (files without a projected georeferencing need --layout "
                         "COLSxROWS)",
                         t.path.c_str(), num(u).c_str(), num(v).c_str())};
      t.i0 = std::int64_t(std::nearbyint(u)), t.j0 = std::int64_t(std::nearbyint(v));
    }
  }
  std::int64_t W = 0, H = 0;
  for (const Placed& t : tiles) {
    W = std::max(W, t.i0 + std::int64_t(t.hf.width()));
    H = std::max(H, t.j0 + std::int64_t(t.hf.height()));
  }
  HeightfieldDesc d = options.placement;
  d.width = std::uint32_t(std::min<std::int64_t>(W, 0xffffffff));
  d.height = std::uint32_t(std::min<std::int64_t>(H, 0xffffffff));
  d.spacing_x = first.spacing_x(), d.spacing_z = first.spacing_z();
  d.origin_x = grid ? first.origin_x() : first.origin_x() - double(tiles[0].i0) * d.spacing_x;
  d.origin_z = grid ? first.origin_z() : first.origin_z() - double(tiles[0].j0) * d.spacing_z;
  d.height_offset = first.height_offset();
  d.nodata.reset();
  d.fill = FillPolicy::kRefuse;
  d.name = fmt("tiles '%s' ... (%zu files)", paths[0].c_str(), paths.size());
  if (W > 0xffffffffLL || H > 0xffffffffLL)
    return Error{d.name + ": the joined field is too large"};
  if (auto s = validate_heightfield_desc(d); !s) return Error{s.message()};
  // 16-bit values stay 16-bit values when every file's are (height = offset + scale * value);
  // otherwise the local heights are joined as floats (scale 1), bit for bit.
  const double scale = first.height_scale();
  bool integral = true;
  for (const Placed& t : tiles)
    for (float h : t.hf.local_heights()) {
      const double v = std::nearbyint(double(h) / scale);
      if (!(v >= 0.0 && v <= 65535.0) || static_cast<float>(scale * v) != h) {
        integral = false;
        break;
      }
    }
  d.height_scale = integral ? scale : 1.0;
  std::vector<float> values(std::size_t(W) * std::size_t(H));
  std::vector<std::uint8_t> covered(values.size(), 0);
  std::vector<std::uint8_t> mats;
  if (first.has_materials()) mats.assign(values.size(), 0);
  for (const Placed& t : tiles)
    for (std::uint32_t j = 0; j < t.hf.height(); ++j)
      for (std::uint32_t i = 0; i < t.hf.width(); ++i) {
        const std::size_t k = std::size_t(t.i0 + i) + std::size_t(t.j0 + j) * std::size_t(W);
        const float h = t.hf.local(i, j);
        const float v = integral ? float(std::nearbyint(double(h) / scale)) : h;
        if (covered[k] && values[k] != v)
          return Error{fmt("tiles: '%s' and a neighbour disagree on their shared sample (%lld, "
                           "%lld) (%s against %s; pass --unshared-edges if the files do not "
                           "repeat their edges)",
                           t.path.c_str(), static_cast<long long>(t.i0 + i),
                           static_cast<long long>(t.j0 + j), detail::numf(h).c_str(),
                           detail::numf(values[k]).c_str())};
        values[k] = v;
        covered[k] = 1;
        if (!mats.empty())
          mats[k] = t.hf.material(std::min(i, t.hf.width() - 2), std::min(j, t.hf.height() - 2));
      }
  for (std::size_t k = 0; k < covered.size(); ++k)
    if (!covered[k])
      return Error{fmt("tiles: no file covers sample (%zu, %zu): the files leave a hole (check "
                       "--layout, or --unshared-edges)",
                       k % std::size_t(W), k / std::size_t(W))};
  std::vector<std::uint8_t> cell_mats;
  if (!mats.empty()) cell_mats = std::move(mats);  // one id per sample: cell (i, j) takes (i, j)'s
  return Heightfield::create(d, values, cell_mats);
}

}  // namespace ridgeline::io
