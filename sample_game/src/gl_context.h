// GlContext: an OpenGL 3.3 core context in one of three ways: a visible GLFW window, a hidden
// GLFW window (needs an X server, e.g. Xvfb), or EGL surfaceless (no X server at all). Rendering
// always goes into a framebuffer object (renderer.h); the window only shows it.
#pragma once

#include <memory>
#include <string>

#include "ridgeline/result.h"

struct GLFWwindow;

namespace game {

enum class GlMode { kWindow, kHiddenWindow, kEglSurfaceless };
const char* to_string(GlMode mode) noexcept;

class GlContext {
 public:
  /// Creates the context and makes it current on this thread. Errors say what was missing
  /// (no display, no EGL device, GL version).
  static ridgeline::Result<std::unique_ptr<GlContext>> create(GlMode mode, int width, int height,
                                                              const std::string& title);
  ~GlContext();
  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;

  GlMode mode() const noexcept { return mode_; }
  /// The GLFW window (visible or hidden); null with EGL.
  GLFWwindow* window() const noexcept { return window_; }
  /// Window mode: swaps and polls events. Other modes: nothing.
  void present();
  /// True when the user closed the window.
  bool should_close() const;
  /// "Mesa llvmpipe ..., 4.5 core" etc.
  std::string description() const;

 private:
  GlContext() = default;
  GlMode mode_ = GlMode::kWindow;
  GLFWwindow* window_ = nullptr;
  void* egl_display_ = nullptr;
  void* egl_context_ = nullptr;
};

}  // namespace game
