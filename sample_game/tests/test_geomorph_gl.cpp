// The terrain vertex shader's geomorph (geomorph_glsl.h) against the ROAM core's
// ridgeline::morphed_height() on the CPU: the GLSL function runs on the real GL driver (Mesa
// llvmpipe) through transform feedback, over the vertices of real ROAM meshes and over made-up
// vertices that reach every branch (the clamp at both ends, patch corners, the data border, no
// morph window, a delay). Exit 77 (ctest: skipped) when no OpenGL context can be made.
#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "geomorph_glsl.h"
#include "gl_context.h"
#include "ridgeline/heightfield.h"
#include "ridgeline/landscape.h"
#include "ridgeline/roam_view.h"
#include "ridgeline/terrain.h"

namespace {

using ridgeline::MeshVertex;

// Evaluates geomorph_height() for each vertex with one eye (patch-local), k, tau, w and delta, by
// transform feedback; returns the heights, or an empty vector with the error in `err`.
class GpuGeomorph {
 public:
  std::string init() {
    const std::string vs = std::string("#version 330 core\n") +
                           "layout(location = 0) in vec3 a_pos;\n"
                           "layout(location = 2) in vec3 a_morph;\n"
                           "uniform vec3 u_eye; uniform float u_k, u_tau, u_w, u_delta;\n"
                           "out float o_height;\n" +
                           game::kGeomorphGlsl +
                           "void main() {\n"
                           "  o_height = geomorph_height(a_pos, a_morph, u_eye, u_k, u_tau, u_w, u_delta);\n"
                           "  gl_Position = vec4(0.0, 0.0, 0.0, 1.0);\n"
                           "}\n";
    const char* src = vs.c_str();
    const GLuint sh = glCreateShader(GL_VERTEX_SHADER);
    glShaderSource(sh, 1, &src, nullptr);
    glCompileShader(sh);
    GLint ok = 0;
    char log[2048] = {};
    glGetShaderiv(sh, GL_COMPILE_STATUS, &ok);
    if (!ok) {
      glGetShaderInfoLog(sh, sizeof log, nullptr, log);
      return std::string("compile: ") + log;
    }
    prog_ = glCreateProgram();
    glAttachShader(prog_, sh);
    const char* varyings[] = {"o_height"};
    glTransformFeedbackVaryings(prog_, 1, varyings, GL_INTERLEAVED_ATTRIBS);
    glLinkProgram(prog_);
    glDeleteShader(sh);
    glGetProgramiv(prog_, GL_LINK_STATUS, &ok);
    if (!ok) {
      glGetProgramInfoLog(prog_, sizeof log, nullptr, log);
      return std::string("link: ") + log;
    }
    glGenVertexArrays(1, &vao_);
    glGenBuffers(1, &vbo_);
    glGenBuffers(1, &tfo_);
    // A complete framebuffer to draw into (EGL surfaceless has no default one), as the game.
    glGenRenderbuffers(1, &rbo_);
    glBindRenderbuffer(GL_RENDERBUFFER, rbo_);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, 4, 4);
    glGenFramebuffers(1, &fbo_);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rbo_);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      return "framebuffer incomplete";
    return {};
  }
  ~GpuGeomorph() {
    glDeleteBuffers(1, &vbo_);
    glDeleteBuffers(1, &tfo_);
    glDeleteVertexArrays(1, &vao_);
    glDeleteProgram(prog_);
    glDeleteFramebuffers(1, &fbo_);
    glDeleteRenderbuffers(1, &rbo_);
  }

  std::vector<float> run(const std::vector<MeshVertex>& v, const glm::vec3& eye, float k, float tau,
                         const ridgeline::Geomorph& g) {
    glUseProgram(prog_);
    glUniform3f(glGetUniformLocation(prog_, "u_eye"), eye.x, eye.y, eye.z);
    glUniform1f(glGetUniformLocation(prog_, "u_k"), k);
    glUniform1f(glGetUniformLocation(prog_, "u_tau"), tau);
    glUniform1f(glGetUniformLocation(prog_, "u_w"), float(g.window));
    glUniform1f(glGetUniformLocation(prog_, "u_delta"), float(g.delay));
    glBindVertexArray(vao_);
    glBindBuffer(GL_ARRAY_BUFFER, vbo_);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(v.size() * sizeof(MeshVertex)), v.data(),
                 GL_STREAM_DRAW);
    // The renderer's layout (bind_mesh_vertex_layout): position, and the three morph floats.
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(MeshVertex),
                          (void*)offsetof(MeshVertex, x));
    glEnableVertexAttribArray(2);
    glVertexAttribPointer(2, 3, GL_FLOAT, GL_FALSE, sizeof(MeshVertex),
                          (void*)offsetof(MeshVertex, morph_dy));
    glBindBuffer(GL_TRANSFORM_FEEDBACK_BUFFER, tfo_);
    glBufferData(GL_TRANSFORM_FEEDBACK_BUFFER, GLsizeiptr(v.size() * 4), nullptr, GL_STREAM_READ);
    glBindBufferBase(GL_TRANSFORM_FEEDBACK_BUFFER, 0, tfo_);
    glEnable(GL_RASTERIZER_DISCARD);
    glBeginTransformFeedback(GL_POINTS);
    glDrawArrays(GL_POINTS, 0, GLsizei(v.size()));
    glEndTransformFeedback();
    glDisable(GL_RASTERIZER_DISCARD);
    std::vector<float> out(v.size());
    glGetBufferSubData(GL_TRANSFORM_FEEDBACK_BUFFER, 0, GLsizeiptr(out.size() * 4), out.data());
    glBindVertexArray(0);
    EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
    return out;
  }

 private:
  GLuint prog_ = 0, vao_ = 0, vbo_ = 0, tfo_ = 0, fbo_ = 0, rbo_ = 0;
};

GpuGeomorph* g_gpu = nullptr;

// Tolerance: the shader computes in float, the CPU in double from the same floats.
void expect_same(const std::vector<MeshVertex>& v, const std::vector<float>& gpu,
                 const glm::vec3& eye, double k, double tau, const ridgeline::Geomorph& g,
                 int* morphing) {
  ASSERT_EQ(gpu.size(), v.size());
  for (std::size_t i = 0; i < v.size(); ++i) {
    const float cpu = ridgeline::morphed_height(v[i], eye, k, tau, g);
    const double tol = 1e-5 * (std::fabs(v[i].y) + std::fabs(v[i].morph_dy)) + 1e-5;
    ASSERT_NEAR(gpu[i], cpu, tol) << "vertex " << i << " y " << v[i].y << " dy " << v[i].morph_dy
                                  << " bound " << v[i].morph_bound << " radius "
                                  << v[i].morph_radius << " tau " << tau << " w " << g.window
                                  << " delta " << g.delay;
    const float t = ridgeline::morph_factor(v[i], eye, k, tau, g);
    if (t > 0.01f && t < 0.99f && std::fabs(v[i].morph_dy) > 0.01f) ++*morphing;
  }
}

TEST(GeomorphGl, TheShaderMatchesMorphedHeightOnMadeUpVertices) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> pos(0, 256), h(-50, 300), dy(-4, 4), mu(0, 6), r(0, 30);
  std::vector<MeshVertex> v;
  for (int i = 0; i < 4000; ++i) {
    MeshVertex m{};
    m.x = pos(rng);
    m.y = h(rng);
    m.z = pos(rng);
    m.morph_dy = dy(rng);
    m.morph_bound = mu(rng);
    m.morph_radius = r(rng);
    if (i % 97 == 0) m.morph_bound = FLT_MAX;   // a patch corner: never morphs
    if (i % 89 == 0) m.morph_radius = FLT_MAX;  // the data border: never morphs
    v.push_back(m);
  }
  int morphing = 0;
  const glm::vec3 eyes[] = {{128, 120, 128}, {-300, 400, 50}, {60, 5, 200}};
  for (const glm::vec3& eye : eyes)
    for (double tau : {1.0, 2.0, 6.0})
      for (const ridgeline::Geomorph g : {ridgeline::Geomorph{0.5, 0.1}, ridgeline::Geomorph{0.0, 0.0},
                                          ridgeline::Geomorph{2.0, 0.0}, ridgeline::Geomorph{0.3, 0.6}}) {
        const double k = 623.5;  // 720 px high, 60 degrees
        expect_same(v, g_gpu->run(v, eye, float(k), float(tau), g), eye, k, tau, g, &morphing);
      }
  EXPECT_GT(morphing, 1000) << "vertices in the middle of their morph were compared";
}

TEST(GeomorphGl, TheShaderMatchesMorphedHeightOnARoamMesh) {
  auto hf = ridgeline::make_default_heightfield({.size = 257, .spacing = 2.0, .seed = 11});
  ASSERT_TRUE(hf);
  auto terrain = ridgeline::Terrain::create(std::move(hf).value()).value();
  auto land = ridgeline::Landscape::create(terrain, {.patch_exponent = 5});
  ASSERT_TRUE(land) << land.error().message;
  auto view = ridgeline::RoamView::create(land.value(), {.threshold = 2.0});
  ASSERT_TRUE(view);
  ridgeline::Camera cam;
  cam.viewport = {1280, 720};
  cam.fov_y_deg = 60;
  cam.eye = {150, 120, 40};
  cam.target = {260, 40, 300};
  // The camera moves, so the mesh carries vertices in every state of their morph.
  auto stats = (*view)->converge(cam);
  ASSERT_TRUE(stats);
  cam.eye += glm::dvec3(20, -10, 30);
  cam.target += glm::dvec3(20, 0, 30);
  const double k = ridgeline::projection_scale(cam);
  const double tau = stats->morph_threshold;
  const ridgeline::Geomorph g = land.value()->geomorph();
  ASSERT_GT(tau, 0);
  ASSERT_GT(g.window, 0);
  ASSERT_GT(g.delay, 0);
  int morphing = 0;
  for (std::uint32_t p = 0; p < land.value()->patch_count(); ++p) {
    const ridgeline::PatchMesh& m = (*view)->patch_mesh(p);
    if (m.vertices.empty()) continue;
    // As the renderer: the eye minus the patch origin in double, then float.
    const glm::vec3 eye(float(cam.eye.x - m.origin_x), float(cam.eye.y - m.origin_y),
                        float(cam.eye.z - m.origin_z));
    expect_same(m.vertices, g_gpu->run(m.vertices, eye, float(k), float(tau), g), eye, k, tau, g,
                &morphing);
  }
  EXPECT_GT(morphing, 20) << "mesh vertices in the middle of their morph were compared";
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  auto ctx = game::GlContext::create(game::GlMode::kEglSurfaceless, 64, 64, "geomorph test");
  if (!ctx) ctx = game::GlContext::create(game::GlMode::kHiddenWindow, 64, 64, "geomorph test");
  if (!ctx) {
    std::printf("no OpenGL context (%s): skipped\n", ctx.error().message.c_str());
    return 77;
  }
  GpuGeomorph gpu;
  if (std::string e = gpu.init(); !e.empty()) {
    std::printf("geomorph shader: %s\n", e.c_str());
    return 1;
  }
  g_gpu = &gpu;
  const int rc = RUN_ALL_TESTS();
  g_gpu = nullptr;
  return rc;
}
