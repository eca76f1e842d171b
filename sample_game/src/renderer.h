// Renderer: draws the game with OpenGL 3.3 core: the active camera's ROAM mesh (per-patch
// buffers, re-uploaded only for dirty patches, geomorphs on the GPU, shaded by the terrain's
// material map), vehicles from their glTF meshes, the loose bodies (boulders, debris), the sky. The
// scene renders into a framebuffer object at the game's render scale (dynamic resolution) and is
// upscaled into the output framebuffer object at full resolution, where the panel draws and
// screenshots read. Needs a current context (gl_context.h).
//
// For the ROAM core's output (docs/game.md, "Rendering"): every patch upload goes through
// upload_patch() (the dirty ranges of RoamView::take_dirty_patches() with glBufferSubData), the
// MeshVertex attribute layout is set in one place (bind_mesh_vertex_layout in renderer.cpp) and
// the geomorph is one GLSL function shared with its test (geomorph_glsl.h).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <vector>

#include "game.h"
#include "ridgeline/result.h"

namespace game {

struct RenderSettings {
  bool wireframe = false;
  bool geomorph = true;
  float fog_density = 0.0005f;  ///< per metre (exponential fog)
  /// The cheaper fragment path: fog and the light terms per vertex, the fragment shader only
  /// fetches the material colour and blends (docs/game.md, "Where the frame goes").
  bool cheap_fragments = true;
  /// Draw patches nearest first so that depth testing rejects hidden terrain fragments early.
  bool front_to_back = true;
};

struct RenderStats {
  std::uint32_t patches_uploaded = 0;  ///< patches whose buffers changed this frame
  /// Patch buffers (re)allocated this frame with glBufferData (a mesh outgrew its buffer, or a
  /// view's first use); every other change is a glBufferSubData of the dirty ranges.
  std::uint32_t buffers_allocated = 0;
  std::uint32_t patches_drawn = 0;
  std::uint32_t patches_culled = 0;       ///< outside the view frustum: not drawn
  std::uint32_t triangles_drawn = 0;      ///< terrain triangles drawn (degenerate slots excluded)
  std::uint64_t bytes_uploaded = 0;       ///< vertex and index bytes sent to GL this frame
  int scene_width = 0, scene_height = 0;  ///< pixels the scene rendered at (render scale)
  /// Wall milliseconds of the uploads (patch_mesh_ms of it: RoamView::take_dirty_patches, the
  /// core filling in the dirty ranges) and of the draw calls.
  double upload_ms = 0, patch_mesh_ms = 0, draw_ms = 0;
};

class Renderer {
 public:
  static ridgeline::Result<std::unique_ptr<Renderer>> create(Game& game, int width, int height);
  ~Renderer();

  /// Draws the frame (at game.render_scale(), upscaled) into the output framebuffer object and
  /// leaves it bound.
  RenderStats draw(Game& game, const RenderSettings& settings);
  /// Copies the output framebuffer object to the window's framebuffer (window mode).
  void blit_to_window(int window_w, int window_h);
  /// Reads the output framebuffer object's pixels (RGBA8, top row first).
  std::vector<std::uint8_t> read_pixels() const;
  int width() const noexcept { return width_; }
  int height() const noexcept { return height_; }

 private:
  Renderer() = default;
  struct PatchGpu {
    unsigned vao = 0, vbo = 0, ibo = 0;
    int count = 0;
    double ox = 0, oy = 0, oz = 0;
    glm::vec3 lo{0}, hi{0};  ///< patch-local bounding box of the vertices (geomorphs included)
    std::uint32_t triangles = 0;
    std::size_t vertex_capacity = 0, index_capacity = 0;  ///< elements the GL buffers hold
  };
  struct MeshGpu {
    unsigned vao = 0, vbo = 0, ibo = 0;
    int count = 0;
  };
  struct Target {
    unsigned fbo = 0, colour = 0, depth = 0;
  };
  /// Uploads what changed in the patches the view marks dirty (every patch whole on a view's
  /// first use).
  void sync_patches(ridgeline::RoamView& view, std::vector<PatchGpu>& set, bool& initialised,
                    RenderStats& st);
  void upload_patch(PatchGpu& gpu, const ridgeline::PatchMesh& mesh, bool whole, RenderStats& st);
  MeshGpu upload_model(const ModelMesh& mesh);
  ridgeline::Status make_target(Target& t, int w, int h);
  void make_material_texture(const ridgeline::Terrain& terrain);

  int width_ = 0, height_ = 0;
  Target output_, scene_;
  unsigned terrain_prog_ = 0, sky_prog_ = 0, model_prog_ = 0, sky_vao_ = 0;
  unsigned material_tex_ = 0;
  float material_uv_[4] = {0, 0, 1, 1};  ///< u = (x - [0]) * [2], v = (z - [1]) * [3]
  std::vector<PatchGpu> patches_[3];     ///< per camera mode: each view has its own mesh
  bool patches_initialised_[3] = {false, false, false};
  std::vector<std::pair<float, std::uint32_t>> order_;
  std::map<std::string, std::pair<MeshGpu, MeshGpu>> models_;  ///< body, wheel
  MeshGpu boulder_, debris_;  ///< loose bodies: unit sphere (faceted), unit cube
};

}  // namespace game
