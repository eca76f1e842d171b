// Ridgeline::bullet on a paged world (a baked world under a small page cache): TerrainSync keeps
// the pages under the bodies resident, so stepping never loads a page on the stepping thread
// however much the rest of the world is paged in and out, and lets them go when the bodies leave.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "bullet_test_util.h"
#include "ridgeline/bullet/terrain_sync.h"
#include "ridgeline/scenes.h"
#include "ridgeline/terrain.h"
#include "ridgeline/world_file.h"

using ridgeline::bullet::TerrainSync;
using ridgeline::bullet::test::World;

namespace {

// A baked world of the project's generator, 1500 x 1300 samples at 1 m (6 x 6 level-0 pages),
// opened under a 4 MiB cache with loads on the asking thread.
std::shared_ptr<ridgeline::Terrain> paged_world() {
  const std::filesystem::path dir = std::filesystem::path(RIDGELINE_TEST_TMP) / "bullet";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "paged.tif").string();
  const std::uint32_t w = 1500, h = 1300;
  std::vector<std::uint16_t> raw(std::size_t(w) * h);
  ridgeline::scenes::generated_world_rows(w, 0, h, 7, raw.data());
  ridgeline::HeightfieldDesc d;
  d.width = w, d.height = h;
  d.height_scale = ridgeline::scenes::kWorldHeightScale;
  auto hf = ridgeline::Heightfield::create(d, std::vector<float>(raw.begin(), raw.end())).value();
  EXPECT_TRUE(ridgeline::io::bake_world(hf, path));
  ridgeline::WorldCacheDesc cache;
  cache.budget_bytes = 4 << 20;
  cache.worker_threads = 0;
  return ridgeline::Terrain::open(ridgeline::io::open_world(path).value(), cache).value();
}

}  // namespace

TEST(BulletPaged, ThePagesUnderTheBodiesStayResidentWhileTheWorldPagesAround) {
  auto terrain = paged_world();
  ASSERT_TRUE(terrain->paged());
  World w(terrain, {.origin = {700, 0, 600}});
  ridgeline::bullet::TerrainSyncDesc desc;
  desc.residency_margin = 4.0;
  auto sync = TerrainSync::create(&w.world, &w.ground, desc).value();
  // Two bodies on different pages (256 m each).
  const double x0 = 600, z0 = 500, x1 = 900, z1 = 820;
  btRigidBody* a = w.sphere(0.5, {x0, *terrain->height(x0, z0) + 0.6, z0});
  btRigidBody* b = w.sphere(0.5, {x1, *terrain->height(x1, z1) + 0.6, z1});
  const auto first = sync.update();
  EXPECT_TRUE(first.residency_changed);
  EXPECT_EQ(first.pinned_pages, 2u) << "one page under each body";
  for (int k = 0; k < 120; ++k) {
    sync.update();
    w.step(1);
  }
  // Page the rest of the world in and out: queries all over it under the 4 MiB cache.
  const ridgeline::WorldInfo& info = terrain->info();
  for (int k = 0; k < 300; ++k) {
    terrain->height(info.origin_x + info.extent_x() * ((k * 37) % 300) / 300.0,
                    info.origin_z + info.extent_z() * ((k * 53) % 300) / 300.0);
    terrain->update_pages();
  }
  ASSERT_GT(terrain->world_stats().evicted, 0u) << "the sweep evicted nothing: no test";
  const std::uint64_t loads = terrain->world_stats().sync_loads;
  for (int k = 0; k < 120; ++k) {
    const auto s = sync.update();
    EXPECT_FALSE(s.residency_changed) << "step " << k;
    w.step(1);
  }
  EXPECT_EQ(terrain->world_stats().sync_loads, loads)
      << "stepping bodies whose pages were pinned loaded pages on the stepping thread";
  for (const btRigidBody* body : {a, b}) {
    const glm::dvec3 p = w.position(body);
    // Resting on the slope under it: its centre above the ground by the radius or a little more.
    const double above = p.y - *terrain->height(p.x, p.z);
    EXPECT_GT(above, 0.45) << "a body sank into the ground";
    EXPECT_LT(above, 1.0) << "a body left the ground";
  }

  // Bodies gone: nothing pinned, the pages go back to the cache.
  const std::size_t pinned = terrain->world_stats().pinned_pages;
  w.dynamics.remove_bodies();
  const auto last = sync.update();
  EXPECT_TRUE(last.residency_changed);
  EXPECT_EQ(last.pinned_pages, 0u);
  EXPECT_LT(terrain->world_stats().pinned_pages, pinned);
}

TEST(BulletPaged, ABadResidencyMarginIsRefused) {
  auto terrain = paged_world();
  World w(terrain);
  for (const double m : {-1.0, double(NAN), double(INFINITY)}) {
    ridgeline::bullet::TerrainSyncDesc desc;
    desc.residency_margin = m;
    auto r = TerrainSync::create(&w.world, &w.ground, desc);
    ASSERT_FALSE(r);
    EXPECT_NE(r.error().message.find("residency margin"), std::string::npos) << r.error().message;
  }
}
