// The landscapes, camera checks and reference bounds the ROAM tests share (tests/unit/roam/).
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <glm/geometric.hpp>
#include <memory>
#include <vector>

#include "ridgeline/roam_view.h"
#include "roam_test_util.h"

namespace ridgeline::test {

// The default test terrain (`size` x `size` samples 2 m apart), in patches of 2^k cells,
// optionally moved far from the origin.
inline std::shared_ptr<const Landscape> make_landscape(std::uint32_t size, std::uint32_t k = 5,
                                                       double origin = 0.0,
                                                       std::uint32_t seed = 1337) {
  auto hf = make_default_heightfield({.size = size, .spacing = 2.0, .seed = seed});
  EXPECT_TRUE(hf);
  if (origin != 0.0) {
    // Same heights, moved far away.
    HeightfieldDesc d;
    d.width = hf->width();
    d.height = hf->height();
    d.spacing_x = d.spacing_z = 2.0;
    d.origin_x = origin;
    d.origin_z = -origin;
    std::vector<float> v(hf->local_heights().begin(), hf->local_heights().end());
    hf = Heightfield::create(d, v);
  }
  auto terrain = Terrain::create(std::move(hf).value()).value();
  auto l = Landscape::create(terrain, {.patch_exponent = k});
  EXPECT_TRUE(l) << (l ? "" : l.error().message);
  return l.value();
}

// A field whose size is not 2^k + 1, nor square (83 x 57 samples, 2 m apart): its last patches
// extend past the samples.
inline constexpr std::uint32_t kPaddedW = 83, kPaddedH = 57;
inline std::shared_ptr<const Landscape> make_padded_landscape(std::uint32_t k) {
  HeightfieldDesc d;
  d.width = kPaddedW;
  d.height = kPaddedH;
  d.spacing_x = d.spacing_z = 2.0;
  std::vector<float> h(std::size_t(d.width) * d.height);
  for (std::uint32_t j = 0; j < d.height; ++j)
    for (std::uint32_t i = 0; i < d.width; ++i)
      h[i + j * d.width] = float(10 * std::sin(0.3 * i) * std::cos(0.21 * j) + 0.05 * i * j);
  auto terrain = Terrain::create(Heightfield::create(d, h).value()).value();
  return Landscape::create(terrain, {.patch_exponent = k}).value();
}

// A leaf's projected bound as the tessellator defines it (landscape.h, docs/roam.md): its
// diamond's morph bound projected at the distance from the eye to the diamond's bounding sphere
// (centred at the diamond's vertex at its true height). Recomputed here in double precision from
// the landscape's public data; `in_view` approximates the frustum from the triangle's corners.
inline double projected_bound(const Landscape& l, const LatticeTriangle& t, const Camera& c,
                              bool* in_view) {
  *in_view = false;
  if (((t.lx + t.rx) | (t.lz + t.rz)) & 1) return 0.0;  // finest triangles never split
  const std::int64_t ci = (t.lx + t.rx) / 2, cj = (t.lz + t.rz) / 2;
  const DiamondBound b = l.diamond(ci, cj);
  const double off = l.terrain().info().height_offset;
  const glm::dvec3 centre(world_x(l, ci), off + lattice_height(l, ci, cj), world_z(l, cj));
  // In view: the sphere meets the frustum (the lattice vertices that carry error are inside it;
  // the triangle's corners carry none).
  *in_view = Frustum(c).classify_sphere(centre, double(b.radius)) != Frustum::Cull::kOut;
  const double d = glm::length(centre - c.eye) - double(b.radius);
  return d > 0 ? double(b.morph) * projection_scale(c) / d : (b.morph > 0 ? INFINITY : 0.0);
}

// Every leaf in view meets the threshold (its projected bound is at most `threshold` pixels).
inline void expect_converged(const RoamView& view, const Camera& c, double threshold) {
  const Landscape& l = view.landscape();
  int checked = 0;
  view.for_each_leaf([&](std::uint32_t root, std::uint64_t heap, const LatticeTriangle& t) {
    bool in = false;
    const double p = projected_bound(l, t, c, &in);
    if (!in) return;
    ++checked;
    EXPECT_LE(p, threshold * (1 + 1e-5)) << "root " << root << " heap " << heap;
  });
  EXPECT_GT(checked, 0);
}

}  // namespace ridgeline::test
