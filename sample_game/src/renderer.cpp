// OpenGL 3.3 core rendering of the game. Positions are camera-relative floats (the patch origin
// minus the eye, in double, then float) so that large worlds keep their precision.
#define GL_GLEXT_PROTOTYPES 1
#include "renderer.h"

#include <GL/gl.h>
#include <GL/glext.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/mat4x4.hpp>
#include <map>
#include <string>

#include "geomorph_glsl.h"
#include "materials.h"
#include "ridgeline/bench/clock.h"

namespace game {
namespace {

using ridgeline::Error;

// The terrain vertex shader: its version line and declarations, the shared geomorph
// (geomorph_glsl.h), then main(); joined by terrain_vs().
const char* kTerrainVsHead = R"(#version 330 core
// The ROAM core's MeshVertex, as bind_mesh_vertex_layout() feeds it.
layout(location = 0) in vec3 a_pos;     // patch-local position (x, height, z)
layout(location = 1) in vec3 a_nrm;     // smooth vertex normal
layout(location = 2) in vec3 a_morph;   // morph_dy, morph_bound, morph_radius
uniform mat4 u_view_proj;               // camera-relative
uniform vec3 u_offset;                  // patch origin - eye
uniform vec3 u_eye_local;               // eye - patch origin (the geomorph's patch-local eye)
uniform vec4 u_uv;                      // material map: uv = u_uv.xy + a_pos.xz * u_uv.zw
uniform float u_proj_scale;             // pixels per metre at unit distance (output pixels)
uniform float u_morph_threshold;        // pixels: the view's RoamStats::morph_threshold
uniform float u_morph_window;           // the landscape's geomorph().window
uniform float u_morph_delay;            // the landscape's geomorph().delay
uniform int u_geomorph;
uniform int u_cheap;
uniform vec3 u_sun;
uniform float u_fog_density;
out vec3 v_nrm;
out vec2 v_uv;
out float v_dist;
out vec3 v_light;   // cheap path: the light terms per vertex
out float v_fog;    // cheap path: the fog factor per vertex
out float v_rock;   // cheap path: the slope's rock weight per vertex
)";

const char* kTerrainVsMain = R"(
void main() {
  float y = a_pos.y;
  if (u_geomorph != 0)
    y = geomorph_height(a_pos, a_morph, u_eye_local, u_proj_scale, u_morph_threshold,
                        u_morph_window, u_morph_delay);
  vec3 rel = u_offset + vec3(a_pos.x, y, a_pos.z);
  float d = max(length(rel), 1e-3);
  v_nrm = a_nrm;
  v_uv = u_uv.xy + a_pos.xz * u_uv.zw;
  v_dist = d;
  if (u_cheap != 0) {
    vec3 n = normalize(a_nrm);
    float diffuse = max(dot(n, u_sun), 0.0);
    float sky = 0.5 + 0.5 * n.y;
    v_light = 0.85 * diffuse * vec3(1.0, 0.96, 0.88) + 0.32 * sky * vec3(0.6, 0.7, 0.9);
    v_fog = clamp(1.0 - exp(-u_fog_density * d), 0.0, 1.0);
    v_rock = smoothstep(0.10, 0.22, 1.0 - n.y);
  }
  gl_Position = u_view_proj * vec4(rel, 1.0);
}
)";

std::string terrain_vs() {
  return std::string(kTerrainVsHead) + kGeomorphGlsl + kTerrainVsMain;
}

// Albedo from the material map (baked per stored cell: material colour, grass tinted by
// height); rock where the surface is steep (also where edits made it so); one sun, a sky
// ambient term, exponential fog.
const char* kTerrainFs = R"(#version 330 core
in vec3 v_nrm;
in vec2 v_uv;
in float v_dist;
in vec3 v_light;
in float v_fog;
in float v_rock;
uniform sampler2D u_materials;
uniform vec3 u_sun;
uniform vec3 u_fog_colour;
uniform float u_fog_density;
uniform int u_wireframe;
uniform int u_cheap;
out vec4 o_colour;
const vec3 kRock = vec3(0.47, 0.44, 0.42);
void main() {
  vec3 albedo = texture(u_materials, v_uv).rgb;
  vec3 lit;
  float fog;
  if (u_cheap != 0) {
    lit = mix(albedo, kRock, v_rock) * v_light;
    fog = v_fog;
  } else {
    vec3 n = normalize(v_nrm);
    vec3 c = mix(albedo, kRock, smoothstep(0.10, 0.22, 1.0 - n.y));
    float diffuse = max(dot(n, u_sun), 0.0);
    float sky = 0.5 + 0.5 * n.y;
    lit = c * (0.85 * diffuse * vec3(1.0, 0.96, 0.88) + 0.32 * sky * vec3(0.6, 0.7, 0.9));
    fog = clamp(1.0 - exp(-u_fog_density * v_dist), 0.0, 1.0);
  }
  if (u_wireframe != 0) lit = vec3(0.05, 0.08, 0.05) + 0.6 * lit;
  o_colour = vec4(mix(lit, u_fog_colour, fog), 1.0);
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

int loc(unsigned p, const char* n) {
  return glGetUniformLocation(p, n);
}

const glm::vec3 kSun = glm::normalize(glm::vec3(0.45f, 0.6f, 0.35f));
const glm::vec3 kFog(0.70f, 0.78f, 0.86f);

// The MeshVertex attribute layout, in one place (locations as in kTerrainVs).
void bind_mesh_vertex_layout() {
  using V = ridgeline::MeshVertex;
  const GLsizei stride = sizeof(V);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, stride, (void*)offsetof(V, x));
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, stride, (void*)offsetof(V, nx));
  glEnableVertexAttribArray(2);
  glVertexAttribPointer(2, 3, GL_FLOAT, GL_FALSE, stride, (void*)offsetof(V, morph_dy));
  static_assert(offsetof(V, morph_radius) == offsetof(V, morph_dy) + 8, "morph data contiguous");
}

// Deterministic per-cell variation of the albedo (+-6 %): grain near the camera.
float cell_grain(std::uint32_t i, std::uint32_t j) {
  std::uint32_t h = i * 0x8da6b343u ^ j * 0xd8163841u;
  h ^= h >> 13;
  h *= 0x5bd1e995u;
  h ^= h >> 15;
  return 0.94f + 0.12f * float(h & 0xffff) / 65535.0f;
}

// A boulder of unit radius: an icosahedron subdivided twice, each vertex pushed in or out by up to
// 5 % (a deterministic hash), flat-shaded facets in pale weathered stone (bright enough to read
// against the grass in the shadowed side). The physics body is
// the sphere; the facets stay within 5 % of it.
ModelMesh boulder_mesh() {
  const double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<glm::dvec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                               {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                               {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                       {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                       {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                       {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (glm::dvec3& p : v) p = glm::normalize(p);
  for (int level = 0; level < 2; ++level) {
    std::map<std::pair<int, int>, int> mid;
    auto middle = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back(glm::normalize(v[std::size_t(a)] + v[std::size_t(b)]));
      return mid[key] = int(v.size()) - 1;
    };
    std::vector<std::array<int, 3>> g;
    for (const auto& [a, b, c] : f) {
      const int ab = middle(a, b), bc = middle(b, c), ca = middle(c, a);
      g.push_back({a, ab, ca});
      g.push_back({b, bc, ab});
      g.push_back({c, ca, bc});
      g.push_back({ab, bc, ca});
    }
    f = std::move(g);
  }
  for (std::size_t k = 0; k < v.size(); ++k)
    v[k] *= 0.95 + 0.05 * cell_grain(std::uint32_t(k), 7u) / 1.06;
  ModelMesh m;
  for (const auto& tri : f) {
    const glm::dvec3 a = v[std::size_t(tri[0])], b = v[std::size_t(tri[1])],
                     c = v[std::size_t(tri[2])];
    const glm::vec3 n(glm::normalize(glm::cross(b - a, c - a)));
    const float shade =
        0.85f + 0.3f * (cell_grain(std::uint32_t(tri[0]), std::uint32_t(tri[1])) - 0.94f);
    for (const glm::dvec3& p : {a, b, c})
      m.vertices.push_back({float(p.x), float(p.y), float(p.z), n.x, n.y, n.z, 0.72f * shade,
                            0.66f * shade, 0.58f * shade});
  }
  for (std::uint32_t k = 0; k < m.vertices.size(); ++k) m.indices.push_back(k);
  return m;
}

// Debris: a unit cube (half extents 1), timber brown, scaled to a body's half extents.
ModelMesh debris_mesh() {
  ModelMesh m;
  for (int axis = 0; axis < 3; ++axis)
    for (int side = -1; side <= 1; side += 2) {
      glm::vec3 n(0);
      n[axis] = float(side);
      const int u = (axis + 1) % 3, w = (axis + 2) % 3;
      const std::uint32_t base = std::uint32_t(m.vertices.size());
      const float shade = 0.8f + 0.1f * float(axis) + (side > 0 ? 0.05f : 0.0f);
      for (int k = 0; k < 4; ++k) {
        glm::vec3 p = n;
        p[u] = (k & 1) ? 1.0f : -1.0f;
        p[w] = (k & 2) ? 1.0f : -1.0f;
        m.vertices.push_back(
            {p.x, p.y, p.z, n.x, n.y, n.z, 0.55f * shade, 0.40f * shade, 0.26f * shade});
      }
      for (std::uint32_t k : {0u, 1u, 3u, 0u, 3u, 2u}) m.indices.push_back(base + k);
    }
  return m;
}

}  // namespace

ridgeline::Status Renderer::make_target(Target& t, int w, int h) {
  glGenFramebuffers(1, &t.fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, t.fbo);
  glGenRenderbuffers(1, &t.colour);
  glBindRenderbuffer(GL_RENDERBUFFER, t.colour);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, w, h);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, t.colour);
  glGenRenderbuffers(1, &t.depth);
  glBindRenderbuffer(GL_RENDERBUFFER, t.depth);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, w, h);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, t.depth);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    return Error{"renderer: framebuffer object incomplete"};
  return {};
}

void Renderer::make_material_texture(const ridgeline::Terrain& terrain) {
  // One texel per stored cell (its centre at the cell's centre): the material's albedo, grass
  // tinted by height as the ground gets higher (meadow, dry grass), and a little grain.
  const ridgeline::WorldInfo& hf = terrain.info();
  const ridgeline::Surface& surface = terrain.surface();
  const int L = int(surface.detail_levels());
  const std::uint32_t w = hf.width - 1, h = hf.height - 1;
  float lo = 1e30f, hi = -1e30f;
  for (std::uint32_t j = 0; j < hf.height; j += 4)
    for (std::uint32_t i = 0; i < hf.width; i += 4) {
      lo = std::min(lo, surface.stored_height(i, j));
      hi = std::max(hi, surface.stored_height(i, j));
    }
  const float range = std::max(hi - lo, 1.0f);
  auto smooth = [](float a, float b, float x) {
    const float t = std::clamp((x - a) / (b - a), 0.0f, 1.0f);
    return t * t * (3 - 2 * t);
  };
  const glm::vec3 meadow(0.42f, 0.55f, 0.22f), dry(0.58f, 0.53f, 0.33f);
  std::vector<std::uint8_t> rgb(std::size_t(w) * h * 3);
  for (std::uint32_t j = 0; j < h; ++j)
    for (std::uint32_t i = 0; i < w; ++i) {
      const std::uint8_t id =
          surface.cell_material(std::int64_t(i) << L, std::int64_t(j) << L);
      const Material& m = material(id);
      glm::vec3 c(m.albedo[0], m.albedo[1], m.albedo[2]);
      if (id == 0) {
        const float t = (surface.stored_height(i, j) - lo) / range;
        c = glm::mix(c, meadow, smooth(0.15f, 0.35f, t));
        c = glm::mix(c, dry, smooth(0.45f, 0.65f, t));
      }
      c *= cell_grain(i, j);
      for (int k = 0; k < 3; ++k)
        rgb[(std::size_t(j) * w + i) * 3 + k] =
            static_cast<std::uint8_t>(std::clamp(c[k], 0.0f, 1.0f) * 255.0f + 0.5f);
    }
  glGenTextures(1, &material_tex_);
  glBindTexture(GL_TEXTURE_2D, material_tex_);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, GLsizei(w), GLsizei(h), 0, GL_RGB, GL_UNSIGNED_BYTE,
               rgb.data());
  glGenerateMipmap(GL_TEXTURE_2D);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  material_uv_[0] = float(hf.origin_x);
  material_uv_[1] = float(hf.origin_z);
  material_uv_[2] = float(1.0 / (hf.spacing_x * w));
  material_uv_[3] = float(1.0 / (hf.spacing_z * h));
}

ridgeline::Result<std::unique_ptr<Renderer>> Renderer::create(Game& game, int width, int height) {
  std::unique_ptr<Renderer> r(new Renderer());
  r->width_ = width;
  r->height_ = height;
  const std::string terrain_vs_src = terrain_vs();
  auto tp = program(terrain_vs_src.c_str(), kTerrainFs, "terrain");
  if (!tp) return Error{tp.error().message};
  auto sp = program(kSkyVs, kSkyFs, "sky");
  if (!sp) return Error{sp.error().message};
  auto mp = program(kModelVs, kModelFs, "model");
  if (!mp) return Error{mp.error().message};
  r->terrain_prog_ = *tp;
  r->sky_prog_ = *sp;
  r->model_prog_ = *mp;
  glGenVertexArrays(1, &r->sky_vao_);
  if (auto s = r->make_target(r->scene_, width, height); !s) return Error{s.message()};
  if (auto s = r->make_target(r->output_, width, height); !s) return Error{s.message()};
  r->make_material_texture(game.terrain());
  for (const std::string& name : game.model_names()) {
    const VehicleModel* m = game.model(name);
    r->models_[name] = {r->upload_model(m->body), r->upload_model(m->wheel)};
  }
  r->boulder_ = r->upload_model(boulder_mesh());
  r->debris_ = r->upload_model(debris_mesh());
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
  std::vector<MeshGpu*> meshes = {&boulder_, &debris_};
  for (auto& [k, m] : models_) meshes.insert(meshes.end(), {&m.first, &m.second});
  for (MeshGpu* g : meshes) {
    glDeleteVertexArrays(1, &g->vao);
    glDeleteBuffers(1, &g->vbo);
    glDeleteBuffers(1, &g->ibo);
  }
  glDeleteProgram(terrain_prog_);
  glDeleteProgram(sky_prog_);
  glDeleteProgram(model_prog_);
  glDeleteVertexArrays(1, &sky_vao_);
  glDeleteTextures(1, &material_tex_);
  for (Target* t : {&scene_, &output_}) {
    glDeleteRenderbuffers(1, &t->colour);
    glDeleteRenderbuffers(1, &t->depth);
    glDeleteFramebuffers(1, &t->fbo);
  }
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

void Renderer::sync_patches(ridgeline::RoamView& view, std::vector<PatchGpu>& set,
                            bool& initialised, RenderStats& st) {
  const std::uint32_t np = view.landscape().patch_count();
  const auto t0 = ridgeline::bench::Clock::now();
  const std::vector<std::uint32_t> dirty = view.take_dirty_patches();
  st.patch_mesh_ms += ridgeline::bench::ms_since(t0);
  if (!initialised || set.size() != np) {
    // First use of this view: every patch, whole.
    set.assign(np, PatchGpu{});
    for (std::uint32_t p = 0; p < np; ++p) upload_patch(set[p], view.patch_mesh(p), true, st);
    initialised = true;
    return;
  }
  for (std::uint32_t p : dirty)
    if (p < np) upload_patch(set[p], view.patch_mesh(p), false, st);
}

namespace {

// Uploads `ranges` of `data` (elements of `elem` bytes, `per` of them per slot) into the bound
// buffer `target`. Returns the bytes sent.
template <class T>
std::uint64_t upload_ranges(GLenum target, const std::vector<T>& data,
                            const std::vector<ridgeline::MeshRange>& ranges, std::size_t per) {
  std::uint64_t bytes = 0;
  for (const ridgeline::MeshRange& r : ranges) {
    const std::size_t first = std::size_t(r.first) * per;
    const std::size_t count =
        std::min(std::size_t(r.count) * per, data.size() - std::min(first, data.size()));
    if (count == 0) continue;
    glBufferSubData(target, GLintptr(first * sizeof(T)), GLsizeiptr(count * sizeof(T)),
                    data.data() + first);
    bytes += count * sizeof(T);
  }
  return bytes;
}

}  // namespace

// Every patch upload goes through here. The core reuses slots and lists what changed since the
// last take_dirty_patches(): the dirty vertex and triangle ranges go up with glBufferSubData;
// the buffers are allocated anew (glBufferData) only when the mesh outgrew them, and sent whole
// when the core reallocated or compacted its arrays (PatchMesh::resized) or on a view's first
// use. Unused slots and triangles over the padding are degenerate (0, 0, 0): the whole index
// array is drawn.
void Renderer::upload_patch(PatchGpu& gpu, const ridgeline::PatchMesh& mesh, bool whole,
                            RenderStats& st) {
  using V = ridgeline::MeshVertex;
  if (gpu.vao == 0) {
    glGenVertexArrays(1, &gpu.vao);
    glBindVertexArray(gpu.vao);
    glGenBuffers(1, &gpu.vbo);
    glGenBuffers(1, &gpu.ibo);
    glBindBuffer(GL_ARRAY_BUFFER, gpu.vbo);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, gpu.ibo);
    bind_mesh_vertex_layout();
  }
  glBindVertexArray(gpu.vao);
  glBindBuffer(GL_ARRAY_BUFFER, gpu.vbo);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, gpu.ibo);
  const std::size_t nv = mesh.vertices.size(), ni = mesh.indices.size();
  whole = whole || mesh.resized || nv > gpu.vertex_capacity || ni > gpu.index_capacity;
  std::uint64_t bytes = 0;
  // Vertices.
  if (nv > gpu.vertex_capacity) {
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(nv * sizeof(V)), mesh.vertices.data(),
                 GL_DYNAMIC_DRAW);
    gpu.vertex_capacity = nv;
    bytes += nv * sizeof(V);
    ++st.buffers_allocated;
  } else if (whole) {
    if (nv > 0)
      glBufferSubData(GL_ARRAY_BUFFER, 0, GLsizeiptr(nv * sizeof(V)), mesh.vertices.data());
    bytes += nv * sizeof(V);
  } else {
    bytes += upload_ranges(GL_ARRAY_BUFFER, mesh.vertices, mesh.dirty_vertices, 1);
  }
  // Indices (three per triangle slot).
  if (ni > gpu.index_capacity) {
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(ni * 4), mesh.indices.data(), GL_DYNAMIC_DRAW);
    gpu.index_capacity = ni;
    bytes += ni * 4;
    ++st.buffers_allocated;
  } else if (whole) {
    if (ni > 0)
      glBufferSubData(GL_ELEMENT_ARRAY_BUFFER, 0, GLsizeiptr(ni * 4), mesh.indices.data());
    bytes += ni * 4;
  } else {
    bytes += upload_ranges(GL_ELEMENT_ARRAY_BUFFER, mesh.indices, mesh.dirty_triangles, 3);
  }
  glBindVertexArray(0);
  st.bytes_uploaded += bytes;
  ++st.patches_uploaded;
  gpu.count = static_cast<int>(ni);
  gpu.triangles = mesh.triangles;
  gpu.ox = mesh.origin_x;
  gpu.oy = mesh.origin_y;
  gpu.oz = mesh.origin_z;
  // The culling box: patch-local, between each vertex's true and unmorphed height. Whole uploads
  // recompute it; partial ones grow it by the changed vertices (stale slots only enlarge it).
  const auto grow = [&](std::size_t first, std::size_t count) {
    for (std::size_t i = first; i < first + count && i < nv; ++i) {
      const V& v = mesh.vertices[i];
      const glm::vec3 p(v.x, v.y, v.z), q(v.x, v.y + v.morph_dy, v.z);
      gpu.lo = glm::min(gpu.lo, glm::min(p, q));
      gpu.hi = glm::max(gpu.hi, glm::max(p, q));
    }
  };
  if (whole) {
    gpu.lo = glm::vec3(1e30f);
    gpu.hi = glm::vec3(-1e30f);
    grow(0, nv);
  } else {
    for (const ridgeline::MeshRange& r : mesh.dirty_vertices) grow(r.first, r.count);
  }
}

RenderStats Renderer::draw(Game& game, const RenderSettings& settings) {
  RenderStats st;
  const int vi = static_cast<int>(game.rig().mode);
  std::vector<PatchGpu>& set = patches_[vi];
  auto t0 = ridgeline::bench::Clock::now();
  sync_patches(game.active_view(), set, patches_initialised_[vi], st);
  st.upload_ms = ridgeline::bench::ms_since(t0);
  t0 = ridgeline::bench::Clock::now();

  // Dynamic resolution: the scene renders into the lower-left scale x scale part of the scene
  // target and is upscaled; at scale 1 it renders into the output target directly.
  const double scale = std::clamp(game.render_scale(), 0.1, 1.0);
  const int sw = std::max(1, int(std::lround(width_ * scale)));
  const int sh = std::max(1, int(std::lround(height_ * scale)));
  const bool scaled = sw != width_ || sh != height_;
  st.scene_width = sw;
  st.scene_height = sh;

  const ridgeline::Camera cam = game.camera();
  const glm::dvec3 eye = cam.eye;
  const float aspect = float(width_) / float(height_);
  const glm::mat4 proj = glm::perspective(glm::radians(float(cam.fov_y_deg)), aspect,
                                          float(cam.near_m), float(cam.far_m));
  const glm::mat4 view_m =
      glm::lookAt(glm::vec3(0), glm::vec3(cam.target - eye), glm::vec3(cam.up));
  const glm::mat4 vp = proj * view_m;

  glBindFramebuffer(GL_FRAMEBUFFER, scaled ? scene_.fbo : output_.fbo);
  glViewport(0, 0, sw, sh);
  glEnable(GL_SCISSOR_TEST);
  glScissor(0, 0, sw, sh);
  glClearColor(kFog.r, kFog.g, kFog.b, 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glDisable(GL_SCISSOR_TEST);
  glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);

  // Vehicles first: they cover terrain, and early depth tests then skip those terrain pixels.
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

  // Loose bodies: boulders (the faceted sphere) and debris (the cube), at the body's size.
  for (const auto& [id, b] : game.bodies()) {
    const glm::dvec3 p = b.position();
    if (glm::length(p - eye) > 1500) continue;
    const MeshGpu& mesh = b.spec().shape == BodyShape::kSphere ? boulder_ : debris_;
    const glm::dmat4 m = glm::translate(glm::dmat4(1.0), p - eye) *
                         glm::dmat4(glm::mat4_cast(b.orientation())) *
                         glm::scale(glm::dmat4(1.0), b.spec().size);
    const glm::mat4 mf(m);
    glUniformMatrix4fv(u_model, 1, GL_FALSE, glm::value_ptr(mf));
    glBindVertexArray(mesh.vao);
    glDrawElements(GL_TRIANGLES, mesh.count, GL_UNSIGNED_INT, nullptr);
  }

  // Terrain, nearest patches first.
  glEnable(GL_CULL_FACE);
  glCullFace(GL_BACK);
  glFrontFace(GL_CCW);
  if (settings.wireframe) glPolygonMode(GL_FRONT_AND_BACK, GL_LINE);
  glUseProgram(terrain_prog_);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, material_tex_);
  glUniform1i(loc(terrain_prog_, "u_materials"), 0);
  glUniformMatrix4fv(loc(terrain_prog_, "u_view_proj"), 1, GL_FALSE, glm::value_ptr(vp));
  glUniform1f(loc(terrain_prog_, "u_proj_scale"), float(ridgeline::projection_scale(cam)));
  // The geomorph's inputs (geomorph_glsl.h): the threshold the mesh corresponds to and the
  // landscape's morph window and delay.
  const ridgeline::Geomorph geomorph = game.active_view().landscape().geomorph();
  glUniform1f(loc(terrain_prog_, "u_morph_threshold"), float(game.morph_threshold()));
  glUniform1f(loc(terrain_prog_, "u_morph_window"), float(geomorph.window));
  glUniform1f(loc(terrain_prog_, "u_morph_delay"), float(geomorph.delay));
  glUniform1i(loc(terrain_prog_, "u_geomorph"), settings.geomorph ? 1 : 0);
  glUniform1i(loc(terrain_prog_, "u_wireframe"), settings.wireframe ? 1 : 0);
  glUniform1i(loc(terrain_prog_, "u_cheap"), settings.cheap_fragments ? 1 : 0);
  glUniform3fv(loc(terrain_prog_, "u_sun"), 1, glm::value_ptr(kSun));
  glUniform3fv(loc(terrain_prog_, "u_fog_colour"), 1, glm::value_ptr(kFog));
  glUniform1f(loc(terrain_prog_, "u_fog_density"), settings.fog_density);
  const int u_offset = loc(terrain_prog_, "u_offset"), u_uv = loc(terrain_prog_, "u_uv");
  const int u_eye_local = loc(terrain_prog_, "u_eye_local");
  order_.clear();
  const ridgeline::Frustum frustum(cam);
  for (std::uint32_t p = 0; p < set.size(); ++p) {
    const PatchGpu& g = set[p];
    if (g.count == 0) continue;
    const glm::dvec3 origin(g.ox, g.oy, g.oz);
    if (frustum.classify_box(origin + glm::dvec3(g.lo), origin + glm::dvec3(g.hi)) ==
        ridgeline::Frustum::Cull::kOut) {
      ++st.patches_culled;
      continue;
    }
    const double dx = g.ox - eye.x, dz = g.oz - eye.z;
    order_.push_back({settings.front_to_back ? float(dx * dx + dz * dz) : float(p), p});
  }
  std::sort(order_.begin(), order_.end());
  for (const auto& [key, p] : order_) {
    const PatchGpu& g = set[p];
    // Differences in double, then float: precise far from the world's origin.
    glUniform3f(u_offset, float(g.ox - eye.x), float(g.oy - eye.y), float(g.oz - eye.z));
    glUniform3f(u_eye_local, float(eye.x - g.ox), float(eye.y - g.oy), float(eye.z - g.oz));
    glUniform4f(u_uv, float((g.ox - material_uv_[0]) * material_uv_[2]),
                float((g.oz - material_uv_[1]) * material_uv_[3]), material_uv_[2],
                material_uv_[3]);
    glBindVertexArray(g.vao);
    glDrawElements(GL_TRIANGLES, g.count, GL_UNSIGNED_INT, nullptr);
    ++st.patches_drawn;
    st.triangles_drawn += g.triangles;
  }
  glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);

  // Sky last, at the far plane with depth test LEQUAL: only pixels no terrain or vehicle
  // covered run its shader.
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

  if (scaled) {  // upscale into the output target (bilinear)
    glBindFramebuffer(GL_READ_FRAMEBUFFER, scene_.fbo);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, output_.fbo);
    glBlitFramebuffer(0, 0, sw, sh, 0, 0, width_, height_, GL_COLOR_BUFFER_BIT, GL_LINEAR);
  }
  glBindFramebuffer(GL_FRAMEBUFFER, output_.fbo);
  glViewport(0, 0, width_, height_);
  st.draw_ms = ridgeline::bench::ms_since(t0);
  return st;
}

void Renderer::blit_to_window(int window_w, int window_h) {
  glBindFramebuffer(GL_READ_FRAMEBUFFER, output_.fbo);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
  glBlitFramebuffer(0, 0, width_, height_, 0, 0, window_w, window_h, GL_COLOR_BUFFER_BIT,
                    GL_LINEAR);
  glBindFramebuffer(GL_FRAMEBUFFER, output_.fbo);
}

std::vector<std::uint8_t> Renderer::read_pixels() const {
  std::vector<std::uint8_t> px(std::size_t(width_) * height_ * 4);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, output_.fbo);
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
