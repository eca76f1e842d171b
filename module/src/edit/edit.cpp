// Deformation (docs/deformation.md): brushes and the edit transaction that applies them to a
// terrain's surface, ray hierarchy and change log. The edit layer is the surface's
// (surface/edit_layer.cpp), the change log the terrain's (change_log.h), the file edit_file.cpp.
#include "ridgeline/edit.h"

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>

#include "change_log.h"
#include "edit/sample_changes.h"
#include "format.h"
#include "surface/edit_layer.h"
#include "surface/lattice.h"
#include "world/page_store.h"
#include "ridgeline/detail.h"

namespace ridgeline {

// ---- brushes ---------------------------------------------------------------------------------

const char* brush_name(Brush b) noexcept {
  switch (b) {
    case Brush::kCrater: return "crater";
    case Brush::kRaise: return "raise";
    case Brush::kLower: return "lower";
    case Brush::kFlatten: return "flatten";
    case Brush::kSmooth: return "smooth";
    case Brush::kHole: return "hole";
    case Brush::kFillHole: return "fill_hole";
  }
  return "?";
}

const char* brush_names() noexcept {
  return "crater, raise, lower, flatten, smooth, hole or fill_hole";
}

std::optional<Brush> parse_brush(std::string_view name) noexcept {
  for (Brush b : {Brush::kCrater, Brush::kRaise, Brush::kLower, Brush::kFlatten, Brush::kSmooth,
                  Brush::kHole, Brush::kFillHole})
    if (name == brush_name(b)) return b;
  return std::nullopt;
}

Status validate_edit(const Edit& e) {
  auto finite = [](double v) { return std::isfinite(v); };
  if (static_cast<unsigned>(e.brush) > static_cast<unsigned>(Brush::kFillHole))
    return Error{fmt("edit: brush %u; need %s", static_cast<unsigned>(e.brush), brush_names())};
  if (!finite(e.x)) return Error{"edit: x is " + num(e.x) + "; need a finite value"};
  if (!finite(e.z)) return Error{"edit: z is " + num(e.z) + "; need a finite value"};
  if (!finite(e.radius) || !(e.radius > 0))
    return Error{"edit: radius is " + num(e.radius) + "; need a finite value > 0"};
  if (!finite(e.strength) || e.strength < 0 || e.strength > 1)
    return Error{"edit: strength is " + num(e.strength) + "; need a value in 0..1"};
  if (!finite(e.depth) || std::abs(e.depth) > 1e5)
    return Error{"edit: depth is " + num(e.depth) + "; need a finite value within +-1e5 m"};
  if (!finite(e.rim) || e.rim < 0 || e.rim > 1)
    return Error{"edit: rim is " + num(e.rim) + "; need a value in 0..1"};
  if (!finite(e.height)) return Error{"edit: height is " + num(e.height) + "; need a finite value"};
  return {};
}

namespace {

// How far a brush reaches, in radii.
double reach_factor(Brush b) { return b == Brush::kCrater ? 1.5 : 1.0; }

// Smooth falloff (1 - r^2)^2: 1 at the centre, 0 with zero slope at r = 1.
double falloff(double r) {
  const double q = 1.0 - r * r;
  return r < 1.0 ? q * q : 0.0;
}

// The crater profile in units of depth (negative down) at r = distance / radius: a parabolic bowl
// of depth 1 plus a rim of height `rim` peaking at r = 1 and falling smoothly to 0 at r = 1.5.
double crater_profile(double r, double rim) {
  if (r <= 1.0) return (r * r - 1.0) + rim * r * r;
  if (r < 1.5) {
    const double t = (r - 1.0) / 0.5, q = 1.0 - t * t;
    return rim * q * q;
  }
  return 0.0;
}

// Flatten weight: 1 inside half the radius, smoothstep down to 0 at the radius.
double plateau(double r) {
  if (r <= 0.5) return 1.0;
  if (r >= 1.0) return 0.0;
  const double t = (r - 0.5) / 0.5;
  return 1.0 - t * t * (3.0 - 2.0 * t);
}

}  // namespace

// ---- the transaction -------------------------------------------------------------------------

// What the changed stored samples of `c` changed on surface `s`: the cells touching them, the
// surface's height range there before and after, the finest-lattice vertices that moved.
static TerrainChange describe_change(const Surface& s, const SampleChanges& c) {
  const WorldInfo& hf = s.info();
  const int L = int(s.detail_levels());
  // Corners of the cells touching a changed sample (unchanged corners keep their height).
  const std::uint32_t vi0 = c.i0 > 0 ? c.i0 - 1 : 0, vj0 = c.j0 > 0 ? c.j0 - 1 : 0;
  const std::uint32_t vi1 = std::min(c.i1 + 1, hf.width - 1),
                      vj1 = std::min(c.j1 + 1, hf.height - 1);
  float lo = c.lo, hi = c.hi;  // the changed samples, before and after
  const detail::StoredLattice g = detail::stored_lattice(s);
  for (std::uint32_t j = vj0; j <= vj1; ++j)
    for (std::uint32_t i = vi0; i <= vi1; ++i)
      lo = std::min(lo, g.local(i, j)), hi = std::max(hi, g.local(i, j));
  // The surface is piecewise linear over those corners, plus detail below the stored resolution.
  const std::int64_t n = std::int64_t{1} << L;  // finest cells per stored cell side
  const double pad = L == 0 ? 0.0
                            : s.detail()->contribution_bound(1, std::uint32_t(L), vi0 * n, vj0 * n,
                                                             vi1 * n, vj1 * n);
  TerrainChange ch;
  ch.box.min = {hf.origin_x + vi0 * hf.spacing_x, hf.height_offset + double(lo) - pad,
                hf.origin_z + vj0 * hf.spacing_z};
  ch.box.max = {hf.origin_x + vi1 * hf.spacing_x, hf.height_offset + double(hi) + pad,
                hf.origin_z + vj1 * hf.spacing_z};
  if (L == 0) {
    ch.vertices = {c.i0, c.j0, c.i1, c.j1};
  } else {
    // Detail-lattice vertices strictly inside those cells are interpolated from the changed
    // samples; the unchanged corners themselves stay.
    const std::int64_t last_i = s.lattice().vertices_x - 1, last_j = s.lattice().vertices_z - 1;
    ch.vertices = {std::max<std::int64_t>(0, (std::int64_t(c.i0) - 1) * n + 1),
                   std::max<std::int64_t>(0, (std::int64_t(c.j0) - 1) * n + 1),
                   std::min(last_i, (std::int64_t(c.i1) + 1) * n - 1),
                   std::min(last_j, (std::int64_t(c.j1) + 1) * n - 1)};
  }
  return ch;
}

// After the samples changed (their pages and ray pyramids are published): the tessellator's
// bounds over them, the version, the change log and the result's box. Nothing is called back:
// views and engines pull the log (Terrain::changes_since).
void Terrain::commit(const SampleChanges& c, EditResult& r) {
  r.samples_changed = c.samples;
  r.cells_changed = c.cells;
  if (c.empty()) return;
  world::PageStore& store = *surface_.store_;
  for (int slot = 0; slot < int(world::kRecordSlots); ++slot)
    if (const world::RecordMaker* m = store.maker(slot))
      store.set_records(slot, m->remake(store, c.i0, c.j0, c.i1, c.j1), true);
  TerrainChange ch = describe_change(surface_, c);
  ch.version = ++edit_version_;
  log_->record(ch);
  r.changed = ch.box;
}

TerrainChanges Terrain::changes_since(std::uint64_t version) const {
  if (version <= edit_version_) return log_->since(version, edit_version_);
  // Not a version of this terrain: everything may differ.
  const WorldInfo& hf = surface_.info();
  const double pad = surface_.detail_bound();
  TerrainChange whole;
  whole.version = edit_version_;
  whole.box.min = {hf.origin_x, hf.height_offset + double(hf.min_local) - pad, hf.origin_z};
  whole.box.max = {hf.origin_x + hf.extent_x(), hf.height_offset + double(hf.max_local) + pad,
                   hf.origin_z + hf.extent_z()};
  whole.vertices = {0, 0, surface_.lattice().vertices_x - 1, surface_.lattice().vertices_z - 1};
  TerrainChanges out;
  out.version = edit_version_;
  out.changes.push_back(whole);
  out.trimmed = true;
  return out;
}

// Writes local height `h` to sample (i, j) of an open edit, clamped to the edit limits' range
// (counted in `r`), unless it equals `old`; the edit layer and the changes record it.
void Terrain::write_sample(world::PageEdit& edit, EditLayer& layer, SampleChanges& c,
                           EditResult& r, std::uint32_t i, std::uint32_t j, float old,
                           double h) {
  const EditLimits& lim = edit_limits_;
  if (h < lim.min_height_rel || h > lim.max_height_rel) {
    h = std::clamp(h, lim.min_height_rel, lim.max_height_rel);
    ++r.samples_clamped;
  }
  const float nh = static_cast<float>(h);
  if (nh == old) return;
  const WorldInfo& hf = surface_.info();
  layer.touch(edit, i, j, hf.width, hf.height);
  edit.write(i, j, nh);
  c.add(i, j, old, nh);
}

Result<EditResult> Terrain::apply_edit(const Edit& e) {
  if (auto s = validate_edit(e); !s) return Error{s.message()};
  const WorldInfo& hf = surface_.info();
  EditLayer& layer = edit_layer();
  const std::uint32_t levels = surface_.detail_levels();
  if (!e.keep_detail && levels != 0)
    // Replacing the detail would need deltas on the detail lattice and error bounds (views,
    // rays) that include them; docs/deformation.md, "keep_detail".
    return Error{
        fmt("edit: keep_detail = false is not supported on a terrain with procedural "
            "detail (%u levels): edits are stored at the base spacing (%s m) and the "
            "detail always rides on top of them; use keep_detail = true",
            levels, num(std::min(hf.spacing_x, hf.spacing_z)).c_str())};
  const double extent = std::max(hf.extent_x(), hf.extent_z());
  if (e.radius > extent)
    return Error{"edit: radius " + num(e.radius) + " m is larger than the terrain (" +
                 num(extent) + " m)"};
  const EditLimits& lim = edit_limits_;
  EditResult r;
  double radius = e.radius;
  const double area = std::numbers::pi * std::pow(radius * reach_factor(e.brush), 2);
  if (area > lim.max_area_m2) {
    if (lim.refuse_oversize)
      return Error{"edit: the brush covers " + num(area) + " m^2, more than the per-edit cap of " +
                   num(lim.max_area_m2) + " m^2"};
    radius = std::sqrt(lim.max_area_m2 / std::numbers::pi) / reach_factor(e.brush);
    r.clipped = true;
  }
  r.radius_used = radius;
  if (e.brush == Brush::kHole || e.brush == Brush::kFillHole) return edit_holes(e, r);
  const double reach = radius * reach_factor(e.brush);
  // Sample range under the brush (lattice units relative to the origin, double: no overflow).
  const double cu = (e.x - hf.origin_x) / hf.spacing_x, cv = (e.z - hf.origin_z) / hf.spacing_z;
  const double ru = reach / hf.spacing_x, rv = reach / hf.spacing_z;
  const double u0 = std::max(std::ceil(cu - ru), 0.0), u1 = std::min(std::floor(cu + ru), double(hf.width - 1));
  const double v0 = std::max(std::ceil(cv - rv), 0.0), v1 = std::min(std::floor(cv + rv), double(hf.height - 1));
  if (!(u0 <= u1 && v0 <= v1)) return r;  // wholly outside: a no-op
  const auto i0 = std::uint32_t(u0), i1 = std::uint32_t(u1), j0 = std::uint32_t(v0), j1 = std::uint32_t(v1);

  auto edit = surface_.store_->begin_edit();
  // Smooth reads the heights before the edit, one sample around the range.
  std::vector<float> before;
  std::uint32_t bi0 = 0, bj0 = 0, bw = 0, bh = 0;
  if (e.brush == Brush::kSmooth) {
    bi0 = i0 > 0 ? i0 - 1 : 0, bj0 = j0 > 0 ? j0 - 1 : 0;
    bw = std::min(i1 + 1, hf.width - 1) - bi0 + 1, bh = std::min(j1 + 1, hf.height - 1) - bj0 + 1;
    before.resize(std::size_t{bw} * bh);
    for (std::uint32_t j = 0; j < bh; ++j)
      for (std::uint32_t i = 0; i < bw; ++i) before[i + j * bw] = edit->height(bi0 + i, bj0 + j);
  }
  const double target = e.height - hf.height_offset;
  const double amount = e.strength * e.depth;
  SampleChanges c;
  for (std::uint32_t j = j0; j <= j1; ++j) {
    const double dz = (double(j) - cv) * hf.spacing_z;
    for (std::uint32_t i = i0; i <= i1; ++i) {
      const double dx = (double(i) - cu) * hf.spacing_x;
      const double r_n = std::sqrt(dx * dx + dz * dz) / radius;
      if (r_n * radius > reach) continue;
      const float old = edit->height(i, j);
      double h = old;
      switch (e.brush) {
        case Brush::kCrater: h += amount * crater_profile(r_n, e.rim); break;
        case Brush::kRaise: h += amount * falloff(r_n); break;
        case Brush::kLower: h -= amount * falloff(r_n); break;
        case Brush::kFlatten: h += e.strength * plateau(r_n) * (target - h); break;
        case Brush::kSmooth: {
          double sum = 0;
          int n = 0;
          for (int b = -1; b <= 1; ++b)
            for (int a = -1; a <= 1; ++a) {
              const std::int64_t x = std::int64_t(i) + a - bi0, z = std::int64_t(j) + b - bj0;
              if (x < 0 || z < 0 || x >= bw || z >= bh) continue;
              sum += before[std::size_t(x) + std::size_t(z) * bw];
              ++n;
            }
          h += e.strength * falloff(r_n) * (sum / n - h);
          break;
        }
        case Brush::kHole:
        case Brush::kFillHole: break;  // edit_holes()
      }
      write_sample(*edit, layer, c, r, i, j, old, h);
    }
  }
  r.clamped = r.samples_clamped > 0;
  edit->commit();
  commit(c, r);
  return r;
}

namespace {

// The checks get_heights and set_heights share.
Status check_rect(const WorldInfo& hf, const char* what, std::uint32_t i0, std::uint32_t j0,
                  std::uint32_t w, std::uint32_t h, std::size_t span, std::size_t stride) {
  if (w == 0 || h == 0)
    return Error{fmt("%s: an empty rectangle (%u x %u samples)", what, w, h)};
  if (std::uint64_t(i0) + w > hf.width || std::uint64_t(j0) + h > hf.height)
    return Error{fmt("%s: samples %u..%llu x %u..%llu pass the stored %u x %u", what, i0,
                     static_cast<unsigned long long>(std::uint64_t(i0) + w - 1), j0,
                     static_cast<unsigned long long>(std::uint64_t(j0) + h - 1), hf.width,
                     hf.height)};
  if (stride < w) return Error{fmt("%s: stride %zu is below the width %u", what, stride, w)};
  const std::uint64_t need = std::uint64_t(h - 1) * stride + w;
  if (span < need)
    return Error{fmt("%s: %zu values given; the rectangle needs %llu", what, span,
                     static_cast<unsigned long long>(need))};
  return {};
}

}  // namespace

Status Terrain::get_heights(std::uint32_t i0, std::uint32_t j0, std::uint32_t w, std::uint32_t h,
                            std::span<float> out, std::size_t stride) const {
  const WorldInfo& hf = surface_.info();
  if (auto s = check_rect(hf, "get_heights", i0, j0, w, h, out.size(), stride); !s) return s;
  for (std::uint32_t r = 0; r < h; ++r)
    for (std::uint32_t c = 0; c < w; ++c)
      out[std::size_t(r) * stride + c] = float(
          hf.height_offset + double(surface_.stored_height(std::int64_t(i0) + c, std::int64_t(j0) + r)));
  return {};
}

Result<EditResult> Terrain::set_heights(std::uint32_t i0, std::uint32_t j0, std::uint32_t w,
                                        std::uint32_t h, std::span<const float> in,
                                        std::size_t stride) {
  const WorldInfo& hf = surface_.info();
  if (auto s = check_rect(hf, "set_heights", i0, j0, w, h, in.size(), stride); !s)
    return Error{s.message()};
  const EditLimits& lim = edit_limits_;
  const double area = double(w) * hf.spacing_x * double(h) * hf.spacing_z;
  if (area > lim.max_area_m2)
    return Error{fmt("set_heights: the rectangle covers %s m^2, more than the per-edit cap of %s "
                     "m^2 (EditLimits::max_area_m2, Terrain::set_edit_limits)",
                     num(area).c_str(), num(lim.max_area_m2).c_str())};
  for (std::uint32_t r = 0; r < h; ++r)
    for (std::uint32_t c = 0; c < w; ++c)
      if (!std::isfinite(in[std::size_t(r) * stride + c]))
        return Error{fmt("set_heights: the height of sample (%u, %u) is %s; need a finite value",
                         i0 + c, j0 + r, num(in[std::size_t(r) * stride + c]).c_str())};
  EditLayer& layer = edit_layer();
  EditResult result;
  auto edit = surface_.store_->begin_edit();
  SampleChanges changes;
  for (std::uint32_t r = 0; r < h; ++r)
    for (std::uint32_t c = 0; c < w; ++c) {
      const std::uint32_t i = i0 + c, j = j0 + r;
      write_sample(*edit, layer, changes, result, i, j, edit->height(i, j),
                   double(in[std::size_t(r) * stride + c]) - hf.height_offset);
    }
  result.clamped = result.samples_clamped > 0;
  edit->commit();
  commit(changes, result);
  return result;
}

Status Terrain::set_edit_limits(const EditLimits& l) {
  if (!std::isfinite(l.max_area_m2) || !(l.max_area_m2 > 0))
    return Error{"edit limits: max_area_m2 is " + num(l.max_area_m2) + "; need a finite value > 0"};
  if (!std::isfinite(l.min_height_rel) || !std::isfinite(l.max_height_rel) ||
      !(l.min_height_rel < l.max_height_rel))
    return Error{"edit limits: height range " + num(l.min_height_rel) + " .. " +
                 num(l.max_height_rel) + "; need finite values with min < max"};
  edit_limits_ = l;
  return {};
}

}  // namespace ridgeline
