// Hierarchical geomorphs (morph_factor() in roam/view/roam_view.cpp; the morph bounds of the
// landscape): a vertex starts on its parent edge as drawn.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "ridgeline/roam_view.h"
#include "roam/diamond.h"
#include "roam_landscapes.h"

using namespace ridgeline;
using namespace ridgeline::test;

// Hierarchical geomorphs (docs/roam.md, "Geomorphs"), checked on the output an engine draws:
// every vertex whose diamond's ratio (what the split test compares with 1) is at least 1 has the
// two ends of the edge it splits at t = 1, at their true heights, so the vertex starts on its
// parent edge as drawn; and at t = 0 it is drawn at that edge's midpoint (its morph offset).
// Along a flyover at several thresholds, morph windows and delays.
TEST(Roam, AVertexStartsOnItsParentEdgeAsDrawn) {
  for (const Geomorph g : {Geomorph{}, Geomorph{0.5, 0.0}, Geomorph{1.0, 0.3}}) {
    auto hf = make_default_heightfield({.size = 257, .spacing = 2.0, .seed = 1337});
    ASSERT_TRUE(hf);
    auto l = Landscape::create(Terrain::create(std::move(hf).value()).value(),
                               {.patch_exponent = 5, .morph_window = g.window,
                                .morph_delay = g.delay})
                 .value();
    ASSERT_EQ(l->geomorph().window, g.window);
    ASSERT_EQ(l->geomorph().delay, g.delay);
    for (const double tau : {1.0, 3.0}) {
      auto v = RoamView::create(l, {.threshold = tau}).value();
      std::size_t active = 0, ends = 0;
      for (int k = 0; k < 12; ++k) {
        const double a = 0.3 * k;
        const glm::dvec3 eye(256 + 150 * std::cos(a), 140, 256 + 150 * std::sin(a));
        const Camera cam = camera_at(eye, {256, 40, 256});
        auto st = v->update(cam);
        ASSERT_TRUE(st);
        const double K = projection_scale(cam);
        for (std::uint32_t p = 0; p < l->patch_count(); ++p) {
          const PatchMesh& m = v->patch_mesh(p);
          const glm::vec3 e(float(eye.x - m.origin_x), float(eye.y - m.origin_y),
                            float(eye.z - m.origin_z));
          // The drawn vertices by lattice position.
          std::map<std::pair<std::int64_t, std::int64_t>, const MeshVertex*> at;
          for (std::size_t t = 0; t + 2 < m.indices.size(); t += 3) {
            if (m.indices[t] == m.indices[t + 1]) continue;
            for (int q = 0; q < 3; ++q) {
              const MeshVertex& mv = m.vertices[m.indices[t + q]];
              at[{std::llround((m.origin_x + mv.x) / 2.0),
                  std::llround((m.origin_z + mv.z) / 2.0)}] = &mv;
            }
          }
          auto rho = [&](const MeshVertex& mv) {
            const double dx = mv.x - e.x, dy = mv.y - e.y, dz = mv.z - e.z;
            const double d = std::sqrt(dx * dx + dy * dy + dz * dz) - mv.morph_radius;
            return mv.morph_bound * K / (st->morph_threshold * std::max(d, 1e-6));
          };
          for (const auto& [ij, mv] : at) {
            if (mv->morph_bound >= 3e38f || mv->morph_radius >= 3e38f) continue;  // never morph
            if (rho(*mv) < 1.0) continue;  // split for the frustum's sake, not its ratio
            ++active;
            std::int64_t hu, hw;
            roam::half_hypotenuse(ij.first, ij.second, l->patch_log2(), hu, hw);
            float ends_y = 0;
            for (const int s : {-1, 1}) {
              const auto it = at.find({ij.first + s * hu, ij.second + s * hw});
              ASSERT_NE(it, at.end()) << "an end of the edge vertex (" << ij.first << ", "
                                      << ij.second << ") splits is not drawn";
              const MeshVertex& end = *it->second;
              ends_y += end.y;
              EXPECT_EQ(morph_factor(end, e, K, st->morph_threshold, g), 1.0f)
                  << "vertex (" << ij.first << ", " << ij.second << ") at ratio " << rho(*mv)
                  << ": an end of its edge is still morphing (ratio " << rho(end) << ")";
              ++ends;
            }
            // At t = 0 the vertex sits on the edge between its ends' true heights.
            EXPECT_NEAR(mv->y + mv->morph_dy, 0.5f * ends_y, 1e-4f * (1 + std::abs(mv->y)));
          }
        }
      }
      EXPECT_GT(active, 1000u) << "w " << g.window << " delay " << g.delay << " threshold " << tau;
      EXPECT_EQ(ends, 2 * active);
    }
  }
}
