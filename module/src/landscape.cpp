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
#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>
#include <thread>

#include "format.h"
#include "ridgeline/detail.h"

namespace ridgeline {

struct Landscape::Sync {
  std::mutex mutex;
  std::atomic<std::uint64_t> version{0};  // the terrain version the bounds reflect
};

Landscape::~Landscape() = default;

std::uint64_t Landscape::synced_version() const noexcept {
  return sync_->version.load(std::memory_order_acquire);
}

Landscape::LatticeBox Landscape::changed_box(const TerrainChange& c) const noexcept {
  LatticeBox b{c.vertices.i0, c.vertices.i1, c.vertices.j0, c.vertices.j1};
  if (b.i1 >= last_i_) b.i1 = std::int64_t(patches_x_) * patch_cells();
  if (b.j1 >= last_j_) b.j1 = std::int64_t(patches_z_) * patch_cells();
  return b;
}

void Landscape::sync() const {
  const std::uint64_t now = terrain_->edit_version();
  if (sync_->version.load(std::memory_order_acquire) == now) return;
  std::lock_guard lock(sync_->mutex);
  const std::uint64_t have = sync_->version.load(std::memory_order_relaxed);
  if (have == now) return;  // another view synced meanwhile
  // Stored bounds over the stored samples inside each change (the finer levels' bounds come
  // from the detail field when asked for).
  const int d = int(detail_);
  const std::int64_t s = std::int64_t{1} << d;
  for (const TerrainChange& c : terrain_->changes_since(have).changes) {
    const LatticeBox b = changed_box(c);
    update_bounds((b.i0 + s - 1) >> d, (b.j0 + s - 1) >> d, b.i1 >> d, b.j1 >> d);
  }
  sync_->version.store(now, std::memory_order_release);
}

std::uint64_t Landscape::update_bounds(std::int64_t i0, std::int64_t j0, std::int64_t i1,
                                       std::int64_t j1) const {
  const std::int64_t p = std::int64_t{1} << exponent_;
  // Patches whose closed square holds part of the region.
  const std::int64_t px0 = std::max<std::int64_t>(0, (i0 + p - 1) / p - 1),
                     px1 = std::min<std::int64_t>(patches_x_ - 1, i1 / p);
  const std::int64_t pz0 = std::max<std::int64_t>(0, (j0 + p - 1) / p - 1),
                     pz1 = std::min<std::int64_t>(patches_z_ - 1, j1 / p);
  const std::uint64_t npr = nodes_per_root_plus_one_;
  std::uint64_t updated = 0;
  struct Item {
    std::uint64_t heap;
    LatticeTriangle t;
  };
  std::vector<Item> order, stack;
  for (std::int64_t pz = pz0; pz <= pz1; ++pz) {
    for (std::int64_t px = px0; px <= px1; ++px) {
      for (std::uint32_t r = 0; r < 2; ++r) {
        const auto root = static_cast<std::uint32_t>(2 * (px + pz * patches_x_) + r);
        // Pre-order over the stored nodes whose triangle's box meets the region; recomputed in
        // reverse (children before parents) so that nesting reads fresh children.
        order.clear();
        stack.push_back({1, base_triangle(root, 1)});
        while (!stack.empty()) {
          const Item it = stack.back();
          stack.pop_back();
          const LatticeTriangle& t = it.t;
          if (std::max({t.ax, t.lx, t.rx}) < i0 || std::min({t.ax, t.lx, t.rx}) > i1 ||
              std::max({t.az, t.lz, t.rz}) < j0 || std::min({t.az, t.lz, t.rz}) > j1)
            continue;
          order.push_back(it);
          if (2 * it.heap < npr) {
            stack.push_back({2 * it.heap, child_triangle(t, 0)});
            stack.push_back({2 * it.heap + 1, child_triangle(t, 1)});
          }
        }
        float* b = bounds_.data() + root * (npr - 1);
        for (auto it = order.rbegin(); it != order.rend(); ++it) {
          const std::uint64_t h = it->heap;
          float v = compute_exact(it->t);
          if (2 * h < npr) v = std::max({v, b[2 * h - 1], b[2 * h]});
          b[h - 1] = v;
        }
        updated += order.size();
      }
    }
  }
  return updated;
}

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
  l->detail_ = l->terrain_->detail_levels();
  const std::int64_t p = std::int64_t{1} << l->exponent_;  // stored cells per patch
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
  l->spacing_x_ = std::ldexp(hf.spacing_x(), -int(l->detail_));
  l->spacing_z_ = std::ldexp(hf.spacing_z(), -int(l->detail_));
  l->last_i_ = std::int64_t(hf.width() - 1) << l->detail_;
  l->last_j_ = std::int64_t(hf.height() - 1) << l->detail_;
  l->bounds_.assign(total, 0.0f);

  // Roots are independent: split them over the hardware threads.
  const std::uint64_t npr = l->nodes_per_root_plus_one_;
  const std::uint32_t max_level = l->base_level();  // stored levels: 0 .. base_level - 1
  auto work = [&](std::uint64_t first, std::uint64_t last) {
    for (std::uint64_t root = first; root < last; ++root) {
      float* b = l->bounds_.data() + root * (npr - 1);
      // Exact error per stored node (levels 0 .. max_level - 1), walking levels top-down so each
      // node's triangle comes from its parent's.
      std::vector<LatticeTriangle> level{l->base_triangle(static_cast<std::uint32_t>(root), 1)};
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
  l->sync_ = std::make_unique<Sync>();
  l->sync_->version.store(l->terrain_->edit_version(), std::memory_order_release);
  return std::shared_ptr<const Landscape>(std::move(l));
}

LatticeTriangle Landscape::child_triangle(const LatticeTriangle& t, int child) noexcept {
  const std::int64_t mx = (t.lx + t.rx) / 2, mz = (t.lz + t.rz) / 2;
  if (child == 0) return {mx, mz, t.ax, t.az, t.lx, t.lz};  // (M, A, L)
  return {mx, mz, t.rx, t.rz, t.ax, t.az};                  // (M, R, A)
}

LatticeTriangle Landscape::triangle(std::uint32_t root, std::uint64_t heap) const noexcept {
  LatticeTriangle t = base_triangle(root, 1);
  const int d = int(detail_);
  t = {t.ax << d, t.az << d, t.lx << d, t.lz << d, t.rx << d, t.rz << d};
  const int depth = 63 - __builtin_clzll(heap);
  for (int bit = depth - 1; bit >= 0; --bit) t = child_triangle(t, int((heap >> bit) & 1));
  return t;
}

float Landscape::detail_bound(int level, const LatticeTriangle& t) const noexcept {
  // Stored levels: the whole detail (from level 1). Level 2k + 2(m - 1) and 2k + 2m - 1 resolve
  // detail levels below m; their error is at most twice the contribution of levels >= m
  // (docs/detail.md, "Bounds"), non-increasing down the tree, so the sum stays nested.
  const int base = int(base_level());
  const int from = level < base ? 1 : (level - base) / 2 + 1;
  if (from > int(detail_)) return 0.0f;
  const DetailField& f = *terrain_->detail();
  const std::int64_t i0 = std::min({t.ax, t.lx, t.rx}), j0 = std::min({t.az, t.lz, t.rz});
  const std::int64_t i1 = std::max({t.ax, t.lx, t.rx}), j1 = std::max({t.az, t.lz, t.rz});
  // The analytic bound holds before any tile exists; inside a resident finest tile the bound
  // measured when the tile was generated (usually much tighter) replaces it. Both are upper
  // bounds of the same quantity, so their minimum is too.
  const double analytic = f.contribution_bound(std::uint32_t(from), detail_, i0, j0, i1, j1);
  const double measured = terrain_->measured_detail_bound(std::uint32_t(from), i0, j0, i1, j1);
  const double b = 2.0 * std::min(analytic, measured);
  float r = static_cast<float>(b);
  if (double(r) < b) r = std::nextafter(r, INFINITY);
  return r;
}

LatticeTriangle Landscape::base_triangle(std::uint32_t root, std::uint64_t heap) const noexcept {
  const std::uint32_t patch = root / 2;
  const std::int64_t p = std::int64_t{1} << exponent_;
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
  const double ha = base_height(t.ax, t.az), hl = base_height(t.lx, t.lz),
               hr = base_height(t.rx, t.rz);
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
  // The three edge functions e(x, z) = a * x + c(z) (weights of R, A and L); inside means all
  // share w's sign. Per row, each edge bounds x from one side: the span is found exactly in
  // integer arithmetic, so only the samples inside are visited.
  const std::int64_t sgn = w > 0 ? 1 : -1;
  const std::int64_t ex[3][2] = {{t.ax, t.az}, {t.lx, t.lz}, {t.rx, t.rz}};
  // Edge k runs from vertex p to vertex q: e = (q - p) x (v - p).
  const int from[3] = {0, 1, 2}, to[3] = {1, 2, 0};
  auto floor_div = [](std::int64_t n, std::int64_t d) {  // d > 0
    return n >= 0 ? n / d : -((-n + d - 1) / d);
  };
  for (std::int64_t z = z0; z <= z1; ++z) {
    std::int64_t lo = x0, hi = x1;
    std::int64_t coef[3], off[3];
    for (int k = 0; k < 3; ++k) {
      const std::int64_t px = ex[from[k]][0], pz = ex[from[k]][1];
      const std::int64_t ux = ex[to[k]][0] - px, uz = ex[to[k]][1] - pz;
      // e(x) = ux * (z - pz) - uz * (x - px) = a * x + c, made >= 0 inside by the sign.
      const std::int64_t a = -uz * sgn, c = (ux * (z - pz) + uz * px) * sgn;
      coef[k] = a, off[k] = c;
      if (a > 0) lo = std::max(lo, -floor_div(c, a));      // x >= ceil(-c / a)
      else if (a < 0) hi = std::min(hi, floor_div(c, -a));  // x <= floor(c / -a)
      else if (c < 0) lo = hi + 1;                          // edge parallel to x, row outside
    }
    if (lo > hi) continue;
    const std::uint32_t zc = static_cast<std::uint32_t>(std::clamp<std::int64_t>(z, 0, hmax));
    for (std::int64_t x = lo; x <= hi; ++x) {
      // Barycentric weights from the edge functions (e_k is opposite the vertex after edge k).
      const std::int64_t e_ab = coef[0] * x + off[0];  // edge A->L: weight of R
      const std::int64_t e_lr = coef[1] * x + off[1];  // edge L->R: weight of A
      const std::int64_t e_ra = coef[2] * x + off[2];  // edge R->A: weight of L
      const double plane = (double(e_lr) * ha + double(e_ra) * hl + double(e_ab) * hr) * inv_w * sgn;
      const double h = hf.local(static_cast<std::uint32_t>(std::clamp<std::int64_t>(x, 0, wmax)), zc);
      worst = std::max(worst, std::abs(h - plane));
    }
  }
  // Round up so the float bound is never below the double error.
  float f = static_cast<float>(worst);
  if (double(f) < worst) f = std::nextafter(f, INFINITY);
  return f;
}

float Landscape::exact_error(std::uint32_t root, std::uint64_t heap) const noexcept {
  return heap < nodes_per_root_plus_one_ ? compute_exact(base_triangle(root, heap)) : 0.0f;
}

}  // namespace ridgeline
