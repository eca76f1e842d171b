// OpenGL 3.3 core rendering of the game. Positions are camera-relative floats (the patch origin
// minus the eye, in double, then float) so that large worlds keep their precision.
#define GL_GLEXT_PROTOTYPES 1
#include "renderer.h"

#include <GL/gl.h>
#include <GL/glext.h>

#include <chrono>
#include <cmath>
#include <cstddef>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/mat4x4.hpp>
#include <string>

namespace game {
namespace {

using ridgeline::Error;

const char* kTerrainVs = R"(#version 330 core
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_nrm;
layout(location = 2) in vec2 a_morph;   // morph_dy, morph_bound
uniform mat4 u_view_proj;               // camera-relative
uniform vec3 u_offset;                  // patch origin - eye
uniform float u_origin_y;               // patch origin height (world)
uniform float u_proj_scale;             // pixels per metre at unit distance
uniform float u_threshold;              // pixels
uniform int u_geomorph;
out vec3 v_nrm;
out float v_height;
out float v_dist;
void main() {
  vec3 rel = u_offset + a_pos;
  float d = max(length(rel), 1e-3);
  float y = a_pos.y;
  if (u_geomorph != 0 && a_morph.y > 0.0) {
    // morph_factor() of roam_view.h: t = clamp(p / threshold - 1, 0, 1)
    float p = a_morph.y * u_proj_scale / d;
    float t = clamp(p / max(u_threshold, 1e-3) - 1.0, 0.0, 1.0);
    y += (1.0 - t) * a_morph.x;
  }
  rel.y = u_offset.y + y;
  v_nrm = a_nrm;
  v_height = u_origin_y + y;
  v_dist = d;
  gl_Position = u_view_proj * vec4(rel, 1.0);
}
)";

const char* kTerrainFs = R"(#version 330 core
in vec3 v_nrm;
in float v_height;
in float v_dist;
uniform vec3 u_sun;
uniform vec3 u_fog_colour;
uniform float u_fog_density;
uniform vec2 u_height_range;
uniform int u_wireframe;
out vec4 o_colour;
void main() {
  vec3 n = normalize(v_nrm);
  float slope = 1.0 - n.y;                       // 0 flat .. 1 vertical
  float h = clamp((v_height - u_height_range.x) / max(u_height_range.y - u_height_range.x, 1.0), 0.0, 1.0);
  vec3 sand = vec3(0.76, 0.70, 0.50), grass = vec3(0.28, 0.48, 0.18);
  vec3 meadow = vec3(0.42, 0.55, 0.22), dry = vec3(0.58, 0.53, 0.33);
  vec3 rock = vec3(0.47, 0.44, 0.42), snow = vec3(0.95, 0.96, 0.98);
  vec3 c = mix(sand, grass, smoothstep(0.03, 0.08, h));
  c = mix(c, meadow, smoothstep(0.15, 0.35, h));
  c = mix(c, dry, smoothstep(0.45, 0.65, h));
  c = mix(c, snow, smoothstep(0.8, 0.88, h) * (1.0 - smoothstep(0.25, 0.45, slope)));
  c = mix(c, rock, smoothstep(0.10, 0.22, slope));
  float diffuse = max(dot(n, u_sun), 0.0);
  float sky = 0.5 + 0.5 * n.y;
  vec3 lit = c * (0.85 * diffuse * vec3(1.0, 0.96, 0.88) + 0.32 * sky * vec3(0.6, 0.7, 0.9));
  if (u_wireframe != 0) lit = vec3(0.05, 0.08, 0.05) + 0.6 * lit;
  float fog = 1.0 - exp(-u_fog_density * v_dist);
  o_colour = vec4(mix(lit, u_fog_colour, clamp(fog, 0.0, 1.0)), 1.0);
}
)";

const char* kSkyVs = R"(#version 330 core
out vec2 v_ndc;
void main() {
  vec2 p = vec2((gl_VertexID == 1) ? 3.0 : -1.0, (gl_VertexID == 2) ? 3.0 : -1.0);
  v_ndc = p;
  gl_Position = vec4(p, 1.0, 1.0);  // z = w: depth 1, the far plane
}
)";

const char* kSkyFs = R"(#version 330 core
in vec2 v_ndc;
uniform mat4 u_inv_view_proj;
uniform vec3 u_sun;
uniform vec3 u_fog_colour;
out vec4 o_colour;
void main() {
  vec4 far = u_inv_view_proj * vec4(v_ndc, 1.0, 1.0);
  vec3 dir = normalize(far.xyz / far.w);
  float up = clamp(dir.y, -1.0, 1.0);
  vec3 zenith = vec3(0.22, 0.42, 0.78);
  vec3 c = mix(u_fog_colour, zenith, smoothstep(0.0, 0.5, up));
  c = mix(c, u_fog_colour * 0.9, smoothstep(0.0, -0.2, up));
  float s = max(dot(dir, u_sun), 0.0);
  c += vec3(1.0, 0.9, 0.7) * (pow(s, 600.0) * 2.0 + pow(s, 12.0) * 0.15);
  o_colour = vec4(c, 1.0);
}
)";

const char* kModelVs = R"(#version 330 core
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_nrm;
layout(location = 2) in vec3 a_col;
uniform mat4 u_view_proj;
uniform mat4 u_model;     // camera-relative
out vec3 v_nrm;
out vec3 v_col;
out float v_dist;
void main() {
  vec4 p = u_model * vec4(a_pos, 1.0);
  v_nrm = mat3(u_model) * a_nrm;
  v_col = a_col;
  v_dist = length(p.xyz);
  gl_Position = u_view_proj * p;
}
)";

const char* kModelFs = R"(#version 330 core
in vec3 v_nrm;
in vec3 v_col;
in float v_dist;
uniform vec3 u_sun;
uniform vec3 u_fog_colour;
uniform float u_fog_density;
out vec4 o_colour;
void main() {
  vec3 n = normalize(v_nrm);
  if (!gl_FrontFacing) n = -n;
  float diffuse = max(dot(n, u_sun), 0.0);
  vec3 lit = v_col * (0.8 * diffuse + 0.35 * (0.5 + 0.5 * n.y));
  float fog = 1.0 - exp(-u_fog_density * v_dist);
  o_colour = vec4(mix(lit, u_fog_colour, clamp(fog, 0.0, 1.0)), 1.0);
}
)";

std::string compile(unsigned shader, const char* src) {
  glShaderSource(shader, 1, &src, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (ok) return {};
  char log[2048];
  glGetShaderInfoLog(shader, sizeof log, nullptr, log);
  return log;
}

ridgeline::Result<unsigned> program(const char* vs, const char* fs, const char* name) {
  const unsigned v = glCreateShader(GL_VERTEX_SHADER), f = glCreateShader(GL_FRAGMENT_SHADER);
  std::string e = compile(v, vs);
  if (e.empty()) e = compile(f, fs);
  if (!e.empty()) return Error{std::string("shader '") + name + "': " + e};
  const unsigned p = glCreateProgram();
  glAttachShader(p, v);
  glAttachShader(p, f);
  glLinkProgram(p);
  glDeleteShader(v);
  glDeleteShader(f);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[2048];
    glGetProgramInfoLog(p, sizeof log, nullptr, log);
    return Error{std::string("program '") + name + "': " + log};
  }
  return p;
}

int loc(unsigned p, const char* n) { return glGetUniformLocation(p, n); }

const glm::vec3 kSun = glm::normalize(glm::vec3(0.45f, 0.6f, 0.35f));
const glm::vec3 kFog(0.70f, 0.78f, 0.86f);

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

ridgeline::Result<std::unique_ptr<Renderer>> Renderer::create(Game& game, int width, int height) {
  std::unique_ptr<Renderer> r(new Renderer());
  r->width_ = width;
  r->height_ = height;
  auto tp = program(kTerrainVs, kTerrainFs, "terrain");
  if (!tp) return Error{tp.error().message};
  auto sp = program(kSkyVs, kSkyFs, "sky");
  if (!sp) return Error{sp.error().message};
  auto mp = program(kModelVs, kModelFs, "model");
  if (!mp) return Error{mp.error().message};
  r->terrain_prog_ = *tp;
  {  // height range for the colouring, from the terrain's samples
    const ridgeline::Heightfield& hf = game.terrain().heightfield();
    float lo = 1e30f, hi = -1e30f;
    for (std::uint32_t j = 0; j < hf.height(); j += 4)
      for (std::uint32_t i = 0; i < hf.width(); i += 4) {
        const float v = float(hf.world(i, j));
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      }
    r->height_min_ = lo;
    r->height_max_ = hi > lo ? hi : lo + 1;
  }
  r->sky_prog_ = *sp;
  r->model_prog_ = *mp;
  glGenVertexArrays(1, &r->sky_vao_);
  glGenFramebuffers(1, &r->fbo_);
  glBindFramebuffer(GL_FRAMEBUFFER, r->fbo_);
  glGenRenderbuffers(1, &r->colour_);
  glBindRenderbuffer(GL_RENDERBUFFER, r->colour_);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width, height);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, r->colour_);
  glGenRenderbuffers(1, &r->depth_);
  glBindRenderbuffer(GL_RENDERBUFFER, r->depth_);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, width, height);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, r->depth_);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    return Error{"renderer: framebuffer object incomplete"};
  for (const std::string& name : game.model_names()) {
    const VehicleModel* m = game.model(name);
    r->models_[name] = {r->upload_model(m->body), r->upload_model(m->wheel)};
  }
  if (glGetError() != GL_NO_ERROR) return Error{"renderer: OpenGL error during setup"};
  return r;
}

Renderer::~Renderer() {
  for (auto& set : patches_)
    for (PatchGpu& p : set) {
      glDeleteVertexArrays(1, &p.vao);
      glDeleteBuffers(1, &p.vbo);
      glDeleteBuffers(1, &p.ibo);
    }
  for (auto& [k, m] : models_)
    for (MeshGpu* g : {&m.first, &m.second}) {
      glDeleteVertexArrays(1, &g->vao);
      glDeleteBuffers(1, &g->vbo);
      glDeleteBuffers(1, &g->ibo);
    }
  glDeleteProgram(terrain_prog_);
  glDeleteProgram(sky_prog_);
  glDeleteProgram(model_prog_);
  glDeleteVertexArrays(1, &sky_vao_);
  glDeleteRenderbuffers(1, &colour_);
  glDeleteRenderbuffers(1, &depth_);
  glDeleteFramebuffers(1, &fbo_);
}

Renderer::MeshGpu Renderer::upload_model(const ModelMesh& mesh) {
  MeshGpu g;
  glGenVertexArrays(1, &g.vao);
  glBindVertexArray(g.vao);
  glGenBuffers(1, &g.vbo);
  glBindBuffer(GL_ARRAY_BUFFER, g.vbo);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(mesh.vertices.size() * sizeof(ModelVertex)),
               mesh.vertices.data(), GL_STATIC_DRAW);
  glGenBuffers(1, &g.ibo);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g.ibo);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(mesh.indices.size() * 4), mesh.indices.data(),
               GL_STATIC_DRAW);
  const GLsizei stride = sizeof(ModelVertex);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, stride, (void*)offsetof(ModelVertex, px));
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, stride, (void*)offsetof(ModelVertex, nx));
  glEnableVertexAttribArray(2);
  glVertexAttribPointer(2, 3, GL_FLOAT, GL_FALSE, stride, (void*)offsetof(ModelVertex, r));
  glBindVertexArray(0);
  g.count = static_cast<int>(mesh.indices.size());
  return g;
}

void Renderer::upload_patch(PatchGpu& gpu, const ridgeline::PatchMesh& mesh) {
  if (gpu.vao == 0) {
    glGenVertexArrays(1, &gpu.vao);
    glBindVertexArray(gpu.vao);
    glGenBuffers(1, &gpu.vbo);
    glGenBuffers(1, &gpu.ibo);
    glBindBuffer(GL_ARRAY_BUFFER, gpu.vbo);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, gpu.ibo);
    const GLsizei stride = sizeof(ridgeline::MeshVertex);
    using V = ridgeline::MeshVertex;
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, stride, (void*)offsetof(V, x));
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, stride, (void*)offsetof(V, nx));
    glEnableVertexAttribArray(2);
    glVertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, stride, (void*)offsetof(V, morph_dy));
  }
  glBindVertexArray(gpu.vao);
  // Unused slots and triangles over the padding are degenerate (0, 0, 0): draw the array as is.
  const std::vector<std::uint32_t>& idx = mesh.indices;
  const std::uint32_t tris = mesh.triangles;
  glBindBuffer(GL_ARRAY_BUFFER, gpu.vbo);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(mesh.vertices.size() * sizeof(ridgeline::MeshVertex)),
               mesh.vertices.data(), GL_DYNAMIC_DRAW);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, gpu.ibo);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(idx.size() * 4), idx.data(), GL_DYNAMIC_DRAW);
  glBindVertexArray(0);
  gpu.count = static_cast<int>(idx.size());
  gpu.triangles = tris;
  gpu.ox = mesh.origin_x;
  gpu.oy = mesh.origin_y;
  gpu.oz = mesh.origin_z;
}

RenderStats Renderer::draw(Game& game, const RenderSettings& settings) {
  RenderStats st;
  const int vi = static_cast<int>(game.rig().mode);
  ridgeline::RoamView& view = game.active_view();
  std::vector<PatchGpu>& set = patches_[vi];
  const std::uint32_t np = view.landscape().patch_count();
  auto t0 = std::chrono::steady_clock::now();
  std::vector<std::uint32_t> dirty = view.take_dirty_patches();
  if (!patches_initialised_[vi]) {
    // First use of this view: every patch.
    set.assign(np, PatchGpu{});
    dirty.clear();
    for (std::uint32_t p = 0; p < np; ++p) dirty.push_back(p);
    patches_initialised_[vi] = true;
  }
  for (std::uint32_t p : dirty) {
    if (p >= np) continue;
    upload_patch(set[p], view.patch_mesh(p));
    ++st.patches_uploaded;
  }
  st.upload_ms = ms_since(t0);
  t0 = std::chrono::steady_clock::now();

  const ridgeline::Camera cam = game.camera();
  const glm::dvec3 eye = cam.eye;
  const float aspect = float(width_) / float(height_);
  const glm::mat4 proj = glm::perspective(glm::radians(float(cam.fov_y_deg)), aspect,
                                          float(cam.near_m), float(cam.far_m));
  const glm::mat4 view_m = glm::lookAt(glm::vec3(0), glm::vec3(cam.target - eye), glm::vec3(cam.up));
  const glm::mat4 vp = proj * view_m;

  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  glViewport(0, 0, width_, height_);
  glClearColor(kFog.r, kFog.g, kFog.b, 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);

  // Terrain.
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glEnable(GL_CULL_FACE);
  glCullFace(GL_BACK);
  glFrontFace(GL_CCW);
  if (settings.wireframe) glPolygonMode(GL_FRONT_AND_BACK, GL_LINE);
  glUseProgram(terrain_prog_);
  glUniformMatrix4fv(loc(terrain_prog_, "u_view_proj"), 1, GL_FALSE, glm::value_ptr(vp));
  glUniform1f(loc(terrain_prog_, "u_proj_scale"), float(ridgeline::projection_scale(cam)));
  glUniform1f(loc(terrain_prog_, "u_threshold"), float(view.settings().threshold));
  glUniform1i(loc(terrain_prog_, "u_geomorph"), settings.geomorph ? 1 : 0);
  glUniform1i(loc(terrain_prog_, "u_wireframe"), settings.wireframe ? 1 : 0);
  glUniform3fv(loc(terrain_prog_, "u_sun"), 1, glm::value_ptr(kSun));
  glUniform3fv(loc(terrain_prog_, "u_fog_colour"), 1, glm::value_ptr(kFog));
  glUniform1f(loc(terrain_prog_, "u_fog_density"), settings.fog_density);
  glUniform2f(loc(terrain_prog_, "u_height_range"), height_min_, height_max_);
  const int u_offset = loc(terrain_prog_, "u_offset"), u_oy = loc(terrain_prog_, "u_origin_y");
  for (const PatchGpu& p : set) {
    if (p.count == 0) continue;
    glUniform3f(u_offset, float(p.ox - eye.x), float(p.oy - eye.y), float(p.oz - eye.z));
    glUniform1f(u_oy, float(p.oy));
    glBindVertexArray(p.vao);
    glDrawElements(GL_TRIANGLES, p.count, GL_UNSIGNED_INT, nullptr);
    ++st.patches_drawn;
    st.triangles_drawn += p.triangles;
  }
  glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);

  // Vehicles: the body from the physics pose, the wheels at their suspension positions.
  glDisable(GL_CULL_FACE);
  glUseProgram(model_prog_);
  glUniformMatrix4fv(loc(model_prog_, "u_view_proj"), 1, GL_FALSE, glm::value_ptr(vp));
  glUniform3fv(loc(model_prog_, "u_sun"), 1, glm::value_ptr(kSun));
  glUniform3fv(loc(model_prog_, "u_fog_colour"), 1, glm::value_ptr(kFog));
  glUniform1f(loc(model_prog_, "u_fog_density"), settings.fog_density);
  const int u_model = loc(model_prog_, "u_model");
  for (auto& [id, e] : game.vehicles()) {
    auto it = models_.find(e.model);
    if (it == models_.end()) continue;
    const glm::dquat q = e.body.orientation();
    const glm::dmat4 rot = glm::mat4_cast(q);
    glm::dmat4 m = glm::translate(glm::dmat4(1.0), e.body.position() - eye) * rot *
                   glm::translate(glm::dmat4(1.0), -e.body.params().com_in_model);
    glm::mat4 mf(m);
    glUniformMatrix4fv(u_model, 1, GL_FALSE, glm::value_ptr(mf));
    glBindVertexArray(it->second.first.vao);
    glDrawElements(GL_TRIANGLES, it->second.first.count, GL_UNSIGNED_INT, nullptr);
    for (const WheelState& w : e.body.wheels()) {
      glm::dmat4 wm = glm::translate(glm::dmat4(1.0), w.centre - eye) * rot *
                      glm::rotate(glm::dmat4(1.0), w.steer, glm::dvec3(0, 1, 0)) *
                      glm::rotate(glm::dmat4(1.0), w.spin, glm::dvec3(1, 0, 0));
      glm::mat4 wf(wm);
      glUniformMatrix4fv(u_model, 1, GL_FALSE, glm::value_ptr(wf));
      glBindVertexArray(it->second.second.vao);
      glDrawElements(GL_TRIANGLES, it->second.second.count, GL_UNSIGNED_INT, nullptr);
    }
  }
  // Sky last, at the far plane with depth test LEQUAL: only pixels no terrain or vehicle
  // covered run its shader (llvmpipe is fill bound at 1280 x 720).
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LEQUAL);
  glDepthMask(GL_FALSE);
  glDisable(GL_CULL_FACE);
  glUseProgram(sky_prog_);
  const glm::mat4 inv = glm::inverse(vp);
  glUniformMatrix4fv(loc(sky_prog_, "u_inv_view_proj"), 1, GL_FALSE, glm::value_ptr(inv));
  glUniform3fv(loc(sky_prog_, "u_sun"), 1, glm::value_ptr(kSun));
  glUniform3fv(loc(sky_prog_, "u_fog_colour"), 1, glm::value_ptr(kFog));
  glBindVertexArray(sky_vao_);
  glDrawArrays(GL_TRIANGLES, 0, 3);

  glDepthMask(GL_TRUE);
  glDepthFunc(GL_LESS);
  glBindVertexArray(0);
  st.draw_ms = ms_since(t0);
  return st;
}

void Renderer::blit_to_window(int window_w, int window_h) {
  glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
  glBlitFramebuffer(0, 0, width_, height_, 0, 0, window_w, window_h, GL_COLOR_BUFFER_BIT,
                    GL_LINEAR);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
}

std::vector<std::uint8_t> Renderer::read_pixels() const {
  std::vector<std::uint8_t> px(std::size_t(width_) * height_ * 4);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE, px.data());
  // GL rows are bottom-up: flip to top row first.
  const std::size_t row = std::size_t(width_) * 4;
  std::vector<std::uint8_t> tmp(row);
  for (int y = 0; y < height_ / 2; ++y) {
    std::uint8_t* a = px.data() + y * row;
    std::uint8_t* b = px.data() + (height_ - 1 - y) * row;
    std::copy(a, a + row, tmp.data());
    std::copy(b, b + row, a);
    std::copy(tmp.data(), tmp.data() + row, b);
  }
  return px;
}

}  // namespace game
