// The drawing code shared by the headless and the windowed previewer. Needs a current
// OpenGL 4.5 core context (function pointers through libepoxy).
#pragma once

#include "camera.hpp"
#include "meso/preview/preview.hpp"

#include <epoxy/gl.h>

#include <array>

namespace meso {

class SurfaceRenderer {
 public:
  SurfaceRenderer(const Mesh& base, const PreviewMaps& maps);
  ~SurfaceRenderer();
  SurfaceRenderer(const SurfaceRenderer&) = delete;
  SurfaceRenderer& operator=(const SurfaceRenderer&) = delete;

  // Draws into the currently bound framebuffer, which must be width x height.
  void draw(const PreviewOptions& options, int width, int height);

 private:
  void upload_sdf(const Image& sdf, const Image& displacement);
  // k = 0: cone.exr, 1: relaxed-cone.exr.
  void upload_cone(int k, const Image& cone, const Image& displacement);

  const Mesh& base_;
  GLuint program_ = 0, vao_ = 0, vbo_ = 0, ibo_ = 0, height_tex_ = 0, normal_tex_ = 0, sdf_tex_ = 0;
  float sdf_scale_ = 0, sdf_bias_ = 0, sdf_relief_ = 0, sdf_aspect_ = 1, sdf_epsilon_ = 0, sdf_margin_ = 0;
  bool sdf_wrap_ = false;
  // The cone maps (RGB32F, read only with texelFetch): texture, height scale/bias, border.
  std::array<GLuint, 2> cone_tex_{};
  std::array<float, 2> cone_scale_{}, cone_bias_{};
  std::array<bool, 2> cone_wrap_{};
  GLsizei index_count_ = 0;
  float h_min_ = 0, h_max_ = 0;
};

// Index of a method name in preview_methods(); throws UsageError if unknown.
int method_index(const std::string& name);

}  // namespace meso
