#include "meso/preview/preview.hpp"

#include "meso/core/error.hpp"
#include "renderer.hpp"

#include <epoxy/egl.h>
#include <epoxy/gl.h>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace meso {

namespace {

void check_maps(const PreviewMaps& maps, const std::string& method) {
  if (maps.displacement.empty() || maps.normal_ts.empty()) throw std::logic_error("preview: maps are empty");
  method_index(method);  // unknown method: UsageError before any OpenGL work
  if (!has_stream(maps, method)) {
    const std::string file = required_stream(method);
    throw UsageError("method " + method + " needs the stream " + file + " (meso streams " + file.substr(0, file.find('.')) +
                     ", then --streams DIR)");
  }
}

bool streams_available(const PreviewMaps& maps, const std::string& method) { return has_stream(maps, method); }

// An OpenGL 4.5 core context without any window system: EGL on Mesa's surfaceless platform
// (llvmpipe when there is no GPU). Rendering goes to a framebuffer object.
class EglContext {
 public:
  EglContext() {
    // Without an EGL vendor that offers platform displays (no Mesa EGL installed), libepoxy
    // aborts the process on the call below: asked first.
    if (!epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_EXT_platform_base") ||
        !epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_MESA_platform_surfaceless"))
      throw InternalError("EGL: no surfaceless platform (is Mesa's libegl-mesa0 installed?)");
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
  // Several previews may live at once (each with its own context): every use makes its own
  // context current first, or it would draw into whichever was made current last.
  void make_current() const {
    if (eglGetCurrentContext() != context_ && !eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_))
      throw InternalError("EGL: cannot make the context current");
  }
  ~EglContext() {
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(display_, context_);
    // No eglTerminate: every preview shares the one surfaceless display (EGL does not count
    // initialisations), and terminating it would invalidate the contexts of the others.
  }
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

 private:
  EGLDisplay display_ = EGL_NO_DISPLAY;
  EGLContext context_ = EGL_NO_CONTEXT;
};

// The driver's limits (llvmpipe: 16384 per side) are a usage error, said as such, not an
// incomplete framebuffer. Needs a current context.
void check_render_size(int w, int h) {
  GLint max_size = 0, max_dims[2] = {0, 0};
  glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_size);
  glGetIntegerv(GL_MAX_VIEWPORT_DIMS, max_dims);
  const int limit = std::min({max_size, max_dims[0], max_dims[1]});
  if (limit > 0 && (w > limit || h > limit))
    throw UsageError("--size " + std::to_string(w) + "x" + std::to_string(h) + ": this OpenGL renders at most " + std::to_string(limit) +
                     " pixels per side");
}

// Float colour targets with depth, bound while alive: attachment 0 RGBA (the image),
// attachment 1 RG (the fetch counts, surface.frag's out_fetches).
class OffscreenTarget {
 public:
  OffscreenTarget(int w, int h) : width_(w), height_(h) {
    check_render_size(w, h);
    glGenFramebuffers(1, &fbo_);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glGenRenderbuffers(3, rb_);
    glBindRenderbuffer(GL_RENDERBUFFER, rb_[0]);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA32F, w, h);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb_[0]);
    glBindRenderbuffer(GL_RENDERBUFFER, rb_[2]);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RG32F, w, h);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_RENDERBUFFER, rb_[2]);
    glBindRenderbuffer(GL_RENDERBUFFER, rb_[1]);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, w, h);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb_[1]);
    const GLenum buffers[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glDrawBuffers(2, buffers);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw InternalError("OpenGL: cannot make a " + std::to_string(w) + "x" + std::to_string(h) +
                          " float framebuffer (about " + std::to_string((28ull * static_cast<unsigned long long>(w) * static_cast<unsigned long long>(h)) >> 20) +
                          " MiB; out of memory, or no float render targets)");
  }
  ~OffscreenTarget() {
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDeleteRenderbuffers(3, rb_);
    glDeleteFramebuffers(1, &fbo_);
  }
  OffscreenTarget(const OffscreenTarget&) = delete;
  OffscreenTarget& operator=(const OffscreenTarget&) = delete;
  int width() const { return width_; }
  int height() const { return height_; }

  // Colour attachment `index` as an Image of `channels` floats, rows from the top.
  Image read(int index, int channels) const {
    Image out(width_, height_, channels);
    std::vector<float> px(out.pixels.size());
    glReadBuffer(index == 0 ? GL_COLOR_ATTACHMENT0 : GL_COLOR_ATTACHMENT1);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, width_, height_, channels == 4 ? GL_RGBA : GL_RG, GL_FLOAT, px.data());
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    // OpenGL's first row is the bottom one; Image's is the top one.
    const size_t row = static_cast<size_t>(width_) * static_cast<size_t>(channels);
    for (int y = 0; y < height_; ++y)
      std::copy_n(px.data() + static_cast<size_t>(height_ - 1 - y) * row, row, out.pixels.data() + static_cast<size_t>(y) * row);
    return out;
  }

 private:
  int width_ = 0, height_ = 0;
  GLuint fbo_ = 0, rb_[3] = {0, 0, 0};
};

}  // namespace

struct HeadlessPreview::Impl {
  // Declaration order is construction order: the context first, destroyed last.
  const PreviewMaps& maps;
  EglContext context;
  std::unique_ptr<SurfaceRenderer> renderer;
  std::unique_ptr<OffscreenTarget> target;

  Impl(const Mesh& base, const PreviewMaps& m) : maps(m) {
    if (maps.displacement.empty() || maps.normal_ts.empty()) throw std::logic_error("preview: maps are empty");
    if (epoxy_gl_version() < 45) throw InternalError("OpenGL 4.5 is not available (got " + std::to_string(epoxy_gl_version()) + ")");
    renderer = std::make_unique<SurfaceRenderer>(base, maps);
  }
  ~Impl() {
    context.make_current();
    target.reset();
    renderer.reset();
  }
  // Binds a target of the options' size, drawn into.
  void draw(const PreviewOptions& o) {
    check_maps(maps, o.method);
    bind_target(o);
    renderer->draw(o, o.width, o.height);
  }
  // Makes the context current with a target of the options' size bound (there is no default
  // framebuffer: every draw, even with rasterisation off, needs one).
  void bind_target(const PreviewOptions& o) {
    context.make_current();
    if (!target || target->width() != o.width || target->height() != o.height) {
      target.reset();
      target = std::make_unique<OffscreenTarget>(o.width, o.height);
    }
  }
};

HeadlessPreview::HeadlessPreview(const Mesh& base, const PreviewMaps& maps) : impl_(std::make_unique<Impl>(base, maps)) {}

HeadlessPreview::~HeadlessPreview() = default;

void HeadlessPreview::check_size(int width, int height) {
  impl_->context.make_current();
  check_render_size(width, height);
}

Image HeadlessPreview::render(const PreviewOptions& o, Image* fetches) {
  impl_->draw(o);
  glFinish();
  Image out = impl_->target->read(0, 4);
  if (fetches) {
    *fetches = impl_->target->read(1, 2);
    // Per-vertex methods fetch in the vertex stages: their count spread evenly over the
    // mesh's pixels.
    const double vertex_fetches = impl_->renderer->vertex_stage_fetches();
    size_t covered = 0;
    for (size_t i = 0; i < fetches->texel_count(); ++i) covered += fetches->pixels[2 * i + 1] > 0.5f;
    if (vertex_fetches > 0 && covered > 0)
      for (size_t i = 0; i < fetches->texel_count(); ++i)
        if (fetches->pixels[2 * i + 1] > 0.5f) fetches->pixels[2 * i] += static_cast<float>(vertex_fetches / static_cast<double>(covered));
  }
  if (glGetError() != GL_NO_ERROR) throw InternalError("OpenGL reported an error while rendering");
  out.metadata["method"] = o.method;
  out.metadata["iterations"] = o.iterations;
  out.metadata["view_angle"] = o.camera.view_angle;
  out.metadata["azimuth"] = o.camera.azimuth;
  return out;
}

double HeadlessPreview::time_draw(const PreviewOptions& o, int repetitions) {
  impl_->draw(o);  // warm-up: shader variants are compiled on first use
  glFinish();
  std::vector<double> ms;
  for (int r = 0; r < std::max(repetitions, 1); ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    impl_->draw(o);
    glFinish();
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  if (glGetError() != GL_NO_ERROR) throw InternalError("OpenGL reported an error while rendering");
  std::sort(ms.begin(), ms.end());
  const size_t n = ms.size();
  return n % 2 ? ms[n / 2] : 0.5 * (ms[n / 2 - 1] + ms[n / 2]);
}

std::vector<Vec3f> HeadlessPreview::dstream_positions(const PreviewOptions& o) {
  impl_->bind_target(o);
  std::vector<Vec3f> out = impl_->renderer->dstream_positions(o);
  if (glGetError() != GL_NO_ERROR) throw InternalError("OpenGL reported an error while capturing the dstream vertices");
  return out;
}

Image render_headless(const Mesh& base, const PreviewMaps& maps, const PreviewOptions& o) {
  check_maps(maps, o.method);  // usage errors before any OpenGL work
  HeadlessPreview preview(base, maps);
  return preview.render(o);
}

namespace {
struct WindowState {
  PreviewOptions options;
  const PreviewMaps* maps;
  bool dragging = false, panning = false;
  double last_x = 0, last_y = 0;
};
}  // namespace

WindowRun run_window(const Mesh& base, const PreviewMaps& maps, const PreviewOptions& initial, int frames) {
  check_maps(maps, initial.method);
  // Larger windows are no use on any screen, and one of 32768 x 32768 aborted inside libxcb
  // (on Xvfb) before a GL limit could be asked.
  constexpr int kMaxWindowSize = 16384;
  if (initial.width > kMaxWindowSize || initial.height > kMaxWindowSize)
    throw UsageError("--size " + std::to_string(initial.width) + "x" + std::to_string(initial.height) + ": a preview window is at most " +
                     std::to_string(kMaxWindowSize) + " pixels per side (render larger frames with --headless)");
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
    if (button == GLFW_MOUSE_BUTTON_LEFT) s->dragging = action == GLFW_PRESS;
    if (button == GLFW_MOUSE_BUTTON_RIGHT || button == GLFW_MOUSE_BUTTON_MIDDLE) s->panning = action == GLFW_PRESS;
    glfwGetCursorPos(w, &s->last_x, &s->last_y);
  });
  glfwSetCursorPosCallback(window, [](GLFWwindow* w, double x, double y) {
    auto* s = static_cast<WindowState*>(glfwGetWindowUserPointer(w));
    if (s->panning) {
      // The mesh follows the cursor: the view's height at the point looked at is about 2.13
      // framing radii / zoom (a 40 degree field of view), pan's unit.
      int width = 0, height = 0;
      glfwGetWindowSize(w, &width, &height);
      const float per_pixel = 2.13f / (s->options.camera.zoom * static_cast<float>(std::max(height, 1)));
      s->options.camera.pan_x -= static_cast<float>(x - s->last_x) * per_pixel;
      s->options.camera.pan_y += static_cast<float>(y - s->last_y) * per_pixel;
    } else if (s->dragging) {
      s->options.camera.azimuth += static_cast<float>(x - s->last_x) * 0.4f;
      s->options.camera.view_angle = std::clamp(s->options.camera.view_angle + static_cast<float>(y - s->last_y) * 0.3f, 0.0f, 89.9f);
    }
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
    if (key == GLFW_KEY_S)  // none -> hard -> soft shadows
      s->options.shadows = static_cast<PreviewShadows>((static_cast<int>(s->options.shadows) + 1) % 3);
    if (key == GLFW_KEY_C) s->options.silhouettes = !s->options.silhouettes;
    if (key == GLFW_KEY_LEFT) s->options.camera.light_azimuth -= 10.0f;
    if (key == GLFW_KEY_RIGHT) s->options.camera.light_azimuth += 10.0f;
    if (key == GLFW_KEY_UP) s->options.camera.light_elevation = std::min(s->options.camera.light_elevation + 5.0f, 90.0f);
    if (key == GLFW_KEY_DOWN) s->options.camera.light_elevation = std::max(s->options.camera.light_elevation - 5.0f, 0.0f);
    if (key == GLFW_KEY_ESCAPE || key == GLFW_KEY_Q) glfwSetWindowShouldClose(w, GLFW_TRUE);
  });
  // The renderer's GL objects go before the window and its context (deleting them without a
  // current context aborted in libepoxy when the window closed).
  struct DestroyWindow {
    GLFWwindow* w;
    ~DestroyWindow() { glfwDestroyWindow(w); }
  } destroy_window{window};
  SurfaceRenderer renderer(base, maps);
  double ms = 0;
  WindowRun run;
  // The last kTimes frame times (a ring: a window left open for hours keeps a bounded buffer).
  constexpr size_t kTimes = 256;
  std::vector<double> times;
  times.reserve(kTimes);
  while (!glfwWindowShouldClose(window)) {
    const auto t0 = std::chrono::steady_clock::now();
    int w = 0, h = 0;
    glfwGetFramebufferSize(window, &w, &h);
    // The on-screen line shows the previous frame's time (this one's is not known yet).
    PreviewOptions frame = state.options;
    frame.status_line = preview_status_line(state.options, ms);
    if (w > 0 && h > 0) renderer.draw(frame, w, h);
    glFinish();
    ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    if (times.size() < kTimes) {
      times.push_back(ms);
    } else {
      times[static_cast<size_t>(run.frames) % kTimes] = ms;
    }
    ++run.frames;
    if (frames > 0 && run.frames >= frames && w > 0 && h > 0) {
      run.last_frame = Image(w, h, 4);
      std::vector<float> rows(static_cast<size_t>(w) * static_cast<size_t>(h) * 4);
      glReadBuffer(GL_BACK);
      glPixelStorei(GL_PACK_ALIGNMENT, 1);
      glReadPixels(0, 0, w, h, GL_RGBA, GL_FLOAT, rows.data());
      const size_t row = static_cast<size_t>(w) * 4;
      for (int y = 0; y < h; ++y)  // GL's rows start at the bottom
        std::copy_n(rows.data() + static_cast<size_t>(h - 1 - y) * row, row, run.last_frame.pixels.data() + static_cast<size_t>(y) * row);
    }
    glfwSetWindowTitle(window, ("meso preview | " + preview_status_line(state.options, ms)).c_str());
    glfwSwapBuffers(window);
    if (frames > 0 && run.frames >= frames) break;
    glfwWaitEventsTimeout(frames > 0 ? 0.0 : 0.1);
  }
  if (!times.empty()) {
    std::nth_element(times.begin(), times.begin() + static_cast<std::ptrdiff_t>(times.size() / 2), times.end());
    run.median_ms = times[times.size() / 2];
  }
  return run;
}

}  // namespace meso
