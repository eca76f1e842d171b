// The geomorph of the ROAM core's output as GLSL source, shared by the terrain vertex shader
// (renderer.cpp) and the test that checks it against ridgeline::morphed_height on the GPU
// (tests/test_geomorph_gl.cpp).
#pragma once

namespace game {

/// GLSL 3.30 source of `float geomorph_height(vec3 pos, vec3 morph, vec3 eye, float k,
/// float tau, float w, float delta)`: the drawn height of a MeshVertex (roam_view.h,
/// morph_factor and morphed_height): y + (1 - t) * morph_dy with
/// t = clamp((mu * k / (tau * max(|eye - p| - r, 1e-6)) - 1 - delta) / w, 0, 1), where
/// pos = (x, y, z), morph = (morph_dy, mu = morph_bound, r = morph_radius), `eye` the camera in
/// the same patch-local frame (the CPU subtracts the patch origin in double), k the projection
/// scale (pixels per metre at 1 m, ridgeline::projection_scale), tau the view's
/// RoamStats::morph_threshold (pixels), w and delta the landscape's geomorph() window and delay.
/// t is 1 (no morph)
/// for w <= 0 or tau <= 0, as on the CPU, and for the FLT_MAX bound of patch corners (tested
/// first: FLT_MAX * k would overflow a float). A FLT_MAX radius (the data border) needs no case
/// of its own: max(d, 1e-6) takes 1e-6 there, as on the CPU.
inline constexpr const char* kGeomorphGlsl = R"(
float geomorph_height(vec3 pos, vec3 morph, vec3 eye, float k, float tau, float w,
                      float delta) {
  if (!(w > 0.0) || !(tau > 0.0) || morph.y >= 3.0e38) return pos.y;
  float d = length(pos - eye) - morph.z;
  float rho = morph.y * k / (tau * max(d, 1e-6));
  float t = clamp((rho - 1.0 - delta) / w, 0.0, 1.0);
  return pos.y + (1.0 - t) * morph.x;
}
)";

}  // namespace game
