// The benchmark library (Ridgeline::bench, module/bench/) and the measurement it shares
// (mesh_error.h): the uniform grid, the CDLOD quadtree and the SOAR refinement are crack-free and
// cover the terrain, the error measurement agrees with a brute-force reference and with
// RoamView::measure_error, triangle counts match, the jump and the pop measure what
// docs/report.md says; the quantile is the one stats.h defines, and the frame loop times and
// measures every technique alike.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <string>

#include "ridgeline/bench/frame_loop.h"
#include "ridgeline/bench/meshes.h"
#include "ridgeline/bench/roam_drawn.h"
#include "ridgeline/bench/soar.h"
#include "ridgeline/bench/stats.h"
#include "ridgeline/bench/summary.h"
#include "ridgeline/bench/techniques.h"
#include "ridgeline/edit.h"
#include "ridgeline/landscape.h"
#include "ridgeline/mesh_error.h"
#include "ridgeline/roam_view.h"
#include "ridgeline/scenes.h"

namespace ridgeline::bench {
namespace {

std::shared_ptr<const Terrain> field(std::uint32_t w, std::uint32_t h, double sx = 1.0,
                                     double sz = 1.0, double origin = 0.0) {
  scenes::FieldDesc d;
  d.width = w;
  d.height = h;
  d.spacing_x = sx;
  d.spacing_z = sz;
  d.origin_x = d.origin_z = origin;
  auto hf = scenes::field(d, [](int i, int j) {
    return 20 * std::sin(0.21 * i) * std::cos(0.17 * j) + 7 * std::sin(0.9 * i + 1.3 * j) + 30;
  });
  EXPECT_TRUE(hf.ok()) << hf.error().message;
  return Terrain::create(std::move(*hf)).value();
}

Camera look(const glm::dvec3& eye, const glm::dvec3& target) {
  Camera c;
  c.eye = eye;
  c.target = target;
  return c;
}

TEST(ReportSurface, HeightsAtSamplesAreExactAndBetweenFollowTheDiagonalRule) {
  auto t = field(9, 7, 2.0, 3.0, 100.0);
  const Heightfield hf = t->surface().to_heightfield().value();
  for (std::uint32_t j = 0; j < 7; ++j)
    for (std::uint32_t i = 0; i < 9; ++i) EXPECT_EQ(surface_height(hf, i, j), hf.world(i, j));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 8), v(0, 6);
  for (int k = 0; k < 500; ++k) {
    const double a = u(rng), b = v(rng);
    const auto q = t->height(100 + 2 * a, 100 + 3 * b);
    ASSERT_TRUE(q.has_value());
    EXPECT_NEAR(surface_height(hf, a, b), *q, 1e-4);  // the query interpolates in float
  }
}

TEST(ReportUniformGrid, IsWatertightAndCoversTheTerrain) {
  for (auto [w, h] : {std::pair{33u, 33u}, {40u, 27u}, {2u, 2u}}) {
    auto t = field(w, h, 1.5, 0.7);
    for (double n : {2.0, 50.0, 700.0, 5000.0}) {
      const UniformGrid g = UniformGrid::for_triangles(Grid(*t), n);
      const DrawnMesh m = g.mesh(Grid(*t));
      EXPECT_EQ(m.triangles(), g.triangles());
      EXPECT_EQ(check_watertight(Grid(*t), m), "") << w << "x" << h << " n=" << n;
    }
  }
}

TEST(ReportUniformGrid, MatchesTriangleCountsWithinFivePercent) {
  auto t = field(1025, 700, 1.0, 2.0);
  for (double n : {100.0, 999.0, 5000.0, 24583.0, 123071.0}) {
    const UniformGrid g = UniformGrid::for_triangles(Grid(*t), n);
    EXPECT_NEAR(double(g.triangles()) / n, 1.0, 0.05) << n;
  }
}

// Cameras all over a 129 x 129 field: high, low, looking along and down.
std::vector<Camera> cameras() {
  std::vector<Camera> c;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> xz(-20, 150), y(35, 300), t(0, 128);
  for (int k = 0; k < 12; ++k) c.push_back(look({xz(rng), y(rng), xz(rng)}, {t(rng), 20, t(rng)}));
  c.push_back(look({64, 400, 64}, {64.1, 0, 64}));
  return c;
}

TEST(ReportCdlod, MorphedSelectionIsWatertightAndCoversTheTerrain) {
  auto t = field(129, 129);
  for (std::uint32_t g : {4u, 8u}) {
    const Cdlod cd(Grid(*t), g);
    int multi_level = 0;
    for (double scale : {1.0, 1.7, 4.0}) {
      for (const Camera& c : cameras()) {
        const auto s = cd.select(c, cd.min_r0() * scale, /*cull=*/false);
        std::uint32_t lo = 99, hi = 0;
        for (const auto& ch : s.chunks) {
          lo = std::min(lo, ch.level);
          hi = std::max(hi, ch.level);
        }
        multi_level += hi > lo;
        EXPECT_EQ(check_watertight(Grid(*t), cd.mesh(s, c, true)), "")
            << "grid " << g << " r0 x" << scale << " eye " << c.eye.x << "," << c.eye.y << ","
            << c.eye.z;
      }
    }
    EXPECT_GT(multi_level, 3) << "few cameras mixed levels: the test would prove little";
  }
}

TEST(ReportCdlod, WithoutMorphingLevelsMeetWithTJunctions) {
  // The check must be able to fail: unmorphed chunks of two levels leave cracks.
  auto t = field(129, 129);
  const Cdlod cd(Grid(*t), 8);
  int cracked = 0;
  for (const Camera& c : cameras()) {
    const auto s = cd.select(c, cd.min_r0(), false);
    cracked += !check_watertight(Grid(*t), cd.mesh(s, c, false)).empty();
  }
  EXPECT_GT(cracked, 0);
}

TEST(ReportCdlod, NonSquareFieldNotAPowerOfTwoIsCovered) {
  auto t = field(95, 90, 598, 927);  // elev.tif's shape and cell size
  const Cdlod cd(Grid(*t), 8);
  const Camera c = look({20000, 3000, 30000}, {40000, 0, 60000});
  const auto s = cd.select(c, cd.min_r0() * 1.3, false);
  EXPECT_EQ(check_watertight(Grid(*t), cd.mesh(s, c, true)), "");
}

TEST(ReportCdlod, MatchesAFeasibleTriangleTargetWithinTenPercent) {
  auto t = field(1025, 1025);
  const Cdlod cd(Grid(*t), 8);
  std::vector<Camera> path;
  for (int k = 0; k < 30; ++k) {
    const double a = 0.2 * k;
    path.push_back(look({512 + 300 * std::cos(a), 120, 512 + 300 * std::sin(a)}, {512, 20, 512}));
  }
  // Feasible targets lie between the shortest ranges the morph allows and full detail in view.
  const double least = cd.match(path, 0).median, most = cd.match(path, 1e12).median;
  ASSERT_LT(least * 4, most);
  for (double target : {least * 1.3, std::sqrt(least * most), most * 0.7}) {
    const auto m = cd.match(path, target);
    EXPECT_GE(m.r0, cd.min_r0());
    EXPECT_NEAR(m.median / target, 1.0, 0.10) << target;
  }
}

TEST(ReportCdlod, RefreshAfterAnEditEqualsARebuiltQuadtree) {
  auto hf = scenes::field({.width = 129, .height = 129},
                          [](int i, int) { return 30 + 10 * std::sin(0.1 * i); });
  ASSERT_TRUE(hf.ok());
  auto t = Terrain::create(std::move(*hf)).value();
  Cdlod cd(Grid(*t), 8);
  Edit e;
  e.brush = Brush::kCrater;
  e.x = 70;
  e.z = 40;
  e.radius = 12;
  e.depth = 30;  // deep: the node boxes around it must grow
  auto r = t->apply_edit(e);
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_FALSE(r->empty());
  cd.refresh(std::int64_t(r->changed.min.x) - 1, std::int64_t(r->changed.min.z) - 1,
             std::int64_t(r->changed.max.x) + 1, std::int64_t(r->changed.max.z) + 1);
  const Cdlod rebuilt(Grid(*t), 8);
  EXPECT_EQ(cd.min_r0(), rebuilt.min_r0());
  for (const Camera& c : cameras()) {
    const auto a = cd.select(c, rebuilt.min_r0() * 1.2, false);
    const auto b = rebuilt.select(c, rebuilt.min_r0() * 1.2, false);
    ASSERT_EQ(a.chunks.size(), b.chunks.size());
    EXPECT_EQ(a.triangles, b.triangles);
    EXPECT_EQ(check_watertight(Grid(*t), cd.mesh(a, c, true)), "");
  }
}

// Brute force: for each lattice vertex in view, search every triangle of the mesh.
MeshError brute_force(const Heightfield& hf, const DrawnMesh& m, const Camera& c) {
  const Frustum f(c);
  MeshError out;
  double sum2 = 0;
  for (std::uint32_t j = 0; j < hf.height(); ++j)
    for (std::uint32_t i = 0; i < hf.width(); ++i) {
      const glm::dvec3 p(hf.origin_x() + i * hf.spacing_x(), hf.world(i, j),
                         hf.origin_z() + j * hf.spacing_z());
      double d;
      if (!f.contains(p, &d)) continue;
      ++out.vertices;
      bool found = false;
      for (std::size_t t = 0; t < m.triangles() && !found; ++t) {
        const glm::dvec3 *a = &m.corners[3 * t], *b = a + 1, *cc = a + 2;
        const double area = (b->x - a->x) * (cc->z - a->z) - (b->z - a->z) * (cc->x - a->x);
        if (std::abs(area) < 1e-12) continue;
        const double w1 = ((i - a->x) * (cc->z - a->z) - (j - a->z) * (cc->x - a->x)) / area;
        const double w2 = ((b->x - a->x) * (j - a->z) - (b->z - a->z) * (i - a->x)) / area;
        if (w1 < -1e-9 || w2 < -1e-9 || w1 + w2 > 1 + 1e-9) continue;
        const double h = a->y + w1 * (b->y - a->y) + w2 * (cc->y - a->y);
        const double e = std::abs(h - p.y);
        out.max_m = std::max(out.max_m, e);
        out.max_px = std::max(out.max_px, e * f.scale / d);
        sum2 += e * e;
        found = true;
      }
      out.uncovered += !found;
    }
  out.rms_m = std::sqrt(sum2 / double(out.vertices - out.uncovered));
  return out;
}

TEST(ReportMeasure, AgreesWithBruteForceOnASmallField) {
  auto t = field(33, 33, 2.0, 1.0);
  const Heightfield hf = t->surface().to_heightfield().value();
  const Cdlod cd(hf, 4);
  const MeshErrorMeter meter(hf);
  for (const Camera& c : {look({-10, 60, -10}, {40, 0, 20}), look({33, 25, 16}, {0, 20, 16}),
                          look({32, 200, 16}, {32.1, 0, 16})}) {
    const DrawnMesh meshes[2] = {UniformGrid::for_triangles(hf, 150).mesh(hf),
                                 cd.mesh(cd.select(c, cd.min_r0(), false), c, true)};
    for (const DrawnMesh& m : meshes) {
      const MeshError a = meter.measure(meter.rasterize(m), c), b = brute_force(hf, m, c);
      ASSERT_GT(a.vertices, 50u);
      EXPECT_EQ(a.vertices, b.vertices);
      EXPECT_EQ(a.uncovered, 0u);
      EXPECT_EQ(b.uncovered, 0u);
      if (&m == &meshes[0]) {
        EXPECT_GT(b.max_m, 0.1);  // coarse: the comparison is not of zeros
      }
      EXPECT_NEAR(a.max_m, b.max_m, 1e-4);
      EXPECT_NEAR(a.rms_m, b.rms_m, 1e-4);
      EXPECT_NEAR(a.max_px, b.max_px, 1e-3 * std::max(1.0, b.max_px));
    }
  }
}

TEST(ReportMeasure, HolesAreCountedAndAStrideSamplesEveryKthVertex) {
  auto t = field(33, 33);
  const Heightfield hf = t->surface().to_heightfield().value();
  DrawnMesh m = UniformGrid{8, 8}.mesh(hf);
  m.corners.resize(m.corners.size() - 6);  // drop the last quad (its corner (32, 32))
  const Camera c = look({16, 80, -40}, {16, 0, 16});
  const MeshErrorMeter all(hf, 1), every4(hf, 4);
  const MeshError a = all.measure(all.rasterize(m), c), b = every4.measure(every4.rasterize(m), c);
  EXPECT_EQ(all.columns(), 33u);
  EXPECT_EQ(every4.columns(), 9u);
  EXPECT_GT(a.uncovered, 0u);
  EXPECT_LT(a.uncovered, 4u * 4u + 1u);  // at most the dropped quad's vertices
  EXPECT_EQ(b.uncovered, 1u);            // of every 4th vertex, only (32, 32) lies in it
  EXPECT_LT(b.vertices, a.vertices);
  const MeshError w = all.measure_all(all.rasterize(m));
  EXPECT_EQ(w.vertices, 33u * 33u);
  EXPECT_EQ(w.max_px, 0.0);
  // A bad camera sees nothing.
  Camera bad = c;
  bad.target = bad.eye;
  EXPECT_EQ(all.measure(all.rasterize(m), bad).vertices, 0u);
}

TEST(ReportMeasure, RoamViewMeasuresItsPatchMeshesAsTheBruteForceDoes) {
  auto t = field(129, 129, 1.0, 1.0, 1e6);
  auto l = Landscape::create(t, {.patch_exponent = 5});
  ASSERT_TRUE(l.ok());
  auto v = RoamView::create(*l, {.threshold = 3.0});
  ASSERT_TRUE(v.ok());
  const Camera c = look({1e6 - 20, 90, 1e6 - 20}, {1e6 + 64, 10, 1e6 + 64});
  ASSERT_TRUE((*v)->converge(c).ok());
  const auto ref = (*v)->measure_error(c);
  const MeshErrorMeter meter(*t);
  // The patch meshes as a renderer draws them (no geomorph) against a search over every triangle.
  const DrawnMesh drawn = RoamSnapshot::capture(**v).draw(meter, c, false);
  const MeshError b = brute_force(t->surface().to_heightfield().value(), drawn, c);
  EXPECT_EQ(b.vertices, ref.vertices);
  EXPECT_EQ(b.uncovered, 0u);
  EXPECT_GT(ref.max_m, 0.1);
  EXPECT_NEAR(b.max_m, ref.max_m, 1e-4);
  EXPECT_NEAR(b.rms_m, ref.rms_m, 1e-4);
  EXPECT_NEAR(b.max_px, ref.max_px, 1e-3);
  EXPECT_EQ(check_watertight(Grid(*t), drawn), "");
  EXPECT_EQ(check_watertight(Grid(*t), leaves_mesh(**v)), "");
}

TEST(ReportMeasure, JumpIsZeroForAnUnchangedMeshAndTheHeightJumpOtherwise) {
  auto t = field(33, 33);
  const Heightfield hf = t->surface().to_heightfield().value();
  const MeshErrorMeter meter(hf);
  const Camera c = look({16, 40, -30}, {16, 20, 16});
  const DrawnHeights a = meter.rasterize(UniformGrid{4, 4}.mesh(hf));
  DrawnHeights b = meter.rasterize(UniformGrid{4, 4}.mesh(hf));
  EXPECT_EQ(meter.jump_px(a, b, c, &c), 0.0);
  DrawnMesh raised = UniformGrid{4, 4}.mesh(hf);
  for (auto& p : raised.corners) p.y += 0.5;
  b = meter.rasterize(raised);
  const double pop = meter.jump_px(a, b, c);
  // 0.5 m at the nearest vertex in view: between 0.5 * scale / far-most and / near-most.
  EXPECT_GT(pop, 0.5 * projection_scale(c) / 100.0);
  EXPECT_LT(pop, 0.5 * projection_scale(c) / 20.0);
  // Seen from behind the field (nothing of it in view) nothing pops.
  EXPECT_EQ(meter.jump_px(a, b, look({16, 40, -30}, {16, 40, -60})), 0.0);
}

// The pop compares two meshes drawn for the same camera: a refinement pops by its height change,
// a mesh that does not change topology does not pop even when it moves continuously.
TEST(ReportPop, ARefinementPopsAndASameMeshMorphedDoesNot) {
  auto t = field(129, 129);
  auto l = Landscape::create(t, {.patch_exponent = 5});
  ASSERT_TRUE(l.ok());
  auto v = RoamView::create(*l, {.threshold = 8.0});
  ASSERT_TRUE(v.ok());
  const Camera c = look({-20, 70, -20}, {64, 10, 64});
  ASSERT_TRUE((*v)->converge(c).ok());
  const MeshErrorMeter meter(*t);
  const RoamSnapshot coarse = RoamSnapshot::capture(**v);
  ASSERT_TRUE((*v)->set_settings({.threshold = 2.0}).ok());
  ASSERT_TRUE((*v)->converge(c).ok());
  const RoamSnapshot fine = RoamSnapshot::capture(**v);
  ASSERT_GT(fine.triangles(), coarse.triangles());
  const DrawnHeights cf = meter.rasterize(coarse.draw(meter, c, false));
  const DrawnHeights ff = meter.rasterize(fine.draw(meter, c, false));
  EXPECT_GT(meter.jump_px(cf, ff, c), 2.0);  // splits past 8 px down to 2 px: visible
  // One mesh drawn twice for one camera does not pop, morphed or not.
  const DrawnHeights f1 = meter.rasterize(fine.draw(meter, c, true));
  EXPECT_EQ(meter.jump_px(f1, meter.rasterize(fine.draw(meter, c, true)), c), 0.0);
}

TEST(ReportRoamDrawn, UnmorphedIsTheTrueHeightAndAFreshSplitStartsOnItsEdge) {
  MeshVertex v{};
  v.y = 10;
  v.morph_dy = 2.0f;
  v.morph_bound = 1.0f;
  Camera c = look({0, 0, -1000}, {0, 0, 0});
  const glm::dvec3 w(0, 10, 0);
  const Geomorph g{0.5, 0.1};
  EXPECT_EQ(roam_drawn_y(v, w, c, 2.0, g, false), 10.0);
  EXPECT_EQ(roam_drawn_y(v, w, c, 0.0, g, true), 10.0);  // no pixel threshold: no morph
  // Far away the bound projects below the threshold: the vertex sits on the coarser edge.
  EXPECT_DOUBLE_EQ(roam_drawn_y(v, w, c, 2.0, g, true), 12.0);
  // Just past the threshold (ratio 1.05, inside the delay): still on the edge.
  const double k = projection_scale(c);
  c.eye = {0, 10, -k / (2.0 * 1.05)};
  EXPECT_DOUBLE_EQ(roam_drawn_y(v, w, c, 2.0, g, true), 12.0);
  // Ratio 1.35: half way through the window.
  c.eye = {0, 10, -k / (2.0 * 1.35)};
  EXPECT_NEAR(roam_drawn_y(v, w, c, 2.0, g, true), 11.0, 1e-5);
  // Close, the projected bound is over twice the threshold: the true height.
  c.eye = {0, 0, -1};
  EXPECT_DOUBLE_EQ(roam_drawn_y(v, w, c, 2.0, g, true), 10.0);
}

// ---- SOAR -------------------------------------------------------------------------------

std::vector<Camera> soar_cameras() {
  return {look({-10, 60, -10}, {64, 0, 64}), look({64, 25, 64}, {100, 20, 64}),
          look({64, 300, 64}, {64.1, 0, 64}), look({200, 40, 64}, {0, 30, 64})};
}

TEST(ReportSoar, StripIsWatertightCoversTheTerrainAndHoldsTheLeafCount) {
  auto t = field(129, 129);
  const Heightfield hf = t->surface().to_heightfield().value();
  const Soar soar(hf);
  EXPECT_EQ(soar.size(), 129u);
  std::vector<std::uint32_t> strip;
  for (const Camera& c : soar_cameras())
    for (double th : {0.5, 2.0, 8.0})
      for (bool cull : {true, false}) {
        const auto f = soar.refine(c, Soar::kappa_for(c, th), strip, cull);
        const DrawnMesh m = soar.mesh(strip);
        EXPECT_EQ(m.triangles(), f.triangles);
        EXPECT_EQ(soar.count(c, Soar::kappa_for(c, th), cull), f.triangles);
        EXPECT_EQ(check_watertight(hf, m), "") << th << " px, cull " << cull;
      }
}

TEST(ReportSoar, InfiniteKappaGivesTheFullLatticeAndZeroError) {
  auto t = field(65, 65);
  const Heightfield hf = t->surface().to_heightfield().value();
  const Soar soar(hf);
  std::vector<std::uint32_t> strip;
  const Camera c = soar_cameras()[0];
  const auto f = soar.refine(c, Soar::kappa_for(c, 0.0), strip, false);
  EXPECT_EQ(f.triangles, 2u * 64u * 64u);
  const MeshErrorMeter meter(hf);
  const MeshError e = meter.measure_all(meter.rasterize(soar.mesh(strip)));
  EXPECT_EQ(e.uncovered, 0u);
  EXPECT_LT(e.max_m, 1e-4);
}

TEST(ReportSoar, MoreKappaMoreTrianglesLessErrorAndCullingDropsTheOutOfView) {
  auto t = field(129, 129);
  const Heightfield hf = t->surface().to_heightfield().value();
  const Soar soar(hf);
  const MeshErrorMeter meter(hf);
  std::vector<std::uint32_t> strip;
  const Camera c = soar_cameras()[0];
  std::uint64_t last = 0;
  double last_rms = 1e9;
  for (double th : {16.0, 4.0, 1.0, 0.25}) {
    const auto f = soar.refine(c, Soar::kappa_for(c, th), strip);
    const MeshError e = meter.measure(meter.rasterize(soar.mesh(strip)), c);
    EXPECT_GT(f.triangles, last);
    EXPECT_LE(e.rms_m, last_rms);
    last = f.triangles;
    last_rms = e.rms_m;
  }
  const Camera away = look({64, 40, -10}, {64, 40, -100});  // looking off the terrain
  EXPECT_LT(soar.count(away, Soar::kappa_for(away, 1.0)),
            soar.count(away, Soar::kappa_for(away, 1.0), false) / 4);
}

TEST(ReportSoar, NonPowerOfTwoFieldIsCoveredThroughThePadding) {
  auto t = field(95, 90, 6.0, 9.0);
  const Heightfield hf = t->surface().to_heightfield().value();
  const Soar soar(hf);
  EXPECT_EQ(soar.size(), 129u);
  const MeshErrorMeter meter(hf);
  std::vector<std::uint32_t> strip;
  for (const Camera& c : {look({-50, 400, -50}, {280, 0, 400}), look({280, 300, 400}, {0, 0, 0})}) {
    soar.refine(c, Soar::kappa_for(c, 2.0), strip);
    const MeshError e = meter.measure_all(meter.rasterize(soar.mesh(strip)));
    EXPECT_EQ(e.uncovered, 0u);
    EXPECT_GT(e.max_m, 0.0);
  }
}

TEST(ReportSoar, MatchFindsTheKappaOfATriangleTarget) {
  auto t = field(257, 257);
  const Soar soar{Grid(*t)};
  std::vector<Camera> path;
  for (int k = 0; k < 12; ++k)
    path.push_back(
        look({128 + 90 * std::cos(k * 0.3), 70, 128 + 90 * std::sin(k * 0.3)}, {128, 20, 128}));
  for (double target : {2000.0, 8000.0}) {
    const Soar::Match m = soar.match(path, target);
    EXPECT_NEAR(m.median / target, 1.0, 0.05) << target;
  }
}


// ---- Ridgeline::bench: statistics, the in-view count, the frame loop ----------------------

TEST(BenchStats, QuantileIsTheElementOfRankFloorQN) {
  const std::vector<double> six = {5, 1, 4, 2, 3, 6};  // sorted: 1 .. 6
  EXPECT_EQ(quantile(six, 0.0), 1);
  EXPECT_EQ(quantile(six, 0.5), 4);   // rank floor(3): the upper of the two middle values
  EXPECT_EQ(quantile(six, 0.99), 6);  // rank floor(5.94)
  EXPECT_EQ(quantile(six, 1.0), 6);
  EXPECT_EQ(quantile(six, 2.0), 6);  // q clamped to [0, 1]
  EXPECT_EQ(median({3, 1, 2}), 2);
  std::vector<double> frames(360);
  std::iota(frames.begin(), frames.end(), 1.0);
  EXPECT_EQ(quantile(frames, 0.99), 357);  // the 357th smallest of 360
  EXPECT_EQ(max_of(frames), 360);
  EXPECT_EQ(mean({1, 2, 6}), 3);
  // An empty series has no figure: NaN, null in JSON, or the fallback asked for.
  EXPECT_TRUE(std::isnan(quantile({}, 0.5)));
  EXPECT_TRUE(std::isnan(max_of({})));
  EXPECT_EQ(quantile_or({}, 0.5, 0.0), 0.0);
  EXPECT_TRUE(number(std::nan("")).is_null());
  EXPECT_EQ(number(2.5), 2.5);
}

TEST(BenchInView, APatchBufferAndTheLeavesOfItsViewCountTheSameTriangles) {
  // 100 x 70 samples: patches over the padding, and unused (0, 0, 0) slots in the buffers.
  auto t = field(100, 70);
  auto l = Landscape::create(t, {.patch_exponent = 4});
  ASSERT_TRUE(l.ok());
  auto v = RoamView::create(*l, {.threshold = 2.0});
  ASSERT_TRUE(v.ok());
  const MeshErrorMeter meter(*t);
  const Camera near = look({-10, 60, -10}, {50, 20, 35}), far = look({150, 80, 120}, {50, 20, 35});
  for (const Camera& c : {near, far, near}) {  // merges leave unused slots behind
    ASSERT_TRUE((*v)->converge(c).ok());
    const DrawnMesh buffers = RoamSnapshot::capture(**v).draw(meter, c, false);
    const DrawnMesh leaves = leaves_mesh(**v);
    EXPECT_GT(buffers.triangles(), (*v)->triangle_count() / 2);
    const auto n = meter.triangles_in_view(leaves, c);
    EXPECT_GT(n, 0u);
    EXPECT_LT(n, (*v)->triangle_count());
    EXPECT_EQ(meter.triangles_in_view(buffers, c), n);
  }
  // A degenerate triangle and one beyond the lattice are not drawn: not counted.
  DrawnMesh odd;
  odd.add({10, 30, 10}, {10, 30, 10}, {10, 30, 10});
  odd.add({99, 30, 10}, {101, 30, 10}, {100, 30, 12});
  EXPECT_EQ(meter.triangles_in_view(odd, far), 0u);
}

// A technique that logs its calls and draws a static 32 x 32 grid.
class Logged final : public Technique {
 public:
  Logged(const Terrain& t, std::string name, std::vector<std::string>& log)
      : grid_(t), name_(std::move(name)), log_(log) {}
  std::string name() const override { return name_; }
  Status start(const Camera&) override {
    log_.push_back(name_ + ":start");
    return {};
  }
  Status update(const Camera&) override {
    log_.push_back(name_ + ":update");
    ++updates_;
    return {};
  }
  bool has_output() const override { return true; }
  void output() override { log_.push_back(name_ + ":output"); }
  FrameFigures figures() const override {
    FrameFigures f;
    f.triangles = double(g_.triangles());
    f.extra = {{"updates", updates_}, {"label", "x"}};
    return f;
  }
  Drawable capture(const MeshErrorMeter&) override {
    log_.push_back(name_ + ":capture");
    auto mesh = std::make_shared<const DrawnMesh>(g_.mesh(grid_));
    return [mesh](const Camera&, bool) { return *mesh; };
  }
  Json summary() const override { return {{"label", name_}}; }

 private:
  Grid grid_;
  UniformGrid g_{32, 32};
  std::string name_;
  std::vector<std::string>& log_;
  int updates_ = 0;
};

TEST(BenchLoop, TimesEveryTechniqueAlikeAndMeasuresTheChosenFrames) {
  auto t = field(33, 33);
  const MeshErrorMeter meter(*t);
  std::vector<Camera> path;
  for (int k = 0; k < 12; ++k) path.push_back(look({-5.0 + k, 40, -5}, {16, 10, 16}));
  std::vector<std::string> log;
  Logged a(*t, "a", log), b(*t, "b", log);
  LoopOptions o;
  o.warmup = 2;
  o.repeat = 2;
  o.error_every = 4;
  o.alternate = true;
  o.keep_frames = true;
  std::vector<std::size_t> before;
  o.before_frame = [&](std::size_t k) {
    before.push_back(k);
    return Status{};
  };
  auto runs = run_path({&a, &b}, path, &meter, o);
  ASSERT_TRUE(runs.ok()) << runs.error().message;
  ASSERT_EQ(runs->size(), 2u);
  // start(), two warm-up frames in order, then the laps with the first technique alternating.
  EXPECT_EQ(log[0], "a:start");
  EXPECT_EQ(log[1], "b:start");
  EXPECT_EQ(log[2], "a:update");
  EXPECT_EQ(log[4], "b:update");
  const auto first = std::find(log.begin() + 10, log.end(), "b:update");
  EXPECT_TRUE(std::find(log.begin() + 10, first, "a:update") != first);  // lap 1, frame 0: a first
  EXPECT_EQ(before.size(), 24u);
  for (const bench::Run& r : *runs) {
    EXPECT_EQ(r.wall_ms.size(), 24u);
    EXPECT_EQ(r.output_ms.size(), 24u);
    EXPECT_EQ(r.frames.size(), 24u);
    EXPECT_EQ(r.max_m.size(), 6u);  // frames 0, 4, 8 of each lap
    EXPECT_EQ(r.in_view.size(), 6u);
    EXPECT_EQ(r.uncovered, 0u);
    EXPECT_TRUE(std::isfinite(max_of(r.max_m)));
    EXPECT_EQ(r.named("updates").size(), 24u);  // numbers become series, strings do not
    EXPECT_TRUE(r.named("label").empty());
    EXPECT_TRUE(r.frames[0].contains("triangles_in_view"));
    EXPECT_FALSE(r.frames[1].contains("triangles_in_view"));
    EXPECT_EQ(r.summary["label"], r.technique);
    const Json lod = lod_figures(r);
    EXPECT_EQ(lod["frames"], 24);
    EXPECT_TRUE(lod["changes_per_frame_median"].is_null());  // not reported by the technique
    EXPECT_EQ(lod["triangles_median"], 2.0 * 32 * 32);
    const Json rep = report_figures(r);
    EXPECT_TRUE(rep["pop_max_px"].is_null());  // no pops asked for
    EXPECT_EQ(rep["measured_frames"], 6);
  }
  // With pops: errors at K, 2K, ... and the mesh of K - 1, 2K - 1, ... captured; only those
  // frames updated when asked.
  log.clear();
  LoopOptions p;
  p.error_every = 4;
  p.pops = true;
  p.only_measured_frames = true;
  auto r = run_path(a, path, &meter, p);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->wall_ms.size(), 5u);  // frames 3, 4, 7, 8, 11
  EXPECT_EQ(r->max_m.size(), 2u);    // frames 4, 8
  EXPECT_EQ(r->pop.size(), 2u);
  EXPECT_EQ(max_of(r->pop), 0.0);  // the same mesh: no pop
  // Measuring needs a meter.
  EXPECT_FALSE(run_path(a, path, nullptr, p).ok());
}

TEST(BenchLoop, RoamAndSoarReportTheSameFiguresThroughOneLoop) {
  auto t = field(129, 129);
  auto l = Landscape::create(t, {.patch_exponent = 5});
  ASSERT_TRUE(l.ok());
  auto v = RoamView::create(*l, {.threshold = 2.0});
  ASSERT_TRUE(v.ok());
  std::vector<Camera> path;
  for (int k = 0; k < 20; ++k) path.push_back(look({-10.0 + 2 * k, 70, -10}, {64, 20, 64}));
  const Heightfield hf = t->surface().to_heightfield().value();
  const MeshErrorMeter meter(hf);
  const Soar soar(hf);
  RoamTechnique roam(std::move(*v), true);
  SoarTechnique stateless(soar, 2.0, std::numeric_limits<double>::infinity());
  LoopOptions o;
  o.error_every = 5;
  o.pops = true;
  auto runs = run_path({&roam, &stateless}, path, &meter, o);
  ASSERT_TRUE(runs.ok()) << runs.error().message;
  for (const bench::Run& r : *runs) {
    const Json j = report_figures(r);
    EXPECT_EQ(j["frames"], 20);
    EXPECT_EQ(j["measured_frames"], 3);
    EXPECT_EQ(j["uncovered_vertices"], 0);
    EXPECT_GT(j["triangles_in_view_median"].get<double>(), 0);
    EXPECT_LE(j["triangles_in_view_median"].get<double>(), j["triangles_median"].get<double>());
    EXPECT_GT(j["memory_bytes"].get<double>(), 0);
  }
  EXPECT_EQ((*runs)[0].technique, "roam_coherent");
  EXPECT_TRUE((*runs)[0].has_morph);
  EXPECT_LE(max_of((*runs)[0].max_px), 2.0 + 1e-9);  // ROAM keeps its threshold, unmorphed
  EXPECT_EQ((*runs)[1].technique, "soar");
  EXPECT_EQ((*runs)[1].named("refine_only_ms").size(), 3u);
  EXPECT_GT((*runs)[1].upload_bytes.front(), 4 * (*runs)[1].triangles.front());
}

}  // namespace
}  // namespace ridgeline::bench
