// Raycast-suspension vehicle (the classic "raycast vehicle": one ray per wheel along the body's
// down axis, a spring-damper on the hit distance, a friction circle per tyre) on Ridgeline's
// surface queries. Semi-implicit Euler with fixed substeps.
#include "vehicle.h"

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/mat3x3.hpp>

#include "materials.h"

namespace game {
namespace {
constexpr double kGravity = 9.81;
constexpr int kSubsteps = 4;
}  // namespace

VehicleParams params_from_model(const VehicleModel& model, double mass_kg) {
  VehicleParams p;
  p.mass = mass_kg;
  p.wheel_radius = model.wheel_radius;
  // Centre of mass a little above the wheel centres.
  const float wheel_y = model.wheel_centres[0].y;
  p.com_in_model = {0, wheel_y + 0.35, 0};
  p.rest_length = 0.45;
  for (int i = 0; i < 4; ++i) {
    // Suspension tops sit rest_length above the wheel centres at rest (the model shows the
    // wheels hanging at full extension).
    const glm::dvec3 c(model.wheel_centres[i]);
    p.attach[i] = c + glm::dvec3(0, p.rest_length, 0) - p.com_in_model;
  }
  const glm::vec3 e = model.body_max - model.body_min;
  p.inertia_extent = {e.x, e.y, e.z};
  // Static sag of about rest_length / 3, damping ratio about 0.5.
  const double per_wheel = mass_kg * kGravity / 4;
  p.spring_k = per_wheel / (p.rest_length / 3);
  p.damper_c = 2 * 0.5 * std::sqrt(p.spring_k * mass_kg / 4);
  p.engine_force = mass_kg * 7.0;
  p.friction = 1.1;
  p.brake_force = mass_kg * 7.0;
  return p;
}

Vehicle::Vehicle(const VehicleParams& params, glm::dvec3 position, double heading_rad)
    : params_(params) {
  const glm::dvec3 e = params.inertia_extent;
  const double m = params.mass;
  inertia_ = {m / 12 * (e.y * e.y + e.z * e.z), m / 12 * (e.x * e.x + e.z * e.z),
              m / 12 * (e.x * e.x + e.y * e.y)};
  place(position, heading_rad);
}

void Vehicle::place(glm::dvec3 position, double heading_rad) {
  pos_ = position;
  q_ = glm::angleAxis(heading_rad, glm::dvec3(0, 1, 0));
  v_ = w_ = glm::dvec3(0);
  for (int i = 0; i < 4; ++i) {
    wheels_[i] = {};
    wheels_[i].suspension_length = params_.rest_length;
    wheels_[i].centre = pos_ + q_ * params_.attach[i] - up() * params_.rest_length;
  }
}

bool Vehicle::place_on_surface(const ridgeline::Terrain& terrain, double x, double z,
                               double heading_rad) {
  const auto hn = terrain.height_normal(x, z);
  if (!hn) return false;
  // The mean face normal under the wheels' footprint gives the tilt.
  glm::dvec3 n(0);
  const glm::dquat yaw = glm::angleAxis(heading_rad, glm::dvec3(0, 1, 0));
  for (const glm::dvec3& at : params_.attach) {
    const glm::dvec3 p = glm::dvec3(x, 0, z) + yaw * at;
    if (auto h = terrain.height_normal(p.x, p.z)) n += glm::dvec3(h->face_normal);
  }
  if (glm::length(n) < 1e-6) n = glm::dvec3(hn->face_normal);
  n = glm::normalize(n);
  place({x, hn->height + params_.com_in_model.y, z}, heading_rad);
  // Tilt: the rotation taking +y to n, applied after the heading.
  const glm::dvec3 axis = glm::cross(glm::dvec3(0, 1, 0), n);
  const double s = glm::length(axis);
  if (s > 1e-9) q_ = glm::angleAxis(std::asin(std::min(1.0, s)), axis / s) * q_;
  pos_.y -= 5;  // start low, then lift until every wheel clears the surface
  resolve_penetration(terrain);
  pos_ += up() * (params_.rest_length * 0.6);
  measure_contacts(terrain);
  return true;
}

double Vehicle::heading() const noexcept {
  const glm::dvec3 f = forward();
  return std::atan2(f.x, f.z);
}

double Vehicle::speed() const noexcept {
  return glm::dot(v_, forward());
}

std::array<glm::dvec3, 4> Vehicle::chassis_corners() const {
  const glm::dvec3 a = chassis_min, b = chassis_max;
  return {pos_ + q_ * glm::dvec3(a.x, a.y, a.z), pos_ + q_ * glm::dvec3(b.x, a.y, a.z),
          pos_ + q_ * glm::dvec3(a.x, a.y, b.z), pos_ + q_ * glm::dvec3(b.x, a.y, b.z)};
}

void Vehicle::step(const ridgeline::Terrain& terrain, double dt) {
  if (!(dt > 0)) return;
  for (int s = 0; s < kSubsteps; ++s) substep(terrain, dt / kSubsteps);
  resolve_penetration(terrain);
}

void Vehicle::substep(const ridgeline::Terrain& terrain, double dt) {
  const glm::dmat3 R = glm::mat3_cast(q_);
  const glm::dvec3 up = R[1], fwd = R[2];
  const double m = params_.mass;
  glm::dvec3 force(0, -kGravity * m, 0), torque(0);
  const double reach = params_.rest_length + params_.wheel_radius;
  const double throttle = std::clamp(controls.throttle, -1.0, 1.0);
  const double brake = std::clamp(controls.brake, 0.0, 1.0);
  const double steer = std::clamp(controls.steer, -1.0, 1.0) * params_.max_steer;
  const double fwd_speed = glm::dot(v_, fwd);
  for (int i = 0; i < 4; ++i) {
    WheelState& w = wheels_[i];
    const glm::dvec3 r_attach = R * params_.attach[i];
    const glm::dvec3 a = pos_ + r_attach;
    w.steer = i < 2 ? steer : 0.0;
    const auto hit = terrain.raycast(a, -up, reach);
    if (!hit) {
      w.contact = false;
      w.load_n = 0;
      w.suspension_length = params_.rest_length;
      w.centre = a - up * w.suspension_length;
      continue;
    }
    const double dist = hit->started_below ? 0.0 : hit->distance;
    const double compression = reach - dist;  // 0 .. reach
    const glm::dvec3 va = v_ + glm::cross(w_, r_attach);
    const double rate = -glm::dot(va, up);  // compression speed
    const double fn = std::max(0.0, params_.spring_k * compression + params_.damper_c * rate);
    w.contact = true;
    w.contact_point = hit->point;
    const glm::dvec3 n(hit->normal);
    w.contact_normal = n;
    w.load_n = fn;
    w.suspension_length = std::clamp(dist - params_.wheel_radius, 0.0, params_.rest_length);
    w.centre = a - up * w.suspension_length;
    glm::dvec3 f = up * fn;
    // Tyre: directions in the contact plane.
    const glm::dvec3 wheel_fwd = glm::angleAxis(w.steer, up) * fwd;
    glm::dvec3 tf = wheel_fwd - n * glm::dot(n, wheel_fwd);
    const double tl = glm::length(tf);
    if (tl > 1e-6) {
      tf /= tl;
      const glm::dvec3 ts = glm::cross(n, tf);
      const glm::dvec3 r_contact = hit->point - pos_;
      const glm::dvec3 vp = v_ + glm::cross(w_, r_contact);
      const double vf = glm::dot(vp, tf), vs = glm::dot(vp, ts);
      const double quarter = m / 4;
      // Lateral: cancel (most of) the side slip this substep.
      double fs = -vs * quarter / dt * 0.5;
      // Longitudinal: engine (none above max speed), brakes, rolling resistance.
      double ff = 0;
      if (!(throttle > 0 && fwd_speed > params_.max_speed) &&
          !(throttle < 0 && fwd_speed < -params_.max_speed / 3))
        ff += throttle * params_.engine_force / 4;
      const double stop = std::abs(vf) * quarter / dt * 0.5;
      ff -= (vf > 0 ? 1 : -1) * std::min(brake * params_.brake_force / 4, stop);
      ff -= vf * 0.02 * quarter;  // rolling resistance
      // Friction circle, scaled by the ground's material (sand, mud and snow slip earlier).
      const double limit = params_.friction * material(hit->material).friction * fn;
      const double mag = std::hypot(ff, fs);
      if (mag > limit && mag > 0) {
        ff *= limit / mag;
        fs *= limit / mag;
      }
      const glm::dvec3 ft = tf * ff + ts * fs;
      f += ft;
      torque += glm::cross(r_contact, ft);
      w.spin += vf * dt / params_.wheel_radius;
    }
    force += up * 0.0;
    torque += glm::cross(r_attach, up * fn);
    force += f;
  }
  // Chassis corners below the surface push back like stiff bump stops (with friction), so a
  // body that lands on its frame slides off instead of hanging.
  for (const glm::dvec3& c : chassis_corners()) {
    const auto hn = terrain.height_normal(c.x, c.z);
    if (!hn || c.y >= hn->height) continue;
    const glm::dvec3 n(hn->face_normal);
    const double depth = (hn->height - c.y) * n.y;
    const glm::dvec3 r = c - pos_;
    const glm::dvec3 vc = v_ + glm::cross(w_, r);
    const double vn = glm::dot(vc, n);
    const double fn = std::max(0.0, 4 * params_.spring_k * depth - 2 * params_.damper_c * vn);
    glm::dvec3 vt = vc - n * vn;
    glm::dvec3 f = n * fn;
    const double vtl = glm::length(vt);
    if (vtl > 1e-6) f -= vt / vtl * std::min(0.6 * fn, vtl * m / 4 / dt * 0.5);
    force += f;
    torque += glm::cross(r, f);
  }
  // Light air drag and angular damping keep the integration calm.
  force -= v_ * (0.05 * m) * glm::length(v_) * 0.01;
  // Integrate (semi-implicit Euler).
  v_ += force / m * dt;
  const glm::dvec3 tb = glm::transpose(R) * torque;  // body frame
  glm::dvec3 wb = glm::transpose(R) * w_;
  wb += tb / inertia_ * dt;
  wb *= std::max(0.0, 1.0 - 1.5 * dt);
  w_ = R * wb;
  pos_ += v_ * dt;
  const glm::dquat spin(0, w_.x, w_.y, w_.z);
  q_ = glm::normalize(q_ + 0.5 * dt * (spin * q_));
}

double Vehicle::resolve_penetration(const ridgeline::Terrain& terrain) {
  const glm::dmat3 R = glm::mat3_cast(q_);
  const glm::dvec3 up = R[1];
  double lift = 0;
  // A wheel at full compression (its centre at the attach point) must clear the surface by its
  // radius; a chassis corner must not be below the surface.
  for (int i = 0; i < 4; ++i) {
    const glm::dvec3 a = pos_ + R * params_.attach[i];
    if (auto hn = terrain.height_normal(a.x, a.z)) {
      const double need =
          hn->height + params_.wheel_radius / std::max(0.2, double(hn->face_normal.y));
      lift = std::max(lift, need - a.y);
    }
  }
  // Corners are held by contact forces in substep(); only a deep one (an edit opened the ground,
  // a teleport) is lifted out at once.
  for (const glm::dvec3& c : chassis_corners())
    if (auto h = terrain.height(c.x, c.z)) lift = std::max(lift, *h - c.y - 0.25);
  if (lift > 0) {
    pos_.y += lift;
    if (v_.y < 0) v_.y = 0;
    for (WheelState& w : wheels_) w.centre.y += lift;
  }
  (void)up;
  return std::max(lift, 0.0);
}

void Vehicle::measure_contacts(const ridgeline::Terrain& terrain) {
  // The wheel state for the final pose of the step (what is drawn and what the tests check).
  const glm::dmat3 R = glm::mat3_cast(q_);
  const glm::dvec3 up = R[1];
  const double reach = params_.rest_length + params_.wheel_radius;
  for (int i = 0; i < 4; ++i) {
    WheelState& w = wheels_[i];
    const glm::dvec3 a = pos_ + R * params_.attach[i];
    const auto hit = terrain.raycast(a, -up, reach);
    const double dist = hit ? (hit->started_below ? 0.0 : hit->distance) : reach;
    w.contact = hit.has_value();
    w.suspension_length = std::clamp(dist - params_.wheel_radius, 0.0, params_.rest_length);
    w.centre = a - up * w.suspension_length;
    const glm::dvec3 bottom = w.centre - up * params_.wheel_radius;
    const auto h = terrain.height(bottom.x, bottom.z);
    w.surface_gap = h ? bottom.y - *h : 0.0;
    w.material = hit ? hit->material : 0;
    ground_[i] = {a.x, a.z, terrain.height(a.x, a.z).value_or(std::nan(""))};
  }
  // The ground's material: the one under most wheels in contact (ties: the lowest id).
  int votes[256] = {};
  for (const WheelState& w : wheels_)
    if (w.contact) ++votes[w.material];
  int best = 0;
  for (int m = 1; m < 256; ++m)
    if (votes[m] > votes[best]) best = m;
  ground_material_ = static_cast<std::uint8_t>(best);
}

glm::dmat3 Vehicle::inverse_inertia_world() const noexcept {
  const glm::dmat3 R = glm::mat3_cast(q_);
  const glm::dmat3 inv_body(glm::dvec3(1.0 / inertia_.x, 0, 0), glm::dvec3(0, 1.0 / inertia_.y, 0),
                            glm::dvec3(0, 0, 1.0 / inertia_.z));
  return R * inv_body * glm::transpose(R);
}

glm::dvec3 Vehicle::velocity_at(const glm::dvec3& p) const noexcept {
  return v_ + glm::cross(w_, p - pos_);
}

void Vehicle::apply_impulse(const glm::dvec3& p, const glm::dvec3& impulse) noexcept {
  v_ += impulse / params_.mass;
  w_ += inverse_inertia_world() * glm::cross(p - pos_, impulse);
}

void Vehicle::nudge(const glm::dvec3& d) noexcept {
  pos_ += d;
  for (WheelState& w : wheels_) w.centre += d;
}

double Vehicle::follow_ground(const ridgeline::Terrain& terrain) {
  // The wheels carry the body: it rises with the ground under them (the chassis is kept out of
  // the ground by resolve_penetration below).
  double rise = 0;
  for (const GroundPoint& g : ground_) {
    const auto h = terrain.height(g.x, g.z);
    if (h && std::isfinite(g.height)) rise = std::max(rise, *h - g.height);
  }
  if (rise > 0) {
    pos_.y += rise;
    for (WheelState& w : wheels_) w.centre.y += rise;
  }
  const double lift = rise + resolve_penetration(terrain);
  measure_contacts(terrain);
  return lift;
}

bool Autopilot::drive(Vehicle& v) {
  if (!active || waypoints.empty()) return false;
  bool reached_one = false;
  const glm::dvec3 p = v.position();
  glm::dvec2 here(p.x, p.z);
  if (next < waypoints.size() && glm::length(waypoints[next] - here) < reach) {
    ++reached;
    reached_one = true;
    ++next;
    if (next >= waypoints.size()) {
      if (loop) {
        next = 0;
      } else {
        active = false;
        v.controls = {0, 0, 1};
        return true;
      }
    }
  }
  const glm::dvec2 target = waypoints[next];
  const glm::dvec2 to = target - here;
  const double want = std::atan2(to.x, to.y);
  double err = want - v.heading();
  while (err > M_PI) err -= 2 * M_PI;
  while (err < -M_PI) err += 2 * M_PI;
  // Heading grows towards +x; steering positive turns left (towards +x when facing +z).
  v.controls.steer = std::clamp(err * 1.5, -1.0, 1.0);
  const double want_speed = speed * (std::abs(err) > 0.8 ? 0.4 : 1.0);
  const double s = v.speed();
  v.controls.throttle = std::clamp((want_speed - s) * 0.4, -0.2, 1.0);
  v.controls.brake = s > want_speed + 3 ? 0.5 : 0.0;
  return reached_one;
}

}  // namespace game
