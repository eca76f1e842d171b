// The split and merge front (roam/front.h): chunked storage, the vectorised pass against the
// test of one entry, the pass in turns of a time budget, trimming.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <random>
#include <vector>

#include "ridgeline/roam_view.h"
#include "roam/front.h"
#include "roam_landscapes.h"

using namespace ridgeline;
using namespace ridgeline::test;

// The front's storage, chunk by chunk: entries added and removed (the last moved into the hole)
// across several chunk boundaries keep their data and state, the pass agrees with the test of one
// entry, and trimming gives back the chunks a peak left.
TEST(Front, ChunkedStorageKeepsEntriesAcrossChunks) {
  struct Ref {
    std::int32_t i, j;
    float x, y, z, mu, r;
    std::uint32_t node;
    bool split;
  };
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> pos(-500.0f, 500.0f), bound(0.0f, 4.0f);
  roam::Front f;
  std::vector<Ref> ref;
  auto add = [&] {
    const Ref e{std::int32_t(rng() % 4096),
                std::int32_t(rng() % 4096),
                pos(rng),
                pos(rng) * 0.1f,
                pos(rng),
                bound(rng),
                bound(rng) * 8.0f,
                std::uint32_t(ref.size()),
                (rng() & 1) != 0};
    ASSERT_EQ(f.add(e.i, e.j, 4, 0, 3, e.x, e.y, e.z, e.mu, e.r, e.node, e.split, false),
              ref.size());
    ref.push_back(e);
  };
  auto remove = [&](std::uint32_t e) {
    const std::uint32_t moved = f.remove(e);
    ASSERT_EQ(moved, ref.size() - 1);
    ref[e] = ref.back();
    ref.pop_back();
  };
  const std::uint32_t chunk = roam::Front::kChunkBlocks * roam::Front::kLanes;
  for (std::uint32_t k = 0; k < 3 * chunk + 77; ++k) add();
  const std::size_t peak_bytes = f.memory_bytes();
  for (std::uint32_t k = 0; k < 2 * chunk; ++k) remove(std::uint32_t(rng() % ref.size()));
  for (std::uint32_t k = 0; k < 300; ++k) add();
  ASSERT_EQ(f.size(), ref.size());
  Camera cam;
  cam.eye = {10.0, 80.0, -30.0};
  cam.target = {40.0, 20.0, 70.0};
  const roam::FrontCamera c = roam::FrontCamera::screen(cam, 1.0, 0, 0, 0, 5000);
  f.evaluate(c);
  for (std::uint32_t e = 0; e < f.size(); ++e) {
    const Ref& r = ref[e];
    ASSERT_EQ(f.ci(e), r.i) << e;
    ASSERT_EQ(f.cj(e), r.j) << e;
    ASSERT_EQ(f.node(e), r.node) << e;
    ASSERT_EQ(f.split(e), r.split) << e;
    ASSERT_EQ(f.y(e), r.y) << e;
    ASSERT_EQ(f.mu(e), r.mu) << e;
    ASSERT_EQ(f.radius(e), r.r) << e;
    const std::uint8_t pass = f.result(e);
    ASSERT_EQ(f.test_one(e, c), pass) << e;  // bit for bit, in whichever chunk
  }
  // Under a time budget the pass goes chunk by chunk: with the time already up, one chunk per
  // call, resuming where the last call stopped, and the calls together test every entry once
  // with the same results as the whole pass.
  {
    Camera moved = cam;
    moved.eye = {-40.0, 60.0, 10.0};
    const roam::FrontCamera c2 = roam::FrontCamera::screen(moved, 2.0, 0, 0, 0, 5000);
    f.evaluate(c2);
    std::vector<std::uint8_t> whole(f.size());
    for (std::uint32_t e = 0; e < f.size(); ++e) whole[e] = f.result(e);
    f.evaluate(c);  // other results again
    std::uint32_t cursor = 1, tested = 0, total = 0;
    const std::uint32_t chunks = (f.size() + chunk - 1) / chunk;
    std::vector<roam::Front::Keyed> changed;
    for (std::uint32_t k = 0; k < chunks; ++k) {
      f.evaluate_until(c2, &changed, std::chrono::steady_clock::now(), &cursor, &tested);
      EXPECT_EQ(cursor, (k + 2) % chunks);
      EXPECT_LE(tested, chunk);
      for (const roam::Front::Keyed& x : changed) {
        const std::uint32_t e = x.entry & ~roam::Front::kKeyedSplit;
        EXPECT_EQ(e / chunk, (k + 1) % chunks) << "a changed entry outside the chunk tested";
        EXPECT_NE(bool(f.result(e) & roam::kActive), f.split(e));
      }
      total += tested;
    }
    EXPECT_EQ(total, f.size());
    for (std::uint32_t e = 0; e < f.size(); ++e) ASSERT_EQ(f.result(e), whole[e]) << e;
    // With time to spare, one call tests everything.
    f.evaluate_until(c, &changed, std::chrono::steady_clock::now() + std::chrono::hours(1),
                     &cursor, &tested);
    EXPECT_EQ(tested, f.size());
  }
  // A chunk's blocks and records (the front may have started on a range an earlier view left,
  // with more committed: so the sizes come from the layout, not from the peak).
  const std::size_t chunk_bytes =
      chunk / roam::Front::kLanes * sizeof(roam::Front::Hot) + chunk * sizeof(roam::Front::Cold);
  auto chunks_for = [&](std::size_t n) { return (n + chunk - 1) / chunk; };
  EXPECT_GE(peak_bytes, 4 * chunk_bytes);  // 3 chunks and 77 entries at the peak
  // Down to a quarter of a chunk: trim() then gives memory back on every platform (reserved
  // address space decommits past a spare chunk; a plain array is copied when that at least
  // halves it, RIDGELINE_PORTABLE).
  while (ref.size() > chunk / 4) remove(std::uint32_t(rng() % ref.size()));
  f.trim();
  EXPECT_LT(f.memory_bytes(), peak_bytes);
  // A spare chunk is kept; everything else beyond the entries in use is given back.
  EXPECT_LE(f.memory_bytes(), (chunks_for(ref.size()) + 1) * chunk_bytes);
  // Growing again past what was given back: the entries in use are intact and the new ones
  // read back as written.
  for (std::uint32_t k = 0; k < 2 * chunk; ++k) add();
  EXPECT_GE(f.memory_bytes(), chunks_for(ref.size()) * chunk_bytes);
  for (std::uint32_t e = 0; e < f.size(); ++e) {
    ASSERT_EQ(f.ci(e), ref[e].i) << e;
    ASSERT_EQ(f.mu(e), ref[e].mu) << e;
    ASSERT_EQ(f.node(e), ref[e].node) << e;
    ASSERT_EQ(f.split(e), ref[e].split) << e;
  }
}
