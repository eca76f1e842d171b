// The packed bounds of roam/records.h: a bound stored in 32 bits must never come back below the
// bound it stores (the tessellator would stop refining where the surface is farther than the
// threshold), nor more than one step of its 6-bit mantissa above it.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <sstream>
#include <tuple>
#include <vector>

#include "ridgeline/heightfield.h"
#include "roam/diamond_bounds.h"
#include "roam/records.h"
#include "surface/hole_mask.h"
#include "world/page_store.h"

using namespace ridgeline;
using namespace ridgeline::roam;

namespace {

// Values over the packed range (2^-30 .. 2^24 m; spheres twice that): random mantissas, and every
// mantissa whose top 6 bits are all set (the values that round up into the next power of two) with
// a few low bits, in every exponent.
std::vector<float> probe_values() {
  std::vector<float> v;
  std::mt19937 rng(11);
  std::uniform_int_distribution<std::uint32_t> mant(0, 0x7fffff);
  for (int e = -30; e <= 23; ++e) {
    for (std::uint32_t low : {0u, 1u, 0x1ffffu, 0x10000u})
      v.push_back(std::ldexp(std::bit_cast<float>(0x3f800000u | 0x7e0000u | low), e));
    for (int k = 0; k < 40; ++k)
      v.push_back(std::ldexp(std::bit_cast<float>(0x3f800000u | mant(rng)), e));
  }
  return v;
}

std::string describe(const char* part, float stored, float back) {
  std::ostringstream s;
  s.precision(9);
  s << part << " " << stored << " m unpacks to " << back << " m";
  return s.str();
}

}  // namespace

// Error, radius and morph bound each: at least what was packed, at most 1/64 above (the error
// and radius: one mantissa step; the morph bound over the error: one 2^(1/64) ratio step, on top
// of the error's own rounding).
TEST(Records, PackedBoundsNeverComeBackBelowWhatTheyStore) {
  std::size_t checked = 0;
  for (float v : probe_values()) {
    for (float morph_ratio : {1.0f, 1.3f, 7.5f}) {
      const DiamondBound b{v, v * morph_ratio, 2.0f * v};
      const DiamondBound q = quantized(b);
      ++checked;
      ASSERT_GE(q.error, b.error) << describe("error", b.error, q.error)
                                  << ": the packed bound is below the error it bounds";
      ASSERT_LE(q.error, b.error * (1.0f + 1.0f / 64.0f))
          << describe("error", b.error, q.error) << ": more than one mantissa step above";
      ASSERT_GE(q.radius, b.radius) << describe("radius", b.radius, q.radius)
                                    << ": the packed sphere is smaller than the one it bounds";
      ASSERT_LE(q.radius, b.radius * (1.0f + 1.0f / 64.0f))
          << describe("radius", b.radius, q.radius) << ": more than one mantissa step above";
      ASSERT_GE(q.morph, b.morph) << describe("morph bound", b.morph, q.morph)
                                  << ": the packed morph bound is below the one it bounds";
      ASSERT_LE(q.morph, b.morph * (1.0f + 1.0f / 64.0f) * std::exp2(1.0f / 64.0f) * 1.0001f)
          << describe("morph bound", b.morph, q.morph) << ": more than one step above";
    }
  }
  EXPECT_GT(checked, 5000u);
  // Zero stays zero, and past the range a bound becomes infinite (never smaller).
  EXPECT_EQ(quantized({0.0f, 0.0f, 0.0f}).error, 0.0f);
  EXPECT_TRUE(std::isinf(quantized({FLT_MAX, FLT_MAX, FLT_MAX}).error));
  EXPECT_TRUE(std::isinf(quantized({1.0f, 1.0f, FLT_MAX}).radius));
}

// The bounds of the small diamonds (t <= 1: most of every world's) come from fixed stencils where
// a diamond lies inside the data, and from the general diamond_bound() elsewhere: both must give
// the same bounds bit for bit, or a baked world's level-0 blocks and the in-memory ones, and the
// pages near a border and the others, would disagree. Blocks placed over every border case (the
// world's first samples, its last ones, padding past them), rough heights, odd spacings.
TEST(Records, SmallDiamondStencilsGiveTheGeneralBoundsBitForBit) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> height(-40.0f, 40.0f);
  std::size_t compared = 0, differing = 0;
  for (int round = 0; round < 24; ++round) {
    RecordConfig c;
    c.patch_log2 = 3 + round % 4;
    c.growth = 1.0 + 0.25 * (round % 3);
    c.last_i = 37 + round, c.last_j = 29 + 2 * round;
    const std::int64_t P = std::int64_t{1} << c.patch_log2;
    c.pad_i = ((c.last_i + P - 1) / P) * P, c.pad_j = ((c.last_j + P - 1) / P) * P;
    c.spacing_x = 0.7 + 0.1 * round, c.spacing_z = 1.9 - 0.05 * round;
    const std::int64_t n = 24;
    const std::int64_t i0 = (round % 3 == 0) ? -6 : (round % 3 == 1 ? c.last_i - 14 : 5);
    const std::int64_t j0 = (round % 2 == 0) ? -6 : c.last_j - 10;
    std::vector<float> block(std::size_t(n * n));
    for (float& v : block) v = (round % 5 == 0) ? std::round(height(rng)) : height(rng);
    const bounds::DenseBlock h{block.data(), i0, j0, n};
    std::vector<std::uint32_t> fast_packed, general_packed;
    bounds::small_bounds(c, h, fast_packed, true);
    bounds::small_bounds(c, h, general_packed, false);
    ASSERT_EQ(fast_packed.size(), general_packed.size());
    std::vector<DiamondBound> fast, general;
    for (std::uint32_t v : fast_packed) fast.push_back(packed::unpack(v));
    for (std::uint32_t v : general_packed) general.push_back(packed::unpack(v));
    for (std::size_t e = 0; e < fast.size(); ++e) {
      ++compared;
      const bool same = std::bit_cast<std::uint32_t>(fast[e].error) == std::bit_cast<std::uint32_t>(general[e].error) &&
                        std::bit_cast<std::uint32_t>(fast[e].morph) == std::bit_cast<std::uint32_t>(general[e].morph) &&
                        std::bit_cast<std::uint32_t>(fast[e].radius) == std::bit_cast<std::uint32_t>(general[e].radius);
      if (!same && ++differing <= 5)
        ADD_FAILURE() << "round " << round << ", sample (" << i0 + std::int64_t(e) % n << ", "
                      << j0 + std::int64_t(e) / n << "): stencil error " << fast[e].error << " morph "
                      << fast[e].morph << " radius " << fast[e].radius << ", general "
                      << general[e].error << " / " << general[e].morph << " / " << general[e].radius;
    }
  }
  EXPECT_EQ(differing, 0u);
  EXPECT_GT(compared, 10000u);
}

// The morph code's search: pack() keeps the smallest ratio step 2^(c/64) that covers the morph
// bound over the packed error, whatever its first guess.
TEST(Records, PackedMorphRatioIsTheSmallestStepThatCovers) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> mant(1.0f, 2.0f);
  std::uniform_real_distribution<float> ratio(1.0f, 20.0f);
  for (int k = 0; k < 200000; ++k) {
    const float e = std::ldexp(mant(rng), int(k % 40) - 20);
    const float m = e * ratio(rng);
    const std::uint32_t v = packed::pack({e, m, 0.0f});
    const float pe = packed::down12(v & 0xfffu);
    const std::uint32_t c = v >> 24;
    ASSERT_GE(pe * packed::kRatio[c], m) << "the packed morph bound is below the one it bounds";
    if (c > 0) {
      ASSERT_LT(pe * packed::kRatio[c - 1], m) << "a smaller ratio step would cover it";
    }
  }
}

// A terrain in memory gets its level-0 blocks from the same pass as the t = 1 squares of the
// coarse bounds (build_all): each must be the block level0_block() makes from the page alone,
// which is what a paged world's arriving page gets. Float and 16-bit pages, several pages a side
// (their aprons joining), holes, and a size that pads the last patches.
TEST(Records, TheWholeWorldPassGivesEachPageItsOwnLevel0Block) {
  for (const bool as_u16 : {false, true}) {
    const std::uint32_t w = 601, hgt = 530;
    std::vector<float> values(std::size_t(w) * hgt);
    std::mt19937 rng(as_u16 ? 3 : 4);
    std::uniform_real_distribution<float> bump(-0.6f, 0.6f);
    for (std::uint32_t j = 0; j < hgt; ++j)
      for (std::uint32_t i = 0; i < w; ++i) {
        const float v = 30.0f * std::sin(0.031f * float(i)) * std::cos(0.017f * float(j)) + bump(rng);
        values[std::size_t(i) + std::size_t(j) * w] = as_u16 ? std::round(4.0f * (v + 40.0f)) : v;
      }
    HeightfieldDesc desc;
    desc.width = w, desc.height = hgt, desc.spacing_x = 1.5, desc.spacing_z = 0.75;
    desc.height_scale = as_u16 ? 0.25 : 1.0;
    auto hf = Heightfield::create(desc, values);
    ASSERT_TRUE(hf) << hf.error().message;
    ASSERT_EQ(world::fits_u16(*hf), as_u16);
    WorldInfo info;
    info.width = w, info.height = hgt, info.spacing_x = 1.5, info.spacing_z = 0.75;
    info.height_scale = hf->height_scale();
    info.format = as_u16 ? SampleFormat::kU16 : SampleFormat::kF32;
    info.min_local = hf->min_local(), info.max_local = hf->max_local();
    const auto store = world::PageStore::from_heightfield(*hf, info);
    const world::PageGrid& g = store->grid();
    ASSERT_GE(g.px[0], 3);
    ASSERT_GE(g.pz[0], 2);
    const auto table = store->snapshot();
    // The heights as Landscape::create copies them: from the level-0 pages.
    std::vector<float> dense(values.size());
    for (std::int64_t j = 0; j <= g.last_j; ++j)
      for (std::int64_t i = 0; i <= g.last_i; ++i)
        dense[std::size_t(i) + std::size_t(j) * w] =
            table->find(0, std::int32_t(i >> 8), std::int32_t(j >> 8))
                ->local(std::int32_t(i & 255), std::int32_t(j & 255));
    Heights h;
    h.f32 = dense.data(), h.stride = w, h.last_i = g.last_i, h.last_j = g.last_j;
    auto holes = std::make_shared<HoleMask>();
    for (std::int64_t k = 0; k < 40; ++k) holes->set(250 + k, 200 + k / 3, true);  // over a page edge
    holes->set(0, 0, true);
    holes->set(w - 2, hgt - 2, true);
    RecordConfig c;
    c.patch_log2 = 6;
    c.growth = std::sqrt(1.3);
    c.last_i = w - 1, c.last_j = hgt - 1;
    c.pad_i = ((c.last_i + 63) / 64) * 64, c.pad_j = ((c.last_j + 63) / 64) * 64;
    c.spacing_x = 1.5, c.spacing_z = 0.75;
    c.hole_source = [holes] { return std::shared_ptr<const HoleMask>(holes); };
    std::vector<std::pair<PageKey, std::shared_ptr<RecordBlock>>> made;
    std::mutex mu;
    build_all(
        c, g, h, [&](const PageKey& k) { return table->find(k); },
        [&](const PageKey& k, std::shared_ptr<RecordBlock> b) {
          std::lock_guard lock(mu);
          made.emplace_back(k, std::move(b));
        },
        2);
    std::size_t level0 = 0;
    for (const auto& [key, block] : made) {
      if (key.level != 0) continue;
      ++level0;
      const auto own = level0_block(c, *table->find(key));
      ASSERT_EQ(block->values.size(), own->values.size());
      std::size_t differing = 0;
      for (std::size_t k = 0; k < own->values.size(); ++k) differing += block->values[k] != own->values[k];
      EXPECT_EQ(differing, 0u) << (as_u16 ? "16-bit" : "float") << " page (" << key.px << ", "
                               << key.pz << "): " << differing << " of " << own->values.size()
                               << " packed bounds differ from the page's own block";
    }
    EXPECT_EQ(level0, std::size_t(g.px[0]) * std::size_t(g.pz[0]));
  }
}

// The coarse levels of a whole world (build_all: sizes 4 and 8 through the small triangles'
// stencils, four at a time where the CPU allows, tile by tile; larger ones through bound_of())
// hold, for every diamond, exactly diamond_bound() of its heights and its children's stored
// bounds: a stencil of the wrong orientation, a child read from the wrong place or a lane mixed
// up changes some of them.
TEST(Records, CoarseLevelsAreTheGeneralBoundsOfTheirStoredChildren) {
  for (const int round : {0, 1}) {
    const std::int64_t w = 700 - 37 * round, hgt = 530 + 21 * round;
    std::vector<float> values(std::size_t(w * hgt));
    std::mt19937 rng(11 + round);
    std::uniform_real_distribution<float> bump(-0.8f, 0.8f);
    for (std::int64_t j = 0; j < hgt; ++j)
      for (std::int64_t i = 0; i < w; ++i) {
        const float v = 25.0f * std::sin(0.023f * float(i)) * std::cos(0.041f * float(j)) + bump(rng);
        values[std::size_t(i + j * w)] = round == 1 ? std::round(8.0f * v) / 8.0f : v;
      }
    HeightfieldDesc desc;
    desc.width = std::uint32_t(w), desc.height = std::uint32_t(hgt);
    desc.spacing_x = 1.25, desc.spacing_z = 0.8;
    auto hf = Heightfield::create(desc, values);
    ASSERT_TRUE(hf) << hf.error().message;
    WorldInfo info;
    info.width = std::uint32_t(w), info.height = std::uint32_t(hgt);
    info.spacing_x = 1.25, info.spacing_z = 0.8;
    info.height_scale = hf->height_scale();
    info.format = world::fits_u16(*hf) ? SampleFormat::kU16 : SampleFormat::kF32;
    info.min_local = hf->min_local(), info.max_local = hf->max_local();
    const auto store = world::PageStore::from_heightfield(*hf, info);
    const world::PageGrid& g = store->grid();
    const auto table = store->snapshot();
    // The heights as the pages hold them (what the level-0 blocks are made from).
    std::vector<float> dense(values.size());
    for (std::int64_t j = 0; j < hgt; ++j)
      for (std::int64_t i = 0; i < w; ++i)
        dense[std::size_t(i + j * w)] = table->find(0, std::int32_t(i >> 8), std::int32_t(j >> 8))
                                            ->local(std::int32_t(i & 255), std::int32_t(j & 255));
    Heights h;
    h.f32 = dense.data(), h.stride = w, h.last_i = w - 1, h.last_j = hgt - 1;
    RecordConfig c;
    c.patch_log2 = 7 - round;
    c.growth = round == 0 ? std::sqrt(1.3) : 1.0;
    c.last_i = w - 1, c.last_j = hgt - 1;
    const std::int64_t P = std::int64_t{1} << c.patch_log2;
    c.pad_i = ((c.last_i + P - 1) / P) * P, c.pad_j = ((c.last_j + P - 1) / P) * P;
    c.spacing_x = 1.25, c.spacing_z = 0.8;
    std::map<std::tuple<std::uint32_t, std::int32_t, std::int32_t>, std::shared_ptr<RecordBlock>> blocks;
    std::mutex mu;
    build_all(
        c, g, h, [&](const PageKey& k) { return table->find(k); },
        [&](const PageKey& k, std::shared_ptr<RecordBlock> b) {
          std::lock_guard lock(mu);
          blocks[{k.level, k.px, k.pz}] = std::move(b);
        },
        2);
    auto stored = [&](std::int64_t i, std::int64_t j) -> std::uint32_t {
      const Diamond d = diamond_at(i, j, c.patch_log2);
      const std::uint32_t k = record_level(d.t, g.levels);
      const PageKey key = g.page_of(k, i, j);
      const RecordBlock& b = *blocks.at({k, key.px, key.pz});
      const std::int32_t a = std::int32_t((i >> (2 * k)) - (std::int64_t(key.px) << 8));
      const std::int32_t bb = std::int32_t((j >> (2 * k)) - (std::int64_t(key.pz) << 8));
      return b.values[b.slot(a, bb)];
    };
    std::size_t compared[8] = {}, differing = 0;
    for (std::int64_t j = 0; j <= c.pad_j; j += 4)
      for (std::int64_t i = 0; i <= c.pad_i; i += 4) {
        const Diamond d = diamond_at(i, j, c.patch_log2);
        if (d.corner || d.t < 2) continue;
        const std::uint32_t want = packed::pack(diamond_bound(
            c, h, i, j, [&](std::int64_t ci, std::int64_t cj) { return packed::unpack(stored(ci, cj)); }));
        const std::uint32_t got = stored(i, j);
        ++compared[std::min(d.t, 7)];
        if (got != want && ++differing <= 5)
          ADD_FAILURE() << "round " << round << ", the size-" << (1 << d.t) << (d.square ? " square" : " edge")
                        << " diamond at (" << i << ", " << j << "): stored " << std::hex << got
                        << ", diamond_bound() " << want << std::dec;
      }
    EXPECT_EQ(differing, 0u);
    EXPECT_GT(compared[2], 3000u);
    EXPECT_GT(compared[3], 1000u);
  }
}

// A row read in one go (the bounds' dense copies) holds the accessor's values bit for bit: past
// the data on either side, wholly past it, on rows past the first and the last, 16-bit and float.
TEST(Records, ReadRowRepeatsTheEdgesAsTheAccessorDoes) {
  const std::int64_t w = 13, hgt = 7;
  std::vector<float> f(std::size_t(w * hgt));
  std::vector<std::uint16_t> u(f.size());
  for (std::size_t k = 0; k < f.size(); ++k) f[k] = 0.37f * float(k) - 5.0f, u[k] = std::uint16_t(977 * k % 65536);
  for (const bool as_u16 : {false, true}) {
    Heights h;
    h.f32 = as_u16 ? nullptr : f.data();
    h.u16 = as_u16 ? u.data() : nullptr;
    h.scale = 0.013;
    h.stride = w, h.last_i = w - 1, h.last_j = hgt - 1;
    std::vector<float> row(64);
    for (std::int64_t z = -3; z <= hgt + 2; ++z)
      for (std::int64_t lo = -20; lo <= w + 5; lo += 3)
        for (std::int64_t hi = lo; hi <= lo + 40; hi += 7) {
          bounds::read_row(h, z, lo, hi, row.data());
          for (std::int64_t x = lo; x <= hi; ++x)
            ASSERT_EQ(std::bit_cast<std::uint32_t>(row[std::size_t(x - lo)]), std::bit_cast<std::uint32_t>(h(x, z)))
                << (as_u16 ? "16-bit" : "float") << " row " << z << ", samples " << lo << " .. " << hi
                << ": sample " << x;
        }
  }
}
