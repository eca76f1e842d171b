// Rays and box queries (module/src/surface/ray_queries.cpp): raycasts against an independent
// brute-force reference (10^5 random rays plus every special case), triangles in a box against
// brute force, the full-detail triangulation's topology, and both after edits (rays of every
// slant and boxes against brute force, the ray pyramid against a rebuild).
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

// ---- Raycasts ---------------------------------------------------------------------------------

namespace {

// Compares one ray with the reference. Returns false (with a message) on a disagreement that the
// rules do not allow: distances must agree within 1e-4 relative unless the surface raised and
// lowered by 1e-6 m gives different answers (the ray passes within 1e-6 m of the surface), in
// which case the answer must lie between those two.
struct RayCheck {
  int hits = 0, misses = 0, ambiguous = 0, started_below = 0;
};

::testing::AssertionResult check_ray(const Terrain& t, glm::dvec3 o, glm::dvec3 dir, double maxd,
                                     RayCheck& stats) {
  const Heightfield hf = t.surface().to_heightfield().value();
  const glm::dvec3 d = glm::normalize(dir);
  const glm::dvec3 lo = local_of(hf, o);
  const Reference exact{&hf, 0.0}, raised{&hf, 1e-6}, lowered{&hf, -1e-6};
  const double tr = exact.raycast(lo, d, maxd);
  const auto hit = t.raycast(o, dir, maxd);
  const double ti = hit ? hit->distance : kInf;
  auto same = [](double a, double b) {
    return (std::isinf(a) && std::isinf(b)) || std::abs(a - b) <= 1e-4 * std::max(1.0, b);
  };
  if (!same(ti, tr)) {
    const double t_hi = raised.raycast(lo, d, maxd), t_lo = lowered.raycast(lo, d, maxd);
    const double slack = 1e-4 * std::max(1.0, std::isinf(t_hi) ? 0.0 : t_hi);
    const bool between = ti >= t_hi - slack && (std::isinf(t_lo) || ti <= t_lo + slack);
    if (same(t_hi, t_lo) || !between)
      return ::testing::AssertionFailure()
             << "ray o=(" << o.x << "," << o.y << "," << o.z << ") d=(" << dir.x << "," << dir.y
             << "," << dir.z << ") max=" << maxd << ": got " << ti << ", reference " << tr
             << " (raised " << t_hi << ", lowered " << t_lo << ")";
    ++stats.ambiguous;
  }
  if (hit) {
    ++stats.hits;
    stats.started_below += hit->started_below;
    // The point is on the ray; started_below means distance 0 and the origin under the surface.
    const glm::dvec3 expect = o + d * hit->distance;
    if (glm::length(hit->point - expect) > 1e-6 * std::max(1.0, hit->distance))
      return ::testing::AssertionFailure() << "hit point off the ray";
    if (hit->started_below &&
        !(hit->distance == 0 && lo.y < exact.height(lo.x, lo.z) + 1e-6 && hit->point == o))
      return ::testing::AssertionFailure() << "started_below inconsistent";
    if (!hit->started_below && hit->distance == 0 && lo.y < exact.height(lo.x, lo.z) - 1e-6)
      return ::testing::AssertionFailure() << "origin below the surface not flagged";
    // The normal belongs to a triangle at the hit point.
    const glm::dvec3 lp = local_of(hf, hit->point);
    bool normal_ok = false;
    for (const glm::dvec3& n : exact.normals_at(lp.x, lp.z, 1e-6))
      normal_ok |= near_vec(hit->normal, n, 1e-5);
    if (!normal_ok) return ::testing::AssertionFailure() << "hit normal is not a face normal there";
  } else {
    ++stats.misses;
  }
  return ::testing::AssertionSuccess();
}

}  // namespace

TEST(Raycast, HundredThousandRandomRaysAgainstBruteForce) {
  FieldSpec s{65, 65, 1.0, 1.25, 1000.5, -300.25, 50.0};
  auto t = make_terrain(s, rough);
  const Heightfield hf = t->surface().to_heightfield().value();
  const double lo_y = s.offset + hf.min_local(), hi_y = s.offset + hf.max_local();
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  auto rand_dir = [&] {
    const double z = 2 * U(rng) - 1, a = 6.283185307179586 * U(rng), r = std::sqrt(1 - z * z);
    return glm::dvec3(r * std::cos(a), z, r * std::sin(a));
  };
  RayCheck stats;
  int failures = 0;
  for (int k = 0; k < 100000; ++k) {
    // Origins over and around the field, from below the lowest to above the highest sample.
    glm::dvec3 o(s.ox + (1.4 * U(rng) - 0.2) * hf.extent_x(),
                 lo_y - 3 + (hi_y - lo_y + 10) * U(rng),
                 s.oz + (1.4 * U(rng) - 0.2) * hf.extent_z());
    glm::dvec3 d = rand_dir();
    const int kind = k % 20;
    if (kind < 6) d.y = -std::abs(d.y);  // bias towards the ground
    if (kind == 6) d = {0, U(rng) < 0.5 ? -1 : 1, 0};
    if (kind == 7) d.x = 0;  // in a plane of constant x
    if (kind == 8) d.z = 0;
    if (kind == 9) o.x = s.ox + std::floor(U(rng) * 65) * s.sx, d.x = 0;  // along a cell edge
    if (kind == 10) o.z = s.oz + std::floor(U(rng) * 65) * s.sz, d.z = 0;
    if (kind == 11) {  // aimed at a lattice vertex
      const glm::dvec3 v(s.ox + std::floor(U(rng) * 65) * s.sx, 0,
                         s.oz + std::floor(U(rng) * 65) * s.sz);
      d = glm::dvec3(v.x, *t->height(v.x, v.z), v.z) - o;
    }
    if (kind == 12) d.y *= 0.02;                   // shallow, nearly grazing
    if (kind == 13 && !(std::abs(d.x) < 1e-12)) {  // along a diagonal direction of the lattice
      d.z = (U(rng) < 0.5 ? 1 : -1) * std::abs(d.x) * s.sz / s.sx;
    }
    const double maxd = k % 3 == 0 ? kInf : 0.1 + 100 * U(rng);
    if (glm::length(d) == 0) continue;
    auto r = check_ray(*t, o, d, maxd, stats);
    if (!r) {
      ADD_FAILURE() << r.message();
      if (++failures > 10) break;
    }
  }
  // A healthy mix, and ambiguous (within 1e-6 m) rays are rare.
  EXPECT_GT(stats.hits, 30000);
  EXPECT_GT(stats.misses, 10000);
  EXPECT_GT(stats.started_below, 1000);
  EXPECT_LT(stats.ambiguous, 100);
  std::printf("hits %d misses %d started below %d ambiguous %d\n", stats.hits, stats.misses,
              stats.started_below, stats.ambiguous);
}

TEST(Raycast, FieldsOfOtherShapesAgreeWithBruteForce) {
  // Sizes that are not block multiples, a single cell, long thin strips, non-square cells.
  const FieldSpec shapes[] = {{2, 2, 1, 1, 0, 0, 0},
                              {3, 9, 2.0, 0.5, 5, 5, 0},
                              {67, 13, 0.7, 1.3, 0, 0, 0},
                              {130, 5, 1, 1, -1e6, 1e6, 100},
                              {6, 70, 3, 1, 0, 0, -20}};
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  for (const FieldSpec& s : shapes) {
    auto t = make_terrain(s, rough);
    const Heightfield hf = t->surface().to_heightfield().value();
    RayCheck stats;
    for (int k = 0; k < 5000; ++k) {
      glm::dvec3 o(s.ox + (1.2 * U(rng) - 0.1) * hf.extent_x(), s.offset - 5 + 25 * U(rng),
                   s.oz + (1.2 * U(rng) - 0.1) * hf.extent_z());
      glm::dvec3 d(2 * U(rng) - 1, -U(rng), 2 * U(rng) - 1);
      ASSERT_TRUE(check_ray(*t, o, d, k % 2 ? kInf : 30 * U(rng), stats)) << s.w << "x" << s.h;
    }
    EXPECT_GT(stats.hits, 100);
  }
}

TEST(Raycast, StartingBelowOrOnTheSurface) {
  FieldSpec s{9, 9};
  auto t = make_terrain(s, rough);
  const double h = *t->height(3.3, 4.6);
  for (glm::dvec3 dir : {glm::dvec3(0, -1, 0), glm::dvec3(0, 1, 0), glm::dvec3(1, 0.5, -0.3)}) {
    auto hit = t->raycast({3.3, h - 0.5, 4.6}, dir, 10.0);
    ASSERT_TRUE(hit);
    EXPECT_EQ(hit->distance, 0.0);
    EXPECT_TRUE(hit->started_below);
    EXPECT_EQ(hit->point, glm::dvec3(3.3, h - 0.5, 4.6));
    EXPECT_EQ(hit->normal, *t->face_normal(3.3, 4.6));
  }
  // Exactly on the surface (a vertex with an exact height): touching, distance 0, not below.
  const double hv = *t->height(4.0, 4.0);
  auto on = t->raycast({4.0, hv, 4.0}, {0.3, 1, 0.1}, 10.0);
  ASSERT_TRUE(on);
  EXPECT_EQ(on->distance, 0.0);
  EXPECT_FALSE(on->started_below);
}

TEST(Raycast, VerticalRaysHitAtTheHeightBelow) {
  FieldSpec s{9, 9, 2.0, 1.0, -7.0, 3.0, 10.0};
  auto t = make_terrain(s, rough);
  const double x = -7.0 + 5.3, z = 3.0 + 2.9, h = *t->height(x, z);
  auto down = t->raycast({x, h + 7.0, z}, {0, -3, 0}, kInf);
  ASSERT_TRUE(down);
  EXPECT_NEAR(down->distance, 7.0, 1e-5);
  EXPECT_NEAR(down->point.y, h, 1e-5);
  EXPECT_EQ(down->point.x, x);
  EXPECT_EQ(down->normal, *t->face_normal(x, z));
  EXPECT_FALSE(t->raycast({x, h + 7.0, z}, {0, 1, 0}, kInf));   // up from above
  EXPECT_FALSE(t->raycast({x, h + 7.0, z}, {0, -1, 0}, 6.99));  // too short
  EXPECT_TRUE(t->raycast({x, h + 7.0, z}, {0, -1, 0}, 7.01));
  // At a vertex with an exact height: max_distance exactly the gap touches.
  const double hv = *t->height(-7.0 + 4.0, 3.0 + 5.0);
  auto exact = t->raycast({-3.0, hv + 4.0, 8.0}, {0, -1, 0}, 4.0);
  ASSERT_TRUE(exact);
  EXPECT_EQ(exact->distance, 4.0);
  // Off the footprint: nothing, even pointing down.
  EXPECT_FALSE(t->raycast({-7.5, 100.0, 5.0}, {0, -1, 0}, kInf));
  EXPECT_FALSE(t->raycast({-7.0 + 16.0 + 1e-9, 100.0, 5.0}, {0, -1, 0}, kInf));
  // On the far edge: a hit.
  EXPECT_TRUE(t->raycast({-7.0 + 16.0, 100.0, 3.0 + 8.0}, {0, -1, 0}, kInf));
  // Tiny or huge direction components are normalised without trouble.
  auto tiny = t->raycast({x, h + 7.0, z}, {0, -1e-300, 0}, kInf);
  ASSERT_TRUE(tiny);
  EXPECT_NEAR(tiny->distance, 7.0, 1e-5);
  auto huge = t->raycast({x, h + 7.0, z}, {1e-320, -1e300, 0}, kInf);
  ASSERT_TRUE(huge);
  EXPECT_NEAR(huge->distance, 7.0, 1e-5);
}

TEST(Raycast, AlongCellEdgesAndBlockBoundaries) {
  // A ridge of height 5 along column `c` (all else 0): a ray in the vertical plane x = c descends
  // onto the ridge line, which is a lattice edge (and for c = 8 a boundary of the 4 x 4 blocks
  // the hierarchy is built from).
  for (int c : {5, 8, 0, 16}) {
    FieldSpec s{17, 17};
    auto t = make_terrain(s, [&](int i, int) { return i == c ? 5.0 : 0.0; });
    for (double sign : {1.0, -1.0}) {
      const double z0 = sign > 0 ? 0.5 : 15.5;
      auto hit = t->raycast({double(c), 9.0, z0}, {0, -1, sign * 2}, kInf);
      ASSERT_TRUE(hit) << c;
      // y drops 4 m at 1 m per 2 m along z: hit at z0 + 8 sign, distance 4 * sqrt(5).
      EXPECT_NEAR(hit->distance, 4 * std::sqrt(5.0), 1e-9) << c;
      EXPECT_NEAR(hit->point.z, z0 + 8 * sign, 1e-9);
      EXPECT_EQ(hit->point.x, double(c));
    }
    // The same along a row (z = c).
    auto tz = make_terrain(s, [&](int, int j) { return j == c ? 5.0 : 0.0; });
    auto hz = tz->raycast({0.5, 9.0, double(c)}, {2, -1, 0}, kInf);
    ASSERT_TRUE(hz);
    EXPECT_NEAR(hz->distance, 4 * std::sqrt(5.0), 1e-9);
    // Horizontal along the ridge line, just above it: a miss; exactly at it: touches at once.
    EXPECT_FALSE(t->raycast({double(c), 5.0 + 1e-6, -1.0}, {0, 0, 1}, kInf));
    auto touch = t->raycast({double(c), 5.0, -1.0}, {0, 0, 1}, kInf);
    ASSERT_TRUE(touch);
    EXPECT_NEAR(touch->distance, 1.0, 1e-12);  // where the ray enters the footprint
    EXPECT_FALSE(touch->started_below);
  }
}

TEST(Raycast, AlongDiagonals) {
  // Main diagonals: cells (k, k) have i + j even, so the line x = z runs along their diagonals.
  FieldSpec s{17, 17};
  auto t = make_terrain(s, [](int i, int j) { return i == j ? 5.0 : 0.0; });
  auto hit = t->raycast({0.5, 15.5, 0.5}, {1, -1, 1}, kInf);
  ASSERT_TRUE(hit);
  // y falls from 15.5 to 5 while x and z move 10.5 each (through lattice vertices (k, k)).
  EXPECT_NEAR(hit->distance, 10.5 * std::sqrt(3.0), 1e-9);
  EXPECT_NEAR(hit->point.x, hit->point.z, 1e-9);
  // Anti diagonals: cells with i + j = 7 (odd) are split along x + z = 8.
  auto ta = make_terrain(s, [](int i, int j) { return i + j == 8 ? 5.0 : 0.0; });
  auto ha = ta->raycast({0.5, 12.0, 7.5}, {1, -1, -1}, kInf);
  ASSERT_TRUE(ha);
  EXPECT_NEAR(ha->distance, 7.0 * std::sqrt(3.0), 1e-9);
  EXPECT_NEAR(ha->point.x + ha->point.z, 8.0, 1e-9);
  // A horizontal ray exactly along the ridge line touches at once (on the footprint).
  auto along = t->raycast({2.0, 5.0, 2.0}, {1, 0, 1}, kInf);
  ASSERT_TRUE(along);
  EXPECT_EQ(along->distance, 0.0);
  // Just above it: nothing.
  EXPECT_FALSE(t->raycast({2.0, 5.0 + 1e-6, 2.0}, {1, 0, 1}, kInf));
}

TEST(Raycast, ThroughVerticesAndGrazing) {
  // A spike of height 10 at vertex (8, 8) on a flat field at 0.
  FieldSpec s{17, 17};
  auto t = make_terrain(s, [](int i, int j) { return (i == 8 && j == 8) ? 10.0 : 0.0; });
  // Aimed exactly at the tip from above, along a lattice diagonal direction.
  auto tip = t->raycast({4.0, 14.0, 4.0}, {1, -1, 1}, kInf);
  ASSERT_TRUE(tip);
  EXPECT_NEAR(tip->point.x, 8.0, 1e-6);
  EXPECT_NEAR(tip->point.y, 10.0, 1e-6);
  // Horizontal through the tip, along the lattice line z = 8: grazes the tip only.
  auto graze = t->raycast({1.0, 10.0, 8.0}, {1, 0, 0}, kInf);
  ASSERT_TRUE(graze);
  EXPECT_NEAR(graze->distance, 7.0, 1e-9);
  EXPECT_FALSE(t->raycast({1.0, 10.0 + 1e-6, 8.0}, {1, 0, 0}, kInf));
  // Horizontal through the tip along a diagonal direction, and across cells at an odd angle.
  auto graze_diag = t->raycast({2.0, 10.0, 2.0}, {1, 0, 1}, kInf);
  ASSERT_TRUE(graze_diag);
  EXPECT_NEAR(graze_diag->distance, 6 * std::sqrt(2.0), 1e-9);
  auto graze_odd = t->raycast({2.0, 10.0, 5.0}, {2, 0, 1}, kInf);
  ASSERT_TRUE(graze_odd);
  EXPECT_NEAR(graze_odd->point.x, 8.0, 1e-6);
  // Grazing a ridge crosswise: a ridge of height 3 along column 5 (a lattice edge).
  auto ridge = make_terrain(s, [](int i, int) { return i == 5 ? 3.0 : 0.0; });
  auto cross = ridge->raycast({0.5, 3.0, 2.3}, {1, 0, 0.1}, kInf);
  ASSERT_TRUE(cross);
  EXPECT_NEAR(cross->point.x, 5.0, 1e-9);
  EXPECT_FALSE(ridge->raycast({0.5, 3.0 + 1e-6, 2.3}, {1, 0, 0.1}, kInf));
  // Running along a flat field at its exact height, entering from outside: touches at entry.
  auto flat = make_terrain(s, [](int, int) { return 2.0; });
  auto run = flat->raycast({-3.0, 2.0, 4.5}, {1, 0, 0.2}, kInf);
  ASSERT_TRUE(run);
  EXPECT_NEAR(run->point.x, 0.0, 1e-12);
}

TEST(Raycast, LeavingAndEnteringTheTerrain) {
  FieldSpec s{9, 9};
  auto t = make_terrain(s, [](int, int) { return 1.0; });
  // Starts over the field, leaves it before coming down: no hit beyond the edge.
  EXPECT_FALSE(t->raycast({7.0, 3.0, 4.0}, {1, -0.1, 0}, kInf));
  // Starts outside, enters, hits.
  auto in = t->raycast({-2.0, 3.0, 4.0}, {1, -0.5, 0}, kInf);
  ASSERT_TRUE(in);
  EXPECT_NEAR(in->point.x, 2.0, 1e-9);
  // Starts outside below the surface level and enters: hits the solid's side at the entry point.
  auto side = t->raycast({-2.0, 0.0, 4.0}, {1, 0, 0}, kInf);
  ASSERT_TRUE(side);
  EXPECT_NEAR(side->distance, 2.0, 1e-12);
  EXPECT_FALSE(side->started_below);
  // Outside going away, or passing beside the field: nothing.
  EXPECT_FALSE(t->raycast({-2.0, 0.0, 4.0}, {-1, 0, 0}, kInf));
  EXPECT_FALSE(t->raycast({-2.0, 0.0, 4.0}, {0, -1, 1}, kInf));
  EXPECT_FALSE(t->raycast({-2.0, 0.0, -1.0}, {1, 0, 0}, kInf));
  // Ends just before reaching the surface: nothing; just after: a hit.
  EXPECT_FALSE(t->raycast({4.0, 3.0, 4.0}, {0, -1, 0}, 1.999));
  EXPECT_TRUE(t->raycast({4.0, 3.0, 4.0}, {0, -1, 0}, 2.001));
}

TEST(Raycast, BadInputIsNoHit) {
  FieldSpec s{9, 9};
  auto t = make_terrain(s, rough);
  const glm::dvec3 o(4, 50, 4), d(0.01, -1, 0.02);
  EXPECT_TRUE(t->raycast(o, d, kInf));
  EXPECT_FALSE(t->raycast(o, {0, 0, 0}, kInf));
  EXPECT_FALSE(t->raycast(o, {-0.0, 0.0, -0.0}, kInf));
  EXPECT_FALSE(t->raycast(o, d, 0.0));
  EXPECT_FALSE(t->raycast(o, d, -1.0));
  EXPECT_FALSE(t->raycast(o, d, kNaN));
  EXPECT_FALSE(t->raycast(o, d, -kInf));
  for (int a = 0; a < 3; ++a) {
    for (double bad : {kNaN, kInf, -kInf}) {
      glm::dvec3 ob = o, db = d;
      ob[a] = bad;
      db[a] = bad;
      EXPECT_FALSE(t->raycast(ob, d, kInf));
      EXPECT_FALSE(t->raycast(o, db, kInf));
    }
  }
  // Started below, but with bad input: still nothing.
  EXPECT_FALSE(t->raycast({4, -50, 4}, {0, 0, 0}, kInf));
  EXPECT_FALSE(t->raycast({4, -50, 4}, {0, 1, 0}, kNaN));
}

TEST(Raycast, ConcurrentQueriesAgree) {
  FieldSpec s{65, 65};
  auto t = make_terrain(s, rough);
  std::vector<glm::dvec3> origins, dirs;
  std::mt19937 rng(10);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  for (int k = 0; k < 4000; ++k) {
    origins.push_back({64 * U(rng), 20 * U(rng), 64 * U(rng)});
    dirs.push_back({U(rng) - 0.5, -U(rng), U(rng) - 0.5});
  }
  std::vector<double> serial(origins.size()), a(origins.size()), b(origins.size());
  auto run = [&](std::vector<double>& out) {
    for (std::size_t k = 0; k < origins.size(); ++k) {
      auto h = t->raycast(origins[k], dirs[k], kInf);
      out[k] = (h ? h->distance : -1) + *t->height(origins[k].x, origins[k].z);
    }
  };
  run(serial);
  std::thread ta([&] { run(a); }), tb([&] { run(b); });
  ta.join();
  tb.join();
  EXPECT_EQ(serial, a);
  EXPECT_EQ(serial, b);
}

// ---- Triangles in a box -----------------------------------------------------------------------

namespace {

using TriKey = std::array<double, 9>;

TriKey key_of(const SurfaceTriangle& t) {
  return {t.v[0].x, t.v[0].y, t.v[0].z, t.v[1].x, t.v[1].y, t.v[1].z, t.v[2].x, t.v[2].y, t.v[2].z};
}

// Rotates a triangle so that its smallest corner comes first (the winding is kept).
TriKey canonical(TriKey k) {
  auto corner = [&](int c) { return std::make_tuple(k[3 * c], k[3 * c + 1], k[3 * c + 2]); };
  int first = 0;
  for (int c = 1; c < 3; ++c)
    if (corner(c) < corner(first)) first = c;
  TriKey out;
  for (int c = 0; c < 3; ++c)
    for (int a = 0; a < 3; ++a) out[3 * c + a] = k[3 * ((first + c) % 3) + a];
  return out;
}

// Closed 2D overlap of a triangle and a rectangle by brute force: a vertex of one inside the
// other, or crossing edges.
bool tri_rect_overlap(const glm::dvec2 p[3], glm::dvec2 lo, glm::dvec2 hi) {
  auto in_rect = [&](glm::dvec2 q) {
    return q.x >= lo.x && q.x <= hi.x && q.y >= lo.y && q.y <= hi.y;
  };
  auto cross2 = [](glm::dvec2 a, glm::dvec2 b) { return a.x * b.y - a.y * b.x; };
  auto in_tri = [&](glm::dvec2 q) {
    double s[3];
    for (int e = 0; e < 3; ++e) s[e] = cross2(p[(e + 1) % 3] - p[e], q - p[e]);
    return (s[0] >= 0 && s[1] >= 0 && s[2] >= 0) || (s[0] <= 0 && s[1] <= 0 && s[2] <= 0);
  };
  auto seg_cross = [&](glm::dvec2 a, glm::dvec2 b, glm::dvec2 c, glm::dvec2 d) {
    const double d1 = cross2(b - a, c - a), d2 = cross2(b - a, d - a);
    const double d3 = cross2(d - c, a - c), d4 = cross2(d - c, b - c);
    return ((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0));
  };
  for (int k = 0; k < 3; ++k)
    if (in_rect(p[k])) return true;
  const glm::dvec2 r[4] = {lo, {hi.x, lo.y}, hi, {lo.x, hi.y}};
  for (const auto& q : r)
    if (in_tri(q)) return true;
  for (int e = 0; e < 3; ++e)
    for (int f = 0; f < 4; ++f)
      if (seg_cross(p[e], p[(e + 1) % 3], r[f], r[(f + 1) % 4])) return true;
  return false;
}

}  // namespace

namespace {

// triangles_in_box(b) on `t` returns exactly the triangles that overlap b by brute force over every
// triangle of the stored lattice (the independent reference), wound counter-clockwise from above,
// with their cell's material.
::testing::AssertionResult box_matches_brute_force(const Terrain& t, const Box& b) {
  const Heightfield hf = t.surface().to_heightfield().value();
  const Reference ref{&hf, 0.0};
  std::vector<SurfaceTriangle> got;
  const std::size_t n = t.triangles_in_box(b, got);
  if (n != got.size()) return ::testing::AssertionFailure() << "count " << n << " != appended";
  std::multiset<TriKey> got_keys, want_keys;
  for (SurfaceTriangle tri : got) {
    for (auto& v : tri.v) v = local_of(hf, v);
    const glm::dvec3 c = glm::cross(tri.v[1] - tri.v[0], tri.v[2] - tri.v[0]);
    if (!(c.y > 0)) return ::testing::AssertionFailure() << "clockwise triangle";
    const double cx = (tri.v[0].x + tri.v[1].x + tri.v[2].x) / 3 / hf.spacing_x();
    const double cz = (tri.v[0].z + tri.v[1].z + tri.v[2].z) / 3 / hf.spacing_z();
    if (tri.material != hf.material(std::uint32_t(cx), std::uint32_t(cz)))
      return ::testing::AssertionFailure() << "material of another cell";
    got_keys.insert(canonical(key_of(tri)));
  }
  const Box lb{local_of(hf, b.min), local_of(hf, b.max)};
  for (int j = 0; j + 1 < int(hf.height()); ++j)
    for (int i = 0; i + 1 < int(hf.width()); ++i)
      for (int w = 0; w < 2; ++w) {
        RefTri r = ref.tri(i, j, w);
        const glm::dvec2 p[3] = {{r.p[0].x, r.p[0].z}, {r.p[1].x, r.p[1].z}, {r.p[2].x, r.p[2].z}};
        const double ylo = std::min({r.p[0].y, r.p[1].y, r.p[2].y});
        const double yhi = std::max({r.p[0].y, r.p[1].y, r.p[2].y});
        if (yhi < lb.min.y || ylo > lb.max.y) continue;
        if (!tri_rect_overlap(p, {lb.min.x, lb.min.z}, {lb.max.x, lb.max.z})) continue;
        // Wind it counter-clockwise about +y like the module does.
        if (glm::cross(r.p[1] - r.p[0], r.p[2] - r.p[0]).y < 0) std::swap(r.p[1], r.p[2]);
        SurfaceTriangle st;
        for (int c = 0; c < 3; ++c) st.v[c] = r.p[c];
        want_keys.insert(canonical(key_of(st)));
      }
  if (got_keys != want_keys)
    return ::testing::AssertionFailure()
           << got_keys.size() << " triangles, brute force finds " << want_keys.size();
  return ::testing::AssertionSuccess();
}

}  // namespace

TEST(TrianglesInBox, MatchesBruteForce) {
  FieldSpec s{23, 19, 1.0, 1.0, 0.0, 0.0, 0.0};
  std::vector<std::uint8_t> mats(22 * 18);
  for (std::size_t k = 0; k < mats.size(); ++k) mats[k] = std::uint8_t(k * 7 % 11);
  auto t = make_terrain(s, rough, mats);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  for (int k = 0; k < 3000; ++k) {
    Box b;
    double x0 = -3 + 28 * U(rng), z0 = -3 + 24 * U(rng);
    double wx = 6 * U(rng) * U(rng), wz = 6 * U(rng) * U(rng);
    if (k % 4 == 0)
      x0 = std::round(x0), z0 = std::round(z0), wx = std::round(wx), wz = std::round(wz);
    if (k % 7 == 0) wx = 0;  // degenerate (a plane)
    const double y0 = -6 + 18 * U(rng), wy = 8 * U(rng) * U(rng);
    b.min = {x0, y0, z0};
    b.max = {x0 + wx, y0 + wy, z0 + wz};
    ASSERT_TRUE(box_matches_brute_force(*t, b)) << "box " << k;
  }
}

TEST(TrianglesInBox, CapsBadBoxesAndPlacementHaveDefinedAnswers) {
  FieldSpec s{9, 9, 2.0, 0.5, 1e7, -1e7, 300.0};
  auto t = make_terrain(s, rough);
  std::vector<SurfaceTriangle> out;
  Box all{{1e7 - 1, -1e6, -1e7 - 1}, {1e7 + 100, 1e6, -1e7 + 100}};
  EXPECT_EQ(t->triangles_in_box(all, out), 2u * 8 * 8);
  // World coordinates: corners at the lattice positions, heights with the offset.
  for (const auto& tri : out)
    for (const auto& v : tri.v) {
      const double u = (v.x - 1e7) / 2.0, w = (v.z + 1e7) / 0.5;
      ASSERT_EQ(u, std::round(u));
      ASSERT_EQ(w, std::round(w));
      ASSERT_EQ(v.y, t->info().height_offset + double(t->surface().stored_height(std::int64_t(u), std::int64_t(w))));
    }
  out.clear();
  EXPECT_EQ(t->triangles_in_box(all, out, 5), 5u);
  EXPECT_EQ(out.size(), 5u);
  const Box bad[] = {{{kNaN, 0, 0}, {1, 1, 1}},
                     {{1e7, 0, -1e7}, {1e7 + 1, kInf, -1e7 + 1}},
                     {{1e7 + 5, -1e6, -1e7}, {1e7 + 4, 1e6, -1e7 + 1}},  // min > max
                     {{0, -1e6, 0}, {10, 1e6, 10}},                      // off terrain
                     {{1e7, 1e5, -1e7}, {1e7 + 10, 1e6, -1e7 + 4}}};     // above everything
  for (const Box& b : bad) {
    out.clear();
    EXPECT_EQ(t->triangles_in_box(b, out), 0u);
    EXPECT_TRUE(out.empty());
  }
}

// ---- The full-detail triangulation -------------------------------------------------------------

TEST(Triangulation, ClosedManifoldAgreeingWithHeight) {
  FieldSpec s{31, 26, 0.8, 1.7, 12.0, -5.0, 40.0};
  auto t = make_terrain(s, rough);
  const Heightfield hf = t->surface().to_heightfield().value();
  // Every cell, both triangles, located through locate_in_cell.
  struct Tri {
    int vi[3], vj[3];
  };
  std::vector<Tri> tris;
  for (int j = 0; j + 1 < 26; ++j)
    for (int i = 0; i + 1 < 31; ++i) {
      std::set<int> seen;
      for (float fu : {0.2f, 0.8f})
        for (float fv : {0.2f, 0.8f}) {
          const CellTriangle c = locate_in_cell(i, j, fu, fv);
          if (!seen.insert(c.which).second) continue;
          Tri tr;
          for (int k = 0; k < 3; ++k) tr.vi[k] = i + c.di[k], tr.vj[k] = j + c.dj[k];
          tris.push_back(tr);
        }
      ASSERT_EQ(seen.size(), 2u);
    }
  ASSERT_EQ(tris.size(), 2u * 30 * 25);
  // Edges: interior ones shared by exactly two triangles (with opposite directions, as a
  // consistently wound manifold has), boundary ones by one.
  std::map<std::pair<int, int>, int> directed;
  auto id = [](int i, int j) { return i + j * 1000; };
  for (const Tri& tr : tris)
    for (int k = 0; k < 3; ++k)
      ++directed[{id(tr.vi[k], tr.vj[k]), id(tr.vi[(k + 1) % 3], tr.vj[(k + 1) % 3])}];
  int boundary = 0;
  std::set<std::pair<int, int>> undirected;
  for (const auto& [e, n] : directed) {
    ASSERT_EQ(n, 1);  // no edge used twice in the same direction
    undirected.insert({std::min(e.first, e.second), std::max(e.first, e.second)});
  }
  for (const auto& e : undirected) {
    const int uses = directed.count({e.first, e.second}) + directed.count({e.second, e.first});
    const int ai = e.first % 1000, aj = e.first / 1000, bi = e.second % 1000, bj = e.second / 1000;
    const bool on_border =
        (ai == bi && (ai == 0 || ai == 30)) || (aj == bj && (aj == 0 || aj == 25));
    ASSERT_EQ(uses, on_border ? 1 : 2);
    boundary += on_border;
  }
  EXPECT_EQ(boundary, 2 * (30 + 25));
  // Height at random points equals the plane of the triangle holding the point (found by
  // brute force over all triangles), to float precision.
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  for (int k = 0; k < 5000; ++k) {
    const double u = U(rng) * 30, v = U(rng) * 25;
    bool found = false;
    for (const Tri& tr : tris) {
      // Barycentric coordinates in the lattice plane.
      const double x0 = tr.vi[0], z0 = tr.vj[0];
      const double ax = tr.vi[1] - x0, az = tr.vj[1] - z0, bx = tr.vi[2] - x0, bz = tr.vj[2] - z0;
      const double det = ax * bz - az * bx;
      const double l1 = ((u - x0) * bz - (v - z0) * bx) / det;
      const double l2 = (ax * (v - z0) - az * (u - x0)) / det;
      const double l0 = 1 - l1 - l2;
      if (l0 < -1e-12 || l1 < -1e-12 || l2 < -1e-12) continue;
      const double h = l0 * hf.local(tr.vi[0], tr.vj[0]) + l1 * hf.local(tr.vi[1], tr.vj[1]) +
                       l2 * hf.local(tr.vi[2], tr.vj[2]);
      ASSERT_NEAR(*t->height(s.ox + u * s.sx, s.oz + v * s.sz) - s.offset, h,
                  1e-6 * (1 + std::abs(h)));
      found = true;
      break;
    }
    ASSERT_TRUE(found);
  }
  // The mesh that triangles_in_box hands to physics is exactly this triangulation.
  std::vector<SurfaceTriangle> all;
  t->triangles_in_box({{-1e9, -1e9, -1e9}, {1e9, 1e9, 1e9}}, all);
  std::set<TriKey> a, b;
  for (const auto& st : all) a.insert(canonical(key_of(st)));
  for (const Tri& tr : tris) {
    SurfaceTriangle st;
    for (int k = 0; k < 3; ++k)
      st.v[k] = {s.ox + tr.vi[k] * s.sx, hf.world(tr.vi[k], tr.vj[k]), s.oz + tr.vj[k] * s.sz};
    b.insert(canonical(key_of(st)));
  }
  EXPECT_EQ(a, b);
}

// ---- Every query sees every edit ---------------------------------------------------------------

namespace {

// The first distance along a ray (unit `d`) at which it is at or below the surface, found by
// marching `step` metres and bisecting: an independent check for surfaces the brute-force
// reference does not model (procedural detail). +inf when none within `max_distance`.
double march(const Terrain& t, glm::dvec3 o, glm::dvec3 d, double max_distance, double step) {
  auto below = [&](double s) {
    const glm::dvec3 p = o + d * s;
    const auto h = t.height(p.x, p.z);
    return h && p.y <= *h;
  };
  for (double s = 0; s <= max_distance; s += step) {
    if (!below(s)) continue;
    double a = std::max(0.0, s - step), b = s;
    for (int k = 0; k < 60; ++k) (below(0.5 * (a + b)) ? b : a) = 0.5 * (a + b);
    return b;
  }
  return kInf;
}

}  // namespace

TEST(QueriesAfterEdits, AHorizontalRayAtHalfTheHeightOfAFreshBumpHitsIt) {
  auto t = make_editable_terrain({129, 129, 1.0, 1.0, 0.0, 0.0, 0.0}, [](int, int) { return 0.0; });
  ASSERT_TRUE(t->apply_edit({.brush = Brush::kRaise, .x = 64, .z = 64, .radius = 10, .depth = 5}));
  ASSERT_NEAR(*t->height(64, 64), 5.0, 1e-6);
  // Where the bump is 2.5 m high: 5 (1 - r^2)^2 = 2.5 at r = 5.41 m (to within the lattice's
  // linear interpolation).
  const double r_half = 10 * std::sqrt(1 - std::sqrt(0.5));
  RayCheck stats;
  for (int k = 0; k < 16; ++k) {
    const double a = k * M_PI / 8 + 0.01 * k;
    const glm::dvec3 d(std::cos(a), 0, std::sin(a));
    const glm::dvec3 o = glm::dvec3(64, 2.5, 64) - 60.0 * d;
    auto hit = t->raycast(o, d, kInf);
    ASSERT_TRUE(hit) << "horizontal ray at angle " << a << " misses the bump";
    EXPECT_NEAR(hit->point.y, 2.5, 1e-9);
    EXPECT_NEAR(glm::length(glm::dvec2(hit->point.x - 64, hit->point.z - 64)), r_half, 0.3);
    EXPECT_TRUE(check_ray(*t, o, d, kInf, stats));
    // Slanted through the bump's flank, down and up.
    for (double dy : {-0.05, 0.04}) {
      const glm::dvec3 ds = glm::normalize(glm::dvec3(d.x, dy, d.z));
      EXPECT_TRUE(check_ray(*t, o, ds, kInf, stats));
      EXPECT_TRUE(check_ray(*t, o, ds, 45.0, stats));
    }
  }
  EXPECT_GE(stats.hits, 16 * 3);
  // The same over procedural detail (2 levels): the bump still stops the ray, where the
  // finest surface first reaches it.
  HeightfieldDesc desc;
  desc.width = desc.height = 65;
  desc.spacing_x = desc.spacing_z = 2.0;
  std::vector<float> zeros(65 * 65, 0.0f);
  DetailParams dp;
  dp.levels = 2;
  dp.amplitude = 0.3;
  DetailCacheDesc cache;
  cache.worker_threads = 0;
  cache.budget_bytes = std::size_t{16} << 20;
  auto fine =
      Terrain::create(std::move(Heightfield::create(desc, zeros)).value(), dp, cache).value();
  ASSERT_TRUE(
      fine->apply_edit({.brush = Brush::kRaise, .x = 64, .z = 64, .radius = 20, .depth = 5}));
  for (int k = 0; k < 8; ++k) {
    const double a = k * M_PI / 4 + 0.1;
    const glm::dvec3 d(std::cos(a), 0, std::sin(a));
    const glm::dvec3 o = glm::dvec3(64, 2.5, 64) - 60.0 * d;
    auto hit = fine->raycast(o, d, kInf);
    ASSERT_TRUE(hit) << "horizontal ray over detail at angle " << a << " misses the bump";
    EXPECT_NEAR(hit->distance, march(*fine, o, d, 120, 0.05), 1e-6);
  }
}

TEST(QueriesAfterEdits, RaysOfEverySlantAndBoxesMatchBruteForceAndThePyramidARebuild) {
  const FieldSpec s{97, 81, 1.0, 1.25, 10.0, -20.0, 5.0};
  auto t = make_editable_terrain(s, rough);
  const Heightfield hf = t->surface().to_heightfield().value();
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const Brush brushes[] = {Brush::kCrater, Brush::kRaise, Brush::kLower, Brush::kFlatten,
                           Brush::kSmooth};
  RayCheck stats;
  int failures = 0;
  for (int k = 0; k < 60; ++k) {
    // Centres over the whole field and past its edges, craters and mounds.
    Edit e{.brush = brushes[k % 5],
           .x = s.ox - 5 + (hf.extent_x() + 10) * U(rng),
           .z = s.oz - 5 + (hf.extent_z() + 10) * U(rng),
           .radius = 2 + 10 * U(rng),
           .depth = -4 + 10 * U(rng),
           .height = s.offset + 12 * U(rng)};
    auto r = t->apply_edit(e);
    ASSERT_TRUE(r) << r.error().message;
    if (r->empty()) continue;
    ASSERT_EQ(t->check_invariants(), "") << "after edit " << k;
    const Box& b = r->changed;
    for (int q = 0; q < 60; ++q) {
      // Aimed at a point of the edited region from around it: horizontal, shallow, steep.
      const glm::dvec3 target(b.min.x + (b.max.x - b.min.x) * U(rng),
                              b.min.y + (b.max.y - b.min.y) * U(rng),
                              b.min.z + (b.max.z - b.min.z) * U(rng));
      const double a = 2 * M_PI * U(rng), dist = 5 + 40 * U(rng);
      const double slant = q % 3 == 0 ? 0.0 : (q % 3 == 1 ? 0.1 : 1.0) * (U(rng) - 0.3);
      const glm::dvec3 o = target - dist * glm::dvec3(std::cos(a), slant, std::sin(a));
      const glm::dvec3 d = target - o;
      auto c = check_ray(*t, o, d, q % 2 ? kInf : 1.5 * dist, stats);
      if (!c) {
        ADD_FAILURE() << "after edit " << k << ": " << c.message();
        if (++failures > 10) return;
      }
    }
    for (int q = 0; q < 10; ++q) {
      // Boxes over the edited region, thin in y (what a mid-phase asks for around a body).
      Box box;
      const double x = b.min.x + (b.max.x - b.min.x) * U(rng),
                   z = b.min.z + (b.max.z - b.min.z) * U(rng);
      const double y = b.min.y + (b.max.y - b.min.y) * U(rng);
      box.min = {x - 3 * U(rng), y - U(rng), z - 3 * U(rng)};
      box.max = {x + 3 * U(rng), y + U(rng), z + 3 * U(rng)};
      ASSERT_TRUE(box_matches_brute_force(*t, box)) << "after edit " << k << ", box " << q;
    }
  }
  EXPECT_GT(stats.hits, 1000);
  EXPECT_LT(stats.ambiguous, 50);
}
