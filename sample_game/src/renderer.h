// Renderer: draws the game into a framebuffer object with OpenGL 3.3 core: sky, the active
// camera's ROAM mesh (per-patch buffers, re-uploaded only for dirty patches, geomorphs on the
// GPU), vehicles from their glTF meshes. Needs a current context (gl_context.h).
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
};

struct RenderStats {
  std::uint32_t patches_uploaded = 0;  ///< patch buffers re-uploaded this frame
  std::uint32_t patches_drawn = 0;
  std::uint32_t triangles_drawn = 0;   ///< terrain triangles sent to GL (padding excluded)
  double upload_ms = 0, draw_ms = 0;
};

class Renderer {
 public:
  static ridgeline::Result<std::unique_ptr<Renderer>> create(Game& game, int width, int height);
  ~Renderer();

  /// Draws the frame into the framebuffer object and leaves it bound.
  RenderStats draw(Game& game, const RenderSettings& settings);
  /// Copies the framebuffer object to the window's framebuffer (window mode).
  void blit_to_window(int window_w, int window_h);
  /// Reads the framebuffer object's pixels (RGBA8, top row first).
  std::vector<std::uint8_t> read_pixels() const;
  int width() const noexcept { return width_; }
  int height() const noexcept { return height_; }
  unsigned framebuffer() const noexcept { return fbo_; }

 private:
  Renderer() = default;
  struct PatchGpu {
    unsigned vao = 0, vbo = 0, ibo = 0;
    int count = 0;
    double ox = 0, oy = 0, oz = 0;
    std::uint32_t triangles = 0;
  };
  struct MeshGpu {
    unsigned vao = 0, vbo = 0, ibo = 0;
    int count = 0;
  };
  void upload_patch(PatchGpu& gpu, const ridgeline::PatchMesh& mesh);
  MeshGpu upload_model(const ModelMesh& mesh);

  int width_ = 0, height_ = 0;
  float height_min_ = 0, height_max_ = 1;  ///< metres, for the height colouring
  unsigned fbo_ = 0, colour_ = 0, depth_ = 0;
  unsigned terrain_prog_ = 0, sky_prog_ = 0, model_prog_ = 0, sky_vao_ = 0;
  std::vector<PatchGpu> patches_[3];  ///< per camera mode: each view has its own mesh
  bool patches_initialised_[3] = {false, false, false};
  std::map<std::string, std::pair<MeshGpu, MeshGpu>> models_;  ///< body, wheel
};

}  // namespace game
