// GLFW windows (visible or hidden) and EGL surfaceless contexts (Mesa's
// EGL_MESA_platform_surfaceless) for an OpenGL 3.3 core profile.
#define GL_GLEXT_PROTOTYPES 1
#define GLFW_INCLUDE_NONE
#include "gl_context.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/gl.h>
#include <GL/glext.h>
#include <GLFW/glfw3.h>

#include <cstdio>
#include <string>

namespace game {
namespace {
using ridgeline::Error;

std::string glfw_error() {
  const char* d = nullptr;
  glfwGetError(&d);
  return d != nullptr ? d : "unknown GLFW error";
}
}  // namespace

const char* to_string(GlMode mode) noexcept {
  switch (mode) {
    case GlMode::kWindow: return "window";
    case GlMode::kHiddenWindow: return "hidden window";
    default: return "EGL surfaceless";
  }
}

ridgeline::Result<std::unique_ptr<GlContext>> GlContext::create(GlMode mode, int width,
                                                                int height,
                                                                const std::string& title) {
  std::unique_ptr<GlContext> c(new GlContext());
  c->mode_ = mode;
  if (mode == GlMode::kEglSurfaceless) {
    auto get_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
        eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (get_display == nullptr) return Error{"EGL: no eglGetPlatformDisplayEXT"};
    EGLDisplay dpy = get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    EGLint major = 0, minor = 0;
    if (dpy == EGL_NO_DISPLAY || !eglInitialize(dpy, &major, &minor))
      return Error{"EGL: no surfaceless display (Mesa's EGL_MESA_platform_surfaceless)"};
    c->egl_display_ = dpy;
    const EGLint config_attr[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE,
                                  EGL_OPENGL_BIT, EGL_NONE};
    EGLConfig config = nullptr;
    EGLint n = 0;
    if (!eglChooseConfig(dpy, config_attr, &config, 1, &n) || n < 1) {
      // Surfaceless displays may offer configs without surface types.
      const EGLint any[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
      if (!eglChooseConfig(dpy, any, &config, 1, &n) || n < 1)
        return Error{"EGL: no OpenGL config"};
    }
    if (!eglBindAPI(EGL_OPENGL_API)) return Error{"EGL: cannot bind the OpenGL API"};
    const EGLint ctx_attr[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 3,
                               EGL_CONTEXT_OPENGL_PROFILE_MASK,
                               EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    EGLContext ctx = eglCreateContext(dpy, config, EGL_NO_CONTEXT, ctx_attr);
    if (ctx == EGL_NO_CONTEXT) return Error{"EGL: cannot create an OpenGL 3.3 core context"};
    c->egl_context_ = ctx;
    if (!eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx))
      return Error{"EGL: cannot make the context current without a surface"};
    return c;
  }
  if (!glfwInit()) return Error{"GLFW: " + glfw_error()};
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_VISIBLE, mode == GlMode::kWindow ? GLFW_TRUE : GLFW_FALSE);
  c->window_ = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
  if (c->window_ == nullptr) {
    const std::string e = glfw_error();
    glfwTerminate();
    return Error{"GLFW: cannot create a window with an OpenGL 3.3 core context: " + e};
  }
  glfwMakeContextCurrent(c->window_);
  glfwSwapInterval(mode == GlMode::kWindow ? 1 : 0);
  return c;
}

GlContext::~GlContext() {
  if (egl_display_ != nullptr) {
    eglMakeCurrent(egl_display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    if (egl_context_ != nullptr) eglDestroyContext(egl_display_, egl_context_);
    eglTerminate(egl_display_);
  }
  if (window_ != nullptr) {
    glfwDestroyWindow(window_);
    glfwTerminate();
  }
}

void GlContext::present() {
  if (mode_ != GlMode::kWindow) return;
  glfwSwapBuffers(window_);
  glfwPollEvents();
}

bool GlContext::should_close() const {
  return window_ != nullptr && mode_ == GlMode::kWindow && glfwWindowShouldClose(window_);
}

std::string GlContext::description() const {
  const char* r = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const char* v = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  return std::string(r ? r : "?") + ", OpenGL " + (v ? v : "?") + " (" + to_string(mode_) + ")";
}

}  // namespace game
