// The Dear ImGui debug panel: LOD, budget and frame figures, camera and render toggles, physics,
// script errors with their tracebacks, the script log, reload. Folded until asked for (F2).
#pragma once

#include <cstdint>
#include <deque>

#include "game.h"
#include "renderer.h"

struct GLFWwindow;

namespace game {

struct PanelInput {
  double frame_ms = 0;
  RenderStats render{};
};

class Panel {
 public:
  /// `window` may be null (offscreen: the display size is set by hand, no input).
  Panel(GLFWwindow* window, int width, int height);
  ~Panel();
  Panel(const Panel&) = delete;
  Panel& operator=(const Panel&) = delete;
  /// Builds and renders the panel into the bound framebuffer.
  void draw(Game& game, RenderSettings& settings, const PanelInput& in, double dt_s);
  /// True when ImGui wants the keyboard (a text field has focus).
  bool wants_keyboard() const;
  /// The panel starts folded (its title bar alone: "Ridgeline - F2: debug panel"); F2 (main.cpp)
  /// or a click on the title bar unfolds it.
  void toggle() noexcept { toggle_ = true; }
  void set_open(bool open) noexcept { open_ = open, apply_ = true; }
  bool open() const noexcept { return open_; }

 private:
  GLFWwindow* window_;
  int width_, height_;
  std::deque<float> frame_history_;
  std::uint64_t last_generated_ = 0;    // detail tiles generated up to the last frame
  bool open_ = false;                   // unfolded (the last frame's state)
  bool toggle_ = false, apply_ = true;  // fold state to force at the next frame
};

}  // namespace game
