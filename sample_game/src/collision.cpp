// Vehicle-vehicle contacts: separating-axis test of two oriented rectangles on the xz plane
// (Ericson, "Real-Time Collision Detection", 4.4), then a sequential-impulse style response at
// one contact point (Catto, "Iterative Dynamics with Temporal Coherence", GDC 2005): a normal
// impulse with a little restitution, a friction impulse within the Coulomb cone, and a split
// position correction (Baumgarte-like) so resting bodies do not sink into each other.
#include "collision.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace game {
namespace {

constexpr double kRestitution = 0.2;
constexpr double kFriction = 0.5;
constexpr double kSlop = 0.02;       // metres of overlap left alone (no jitter at rest)
constexpr double kCorrection = 0.8;  // fraction of the overlap removed per step

struct Rect {
  glm::dvec2 centre;
  glm::dvec2 axis[2];  // unit: body x and body z projected on the ground
  double half[2];
  double y_min, y_max;
};

Rect rect_of(const Vehicle& v) {
  const glm::dquat q = v.orientation();
  const glm::dvec3 lo = v.chassis_min, hi = v.chassis_max;
  const glm::dvec3 c = v.position() + q * ((lo + hi) * 0.5);
  Rect r;
  r.centre = {c.x, c.z};
  const glm::dvec3 ax = q * glm::dvec3(1, 0, 0), az = q * glm::dvec3(0, 0, 1);
  r.axis[0] = glm::dvec2(ax.x, ax.z);
  r.axis[1] = glm::dvec2(az.x, az.z);
  for (auto& a : r.axis) {
    const double l = glm::length(a);
    a = l > 1e-9 ? a / l : glm::dvec2(1, 0);
  }
  r.half[0] = (hi.x - lo.x) * 0.5;
  r.half[1] = (hi.z - lo.z) * 0.5;
  // Height range of the tilted box: its eight corners.
  r.y_min = 1e300;
  r.y_max = -1e300;
  for (int i = 0; i < 8; ++i) {
    const glm::dvec3 p(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z);
    const double y = (v.position() + q * p).y;
    r.y_min = std::min(r.y_min, y);
    r.y_max = std::max(r.y_max, y);
  }
  return r;
}

double radius_along(const Rect& r, const glm::dvec2& n) {
  return r.half[0] * std::abs(glm::dot(r.axis[0], n)) +
         r.half[1] * std::abs(glm::dot(r.axis[1], n));
}

std::array<glm::dvec2, 4> corners(const Rect& r) {
  const glm::dvec2 x = r.axis[0] * r.half[0], z = r.axis[1] * r.half[1];
  return {r.centre - x - z, r.centre + x - z, r.centre + x + z, r.centre - x + z};
}

bool inside(const Rect& r, const glm::dvec2& p) {
  const glm::dvec2 d = p - r.centre;
  return std::abs(glm::dot(d, r.axis[0])) <= r.half[0] + 1e-9 &&
         std::abs(glm::dot(d, r.axis[1])) <= r.half[1] + 1e-9;
}

}  // namespace

bool find_contact(const Vehicle& va, const Vehicle& vb, VehicleContact& out) {
  const Rect a = rect_of(va), b = rect_of(vb);
  if (a.y_max < b.y_min || b.y_max < a.y_min) return false;
  const glm::dvec2 d = b.centre - a.centre;
  double best = 1e300;
  glm::dvec2 normal(1, 0);
  for (const glm::dvec2& n : {a.axis[0], a.axis[1], b.axis[0], b.axis[1]}) {
    const double overlap = radius_along(a, n) + radius_along(b, n) - std::abs(glm::dot(d, n));
    if (overlap <= 0) return false;  // a separating axis
    if (overlap < best) {
      best = overlap;
      normal = glm::dot(d, n) >= 0 ? n : -n;
    }
  }
  // The contact point: the mean of the corners of each box inside the other (edge crossings
  // with no corner inside: the midpoint between the centres).
  glm::dvec2 sum(0);
  int count = 0;
  for (const glm::dvec2& c : corners(a))
    if (inside(b, c)) sum += c, ++count;
  for (const glm::dvec2& c : corners(b))
    if (inside(a, c)) sum += c, ++count;
  const glm::dvec2 p = count > 0 ? sum / double(count) : (a.centre + b.centre) * 0.5;
  const double y = 0.5 * (std::max(a.y_min, b.y_min) + std::min(a.y_max, b.y_max));
  out.normal = glm::dvec3(normal.x, 0, normal.y);
  out.point = glm::dvec3(p.x, y, p.y);
  out.depth = best;
  return true;
}

std::size_t resolve_vehicle_contacts(std::map<int, VehicleEntry>& vehicles,
                                     std::map<std::pair<int, int>, bool>& touching) {
  std::vector<VehicleEntry*> all;
  for (auto& [id, e] : vehicles) all.push_back(&e);
  std::map<std::pair<int, int>, bool> now;
  std::size_t contacts = 0;
  for (std::size_t i = 0; i < all.size(); ++i) {
    for (std::size_t j = i + 1; j < all.size(); ++j) {
      Vehicle& a = all[i]->body;
      Vehicle& b = all[j]->body;
      // Broad phase: bodies further apart than their box diagonals cannot touch.
      const glm::dvec3 da = a.chassis_max - a.chassis_min, db = b.chassis_max - b.chassis_min;
      const double reach = 0.5 * (glm::length(da) + glm::length(db));
      const glm::dvec3 gap = b.position() - a.position();
      if (glm::dot(gap, gap) > reach * reach) continue;
      VehicleContact c;
      if (!find_contact(a, b, c)) continue;
      ++contacts;
      const std::pair<int, int> key(all[i]->id, all[j]->id);
      now[key] = true;
      if (!touching.count(key)) {
        ++a.collisions;
        ++b.collisions;
      }
      const glm::dvec3 n = c.normal;
      const glm::dvec3 ra = c.point - a.position(), rb = c.point - b.position();
      const glm::dmat3 ia = a.inverse_inertia_world(), ib = b.inverse_inertia_world();
      auto effective_mass = [&](const glm::dvec3& dir) {
        const double k = a.inverse_mass() + b.inverse_mass() +
                         glm::dot(dir, glm::cross(ia * glm::cross(ra, dir), ra)) +
                         glm::dot(dir, glm::cross(ib * glm::cross(rb, dir), rb));
        return k > 0 ? 1.0 / k : 0.0;
      };
      const glm::dvec3 vrel = b.velocity_at(c.point) - a.velocity_at(c.point);
      const double vn = glm::dot(vrel, n);
      double jn = 0;
      if (vn < 0) {  // approaching: stop them, with a little bounce
        jn = -(1 + kRestitution) * vn * effective_mass(n);
        a.apply_impulse(c.point, -n * jn);
        b.apply_impulse(c.point, n * jn);
        // Friction against the sliding velocity left in the contact plane.
        const glm::dvec3 v2 = b.velocity_at(c.point) - a.velocity_at(c.point);
        glm::dvec3 vt = v2 - n * glm::dot(v2, n);
        const double vtl = glm::length(vt);
        if (vtl > 1e-6) {
          vt /= vtl;
          const double jt = std::min(vtl * effective_mass(vt), kFriction * jn);
          a.apply_impulse(c.point, vt * jt);
          b.apply_impulse(c.point, -vt * jt);
        }
      }
      // Push apart, by inverse mass, what exceeds the slop.
      const double push = std::max(0.0, c.depth - kSlop) * kCorrection;
      const double wa = a.inverse_mass() / (a.inverse_mass() + b.inverse_mass());
      a.nudge(-n * push * wa);
      b.nudge(n * push * (1 - wa));
    }
  }
  touching = std::move(now);
  return contacts;
}

}  // namespace game
