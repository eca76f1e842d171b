// The surface's point queries (module/src/surface/point_queries.cpp): analytic cases, the
// diagonal rule, hard points (vertices, edges, diagonals, seams, far edge, off-terrain,
// non-finite input), cliffs, flat fields, precision far from the origin, smooth normals against a
// hand computation, batched == single, materials. Checked against the independent reference of
// query_reference.h.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <glm/geometric.hpp>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <thread>
#include <tuple>
#include <vector>

#include "query_reference.h"
#include "ridgeline/detail.h"
#include "ridgeline/edit.h"
#include "ridgeline/scenes.h"
#include "ridgeline/surface.h"
#include "ridgeline/terrain.h"

using namespace ridgeline;
using namespace ridgeline::test;

// ---- Analytic cases ---------------------------------------------------------------------------

TEST(PointQueries, PlaneHeightIsExactInsideAndEmptyOutside) {
  auto t = make_terrain({}, [](int i, int j) { return 2 * i + 3 * j; });
  EXPECT_NEAR(*t->height(1.25, 2.5), 2 * 1.25 + 3 * 2.5, 1e-5);
  EXPECT_FALSE(t->height(-0.1, 1.0));
}

TEST(PointQueries, PlaneHeightAndNormalsAreExactOnNonSquareCells) {
  // h = 1 + 0.5 x - 0.25 z on non-square cells.
  FieldSpec s{9, 7, 2.0, 0.5, 10.0, -4.0, 0.0};
  auto t = make_terrain(s, [&](int i, int j) { return 1 + 0.5 * (i * 2.0) - 0.25 * (j * 0.5); });
  const glm::dvec3 n = glm::normalize(glm::dvec3(-0.5, 1, 0.25));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> ux(10.0, 26.0), uz(-4.0, -1.0);
  for (int k = 0; k < 2000; ++k) {
    const double x = ux(rng), z = uz(rng);
    const double expect = 1 + 0.5 * (x - 10.0) - 0.25 * (z + 4.0);
    ASSERT_NEAR(*t->height(x, z), expect, 1e-5);
    ASSERT_TRUE(near_vec(*t->face_normal(x, z), n, 1e-6));
    ASSERT_TRUE(near_vec(*t->smooth_normal(x, z), n, 1e-6));
    const auto s1 = *t->sample(x, z);
    ASSERT_NEAR(s1.height, expect, 1e-5);
    const auto hn = *t->height_normal(x, z);
    ASSERT_NEAR(hn.height, expect, 1e-5);
    ASSERT_TRUE(near_vec(hn.face_normal, n, 1e-6));
  }
}

TEST(PointQueries, BowlIsExactAtSamplesAboveTheCurveBetweenAndNormalsTiltInwards) {
  // h = (x - 8)^2 + (z - 8)^2 sampled at integers: exact at samples, the interpolant lies above
  // the convex bowl by at most (sx^2 + sz^2) / 2 (curvature 2), normals tilt towards the centre.
  FieldSpec s{17, 17};
  auto bowl = [](double x, double z) { return (x - 8) * (x - 8) + (z - 8) * (z - 8); };
  auto t = make_terrain(s, [&](int i, int j) { return bowl(i, j); });
  for (int j = 0; j < 17; ++j)
    for (int i = 0; i < 17; ++i) ASSERT_EQ(*t->height(i, j), bowl(i, j));
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(0.0, 16.0);
  for (int k = 0; k < 2000; ++k) {
    const double x = u(rng), z = u(rng);
    const double h = *t->height(x, z);
    ASSERT_GE(h, bowl(x, z) - 1e-4);
    ASSERT_LE(h, bowl(x, z) + 1.0 + 1e-4);
    const glm::vec3 n = *t->smooth_normal(x, z);
    if (std::abs(x - 8) > 1.5) {
      ASSERT_EQ(n.x > 0, x < 8) << x << " " << z;
    }
  }
  EXPECT_TRUE(near_vec(*t->smooth_normal(8, 8), glm::dvec3(0, 1, 0), 1e-6));
}

// ---- The diagonal rule ------------------------------------------------------------------------

TEST(PointQueries, DiagonalRuleSeenThroughARaisedVertex) {
  // Raise corner (i+1, j) of each cell in turn. At the cell's centre, a main diagonal
  // (i, j)-(i+1, j+1) runs through two zero corners (height 0); the anti diagonal
  // (i+1, j)-(i, j+1) runs through the raised corner (height 1/2).
  FieldSpec s{7, 6, 1.5, 0.75, -3.0, 2.0};
  for (int j = 0; j + 1 < 6; ++j) {
    for (int i = 0; i + 1 < 7; ++i) {
      auto t = make_terrain(s, [&](int a, int b) { return (a == i + 1 && b == j) ? 1.0 : 0.0; });
      const bool spec_main = (i + j) % 2 == 0;
      const double cx = s.ox + (i + 0.5) * s.sx, cz = s.oz + (j + 0.5) * s.sz;
      EXPECT_NEAR(*t->height(cx, cz), spec_main ? 0.0 : 0.5, 1e-6) << i << "," << j;
      EXPECT_EQ(cell_has_main_diagonal(i, j), spec_main);
      // On the other diagonal's line, (0.75, 0.25) from corner (i, j): with the main diagonal
      // the triangle (i,j),(i+1,j+1),(i+1,j) holds it with weight 1/2 on (i+1, j); with the anti
      // diagonal it lies on that diagonal, 3/4 of the way to (i+1, j).
      EXPECT_NEAR(*t->height(s.ox + (i + 0.75) * s.sx, s.oz + (j + 0.25) * s.sz),
                  spec_main ? 0.5 : 0.75, 1e-6);
      // (0.25, 0.75): the main diagonal's other triangle does not hold (i+1, j) at all; on the
      // anti diagonal the weight of (i+1, j) is 1/4.
      EXPECT_NEAR(*t->height(s.ox + (i + 0.25) * s.sx, s.oz + (j + 0.75) * s.sz),
                  spec_main ? 0.0 : 0.25, 1e-6);
    }
  }
}

TEST(PointQueries, LocateInCellMatchesSpecTriangles) {
  // Both triangles of every cell parity, against the corners of the rule's wording, and
  // counter-clockwise.
  for (int j = 0; j < 2; ++j) {
    for (int i = 0; i < 2; ++i) {
      std::set<std::vector<int>> from_locate, from_spec;
      for (float fu : {0.1f, 0.9f, 0.4f})
        for (float fv : {0.1f, 0.9f, 0.6f}) {
          const CellTriangle t = locate_in_cell(i, j, fu, fv);
          std::vector<int> c;
          for (int k = 0; k < 3; ++k) c.push_back(t.di[k] * 2 + t.dj[k]);
          // CCW seen from above with x right and z down the page, as surface.h says: the y of
          // (p1 - p0) x (p2 - p0) is positive for a flat triangle lifted to y = 0.
          const glm::dvec3 p0(t.di[0], 0, t.dj[0]), p1(t.di[1], 0, t.dj[1]),
              p2(t.di[2], 0, t.dj[2]);
          EXPECT_GT(glm::cross(p1 - p0, p2 - p0).y, 0);
          // Barycentric weights reproduce the point.
          float su = 0, sv = 0, sw = 0;
          for (int k = 0; k < 3; ++k) su += t.w[k] * t.di[k], sv += t.w[k] * t.dj[k], sw += t.w[k];
          EXPECT_NEAR(su, fu, 1e-6);
          EXPECT_NEAR(sv, fv, 1e-6);
          EXPECT_NEAR(sw, 1.0f, 1e-6);
          for (int k = 0; k < 3; ++k) EXPECT_GE(t.w[k], -1e-6);
          std::sort(c.begin(), c.end());
          from_locate.insert(c);
        }
      for (const auto& sc : spec_cell_corners(i, j)) {
        std::vector<int> c;
        for (int k = 0; k < 3; ++k) c.push_back(sc[2 * k] * 2 + sc[2 * k + 1]);
        std::sort(c.begin(), c.end());
        from_spec.insert(c);
      }
      EXPECT_EQ(from_locate, from_spec) << i << "," << j;
    }
  }
}

// ---- Hard points ------------------------------------------------------------------------------

TEST(PointQueries, VerticesEdgesDiagonalsAndSeamsAgreeWithTheReference) {
  FieldSpec s{13, 11, 1.25, 0.5, 100.0, 200.0, 0.0};
  auto t = make_terrain(s, rough);
  const Heightfield hf = t->surface().to_heightfield().value();
  auto X = [&](double u) { return s.ox + u * s.sx; };
  auto Z = [&](double v) { return s.oz + v * s.sz; };
  for (int j = 0; j < 11; ++j)
    for (int i = 0; i < 13; ++i) EXPECT_EQ(*t->height(X(i), Z(j)), hf.world(i, j));
  for (int j = 0; j + 1 < 11; ++j) {
    for (int i = 0; i + 1 < 13; ++i) {
      const double a = hf.world(i, j), b = hf.world(i + 1, j), c = hf.world(i, j + 1),
                   d = hf.world(i + 1, j + 1);
      for (double f : {0.25, 0.5, 0.8}) {
        // Cell edges: linear between their endpoints.
        EXPECT_NEAR(*t->height(X(i + f), Z(j)), a + f * (b - a), 1e-5);
        EXPECT_NEAR(*t->height(X(i), Z(j + f)), a + f * (c - a), 1e-5);
        // The diagonal: linear between its endpoints.
        if ((i + j) % 2 == 0)
          EXPECT_NEAR(*t->height(X(i + f), Z(j + f)), a + f * (d - a), 1e-5);
        else
          EXPECT_NEAR(*t->height(X(i + 1 - f), Z(j + f)), b + f * (c - b), 1e-5);
        // Seams: both sides of an edge agree in the limit.
        const double e = 1e-9;
        EXPECT_NEAR(*t->height(X(i + f), Z(j) - e * (j > 0)), *t->height(X(i + f), Z(j) + e), 1e-5);
        EXPECT_NEAR(*t->height(X(i) - e * (i > 0), Z(j + f)), *t->height(X(i) + e, Z(j + f)), 1e-5);
      }
    }
  }
}

TEST(PointQueries, FarEdgeIsOnTerrainAndOutsideIsEmpty) {
  FieldSpec s{6, 4, 2.0, 3.0, 1e6, -1e6, 5.0};
  auto t = make_terrain(s, rough);
  const Heightfield hf = t->surface().to_heightfield().value();
  const double x1 = s.ox + hf.extent_x(), z1 = s.oz + hf.extent_z();
  EXPECT_EQ(*t->height(x1, z1), hf.world(5, 3));
  EXPECT_EQ(*t->height(s.ox, s.oz), hf.world(0, 0));
  EXPECT_TRUE(t->face_normal(x1, z1));
  EXPECT_TRUE(t->smooth_normal(x1, s.oz));
  EXPECT_TRUE(t->sample(s.ox, z1));
  const double bad[][2] = {{x1 + 1e-6, z1},     {x1, z1 + 1e-6}, {s.ox - 1e-6, s.oz},
                           {s.ox, s.oz - 1e-6}, {kNaN, s.oz},    {s.ox, kNaN},
                           {kInf, s.oz},        {-kInf, s.oz},   {s.ox, kInf},
                           {1e308, 1e308},      {-1e308, -1e308}};
  for (const auto& p : bad) {
    EXPECT_FALSE(t->height(p[0], p[1])) << p[0] << "," << p[1];
    EXPECT_FALSE(t->face_normal(p[0], p[1]));
    EXPECT_FALSE(t->smooth_normal(p[0], p[1]));
    EXPECT_FALSE(t->sample(p[0], p[1]));
    EXPECT_FALSE(t->height_normal(p[0], p[1]));
  }
}

TEST(PointQueries, ThousandMetreCliffGivesFiniteUnitUpwardNormals) {
  // Samples jump by 1,000 m between columns 3 and 4 (and rows 2 and 3) on 1 m cells.
  FieldSpec s{9, 8};
  auto t =
      make_terrain(s, [](int i, int j) { return (i >= 4 ? 1000.0 : 0.0) + (j >= 3) * 1000.0; });
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> ux(0.0, 8.0), uz(0.0, 7.0);
  for (int k = 0; k < 5000; ++k) {
    const double x = k < 100 ? 3.0 + k / 100.0 : ux(rng), z = uz(rng);
    for (const glm::vec3 n : {*t->face_normal(x, z), *t->smooth_normal(x, z)}) {
      ASSERT_TRUE(std::isfinite(n.x) && std::isfinite(n.y) && std::isfinite(n.z));
      ASSERT_NEAR(glm::length(n), 1.0f, 1e-6f);
      ASSERT_GT(n.y, 0.0f);
    }
  }
  // The face of the cliff (cell 3, row 0): slope 1000 along x.
  const glm::dvec3 face = glm::normalize(glm::dvec3(-1000, 1, 0));
  EXPECT_TRUE(near_vec(*t->face_normal(3.6, 0.3), face, 1e-6));
  // A horizontal ray into the cliff hits its face.
  auto hit = t->raycast({0.5, 500.0, 0.25}, {1, 0, 0}, kInf);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->distance, 3.5 - 0.5, 1e-9);
  EXPECT_FALSE(hit->started_below);
  EXPECT_NEAR(glm::length(hit->normal), 1.0f, 1e-6f);
}

TEST(PointQueries, PerfectlyFlatFieldNormalIsExactlyUp) {
  for (double level : {0.0, 123.456, -7.0}) {
    FieldSpec s{11, 9, 0.3, 7.0, 1e7, -1e7, 1000.0};
    auto t = make_terrain(s, [&](int, int) { return level; });
    std::mt19937 rng(6);
    std::uniform_real_distribution<double> ux(s.ox, s.ox + 3.0), uz(s.oz, s.oz + 56.0);
    for (int k = 0; k < 500; ++k) {
      const double x = ux(rng), z = uz(rng);
      EXPECT_EQ(*t->face_normal(x, z), glm::vec3(0, 1, 0));
      EXPECT_EQ(*t->smooth_normal(x, z), glm::vec3(0, 1, 0));
      EXPECT_EQ(t->height_normal(x, z)->face_normal, glm::vec3(0, 1, 0));
      EXPECT_NEAR(*t->height(x, z), 1000.0 + level, 1e-4);
    }
    auto hit = t->raycast({s.ox + 1.0, 2000.0, s.oz + 3.0}, {0.001, -1, 0.002}, kInf);
    ASSERT_TRUE(hit);
    EXPECT_EQ(hit->normal, glm::vec3(0, 1, 0));
  }
}

TEST(PointQueries, SameTerrainFarFromOriginGivesTheSameAnswers) {
  const FieldSpec base{33, 29, 1.5, 2.0, 0.0, 0.0, 0.0};
  auto t0 = make_terrain(base, rough);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ux(0.0, 48.0), uz(0.0, 56.0), ua(0.0, 6.283185307179586);
  for (double far : {1e6, 1e7, -1e7}) {
    FieldSpec s = base;
    s.ox = far;
    s.oz = -far * 0.5;
    auto t1 = make_terrain(s, rough);
    for (int k = 0; k < 2000; ++k) {
      const double x = ux(rng), z = uz(rng);
      const double h0 = *t0->height(x, z), h1 = *t1->height(s.ox + x, s.oz + z);
      ASSERT_NEAR(h0, h1, 1e-3);
      ASSERT_TRUE(
          near_vec(*t1->face_normal(s.ox + x, s.oz + z), glm::dvec3(*t0->face_normal(x, z)), 1e-4));
      ASSERT_TRUE(near_vec(*t1->smooth_normal(s.ox + x, s.oz + z),
                           glm::dvec3(*t0->smooth_normal(x, z)), 1e-4));
      // Rays too: a slanted ray from the same relative origin.
      const double a = ua(rng);
      const glm::dvec3 dir(std::cos(a), -0.4, std::sin(a));
      auto r0 = t0->raycast({x, 20.0, z}, dir, kInf);
      auto r1 = t1->raycast({s.ox + x, 20.0, s.oz + z}, dir, kInf);
      ASSERT_EQ(bool(r0), bool(r1));
      if (r0) {
        ASSERT_NEAR(r0->distance, r1->distance, 1e-4 * std::max(1.0, r0->distance));
        ASSERT_NEAR(r0->point.x + s.ox, r1->point.x, 1e-3);
        ASSERT_NEAR(r0->point.y, r1->point.y, 1e-3);
      }
    }
  }
}

TEST(PointQueries, SmoothNormalIsAreaWeightedVertexNormals) {
  // 3 x 2 samples, spacing 1, h(1,1) = 2 and h(2,0) = 1, all else 0. Vertex (1, 0) is a corner of
  // two triangles: A = (0,0)-(1,1)-(1,0) in cell (0,0) (main diagonal) and B = (1,0)-(1,1)-(2,0)
  // in cell (1,0) (anti diagonal). By hand:
  //   A: (1,2,1) x (1,0,0) = (0, 1, -2)      (|A| = sqrt 5, twice its area)
  //   B: (0,2,1) x (1,1,0) = (-1, 1, -2)     (|B| = sqrt 6)
  // Area-weighted: the sum (-1, 2, -4) / sqrt 21. (Equal weights would give a different vector.)
  FieldSpec s{3, 2};
  auto t = make_terrain(s, [](int i, int j) {
    return (i == 1 && j == 1) ? 2.0 : (i == 2 && j == 0) ? 1.0 : 0.0;
  });
  const glm::dvec3 expect = glm::dvec3(-1, 2, -4) / std::sqrt(21.0);
  EXPECT_TRUE(near_vec(*t->smooth_normal(1.0, 0.0), expect, 1e-6));
  const glm::dvec3 equal_weights = glm::normalize(glm::dvec3(0, 1, -2) / std::sqrt(5.0) +
                                                  glm::dvec3(-1, 1, -2) / std::sqrt(6.0));
  EXPECT_FALSE(near_vec(*t->smooth_normal(1.0, 0.0), equal_weights, 1e-3));
  // Vertex (0, 0): both triangles of cell (0, 0):
  //   A = (0, 1, -2); C = (0,0,0),(0,0,1),(1,2,1): (0,0,1) x (1,2,1) = (-2, 1, 0). Sum (-2, 2, -2).
  EXPECT_TRUE(near_vec(*t->smooth_normal(0.0, 0.0), glm::normalize(glm::dvec3(-1, 1, -1)), 1e-6));
  // Inside triangle A: blend the three vertex normals barycentrically and normalise.
  // Vertex (1,1): corner of C and A (cell 0,0) and of cell (1,0)'s triangles B and
  //   D = (2,0),(1,1),(2,1) at heights 1, 2, 0: (1,1,1) - (2,1,0) = (-1, 1, 1) and
  //   (2,0,1) - (2,1,0) = (0, -1, 1) -> (1*1 - 1*(-1), 1*0 - (-1)*1, (-1)(-1) - 1*0) = (2, 1, 1).
  //   Sum A + C + B + D = (0,1,-2) + (-2,1,0) + (-1,1,-2) + (2,1,1) = (-1, 4, -3).
  const glm::dvec3 n00 = glm::normalize(glm::dvec3(-1, 1, -1));
  const glm::dvec3 n11 = glm::normalize(glm::dvec3(-1, 4, -3));
  EXPECT_TRUE(near_vec(*t->smooth_normal(1.0, 1.0), n11, 1e-6));
  // (0.75, 0.25) in A: weights 1/4 on (0,0), 1/4 on (1,1), 1/2 on (1,0).
  const glm::dvec3 blend = glm::normalize(0.25 * n00 + 0.25 * n11 + 0.5 * expect);
  EXPECT_TRUE(near_vec(*t->smooth_normal(0.75, 0.25), blend, 1e-6));
  // And the face normal there is A's.
  EXPECT_TRUE(near_vec(*t->face_normal(0.75, 0.25), glm::normalize(glm::dvec3(0, 1, -2)), 1e-6));
}

TEST(PointQueries, BatchedEqualsSingle) {
  FieldSpec s{21, 17, 0.5, 1.5, -50.0, 30.0, 2.0};
  std::vector<std::uint8_t> mats(20 * 16);
  for (std::size_t k = 0; k < mats.size(); ++k) mats[k] = std::uint8_t(k % 5);
  auto t = make_terrain(s, rough, mats);
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> ux(-52.0, -38.0), uz(28.0, 56.0);
  std::vector<glm::dvec2> pts(3000);
  for (auto& p : pts) p = {ux(rng), uz(rng)};
  pts[0] = {kNaN, 30.0};
  pts[1] = {-50.0, kInf};
  pts[2] = {-40.0, 54.0};  // far corner
  std::vector<double> hs(pts.size());
  std::vector<SurfaceSample> ss(pts.size());
  std::vector<std::uint8_t> valid(pts.size());
  t->heights(pts, hs);
  t->samples(pts, ss, valid);
  int off = 0;
  for (std::size_t k = 0; k < pts.size(); ++k) {
    const auto h = t->height(pts[k].x, pts[k].y);
    const auto sm = t->sample(pts[k].x, pts[k].y);
    ASSERT_EQ(bool(h), !std::isnan(hs[k]));
    ASSERT_EQ(bool(sm), bool(valid[k]));
    off += !h;
    if (!h) continue;
    ASSERT_EQ(*h, hs[k]);
    ASSERT_EQ(sm->height, ss[k].height);
    ASSERT_EQ(sm->face_normal, ss[k].face_normal);
    ASSERT_EQ(sm->smooth_normal, ss[k].smooth_normal);
    ASSERT_EQ(sm->material, ss[k].material);
    ASSERT_EQ(sm->height, *h);
    ASSERT_EQ(sm->face_normal, *t->face_normal(pts[k].x, pts[k].y));
    ASSERT_EQ(sm->smooth_normal, *t->smooth_normal(pts[k].x, pts[k].y));
    const auto hn = *t->height_normal(pts[k].x, pts[k].y);
    ASSERT_EQ(hn.height, *h);
    ASSERT_EQ(hn.face_normal, sm->face_normal);
    ASSERT_EQ(hn.material, sm->material);
  }
  EXPECT_GT(off, 2);
  // Shorter outputs are not overrun.
  std::vector<double> small(2);
  t->heights(pts, small);
  EXPECT_EQ(small[0] != small[0], true);
}

TEST(PointQueries, MaterialsComeFromTheCellUnderThePoint) {
  FieldSpec s{4, 3};
  std::vector<std::uint8_t> mats{1, 2, 3, 4, 5, 6};  // per cell, 3 x 2 cells
  auto t = make_terrain(s, rough, mats);
  EXPECT_EQ(t->sample(0.5, 0.5)->material, 1);
  EXPECT_EQ(t->sample(2.5, 1.5)->material, 6);
  EXPECT_EQ(t->sample(3.0, 2.0)->material, 6);  // far corner: the last cell
  EXPECT_EQ(t->height_normal(1.5, 0.2)->material, 2);
  auto hit = t->raycast({2.5, 100, 1.5}, {0, -1, 0}, kInf);
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->material, 6);
}
