#include "renderer.hpp"

#include "meso/bake/tangent_frame.hpp"
#include "meso/core/error.hpp"
#include "meso/bake/curvature.hpp"
#include "meso/core/mesh_arrays.hpp"
#include "meso/formats/image_io.hpp"
#include "meso/streams/height_field.hpp"
#include "meso/streams/pyramid.hpp"
#include "meso/streams/vdm.hpp"
#include "sampling.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <initializer_list>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace meso {

namespace shaders {
extern const char* const surface_vert;
extern const char* const surface_common_glsl;
extern const char* const footprint_glsl;
extern const char* const cone_stepping_glsl;
extern const char* const pyramid_glsl;
extern const char* const sphere_tracing_glsl;
extern const char* const dig_glsl;
extern const char* const vdm_glsl;
extern const char* const dstream_vert;
extern const char* const tess_vert;
extern const char* const tess_tesc;
extern const char* const tess_tese;
extern const char* const surface_frag;
}  // namespace shaders

const std::vector<std::string>& preview_methods() {
  // The order is the shader's method numbering (surface.frag).
  static const std::vector<std::string> names{"mesh",         "tessellation", "bump",  "parallax", "offset-limited",
                                              "slope",        "iterative-parallax", "steep", "relief", "pom",
                                              "cone",         "relaxed-cone", "pyramid", "sphere-tracing", "dig",
                                              "vdm",          "dstream"};
  return names;
}

namespace {
// A numeric header attribute of a stream file written by `producer`.
float stream_number(const Image& stream, const char* key, const std::string& name, const char* producer = "meso streams sdf") {
  const auto it = stream.metadata.find(key);
  if (it == stream.metadata.end()) throw InputError(name, std::string("lacks the meso:") + key + " attribute of " + producer);
  if (const int* i = std::get_if<int>(&it->second)) return static_cast<float>(*i);
  if (const float* f = std::get_if<float>(&it->second)) {
    // Every number meso writes in a stream header is finite and none is negative.
    if (!std::isfinite(*f) || (*f < 0.0f && std::string(key) != "height_bias"))
      throw InputError(name, std::string("meso:") + key + " is " + std::to_string(*f) + ", not a value " + producer + " writes");
    return *f;
  }
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

std::string string_attribute(const Image& img, const char* key);

// A stream made from another height map with the same range passes check_height_range: its
// own heights must also be this map's. `holds(texel, x, y, h, footprint)` says whether the
// stream's texel (x, y) of level 0 fits the displacement there: h its normalised height,
// footprint the exact minimum and maximum of its filtered surface over the texel
// (footprint_min_max, with the stream's meso:border), i.e. pyramid.exr's level 0 as this map
// makes it. The tolerance covers what quantisation between the two files can change: --half
// values (at most 2^-12 near 1) and streams made from bake's 8-bit displacement.png (1/510);
// a map whose heights differ by more than 1/256 of the range at some texel is another map.
constexpr float kStreamHeightTolerance = 1.0f / 256.0f;
template <typename Holds>
void check_stream_heights(const Image& stream, const Image& displacement, const std::string& name, Holds holds) {
  const Border border = string_attribute(stream, "border") == "wrap" ? Border::wrap : Border::clamp;
  const HeightField field = make_height_field(displacement, border);
  const Image footprint = footprint_min_max(field);
  const size_t channels = static_cast<size_t>(stream.channels), w = static_cast<size_t>(displacement.width);
  for (size_t i = 0; i < field.height.texel_count(); ++i)
    if (!holds(&stream.pixels[i * channels], i % w, i / w, field.height.pixels[i], &footprint.pixels[2 * i]))
      throw InputError(name, "the height at texel (" + std::to_string(i % w) + ", " + std::to_string(i / w) +
                                 ") differs from displacement.exr's (made from another height map?)");
}

std::string string_attribute(const Image& img, const char* key) {
  const auto it = img.metadata.find(key);
  if (it == img.metadata.end()) return "";
  const std::string* s = std::get_if<std::string>(&it->second);
  return s ? *s : "";
}

// The first texel of `stream` (level 0) whose channels break what its producer guarantees
// (`ok` on the texel's channel values), named in the error: streams whose values contradict
// their definition (ratios above the cap, a minimum above the maximum, negative distances)
// had been drawn without a word.
template <typename Ok>
void check_stream_values(const Image& stream, const std::string& name, const char* what, Ok ok) {
  const size_t channels = static_cast<size_t>(stream.channels);
  for (size_t i = 0; i < stream.texel_count(); ++i)
    if (!ok(&stream.pixels[i * channels]))
      throw InputError(name, "texel (" + std::to_string(i % static_cast<size_t>(stream.width)) + ", " +
                                 std::to_string(i / static_cast<size_t>(stream.width)) + ") breaks " + what);
}
}  // namespace

bool maps_tile(const PreviewMaps& maps) {
  for (const Image* stream : {&maps.sdf, &maps.cone, &maps.relaxed_cone, &maps.pyramid, &maps.vdm_weights})
    if (!stream->empty() && string_attribute(*stream, "border") == "wrap") return true;
  return false;
}

void check_sdf_matches(const Image& sdf, const Image& displacement, const std::string& name) {
  const int depth = static_cast<int>(stream_number(sdf, "depth", name));
  if (depth < 1 || sdf.height % depth != 0 || sdf.width != displacement.width || sdf.height / depth != displacement.height)
    throw InputError(name, "its size does not match displacement.exr (made from another height map?)");
  if (sdf.channels != 1) throw InputError(name, "needs 1 channel (the distance): is it meso streams sdf's output?");
  if (!(stream_number(sdf, "relief", name) > 0)) throw InputError(name, "its meso:relief is not a height range > 0");
  check_stream_values(sdf, name, "a distance field's values (distances >= 0)", [](const float* v) { return v[0] >= 0; });
  check_height_range(sdf, displacement, name, "meso streams sdf");
  // Per column (x, y), with top the maximum of the filtered surface over the texel's
  // footprint (the solid's top there): voxels whose centre lies below it are inside (0);
  // those above are outside, at least min(1/2 texel, their height above it) away (other
  // columns are half a texel away at least), which is checked where that stays above half's
  // smallest normal number (a --half file rounds distances down).
  const size_t w = static_cast<size_t>(sdf.width), rows = static_cast<size_t>(displacement.height);
  const float relief = stream_number(sdf, "relief", name);
  check_stream_heights(sdf, displacement, name, [&](const float*, size_t x, size_t y, float, const float* footprint) {
    const float top = footprint[1];
    for (int k = 0; k < depth; ++k) {
      const float z = (static_cast<float>(k) + 0.5f) / static_cast<float>(depth);
      const float d = sdf.pixels[(static_cast<size_t>(k) * rows + y) * w + x];
      if (z < top - kStreamHeightTolerance && d != 0.0f) return false;
      const float away = std::min(0.5f / static_cast<float>(w), (z - top - kStreamHeightTolerance) * relief);
      if (away > 6.2e-5f && !(d > 0.0f)) return false;
    }
    return true;
  });
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
  const float cap = cone.metadata.count("ratio_cap") ? stream_number(cone, "ratio_cap", name, producer) : std::numeric_limits<float>::max();
  check_stream_values(cone, name, "a cone map's values (height in [0, 1], ratio in [0, meso:ratio_cap], apex >= height)",
                      [cap](const float* v) { return v[0] >= 0 && v[0] <= 1 && v[1] >= 0 && v[1] <= cap && v[2] >= v[0]; });
  check_height_range(cone, displacement, name, producer);
  // R is the texel's normalised height (the surface the cone methods trace), B its footprint's maximum.
  check_stream_heights(cone, displacement, name, [](const float* v, size_t, size_t, float h, const float* footprint) {
    return std::abs(v[0] - h) <= kStreamHeightTolerance && std::abs(v[2] - footprint[1]) <= kStreamHeightTolerance;
  });
}

void check_pyramid_matches(const Image& pyramid, const Image& displacement, const std::string& name) {
  if (pyramid.channels != 2) throw InputError(name, "needs 2 channels (min, max): is it meso streams pyramid's output?");
  if (pyramid.width != displacement.width || pyramid.height != displacement.height)
    throw InputError(name, "its size does not match displacement.exr (made from another height map?)");
  check_stream_values(pyramid, name, "a min-max pyramid's values (0 <= min <= max <= 1)",
                      [](const float* v) { return v[0] >= 0 && v[0] <= v[1] && v[1] <= 1; });
  check_height_range(pyramid, displacement, name, "meso streams pyramid");
  // Level 0 holds the extremes over each texel's footprint.
  check_stream_heights(pyramid, displacement, name, [](const float* v, size_t, size_t, float, const float* footprint) {
    return std::abs(v[0] - footprint[0]) <= kStreamHeightTolerance && std::abs(v[1] - footprint[1]) <= kStreamHeightTolerance;
  });
}

void check_stream_matches(const std::string& method, const Image& stream, const Image& displacement, const std::string& name) {
  if (method == "sphere-tracing") check_sdf_matches(stream, displacement, name);
  if (method == "cone") check_cone_matches(stream, displacement, "conservative", name);
  if (method == "relaxed-cone") check_cone_matches(stream, displacement, "relaxed", name);
  if (method == "pyramid") check_pyramid_matches(stream, displacement, name);
}

std::vector<float> vdm_curvatures(const Image& weights, const std::string& name) {
  std::vector<float> out;
  std::stringstream list(string_attribute(weights, "curvatures"));
  std::string item;
  while (std::getline(list, item, ',')) {
    char* end = nullptr;
    const float c = std::strtof(item.c_str(), &end);
    if (end == item.c_str() || !std::isfinite(c)) throw InputError(name, "has a meso:curvatures list that is not numbers");
    out.push_back(c);
  }
  if (out.empty()) throw InputError(name, "lacks the meso:curvatures attribute of meso streams vdm");
  if (std::adjacent_find(out.begin(), out.end(), std::greater_equal<float>()) != out.end())
    throw InputError(name, "its curvatures are not in strictly increasing order");
  return out;
}

void check_vdm_matches(const Image& weights, const Image& basis, const Image& displacement, const std::string& name) {
  const char* producer = "meso streams vdm";
  if (weights.width != displacement.width || weights.height != displacement.height)
    throw InputError(name, "its size does not match displacement.exr (made from another height map?)");
  const int theta = static_cast<int>(stream_number(weights, "theta", name, producer));
  const int phi = static_cast<int>(stream_number(weights, "phi", name, producer));
  const int rank = static_cast<int>(stream_number(weights, "rank", name, producer));
  const float theta_max = stream_number(weights, "theta_max", name, producer), relief = stream_number(weights, "relief", name, producer);
  const size_t curvatures = vdm_curvatures(weights, name).size();
  if (theta < 1 || phi < 1 || !(theta_max > 0 && theta_max <= 90) || !(relief > 0))
    throw InputError(name, "has an invalid direction sampling or relief in its metadata");
  if (rank > kMaxVdmRank || curvatures > kMaxVdmCurvatures)
    throw InputError(name, "has rank " + std::to_string(rank) + " and " + std::to_string(curvatures) + " curvatures; the previewer takes at most " +
                               std::to_string(kMaxVdmRank) + " and " + std::to_string(kMaxVdmCurvatures) + " (meso streams vdm --max-rank)");
  if (weights.channels != std::max(rank, 1) || basis.width != rank + 1 ||
      static_cast<size_t>(basis.height) != static_cast<size_t>(theta) * static_cast<size_t>(phi) * curvatures)
    throw InputError(name, "its parts' sizes do not match its rank and direction sampling");
  check_height_range(weights, displacement, name, producer);
}

std::string vdm_relief_mismatch(const Image& weights, const Mesh& base, const std::string& name) {
  const float relief = stream_number(weights, "relief", name, "meso streams vdm");
  const float scale = stream_number(weights, "height_scale", name, "meso streams vdm");
  const double per_u = object_length_per_uv(base);
  if (!(per_u > 0) || !(scale > 0)) return "";
  const double expected = vdm_relief_on_mesh(scale, per_u);
  if (std::abs(relief / expected - 1.0) <= 0.01) return "";
  std::ostringstream text;
  text.precision(4);
  text << name << ": made for a relief of " << relief << " units of u, but its height range on this mesh is " << expected << " (make it with --mesh)";
  return text.str();
}

std::string required_stream(const std::string& method) {
  if (method == "sphere-tracing") return "sdf.exr";
  if (method == "cone") return "cone.exr";
  if (method == "relaxed-cone") return "relaxed-cone.exr";
  if (method == "pyramid") return "pyramid.exr";
  if (method == "vdm") return "vdm.exr";
  if (method == "dstream") return "dstream.bin";
  return "";
}

namespace {
// The image member holding a method's stream (nullptr for vdm, dstream and methods without one).
Image* image_stream(PreviewMaps& maps, const std::string& method) {
  if (method == "sphere-tracing") return &maps.sdf;
  if (method == "cone") return &maps.cone;
  if (method == "relaxed-cone") return &maps.relaxed_cone;
  if (method == "pyramid") return &maps.pyramid;
  return nullptr;
}
}  // namespace

bool has_stream(const PreviewMaps& maps, const std::string& method) {
  if (method == "vdm") return !maps.vdm_weights.empty();
  if (method == "dstream") return !maps.dstream.vertices.empty();
  const Image* image = image_stream(const_cast<PreviewMaps&>(maps), method);
  return !image || !image->empty();
}

bool method_tiles(const PreviewMaps& maps, const std::string& method) {
  const Image* own = method == "vdm" ? &maps.vdm_weights : image_stream(const_cast<PreviewMaps&>(maps), method);
  if (own && !own->empty()) return string_attribute(*own, "border") == "wrap";
  return maps_tile(maps);
}

void clear_stream(PreviewMaps& maps, const std::string& method) {
  if (method == "vdm") maps.vdm_weights = maps.vdm_basis = Image();
  if (method == "dstream") maps.dstream = EncodedStream();
  if (Image* image = image_stream(maps, method)) *image = Image();
}

namespace {
// displacement.exr in object units. A map that records its mapping to object units (bake's
// displacement.png converted to EXR keeps meso:height_scale and meso:height_bias) is taken
// back through it, as `meso streams` reads it, so the previewer and the streams see one
// relief. Another meso map under this name (a stream, a normal map) is refused.
Image read_displacement(const std::filesystem::path& file) {
  Image map = read_image(file);
  const std::string quantity = string_attribute(map, "quantity");
  if (!quantity.empty() && quantity != "displacement")
    throw InputError(file.string(), "holds a " + quantity + " (meso:quantity), not a displacement map");
  const std::string mapping = height_mapping_problem(map.metadata);
  if (!mapping.empty()) throw InputError(file.string(), mapping);
  return heights_in_object_units(std::move(map));
}

// normal_ts.png as the previewer's shaders take it: green up (OpenGL, +y = +v). A map baked
// with --normal-y down (meso:normal_y "down") has its green turned back; an object-space or
// another quantity's map is refused.
Image read_tangent_normals(const std::filesystem::path& file) {
  Image map = read_image(file);
  if (map.channels < 3) throw InputError(file.string(), "needs 3 channels (a tangent-space normal map)");
  const std::string quantity = string_attribute(map, "quantity");
  if (!quantity.empty() && quantity != "normal")
    throw InputError(file.string(), "holds a " + quantity + " (meso:quantity), not a tangent-space normal map");
  if (string_attribute(map, "space").rfind("object", 0) == 0) throw InputError(file.string(), "is an object-space normal map; the previewer needs bake's normal_ts");
  const std::string y = string_attribute(map, "normal_y");
  if (!y.empty() && y != "up" && y != "down") throw InputError(file.string(), "its meso:normal_y is '" + y + "' (up or down)");
  if (y == "down")  // stored as (n + 1) / 2: n.y -> -n.y is c -> 1 - c
    for (size_t i = 1; i < map.pixels.size(); i += static_cast<size_t>(map.channels)) map.pixels[i] = 1.0f - map.pixels[i];
  return map;
}

}  // namespace

void load_bake_maps(PreviewMaps& maps, const std::filesystem::path& dir) {
  const std::filesystem::path height_file = dir / "displacement.exr";
  Image displacement = read_displacement(height_file);
  if (displacement.channels > 1) {
    // Channel 0 is the height, as for the streams (a G of 1e20 had set the height range and
    // emptied the frame).
    Image height(displacement.width, displacement.height, 1);
    for (size_t i = 0; i < height.pixels.size(); ++i) height.pixels[i] = displacement.pixels[i * static_cast<size_t>(displacement.channels)];
    height.metadata = std::move(displacement.metadata);
    displacement = std::move(height);
  }
  if (!displacement.pixels.empty()) {
    // Finite heights whose span is not (e.g. -3e38 and 3e38) cannot be normalised in float:
    // the streams refuse such a map, and so does the previewer.
    const auto [lo, hi] = std::minmax_element(displacement.pixels.begin(), displacement.pixels.end());
    if (!std::isfinite(*hi - *lo)) throw InputError(height_file.string(), "its heights span more than the float range; rescale the map");
  }
  Image normals = read_tangent_normals(dir / "normal_ts.png");
  maps.displacement = std::move(displacement);
  maps.normal_ts = std::move(normals);
}

void load_stream(PreviewMaps& maps, const Mesh& base, const std::string& method, const std::filesystem::path& file) {
  if (required_stream(method).empty()) return;
  const std::string name = file.string();
  if (!std::filesystem::exists(file)) throw InputError(name, "missing: method " + method + " needs it (meso streams)");
  if (method == "vdm") {
    std::vector<Image> parts = read_image_parts(file);
    if (parts.size() != 2) throw InputError(name, "needs two parts (weights, basis): is it meso streams vdm's output?");
    check_vdm_matches(parts[0], parts[1], maps.displacement, name);
    maps.vdm_weights = std::move(parts[0]);
    maps.vdm_basis = std::move(parts[1]);
  } else if (method == "dstream") {
    int vertices = 0, triangles = 0;
    EncodedStream stream = read_displacement_stream(name, &vertices, &triangles);
    if (static_cast<size_t>(vertices) != base.n_vertices() || static_cast<size_t>(triangles) != base.n_faces())
      throw InputError(name, "was made for a base mesh of " + std::to_string(vertices) + " vertices and " + std::to_string(triangles) +
                                 " triangles; this one has " + std::to_string(base.n_vertices()) + " and " + std::to_string(base.n_faces()));
    maps.dstream = std::move(stream);
  } else {
    Image image = read_image(file);
    check_stream_matches(method, image, maps.displacement, name);
    *image_stream(maps, method) = std::move(image);
  }
}

int method_index(const std::string& name) {
  const auto& m = preview_methods();
  const auto it = std::find(m.begin(), m.end(), name);
  if (it == m.end()) throw UsageError("unknown preview method '" + name + "' (see --list-methods)");
  return static_cast<int>(it - m.begin());
}

GLuint compile(GLenum type, std::initializer_list<const char*> pieces) {
  const std::vector<const char*> src(pieces);
  const GLuint s = glCreateShader(type);
  glShaderSource(s, static_cast<GLsizei>(src.size()), src.data(), nullptr);
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

GLuint link(std::initializer_list<GLuint> stages, const char* feedback) {
  const GLuint program = glCreateProgram();
  for (GLuint s : stages) glAttachShader(program, s);
  if (feedback) glTransformFeedbackVaryings(program, 1, &feedback, GL_INTERLEAVED_ATTRIBS);
  glLinkProgram(program);
  for (GLuint s : stages) glDeleteShader(s);
  GLint ok = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[4096];
    glGetProgramInfoLog(program, sizeof log, nullptr, log);
    throw InternalError(std::string("preview shaders do not link: ") + log);
  }
  return program;
}

namespace {

// Every sampler of the fragment stage on its own texture unit, fixed for the program's life:
// two sampler types on one unit (all default to unit 0) make every draw invalid, even with
// rasterisation off. draw() binds the textures to these units.
void assign_texture_units(GLuint program) {
  glUseProgram(program);
  const char* const names[] = {"u_height", "u_normal", "u_sdf", "u_cone", "u_pyramid", "u_dig", "u_vdm_weights", "u_vdm_basis"};
  for (GLint unit = 0; unit < 8; ++unit) glUniform1i(glGetUniformLocation(program, names[unit]), unit);
}

// Filtering and border of the texture bound to `target`: linear, repeat or clamp in s and t.
void set_linear_sampling(GLenum target, bool wrap) {
  glTexParameteri(target, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(target, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  const GLint wrap_mode = wrap ? GL_REPEAT : GL_CLAMP_TO_EDGE;
  glTexParameteri(target, GL_TEXTURE_WRAP_S, wrap_mode);
  glTexParameteri(target, GL_TEXTURE_WRAP_T, wrap_mode);
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

// The mesh method draws a segment per texel along every edge, but GL cuts a patch edge into
// at most 64 segments. So where an edge spans more than 64 texels of the displacement map,
// every base triangle is first cut uniformly into k x k, k = ceil(longest edge / 64) (capped
// so that no more than 2^22 sub-triangles are made): every sub-edge then spans at most 64
// texels, 64 k over the whole edge. Attributes are interpolated linearly, as tess.tese does
// over a patch. Crack-free: a vertex on an edge is made once per pair of corners (both
// triangles share it) and interpolated from the end that comes first by position (tess.tesc's
// canonical order), so a seam's two copies of an edge get the same positions bitwise; the
// tangent sign is the triangle's first corner's (the baker's convention).
// `verts`: per-corner attributes of `stride` floats (position first, the tangent sign at
// `sign_at`); `tris`: corner indices. Returns k (1: nothing made).
int subdivide_for_mesh(const std::vector<float>& verts, const std::vector<uint32_t>& tris, size_t stride, size_t sign_at, int map_w,
                       int map_h, std::vector<float>& out_verts, std::vector<uint32_t>& out_tris) {
  const size_t nt = tris.size() / 3;
  double longest = 0;
  for (size_t t = 0; t < nt; ++t)
    for (size_t e = 0; e < 3; ++e) {
      const float* a = &verts[tris[3 * t + e] * stride];
      const float* b = &verts[tris[3 * t + (e + 1) % 3] * stride];
      longest = std::max(longest, std::hypot((static_cast<double>(b[6]) - a[6]) * map_w, (static_cast<double>(b[7]) - a[7]) * map_h));
    }
  int k = static_cast<int>(std::ceil(longest / 64.0 - 1e-9));
  const double cap = nt ? std::sqrt(static_cast<double>(1u << 22) / static_cast<double>(nt)) : 1.0;
  k = std::clamp(k, 1, std::max(1, static_cast<int>(cap)));
  if (k == 1) return 1;
  out_verts = verts;  // the corners keep their indices
  out_tris.clear();
  auto before = [&](uint32_t i, uint32_t j) {
    const float *a = &verts[i * stride], *b = &verts[j * stride];
    if (a[0] != b[0]) return a[0] < b[0];
    if (a[1] != b[1]) return a[1] < b[1];
    if (a[2] != b[2]) return a[2] < b[2];
    return i < j;
  };
  auto add = [&](const float* values) {
    out_verts.insert(out_verts.end(), values, values + stride);
    return static_cast<uint32_t>(out_verts.size() / stride - 1);
  };
  // Vertex m (1..k-1) of the edge between corners i and j, counted from the first by position.
  std::map<std::pair<uint32_t, uint32_t>, uint32_t> edge_first;
  std::vector<float> value(stride);
  auto edge_vertex = [&](uint32_t i, uint32_t j, int m, float sign) {
    if (!before(i, j)) {
      std::swap(i, j);
      m = k - m;
    }
    auto [it, fresh] = edge_first.try_emplace({i, j}, 0u);
    if (fresh) {
      const float *a = &verts[i * stride], *b = &verts[j * stride];
      for (int s = 1; s < k; ++s) {
        const float t = static_cast<float>(s) / static_cast<float>(k);
        for (size_t c = 0; c < stride; ++c) value[c] = a[c] + (b[c] - a[c]) * t;
        value[sign_at] = sign;
        const uint32_t id = add(value.data());
        if (s == 1) it->second = id;
      }
    }
    return it->second + static_cast<uint32_t>(m - 1);
  };
  std::vector<uint32_t> grid;
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t A = tris[3 * t], B = tris[3 * t + 1], C = tris[3 * t + 2];
    const float sign = verts[A * stride + sign_at];
    // grid[(i, j)]: the point A + i/k (B - A) + j/k (C - A), i + j <= k.
    grid.assign(static_cast<size_t>((k + 1) * (k + 1)), 0u);
    auto at = [&](int i, int j) -> uint32_t& { return grid[static_cast<size_t>(j * (k + 1) + i)]; };
    for (int j = 0; j <= k; ++j)
      for (int i = 0; i + j <= k; ++i) {
        if (i == 0 && j == 0) at(i, j) = A;
        else if (i == k) at(i, j) = B;
        else if (j == k) at(i, j) = C;
        else if (j == 0) at(i, j) = edge_vertex(A, B, i, sign);
        else if (i == 0) at(i, j) = edge_vertex(A, C, j, sign);
        else if (i + j == k) at(i, j) = edge_vertex(B, C, j, sign);
        else {
          const float wb = static_cast<float>(i) / static_cast<float>(k), wc = static_cast<float>(j) / static_cast<float>(k);
          const float wa = 1.0f - wb - wc;
          for (size_t c = 0; c < stride; ++c) value[c] = wa * verts[A * stride + c] + wb * verts[B * stride + c] + wc * verts[C * stride + c];
          value[sign_at] = sign;
          at(i, j) = add(value.data());
        }
      }
    // Corners and edge vertices keep their own attributes; the cut triangles keep ABC's turn.
    for (int j = 0; j < k; ++j)
      for (int i = 0; i + j < k; ++i) {
        out_tris.insert(out_tris.end(), {at(i, j), at(i + 1, j), at(i, j + 1)});
        if (i + j + 1 < k) out_tris.insert(out_tris.end(), {at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
      }
  }
  return k;
}

// Per triangle of `tris`, the derivatives of position by UV, dp/du and dp/dv (object units per
// UV unit), from the per-corner floats the vertex shader reads (position at 0, UV at 6 of
// each `stride`), in the layout of surface_common.glsl's FaceJacobians: 12 floats per
// triangle, (a, |dp/du|), (b, |dp/dv|), (a x b, valid) with a and b the unit directions of
// dp/du and dp/dv. Exact, since UVs are affine over a triangle: [e1 e2] = J [f1 f2] for the
// edges e in space and f in UV, so J = [e1 e2] [f1 f2]^-1. In double, the cross product too:
// on a sliver of UV space a and b are nearly parallel, and a float cross product of them
// (the shader's) loses its direction. Valid = 0 where the UV triangle has no area.
std::vector<float> face_jacobians(const std::vector<float>& verts, const std::vector<uint32_t>& tris, size_t stride) {
  std::vector<float> out(tris.size() / 3 * 12, 0.0f);
  for (size_t t = 0; t < tris.size() / 3; ++t) {
    const float* c[3] = {&verts[tris[3 * t] * stride], &verts[tris[3 * t + 1] * stride], &verts[tris[3 * t + 2] * stride]};
    const double f1u = static_cast<double>(c[1][6]) - c[0][6], f1v = static_cast<double>(c[1][7]) - c[0][7];
    const double f2u = static_cast<double>(c[2][6]) - c[0][6], f2v = static_cast<double>(c[2][7]) - c[0][7];
    const double det = f1u * f2v - f2u * f1v;
    if (!(std::abs(det) > 1e-12 * std::hypot(f1u, f1v) * std::hypot(f2u, f2v))) continue;
    OpenMesh::Vec3d du, dv;
    for (int k = 0; k < 3; ++k) {
      const double e1 = static_cast<double>(c[1][k]) - c[0][k], e2 = static_cast<double>(c[2][k]) - c[0][k];
      // [f1 f2]^-1 = [[f2v, -f2u], [-f1v, f1u]] / det.
      du[k] = (e1 * f2v - e2 * f1v) / det;
      dv[k] = (e2 * f1u - e1 * f2u) / det;
    }
    const double lu = du.norm(), lv = dv.norm();
    if (!(lu > 0 && lv > 0 && std::isfinite(lu) && std::isfinite(lv) && lu < 1e38 && lv < 1e38)) continue;
    const OpenMesh::Vec3d a = du / lu, b = dv / lv, ab = OpenMesh::cross(a, b);
    const double values[12] = {a[0], a[1], a[2], lu, b[0], b[1], b[2], lv, ab[0], ab[1], ab[2], 1.0};
    std::transform(values, values + 12, &out[t * 12], [](double v) { return static_cast<float>(v); });
  }
  return out;
}

}  // namespace

SurfaceRenderer::SurfaceRenderer(const Mesh& base, const PreviewMaps& maps) : base_(base) {
  // Per-corner vertices: the same frames the baker encoded with.
  Mesh m = base;
  const auto frames = compute_tangent_frames(m);
  store_tangents(m, frames);
  const CornerSplit split = split_corners(m);
  // The principal curvatures (curvature along the view: vdm, and the silhouettes' curved rays).
  const std::vector<VertexCurvature> curvature = fit_curvature(m);
  constexpr size_t kStride = 3 + 3 + 2 + 4 + 2 + 3 + 2;
  std::vector<float> verts(split.corner.size() * kStride);
  for (size_t i = 0; i < split.corner.size(); ++i) {
    const auto h = split.corner[i];
    const auto v = m.to_vertex_handle(h);
    const auto& fr = frames[static_cast<size_t>(h.idx())];
    const Vec3f p = m.point(v), nv = m.normal(v);
    const Vec2f uv = m.texcoord2D(h);
    const VertexCurvature k = curvature[static_cast<size_t>(v.idx())];
    float* o = &verts[i * kStride];
    const float values[kStride] = {p[0], p[1], p[2], nv[0], nv[1], nv[2], uv[0], uv[1],
                                   fr.tangent[0], fr.tangent[1], fr.tangent[2], fr.sign, fr.du_length, fr.dv_length,
                                   k.d1[0], k.d1[1], k.d1[2], k.k1, k.k2};
    std::copy(values, values + kStride, o);
  }
  index_count_ = static_cast<GLsizei>(split.triangles.size());

  // Per-pixel methods: surface.vert + the fragment pieces; per-vertex methods (mesh,
  // tessellation): the tessellation stages + the same fragment pieces.
  auto fragment = [] {
    return compile(GL_FRAGMENT_SHADER, {shaders::surface_common_glsl, shaders::footprint_glsl, shaders::cone_stepping_glsl,
                                        shaders::pyramid_glsl, shaders::sphere_tracing_glsl, shaders::dig_glsl, shaders::vdm_glsl,
                                        shaders::surface_frag});
  };
  program_ = link({compile(GL_VERTEX_SHADER, {shaders::surface_vert}), fragment()});
  tess_program_ = link({compile(GL_VERTEX_SHADER, {shaders::tess_vert}), compile(GL_TESS_CONTROL_SHADER, {shaders::tess_tesc}),
                        compile(GL_TESS_EVALUATION_SHADER, {shaders::tess_tese}), fragment()});
  assign_texture_units(program_);
  assign_texture_units(tess_program_);
  glGenBuffers(1, &vertex_work_);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, vertex_work_);
  const GLuint zero = 0;
  glBufferData(GL_SHADER_STORAGE_BUFFER, sizeof zero, &zero, GL_DYNAMIC_READ);

  glGenVertexArrays(1, &vao_);
  glBindVertexArray(vao_);
  // The vertex array bound (a fresh one), its vertex and index buffers filled.
  auto fill_vertex_array = [&](const std::vector<float>& v, const std::vector<uint32_t>& tris, GLuint& vbo, GLuint& ibo) {
    glGenBuffers(1, &vbo);
    glBindBuffer(GL_ARRAY_BUFFER, vbo);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(v.size() * sizeof(float)), v.data(), GL_STATIC_DRAW);
    const GLint sizes[7] = {3, 3, 2, 4, 2, 3, 2};
    size_t offset = 0;
    for (GLuint a = 0; a < 7; ++a) {
      glEnableVertexAttribArray(a);
      glVertexAttribPointer(a, sizes[a], GL_FLOAT, GL_FALSE, static_cast<GLsizei>(kStride * sizeof(float)),
                            reinterpret_cast<const void*>(offset * sizeof(float)));
      offset += static_cast<size_t>(sizes[a]);
    }
    glGenBuffers(1, &ibo);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(tris.size() * sizeof(uint32_t)), tris.data(), GL_STATIC_DRAW);
    glBindVertexArray(0);
  };
  fill_vertex_array(verts, split.triangles, vbo_, ibo_);
  {
    const std::vector<float> jacobians = face_jacobians(verts, split.triangles, kStride);
    glGenBuffers(1, &face_jacobians_);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, face_jacobians_);
    // An empty mesh still gets a buffer to bind (one invalid entry).
    const std::vector<float> none(12, 0.0f);
    const std::vector<float>& data = jacobians.empty() ? none : jacobians;
    glBufferData(GL_SHADER_STORAGE_BUFFER, static_cast<GLsizeiptr>(data.size() * sizeof(float)), data.data(), GL_STATIC_DRAW);
  }
  {
    std::vector<float> cut_verts;
    std::vector<uint32_t> cut_tris;
    mesh_subdivision_ = subdivide_for_mesh(verts, split.triangles, kStride, 11, maps.displacement.width, maps.displacement.height, cut_verts, cut_tris);
    if (mesh_subdivision_ > 1) {
      glGenVertexArrays(1, &mesh_vao_);
      glBindVertexArray(mesh_vao_);
      fill_vertex_array(cut_verts, cut_tris, mesh_vbo_, mesh_ibo_);
      mesh_index_count_ = static_cast<GLsizei>(cut_tris.size());
    }
  }

  height_tex_ = upload_texture(maps.displacement, 1);
  normal_tex_ = upload_texture(maps.normal_ts, 3);
  if (!maps.sdf.empty()) upload_sdf(maps.sdf, maps.displacement);
  if (!maps.cone.empty()) upload_cone(0, maps.cone, maps.displacement);
  if (!maps.relaxed_cone.empty()) upload_cone(1, maps.relaxed_cone, maps.displacement);
  if (!maps.pyramid.empty()) upload_pyramid(maps.pyramid, maps.displacement);
  if (!maps.vdm_weights.empty()) upload_vdm(maps);
  if (!maps.dstream.vertices.empty()) {
    dstream_program_ = link({compile(GL_VERTEX_SHADER, {shaders::dstream_vert}), fragment()}, "v_position");
    assign_texture_units(dstream_program_);
    upload_dstream(base, maps.dstream, frames);
  }
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
  set_linear_sampling(GL_TEXTURE_3D, wrap);
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

void SurfaceRenderer::upload_pyramid(const Image& level0, const Image& displacement) {
  check_pyramid_matches(level0, displacement, "pyramid.exr");
  pyramid_scale_ = stream_number(level0, "height_scale", "pyramid.exr", "meso streams pyramid");
  pyramid_bias_ = stream_number(level0, "height_bias", "pyramid.exr", "meso streams pyramid");
  pyramid_wrap_ = string_attribute(level0, "border") == "wrap";
  const MinMaxPyramid pyramid = min_max_pyramid_from_level0(level0);
  // The levels' maxima side by side in one single-level texture: level 0 at the left, the
  // coarser ones stacked in a column to its right. (llvmpipe's texelFetch does not take a level
  // that differs between the fragments of a SIMD batch, which a traversal needs.)
  const int levels = std::min(static_cast<int>(pyramid.levels.size()), kMaxPyramidLevels);
  const int w0 = level0.width, h0 = level0.height;
  const int atlas_w = w0 + (levels > 1 ? pyramid.levels[1].width : 0);
  int column = 0;
  pyramid_offset_.assign(static_cast<size_t>(2 * levels), 0);
  pyramid_size_.assign(static_cast<size_t>(2 * levels), 0);
  for (int l = 0; l < levels; ++l) {
    const Image& img = pyramid.levels[static_cast<size_t>(l)];
    pyramid_offset_[static_cast<size_t>(2 * l)] = l == 0 ? 0 : w0;
    pyramid_offset_[static_cast<size_t>(2 * l + 1)] = l == 0 ? 0 : column;
    pyramid_size_[static_cast<size_t>(2 * l)] = img.width;
    pyramid_size_[static_cast<size_t>(2 * l + 1)] = img.height;
    if (l > 0) column += img.height;
  }
  const int atlas_h = std::max(h0, column);
  Image atlas(atlas_w, atlas_h, 1, 0.0f);  // rows from the top, as every Image
  for (int l = 0; l < levels; ++l) {
    const Image& img = pyramid.levels[static_cast<size_t>(l)];
    const int ox = pyramid_offset_[static_cast<size_t>(2 * l)], oy = pyramid_offset_[static_cast<size_t>(2 * l + 1)];
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x) atlas.at(ox + x, oy + y) = img.at(x, y, 1);
  }
  pyramid_levels_ = levels;
  pyramid_tex_ = upload_texture(atlas, 1);  // flipped: GL row = atlas_h - 1 - row
  // Read with texelFetch only: a filtered maximum bounds nothing.
  glBindTexture(GL_TEXTURE_2D, pyramid_tex_);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
}

void SurfaceRenderer::upload_vdm(const PreviewMaps& maps) {
  const Image& weights = maps.vdm_weights;
  const Image& basis = maps.vdm_basis;
  check_vdm_matches(weights, basis, maps.displacement, "vdm.exr");
  auto number = [&](const char* key) { return stream_number(weights, key, "vdm.exr", "meso streams vdm"); };
  vdm_rank_ = static_cast<int>(number("rank"));
  vdm_theta_ = static_cast<int>(number("theta"));
  vdm_phi_ = static_cast<int>(number("phi"));
  vdm_theta_max_ = number("theta_max") * 3.14159265f / 180.0f;
  vdm_relief_ = number("relief");
  vdm_scale_ = number("height_scale");
  vdm_bias_ = number("height_bias");
  vdm_aspect_ = static_cast<float>(weights.height) / static_cast<float>(weights.width);
  vdm_curvatures_ = vdm_curvatures(weights, "vdm.exr");
  vdm_wrap_ = string_attribute(weights, "border") == "wrap";
  // Weights: 4 components per layer, rows flipped as every 2D map (GL row 0 = v near 0).
  const int layers = std::max(1, (vdm_rank_ + 3) / 4), w = weights.width, h = weights.height;
  std::vector<float> texels(static_cast<size_t>(layers) * static_cast<size_t>(w) * static_cast<size_t>(h) * 4, 0.0f);
  for (int l = 0; l < layers; ++l)
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < 4; ++c) {
          const int k = 4 * l + c;
          if (k >= vdm_rank_) continue;
          texels[((static_cast<size_t>(l) * static_cast<size_t>(h) + static_cast<size_t>(h - 1 - y)) * static_cast<size_t>(w) + static_cast<size_t>(x)) * 4 +
                 static_cast<size_t>(c)] = weights.at(x, y, k);
        }
  glGenTextures(1, &vdm_weights_tex_);
  glBindTexture(GL_TEXTURE_2D_ARRAY, vdm_weights_tex_);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage3D(GL_TEXTURE_2D_ARRAY, 0, GL_RGBA32F, w, h, layers, 0, GL_RGBA, GL_FLOAT, texels.data());
  set_linear_sampling(GL_TEXTURE_2D_ARRAY, vdm_wrap_);
  // Mean and basis: row = direction, as stored (read with texelFetch by direction index).
  std::vector<float> table(basis.pixels.size());
  for (int y = 0; y < basis.height; ++y)
    for (int x = 0; x < basis.width; ++x) table[static_cast<size_t>(y) * static_cast<size_t>(basis.width) + static_cast<size_t>(x)] = basis.at(x, y);
  glGenTextures(1, &vdm_basis_tex_);
  glBindTexture(GL_TEXTURE_2D, vdm_basis_tex_);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_R32F, basis.width, basis.height, 0, GL_RED, GL_FLOAT, table.data());
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
}

void SurfaceRenderer::upload_dstream(const Mesh& base, const EncodedStream& stream, const std::vector<TangentFrame>& frames) {
  // The base triangles' corners in face_halfedges() order, as displacement_stream_point().
  std::vector<float> corners(base.n_faces() * 3 * 16, 0.0f);
  for (auto f : base.faces()) {
    int k = 0;
    for (auto h : face_halfedges(base, f)) {
      const auto v = base.to_vertex_handle(h);
      const auto& fr = frames[static_cast<size_t>(h.idx())];
      const Vec3f p = base.point(v), n = base.normal(v);
      const Vec2f uv = base.has_halfedge_texcoords2D() ? base.texcoord2D(h) : Vec2f(0, 0);
      const int32_t index = v.idx();
      float index_bits;
      std::memcpy(&index_bits, &index, sizeof index_bits);
      const float values[16] = {p[0], p[1], p[2], index_bits, n[0], n[1], n[2], 0.0f, uv[0], uv[1], fr.du_length, fr.dv_length,
                                fr.tangent[0], fr.tangent[1], fr.tangent[2], fr.sign};
      std::copy(values, values + 16, &corners[(static_cast<size_t>(f.idx()) * 3 + static_cast<size_t>(k++)) * 16]);
    }
  }
  glGenBuffers(1, &dstream_corners_);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, dstream_corners_);
  glBufferData(GL_SHADER_STORAGE_BUFFER, static_cast<GLsizeiptr>(corners.size() * sizeof(float)), corners.data(), GL_STATIC_DRAW);
  dstream_min_ = stream.min_value;
  dstream_max_ = stream.max_value;
  const int triangles = static_cast<int>(base.n_faces());
  for (size_t l = 0; l < stream.vertices.size(); ++l) {
    const std::vector<uint64_t>& level = stream.vertices[l];
    std::vector<uint32_t> words(2 * level.size());
    for (size_t k = 0; k < level.size(); ++k) {
      words[2 * k] = static_cast<uint32_t>(level[k]);
      words[2 * k + 1] = static_cast<uint32_t>(level[k] >> 32);
    }
    GLuint buffer = 0;
    glGenBuffers(1, &buffer);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, buffer);
    glBufferData(GL_SHADER_STORAGE_BUFFER, static_cast<GLsizeiptr>(words.size() * sizeof(uint32_t)), words.data(), GL_STATIC_DRAW);
    // Small triangles of the regular tessellation, oriented as the base triangle: per cell
    // (i, j) the upright (i, j), (i+1, j), (i, j+1) and, inside, (i+1, j), (i+1, j+1), (i, j+1).
    const int n = stream.segments[l], per = (n + 1) * (n + 2) / 2;
    auto at = [n](int i, int j) { return static_cast<uint32_t>(i * (n + 1) - i * (i - 1) / 2 + j); };
    std::vector<uint32_t> indices;
    indices.reserve(static_cast<size_t>(triangles) * static_cast<size_t>(n) * static_cast<size_t>(n) * 3);
    for (int t = 0; t < triangles; ++t) {
      const uint32_t o = static_cast<uint32_t>(t) * static_cast<uint32_t>(per);
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n - i; ++j) {
          for (uint32_t q : {at(i, j), at(i + 1, j), at(i, j + 1)}) indices.push_back(o + q);
          if (i + j < n - 1)
            for (uint32_t q : {at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)}) indices.push_back(o + q);
        }
    }
    GLuint ibo = 0;
    glGenBuffers(1, &ibo);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(indices.size() * sizeof(uint32_t)), indices.data(), GL_STATIC_DRAW);
    dstream_vertices_.push_back(buffer);
    dstream_indices_.push_back(ibo);
    dstream_vertex_count_.push_back(static_cast<GLsizei>(level.size()));
    dstream_index_count_.push_back(static_cast<GLsizei>(indices.size()));
    dstream_segments_.push_back(n);
  }
  glGenVertexArrays(1, &dstream_vao_);
  glGenBuffers(1, &dstream_capture_);
}

int SurfaceRenderer::bind_dstream(const PreviewOptions& o, const CameraPose& pose) {
  if (dstream_segments_.empty()) return -1;
  int level = 0;
  while (level + 1 < static_cast<int>(dstream_segments_.size()) && dstream_segments_[static_cast<size_t>(level + 1)] <= std::max(o.iterations, 1))
    ++level;
  const GLuint prog = dstream_program_;
  glUseProgram(prog);
  glUniformMatrix4fv(glGetUniformLocation(prog, "u_view_projection"), 1, GL_FALSE, pose.view_projection.data());
  glUniform3f(glGetUniformLocation(prog, "u_eye"), pose.eye[0], pose.eye[1], pose.eye[2]);
  glUniform1i(glGetUniformLocation(prog, "u_segments"), dstream_segments_[static_cast<size_t>(level)]);
  glUniform1f(glGetUniformLocation(prog, "u_dstream_min"), dstream_min_);
  glUniform1f(glGetUniformLocation(prog, "u_dstream_max"), dstream_max_);
  glUniform1f(glGetUniformLocation(prog, "u_morph"), o.morph >= 0 ? std::min(o.morph, 1.0f) : -1.0f);
  glUniform1f(glGetUniformLocation(prog, "u_lod_distance"), o.lod_distance);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, dstream_corners_);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, dstream_vertices_[static_cast<size_t>(level)]);
  const GLuint zero = 0;
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, vertex_work_);
  glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof zero, &zero);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, vertex_work_);
  return level;
}

std::vector<Vec3f> SurfaceRenderer::dstream_positions(const PreviewOptions& o) {
  const CameraPose pose = frame_camera(base_, o.camera, static_cast<float>(o.width) / static_cast<float>(o.height), std::max(-h_min_, h_max_));
  const int level = bind_dstream(o, pose);
  if (level < 0) return {};
  const GLsizei count = dstream_vertex_count_[static_cast<size_t>(level)];
  glBindBuffer(GL_TRANSFORM_FEEDBACK_BUFFER, dstream_capture_);
  glBufferData(GL_TRANSFORM_FEEDBACK_BUFFER, static_cast<GLsizeiptr>(count) * 3 * static_cast<GLsizeiptr>(sizeof(float)), nullptr, GL_STREAM_READ);
  glBindBufferBase(GL_TRANSFORM_FEEDBACK_BUFFER, 0, dstream_capture_);
  glEnable(GL_RASTERIZER_DISCARD);
  glBindVertexArray(dstream_vao_);
  glBeginTransformFeedback(GL_POINTS);
  glDrawArrays(GL_POINTS, 0, count);
  glEndTransformFeedback();
  glBindVertexArray(0);
  glDisable(GL_RASTERIZER_DISCARD);
  std::vector<float> xyz(static_cast<size_t>(count) * 3);
  glGetBufferSubData(GL_TRANSFORM_FEEDBACK_BUFFER, 0, static_cast<GLsizeiptr>(xyz.size() * sizeof(float)), xyz.data());
  glBindBufferBase(GL_TRANSFORM_FEEDBACK_BUFFER, 0, 0);
  std::vector<Vec3f> out(static_cast<size_t>(count));
  for (size_t k = 0; k < out.size(); ++k) out[k] = Vec3f(xyz[3 * k], xyz[3 * k + 1], xyz[3 * k + 2]);
  return out;
}

void SurfaceRenderer::ensure_dig_target(int width, int height) {
  if (dig_fbo_ && dig_width_ == width && dig_height_ == height) return;
  if (!dig_fbo_) {
    glGenFramebuffers(1, &dig_fbo_);
    glGenTextures(1, &dig_tex_);
    glGenRenderbuffers(1, &dig_depth_);
  }
  dig_width_ = width;
  dig_height_ = height;
  glActiveTexture(GL_TEXTURE5);  // u_dig's unit: binding it here disturbs no other map
  glBindTexture(GL_TEXTURE_2D, dig_tex_);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RG32F, width, height, 0, GL_RG, GL_FLOAT, nullptr);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glBindRenderbuffer(GL_RENDERBUFFER, dig_depth_);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, width, height);
  GLint previous = 0;
  glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &previous);
  glBindFramebuffer(GL_FRAMEBUFFER, dig_fbo_);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, dig_tex_, 0);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, dig_depth_);
  const GLenum buffers[1] = {GL_COLOR_ATTACHMENT0};
  glDrawBuffers(1, buffers);
  const bool complete = glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
  glBindFramebuffer(GL_FRAMEBUFFER, static_cast<GLuint>(previous));
  if (!complete) throw InternalError("OpenGL: the depth interval grid's float target is not supported");
}

double SurfaceRenderer::vertex_stage_fetches() const {
  if (!last_per_vertex_) return 0;
  GLuint count = 0;
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, vertex_work_);
  glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof count, &count);
  return count;
}

SurfaceRenderer::~SurfaceRenderer() {
  glDeleteTextures(1, &vdm_weights_tex_);
  glDeleteTextures(1, &vdm_basis_tex_);
  glDeleteProgram(dstream_program_);
  glDeleteVertexArrays(1, &dstream_vao_);
  glDeleteBuffers(1, &dstream_corners_);
  glDeleteBuffers(1, &dstream_capture_);
  if (!dstream_vertices_.empty()) glDeleteBuffers(static_cast<GLsizei>(dstream_vertices_.size()), dstream_vertices_.data());
  if (!dstream_indices_.empty()) glDeleteBuffers(static_cast<GLsizei>(dstream_indices_.size()), dstream_indices_.data());
  glDeleteBuffers(1, &vertex_work_);
  glDeleteBuffers(1, &face_jacobians_);
  glDeleteProgram(tess_program_);
  glDeleteFramebuffers(1, &dig_fbo_);
  glDeleteTextures(1, &dig_tex_);
  glDeleteRenderbuffers(1, &dig_depth_);
  glDeleteTextures(1, &pyramid_tex_);
  glDeleteTextures(2, cone_tex_.data());
  glDeleteTextures(1, &sdf_tex_);
  glDeleteTextures(1, &height_tex_);
  glDeleteTextures(1, &normal_tex_);
  glDeleteBuffers(1, &vbo_);
  glDeleteBuffers(1, &ibo_);
  glDeleteVertexArrays(1, &vao_);
  glDeleteBuffers(1, &mesh_vbo_);
  glDeleteBuffers(1, &mesh_ibo_);
  glDeleteVertexArrays(1, &mesh_vao_);
  glDeleteProgram(program_);
}

void SurfaceRenderer::draw(const PreviewOptions& o, int width, int height) {
  const CameraPose pose = frame_camera(base_, o.camera, static_cast<float>(width) / static_cast<float>(height), std::max(-h_min_, h_max_));
  glViewport(0, 0, width, height);
  glClearColor(0, 0, 0, 0);
  glClearDepth(1.0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  // The flat tangent sign comes from a triangle's first corner, the corner the baker uses.
  glProvokingVertex(GL_FIRST_VERTEX_CONVENTION);
  const bool dstream = o.method == "dstream", vdm = o.method == "vdm";
  const bool per_vertex = o.method == "mesh" || o.method == "tessellation" || dstream;
  if ((dstream && !dstream_program_) || (vdm && !vdm_weights_tex_))
    throw UsageError("method " + o.method + " needs the stream " + required_stream(o.method) + " (meso streams)");
  const GLuint prog = dstream ? dstream_program_ : per_vertex ? tess_program_ : program_;
  glUseProgram(prog);
  glUniformMatrix4fv(glGetUniformLocation(prog, "u_view_projection"), 1, GL_FALSE, pose.view_projection.data());
  glUniform3f(glGetUniformLocation(prog, "u_eye"), pose.eye[0], pose.eye[1], pose.eye[2]);
  glUniform3f(glGetUniformLocation(prog, "u_light"), pose.light[0], pose.light[1], pose.light[2]);
  glUniform1i(glGetUniformLocation(prog, "u_method"), method_index(o.method));
  // The per-pixel methods draw face t as primitive t: its dp/du, dp/dv (face_jacobians()).
  glUniform1i(glGetUniformLocation(prog, "u_face_jacobians"), per_vertex ? 0 : 1);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, face_jacobians_);
  glUniform1i(glGetUniformLocation(prog, "u_iterations"), o.iterations);
  glUniform1i(glGetUniformLocation(prog, "u_shade"), static_cast<int>(o.shade));
  glUniform1i(glGetUniformLocation(prog, "u_shadows"), static_cast<int>(o.shadows));
  glUniform1i(glGetUniformLocation(prog, "u_shadow_steps"), std::clamp(o.shadow_steps, 1, 4096));
  glUniform1f(glGetUniformLocation(prog, "u_light_size"), o.light_size * 3.14159265f / 180.0f);
  glUniform1f(glGetUniformLocation(prog, "u_h_min"), h_min_);
  glUniform1i(glGetUniformLocation(prog, "u_silhouettes"), o.silhouettes ? 1 : 0);
  glUniform1f(glGetUniformLocation(prog, "u_h_max"), h_max_);
  // The methods' own knobs, clamped to the ranges preview.hpp documents (a uniform a program
  // does not have is located at -1, which glUniform ignores).
  glUniform1i(glGetUniformLocation(prog, "u_binary_steps"), std::clamp(o.binary_steps, 0, 64));
  glUniform1i(glGetUniformLocation(prog, "u_bisection_steps"), std::clamp(o.bisection_steps, 0, 64));
  glUniform1f(glGetUniformLocation(prog, "u_dig_epsilon"), std::isfinite(o.dig_epsilon) ? std::clamp(o.dig_epsilon, 0.0f, 1.0f) : 0.1f);
  glUniform1f(glGetUniformLocation(prog, "u_dig_fallback"),
              std::isfinite(o.dig_fallback_texels) && o.dig_fallback_texels > 0 ? o.dig_fallback_texels : 1e30f);
  const int cone = o.method == "cone" ? 0 : o.method == "relaxed-cone" ? 1 : -1;
  const bool pyramid = o.method == "pyramid";
  const bool stream_missing = o.method == "sphere-tracing" ? !sdf_tex_
                              : pyramid                    ? !pyramid_tex_
                                                           : cone >= 0 && !cone_tex_[static_cast<size_t>(cone)];
  if (stream_missing) throw UsageError("method " + o.method + " needs the stream " + required_stream(o.method) + " (meso streams)");
  // Streams and shaders agree on the border (height_field.hpp): a tiling field makes the
  // height and normal maps tile too. A method with a stream follows its stream; the others
  // tile when any loaded stream does.
  const bool wrap = o.method == "sphere-tracing" ? sdf_wrap_
                    : pyramid                    ? pyramid_wrap_
                    : vdm                        ? vdm_wrap_
                    : cone >= 0                  ? cone_wrap_[static_cast<size_t>(cone)]
                                                 : (sdf_tex_ && sdf_wrap_) || (cone_tex_[0] && cone_wrap_[0]) ||
                                      (cone_tex_[1] && cone_wrap_[1]) || (pyramid_tex_ && pyramid_wrap_) ||
                                      (vdm_weights_tex_ && vdm_wrap_);
  const GLint wrap_mode = wrap ? GL_REPEAT : GL_CLAMP_TO_EDGE;
  glUniform1i(glGetUniformLocation(prog, "u_wrap"), wrap ? 1 : 0);
  for (GLuint tex : {height_tex_, normal_tex_}) {
    glBindTexture(GL_TEXTURE_2D, tex);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, wrap_mode);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, wrap_mode);
  }
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, height_tex_);
  glActiveTexture(GL_TEXTURE1);
  glBindTexture(GL_TEXTURE_2D, normal_tex_);
  glActiveTexture(GL_TEXTURE2);
  glBindTexture(GL_TEXTURE_3D, sdf_tex_);
  glUniform1f(glGetUniformLocation(prog, "u_sdf_scale"), sdf_scale_);
  glUniform1f(glGetUniformLocation(prog, "u_sdf_bias"), sdf_bias_);
  glUniform1f(glGetUniformLocation(prog, "u_sdf_relief"), sdf_relief_);
  glUniform1f(glGetUniformLocation(prog, "u_sdf_aspect"), sdf_aspect_);
  glUniform1f(glGetUniformLocation(prog, "u_sdf_epsilon"), sdf_epsilon_);
  glUniform1f(glGetUniformLocation(prog, "u_sdf_margin"), sdf_margin_);
  const size_t c = cone >= 0 ? static_cast<size_t>(cone) : 0;
  glActiveTexture(GL_TEXTURE3);
  glBindTexture(GL_TEXTURE_2D, cone_tex_[c]);
  glActiveTexture(GL_TEXTURE4);
  glBindTexture(GL_TEXTURE_2D, pyramid_tex_);
  glUniform1i(glGetUniformLocation(prog, "u_pyramid_levels"), pyramid_levels_);
  if (pyramid_levels_ > 0) {
    glUniform2iv(glGetUniformLocation(prog, "u_pyramid_offset"), pyramid_levels_, pyramid_offset_.data());
    glUniform2iv(glGetUniformLocation(prog, "u_pyramid_size"), pyramid_levels_, pyramid_size_.data());
  }
  // View-dependent displacement (vdm.glsl).
  glActiveTexture(GL_TEXTURE6);
  glBindTexture(GL_TEXTURE_2D_ARRAY, vdm_weights_tex_);
  glActiveTexture(GL_TEXTURE7);
  glBindTexture(GL_TEXTURE_2D, vdm_basis_tex_);
  if (vdm_weights_tex_) {
    glUniform1i(glGetUniformLocation(prog, "u_vdm_rank"), vdm_rank_);
    glUniform1i(glGetUniformLocation(prog, "u_vdm_theta"), vdm_theta_);
    glUniform1i(glGetUniformLocation(prog, "u_vdm_phi"), vdm_phi_);
    glUniform1f(glGetUniformLocation(prog, "u_vdm_theta_max"), vdm_theta_max_);
    glUniform1i(glGetUniformLocation(prog, "u_vdm_curvature_count"), static_cast<GLint>(vdm_curvatures_.size()));
    glUniform1fv(glGetUniformLocation(prog, "u_vdm_curvatures"), static_cast<GLsizei>(vdm_curvatures_.size()), vdm_curvatures_.data());
    glUniform1f(glGetUniformLocation(prog, "u_vdm_relief"), vdm_relief_);
    glUniform1f(glGetUniformLocation(prog, "u_vdm_scale"), vdm_scale_);
    glUniform1f(glGetUniformLocation(prog, "u_vdm_bias"), vdm_bias_);
    glUniform1f(glGetUniformLocation(prog, "u_vdm_aspect"), vdm_aspect_);
  }
  // The method's stream: its normalisation and border (footprint.glsl reads the height map
  // with them; sphere tracing's exact texel tests use the distance field's).
  const bool sdf = o.method == "sphere-tracing";
  glUniform1f(glGetUniformLocation(prog, "u_stream_scale"), sdf ? sdf_scale_ : pyramid ? pyramid_scale_ : cone_scale_[c]);
  glUniform1f(glGetUniformLocation(prog, "u_stream_bias"), sdf ? sdf_bias_ : pyramid ? pyramid_bias_ : cone_bias_[c]);
  glUniform1i(glGetUniformLocation(prog, "u_stream_wrap"), (sdf ? sdf_wrap_ : pyramid ? pyramid_wrap_ : cone_wrap_[c]) ? 1 : 0);
  const GLint ndc = glGetUniformLocation(prog, "u_ndc_transform");
  glUniform4f(ndc, 1.0f, 0.0f, 1.0f, 0.0f);
  glBindVertexArray(vao_);
  if (o.method == "dig") {
    // Pass 1 (dig.glsl): grid texel (i, j) holds the ray of pixel (4i, 4j), for the corners of
    // every 4 x 4 block: (width - 1) / 4 + 2 corners across. Normalised device x of pixel
    // 4i's centre, 2 (4i + 0.5) / width - 1, maps onto grid texel i's, 2 (i + 0.5) / grid - 1.
    const int gw = (width - 1) / 4 + 2, gh = (height - 1) / 4 + 2;
    ensure_dig_target(gw, gh);
    GLint previous = 0;
    glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &previous);
    glBindFramebuffer(GL_FRAMEBUFFER, dig_fbo_);
    glViewport(0, 0, gw, gh);
    glClearColor(-1, 0, 0, 0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    const float w = static_cast<float>(width), h = static_cast<float>(height);
    glUniform4f(ndc, w / (4.0f * static_cast<float>(gw)), (w + 3.0f) / (4.0f * static_cast<float>(gw)) - 1.0f,
                h / (4.0f * static_cast<float>(gh)), (h + 3.0f) / (4.0f * static_cast<float>(gh)) - 1.0f);
    glUniform1i(glGetUniformLocation(prog, "u_dig_pass"), 1);
    glDrawElements(GL_TRIANGLES, index_count_, GL_UNSIGNED_INT, nullptr);
    glBindFramebuffer(GL_FRAMEBUFFER, static_cast<GLuint>(previous));
    glViewport(0, 0, width, height);
    glUniform4f(ndc, 1.0f, 0.0f, 1.0f, 0.0f);
    glActiveTexture(GL_TEXTURE5);
    glBindTexture(GL_TEXTURE_2D, dig_tex_);
  }
  glUniform1i(glGetUniformLocation(prog, "u_dig_pass"), 2);
  if (dstream) {
    const int level = bind_dstream(o, pose);
    glBindVertexArray(dstream_vao_);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, dstream_indices_[static_cast<size_t>(level)]);
    glDrawElements(GL_TRIANGLES, dstream_index_count_[static_cast<size_t>(level)], GL_UNSIGNED_INT, nullptr);
  } else if (per_vertex) {
    glUniform1i(glGetUniformLocation(prog, "u_tess_mode"), o.method == "mesh" ? 0 : 1);
    glUniform2f(glGetUniformLocation(prog, "u_viewport"), static_cast<float>(width), static_cast<float>(height));
    auto positive = [](float v, float fallback) { return std::isfinite(v) && v > 0 ? v : fallback; };
    glUniform1i(glGetUniformLocation(prog, "u_tess_edge_samples"), std::clamp(o.tess_edge_samples, 1, 64));
    glUniform1f(glGetUniformLocation(prog, "u_tess_displacement"), std::isfinite(o.tess_displacement) ? std::max(o.tess_displacement, 0.0f) : 0.02f);
    glUniform1f(glGetUniformLocation(prog, "u_tess_normal_angle"), positive(o.tess_normal_angle, 5.0f) * 3.14159265f / 180.0f);
    glUniform1f(glGetUniformLocation(prog, "u_tess_pixels"), positive(o.tess_pixels, 2.0f));
    const GLuint zero = 0;
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, vertex_work_);
    glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof zero, &zero);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, vertex_work_);
    glPatchParameteri(GL_PATCH_VERTICES, 3);
    // A few patches per draw call: with all patches in one draw, Mesa's llvmpipe dropped
    // part of the output of large tessellations (an 8 x 8 grid at a segment per texel of a
    // 256² map lost 13,666 of its pixels; where its limit lies was not measured). 16 per call
    // draws every patch (Measure.PerVertexMethodsDrawEveryPatchAndMeshASegmentPerTexel).
    const bool cut = o.method == "mesh" && mesh_vao_;
    if (cut) glBindVertexArray(mesh_vao_);
    const GLsizei count = cut ? mesh_index_count_ : index_count_;
    constexpr GLsizei kPatchesPerDraw = 16;
    for (GLsizei first = 0; first < count; first += 3 * kPatchesPerDraw)
      glDrawElements(GL_PATCHES, std::min<GLsizei>(3 * kPatchesPerDraw, count - first), GL_UNSIGNED_INT,
                     reinterpret_cast<const void*>(static_cast<size_t>(first) * sizeof(uint32_t)));
  } else {
    glDrawElements(GL_TRIANGLES, index_count_, GL_UNSIGNED_INT, nullptr);
  }
  last_per_vertex_ = per_vertex;
  glBindVertexArray(0);
  if (!o.status_line.empty()) {
    if (!status_line_) status_line_ = std::make_unique<StatusLine>();
    status_line_->draw(o.status_line, width, height);
  }
}

}  // namespace meso
