// The drawing code shared by the headless and the windowed previewer. Needs a current
// OpenGL 4.5 core context (function pointers through libepoxy).
#pragma once

#include "camera.hpp"
#include "meso/preview/preview.hpp"

#include <epoxy/gl.h>

#include <array>
#include <vector>

namespace meso {

class SurfaceRenderer {
 public:
  SurfaceRenderer(const Mesh& base, const PreviewMaps& maps);
  ~SurfaceRenderer();
  SurfaceRenderer(const SurfaceRenderer&) = delete;
  SurfaceRenderer& operator=(const SurfaceRenderer&) = delete;

  // Draws into the currently bound framebuffer, which must be width x height.
  void draw(const PreviewOptions& options, int width, int height);

  // Height fetches the vertex stages made in the last draw (per-vertex methods: the
  // tessellation levels' edge samples and one per generated vertex; 0 for the others).
  double vertex_stage_fetches() const;

 private:
  void upload_sdf(const Image& sdf, const Image& displacement);
  // k = 0: cone.exr, 1: relaxed-cone.exr.
  void upload_cone(int k, const Image& cone, const Image& displacement);
  void upload_pyramid(const Image& level0, const Image& displacement);
  // DIG-DM's grid target (RG32F colour + depth) of this size.
  void ensure_dig_target(int width, int height);

  const Mesh& base_;
  GLuint program_ = 0, vao_ = 0, vbo_ = 0, ibo_ = 0, height_tex_ = 0, normal_tex_ = 0, sdf_tex_ = 0;
  float sdf_scale_ = 0, sdf_bias_ = 0, sdf_relief_ = 0, sdf_aspect_ = 1, sdf_epsilon_ = 0, sdf_margin_ = 0;
  bool sdf_wrap_ = false;
  // The cone maps (RGB32F, read only with texelFetch): texture, height scale/bias, border.
  std::array<GLuint, 2> cone_tex_{};
  std::array<float, 2> cone_scale_{}, cone_bias_{};
  std::array<bool, 2> cone_wrap_{};
  // The max pyramid: every level's maximum in one R32F texture (read only with texelFetch), at
  // the texel offsets pyramid_offset_ (x, y per level, rows from the top) with sizes pyramid_size_.
  static constexpr int kMaxPyramidLevels = 16;  // surface_common.glsl's u_pyramid_offset
  GLuint pyramid_tex_ = 0;
  int pyramid_levels_ = 0;
  std::vector<GLint> pyramid_offset_, pyramid_size_;
  float pyramid_scale_ = 0, pyramid_bias_ = 0;
  bool pyramid_wrap_ = false;
  GLuint tess_program_ = 0, vertex_work_ = 0;  // per-vertex methods; their fetch counter (SSBO)
  bool last_per_vertex_ = false;
  GLuint dig_fbo_ = 0, dig_tex_ = 0, dig_depth_ = 0;
  int dig_width_ = 0, dig_height_ = 0;
  GLsizei index_count_ = 0;
  float h_min_ = 0, h_max_ = 0;
};

// Index of a method name in preview_methods(); throws UsageError if unknown.
int method_index(const std::string& name);

}  // namespace meso
