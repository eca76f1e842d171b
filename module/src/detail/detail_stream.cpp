// The detail request rule and the per-frame streaming driver (detail_stream.h; docs/detail.md,
// "Streaming").
#include "ridgeline/detail_stream.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "format.h"

namespace ridgeline {

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// Tiles this fine (stored cells per side) are checked against the stored heights under them.
constexpr std::int64_t kLocalRangeCells = 16;

// Vertical distance from the eye to the height range of tile (level, tx, tz): the stored samples
// of every cell the tile overlaps (the stored surface there lies within their range) widened by
// the bound of the detail over the tile.
template <class Vertical>
double vertical_to_tile(const Surface& surface, const DetailField& field, std::uint32_t level,
                        std::int64_t tx, std::int64_t tz, const Vertical& vertical) {
  const WorldInfo& hf = surface.info();
  const std::int64_t li0 = tx * kDetailTileCells, lj0 = tz * kDetailTileCells;
  const std::int64_t li1 = li0 + kDetailTileCells, lj1 = lj0 + kDetailTileCells;
  // Stored sample indices covering [li0, li1] / 2^level (floor and ceiling), clamped.
  const std::int64_t w = hf.width - 1, h = hf.height - 1;
  const std::int64_t i0 = std::clamp<std::int64_t>(li0 >> level, 0, w);
  const std::int64_t j0 = std::clamp<std::int64_t>(lj0 >> level, 0, h);
  const std::int64_t i1 =
      std::clamp<std::int64_t>((li1 + (std::int64_t{1} << level) - 1) >> level, 0, w);
  const std::int64_t j1 =
      std::clamp<std::int64_t>((lj1 + (std::int64_t{1} << level) - 1) >> level, 0, h);
  float lo = surface.stored_height(i0, j0), hi = lo;
  for (std::int64_t j = j0; j <= j1; ++j)
    for (std::int64_t i = i0; i <= i1; ++i) {
      const float v = surface.stored_height(i, j);
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  const double amp = field.contribution_bound(1, level, li0, lj0, li1, lj1);
  return vertical(hf.height_offset + double(lo) - amp, hf.height_offset + double(hi) + amp);
}

}  // namespace

Status validate_detail_view_rule(const DetailViewRule& rule) {
  if (!std::isfinite(rule.pixels) || rule.pixels <= 0)
    return Error{fmt("detail view rule: pixels is %g; need a finite value > 0", rule.pixels)};
  if (!std::isfinite(rule.prefetch) || rule.prefetch < 0 || rule.prefetch > 4)
    return Error{
        fmt("detail view rule: prefetch is %g; need a finite value in [0, 4]", rule.prefetch)};
  if (rule.max_tiles < 1) return Error{"detail view rule: max_tiles is 0; need at least 1"};
  return {};
}

double detail_level_radius(const DetailField& field, const Camera& camera, std::uint32_t level,
                           const DetailViewRule& rule) noexcept {
  if (level == 0 || level > field.levels() || !(rule.pixels > 0)) return 0.0;
  const double spacing = std::ldexp(std::max(field.spacing_x(), field.spacing_z()), -int(level));
  return spacing * projection_scale(camera) / rule.pixels;
}

Status detail_tiles_for_view(const Surface& surface, const Camera& camera,
                             const DetailViewRule& rule, std::vector<DetailTileNeed>& out) {
  out.clear();
  if (auto s = validate_detail_view_rule(rule); !s) return s;
  if (auto s = validate_camera(camera); !s) return s;
  if (!surface.detail()) return {};
  const DetailField& field = *surface.detail();
  const WorldInfo& hf = surface.info();
  // The height range any surface point can have: a lower bound of the vertical distance.
  const double amp = field.contribution_bound(1);
  const double global_top = hf.height_offset + double(hf.max_local) + amp;
  const double global_bottom = hf.height_offset + double(hf.min_local) - amp;
  const double ex = camera.eye.x, ey = camera.eye.y, ez = camera.eye.z;
  auto vertical = [ey](double bottom, double top) {
    return std::max({0.0, ey - top, bottom - ey});
  };
  const double global_dy = vertical(global_bottom, global_top);

  for (std::uint32_t level = 1; level <= field.levels(); ++level) {
    const double radius = detail_level_radius(field, camera, level, rule);
    const double reach = (1.0 + rule.prefetch) * radius;
    if (!(global_dy <= reach)) continue;
    const double horizontal = std::sqrt(reach * reach - global_dy * global_dy);
    // Tiles of at most kLocalRangeCells stored cells per side get the height range of the stored
    // samples under them (plus the detail bound there); coarser tiles the global range.
    const bool local_range = (kDetailTileCells >> level) <= kLocalRangeCells;
    // Tile sides in metres, and the footprint's tiles: lattice indices 0 .. (w - 1) * 2^level.
    const double side_x = std::ldexp(hf.spacing_x, -int(level)) * kDetailTileCells;
    const double side_z = std::ldexp(hf.spacing_z, -int(level)) * kDetailTileCells;
    const std::int64_t tiles_x =
        ((std::int64_t{hf.width} - 1) * (std::int64_t{1} << level) + kDetailTileCells - 1) /
        kDetailTileCells;
    const std::int64_t tiles_z =
        ((std::int64_t{hf.height} - 1) * (std::int64_t{1} << level) + kDetailTileCells - 1) /
        kDetailTileCells;
    // Index range of the square around the eye, clamped to the footprint (in double first: the
    // eye may be far away).
    auto range = [](double lo, double hi, double side, std::int64_t n, std::int64_t& a,
                    std::int64_t& b) {
      const double fa = std::floor(lo / side), fb = std::floor(hi / side);
      a = std::int64_t(std::clamp(fa, 0.0, double(n)));
      b = std::int64_t(std::clamp(fb, -1.0, double(n - 1)));
    };
    std::int64_t tx0, tx1, tz0, tz1;
    range(ex - horizontal - hf.origin_x, ex + horizontal - hf.origin_x, side_x, tiles_x, tx0,
          tx1);
    range(ez - horizontal - hf.origin_z, ez + horizontal - hf.origin_z, side_z, tiles_z, tz0,
          tz1);
    const std::size_t level_begin = out.size();
    for (std::int64_t tz = tz0; tz <= tz1; ++tz) {
      const double z0 = hf.origin_z + double(tz) * side_z;
      const double dz = std::max({0.0, z0 - ez, ez - (z0 + side_z)});
      for (std::int64_t tx = tx0; tx <= tx1; ++tx) {
        const double x0 = hf.origin_x + double(tx) * side_x;
        const double dx = std::max({0.0, x0 - ex, ex - (x0 + side_x)});
        const double dxz2 = dx * dx + dz * dz;
        if (dxz2 + global_dy * global_dy > reach * reach) continue;
        const double dy =
            local_range ? vertical_to_tile(surface, field, level, tx, tz, vertical) : global_dy;
        const double d = std::sqrt(dxz2 + dy * dy);
        if (d > reach) continue;
        if (out.size() >= rule.max_tiles) {
          out.clear();
          return Error{
              fmt("detail view rule: the view asks for more than %zu tiles (level %u, "
                  "pixels %g, prefetch %g); raise pixels or max_tiles",
                  rule.max_tiles, level, rule.pixels, rule.prefetch)};
        }
        out.push_back({DetailTileKey{level, std::int32_t(tx), std::int32_t(tz)}, d, d <= radius});
      }
    }
    std::sort(out.begin() + std::ptrdiff_t(level_begin), out.end(),
              [](const DetailTileNeed& a, const DetailTileNeed& b) {
                return a.distance_m < b.distance_m;
              });
  }
  return {};
}

Result<DetailStream> DetailStream::create(const Surface& surface, DetailCache& cache,
                                          const DetailViewRule& rule) {
  if (auto s = validate_detail_view_rule(rule); !s) return Error{s.message()};
  if (&cache.field() != surface.detail())
    return Error{"detail stream: the cache holds tiles of another detail field than the surface's"};
  return DetailStream(surface, cache, rule);
}

Result<DetailFrameStats> DetailStream::frame(const Camera& camera) {
  if (auto s = detail_tiles_for_view(*surface_, camera, rule_, tiles_); !s)
    return Error{s.message()};
  DetailFrameStats st;
  st.requested = tiles_.size();

  const auto t0 = Clock::now();
  // Prefetch first (queued behind, in distance order), then the needed tiles as urgent ones
  // from the farthest to the nearest: urgent requests go to the front of the queue, so the
  // nearest needed tile is generated first.
  // Each group in one call: the cache's lock is taken twice a frame, not once per tile.
  std::vector<const DetailTileNeed*> needed;
  keys_.clear();
  for (const DetailTileNeed& t : tiles_) {
    if (t.needed)
      needed.push_back(&t);
    else
      keys_.push_back(t.key);
  }
  cache_->request_many(keys_.data(), keys_.size(), false);
  std::sort(needed.begin(), needed.end(), [](const DetailTileNeed* a, const DetailTileNeed* b) {
    return a->distance_m > b->distance_m;
  });
  keys_.clear();
  for (const DetailTileNeed* t : needed) keys_.push_back(t->key);
  cache_->request_many(keys_.data(), keys_.size(), true);
  st.request_ms = ms_since(t0);

  const auto t1 = Clock::now();
  cache_->update();
  st.update_ms = ms_since(t1);

  const auto snap = cache_->snapshot();
  st.needed = needed.size();
  next_late_.clear();
  for (const DetailTileNeed* t : needed) {
    if (snap->find(t->key)) {
      ++st.needed_resident;
      continue;
    }
    const auto it = late_.find(t->key);
    const std::uint64_t frames = (it == late_.end() ? 0 : it->second) + 1;
    next_late_.emplace(t->key, frames);
    st.late_frames = std::max(st.late_frames, frames);
  }
  late_.swap(next_late_);
  worst_late_ = std::max(worst_late_, st.late_frames);
  st.cache = cache_->stats();
  return st;
}

}  // namespace ridgeline
