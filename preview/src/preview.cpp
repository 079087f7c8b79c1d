#include "meso/preview/preview.hpp"

#include "meso/core/error.hpp"
#include "renderer.hpp"

#include <epoxy/egl.h>
#include <epoxy/gl.h>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <chrono>
#include <cstdio>
#include <string>

namespace meso {

namespace {

void check_maps(const PreviewMaps& maps, const std::string& method) {
  if (maps.displacement.empty() || maps.normal_ts.empty()) throw std::logic_error("preview: maps are empty");
  method_index(method);  // unknown method: UsageError before any OpenGL work
  const Image* stream = stream_for(maps, method);
  if (stream && stream->empty()) {
    const std::string file = required_stream(method);
    const std::string what = method == "sphere-tracing" ? "the distance field " : "the cone map ";
    throw UsageError("method " + method + " needs " + what + file + " (meso streams " + file.substr(0, file.size() - 4) +
                     ", then --streams DIR)");
  }
}

bool streams_available(const PreviewMaps& maps, const std::string& method) {
  const Image* stream = stream_for(maps, method);
  return !stream || !stream->empty();
}

// An OpenGL 4.5 core context without any window system: EGL on Mesa's surfaceless platform
// (llvmpipe when there is no GPU). Rendering goes to a framebuffer object.
class EglContext {
 public:
  EglContext() {
    display_ = eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (display_ == EGL_NO_DISPLAY) throw InternalError("EGL: no surfaceless display (is Mesa's libegl-mesa0 installed?)");
    EGLint major = 0, minor = 0;
    if (!eglInitialize(display_, &major, &minor)) throw InternalError("EGL: cannot initialise the surfaceless display");
    if (!eglBindAPI(EGL_OPENGL_API)) throw InternalError("EGL: OpenGL API not available");
    const EGLint attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                              EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    context_ = eglCreateContext(display_, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, attribs);
    if (context_ == EGL_NO_CONTEXT) throw InternalError("EGL: cannot create an OpenGL 4.5 core context");
    if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_))
      throw InternalError("EGL: cannot make the context current");
  }
  ~EglContext() {
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(display_, context_);
    eglTerminate(display_);
  }
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

 private:
  EGLDisplay display_ = EGL_NO_DISPLAY;
  EGLContext context_ = EGL_NO_CONTEXT;
};

// A float RGBA colour target with depth, bound while alive.
class OffscreenTarget {
 public:
  OffscreenTarget(int w, int h) {
    glGenFramebuffers(1, &fbo_);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glGenRenderbuffers(2, rb_);
    glBindRenderbuffer(GL_RENDERBUFFER, rb_[0]);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA32F, w, h);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb_[0]);
    glBindRenderbuffer(GL_RENDERBUFFER, rb_[1]);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, w, h);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb_[1]);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw InternalError("OpenGL: float framebuffer is not supported");
  }
  ~OffscreenTarget() {
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDeleteRenderbuffers(2, rb_);
    glDeleteFramebuffers(1, &fbo_);
  }
  OffscreenTarget(const OffscreenTarget&) = delete;
  OffscreenTarget& operator=(const OffscreenTarget&) = delete;

 private:
  GLuint fbo_ = 0, rb_[2] = {0, 0};
};

}  // namespace

Image render_headless(const Mesh& base, const PreviewMaps& maps, const PreviewOptions& o) {
  check_maps(maps, o.method);
  EglContext context;
  if (epoxy_gl_version() < 45) throw InternalError("OpenGL 4.5 is not available (got " + std::to_string(epoxy_gl_version()) + ")");
  Image out(o.width, o.height, 4);
  {
    OffscreenTarget target(o.width, o.height);
    SurfaceRenderer renderer(base, maps);
    renderer.draw(o, o.width, o.height);
    glFinish();
    std::vector<float> px(out.pixels.size());
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, o.width, o.height, GL_RGBA, GL_FLOAT, px.data());
    // OpenGL's first row is the bottom one; Image's is the top one.
    const size_t row = static_cast<size_t>(o.width) * 4;
    for (int y = 0; y < o.height; ++y)
      std::copy_n(px.data() + static_cast<size_t>(o.height - 1 - y) * row, row, out.pixels.data() + static_cast<size_t>(y) * row);
    if (glGetError() != GL_NO_ERROR) throw InternalError("OpenGL reported an error while rendering");
  }
  out.metadata["method"] = o.method;
  out.metadata["iterations"] = o.iterations;
  out.metadata["view_angle"] = o.camera.view_angle;
  out.metadata["azimuth"] = o.camera.azimuth;
  return out;
}

namespace {
struct WindowState {
  PreviewOptions options;
  const PreviewMaps* maps;
  bool dragging = false;
  double last_x = 0, last_y = 0;
};
}  // namespace

void run_window(const Mesh& base, const PreviewMaps& maps, const PreviewOptions& initial) {
  check_maps(maps, initial.method);
  if (!glfwInit()) throw InternalError("no display for a preview window (use --headless --png FILE)");
  struct Terminate {
    ~Terminate() { glfwTerminate(); }
  } terminate;
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  GLFWwindow* window = glfwCreateWindow(initial.width, initial.height, "meso preview", nullptr, nullptr);
  if (!window) throw InternalError("cannot open an OpenGL 4.5 window (use --headless --png FILE)");
  glfwMakeContextCurrent(window);
  glfwSwapInterval(1);
  WindowState state{initial, &maps, false, 0, 0};
  glfwSetWindowUserPointer(window, &state);
  glfwSetMouseButtonCallback(window, [](GLFWwindow* w, int button, int action, int) {
    auto* s = static_cast<WindowState*>(glfwGetWindowUserPointer(w));
    if (button == GLFW_MOUSE_BUTTON_LEFT) {
      s->dragging = action == GLFW_PRESS;
      glfwGetCursorPos(w, &s->last_x, &s->last_y);
    }
  });
  glfwSetCursorPosCallback(window, [](GLFWwindow* w, double x, double y) {
    auto* s = static_cast<WindowState*>(glfwGetWindowUserPointer(w));
    if (!s->dragging) return;
    s->options.camera.azimuth += static_cast<float>(x - s->last_x) * 0.4f;
    s->options.camera.view_angle = std::clamp(s->options.camera.view_angle + static_cast<float>(y - s->last_y) * 0.3f, 0.0f, 89.9f);
    s->last_x = x;
    s->last_y = y;
  });
  glfwSetScrollCallback(window, [](GLFWwindow* w, double, double dy) {
    auto* s = static_cast<WindowState*>(glfwGetWindowUserPointer(w));
    s->options.camera.zoom = std::clamp(s->options.camera.zoom * static_cast<float>(std::pow(1.1, dy)), 0.1f, 50.0f);
  });
  glfwSetKeyCallback(window, [](GLFWwindow* w, int key, int, int action, int mods) {
    if (action == GLFW_RELEASE) return;
    auto* s = static_cast<WindowState*>(glfwGetWindowUserPointer(w));
    const auto& methods = preview_methods();
    // 1-9 and 0 choose one of the first ten methods, Tab (Shift+Tab) the next (previous)
    // one; methods whose streams were not given are skipped.
    int pick = -1;
    if (key >= GLFW_KEY_1 && key <= GLFW_KEY_9) pick = key - GLFW_KEY_1;
    if (key == GLFW_KEY_0) pick = 9;
    if (pick >= 0 && static_cast<size_t>(pick) < methods.size() && streams_available(*s->maps, methods[static_cast<size_t>(pick)]))
      s->options.method = methods[static_cast<size_t>(pick)];
    if (key == GLFW_KEY_TAB) {
      const int count = static_cast<int>(methods.size()), delta = (mods & GLFW_MOD_SHIFT) ? count - 1 : 1;
      int k = method_index(s->options.method);
      for (int n = 0; n < count; ++n) {
        k = (k + delta) % count;
        if (streams_available(*s->maps, methods[static_cast<size_t>(k)])) break;
      }
      s->options.method = methods[static_cast<size_t>(k)];
    }
    if (key == GLFW_KEY_EQUAL || key == GLFW_KEY_KP_ADD) s->options.iterations = std::min(s->options.iterations * 2, 1024);
    if (key == GLFW_KEY_MINUS || key == GLFW_KEY_KP_SUBTRACT) s->options.iterations = std::max(s->options.iterations / 2, 1);
    if (key == GLFW_KEY_ESCAPE || key == GLFW_KEY_Q) glfwSetWindowShouldClose(w, GLFW_TRUE);
  });
  SurfaceRenderer renderer(base, maps);
  while (!glfwWindowShouldClose(window)) {
    const auto t0 = std::chrono::steady_clock::now();
    int w = 0, h = 0;
    glfwGetFramebufferSize(window, &w, &h);
    if (w > 0 && h > 0) renderer.draw(state.options, w, h);
    glFinish();
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    char title[256];
    std::snprintf(title, sizeof title, "meso preview | %s | %d iterations | view %.1f deg | %.2f ms",
                  state.options.method.c_str(), state.options.iterations, static_cast<double>(state.options.camera.view_angle), ms);
    glfwSetWindowTitle(window, title);
    glfwSwapBuffers(window);
    glfwWaitEventsTimeout(0.1);
  }
  glfwDestroyWindow(window);
}

}  // namespace meso
