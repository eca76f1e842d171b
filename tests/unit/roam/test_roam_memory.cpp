// The memory of the node and front arrays (roam/reserved.cpp, roam/roam_memory.cpp): ranges that
// grow in place, a pool that hands a destroyed view's pages to the next view, its cap, and the
// out-of-memory error an update returns at the cap.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <new>

#include "ridgeline/roam_view.h"
#include "roam/reserved.h"
#include "roam_landscapes.h"

using namespace ridgeline;
using namespace ridgeline::test;

// The storage of the node and front arrays: address space reserved once, pages committed as the
// array grows, given back on request, zero when committed again; a request past the range is
// refused like a failed allocation, and what was committed stays usable. A destroyed
// reservation's range and pages go to the next reservation of the same size through its pool.
// With RIDGELINE_PORTABLE the array is a plain allocation that moves: the same contents, read
// through data() again after each call.
TEST(Reservation, GrowsInPlaceGivesBackAndRefusesPastItsRange) {
  constexpr std::size_t kStep = 64 << 10, kMax = (64 << 20) + (12 << 10);
  roam::RangePool pool(std::size_t{64} << 20, 0);
  const void* base = nullptr;
  {
    roam::Reservation r("test array", &pool);
    auto bytes = [&] { return static_cast<unsigned char*>(r.data()); };
    EXPECT_EQ(r.data(), nullptr);
    r.grow_to(1, kStep, kMax);
    ASSERT_NE(r.data(), nullptr);
#ifndef RIDGELINE_PORTABLE
    EXPECT_TRUE(r.grows_in_place());
#else
    EXPECT_FALSE(r.grows_in_place());
#endif
    EXPECT_EQ(r.committed(), kStep);
    EXPECT_EQ(pool.bytes(), kStep);
    base = r.data();
    std::memset(bytes(), 0xab, kStep);
    r.grow_to(5 * kStep + 1, kStep, kMax);
    if (r.grows_in_place()) {
      EXPECT_EQ(r.data(), base) << "the array moved";
    }
    EXPECT_GE(r.committed(), 6 * kStep);
    EXPECT_EQ(bytes()[kStep - 1], 0xab);
    std::memset(bytes(), 0xcd, 6 * kStep);
    r.shrink_to(kStep + 1);  // keeps whole pages
    EXPECT_GE(r.committed(), kStep + 1);
    EXPECT_LT(r.committed(), 2 * kStep);
    EXPECT_EQ(pool.bytes(), r.committed());
    r.grow_to(3 * kStep, kStep, kMax);
    EXPECT_EQ(r.committed(), 3 * kStep);
    EXPECT_EQ(bytes()[kStep], 0xcd);       // kept
    EXPECT_EQ(bytes()[3 * kStep - 1], 0);  // given back, then fresh
    try {
      r.grow_to(kMax + 1, kStep, kMax);
      ADD_FAILURE() << "grew past its range";
    } catch (const roam::OutOfMemory& e) {
      EXPECT_NE(std::string(e.what()).find("test array of 67121153 bytes"), std::string::npos)
          << e.what();
    }
    EXPECT_EQ(r.committed(), 3 * kStep);
    EXPECT_EQ(bytes()[0], 0xcd);
    r.grow_to(kMax, kStep, kMax);  // up to the last byte of the range
    bytes()[kMax - 1] = 1;
    EXPECT_EQ(r.committed(), kMax);
    r.shrink_to(4 * kStep);
    bytes()[4 * kStep - 1] = 0xef;
    base = r.data();
  }
  // The next reservation of that size gets the range back with its pages (no new faults);
  // another size gets a range of its own.
  EXPECT_EQ(pool.spare_bytes(), 4 * kStep);
  EXPECT_EQ(pool.bytes(), 4 * kStep);
  roam::Reservation again("again", &pool), other("other", &pool);
  again.grow_to(kStep, kStep, kMax);
  EXPECT_EQ(again.data(), base);
  EXPECT_EQ(again.committed(), 4 * kStep);
  EXPECT_EQ(static_cast<unsigned char*>(again.data())[4 * kStep - 1], 0xef);
  EXPECT_EQ(pool.spare_bytes(), 0u);
  other.grow_to(kStep, kStep, kMax + kStep);
  EXPECT_NE(other.data(), base);
  EXPECT_EQ(pool.bytes(), 5 * kStep);
}

// A pool's cap: a growth past it is refused (naming the array and the limit) and changes
// nothing; kept ranges are given back first when they are what stands in the way.
TEST(Reservation, APoolsCapRefusesGrowthPastItAfterGivingBackSpares) {
  constexpr std::size_t kStep = 64 << 10, kMax = 16 << 20;
  roam::RangePool pool(std::size_t{64} << 20, 4 * kStep);
  {
    roam::Reservation kept("kept", &pool);
    kept.grow_to(3 * kStep, kStep, kMax + kStep);  // a size no one asks for again
  }
  EXPECT_EQ(pool.spare_bytes(), 3 * kStep);
  roam::Reservation r("node array", &pool);
  r.grow_to(2 * kStep, kStep, kMax);  // room made by giving the spare range back
  EXPECT_EQ(pool.spare_bytes(), 0u);
  EXPECT_EQ(pool.bytes(), 2 * kStep);
  r.grow_to(4 * kStep, kStep, kMax);
  try {
    r.grow_to(4 * kStep + 1, kStep, kMax);
    ADD_FAILURE() << "grew past the cap";
  } catch (const roam::OutOfMemory& e) {
    EXPECT_EQ(std::string(e.what()),
              "node array of 262145 bytes: past the RoamMemory's limit of 262144 bytes");
  }
  EXPECT_EQ(r.committed(), 4 * kStep);
  EXPECT_EQ(pool.bytes(), 4 * kStep);
}

// A view created after a bigger one was destroyed, with the same RoamMemory, takes over its node
// and front ranges with their pages (no new faults), but holds and reports only what its own mesh
// needs after its first update: the same memory as the same view made first in a fresh range,
// within the spare steps each array keeps (384 KiB of nodes, 40 KiB of front).
TEST(Roam, AViewTakingOverABiggerViewsMemoryKeepsOnlyWhatItNeeds) {
  auto l = make_landscape(257, 5);
  const Camera c = camera_at({128, 60, -40}, {128, 20, 128}, 60);
  auto memory = RoamMemory::create();
  auto coarse_memory = [&] {
    RoamSettings s;
    s.threshold = 16;
    auto v = RoamView::create(l, s, memory).value();
    const auto st = v->update(c);
    EXPECT_TRUE(st);
    return st ? st->memory_bytes : 0;
  };
  const std::size_t alone = coarse_memory();
  std::size_t big = 0;
  {
    RoamSettings s;
    s.threshold = 0.5;
    auto v = RoamView::create(l, s, memory).value();
    const auto st = v->update(c);
    ASSERT_TRUE(st);
    big = st->memory_bytes;
  }
  ASSERT_GT(big, alone + 2 * 384 * 1024) << "the fine view is not big enough to tell";
  EXPECT_GE(memory->spare_bytes(), big / 2) << "the fine view's ranges were not kept";
  const std::size_t after = coarse_memory();
  EXPECT_LE(after, alone + 384 * 1024 + 40 * 1024) << "fine view " << big << " bytes";
}

// What a RoamMemory keeps after its views are gone, and gives back on request; a memory that
// keeps nothing, and views without a memory, leave nothing behind.
TEST(RoamMemory, KeepsDestroyedViewsRangesUntilReleased) {
  auto l = make_landscape(129, 5);
  const Camera c = camera_at({20, 80, 30}, {200, 20, 160});
  auto memory = RoamMemory::create({.max_spare_bytes = std::size_t{64} << 20});
  std::size_t used = 0;
  {
    auto view = RoamView::create(l, {.threshold = 1.0}, memory).value();
    const auto st = view->update(c);
    ASSERT_TRUE(st);
    used = memory->committed_bytes();
    EXPECT_GT(used, 0u);
    EXPECT_EQ(memory->spare_bytes(), 0u);
    // The view's node and front arrays are what the memory counts.
    EXPECT_LE(used, st->memory_bytes);
  }
  EXPECT_EQ(memory->spare_bytes(), used);  // the ranges of the destroyed view, pages and all
  EXPECT_EQ(memory->committed_bytes(), used);
  EXPECT_EQ(memory->release_spares(), used);
  EXPECT_EQ(memory->spare_bytes(), 0u);
  EXPECT_EQ(memory->committed_bytes(), 0u);

  auto keeps_nothing = RoamMemory::create({.max_spare_bytes = 0});
  {
    auto view = RoamView::create(l, {.threshold = 1.0}, keeps_nothing).value();
    ASSERT_TRUE(view->update(c));
    EXPECT_GT(keeps_nothing->committed_bytes(), 0u);
  }
  EXPECT_EQ(keeps_nothing->committed_bytes(), 0u);
}

// A view whose RoamMemory cannot hold its mesh: update() returns an out-of-memory error naming
// the array and the limit (no exception), the mesh is back at its root triangles (every patch
// dirty and resized, the invariants intact), and a coarser threshold that fits carries on from
// the roots.
TEST(RoamMemory, AnUpdatePastTheCapFailsWithAnErrorAndTheViewCarriesOn) {
  auto l = make_landscape(257, 5);
  const std::size_t cap = std::size_t{1} << 20;  // two node steps and some front chunks
  auto memory = RoamMemory::create({.max_spare_bytes = 0, .max_bytes = cap});
  auto view = RoamView::create(l, {.threshold = 0.3}, memory).value();
  const Camera c = camera_at({20, 120, 30}, {300, 60, 260});
  const auto fine = view->update(c);  // ~50,000 triangles: ~2.4 MB of nodes
  ASSERT_FALSE(fine) << "the mesh fitted the cap";
  const std::string* failed = &fine.error().message;
  EXPECT_EQ(failed->rfind("roam view: out of memory: ", 0), 0u) << *failed;
  EXPECT_NE(failed->find("past the RoamMemory's limit of 1048576 bytes"), std::string::npos)
      << *failed;
  EXPECT_LE(memory->committed_bytes(), cap);
  EXPECT_EQ(view->triangle_count(), l->root_count());
  EXPECT_EQ(view->check_invariants(), "");
  const auto dirty = view->take_dirty_patches();
  EXPECT_EQ(dirty.size(), l->patch_count());
  for (const std::uint32_t p : dirty) EXPECT_TRUE(view->patch_mesh(p).resized) << "patch " << p;
  RoamSettings s = view->settings();
  s.threshold = 16.0;
  ASSERT_TRUE(view->set_settings(s));
  const auto st = view->update(c);
  ASSERT_TRUE(st) << st.error().message;
  EXPECT_TRUE(st->rebuilt);
  EXPECT_GT(st->triangles, l->root_count());
  EXPECT_EQ(view->check_invariants(), "");
  EXPECT_EQ(check_crack_free(*view), "");
  expect_converged(*view, c, 16.0);
}
