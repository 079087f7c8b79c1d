#include "renderer.hpp"

#include "meso/bake/tangent_frame.hpp"
#include "meso/core/error.hpp"
#include "meso/core/mesh_arrays.hpp"
#include "sampling.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace meso {

namespace shaders {
extern const char* const surface_vert;
extern const char* const surface_frag;
}  // namespace shaders

const std::vector<std::string>& preview_methods() {
  // The order is the shader's method numbering (surface.frag).
  static const std::vector<std::string> names{"bump",   "parallax", "offset-limited", "slope",         "iterative-parallax", "steep",
                                              "relief", "pom",      "cone",           "relaxed-cone", "sphere-tracing"};
  return names;
}

namespace {
// A numeric header attribute of a stream file written by `producer`.
float stream_number(const Image& stream, const char* key, const std::string& name, const char* producer = "meso streams sdf") {
  const auto it = stream.metadata.find(key);
  if (it == stream.metadata.end()) throw InputError(name, std::string("lacks the meso:") + key + " attribute of " + producer);
  if (const int* i = std::get_if<int>(&it->second)) return static_cast<float>(*i);
  if (const float* f = std::get_if<float>(&it->second)) return *f;
  throw InputError(name, std::string("meso:") + key + " is not a number");
}

// The height range a stream was normalised with must be the displacement's own.
void check_height_range(const Image& stream, const Image& displacement, const std::string& name, const char* producer) {
  float lo = displacement.pixels[0], hi = lo;
  for (size_t i = 0; i < displacement.texel_count(); ++i) {
    const float v = displacement.pixels[i * static_cast<size_t>(displacement.channels)];
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  const float bias = stream_number(stream, "height_bias", name, producer), scale = stream_number(stream, "height_scale", name, producer);
  const float tol = 1e-6f * std::max({std::abs(lo), std::abs(hi), 1e-30f});
  if (std::abs(bias - lo) > tol || std::abs(bias + scale - hi) > tol * 4)
    throw InputError(name, "was made from another height map (its height range differs from displacement.exr's)");
}

std::string string_attribute(const Image& img, const char* key) {
  const auto it = img.metadata.find(key);
  if (it == img.metadata.end()) return "";
  const std::string* s = std::get_if<std::string>(&it->second);
  return s ? *s : "";
}
}  // namespace

bool maps_tile(const PreviewMaps& maps) {
  for (const Image* stream : {&maps.sdf, &maps.cone, &maps.relaxed_cone})
    if (!stream->empty() && string_attribute(*stream, "border") == "wrap") return true;
  return false;
}

void check_sdf_matches(const Image& sdf, const Image& displacement, const std::string& name) {
  const int depth = static_cast<int>(stream_number(sdf, "depth", name));
  if (depth < 1 || sdf.height % depth != 0 || sdf.width != displacement.width || sdf.height / depth != displacement.height)
    throw InputError(name, "its size does not match displacement.exr (made from another height map?)");
  check_height_range(sdf, displacement, name, "meso streams sdf");
}

void check_cone_matches(const Image& cone, const Image& displacement, const std::string& kind, const std::string& name) {
  const char* producer = kind == "relaxed" ? "meso streams relaxed-cone" : "meso streams cone";
  const std::string found = string_attribute(cone, "cone_kind");
  if (found.empty()) throw InputError(name, std::string("lacks the meso:cone_kind attribute of ") + producer);
  if (found != kind)
    throw InputError(name, "is a " + found + " cone map; this method needs a " + kind + " one (" + producer + ")");
  if (cone.channels < 3) throw InputError(name, "needs 3 channels (height, cone ratio, apex height)");
  if (cone.width != displacement.width || cone.height != displacement.height)
    throw InputError(name, "its size does not match displacement.exr (made from another height map?)");
  // Ratios are stored in units of u: texels_per_u must be the width the shader multiplies by.
  if (cone.metadata.count("texels_per_u") && static_cast<int>(stream_number(cone, "texels_per_u", name, producer)) != cone.width)
    throw InputError(name, "its meso:texels_per_u differs from its width");
  check_height_range(cone, displacement, name, producer);
}

void check_stream_matches(const std::string& method, const Image& stream, const Image& displacement, const std::string& name) {
  if (method == "sphere-tracing") check_sdf_matches(stream, displacement, name);
  if (method == "cone") check_cone_matches(stream, displacement, "conservative", name);
  if (method == "relaxed-cone") check_cone_matches(stream, displacement, "relaxed", name);
}

std::string required_stream(const std::string& method) {
  if (method == "sphere-tracing") return "sdf.exr";
  if (method == "cone") return "cone.exr";
  if (method == "relaxed-cone") return "relaxed-cone.exr";
  return "";
}

const Image* stream_for(const PreviewMaps& maps, const std::string& method) {
  if (method == "sphere-tracing") return &maps.sdf;
  if (method == "cone") return &maps.cone;
  if (method == "relaxed-cone") return &maps.relaxed_cone;
  return nullptr;
}

Image* stream_for(PreviewMaps& maps, const std::string& method) {
  return const_cast<Image*>(stream_for(static_cast<const PreviewMaps&>(maps), method));
}

int method_index(const std::string& name) {
  const auto& m = preview_methods();
  const auto it = std::find(m.begin(), m.end(), name);
  if (it == m.end()) throw UsageError("unknown preview method '" + name + "' (see --list-methods)");
  return static_cast<int>(it - m.begin());
}

namespace {

GLuint compile(GLenum type, const char* src) {
  const GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &src, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[4096];
    glGetShaderInfoLog(s, sizeof log, nullptr, log);
    throw InternalError(std::string("preview shader does not compile: ") + log);
  }
  return s;
}

GLuint upload_texture(const Image& img, int channels) {
  // Image rows are top row first; OpenGL's first row is v = 0 (bottom): flip on upload so
  // texture(s, uv) uses meso's UV convention directly.
  std::vector<float> rows(static_cast<size_t>(img.width) * static_cast<size_t>(img.height) * static_cast<size_t>(channels));
  for (int y = 0; y < img.height; ++y) {
    for (int x = 0; x < img.width; ++x) {
      for (int c = 0; c < channels; ++c) {
        rows[(static_cast<size_t>(img.height - 1 - y) * static_cast<size_t>(img.width) + static_cast<size_t>(x)) * static_cast<size_t>(channels) + static_cast<size_t>(c)] =
            img.at(x, y, std::min(c, img.channels - 1));
      }
    }
  }
  GLuint tex = 0;
  glGenTextures(1, &tex);
  glBindTexture(GL_TEXTURE_2D, tex);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  const GLenum internal = channels == 1 ? GL_R32F : GL_RGB32F;
  const GLenum format = channels == 1 ? GL_RED : GL_RGB;
  glTexImage2D(GL_TEXTURE_2D, 0, static_cast<GLint>(internal), img.width, img.height, 0, format, GL_FLOAT, rows.data());
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  return tex;
}

}  // namespace

SurfaceRenderer::SurfaceRenderer(const Mesh& base, const PreviewMaps& maps) : base_(base) {
  // Per-corner vertices: the same frames the baker encoded with.
  Mesh m = base;
  const auto frames = compute_tangent_frames(m);
  store_tangents(m, frames);
  const CornerSplit split = split_corners(m);
  constexpr size_t kStride = 3 + 3 + 2 + 4 + 2;
  std::vector<float> verts(split.corner.size() * kStride);
  for (size_t i = 0; i < split.corner.size(); ++i) {
    const auto h = split.corner[i];
    const auto v = m.to_vertex_handle(h);
    const auto& fr = frames[static_cast<size_t>(h.idx())];
    const Vec3f p = m.point(v), nv = m.normal(v);
    const Vec2f uv = m.texcoord2D(h);
    float* o = &verts[i * kStride];
    const float values[kStride] = {p[0], p[1], p[2], nv[0], nv[1], nv[2], uv[0], uv[1],
                                   fr.tangent[0], fr.tangent[1], fr.tangent[2], fr.sign, fr.du_length, fr.dv_length};
    std::copy(values, values + kStride, o);
  }
  index_count_ = static_cast<GLsizei>(split.triangles.size());

  const GLuint vs = compile(GL_VERTEX_SHADER, shaders::surface_vert);
  const GLuint fs = compile(GL_FRAGMENT_SHADER, shaders::surface_frag);
  program_ = glCreateProgram();
  glAttachShader(program_, vs);
  glAttachShader(program_, fs);
  glLinkProgram(program_);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(program_, GL_LINK_STATUS, &ok);
  if (!ok) throw InternalError("preview shaders do not link");

  glGenVertexArrays(1, &vao_);
  glBindVertexArray(vao_);
  glGenBuffers(1, &vbo_);
  glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(verts.size() * sizeof(float)), verts.data(), GL_STATIC_DRAW);
  const GLint sizes[5] = {3, 3, 2, 4, 2};
  size_t offset = 0;
  for (GLuint a = 0; a < 5; ++a) {
    glEnableVertexAttribArray(a);
    glVertexAttribPointer(a, sizes[a], GL_FLOAT, GL_FALSE, static_cast<GLsizei>(kStride * sizeof(float)),
                          reinterpret_cast<const void*>(offset * sizeof(float)));
    offset += static_cast<size_t>(sizes[a]);
  }
  glGenBuffers(1, &ibo_);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo_);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(split.triangles.size() * sizeof(uint32_t)),
               split.triangles.data(), GL_STATIC_DRAW);
  glBindVertexArray(0);

  height_tex_ = upload_texture(maps.displacement, 1);
  normal_tex_ = upload_texture(maps.normal_ts, 3);
  if (!maps.sdf.empty()) upload_sdf(maps.sdf, maps.displacement);
  if (!maps.cone.empty()) upload_cone(0, maps.cone, maps.displacement);
  if (!maps.relaxed_cone.empty()) upload_cone(1, maps.relaxed_cone, maps.displacement);
  const auto& px = maps.displacement.pixels;
  if (!px.empty()) {
    const auto [lo, hi] = std::minmax_element(px.begin(), px.end());
    h_min_ = std::min(*lo, 0.0f);
    h_max_ = std::max(*hi, 0.0f);
  }
}

void SurfaceRenderer::upload_sdf(const Image& sdf, const Image& displacement) {
  check_sdf_matches(sdf, displacement, "sdf.exr");
  auto number = [&](const char* key) { return stream_number(sdf, key, "sdf.exr"); };
  const int depth = static_cast<int>(number("depth"));
  sdf_relief_ = number("relief");
  sdf_scale_ = number("height_scale");
  sdf_bias_ = number("height_bias");
  sdf_aspect_ = static_cast<float>(displacement.height) / static_cast<float>(displacement.width);
  sdf_epsilon_ = 0.25f / static_cast<float>(displacement.width);  // a quarter texel, units of u
  {
    const double tx = 1.0 / displacement.width, tz = static_cast<double>(sdf_relief_) / depth;
    sdf_margin_ = static_cast<float>(std::sqrt(2 * tx * tx + tz * tz));  // voxel diagonal, units of u
  }
  const bool wrap = string_attribute(sdf, "border") == "wrap";
  sdf_wrap_ = wrap;
  // Slices in rows [k H, (k+1) H) top row first; GL rows bottom first within each slice.
  const int w = sdf.width, h = sdf.height / depth;
  std::vector<float> voxels(sdf.pixels.size());
  for (int k = 0; k < depth; ++k)
    for (int y = 0; y < h; ++y)
      std::copy_n(sdf.texel(0, k * h + y), w, &voxels[(static_cast<size_t>(k) * static_cast<size_t>(h) + static_cast<size_t>(h - 1 - y)) * static_cast<size_t>(w)]);
  glGenTextures(1, &sdf_tex_);
  glBindTexture(GL_TEXTURE_3D, sdf_tex_);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage3D(GL_TEXTURE_3D, 0, GL_R32F, w, h, depth, 0, GL_RED, GL_FLOAT, voxels.data());
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  const GLint wrap_mode = wrap ? GL_REPEAT : GL_CLAMP_TO_EDGE;
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_WRAP_S, wrap_mode);
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_WRAP_T, wrap_mode);
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_WRAP_R, GL_CLAMP_TO_EDGE);
}

void SurfaceRenderer::upload_cone(int k, const Image& cone, const Image& displacement) {
  const bool relaxed = k == 1;
  const std::string name = relaxed ? "relaxed-cone.exr" : "cone.exr";
  check_cone_matches(cone, displacement, relaxed ? "relaxed" : "conservative", name);
  const size_t i = static_cast<size_t>(k);
  cone_scale_[i] = stream_number(cone, "height_scale", name);
  cone_bias_[i] = stream_number(cone, "height_bias", name);
  cone_wrap_[i] = string_attribute(cone, "border") == "wrap";
  // Rows flipped as every 2D map (GL row 0 = image row H-1); the shader reads texels with
  // texelFetch only (a filtered cone ratio is not a cone of anything), so filtering is off.
  cone_tex_[i] = upload_texture(cone, 3);
  glBindTexture(GL_TEXTURE_2D, cone_tex_[i]);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
}

SurfaceRenderer::~SurfaceRenderer() {
  glDeleteTextures(2, cone_tex_.data());
  glDeleteTextures(1, &sdf_tex_);
  glDeleteTextures(1, &height_tex_);
  glDeleteTextures(1, &normal_tex_);
  glDeleteBuffers(1, &vbo_);
  glDeleteBuffers(1, &ibo_);
  glDeleteVertexArrays(1, &vao_);
  glDeleteProgram(program_);
}

void SurfaceRenderer::draw(const PreviewOptions& o, int width, int height) {
  const CameraPose pose = frame_camera(base_, o.camera, static_cast<float>(width) / static_cast<float>(height));
  glViewport(0, 0, width, height);
  glClearColor(0, 0, 0, 0);
  glClearDepth(1.0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  // The flat tangent sign comes from a triangle's first corner, the corner the baker uses.
  glProvokingVertex(GL_FIRST_VERTEX_CONVENTION);
  glUseProgram(program_);
  glUniformMatrix4fv(glGetUniformLocation(program_, "u_view_projection"), 1, GL_FALSE, pose.view_projection.data());
  glUniform3f(glGetUniformLocation(program_, "u_eye"), pose.eye[0], pose.eye[1], pose.eye[2]);
  glUniform3f(glGetUniformLocation(program_, "u_light"), pose.light[0], pose.light[1], pose.light[2]);
  glUniform1i(glGetUniformLocation(program_, "u_method"), method_index(o.method));
  glUniform1i(glGetUniformLocation(program_, "u_iterations"), o.iterations);
  glUniform1i(glGetUniformLocation(program_, "u_shade"), static_cast<int>(o.shade));
  glUniform1f(glGetUniformLocation(program_, "u_h_min"), h_min_);
  glUniform1f(glGetUniformLocation(program_, "u_h_max"), h_max_);
  const int cone = o.method == "cone" ? 0 : o.method == "relaxed-cone" ? 1 : -1;
  const bool stream_missing = o.method == "sphere-tracing" ? !sdf_tex_ : cone >= 0 && !cone_tex_[static_cast<size_t>(cone)];
  if (stream_missing) throw UsageError("method " + o.method + " needs the stream " + required_stream(o.method) + " (meso streams)");
  // Streams and shaders agree on the border (height_field.hpp): a tiling field makes the
  // height and normal maps tile too. A method with a stream follows its stream; the others
  // tile when any loaded stream does.
  const bool wrap = o.method == "sphere-tracing" ? sdf_wrap_
                    : cone >= 0                  ? cone_wrap_[static_cast<size_t>(cone)]
                                                 : (sdf_tex_ && sdf_wrap_) || (cone_tex_[0] && cone_wrap_[0]) || (cone_tex_[1] && cone_wrap_[1]);
  const GLint wrap_mode = wrap ? GL_REPEAT : GL_CLAMP_TO_EDGE;
  for (GLuint tex : {height_tex_, normal_tex_}) {
    glBindTexture(GL_TEXTURE_2D, tex);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, wrap_mode);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, wrap_mode);
  }
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, height_tex_);
  glUniform1i(glGetUniformLocation(program_, "u_height"), 0);
  glActiveTexture(GL_TEXTURE1);
  glBindTexture(GL_TEXTURE_2D, normal_tex_);
  glUniform1i(glGetUniformLocation(program_, "u_normal"), 1);
  glActiveTexture(GL_TEXTURE2);
  glBindTexture(GL_TEXTURE_3D, sdf_tex_);
  glUniform1i(glGetUniformLocation(program_, "u_sdf"), 2);
  glUniform1f(glGetUniformLocation(program_, "u_sdf_scale"), sdf_scale_);
  glUniform1f(glGetUniformLocation(program_, "u_sdf_bias"), sdf_bias_);
  glUniform1f(glGetUniformLocation(program_, "u_sdf_relief"), sdf_relief_);
  glUniform1f(glGetUniformLocation(program_, "u_sdf_aspect"), sdf_aspect_);
  glUniform1f(glGetUniformLocation(program_, "u_sdf_epsilon"), sdf_epsilon_);
  glUniform1f(glGetUniformLocation(program_, "u_sdf_margin"), sdf_margin_);
  const size_t c = cone >= 0 ? static_cast<size_t>(cone) : 0;
  glActiveTexture(GL_TEXTURE3);
  glBindTexture(GL_TEXTURE_2D, cone_tex_[c]);
  glUniform1i(glGetUniformLocation(program_, "u_cone"), 3);
  glUniform1f(glGetUniformLocation(program_, "u_cone_scale"), cone_scale_[c]);
  glUniform1f(glGetUniformLocation(program_, "u_cone_bias"), cone_bias_[c]);
  glUniform1i(glGetUniformLocation(program_, "u_cone_wrap"), cone_wrap_[c] ? 1 : 0);
  glBindVertexArray(vao_);
  glDrawElements(GL_TRIANGLES, index_count_, GL_UNSIGNED_INT, nullptr);
  glBindVertexArray(0);
}

}  // namespace meso
