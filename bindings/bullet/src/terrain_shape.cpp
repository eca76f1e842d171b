// TerrainShape: Bullet's concave-shape interface answered from Ridgeline's queries. Contacts take
// Terrain::triangles_in_box over the body's box; rays take Terrain::raycast, recognised through
// the btTriangleRaycastCallback that btCollisionWorld::rayTestSingleInternal passes to a generic
// concave shape (Bullet 3.24, src/BulletCollision/CollisionDispatch/btCollisionWorld.cpp).
#include "ridgeline/bullet/terrain_shape.h"

#include <BulletCollision/BroadphaseCollision/btBroadphaseProxy.h>
#include <BulletCollision/NarrowPhaseCollision/btRaycastCallback.h>
#include <LinearMath/btAabbUtil2.h>
#include <LinearMath/btTransform.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "ridgeline/surface.h"

namespace ridgeline::bullet {
namespace {

// Boxes wider than this many finest cells on an axis are split into tiles of this size, so that
// the scratch buffer stays small (at most (32 + 1)^2 x 2 triangles, about 175 KB) whatever the
// box (a debug drawer asks for the whole world at once).
constexpr std::int64_t kTileCells = 32;
constexpr double kInf = std::numeric_limits<double>::infinity();
// How far the shape's bounding box reaches under the lowest ground, metres (the header's
// "Rays"): Ridgeline's ground is solid all the way down, Bullet's broadphase needs a bottom.
constexpr double kSolidDepth = 1000;

// One scratch buffer per thread, reused by every shape and every call on that thread: the only
// memory the contact path touches besides the terrain. `busy` catches a callback that re-enters
// processAllTriangles on the same thread (it then gets a buffer of its own).
struct Scratch {
  std::vector<SurfaceTriangle> triangles;
  bool busy = false;
};
thread_local Scratch t_scratch;

bool finite(const glm::dvec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

std::string str(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

}  // namespace

Result<std::unique_ptr<TerrainShape>> TerrainShape::create(std::shared_ptr<const Terrain> terrain,
                                                           const TerrainShapeDesc& desc) {
  if (terrain == nullptr) return Error{"bullet terrain shape: the terrain is null"};
  if (!finite(desc.origin))
    return Error{"bullet terrain shape: origin is (" + str(desc.origin.x) + ", " +
                 str(desc.origin.y) + ", " + str(desc.origin.z) + "); need finite metres"};
  if (!(std::isfinite(desc.margin) && desc.margin >= 0))
    return Error{"bullet terrain shape: margin is " + str(desc.margin) +
                 "; need a finite value >= 0 metres"};
  return std::unique_ptr<TerrainShape>(new TerrainShape(std::move(terrain), desc));
}

TerrainShape::TerrainShape(std::shared_ptr<const Terrain> terrain, const TerrainShapeDesc& desc)
    : terrain_(std::move(terrain)), origin_(desc.origin) {
  // Not CUSTOM_CONCAVE_SHAPE_TYPE: Bullet 3 aliases it to SDF_SHAPE_PROXYTYPE, which its
  // convex-concave algorithm casts to btSdfCollisionShape. Not TERRAIN_SHAPE_PROXYTYPE either:
  // rayTest casts that to btHeightfieldTerrainShape. FAST_CONCAVE_MESH_PROXYTYPE is a concave
  // type Bullet gives no special path, so contacts take the generic convex-concave algorithm and
  // rays the generic concave branch (processAllTriangles with a btTriangleRaycastCallback).
  m_shapeType = FAST_CONCAVE_MESH_PROXYTYPE;
  m_collisionMargin = btScalar(desc.margin);
  const SurfaceLattice& lat = terrain_->surface().lattice();
  lattice_x0_ = lat.origin_x;
  lattice_z0_ = lat.origin_z;
  cell_x_ = lat.spacing_x;
  cell_z_ = lat.spacing_z;
  inv_cell_x_ = 1.0 / cell_x_;
  inv_cell_z_ = 1.0 / cell_z_;
  cells_x_ = lat.vertices_x - 1;
  cells_z_ = lat.vertices_z - 1;
}

TerrainShape::~TerrainShape() = default;

glm::dvec3 TerrainShape::to_world(const btVector3& local) const noexcept {
  return origin_ + glm::dvec3(double(local.x()), double(local.y()), double(local.z()));
}

btVector3 TerrainShape::to_local(const glm::dvec3& world) const noexcept {
  return btVector3(btScalar(world.x - origin_.x), btScalar(world.y - origin_.y),
                   btScalar(world.z - origin_.z));
}

btVector3 TerrainShape::set_origin(const glm::dvec3& origin) noexcept {
  if (!finite(origin)) return btVector3(0, 0, 0);
  const glm::dvec3 d = origin - origin_;
  origin_ = origin;
  return btVector3(btScalar(d.x), btScalar(d.y), btScalar(d.z));
}

void TerrainShape::setLocalScaling(const btVector3&) {}

void TerrainShape::calculateLocalInertia(btScalar, btVector3& inertia) const {
  inertia.setValue(0, 0, 0);
}

void TerrainShape::setMargin(btScalar margin) {
  if (std::isfinite(margin) && margin >= 0) m_collisionMargin = margin;
}

void TerrainShape::getAabb(const btTransform& t, btVector3& aabb_min, btVector3& aabb_max) const {
  const WorldInfo& hf = terrain_->info();
  const double detail = terrain_->surface().detail_bound();
  const glm::dvec3 lo(hf.origin_x, hf.height_offset + hf.min_local - detail - kSolidDepth,
                      hf.origin_z);
  const glm::dvec3 hi(hf.origin_x + hf.extent_x(), hf.height_offset + hf.max_local + detail,
                      hf.origin_z + hf.extent_z());
  // Rounded outwards: the float box must contain every float vertex.
  const auto pad = [](double v) { return 1e-3 + 1e-6 * std::abs(v); };
  glm::dvec3 a = lo - origin_, b = hi - origin_;
  for (int k = 0; k < 3; ++k) a[k] -= pad(a[k]), b[k] += pad(b[k]);
  const btVector3 local_min(btScalar(a.x), btScalar(a.y), btScalar(a.z));
  const btVector3 local_max(btScalar(b.x), btScalar(b.y), btScalar(b.z));
  btTransformAabb(local_min, local_max, getMargin(), t, aabb_min, aabb_max);
}

std::optional<TriangleId> TerrainShape::triangle_id(int triangle_index) const noexcept {
  if (triangle_index < 0) return std::nullopt;
  const std::int64_t cell = triangle_index / 2;
  if (cell >= cells_x_ * cells_z_) return std::nullopt;
  return TriangleId{cell % cells_x_, cell / cells_x_, triangle_index % 2};
}

int TerrainShape::triangle_index(const SurfaceTriangle& t) const noexcept {
  // The cell's lower corner is the triangle's smallest x and z, which lie exactly on lattice
  // lines: rounding finds them without std::floor (a libm call per use at the baseline x86-64
  // instruction set, a third of this function's cost). The centroid's offset in the cell, a
  // third or two thirds of it on each axis, picks the half.
  const double x = std::min({t.v[0].x, t.v[1].x, t.v[2].x});
  const double z = std::min({t.v[0].z, t.v[1].z, t.v[2].z});
  const double u = (x - lattice_x0_) * inv_cell_x_, v = (z - lattice_z0_) * inv_cell_z_;
  if (!(u > -0.5 && v > -0.5 && u < double(cells_x_) - 0.5 && v < double(cells_z_) - 0.5))
    return -1;
  const auto i = std::int64_t(u + 0.5), j = std::int64_t(v + 0.5);
  const double fu =
      ((t.v[0].x + t.v[1].x + t.v[2].x) / 3.0 - lattice_x0_) * inv_cell_x_ - double(i);
  const double fv =
      ((t.v[0].z + t.v[1].z + t.v[2].z) / 3.0 - lattice_z0_) * inv_cell_z_ - double(j);
  const int which = locate_in_cell(i, j, float(fu), float(fv)).which;
  const std::int64_t index = (i + j * cells_x_) * 2 + which;
  return index <= INT_MAX ? int(index) : -1;
}

void TerrainShape::report_box(btTriangleCallback& callback, const Box& box, double tx0, double tx1,
                              double tz0, double tz1, bool filter) const {
  Scratch& s = t_scratch;
  std::vector<SurfaceTriangle> own;  // only when a callback re-entered on this thread
  std::vector<SurfaceTriangle>& tris = s.busy ? own : s.triangles;
  const bool was_busy = s.busy;
  s.busy = true;
  tris.clear();
  terrain_->triangles_in_box(box, tris);
  for (const SurfaceTriangle& t : tris) {
    if (filter) {
      const double cx = (t.v[0].x + t.v[1].x + t.v[2].x) / 3.0;
      const double cz = (t.v[0].z + t.v[1].z + t.v[2].z) / 3.0;
      if (cx < tx0 || cx >= tx1 || cz < tz0 || cz >= tz1) continue;  // another tile's
    }
    btVector3 v[3] = {to_local(t.v[0]), to_local(t.v[1]), to_local(t.v[2])};
    callback.processTriangle(v, int(t.material), triangle_index(t));
  }
  s.busy = was_busy;
}

void TerrainShape::processAllTriangles(btTriangleCallback* callback, const btVector3& aabb_min,
                                       const btVector3& aabb_max) const {
  if (callback == nullptr) return;
  if (auto* ray = dynamic_cast<btTriangleRaycastCallback*>(callback)) {
    (void)report_ray(*ray);
    return;
  }
  const Box box{to_world(aabb_min), to_world(aabb_max)};
  for (int k = 0; k < 3; ++k)
    if (!std::isfinite(box.min[k]) || !std::isfinite(box.max[k]) || !(box.min[k] <= box.max[k]))
      return;
  const double u0 = (box.min.x - lattice_x0_) * inv_cell_x_;
  const double u1 = (box.max.x - lattice_x0_) * inv_cell_x_;
  const double v0 = (box.min.z - lattice_z0_) * inv_cell_z_;
  const double v1 = (box.max.z - lattice_z0_) * inv_cell_z_;
  if (u1 < 0 || v1 < 0 || u0 > double(cells_x_) || v0 > double(cells_z_)) return;
  if (u1 - u0 <= double(kTileCells) && v1 - v0 <= double(kTileCells)) {
    report_box(*callback, box, -kInf, kInf, -kInf, kInf, false);
    return;
  }
  // Tiles with edges on lattice lines: every triangle lies within one tile's column and row and
  // is reported by that tile alone (the one holding its centroid); the outermost tiles take what
  // touches the box beyond them.
  // (Clamped in double before the conversion: a box may reach 1e30 m.)
  const auto first = [](double a, std::int64_t cells) {
    return std::int64_t(std::clamp(std::floor(a), 0.0, double(cells - 1)));
  };
  const auto last = [](double b, std::int64_t lo, std::int64_t cells) {
    return std::int64_t(std::clamp(std::ceil(b), double(lo + 1), double(cells)));
  };
  const std::int64_t a0 = first(u0, cells_x_), a1 = last(u1, a0, cells_x_);
  const std::int64_t b0 = first(v0, cells_z_), b1 = last(v1, b0, cells_z_);
  for (std::int64_t tj = b0; tj < b1; tj += kTileCells) {
    const double z0 = lattice_z0_ + double(tj) * cell_z_;
    const double z1 = lattice_z0_ + double(tj + kTileCells) * cell_z_;
    const bool last_row = tj + kTileCells >= b1;
    for (std::int64_t ti = a0; ti < a1; ti += kTileCells) {
      const double x0 = lattice_x0_ + double(ti) * cell_x_;
      const double x1 = lattice_x0_ + double(ti + kTileCells) * cell_x_;
      const bool last_column = ti + kTileCells >= a1;
      Box tile = box;
      tile.min.x = std::max(box.min.x, x0);
      tile.max.x = last_column ? box.max.x : std::min(box.max.x, x1);
      tile.min.z = std::max(box.min.z, z0);
      tile.max.z = last_row ? box.max.z : std::min(box.max.z, z1);
      if (ti == a0) tile.min.x = box.min.x;
      if (tj == b0) tile.min.z = box.min.z;
      report_box(*callback, tile, ti == a0 ? -kInf : x0, last_column ? kInf : x1,
                 tj == b0 ? -kInf : z0, last_row ? kInf : z1, true);
    }
  }
}

bool TerrainShape::report_ray(btTriangleRaycastCallback& callback) const {
  const glm::dvec3 from = to_world(callback.m_from), to = to_world(callback.m_to);
  const glm::dvec3 d = to - from;
  const double length = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
  const double limit = std::min(double(callback.m_hitFraction), 1.0);
  if (!(length > 0) || !std::isfinite(length) || !(limit > 0)) return false;
  const std::optional<RayHit> hit = terrain_->raycast(from, d, length * limit);
  if (!hit) return false;
  if (hit->started_below && (callback.m_flags & btTriangleRaycastCallback::kF_FilterBackfaces))
    return false;  // from inside the ground: the surface faces away from the ray
  const double fraction = hit->distance / length;
  if (!(fraction < double(callback.m_hitFraction))) return false;
  // The triangle hit: the one under the hit point (on the far edge, the last cell).
  const double u = (hit->point.x - lattice_x0_) * inv_cell_x_;
  const double v = (hit->point.z - lattice_z0_) * inv_cell_z_;
  const auto i = std::int64_t(std::clamp(std::floor(u), 0.0, double(cells_x_ - 1)));
  const auto j = std::int64_t(std::clamp(std::floor(v), 0.0, double(cells_z_ - 1)));
  const float fu = std::clamp(float(u - double(i)), 0.0f, 1.0f);
  const float fv = std::clamp(float(v - double(j)), 0.0f, 1.0f);
  const std::int64_t index = (i + j * cells_x_) * 2 + locate_in_cell(i, j, fu, fv).which;
  const btVector3 normal(hit->normal.x, hit->normal.y, hit->normal.z);
  callback.m_hitFraction = callback.reportHit(normal, btScalar(fraction), int(hit->material),
                                              index <= INT_MAX ? int(index) : -1);
  return true;
}

}  // namespace ridgeline::bullet
