// Detail streaming (detail_stream.h): the request rule against a brute-force enumeration, bad
// input, and a 20 km flight at 300 m/s (dt 1/60 s) in synchronous and asynchronous modes: the
// cache stays under its byte budget after every update, and every tile checked equals the
// direct evaluator.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include "ridgeline/detail_stream.h"
#include "ridgeline/scenes.h"
#include "ridgeline/terrain.h"

namespace ridgeline {
namespace {

constexpr double kSpacing = 100.0;    // metres between stored samples
constexpr std::uint32_t kSize = 257;  // 25.6 km square

// 257 x 257 samples, 100 m apart: rolling hills with a plain in the south.
Heightfield make_heightfield() {
  auto hf = scenes::field(
      {.width = kSize,
       .height = kSize,
       .spacing_x = kSpacing,
       .spacing_z = kSpacing,
       .origin_x = -500,
       .origin_z = 300},
      [](int i, int j) {
        const double x = i * kSpacing, z = j * kSpacing;
        return z < 3000 ? 20.0 : 200 + 150 * std::sin(x / 1700.0) * std::cos(z / 2300.0);
      });
  EXPECT_TRUE(hf.ok());
  return std::move(hf).value();
}

// The terrain with 6 detail levels (seed 11, 4 m) as part of its surface, a synchronous cache.
std::shared_ptr<const Terrain> make_detailed() {
  DetailParams p;
  p.levels = 6;
  p.seed = 11;
  p.amplitude = 4.0;
  DetailCacheDesc d;
  d.worker_threads = 0;
  auto t = Terrain::create(make_heightfield(), p, d);
  EXPECT_TRUE(t.ok()) << (t.ok() ? "" : t.error().message);
  return std::move(t).value();
}

// The terrain's detail field, keeping the terrain alive (for caches of its own).
std::shared_ptr<const DetailField> field_of(const std::shared_ptr<const Terrain>& t) {
  return std::shared_ptr<const DetailField>(t, t->surface().detail());
}

DetailCacheDesc cache_desc(std::size_t budget_bytes, std::uint32_t workers) {
  DetailCacheDesc d;
  d.budget_bytes = budget_bytes;
  d.worker_threads = workers;
  return d;
}

Camera camera_at(double x, double z, double y, double heading_x = 1, double heading_z = 0) {
  Camera c;
  c.eye = {x, y, z};
  c.target = {x + 100 * heading_x, y - 20, z + 100 * heading_z};
  c.viewport = {640, 360};
  return c;
}

// Brute force: every tile of every level over the footprint, with the distance as documented
// (the vertical part from every stored sample under tiles of at most 16 cells per side).
std::set<std::tuple<std::uint32_t, int, int, bool>> brute_force(const Terrain& terrain,
                                                                const Camera& c,
                                                                const DetailViewRule& rule) {
  const Heightfield hf = terrain.surface().to_heightfield().value();
  const DetailField& f = *terrain.surface().detail();
  auto vertical = [&](double lo, double hi) { return std::max({0.0, c.eye.y - hi, lo - c.eye.y}); };
  const double amp = f.contribution_bound(1);
  const double global_dy = vertical(hf.height_offset() + hf.min_local() - amp,
                                    hf.height_offset() + hf.max_local() + amp);
  std::set<std::tuple<std::uint32_t, int, int, bool>> out;
  for (std::uint32_t l = 1; l <= f.levels(); ++l) {
    const double r = detail_level_radius(f, c, l, rule);
    const int n = int(((kSize - 1) << l) / kDetailTileCells);
    const double side = kSpacing / double(1 << l) * kDetailTileCells;
    const int cells = kDetailTileCells >> l;  // stored cells per tile side
    for (int tz = 0; tz < n; ++tz)
      for (int tx = 0; tx < n; ++tx) {
        const double x0 = hf.origin_x() + tx * side, z0 = hf.origin_z() + tz * side;
        const double dx = std::max({0.0, x0 - c.eye.x, c.eye.x - x0 - side});
        const double dz = std::max({0.0, z0 - c.eye.z, c.eye.z - z0 - side});
        double dy = global_dy;
        if (cells <= 16) {
          double lo = 1e300, hi = -1e300;
          for (int j = tz * cells; j <= (tz + 1) * cells; ++j)
            for (int i = tx * cells; i <= (tx + 1) * cells; ++i) {
              lo = std::min(lo, hf.world(std::uint32_t(i), std::uint32_t(j)));
              hi = std::max(hi, hf.world(std::uint32_t(i), std::uint32_t(j)));
            }
          const std::int64_t li = std::int64_t{tx} * kDetailTileCells;
          const std::int64_t lj = std::int64_t{tz} * kDetailTileCells;
          const double a = f.contribution_bound(1, l, li, lj, li + 128, lj + 128);
          dy = vertical(lo - a, hi + a);
        }
        const double d = std::sqrt(dx * dx + dz * dz + dy * dy);
        if (d <= (1 + rule.prefetch) * r) out.insert({l, tx, tz, d <= r});
      }
  }
  return out;
}

TEST(DetailStream, RuleListsExactlyTheTilesWithinTheRadius) {
  auto terrain = make_detailed();
  DetailViewRule rule;
  // Inside, near a corner (tiles clipped by the footprint), high up, and outside the footprint.
  for (const Camera& c : {camera_at(9000, 14000, 260), camera_at(-400, 400, 40),
                          camera_at(12000, 12000, 3000), camera_at(-2500, 9000, 50)}) {
    std::vector<DetailTileNeed> tiles;
    ASSERT_TRUE(detail_tiles_for_view(terrain->surface(), c, rule, tiles).ok());
    std::set<std::tuple<std::uint32_t, int, int, bool>> got;
    for (const auto& t : tiles) got.insert({t.key.level, t.key.tx, t.key.tz, t.needed});
    EXPECT_EQ(got.size(), tiles.size()) << "a tile listed twice";
    EXPECT_EQ(got, brute_force(*terrain, c, rule));
    // Coarsest level first, nearest first within a level.
    for (std::size_t k = 1; k < tiles.size(); ++k) {
      ASSERT_LE(tiles[k - 1].key.level, tiles[k].key.level);
      if (tiles[k - 1].key.level == tiles[k].key.level) {
        EXPECT_LE(tiles[k - 1].distance_m, tiles[k].distance_m);
      }
    }
  }
  // A camera high above everything needs fewer fine tiles than one near the ground.
  std::vector<DetailTileNeed> low, high;
  const Surface& s = terrain->surface();
  ASSERT_TRUE(detail_tiles_for_view(s, camera_at(9000, 14000, 400), rule, low).ok());
  ASSERT_TRUE(detail_tiles_for_view(s, camera_at(9000, 14000, 2500), rule, high).ok());
  auto count = [](const std::vector<DetailTileNeed>& v, std::uint32_t l) {
    return std::count_if(v.begin(), v.end(), [l](const auto& t) { return t.key.level == l; });
  };
  EXPECT_GT(count(low, 6), 0);
  EXPECT_EQ(count(high, 6), 0);
}

TEST(DetailStream, RadiiHalvePerLevelAndAncestorsAreNeeded) {
  auto terrain = make_detailed();
  auto f = field_of(terrain);
  const Camera c = camera_at(7000, 15000, 250);
  DetailViewRule rule;
  const double k = projection_scale(c);
  for (std::uint32_t l = 1; l <= f->levels(); ++l)
    EXPECT_DOUBLE_EQ(detail_level_radius(*f, c, l, rule), kSpacing / double(1 << l) * k);
  EXPECT_EQ(detail_level_radius(*f, c, 0, rule), 0.0);
  EXPECT_EQ(detail_level_radius(*f, c, 7, rule), 0.0);
  rule.pixels = 2;
  EXPECT_DOUBLE_EQ(detail_level_radius(*f, c, 3, rule), kSpacing / 8 * k / 2);

  std::vector<DetailTileNeed> tiles;
  ASSERT_TRUE(detail_tiles_for_view(terrain->surface(), c, DetailViewRule{}, tiles).ok());
  std::set<std::tuple<std::uint32_t, int, int>> needed;
  for (const auto& t : tiles)
    if (t.needed) needed.insert({t.key.level, t.key.tx, t.key.tz});
  ASSERT_FALSE(needed.empty());
  for (const auto& [l, tx, tz] : needed) {
    if (l > 1) {
      EXPECT_TRUE(needed.count({l - 1, tx >> 1, tz >> 1})) << l << " " << tx << " " << tz;
    }
  }
}

TEST(DetailStream, BadInputRefused) {
  auto terrain = make_detailed();
  auto f = field_of(terrain);
  std::vector<DetailTileNeed> tiles(3);
  const Camera good = camera_at(9000, 9000, 300);
  auto refused = [&](const DetailViewRule& rule, const Camera& c, const char* needle) {
    const Status s = detail_tiles_for_view(terrain->surface(), c, rule, tiles);
    ASSERT_FALSE(s.ok()) << needle;
    EXPECT_NE(s.message().find(needle), std::string::npos) << s.message();
    EXPECT_TRUE(tiles.empty());
  };
  DetailViewRule r;
  r.pixels = 0;
  refused(r, good, "pixels is 0");
  r.pixels = std::numeric_limits<double>::quiet_NaN();
  refused(r, good, "pixels is nan");
  r = {};
  r.prefetch = 5;
  refused(r, good, "prefetch is 5");
  r.prefetch = -0.5;
  refused(r, good, "prefetch is -0.5");
  r = {};
  r.max_tiles = 0;
  refused(r, good, "max_tiles");
  Camera bad = good;
  bad.eye.x = std::numeric_limits<double>::infinity();
  refused(DetailViewRule{}, bad, "");
  bad = good;
  bad.target = bad.eye;
  refused(DetailViewRule{}, bad, "");
  // A rule that would flood the cache (here the whole footprint: 21,840 tiles).
  r = {};
  r.pixels = 0.01;
  r.max_tiles = 10000;
  refused(r, good, "more than 10000 tiles");

  auto cache = DetailCache::create(f, cache_desc(8u << 20, 0));
  ASSERT_TRUE(cache.ok());
  r = {};
  r.prefetch = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(DetailStream::create(terrain->surface(), **cache, r).ok());
  // A cache of another field (the same parameters, another object) is not the surface's.
  auto other = DetailField::create(make_heightfield(), terrain->surface().detail()->params());
  ASSERT_TRUE(other.ok());
  auto other_cache = DetailCache::create(*other, cache_desc(8u << 20, 0));
  ASSERT_TRUE(other_cache.ok());
  auto wrong = DetailStream::create(terrain->surface(), **other_cache);
  ASSERT_FALSE(wrong.ok());
  EXPECT_NE(wrong.error().message.find("another detail field"), std::string::npos);
  auto stream = DetailStream::create(terrain->surface(), **cache);
  ASSERT_TRUE(stream.ok());
  bad = good;
  bad.fov_y_deg = 180;
  EXPECT_FALSE(stream->frame(bad).ok());
  EXPECT_EQ((*cache)->stats().frame, 0u) << "a refused frame must not update the cache";
}

// Compares `count` tiles of the snapshot with the direct evaluator at random samples, the
// corners and the aprons.
void expect_tiles_match_direct(const DetailCache& cache, const std::vector<DetailTileNeed>& tiles,
                               std::mt19937& rng, int count, bool require = true) {
  const auto snap = cache.snapshot();
  const DetailField& f = cache.field();
  std::vector<const DetailTile*> found;
  for (const auto& t : tiles)
    if (const DetailTile* tile = snap->find(t.key)) found.push_back(tile);
  if (!require && found.empty()) return;  // nothing delivered yet (asynchronous mode)
  ASSERT_FALSE(found.empty());
  std::uniform_int_distribution<std::size_t> pick(0, found.size() - 1);
  std::uniform_int_distribution<std::int32_t> local(-kDetailTileApron,
                                                    kDetailTileCells + kDetailTileApron);
  for (int n = 0; n < count; ++n) {
    const DetailTile& tile = *found[pick(rng)];
    const std::uint32_t l = tile.key().level;
    std::vector<std::pair<std::int32_t, std::int32_t>> points = {{0, 0},     {128, 0}, {0, 128},
                                                                 {128, 128}, {-3, -3}, {131, 131}};
    for (int k = 0; k < 10; ++k) points.push_back({local(rng), local(rng)});
    for (auto [li, lj] : points)
      ASSERT_EQ(tile.raw(li, lj), f.detail_raw(l, tile.first_i() + li, tile.first_j() + lj))
          << "level " << l << " tile " << tile.key().tx << "," << tile.key().tz << " sample " << li
          << "," << lj;
  }
}

struct FlightResult {
  std::size_t max_resident_bytes = 0;
  std::size_t max_needed = 0;
  double min_needed_fraction = 1;
  std::uint64_t evicted = 0, generated = 0;
};

// Flies from (1000, 13000) east at 300 m/s, 40 m above the stored surface, dt 1/60 s, for
// `metres`; checks the budget after every frame and tiles against the direct evaluator now
// and then.
FlightResult fly(const std::shared_ptr<const Terrain>& terrain, const DetailCacheDesc& desc,
                 double metres, bool working_set_fits = true) {
  FlightResult r;
  auto cache = DetailCache::create(field_of(terrain), desc);
  EXPECT_TRUE(cache.ok()) << (cache.ok() ? "" : cache.error().message);
  if (!cache.ok()) return r;
  auto stream = DetailStream::create(terrain->surface(), **cache);
  EXPECT_TRUE(stream.ok());
  std::mt19937 rng(5);
  const double speed = 300, dt = 1.0 / 60;
  const int frames = int(std::lround(metres / (speed * dt)));
  Camera c;
  for (int k = 0; k <= frames; ++k) {
    const double x = 1000 + speed * dt * k, z = 13000;
    c = camera_at(x, z, *terrain->height(x, z) + 40, 1, 0.2);
    auto st = stream->frame(c);
    EXPECT_TRUE(st.ok());
    if (!st.ok()) return r;
    EXPECT_LE(st->cache.resident_bytes, desc.budget_bytes) << "frame " << k;
    r.max_resident_bytes = std::max(r.max_resident_bytes, st->cache.resident_bytes);
    r.max_needed = std::max(r.max_needed, st->needed);
    r.min_needed_fraction =
        std::min(r.min_needed_fraction, double(st->needed_resident) / double(st->needed));
    if (k % 500 == 0) expect_tiles_match_direct(**cache, stream->tiles(), rng, 4, false);
  }
  // Let the workers finish: after one frame whose requests were all generated, every needed
  // tile is resident (when the working set fits the budget).
  for (int round = 0; working_set_fits && round < 3; ++round) {
    EXPECT_TRUE((*cache)->wait_idle(60.0));
    auto st = stream->frame(c);
    EXPECT_TRUE(st.ok());
    if (!st.ok()) return r;
    EXPECT_LE(st->cache.resident_bytes, desc.budget_bytes);
    if (st->needed_resident == st->needed) break;
    EXPECT_LT(round, 2) << "needed tiles still missing after the cache went idle";
  }
  expect_tiles_match_direct(**cache, stream->tiles(), rng, 16);
  const DetailCacheStats s = (*cache)->stats();
  r.evicted = s.evicted;
  r.generated = s.generated;
  return r;
}

TEST(DetailStream, FlightStaysUnderBudgetSynchronous) {
  auto terrain = make_detailed();
  const std::size_t budget = std::size_t{32} << 20;
  const FlightResult r = fly(terrain, cache_desc(budget, 0), 20000);
  EXPECT_LE(r.max_resident_bytes, budget);
  // The working set fits: every needed tile is there every frame, and the flight reached the
  // budget and evicted (20 km of tiles do not fit in 32 MB).
  EXPECT_EQ(r.min_needed_fraction, 1.0);
  EXPECT_GT(r.max_needed, 50u);
  EXPECT_GT(r.evicted, 0u);
  EXPECT_GT(r.max_resident_bytes, budget - 2 * 73000);
}

TEST(DetailStream, FlightStaysUnderBudgetAsynchronous) {
  auto terrain = make_detailed();
  const std::size_t budget = std::size_t{32} << 20;
  for (std::uint32_t workers : {1u, 3u}) {
    const FlightResult r = fly(terrain, cache_desc(budget, workers), 20000);
    EXPECT_LE(r.max_resident_bytes, budget) << workers;
    EXPECT_GT(r.evicted, 0u) << workers;
  }
}

TEST(DetailStream, BudgetBelowTheWorkingSetStillHolds) {
  // A budget smaller than what the view needs: the LRU keeps the bytes under it; needed tiles
  // are then missing at times (it thrashes), which the statistics show.
  auto terrain = make_detailed();
  const std::size_t budget = std::size_t{6} << 20;  // 86 tiles
  const FlightResult r = fly(terrain, cache_desc(budget, 0), 60, false);
  EXPECT_LE(r.max_resident_bytes, budget);
  EXPECT_GT(r.max_needed * 73000, budget);
  EXPECT_LT(r.min_needed_fraction, 1.0);
}

}  // namespace
}  // namespace ridgeline
