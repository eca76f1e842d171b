// The detail layer's core (detail.h): determinism, tiles == direct evaluator, seams, the
// amplitude bound against brute force, the cache (LRU budget, asynchronous delivery), bad input.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <random>
#include <thread>
#include <vector>

#include "ridgeline/detail.h"
#include "ridgeline/scenes.h"
#include "ridgeline/surface.h"
#include "ridgeline/terrain.h"

namespace ridgeline {
namespace {

// 65 x 65 samples, 8 m apart: a flat plain (x < 200 m) next to steep sinusoidal hills.
Heightfield make_heightfield() {
  auto hf = scenes::field(
      {.width = 65, .height = 65, .spacing_x = 8, .spacing_z = 8, .origin_x = -100, .origin_z = 50},
      [](int i, int j) {
        const double x = i * 8.0, z = j * 8.0;
        return x < 200 ? 10.0 : 10 + 60 * std::sin(x / 40.0) * std::cos(z / 55.0) + 0.3 * (x - 200);
      });
  EXPECT_TRUE(hf.ok());
  return std::move(hf).value();
}

std::shared_ptr<const Terrain> make_terrain() {
  return Terrain::create(make_heightfield()).value();
}

DetailParams params(std::uint32_t levels, std::uint64_t seed, double amplitude, double gain) {
  DetailParams p;
  p.levels = levels;
  p.seed = seed;
  p.amplitude = amplitude;
  p.gain = gain;
  return p;
}

std::shared_ptr<const DetailField> make_field(std::uint32_t levels, std::uint64_t seed = 7,
                                              double amplitude = 3.0, double gain = 0.55) {
  auto f = DetailField::create(make_heightfield(), params(levels, seed, amplitude, gain));
  EXPECT_TRUE(f.ok()) << (f.ok() ? "" : f.error().message);
  return std::move(f).value();
}

// make_terrain() with make_field()'s detail as part of its surface (a synchronous cache).
std::shared_ptr<const Terrain> make_detailed(std::uint32_t levels, std::uint64_t seed = 7,
                                             double amplitude = 3.0, double gain = 0.55) {
  DetailCacheDesc d;
  d.worker_threads = 0;
  auto t = Terrain::create(make_heightfield(), params(levels, seed, amplitude, gain), d);
  EXPECT_TRUE(t.ok()) << (t.ok() ? "" : t.error().message);
  return std::move(t).value();
}

std::uint64_t fnv(std::uint64_t h, std::int32_t v) {
  for (int b = 0; b < 4; ++b) h = (h ^ ((std::uint32_t(v) >> (8 * b)) & 0xFF)) * 0x100000001b3ull;
  return h;
}

// Hash of level-L detail over rows [j0, j1) of a 256-wide region, one row at a time.
std::uint64_t hash_rows(const DetailField& f, std::int64_t j0, std::int64_t j1) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  std::vector<std::int32_t> row(256);
  for (std::int64_t j = j0; j < j1; ++j) {
    f.detail_window(f.levels(), -40, j, 256, 1, row);
    for (std::int32_t v : row) h = fnv(h, v);
  }
  return h;
}

TEST(Detail, BadParamsRefused) {
  const Heightfield hf = make_heightfield();
  auto refused = [&](DetailParams p, const char* needle) {
    auto f = DetailField::create(hf, p);
    ASSERT_FALSE(f.ok()) << needle;
    EXPECT_NE(f.error().message.find(needle), std::string::npos) << f.error().message;
    EXPECT_FALSE(validate_detail_params(p).ok());
  };
  DetailParams p;
  p.levels = 13;
  refused(p, "levels is 13");
  p = {};
  p.amplitude = -1;
  refused(p, "amplitude (metres) is -1");
  p.amplitude = std::nan("");
  refused(p, "amplitude (metres) is nan");
  p.amplitude = 2000;
  refused(p, "amplitude (metres) is 2e+03");
  p = {};
  p.gain = 0;
  refused(p, "gain is 0");
  p.gain = 1.5;
  refused(p, "gain is 1.5");
  p.gain = INFINITY;
  refused(p, "gain is inf");
  p = {};
  p.flat_shape = 2;
  refused(p, "flat shape is 2");
  p = {};
  p.steep_shape = -0.5;
  refused(p, "steep shape is -0.5");
  p = {};
  p.flat_slope = -1;
  refused(p, "flat slope is -1");
  p = {};
  p.steep_slope = p.flat_slope;
  refused(p, "steep slope is 0.05");
  p = {};
  p.blur_radius = 65;
  refused(p, "blur radius is 65");
  // Valid fields whose sum can overflow the fixed-point range.
  p = {};
  p.levels = 12;
  p.amplitude = 1000;
  p.gain = 1;
  auto f = DetailField::create(hf, p);
  ASSERT_FALSE(f.ok());
  EXPECT_NE(f.error().message.find("can reach"), std::string::npos) << f.error().message;
  EXPECT_TRUE(validate_detail_params(p).ok());  // each field alone is fine

  // The cache refuses what it cannot work with.
  auto field = make_field(4);
  DetailCacheDesc d;
  d.budget_bytes = 1000;
  auto c = DetailCache::create(field, d);
  ASSERT_FALSE(c.ok());
  EXPECT_NE(c.error().message.find("budget of 1000 bytes"), std::string::npos) << c.error().message;
  d = {};
  d.worker_threads = 65;
  EXPECT_FALSE(DetailCache::create(field, d).ok());
  EXPECT_FALSE(DetailCache::create(nullptr, {}).ok());
  EXPECT_FALSE(DetailCache::create(make_field(0), {}).ok());
}

TEST(Detail, LevelZeroAndParentSamplesKeepTheirValues) {
  auto f = make_field(5);
  std::mt19937_64 rng(1);
  std::uniform_int_distribution<std::int64_t> idx(-300, 300);
  for (int n = 0; n < 2000; ++n) {
    const std::int64_t i = idx(rng), j = idx(rng);
    EXPECT_EQ(f->detail_raw(0, i, j), 0);
    for (std::uint32_t l = 1; l <= 5; ++l)
      ASSERT_EQ(f->detail_raw(l, 2 * i, 2 * j), f->detail_raw(l - 1, i, j)) << l << " " << i;
  }
  // The finest lattice at a base sample is the stored height exactly.
  auto t = make_detailed(5);
  const Heightfield hf = t->surface().to_heightfield().value();
  for (std::uint32_t j = 0; j < hf.height(); j += 7)
    for (std::uint32_t i = 0; i < hf.width(); i += 5)
      EXPECT_EQ(t->surface().vertex_height(std::int64_t{i} << 5, std::int64_t{j} << 5),
                hf.local(i, j));
}

TEST(Detail, TilesReproduceTheDirectEvaluatorBitForBit) {
  constexpr std::uint32_t kLevels = 7;
  auto f = make_field(kLevels, 99);
  std::mt19937_64 rng(2);
  for (std::uint32_t l = 1; l <= kLevels; ++l) {
    // Tiles on both sides of the origin (negative indices, arithmetic shifts) and inside.
    const std::int32_t span = std::max(1, (64 << l) / kDetailTileCells);
    std::uniform_int_distribution<std::int32_t> tdist(-1, span);
    for (int t = 0; t < 3; ++t) {
      const DetailTileKey key{l, tdist(rng), tdist(rng)};
      auto tile = f->make_tile_chain(key);
      ASSERT_EQ(tile->key(), key);
      std::uniform_int_distribution<std::int32_t> s(-kDetailTileApron,
                                                    kDetailTileCells + kDetailTileApron);
      for (int n = 0; n < 300; ++n) {
        const std::int32_t li = s(rng), lj = s(rng);
        ASSERT_EQ(tile->raw(li, lj), f->detail_raw(l, tile->first_i() + li, tile->first_j() + lj))
            << "level " << l << " tile " << key.tx << "," << key.tz << " at " << li << "," << lj;
      }
      // A whole row and a whole column through detail_window.
      std::vector<std::int32_t> row(kDetailTileStride);
      f->detail_window(l, tile->first_i() - kDetailTileApron, tile->first_j() + 17,
                       kDetailTileStride, 1, row);
      for (std::int32_t li = -kDetailTileApron; li <= kDetailTileCells + kDetailTileApron; ++li)
        ASSERT_EQ(row[std::size_t(li + kDetailTileApron)], tile->raw(li, 17));
      f->detail_window(l, tile->first_i() + 5, tile->first_j() - kDetailTileApron, 1,
                       kDetailTileStride, row);
      for (std::int32_t lj = -kDetailTileApron; lj <= kDetailTileCells + kDetailTileApron; ++lj)
        ASSERT_EQ(row[std::size_t(lj + kDetailTileApron)], tile->raw(5, lj));
      double lo = 1e30, hi = -1e30;
      for (std::int32_t lj = 0; lj <= kDetailTileCells; ++lj)
        for (std::int32_t li = 0; li <= kDetailTileCells; ++li)
          lo = std::min(lo, tile->detail(li, lj)), hi = std::max(hi, tile->detail(li, lj));
      EXPECT_EQ(tile->min_detail(), lo);
      EXPECT_EQ(tile->max_detail(), hi);
    }
  }
}

TEST(Detail, NeighbouringTilesShareTheirSeams) {
  auto f = make_field(6, 3);
  for (std::uint32_t l = 1; l <= 6; ++l) {
    const auto a = f->make_tile_chain({l, 0, 1});
    const auto right = f->make_tile_chain({l, 1, 1});
    const auto below = f->make_tile_chain({l, 0, 2});
    const auto left = f->make_tile_chain({l, -1, 1});
    for (std::int32_t s = -kDetailTileApron; s <= kDetailTileCells + kDetailTileApron; ++s)
      for (std::int32_t o = -kDetailTileApron; o <= kDetailTileApron; ++o) {
        // Every sample the two tiles both store (edge and aprons) is identical.
        ASSERT_EQ(a->raw(kDetailTileCells + o, s), right->raw(o, s)) << l;
        ASSERT_EQ(a->raw(s, kDetailTileCells + o), below->raw(s, o)) << l;
        ASSERT_EQ(a->raw(o, s), left->raw(kDetailTileCells + o, s)) << l;
      }
  }
}

TEST(Detail, DeterministicAcrossRunsAndThreadCounts) {
  auto f = make_field(6, 12345);
  const std::uint64_t one = hash_rows(*f, -40, 216);
  // Four threads, each a quarter of the rows, combined in row order.
  std::vector<std::vector<std::int32_t>> parts(4);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      std::vector<std::int32_t> row(256);
      for (std::int64_t j = -40 + 64 * t; j < -40 + 64 * (t + 1); ++j) {
        f->detail_window(6, -40, j, 256, 1, row);
        parts[t].insert(parts[t].end(), row.begin(), row.end());
      }
    });
  for (auto& t : threads) t.join();
  std::uint64_t four = 0xcbf29ce484222325ull;
  for (const auto& p : parts)
    for (std::int32_t v : p) four = fnv(four, v);
  EXPECT_EQ(one, four);
  // A second field with the same parameters, and the golden value from the first run of this
  // test (integer arithmetic throughout: the same on every platform and compiler).
  EXPECT_EQ(one, hash_rows(*make_field(6, 12345), -40, 216));
  std::printf("detail hash (levels 6, seed 12345): 0x%016llx\n", (unsigned long long)one);
  EXPECT_EQ(one, 0xf0219510bdd0082full);
  // Another seed gives another surface.
  EXPECT_NE(one, hash_rows(*make_field(6, 12346), -40, 216));

  // Heights (base + detail, doubles) over a region: one thread against three, bit for bit.
  auto detailed = make_detailed(6, 12345);
  auto height_hash = [&](std::int64_t j0, std::int64_t j1) {
    std::uint64_t h = 0xcbf29ce484222325ull;
    for (std::int64_t j = j0; j < j1; ++j)
      for (std::int64_t i = 1000; i < 1300; ++i) {
        const double v = detailed->surface().vertex_height(i, j);
        std::uint64_t bits;
        std::memcpy(&bits, &v, sizeof bits);
        h = fnv(fnv(h, std::int32_t(bits)), std::int32_t(bits >> 32));
      }
    return h;
  };
  const std::uint64_t serial = height_hash(2000, 2090);
  std::uint64_t parts3[3];
  std::vector<std::thread> hthreads;
  for (int t = 0; t < 3; ++t)
    hthreads.emplace_back([&, t] { parts3[t] = height_hash(2000 + 30 * t, 2030 + 30 * t); });
  for (auto& t : hthreads) t.join();
  std::uint64_t again[3] = {height_hash(2000, 2030), height_hash(2030, 2060),
                            height_hash(2060, 2090)};
  for (int t = 0; t < 3; ++t) EXPECT_EQ(parts3[t], again[t]);
  EXPECT_EQ(serial, height_hash(2000, 2090));
}

// Brute force: the largest |D_L(v) - P(v)| over the finest samples of a rectangle, P the
// piecewise-linear interpolation (diagonal rule) of the level-(from - 1) lattice.
double brute_contribution(const DetailField& f, std::uint32_t from, std::int64_t i0,
                          std::int64_t j0, std::uint32_t n) {
  const std::uint32_t L = f.levels(), s = L - (from - 1);
  std::vector<std::int32_t> fine(std::size_t(n) * n);
  f.detail_window(L, i0, j0, n, n, fine);
  const std::int64_t k0 = i0 >> s, m0 = j0 >> s, cn = ((n - 1) >> s) + 3;
  std::vector<std::int32_t> coarse(std::size_t(cn * cn));
  f.detail_window(from - 1, k0, m0, std::uint32_t(cn), std::uint32_t(cn), coarse);
  const std::int64_t mask = (std::int64_t{1} << s) - 1;
  double worst = 0;
  for (std::int64_t b = 0; b < n; ++b)
    for (std::int64_t a = 0; a < n; ++a) {
      const std::int64_t I = i0 + a, J = j0 + b, k = I >> s, m = J >> s;
      const CellTriangle t = locate_in_cell(k, m, std::ldexp(float(I & mask), -int(s)),
                                            std::ldexp(float(J & mask), -int(s)));
      double p = 0;
      for (int c = 0; c < 3; ++c)
        p += double(t.w[c]) * coarse[std::size_t((k + t.di[c] - k0) + (m + t.dj[c] - m0) * cn)];
      worst = std::max(worst, std::abs(fine[std::size_t(a + b * n)] - p) * kDetailUnit);
    }
  return worst;
}

TEST(Detail, AmplitudeBoundHoldsAgainstBruteForce) {
  constexpr std::uint32_t kLevels = 6;
  for (double gain : {0.5, 0.8}) {
    auto f = make_field(kLevels, 5, 4.0, gain);
    std::mt19937_64 rng(3);
    // Regions of 96 x 96 finest samples (1.5 x 1.5 base cells at level 6) over flat and steep
    // ground, plus the whole-lattice bound.
    std::uniform_int_distribution<std::int64_t> pos(-100, 64 << kLevels);
    for (int r = 0; r < 12; ++r) {
      const std::int64_t i0 = pos(rng), j0 = pos(rng);
      for (std::uint32_t from = 1; from <= kLevels; ++from) {
        const double brute = brute_contribution(*f, from, i0, j0, 96);
        const double bound = f->contribution_bound(from, kLevels, i0, j0, i0 + 95, j0 + 95);
        ASSERT_LE(brute, bound) << "gain " << gain << " from " << from << " at " << i0 << "," << j0;
        ASSERT_LE(bound, f->contribution_bound(from));
        if (r == 0)
          std::printf("gain %.1f from level %u: brute %.4f m, bound %.4f m (ratio %.2f)\n", gain,
                      from, brute, bound, bound / std::max(brute, 1e-12));
      }
    }
    EXPECT_EQ(f->contribution_bound(kLevels + 1), 0.0);
    // Flat ground gets a smaller bound than steep ground (the shape field).
    const double flat = f->contribution_bound(1, 0, 2, 2, 10, 10);
    const double steep = f->contribution_bound(1, 0, 40, 2, 50, 10);
    EXPECT_LT(flat, 0.5 * steep);
  }
}

TEST(Detail, RegionalBoundUsesTheLargestShapeInReach) {
  // From the finest level only, the bound is (a_L + a_{L-1}) * max shape + 1 unit: recover the
  // max shape it used and compare with a brute-force scan of the stored samples in reach.
  auto f = make_field(5);
  const double unit = kDetailUnit;
  double all = 0;
  for (int j = 0; j < 65; ++j)
    for (int i = 0; i < 65; ++i) all = std::max(all, f->shape(0, i, j));
  const double per_shape = (f->contribution_bound(5) - unit) / all;
  std::mt19937_64 rng(9);
  std::uniform_int_distribution<std::int64_t> pos(-5, 70), len(0, 40);
  for (int n = 0; n < 500; ++n) {
    const std::int64_t i0 = pos(rng), j0 = pos(rng), i1 = i0 + len(rng), j1 = j0 + len(rng);
    double want = 0;
    for (std::int64_t j = std::max<std::int64_t>(j0 - 1, 0);
         j <= std::min<std::int64_t>(j1 + 2, 64); ++j)
      for (std::int64_t i = std::max<std::int64_t>(i0 - 1, 0);
           i <= std::min<std::int64_t>(i1 + 2, 64); ++i)
        want = std::max(want, f->shape(0, i, j));
    if (i0 - 1 > 64 || j0 - 1 > 64)
      want = f->shape(0, std::min<std::int64_t>(i0, 64), std::min<std::int64_t>(j0, 64));
    const double got = (f->contribution_bound(5, 0, i0, j0, i1, j1) - unit) / per_shape;
    // The pyramid may take a few more samples (whole blocks), never fewer.
    ASSERT_GE(got, want - 1e-9) << i0 << "," << j0 << " .. " << i1 << "," << j1;
  }
}

TEST(Detail, ShapeFieldIsSmoothAndFollowsSlope) {
  auto f = make_field(8);
  // Flat plain: flat_shape; inside the hills somewhere: steep_shape.
  EXPECT_NEAR(f->shape(0, 5, 30), 0.25, 1e-4);
  double most = 0;
  for (int i = 30; i < 64; ++i) most = std::max(most, f->shape(0, i, 30));
  EXPECT_NEAR(most, 1.0, 1e-4);
  // C1 along a line of level-8 samples: the step between neighbours changes slowly (no kinks at
  // base samples, unlike bilinear weights).
  double worst_jump = 0;
  double prev_step = f->shape(8, 1, 30 << 8) - f->shape(8, 0, 30 << 8);
  for (std::int64_t i = 1; i < (64 << 8) - 1; ++i) {
    const double step = f->shape(8, i + 1, 30 << 8) - f->shape(8, i, 30 << 8);
    worst_jump = std::max(worst_jump, std::abs(step - prev_step));
    prev_step = step;
  }
  EXPECT_LT(worst_jump, 2e-4);  // steps themselves reach ~3e-3 on the ramps
}

TEST(Detail, HeightsAreBasePlusDetail) {
  auto f = make_field(4);
  auto base = make_terrain();  // the same samples without detail
  auto t = make_detailed(4);   // with f's detail
  const Surface& s = t->surface();
  const double offset = t->info().height_offset;
  std::mt19937_64 rng(4);
  std::uniform_int_distribution<std::int64_t> idx(0, 64 << 4);
  for (int n = 0; n < 500; ++n) {
    const std::int64_t i = idx(rng), j = idx(rng);
    const auto b = base->height(f->lattice_x(4, i), f->lattice_z(4, j));
    ASSERT_TRUE(b);
    EXPECT_NEAR(offset + s.vertex_height(i, j), *b + f->detail(4, i, j), 1e-4);
    EXPECT_EQ(s.vertex_detail(i, j), f->detail(4, i, j));
  }
  // Outside the lattice the vertex is clamped in (the padding rule).
  EXPECT_EQ(s.vertex_height(-1, 0), s.vertex_height(0, 0));
  EXPECT_EQ(s.vertex_height(0, (64 << 4) + 1), s.vertex_height(0, 64 << 4));
  EXPECT_EQ(f->lattice_x(4, 16), -100 + 8.0);
  EXPECT_EQ(f->lattice_z(4, 16), 50 + 8.0);
  EXPECT_EQ(f->base_width(), 65u);
  EXPECT_EQ(f->spacing_x(), 8.0);
}

// Tiles of the 128 x 128-cell lattice along a diagonal flight, finest level first with its
// ancestors, as ROAM would request them.
std::vector<DetailTileKey> flight(std::uint32_t level, int steps) {
  std::vector<DetailTileKey> keys;
  for (int s = 0; s < steps; ++s) keys.push_back({level, s, s / 2});
  return keys;
}

TEST(DetailCache, SynchronousLruStaysUnderBudget) {
  auto f = make_field(6);
  const std::size_t tile_bytes = f->make_tile({1, 0, 0}, nullptr)->memory_bytes();
  DetailCacheDesc d;
  d.worker_threads = 0;
  d.budget_bytes = 20 * tile_bytes + tile_bytes / 2;
  auto cache = DetailCache::create(f, d);
  ASSERT_TRUE(cache.ok()) << cache.error().message;
  DetailCache& c = **cache;
  std::size_t most = 0;
  for (const DetailTileKey& k : flight(6, 40)) {
    c.update();
    EXPECT_TRUE(c.request(k));  // synchronous: ready at once
    const auto tile = c.try_get(k);
    ASSERT_TRUE(tile);
    EXPECT_EQ(tile->raw(64, 64), f->detail_raw(6, tile->first_i() + 64, tile->first_j() + 64));
    const DetailCacheStats s = c.stats();
    EXPECT_LE(s.resident_bytes, d.budget_bytes);
    most = std::max(most, s.resident_tiles);
  }
  const DetailCacheStats s = c.stats();
  EXPECT_EQ(most, 20u);
  EXPECT_GT(s.evicted, 0u);
  EXPECT_EQ(s.resident_tiles + s.evicted, s.generated);
  EXPECT_EQ(s.pending, 0u);
  // The most recent tiles survive; the oldest were evicted.
  EXPECT_TRUE(c.snapshot()->find({6, 39, 19}));
  EXPECT_FALSE(c.snapshot()->find({6, 0, 0}));
}

TEST(DetailCache, AsynchronousDeliversTheSameTiles) {
  auto f = make_field(5);
  for (std::uint32_t threads : {1u, 3u}) {
    DetailCacheDesc d;
    d.worker_threads = threads;
    auto cache = DetailCache::create(f, d);
    ASSERT_TRUE(cache.ok());
    DetailCache& c = **cache;
    const auto keys = flight(5, 12);
    std::size_t ready = 0;
    for (int frame = 0; frame < 1000 && ready < keys.size(); ++frame) {
      c.update();
      ready = 0;
      for (const auto& k : keys) ready += c.request(k) ? 1 : 0;
      if (ready < keys.size()) c.wait_idle(0.05);
    }
    ASSERT_EQ(ready, keys.size());
    c.update();
    auto snap = c.snapshot();
    for (const auto& k : keys) {
      const DetailTile* t = snap->find(k);
      ASSERT_TRUE(t);
      const auto ref = f->make_tile_chain(k);
      for (std::int32_t lj = 0; lj <= kDetailTileCells; lj += 9)
        for (std::int32_t li = 0; li <= kDetailTileCells; li += 7)
          ASSERT_EQ(t->raw(li, lj), ref->raw(li, lj));
    }
    const DetailCacheStats s = c.stats();
    EXPECT_EQ(s.pending, 0u);
    EXPECT_GE(s.generated, keys.size());
    EXPECT_GT(s.generation_seconds, 0.0);
  }
}

// request_many() (one lock for a frame's requests) behaves as request() one key at a time: in
// every mode the same tiles become resident, the count it returns is the resident keys, and a
// key asked for twice is queued once.
TEST(DetailCache, RequestManyMatchesRequestOneByOne) {
  auto f = make_field(5);
  std::vector<DetailTileKey> keys = flight(5, 12);
  keys.push_back(keys.front());  // a duplicate
  for (std::uint32_t threads : {0u, 1u, 3u}) {
    DetailCacheDesc d;
    d.worker_threads = threads;
    auto cache = DetailCache::create(f, d);
    ASSERT_TRUE(cache.ok());
    DetailCache& c = **cache;
    std::size_t ready = 0;
    for (int frame = 0; frame < 1000 && ready < keys.size(); ++frame) {
      c.update();
      ready = c.request_many(keys.data(), keys.size(), frame % 2 == 0);
      std::size_t resident = 0;
      for (const auto& k : keys) resident += c.try_get(k) ? 1 : 0;
      if (threads == 0) {
        EXPECT_EQ(ready, keys.size()) << "synchronous: every tile at once";
      }
      EXPECT_LE(ready, resident) << threads << " workers, frame " << frame;
      if (ready < keys.size()) c.wait_idle(0.05);
    }
    ASSERT_EQ(ready, keys.size()) << threads << " workers";
    c.update();
    const auto snap = c.snapshot();
    for (const auto& k : keys) {
      const DetailTile* t = snap->find(k);
      ASSERT_TRUE(t);
      EXPECT_EQ(t->raw(64, 64), f->make_tile_chain(k)->raw(64, 64));
    }
    const DetailCacheStats s = c.stats();
    EXPECT_EQ(s.pending, 0u);
    // Every key generated once (its ancestors too, at most), the duplicate not again.
    EXPECT_LE(s.generated, 4 * (keys.size() - 1));
  }
}

TEST(DetailCache, RequestNeverWaitsForGeneration) {
  auto f = make_field(4);
  // An engine job system that runs nothing until told to: request() must still return at once.
  std::mutex mu;
  std::vector<std::function<void()>> jobs;
  DetailCacheDesc d;
  d.executor = [&](std::function<void()> job) {
    std::lock_guard<std::mutex> lock(mu);
    jobs.push_back(std::move(job));
  };
  auto cache = DetailCache::create(f, d);
  ASSERT_TRUE(cache.ok());
  DetailCache& c = **cache;
  const DetailTileKey key{4, 2, 1};
  EXPECT_FALSE(c.request(key));
  EXPECT_FALSE(c.request(key));  // queued once
  EXPECT_FALSE(c.try_get(key));
  EXPECT_FALSE(c.wait_idle(0.01));
  EXPECT_EQ(c.stats().pending, 1u);
  c.update();
  c.update();
  EXPECT_FALSE(c.request(key));
  ASSERT_EQ(jobs.size(), 1u);
  std::thread runner([&] { jobs[0](); });  // the engine runs the job on one of its threads
  runner.join();
  EXPECT_TRUE(c.wait_idle(5.0));
  EXPECT_FALSE(c.try_get(key));  // generated, not yet integrated
  c.update();
  EXPECT_TRUE(c.try_get(key));
  EXPECT_TRUE(c.request(key));
  const DetailCacheStats s = c.stats();
  EXPECT_EQ(s.worst_lag_frames, 3u);  // requested before update 1, integrated at update 3
  EXPECT_EQ(s.generated, 4u);         // the tile and its three ancestors
  EXPECT_EQ(s.pending, 0u);
  // A job that outlives its cache does nothing.
  EXPECT_FALSE(c.request({4, 5, 5}));
  ASSERT_EQ(jobs.size(), 2u);
  cache = Error{"gone"};
  jobs[1]();
}

TEST(DetailCache, ReadersNeedNoLockWhileTheOwnerUpdates) {
  auto f = make_field(4);
  DetailCacheDesc d;
  d.worker_threads = 2;
  d.budget_bytes = 12 * f->make_tile({1, 0, 0}, nullptr)->memory_bytes();
  auto cache = DetailCache::create(f, d);
  ASSERT_TRUE(cache.ok());
  DetailCache& c = **cache;
  std::atomic<bool> done{false};
  std::atomic<std::uint64_t> found{0}, bad{0};
  std::vector<std::thread> readers;
  for (int r = 0; r < 3; ++r)
    readers.emplace_back([&] {
      while (!done.load()) {
        const auto snap = c.snapshot();
        for (int k = 0; k < 16; ++k)
          if (const DetailTile* t = snap->find({4, k, 0})) {
            ++found;
            if (t->raw(3, 3) != f->detail_raw(4, t->first_i() + 3, 3)) ++bad;
          }
      }
    });
  for (int frame = 0; frame < 200; ++frame) {
    c.update();
    for (int k = 0; k < 16; ++k) c.request({4, (k + frame / 10) % 16, 0});
    if (frame % 20 == 0) c.wait_idle(1.0);
  }
  done = true;
  for (auto& t : readers) t.join();
  EXPECT_EQ(bad.load(), 0u);
  EXPECT_GT(found.load(), 0u);
  EXPECT_LE(c.stats().resident_bytes, d.budget_bytes);
}

}  // namespace
}  // namespace ridgeline
