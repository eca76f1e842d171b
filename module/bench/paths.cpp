// The six generated camera paths (paths.h).
#include "ridgeline/bench/paths.h"

#include <algorithm>
#include <cmath>

namespace ridgeline::bench {

std::vector<NamedPath> make_paths(const Terrain& terrain, int frames) {
  constexpr double kPi = 3.14159265358979323846;
  const WorldInfo& hf = terrain.info();
  const double ex = hf.extent_x(), ez = hf.extent_z(), E = std::min(ex, ez);
  const double cx = hf.origin_x + ex / 2, cz = hf.origin_z + ez / 2;
  const double top = hf.height_offset + hf.max_local;
  const double far = std::max(50000.0, 2.0 * std::hypot(ex, ez));
  auto ground = [&](double x, double z) {
    x = std::clamp(x, hf.origin_x, hf.origin_x + ex);
    z = std::clamp(z, hf.origin_z, hf.origin_z + ez);
    return terrain.height(x, z).value_or(top);
  };
  auto cam = [&](glm::dvec3 eye, glm::dvec3 target, double fov = 60, glm::dvec3 up = {0, 1, 0}) {
    Camera c;
    c.eye = eye;
    c.target = target;
    c.up = up;
    c.fov_y_deg = fov;
    c.viewport = {1280, 720};
    c.far_m = far;
    return c;
  };
  const int n = std::max(frames, 3);
  std::vector<NamedPath> out(6);
  out[0].name = "flyover";
  out[1].name = "drive";
  out[2].name = "fast_yaw";
  out[3].name = "zoom";
  out[4].name = "down";
  out[5].name = "fast_pass";
  const double alt = top + 0.08 * E;
  for (int k = 0; k < n; ++k) {
    const double s = double(k) / n;
    {  // flyover: 1 degree per frame (the 360-frame circle of docs/benchmarks.md)
      const double a = 2 * kPi * k / 360.0;
      const glm::dvec3 eye(cx + 0.3 * E * std::cos(a), alt, cz + 0.3 * E * std::sin(a));
      const glm::dvec3 ahead(-std::sin(a), 0, std::cos(a));
      out[0].frames.push_back(cam(eye, eye + ahead * (0.1 * E) - glm::dvec3(0, 0.05 * E, 0)));
    }
    {  // drive: 20 m/s, winding
      const double x = cx - 0.3 * E + 20.0 * k / 60.0;
      auto zf = [&](double xx) { return cz + 0.02 * E * std::sin((xx - cx) / (0.05 * E)); };
      const double z = zf(x);
      const glm::dvec3 eye(x, ground(x, z) + 2.0, z);
      const double xa = x + 30.0;
      out[1].frames.push_back(cam(eye, {xa, ground(xa, zf(xa)) + 2.0, zf(xa)}));
    }
    {  // fast yaw: 3 degrees per frame
      const double a = 3.0 * k * kPi / 180.0;
      const glm::dvec3 eye(cx, ground(cx, cz) + 40.0, cz);
      out[2].frames.push_back(
          cam(eye, eye + glm::dvec3(100 * std::cos(a), -20, 100 * std::sin(a))));
    }
    {  // zoom: slow flight (0.002 x extent per frame); field of view snaps 70 -> 8 -> 70
      const double x = cx - 0.2 * E + 0.002 * E * k;
      const glm::dvec3 eye(x, top + 0.03 * E, cz - 0.3 * E);
      const double fov = (k >= n / 3 && k < 2 * n / 3) ? 8.0 : 70.0;
      out[3].frames.push_back(cam(eye, {x, ground(x, cz), cz}, fov));
    }
    {  // straight down, descending
      const double hi = top + 0.7 * E, lo = ground(cx, cz) + 60.0;
      const glm::dvec3 eye(cx, hi + (lo - hi) * s, cz);
      out[4].frames.push_back(cam(eye, eye - glm::dvec3(0, 1, 0), 60, {0, 0, 1}));
    }
    {  // 1,000 km/h along the diagonal
      const double d = 1000.0 / 3.6 / 60.0 * k, r = std::sqrt(0.5);
      const glm::dvec3 eye(cx - 0.3 * E + d * r, top + 40.0, cz - 0.3 * E + d * r);
      out[5].frames.push_back(cam(eye, eye + glm::dvec3(100 * r, -15, 100 * r)));
    }
  }
  return out;
}

}  // namespace ridgeline::bench
