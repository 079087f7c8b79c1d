// The drawing code shared by the headless and the windowed previewer. Needs a current
// OpenGL 4.5 core context (function pointers through libepoxy).
#pragma once

#include "camera.hpp"
#include "status_line.hpp"
#include "meso/bake/tangent_frame.hpp"
#include "meso/preview/preview.hpp"

#include <epoxy/gl.h>

#include <array>
#include <initializer_list>
#include <memory>
#include <vector>

namespace meso {

// One shader stage from its pieces, concatenated in order (the first starts with #version).
// Throws InternalError with the compiler's log.
GLuint compile(GLenum type, std::initializer_list<const char*> pieces);

// Links the compiled stages into a program (and deletes the stages); `feedback`: a vertex
// output to capture with transform feedback. Throws InternalError with the linker's log.
GLuint link(std::initializer_list<GLuint> stages, const char* feedback = nullptr);

class SurfaceRenderer {
 public:
  SurfaceRenderer(const Mesh& base, const PreviewMaps& maps);
  ~SurfaceRenderer();
  SurfaceRenderer(const SurfaceRenderer&) = delete;
  SurfaceRenderer& operator=(const SurfaceRenderer&) = delete;

  // Draws into the currently bound framebuffer, which must be width x height.
  void draw(const PreviewOptions& options, int width, int height);

  // Height fetches the vertex stages made in the last draw (per-vertex methods: the
  // tessellation levels' edge samples and one per generated vertex; dstream: one stream read
  // per vertex invocation; 0 for the others).
  double vertex_stage_fetches() const;

  // The dstream method's vertex positions for `options` (its level and morph), captured by
  // transform feedback, in the level's vertex order. Empty without a stream.
  std::vector<Vec3f> dstream_positions(const PreviewOptions& options);

 private:
  void upload_sdf(const Image& sdf, const Image& displacement);
  // k = 0: cone.exr, 1: relaxed-cone.exr.
  void upload_cone(int k, const Image& cone, const Image& displacement);
  void upload_pyramid(const Image& level0, const Image& displacement);
  // DIG-DM's grid target (RG32F colour + depth) of this size.
  void ensure_dig_target(int width, int height);
  void upload_vdm(const PreviewMaps& maps);
  void upload_dstream(const Mesh& base, const EncodedStream& stream, const std::vector<TangentFrame>& frames);
  // The dstream level `options` draws (the finest whose segments do not exceed the iteration
  // budget); sets the vertex shader's uniforms and binds its buffers. -1 without a stream.
  int bind_dstream(const PreviewOptions& options, const CameraPose& pose);

  const Mesh& base_;
  std::unique_ptr<StatusLine> status_line_;  // made on first use
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
  GLuint face_jacobians_ = 0;  // SSBO: dp/du, dp/dv per base face (per-pixel methods' ray frame)
  bool last_per_vertex_ = false;
  GLuint dig_fbo_ = 0, dig_tex_ = 0, dig_depth_ = 0;
  int dig_width_ = 0, dig_height_ = 0;
  // View-dependent displacement: the weights (RGBA32F array, 4 components per layer), the mean
  // and basis (R32F, texelFetch), the direction sampling.
  GLuint vdm_weights_tex_ = 0, vdm_basis_tex_ = 0;
  int vdm_rank_ = 0, vdm_theta_ = 0, vdm_phi_ = 0;
  float vdm_theta_max_ = 0, vdm_relief_ = 0, vdm_scale_ = 0, vdm_bias_ = 0, vdm_aspect_ = 1;
  std::vector<float> vdm_curvatures_;
  bool vdm_wrap_ = false;
  // dstream: its program, the base triangles' corners (SSBO), per level the vertices (SSBO)
  // and the small triangles' indices, an attribute-less vertex array, the capture buffer.
  GLuint dstream_program_ = 0, dstream_vao_ = 0, dstream_corners_ = 0, dstream_capture_ = 0;
  std::vector<GLuint> dstream_vertices_, dstream_indices_;
  std::vector<GLsizei> dstream_vertex_count_, dstream_index_count_;
  std::vector<int> dstream_segments_;
  float dstream_min_ = 0, dstream_max_ = 0;
  GLsizei index_count_ = 0;
  // The mesh method's patches where an edge spans more texels than GL's 64 segments: every
  // base triangle cut into k x k (see the constructor); 0 and k = 1 when none is needed.
  GLuint mesh_vao_ = 0, mesh_vbo_ = 0, mesh_ibo_ = 0;
  GLsizei mesh_index_count_ = 0;
  int mesh_subdivision_ = 1;
  float h_min_ = 0, h_max_ = 0;

 public:
  // k of the mesh method's k x k cut of every base triangle (1: none).
  int mesh_subdivision() const { return mesh_subdivision_; }
};

// The previewer's limits on vdm.exr (uniform arrays in vdm.glsl).
inline constexpr int kMaxVdmRank = 64;
inline constexpr int kMaxVdmCurvatures = 64;

// Index of a method name in preview_methods(); throws UsageError if unknown.
int method_index(const std::string& name);

}  // namespace meso
