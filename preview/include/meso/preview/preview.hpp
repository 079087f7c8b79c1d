// preview: renders the base mesh with its baked maps by per-pixel displacement methods,
// headless through EGL (Mesa llvmpipe in CI) or in a GLFW window; OpenGL 4.5 core.
#pragma once

#include "meso/core/image.hpp"
#include "meso/core/mesh.hpp"

#include <string>
#include <vector>

namespace meso {

// What `meso bake` wrote: displacement (1 channel, object units along the base normal,
// positive outward) and the tangent-space normal map (3 channels, encoded n * 0.5 + 0.5);
// and the streams the chosen method needs (`meso streams`), computed from that displacement.
struct PreviewMaps {
  Image displacement;
  Image normal_ts;
  Image sdf;  // sdf.exr as written (W x H*depth, metadata depth, relief, height_scale/bias, border)
  // cone.exr and relaxed-cone.exr (meso streams cone / relaxed-cone), level 0 as read_image
  // returns it: W x H, R = height, G = cone ratio, B = apex height; metadata cone_kind,
  // height_scale/bias, border, texels_per_u.
  Image cone;
  Image relaxed_cone;
};

// The stream file a method needs in --streams DIR ("sdf.exr", "cone.exr",
// "relaxed-cone.exr"), or "" for none.
std::string required_stream(const std::string& method);

// The member of `maps` that holds the stream `required_stream(method)`, or nullptr when the
// method needs none.
const Image* stream_for(const PreviewMaps& maps, const std::string& method);
Image* stream_for(PreviewMaps& maps, const std::string& method);

// Throws InputError naming `name` unless `sdf` is meso streams sdf's output for exactly this
// displacement map (its size and the height range it normalised).
void check_sdf_matches(const Image& sdf, const Image& displacement, const std::string& name);

// Throws InputError naming `name` unless `cone` is meso streams cone (kind "conservative") or
// relaxed-cone (kind "relaxed") output for exactly this displacement map: its size, the
// height range it normalised, 3 channels and the kind.
void check_cone_matches(const Image& cone, const Image& displacement, const std::string& kind, const std::string& name);

// Checks the stream `required_stream(method)` against the displacement map (one of the two
// functions above); nothing for a method that needs no stream.
void check_stream_matches(const std::string& method, const Image& stream, const Image& displacement, const std::string& name);

enum class PreviewShade {
  lit,     // Lambert shading with the mesostructure normal, sRGB-encoded
  uv,      // R, G = UV of the visible point found by the method (for measurements)
  height,  // R = displacement at the visible point, object units
};

struct PreviewCamera {
  // Degrees between the view direction and the mesh's mean normal (0 = straight on,
  // up to 89.9), and around it (0 = from the side of +tangent of the mean frame).
  float view_angle = 30.0f;
  float azimuth = 0.0f;
  float zoom = 1.0f;  // > 1 moves closer
};

struct PreviewOptions {
  std::string method = "pom";
  int width = 512, height = 512;
  PreviewCamera camera;
  int iterations = 32;  // the method's main iteration budget (POM: linear-search steps; cone methods: loop passes)
  PreviewShade shade = PreviewShade::lit;
};

// Method names this build renders, in the order of the survey.
const std::vector<std::string>& preview_methods();

// Renders one frame off screen. Returns RGBA float pixels, top row first; alpha is 1 on
// the mesh and 0 on the background. Throws UsageError for an unknown method and
// InternalError when no OpenGL 4.5 context can be had.
Image render_headless(const Mesh& base, const PreviewMaps& maps, const PreviewOptions& options);

// Opens a window and renders interactively until it is closed: left drag orbits, wheel
// zooms, 1-9 and 0 choose among the first ten methods, Tab (Shift+Tab) goes to the next
// (previous) method, +/- change the iteration budget; methods whose stream was not loaded
// are skipped. Throws InternalError when no display is available.
void run_window(const Mesh& base, const PreviewMaps& maps, const PreviewOptions& options);

}  // namespace meso
