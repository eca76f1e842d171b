// The output an engine uploads (roam/patch_output.cpp, roam/view/output_compaction.cpp): buffers
// that match the leaves, seams that share height bits, compaction, and an engine copy kept up to
// date from the dirty ranges.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <set>

#include "ridgeline/roam_view.h"
#include "roam_landscapes.h"

using namespace ridgeline;
using namespace ridgeline::test;

TEST(Roam, OutputBuffersMatchTheLeavesAndSeamsShareHeightBits) {
  auto l = make_landscape(257, 5);
  auto view = RoamView::create(l, {.threshold = 1.0}).value();
  const Camera c = camera_at({20, 120, 30}, {300, 60, 260});
  ASSERT_TRUE(view->update(c));
  auto dirty = view->take_dirty_patches();
  EXPECT_EQ(dirty.size(), l->patch_count());
  std::size_t tris = 0;
  std::map<std::pair<std::int64_t, std::int64_t>, std::uint32_t> height_bits;
  for (std::uint32_t p = 0; p < l->patch_count(); ++p) {
    const PatchMesh& m = view->patch_mesh(p);
    tris += m.indices.size() / 3;
    for (std::size_t k = 0; k < m.indices.size(); k += 3) {
      const MeshVertex& a = m.vertices[m.indices[k]];
      const MeshVertex& b = m.vertices[m.indices[k + 1]];
      const MeshVertex& cc = m.vertices[m.indices[k + 2]];
      // Counter-clockwise from above: cross product's y > 0 in (x, y, z).
      const double cy = double(b.z - a.z) * (cc.x - a.x) - double(b.x - a.x) * (cc.z - a.z);
      EXPECT_GT(cy, 0.0);
    }
    for (const MeshVertex& v : m.vertices) {
      const auto i = std::llround((m.origin_x + v.x) / 2.0),
                 j = std::llround((m.origin_z + v.z) / 2.0);
      std::uint32_t bits;
      std::memcpy(&bits, &v.y, 4);
      auto [it, fresh] = height_bits.emplace(std::make_pair(i, j), bits);
      if (!fresh) {
        EXPECT_EQ(it->second, bits) << "vertex " << i << "," << j;
      }
      EXPECT_NEAR(glm::length(glm::vec3(v.nx, v.ny, v.nz)), 1.0f, 1e-4f);
    }
  }
  EXPECT_EQ(tris, view->triangle_count());
  // A small move changes only some patches.
  Camera c2 = c;
  c2.eye += glm::dvec3(2, 0, 2);
  c2.target += glm::dvec3(2, 0, 2);
  ASSERT_TRUE(view->update(c2));
  dirty = view->take_dirty_patches();
  EXPECT_LT(dirty.size(), l->patch_count());
}

// What an engine keeps: a copy of every patch's buffers, brought up to date after each update
// from take_dirty_patches() the way docs/roam.md says (whole when resized, else the dirty ranges),
// equals the view's buffers at every step; and a patch's buffers hold at most about twice the
// slots it uses (compaction), while the camera dives close to the ground and climbs away again,
// through threshold changes, a triangle cap and a time budget.
TEST(Roam, OutputStaysCompactAndAnEngineCopyFollowsIt) {
  auto l = make_landscape(257, 5);  // no padding: every live triangle is drawn
  auto view = RoamView::create(l, {.threshold = 0.5}).value();
  struct Copy {
    std::vector<MeshVertex> vertices;
    std::vector<std::uint32_t> indices;
  };
  std::vector<Copy> gpu(l->patch_count());
  std::uint32_t compacted = 0, checked_bounds = 0;
  for (int frame = 0; frame < 120; ++frame) {
    // Down to 12 m over the south-west corner looking north-east, then up to 400 m and away.
    const double t = frame / 119.0, up = t < 0.3 ? 1.0 - t / 0.3 : (t - 0.3) / 0.7;
    const glm::dvec3 eye(30 + 300 * t, 12 + 390 * up, 30 + 120 * t);
    RoamSettings s = view->settings();
    s.threshold = frame < 60 ? 0.5 : frame < 90 ? 3.0 : 1.0;
    s.max_triangles = frame >= 70 && frame < 80 ? 6000 : 0;
    s.budget_ms = frame >= 100 && frame < 105 ? 0.05 : 0.0;
    ASSERT_TRUE(view->set_settings(s));
    const auto st = view->update(camera_at(eye, eye + glm::dvec3(1, -0.5, 1)));
    ASSERT_TRUE(st);
    ASSERT_EQ(view->check_invariants(), "") << "frame " << frame;
    compacted += st->compacted_patches;
    for (const std::uint32_t p : view->take_dirty_patches()) {
      const PatchMesh& m = view->patch_mesh(p);
      Copy& g = gpu[p];
      if (m.resized) {
        g.vertices = m.vertices;
        g.indices = m.indices;
        continue;
      }
      g.vertices.resize(m.vertices.size());
      g.indices.resize(m.indices.size());
      for (const MeshRange& r : m.dirty_vertices)
        std::copy_n(m.vertices.begin() + r.first, r.count, g.vertices.begin() + r.first);
      for (const MeshRange& r : m.dirty_triangles)
        std::copy_n(m.indices.begin() + 3 * std::size_t(r.first), 3 * std::size_t(r.count),
                    g.indices.begin() + 3 * std::size_t(r.first));
    }
    for (std::uint32_t p = 0; p < l->patch_count(); ++p) {
      const PatchMesh& m = view->patch_mesh(p);
      const Copy& g = gpu[p];
      ASSERT_EQ(g.indices, m.indices) << "frame " << frame << " patch " << p;
      std::set<std::uint32_t> used;
      for (std::size_t k = 0; k < m.indices.size(); k += 3)
        if (m.indices[k] != m.indices[k + 1]) used.insert(&m.indices[k], &m.indices[k + 3]);
      for (const std::uint32_t v : used)
        ASSERT_EQ(std::memcmp(&g.vertices[v], &m.vertices[v], sizeof(MeshVertex)), 0)
            << "frame " << frame << " patch " << p << " vertex " << v;
      // Without a time budget every oversized patch is compacted before the update returns.
      if (s.budget_ms == 0.0) {
        EXPECT_LE(m.indices.size() / 3, 2 * std::size_t(m.triangles) + 64)
            << "frame " << frame << " patch " << p;
        EXPECT_LE(m.vertices.size(), 2 * used.size() + 64) << "frame " << frame << " patch " << p;
        ++checked_bounds;
      }
    }
  }
  EXPECT_GT(compacted, 10u);  // the climb empties the patches the dive filled
  EXPECT_GT(checked_bounds, 0u);
}
