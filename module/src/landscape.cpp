// Patches, bintree geometry and exact nested error bounds.
//
// The bound of a node is the RTIN ("martini") definition: the largest vertical distance between
// the surface and the node's triangle over every lattice vertex under the triangle. Since both the
// triangle and the surface under it are piecewise linear over the finest lattice triangles (the
// node is a union of them), the largest distance is reached at a lattice vertex, so this is the
// exact error. It is made nested by taking the maximum with the children's bounds (Duchaineau et
// al. 1997 require nested bounds for the queues to be monotone). Cost: every level touches every
// vertex about once, O(N log N) per patch.
#include "ridgeline/landscape.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>

#include "format.h"

namespace ridgeline {

Result<std::shared_ptr<const Landscape>> Landscape::create(std::shared_ptr<const Terrain> terrain,
                                                           const LandscapeDesc& desc) {
  if (!terrain) return Error{"landscape: no terrain given"};
  if (desc.patch_exponent < 2 || desc.patch_exponent > 10)
    return Error{fmt("landscape: patch exponent %u; need 2..10 (patches of 5 .. 1025 samples)",
                     desc.patch_exponent)};
  const auto t0 = std::chrono::steady_clock::now();
  std::shared_ptr<Landscape> l(new Landscape());
  const Heightfield& hf = terrain->heightfield();
  l->terrain_ = std::move(terrain);
  l->exponent_ = desc.patch_exponent;
  const std::int64_t p = l->patch_cells();
  l->patches_x_ = static_cast<std::uint32_t>((hf.width() - 1 + p - 1) / p);
  l->patches_z_ = static_cast<std::uint32_t>((hf.height() - 1 + p - 1) / p);
  const std::uint64_t roots = std::uint64_t{2} * l->patches_x_ * l->patches_z_;
  l->nodes_per_root_plus_one_ = std::uint64_t{1} << (2 * l->exponent_);
  const std::uint64_t total = roots * (l->nodes_per_root_plus_one_ - 1);
  if (total > (std::uint64_t{1} << 32))
    return Error{fmt("landscape: %llu bound entries; too many (use larger heightfield spacing)",
                     static_cast<unsigned long long>(total))};
  l->origin_x_ = hf.origin_x();
  l->origin_z_ = hf.origin_z();
  l->spacing_x_ = hf.spacing_x();
  l->spacing_z_ = hf.spacing_z();
  l->bounds_.assign(total, 0.0f);

  // Roots are independent: split them over the hardware threads.
  const std::uint64_t npr = l->nodes_per_root_plus_one_;
  const std::uint32_t max_level = l->max_level();
  auto work = [&](std::uint64_t first, std::uint64_t last) {
    for (std::uint64_t root = first; root < last; ++root) {
      float* b = l->bounds_.data() + root * (npr - 1);
      // Exact error per stored node (levels 0 .. max_level - 1), walking levels top-down so each
      // node's triangle comes from its parent's.
      std::vector<LatticeTriangle> level{l->triangle(static_cast<std::uint32_t>(root), 1)};
      std::vector<LatticeTriangle> next;
      std::uint64_t first_heap = 1;
      for (std::uint32_t lv = 0; lv < max_level; ++lv) {
        next.clear();
        for (std::size_t k = 0; k < level.size(); ++k) {
          b[first_heap + k - 1] = l->compute_exact(level[k]);
          if (lv + 1 < max_level) {
            next.push_back(child_triangle(level[k], 0));
            next.push_back(child_triangle(level[k], 1));
          }
        }
        first_heap <<= 1;
        level.swap(next);
      }
      // Nested: bottom-up maximum with the children.
      for (std::uint64_t h = npr / 2 - 1; h >= 1; --h)
        b[h - 1] = std::max({b[h - 1], b[2 * h - 1], b[2 * h]});
    }
  };
  const unsigned threads = std::max(1u, std::min(8u, std::thread::hardware_concurrency()));
  if (threads <= 1 || roots < 4) {
    work(0, roots);
  } else {
    std::vector<std::thread> pool;
    for (unsigned t = 0; t < threads; ++t)
      pool.emplace_back(work, roots * t / threads, roots * (t + 1) / threads);
    for (auto& th : pool) th.join();
  }
  l->build_ms_ =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return std::shared_ptr<const Landscape>(std::move(l));
}

LatticeTriangle Landscape::child_triangle(const LatticeTriangle& t, int child) noexcept {
  const std::int64_t mx = (t.lx + t.rx) / 2, mz = (t.lz + t.rz) / 2;
  if (child == 0) return {mx, mz, t.ax, t.az, t.lx, t.lz};  // (M, A, L)
  return {mx, mz, t.rx, t.rz, t.ax, t.az};                  // (M, R, A)
}

LatticeTriangle Landscape::triangle(std::uint32_t root, std::uint64_t heap) const noexcept {
  const std::uint32_t patch = root / 2;
  const std::int64_t p = patch_cells();
  const std::int64_t ox = std::int64_t(patch % patches_x_) * p;
  const std::int64_t oz = std::int64_t(patch / patches_x_) * p;
  LatticeTriangle t = (root & 1) == 0 ? LatticeTriangle{ox + p, oz, ox, oz, ox + p, oz + p}
                                      : LatticeTriangle{ox, oz + p, ox + p, oz + p, ox, oz};
  const int depth = 63 - __builtin_clzll(heap);
  for (int bit = depth - 1; bit >= 0; --bit) t = child_triangle(t, int((heap >> bit) & 1));
  return t;
}

float Landscape::compute_exact(const LatticeTriangle& t) const noexcept {
  const std::int64_t x0 = std::min({t.ax, t.lx, t.rx}), x1 = std::max({t.ax, t.lx, t.rx});
  const std::int64_t z0 = std::min({t.az, t.lz, t.rz}), z1 = std::max({t.az, t.lz, t.rz});
  const double ha = lattice_height(t.ax, t.az), hl = lattice_height(t.lx, t.lz),
               hr = lattice_height(t.rx, t.rz);
  // Edge functions in integer arithmetic; w is twice the signed area.
  auto cross = [](std::int64_t ux, std::int64_t uz, std::int64_t vx, std::int64_t vz) {
    return ux * vz - uz * vx;
  };
  const std::int64_t w = cross(t.lx - t.ax, t.lz - t.az, t.rx - t.ax, t.rz - t.az);
  if (w == 0) return 0.0f;
  const double inv_w = 1.0 / double(w);
  double worst = 0.0;
  const Heightfield& hf = terrain_->heightfield();
  const std::int64_t wmax = hf.width() - 1, hmax = hf.height() - 1;
  for (std::int64_t z = z0; z <= z1; ++z) {
    for (std::int64_t x = x0; x <= x1; ++x) {
      const std::int64_t e_r = cross(t.lx - t.ax, t.lz - t.az, x - t.ax, z - t.az);  // weight of R
      const std::int64_t e_a = cross(t.rx - t.lx, t.rz - t.lz, x - t.lx, z - t.lz);  // weight of A
      const std::int64_t e_l = cross(t.ax - t.rx, t.az - t.rz, x - t.rx, z - t.rz);  // weight of L
      const bool inside =
          w > 0 ? (e_r >= 0 && e_a >= 0 && e_l >= 0) : (e_r <= 0 && e_a <= 0 && e_l <= 0);
      if (!inside) continue;
      const double plane = (e_a * ha + e_l * hl + e_r * hr) * inv_w;
      const double h = hf.local(static_cast<std::uint32_t>(std::clamp<std::int64_t>(x, 0, wmax)),
                                static_cast<std::uint32_t>(std::clamp<std::int64_t>(z, 0, hmax)));
      worst = std::max(worst, std::abs(h - plane));
    }
  }
  // Round up so the float bound is never below the double error.
  float f = static_cast<float>(worst);
  if (double(f) < worst) f = std::nextafter(f, INFINITY);
  return f;
}

float Landscape::exact_error(std::uint32_t root, std::uint64_t heap) const noexcept {
  return compute_exact(triangle(root, heap));
}

}  // namespace ridgeline
