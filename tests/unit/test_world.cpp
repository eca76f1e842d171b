// Baked worlds (docs/worlds.md): a world baked by Ridgeline::io and opened as a PageSource must be
// the terrain made in memory from the same samples, bit for bit (heights, hash, queries, meshes),
// whatever is resident; its pages are evicted under the budget but edited ones never are; a bad
// file is refused with a message naming it; a bake that fails leaves no half-written world.
#include <gtest/gtest.h>
#include <OpenImageIO/imageio.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <string>
#include <thread>
#include <chrono>
#include <vector>

#include "file_limit_child.h"
#include "ridgeline/edit.h"
#include "ridgeline/io.h"
#include "ridgeline/roam_view.h"
#include "ridgeline/scenes.h"
#include "ridgeline/world_file.h"
#include "roam_test_util.h"

using namespace ridgeline;
using namespace ridgeline::test;

namespace {

std::string tmp_path(const std::string& leaf) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::filesystem::path dir = std::filesystem::path(RIDGELINE_TEST_TMP) / "world";
  std::filesystem::create_directories(dir);
  return (dir / (std::string(info->test_suite_name()) + "_" + info->name() + "_" + leaf)).string();
}

// The project's generated world (16-bit values of 2 cm), `w` x `h` samples at 2 m spacing, placed
// away from the origin.
Heightfield generated(std::uint32_t w, std::uint32_t h, std::uint32_t seed = 3) {
  std::vector<std::uint16_t> raw(std::size_t(w) * h);
  scenes::generated_world_rows(w, 0, h, seed, raw.data());
  HeightfieldDesc d;
  d.width = w, d.height = h;
  d.spacing_x = 2.0, d.spacing_z = 1.5;
  d.origin_x = 1000.0, d.origin_z = -3000.0;
  d.height_offset = 120.0;
  d.height_scale = scenes::kWorldHeightScale;
  d.name = "generated";
  return Heightfield::create(d, std::vector<float>(raw.begin(), raw.end())).value();
}

std::shared_ptr<Terrain> open_baked(const std::string& path, std::size_t budget_mb = 192,
                                    std::uint32_t resident_levels = 2) {
  auto source = io::open_world(path);
  EXPECT_TRUE(source) << (source ? "" : source.error().message);
  WorldCacheDesc cache;
  cache.budget_bytes = budget_mb << 20;
  cache.worker_threads = 0;  // loads on the asking thread: deterministic
  cache.resident_levels = resident_levels;
  return Terrain::open(*source, cache).value();
}

std::vector<std::uint8_t> read_file(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), {}};
}
void write_file(const std::string& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
}

Camera looking_over(const Terrain& t, double fx, double fz) {
  const WorldInfo& w = t.info();
  const double x = w.origin_x + fx * w.extent_x(), z = w.origin_z + fz * w.extent_z();
  const double y = w.height_offset + w.max_local + 150.0;
  return camera_at({x, y, z}, {x + 0.3 * w.extent_x(), w.height_offset, z + 0.25 * w.extent_z()});
}

// The converged mesh of a fresh landscape over `t` (the world's own patch exponent).
std::uint64_t converged_mesh(const std::shared_ptr<Terrain>& t, const Camera& cam,
                             std::string* cracks = nullptr) {
  auto land = Landscape::create(t).value();
  auto view = RoamView::create(land, {.threshold = 1.5}).value();
  EXPECT_TRUE(view->converge(cam));
  if (cracks) *cracks = check_crack_free(*view);
  return view->mesh_hash();
}

// Random points over the footprint (and a margin past it).
std::vector<glm::dvec2> points(const WorldInfo& w, std::size_t n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> fx(-0.02, 1.02), fz(-0.02, 1.02);
  std::vector<glm::dvec2> out;
  for (std::size_t k = 0; k < n; ++k)
    out.push_back({w.origin_x + fx(rng) * w.extent_x(), w.origin_z + fz(rng) * w.extent_z()});
  return out;
}

}  // namespace

// ---- the same surface ------------------------------------------------------------------------

// 16-bit input: the baked world is the terrain in memory. Same content hash, same stored value
// at every sample, same answers to height, normal and ray queries at random places (exactly),
// same converged mesh, crack-free across every page border.
TEST(World, ABakedWorldIsTheTerrainInMemoryBitForBit) {
  const std::string path = tmp_path("w.tif");
  auto baked = io::bake_world(generated(700, 530), path);
  ASSERT_TRUE(baked) << baked.error().message;
  EXPECT_EQ(baked->format, SampleFormat::kU16);
  EXPECT_EQ(baked->max_error_m, 0.0);
  auto memory = Terrain::create(generated(700, 530)).value();
  auto world = open_baked(path);
  ASSERT_TRUE(world->paged());
  EXPECT_EQ(world->info().content_hash, memory->info().content_hash);
  EXPECT_EQ(baked->content_hash, memory->info().content_hash);
  EXPECT_EQ(world->info().width, 700u);
  EXPECT_EQ(world->info().origin_z, -3000.0);
  std::size_t differ = 0;
  for (std::int64_t j = 0; j < 530; ++j)
    for (std::int64_t i = 0; i < 700; ++i)
      differ += world->surface().stored_height(i, j) != memory->surface().stored_height(i, j);
  EXPECT_EQ(differ, 0u) << "stored samples differ between the baked world and the map";
  EXPECT_EQ(world->surface().heights_hash(), memory->surface().heights_hash());

  for (const glm::dvec2& p : points(memory->info(), 3000, 7)) {
    const auto a = memory->sample(p.x, p.y), b = world->sample(p.x, p.y);
    ASSERT_EQ(a.has_value(), b.has_value()) << p.x << ", " << p.y;
    if (!a) continue;
    EXPECT_EQ(a->height, b->height) << p.x << ", " << p.y;
    EXPECT_EQ(a->face_normal, b->face_normal) << p.x << ", " << p.y;
    EXPECT_EQ(a->smooth_normal, b->smooth_normal) << p.x << ", " << p.y;
  }
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  const auto starts = points(memory->info(), 400, 13);
  for (const glm::dvec2& p : starts) {
    const glm::dvec3 o(p.x, memory->info().height_offset + 1500.0 * (0.5 + 0.5 * u(rng)), p.y);
    const glm::dvec3 d(u(rng), -0.05 - std::abs(u(rng)), u(rng));
    const auto a = memory->raycast(o, d, INFINITY), b = world->raycast(o, d, INFINITY);
    ASSERT_EQ(a.has_value(), b.has_value());
    if (a) {
      EXPECT_EQ(a->distance, b->distance);
      EXPECT_EQ(a->normal, b->normal);
    }
  }
  for (const auto& f : {std::pair{0.1, 0.1}, std::pair{0.5, 0.4}}) {
    std::string cracks;
    const Camera cam = looking_over(*memory, f.first, f.second);
    EXPECT_EQ(converged_mesh(world, cam, &cracks), converged_mesh(memory, cam))
        << "the baked world's converged mesh differs from the map's";
    EXPECT_EQ(cracks, "");
  }
}

// Float input is kept exactly by default, and quantised to 16 bits only within the tolerance
// asked for (the measured error reported and honoured); a tolerance 16 bits cannot meet is
// refused with the flag that fixes it.
TEST(World, FloatInputIsExactOrQuantisedWithinTheTolerance) {
  HeightfieldDesc d;
  d.width = 300, d.height = 260;
  std::vector<float> v(std::size_t(d.width) * d.height);
  for (std::size_t k = 0; k < v.size(); ++k)
    v[k] = float(40.0 * std::sin(0.037 * double(k % 300)) * std::cos(0.051 * double(k / 300)) +
                 0.001 * double(k % 7));
  auto make = [&] { return Heightfield::create(d, v).value(); };
  const std::string exact = tmp_path("exact.tif"), quant = tmp_path("quant.tif");
  auto r = io::bake_world(make(), exact);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->format, SampleFormat::kF32);
  auto memory = Terrain::create(make()).value();
  auto world = open_baked(exact);
  EXPECT_EQ(world->surface().heights_hash(), memory->surface().heights_hash());

  io::BakeOptions o;
  o.tolerance = 0.01;
  auto q = io::bake_world(make(), quant, o);
  ASSERT_TRUE(q) << q.error().message;
  EXPECT_EQ(q->format, SampleFormat::kU16);
  EXPECT_GT(q->max_error_m, 0.0);
  EXPECT_LE(q->max_error_m, 0.01);
  auto qw = open_baked(quant);
  double worst = 0;  // world heights: the quantised world moves its offset to the lowest height
  for (std::int64_t j = 0; j < 260; ++j)
    for (std::int64_t i = 0; i < 300; ++i)
      worst = std::max(worst, std::abs(qw->info().height_offset +
                                       double(qw->surface().stored_height(i, j)) -
                                       memory->info().height_offset -
                                       double(memory->surface().stored_height(i, j))));
  EXPECT_LE(worst, 0.01 + 1e-9);
  EXPECT_NEAR(worst, q->max_error_m, 1e-6);

  o.tolerance = 1e-5;  // 80 m in 65,536 steps cannot hold 10 microns
  auto refused = io::bake_world(make(), tmp_path("refused.tif"), o);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("raise --tolerance"), std::string::npos)
      << refused.error().message;
  EXPECT_FALSE(std::filesystem::exists(tmp_path("refused.tif")));
}

// ---- pages under a budget ----------------------------------------------------------------------

// A 10 MiB cache over a world of 64 level-0 pages and 4 level-1 pages: a sweep of queries over the whole world loads
// and evicts pages, yet the edited pages (and the bounds an edit remade) are never lost: after
// the sweep the edited ground answers as the same edit on the terrain in memory, and so do the
// meshes of a landscape made before the edit and of one made after it.
TEST(World, PagesAreEvictedUnderATinyBudgetButEditsAreKept) {
  const std::string path = tmp_path("w.tif");
  ASSERT_TRUE(io::bake_world(generated(2049, 2049), path));
  auto memory = Terrain::create(generated(2049, 2049)).value();
  // 10 MiB: the view's pages fit beside the edited ones (a budget below a view's working set
  // leaves it a coarser mesh); only the top level is held, so level-1 pages are evicted too.
  auto world = open_baked(path, 10, 1);
  const WorldInfo& w = memory->info();
  const Camera cam = looking_over(*memory, 0.05, 0.05);
  auto before_land = Landscape::create(world).value();
  auto before_view = RoamView::create(before_land, {.threshold = 1.5}).value();
  ASSERT_TRUE(before_view->converge(cam));

  std::vector<Edit> edits;
  for (int k = 0; k < 3; ++k) {
    Edit e;
    e.brush = k == 1 ? Brush::kRaise : Brush::kCrater;
    e.x = w.origin_x + (0.12 + 0.05 * k) * w.extent_x();
    e.z = w.origin_z + 0.1 * w.extent_z();
    e.radius = 20.0 + 10.0 * k;
    e.depth = 6.0;
    edits.push_back(e);
  }
  for (const Edit& e : edits) {
    ASSERT_TRUE(memory->apply_edit(e));
    ASSERT_TRUE(world->apply_edit(e));
  }
  // The sweep: every page of the world asked for in turn, the cache trimmed after each row.
  const std::uint64_t evicted_before = world->world_stats().evicted;
  for (double fz = 0.0; fz <= 1.0; fz += 1.0 / 16)
    for (double fx = 0.0; fx <= 1.0; fx += 1.0 / 16) {
      const double x = w.origin_x + fx * w.extent_x(), z = w.origin_z + fz * w.extent_z();
      ASSERT_EQ(world->height(x, z), memory->height(x, z)) << x << ", " << z;
      world->update_pages();
    }
  const WorldStats s = world->world_stats();
  EXPECT_GT(s.evicted, evicted_before) << "a 10 MiB cache over 2049^2 samples evicted nothing";
  EXPECT_TRUE(s.resident_bytes <= s.budget_bytes + s.budget_bytes / 10 ||
              s.resident_pages == s.pinned_pages)
      << s.resident_bytes << " bytes resident over a budget of " << s.budget_bytes << " with "
      << s.resident_pages - s.pinned_pages << " evictable pages";

  for (const Edit& e : edits)
    for (double a = 0; a < 6.283; a += 0.3)
      for (double r : {0.0, 0.5, 1.0, 1.4}) {
        const double x = e.x + r * e.radius * std::cos(a), z = e.z + r * e.radius * std::sin(a);
        ASSERT_EQ(world->height(x, z), memory->height(x, z)) << "edited ground lost at " << x
                                                             << ", " << z;
      }
  EXPECT_EQ(world->check_invariants(), "");
  ASSERT_TRUE(before_view->converge(cam));
  EXPECT_EQ(before_view->mesh_hash(), converged_mesh(memory, cam))
      << "a view made before the edits, after the sweep, differs from the map's";
  EXPECT_EQ(converged_mesh(world, cam), converged_mesh(memory, cam))
      << "a landscape made after the edits does not see them";
}

// Queries over pages nobody loaded load them on the asking thread and answer as the terrain in
// memory does: heights along a long transect and rays that cross most of the world.
TEST(World, QueriesOverPagesNotResidentAreExact) {
  const std::string path = tmp_path("w.tif");
  ASSERT_TRUE(io::bake_world(generated(1500, 1300), path));
  auto memory = Terrain::create(generated(1500, 1300)).value();
  auto world = open_baked(path, 4);
  const WorldStats at_open = world->world_stats();
  EXPECT_LT(at_open.resident_pages, 12u) << "opening loaded more than the coarse levels";
  const WorldInfo& w = memory->info();
  for (int k = 0; k <= 400; ++k) {
    const double x = w.origin_x + w.extent_x() * k / 400.0;
    const double z = w.origin_z + w.extent_z() * (0.5 + 0.45 * std::sin(k * 0.05));
    ASSERT_EQ(world->height(x, z), memory->height(x, z));
  }
  for (int k = 0; k < 40; ++k) {
    const glm::dvec3 o(w.origin_x - 50.0, w.height_offset + w.max_local + 10.0,
                       w.origin_z + w.extent_z() * k / 40.0);
    const glm::dvec3 d(1.0, -0.012 - 0.001 * k, 0.2);
    const auto a = memory->raycast(o, d, INFINITY), b = world->raycast(o, d, INFINITY);
    ASSERT_EQ(a.has_value(), b.has_value()) << "ray " << k;
    if (a) {
      EXPECT_EQ(a->distance, b->distance) << "ray " << k;
    }
  }
  EXPECT_GT(world->world_stats().sync_loads, 0u);
}

// pin() keeps the pages under a box resident through any amount of eviction; prefetch() loads in
// the background; a pin's pages go back to the cache when it is destroyed.
TEST(World, PinnedRegionsStayResident) {
  const std::string path = tmp_path("w.tif");
  ASSERT_TRUE(io::bake_world(generated(1500, 1300), path));
  auto source = io::open_world(path).value();
  WorldCacheDesc cache;
  cache.budget_bytes = 4 << 20;
  cache.worker_threads = 1;
  auto world = Terrain::open(source, cache).value();
  const WorldInfo& w = world->info();
  const Box box{{w.origin_x + 600, -1e4, w.origin_z + 500}, {w.origin_x + 700, 1e4, w.origin_z + 560}};
  {
    RegionPin pin = world->pin(box);
    const std::uint64_t loads = world->world_stats().sync_loads;
    for (int k = 0; k < 200; ++k) {
      world->height(w.origin_x + w.extent_x() * ((k * 37) % 200) / 200.0,
                    w.origin_z + w.extent_z() * ((k * 53) % 200) / 200.0);
      world->update_pages();
    }
    const std::uint64_t after_sweep = world->world_stats().sync_loads;
    world->height(w.origin_x + 650, w.origin_z + 530);
    EXPECT_EQ(world->world_stats().sync_loads, after_sweep)
        << "a query inside a pinned box loaded a page";
    EXPECT_GT(after_sweep, loads);
  }
  world->prefetch(box);
  for (int k = 0; k < 100 && world->world_stats().pending > 0; ++k) world->update_pages();
  EXPECT_EQ(world->world_stats().failed, 0u);
}

// ---- bad files ---------------------------------------------------------------------------------

// Truncated anywhere, a damaged header or index, a newer version, a foreign file: refused at
// open with a message naming the file and the fault. A damaged page is found when it loads:
// the query over it answers "no data", the rest of the world works.
TEST(World, DamagedTruncatedNewerAndForeignFilesAreRefused) {
  const std::string path = tmp_path("w.tif");
  ASSERT_TRUE(io::bake_world(generated(600, 600), path));
  const std::vector<std::uint8_t> good = read_file(path);
  auto refused = [&](const std::vector<std::uint8_t>& bytes, const std::string& what) {
    const std::string p = tmp_path("bad.tif");
    write_file(p, bytes);
    auto r = io::open_world(p);
    if (r) return std::string("opened");
    EXPECT_NE(r.error().message.find(p), std::string::npos) << r.error().message;
    EXPECT_NE(r.error().message.find(what), std::string::npos) << r.error().message;
    return r.error().message;
  };
  // A damaged file that open_world() accepts, opened as a terrain (loads on this thread).
  auto open_damaged = [&](const std::vector<std::uint8_t>& bytes,
                          const std::string& leaf) -> Result<std::shared_ptr<Terrain>> {
    const std::string p = tmp_path(leaf);
    write_file(p, bytes);
    auto source = io::open_world(p);
    if (!source) return Error{"open_world: " + source.error().message};
    WorldCacheDesc cache;
    cache.worker_threads = 0;
    return Terrain::open(*source, cache);
  };
  for (std::size_t cut : {std::size_t{0}, std::size_t{10}, std::size_t{100}, good.size() / 2,
                          good.size() - 1}) {
    std::vector<std::uint8_t> b(good.begin(), good.begin() + std::ptrdiff_t(cut));
    EXPECT_NE(refused(b, cut < 100 ? "not a Ridgeline world" : "truncated"), "opened")
        << "cut at " << cut;
  }
  {
    std::vector<std::uint8_t> b = good;
    b[16 + 8] = 9;  // the locator's version
    EXPECT_NE(refused(b, "format version 9; this build reads versions 3 to 5"), "opened");
    b[16 + 8] = 2;  // older than any this build reads
    EXPECT_NE(refused(b, "format version 2; this build reads versions 3 to 5"), "opened");
  }
  {
    std::vector<std::uint8_t> b = good;
    b[16 + 20] ^= 0x40;  // the index's offset
    EXPECT_NE(refused(b, "corrupted"), "opened");
  }
  {
    std::vector<std::uint8_t> b = good;
    std::uint64_t index_at = 0;  // the locator: magic, version, reserved, then the index's offset
    for (int k = 7; k >= 0; --k) index_at = (index_at << 8) | b[16 + 16 + std::size_t(k)];
    ASSERT_LT(index_at + 100, b.size());
    b[index_at + 60] ^= 0x01;  // inside the index
    EXPECT_NE(refused(b, "index is corrupted"), "opened");
    // The page entries lie in chunks just before the index, each checked when first read: the
    // open (which reads no entry) succeeds, the first load of a page of a damaged chunk fails
    // naming it; nothing is loaded from it.
    b = good;
    b[index_at - 5] ^= 0x01;
    auto t = open_damaged(b, "chunk.tif");
    ASSERT_FALSE(t) << "a world whose only entry chunk is damaged opened";
    EXPECT_EQ(t.error().message.find("open_world"), std::string::npos) << t.error().message;
    EXPECT_NE(t.error().message.find("page entry chunk 0 is corrupted (checksum mismatch)"),
              std::string::npos)
        << t.error().message;
  }
  {
    std::vector<std::uint8_t> b = good;
    b[8] = 0;  // a TIFF, but the locator's magic gone
    b[16] = 'X';
    EXPECT_NE(refused(b, "not a Ridgeline world"), "opened");
  }
  EXPECT_NE(refused({0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'}, "not a Ridgeline world"),
            "opened");
  {
    // A damaged page: found by its checksum when loaded; the world works around it.
    std::vector<std::uint8_t> b = good;
    b[1024 + 333] ^= 0xff;  // early in the first page written
    auto t = open_damaged(b, "page.tif");
    if (!t) {
      ASSERT_EQ(t.error().message.find("open_world"), std::string::npos) << t.error().message;
      // The damaged page was one of the coarse levels read at open: refused, naming it.
      EXPECT_NE(t.error().message.find("corrupted"), std::string::npos) << t.error().message;
      return;
    }
    std::size_t no_data = 0, answered = 0;
    const WorldInfo& w = (*t)->info();
    for (const glm::dvec2& q : points(w, 400, 5)) {
      const bool inside = q.x >= w.origin_x && q.x <= w.origin_x + w.extent_x() &&
                          q.y >= w.origin_z && q.y <= w.origin_z + w.extent_z();
      if (!inside) continue;
      ((*t)->height(q.x, q.y) ? answered : no_data)++;
    }
    EXPECT_GT(answered, 0u);
    EXPECT_GT((*t)->world_stats().failed + no_data, 0u) << "the damaged page went unnoticed";
  }
}

// A full disk in the middle of a bake (the file may not grow past 200 kB): the bake fails naming
// the write, and the world already at the path is untouched; no temporary file stays behind.
TEST(World, AFullDiskDuringABakeLeavesThePreviousWorld) {
  const std::string path = tmp_path("w.tif");
  ASSERT_TRUE(io::bake_world(generated(600, 600, 1), path));
  const std::vector<std::uint8_t> before = read_file(path);
  const std::string msg = in_child_with_file_limit(200 << 10, [&] {
    auto r = io::bake_world(generated(900, 900, 2), path);
    return r ? std::string("baked") : r.error().message;
  });
  EXPECT_NE(msg.find("writing failed"), std::string::npos) << msg;
  EXPECT_NE(msg.find("nothing was written"), std::string::npos) << msg;
  EXPECT_EQ(read_file(path), before) << "the previous world was damaged";
  for (const auto& e : std::filesystem::directory_iterator(std::filesystem::path(path).parent_path()))
    EXPECT_EQ(e.path().string().find(path + ".tmp"), std::string::npos)
        << "left behind: " << e.path();
}

// Cancelling from the progress callback stops the bake with "cancelled" and writes nothing.
TEST(World, ACancelledBakeWritesNothing) {
  const std::string path = tmp_path("w.tif");
  io::BakeOptions o;
  int calls = 0;
  o.progress = [&](double f, const char*) {
    ++calls;
    return f < 0.3;
  };
  auto r = io::bake_world(generated(800, 800), path, o);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("cancelled"), std::string::npos) << r.error().message;
  EXPECT_GT(calls, 1);
  EXPECT_FALSE(std::filesystem::exists(path));
}

// ---- worlds of several files -------------------------------------------------------------------

// One map cut into 2 x 2 files (shared edges, and abutting ones): joined by load_tiles, the world
// is the one-file map (same hash), and a mesh over the file borders is crack-free.
TEST(World, SeveralFilesMakeOneSeamlessWorld) {
  for (const bool shared : {true, false}) {
    // Files of 257 samples repeating their shared edge (a 513-sample world), or of 256 abutting.
    const std::uint32_t n = shared ? 513 : 512, t = shared ? 257 : 256;
    std::vector<std::uint16_t> raw(std::size_t(n) * n);
    scenes::generated_world_rows(n, 0, n, 9, raw.data());
    std::vector<std::string> files;
    for (std::uint32_t row = 0; row < 2; ++row)
      for (std::uint32_t col = 0; col < 2; ++col) {
        std::vector<std::uint8_t> b;
        for (std::uint32_t j = row * 256; j < row * 256 + t; ++j)
          for (std::uint32_t i = col * 256; i < col * 256 + t; ++i) {
            const std::uint16_t v = raw[i + std::size_t(j) * n];
            b.push_back(std::uint8_t(v & 0xff));
            b.push_back(std::uint8_t(v >> 8));
          }
        files.push_back(tmp_path(std::string(shared ? "s" : "u") + std::to_string(row) +
                                 std::to_string(col) + ".r16"));
        write_file(files.back(), b);
      }
    io::LoadOptions lo;
    lo.placement.spacing_x = 2.0, lo.placement.spacing_z = 1.5;
    lo.placement.origin_x = 1000.0, lo.placement.origin_z = -3000.0;
    lo.placement.height_offset = 120.0;
    lo.placement.height_scale = scenes::kWorldHeightScale;
    io::RawFormat format{t, t, io::RawType::kU16};
    auto joined = io::load_tiles(files, lo, io::TileLayout{2, 2, shared}, &format);
    ASSERT_TRUE(joined) << joined.error().message;
    ASSERT_EQ(joined->width(), n) << "2 x 2 files with " << (shared ? "shared" : "abutting")
                                  << " edges joined into the wrong width";
    auto from_files = Terrain::create(std::move(*joined)).value();
    auto from_one = Terrain::create(generated(n, n, 9)).value();
    EXPECT_EQ(from_files->info().content_hash, from_one->info().content_hash)
        << (shared ? "shared" : "abutting") << " edges";
    std::string cracks;
    const Camera cam = camera_at({1000.0 + 512.0, 120.0 + 900.0, -3000.0 + 384.0},
                                 {1000.0 + 520.0, 120.0, -3000.0 + 390.0});
    EXPECT_EQ(converged_mesh(from_files, cam, &cracks), converged_mesh(from_one, cam));
    EXPECT_EQ(cracks, "");
  }
}

// ---- caps --------------------------------------------------------------------------------------

// The size cap takes the usual 2^k + 1 sizes (16385^2 is the default cap itself) and its message
// names the option that raises it (the command line adds its flag: tests/cli).
TEST(World, TheSizeCapTakesTwoToTheKPlusOneAndNamesItsOption) {
  HeightfieldDesc d;
  d.width = d.height = 16385;
  EXPECT_TRUE(validate_heightfield_desc(d)) << "16385^2 is refused by the default cap";
  d.width = 16386;
  const Status s = validate_heightfield_desc(d);
  ASSERT_FALSE(s);
  EXPECT_NE(s.message().find("HeightfieldDesc::max_samples"), std::string::npos) << s.message();
}

// A baked world is a tiled GeoTIFF with overviews that image and GIS tools read whole: every
// sample of every level, the extra column and row of a 2^k + 1 size included (each level's tile
// grid then has one more column and row than its pages), 16-bit and float.
TEST(World, TheFileIsATiledTiffWithOverviewsThatImageToolsReadWhole) {
  for (const bool floats : {false, true}) {
    SCOPED_TRACE(floats ? "float" : "16-bit");
    const std::uint32_t n = 1025;  // 4 pages a side at level 0, 5 tiles
    Heightfield hf = generated(n, 769);
    const double scale = hf.height_scale();
    if (floats) {
      std::vector<float> local(hf.local_heights().begin(), hf.local_heights().end());
      for (std::size_t k = 0; k < local.size(); ++k) local[k] += 0.001f * float(k % 7);
      HeightfieldDesc d;
      d.width = n, d.height = 769;
      hf = Heightfield::create(d, local).value();
    }
    const std::string path = tmp_path(floats ? "f32.tif" : "u16.tif");
    ASSERT_TRUE(io::bake_world(hf, path, {})) << path;
    auto in = OIIO::ImageInput::open(path);
    ASSERT_TRUE(in) << OIIO::geterror();
    int levels = 0;
    for (int sub = 0; in->seek_subimage(sub, 0); ++sub, ++levels) {
      const OIIO::ImageSpec& spec = in->spec();
      const int shift = 2 * sub;  // level k holds every 4^k-th sample
      ASSERT_EQ(spec.width, int(((n - 1) >> shift) + 1));
      ASSERT_EQ(spec.height, int(((769 - 1) >> shift) + 1));
      ASSERT_EQ(spec.tile_width, 256);
      std::vector<float> px(std::size_t(spec.width) * std::size_t(spec.height));
      ASSERT_TRUE(in->read_image(sub, 0, 0, 1, OIIO::TypeDesc::FLOAT, px.data())) << in->geterror();
      std::size_t wrong = 0;
      for (int j = 0; j < spec.height; ++j)
        for (int i = 0; i < spec.width; ++i) {
          const float want = hf.local_heights()[std::size_t(i << shift) +
                                                std::size_t(j << shift) * n];
          // 16-bit files hold the stored value: local = scale * value.
          const float got = floats ? px[std::size_t(i) + std::size_t(j) * std::size_t(spec.width)]
                                   : float(scale *
                                           std::round(px[std::size_t(i) + std::size_t(j) * std::size_t(spec.width)] * 65535.0));
          if (std::abs(got - want) > (floats ? 0.0f : 1e-3f)) ++wrong;
        }
      EXPECT_EQ(wrong, 0u) << "level " << sub << " of " << spec.width << " x " << spec.height;
    }
    EXPECT_GE(levels, 2);
  }
}

// Pages loaded by workers before a landscape exists (opening queues the coarse levels; a game
// prefetches around its player) get that landscape's bounds when they are integrated: the view
// converges to the mesh the terrain in memory gives, crack-free.
TEST(World, PagesLoadedBeforeTheLandscapeGetItsBounds) {
  const std::string path = tmp_path("w.tif");
  ASSERT_TRUE(io::bake_world(generated(1025, 1025), path));
  auto source = io::open_world(path);
  ASSERT_TRUE(source);
  WorldCacheDesc cache;
  cache.worker_threads = 2;
  auto world = Terrain::open(*source, cache).value();
  const WorldInfo& w = world->info();
  world->prefetch({{w.origin_x, -1e9, w.origin_z}, {w.origin_x + w.extent_x(), 1e9, w.origin_z + w.extent_z()}});
  // Loaded (not yet integrated: no update_pages() until the view's first update).
  for (int k = 0; k < 1000 && world->world_stats().loaded < 17; ++k)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  EXPECT_EQ(world->world_stats().loaded, 17u) << "every page (16 + the top one) loaded first";
  auto memory = Terrain::create(generated(1025, 1025)).value();
  const Camera cam = looking_over(*memory, 0.2, 0.2);
  std::string cracks;
  const std::uint64_t from_world = converged_mesh(world, cam, &cracks);
  EXPECT_EQ(cracks, "");
  EXPECT_EQ(from_world, converged_mesh(memory, cam));
}

// Holes on a paged world: queries as in memory, a view made before the hole and a landscape
// made after it (its baked bounds remade around the hole blocks) draw the map's mesh.
TEST(World, HolesOnABakedWorldAreTheMapsHoles) {
  const std::string path = tmp_path("w.tif");
  ASSERT_TRUE(io::bake_world(generated(513, 513), path));
  auto memory = Terrain::create(generated(513, 513)).value();
  auto world = open_baked(path);
  const WorldInfo& w = memory->info();
  const Camera cam = looking_over(*memory, 0.2, 0.2);
  auto before_land = Landscape::create(world).value();
  auto before_view = RoamView::create(before_land, {.threshold = 1.5}).value();
  ASSERT_TRUE(before_view->converge(cam));
  const double x = w.origin_x + 0.5 * w.extent_x() + 1.0, z = w.origin_z + 0.5 * w.extent_z();
  for (auto* t : {memory.get(), world.get()})
    ASSERT_TRUE(t->apply_edit({.brush = Brush::kHole, .x = x, .z = z, .radius = 30}));
  EXPECT_GT(world->surface().hole_cells(), 100u);
  EXPECT_FALSE(world->height(x, z));
  EXPECT_EQ(world->height(x + 40, z), memory->height(x + 40, z));
  ASSERT_TRUE(before_view->converge(cam));
  std::string cracks;
  EXPECT_EQ(before_view->mesh_hash(), converged_mesh(memory, cam, &cracks));
  EXPECT_EQ(cracks, "");
  EXPECT_EQ(converged_mesh(world, cam), converged_mesh(memory, cam));
}

// The map's own holes (no-data samples with FillPolicy::kHole) are baked with the world: a world
// opened from the file has the same hole cells as the terrain made in memory from the map, the
// same answers to queries (no ground over a hole), the same converged mesh (its baked bounds made
// around the holes), crack-free; a fill edit gives the ground back on both. A hole list that
// leaves the cells is refused when the file is opened.
TEST(World, TheMapsOwnHolesAreBakedWithTheWorld) {
  const std::string path = tmp_path("w.tif");
  auto holed = [] {
    const Heightfield g = generated(513, 385);
    std::vector<float> h(g.local_heights().begin(), g.local_heights().end());
    for (std::int64_t j = 0; j < 385; ++j)
      for (std::int64_t i = 0; i < 513; ++i) {
        const double a = double(i - 300), b = double(j - 200);
        if (a * a + 0.5 * b * b < 40.0 * 40.0 || (i >= 40 && i < 44 && j >= 30 && j < 300))
          h[std::size_t(i) + std::size_t(j) * 513] = -9999.0f;
      }
    HeightfieldDesc d;
    d.width = 513, d.height = 385;
    d.spacing_x = 2.0, d.spacing_z = 1.5;
    d.origin_x = 1000.0, d.origin_z = -3000.0;
    d.height_offset = 120.0;
    d.height_scale = scenes::kWorldHeightScale;
    d.nodata = -9999.0;
    d.fill = FillPolicy::kHole;
    return Heightfield::create(d, std::move(h)).value();
  };
  const Heightfield map = holed();
  ASSERT_GT(map.hole_cells().size(), 3000u);
  auto baked = io::bake_world(map, path);
  ASSERT_TRUE(baked) << baked.error().message;
  EXPECT_EQ(baked->hole_cells, map.hole_cells().size());
  auto memory = Terrain::create(holed()).value();
  auto world = open_baked(path);
  ASSERT_EQ(world->surface().hole_cells(), memory->surface().hole_cells());
  ASSERT_EQ(world->surface().hole_cells(), map.hole_cells().size());
  EXPECT_EQ(world->info().content_hash, memory->info().content_hash);
  const WorldInfo& w = memory->info();
  std::size_t none = 0;
  for (const glm::dvec2& p : points(w, 4000, 21)) {
    const auto a = memory->sample(p.x, p.y), b = world->sample(p.x, p.y);
    ASSERT_EQ(a.has_value(), b.has_value()) << p.x << ", " << p.y;
    none += !a;
    if (a) {
      EXPECT_EQ(a->height, b->height) << p.x << ", " << p.y;
    }
  }
  EXPECT_GT(none, 100u) << "no point fell in a hole: the test misses its subject";
  const double hx = w.origin_x + 300 * 2.0 + 0.5, hz = w.origin_z + 200 * 1.5 + 0.5;
  EXPECT_FALSE(world->height(hx, hz));
  for (const auto& f : {std::pair{0.45, 0.35}, std::pair{0.05, 0.1}}) {
    std::string cracks;
    const Camera cam = looking_over(*memory, f.first, f.second);
    EXPECT_EQ(converged_mesh(world, cam, &cracks), converged_mesh(memory, cam))
        << "the baked world's converged mesh differs from the map's";
    EXPECT_EQ(cracks, "");
  }
  for (auto* t : {memory.get(), world.get()})
    ASSERT_TRUE(t->apply_edit({.brush = Brush::kFillHole, .x = hx, .z = hz, .radius = 100}));
  EXPECT_EQ(world->surface().hole_cells(), memory->surface().hole_cells());
  EXPECT_TRUE(world->height(hx, hz));
  EXPECT_EQ(world->height(hx, hz), memory->height(hx, hz));

  // A hole run past the cells: refused at the open, naming the file.
  struct Lying : PageSource {
    std::shared_ptr<const PageSource> inner;
    const WorldInfo& info() const noexcept override { return inner->info(); }
    Status summaries(std::vector<PageSummary>& out) const override { return inner->summaries(out); }
    Status load(const PageKey& k, PageData& out) const override { return inner->load(k, out); }
    Status holes(std::vector<HoleRun>& out) const override {
      out = {{10, 500, 512}};  // cell 512 of a 512-cell row
      return {};
    }
  };
  auto lying = std::make_shared<Lying>();
  lying->inner = io::open_world(path).value();
  auto refused = Terrain::open(lying, {});
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("lies outside its 512 x 384 cells"), std::string::npos)
      << refused.error().message;
}

// A view under a triangle cap and a time budget over pages that arrive a frame or more after
// they are asked for (the engine's executor, run by hand between frames: the same run on every
// machine): the queues hold diamonds whose pages are missing, merges free nodes still queued, the
// cap falls and rises; after every update the mesh is consistent and crack-free.
TEST(World, ACappedBudgetedViewOverArrivingPagesStaysConsistent) {
  const std::string path = tmp_path("w.tif");
  ASSERT_TRUE(io::bake_world(generated(1025, 1025), path));
  auto source = io::open_world(path);
  ASSERT_TRUE(source);
  std::vector<std::function<void()>> jobs;
  WorldCacheDesc cache;
  cache.budget_bytes = std::size_t{4} << 20;
  cache.resident_levels = 1;
  cache.executor = [&jobs](std::function<void()> job) { jobs.push_back(std::move(job)); };
  auto world = Terrain::open(*source, cache).value();
  const WorldInfo& w = world->info();
  auto land = Landscape::create(world).value();
  auto view =
      RoamView::create(land, {.threshold = 0.5, .max_triangles = 20000, .budget_ms = 1e4}).value();
  std::uint64_t pending = 0;
  for (int f = 0; f < 300; ++f) {
    const double a = f * 0.05;
    const double cx = w.origin_x + w.extent_x() * (0.5 + 0.35 * std::cos(a));
    const double cz = w.origin_z + w.extent_z() * (0.5 + 0.35 * std::sin(a));
    const double y = w.height_offset + w.max_local + 5.0 + 40.0 * (1 + std::sin(f * 0.11));
    const Camera c = camera_at({cx, y, cz}, {cx + 200 * std::cos(a + 1.6), w.height_offset,
                                             cz + 200 * std::sin(a + 1.6)});
    RoamSettings s = view->settings();
    s.max_triangles = (f / 25) % 2 ? 6000 : 20000;
    ASSERT_TRUE(view->set_settings(s));
    auto st = view->update(c);
    ASSERT_TRUE(st);
    pending += st->pending_splits;
    ASSERT_EQ(view->check_invariants(), "") << "frame " << f;
    ASSERT_EQ(check_crack_free(*view), "") << "frame " << f;
    // Every other frame half of the loads asked for arrive (the oldest first).
    if (f % 2 == 0) {
      const std::size_t n = (jobs.size() + 1) / 2;
      std::vector<std::function<void()>> run(jobs.begin(), jobs.begin() + std::ptrdiff_t(n));
      jobs.erase(jobs.begin(), jobs.begin() + std::ptrdiff_t(n));
      for (auto& job : run) job();
    }
    world->update_pages();
  }
  for (auto& job : jobs) job();
  EXPECT_GT(pending, 100u) << "no split waited for a page";
}
