// preview: renders the base mesh with its baked maps by per-pixel displacement methods,
// headless through EGL (Mesa llvmpipe in CI) or in a GLFW window; OpenGL 4.5 core.
#pragma once

#include "meso/bake/displacement_stream.hpp"
#include "meso/core/image.hpp"
#include "meso/core/mesh.hpp"

#include <cstddef>
#include <filesystem>
#include <memory>
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
  // pyramid.exr (meso streams pyramid), level 0 as read_image returns it: W x H, R = min and
  // G = max of the filtered surface over the texel's footprint (normalised heights); metadata
  // height_scale/bias, border. The coarser levels are rebuilt from it exactly as the streams
  // build them (min_max_pyramid_from_level0).
  Image pyramid;
  // vdm.exr (meso streams vdm), its two parts as read_image_parts returns them: the per-texel
  // PCA weights (W x H, one channel per component; metadata theta, theta_max, phi,
  // curvatures, relief, rank, height_scale/bias, border) and the mean and basis per direction
  // ((rank + 1) x directions). See docs/formats.md.
  Image vdm_weights, vdm_basis;
  // dstream.bin (meso streams dstream) for the base mesh: every level's compressed vertices.
  // Empty (no levels) when not loaded.
  EncodedStream dstream;
};

// Reads bake's maps from `dir` into maps.displacement (DIR/displacement.exr, channel 0, in
// object units: through its own meso:height_scale/meso:height_bias when it records them, as
// `meso streams` reads a height map) and maps.normal_ts (DIR/normal_ts.png, green up: a map
// baked with --normal-y down is turned back). Throws InputError naming the file when one is
// missing or unreadable, holds another meso:quantity, is an object-space normal map, or has
// heights whose span exceeds the float range.
void load_bake_maps(PreviewMaps& maps, const std::filesystem::path& dir);

// The stream file a method needs in --streams DIR ("sdf.exr", "cone.exr",
// "relaxed-cone.exr", "pyramid.exr", "vdm.exr", "dstream.bin"), or "" for none.
std::string required_stream(const std::string& method);

// Whether `maps` holds what `method` needs (true for a method that needs no stream).
bool has_stream(const PreviewMaps& maps, const std::string& method);

// Reads `file` into the member of `maps` that holds the stream `required_stream(method)` and
// checks that it belongs to this displacement map (image streams: size, height range, kind)
// or, for dstream.bin, to this base mesh (vertex and triangle counts). Throws InputError
// naming `file` when it is missing, unreadable or made from something else; `maps` is left
// unchanged then. Nothing for a method that needs no stream.
void load_stream(PreviewMaps& maps, const Mesh& base, const std::string& method, const std::filesystem::path& file);

// Empties the member of `maps` that holds the stream of `method`.
void clear_stream(PreviewMaps& maps, const std::string& method);

// Throws InputError naming `name` unless `sdf` is meso streams sdf's output for exactly this
// displacement map (its size and the height range it normalised).
void check_sdf_matches(const Image& sdf, const Image& displacement, const std::string& name);

// Throws InputError naming `name` unless `cone` is meso streams cone (kind "conservative") or
// relaxed-cone (kind "relaxed") output for exactly this displacement map: its size, the
// height range it normalised, 3 channels and the kind.
void check_cone_matches(const Image& cone, const Image& displacement, const std::string& kind, const std::string& name);

// Throws InputError naming `name` unless `weights` and `basis` are the two parts of meso streams
// vdm's output for exactly this displacement map (size, height range, parts' shapes), with
// increasing curvatures, rank and curvature count at most 64 (the previewer's limit).
void check_vdm_matches(const Image& weights, const Image& basis, const Image& displacement, const std::string& name);

// "" when the vdm table's relief (its metadata `relief`, units of u) is that of its height
// range on `base` (height_scale / object_length_per_uv, as `meso streams vdm --mesh` makes
// it) within 1 %; else a warning naming `name` and both figures. A table made without --mesh
// (relief 0.1 by default) traces another height field: 13 % wrong hits on the demo's bricks
// (relief 0.0028) against 1.4 % with --mesh.
std::string vdm_relief_mismatch(const Image& weights, const Mesh& base, const std::string& name);

// Throws InputError naming `name` unless `pyramid` is meso streams pyramid's output (level 0)
// for exactly this displacement map: its size, 2 channels, the height range it normalised.
void check_pyramid_matches(const Image& pyramid, const Image& displacement, const std::string& name);

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
  // Pan: the point looked at moves from the mesh's bounding-box centre across the view, right
  // and up on screen, in units of the framing radius (half the box's diagonal).
  float pan_x = 0.0f, pan_y = 0.0f;
  // The light, fixed relative to the mesh: degrees above the mean plane, and around the mean
  // normal from the same reference direction as azimuth (the defaults: n + 0.6 e2 - 0.4 e1).
  float light_elevation = 54.20424f;
  float light_azimuth = 123.690068f;
};

enum class PreviewShadows {
  none,
  hard,  // a shadow ray toward the light through the height field (linear search)
  soft,  // 8 shadow rays toward points of a disc light of angular radius light_size, averaged
};

struct PreviewOptions {
  std::string method = "pom";
  int width = 512, height = 512;
  PreviewCamera camera;
  // The method's main iteration budget (POM: linear-search steps; cone methods: loop passes;
  // sphere tracing: loop passes, sphere steps and the fine march near the surface alike).
  int iterations = 32;
  PreviewShade shade = PreviewShade::lit;
  // Self-shadowing of the lit shade: from the visible point toward the light, shadow_steps
  // samples of the height map up to the top of the height range (not counted as fetches: they
  // shade, they do not find the visible point; compare_methods renders without shadows, as
  // the reference has none).
  PreviewShadows shadows = PreviewShadows::none;
  int shadow_steps = 32;
  float light_size = 4.0f;  // degrees, angular radius of the soft shadows' light
  // Silhouettes (survey section 5.1): the linear-search methods (steep, relief, pom) bend the
  // view ray with the base's curvature along it (quadric fits per vertex) and discard it when
  // it leaves the height field without a hit; every per-pixel method discards a visible point
  // outside [0, 1]^2 of a map that does not tile. Off by default (compare_methods keeps it).
  bool silhouettes = false;
  // dstream: the level drawn is the finest whose segments per edge do not exceed
  // `iterations`. Its vertices morph toward the coarser level's surface: with morph in [0, 1]
  // all by that much (1: the level itself, 0: what the coarser level interpolates there);
  // with morph < 0 by distance from the eye, 1 up to lod_distance (object units), 0 from
  // twice that on (lod_distance 0: no morph).
  float morph = -1.0f;
  float lod_distance = 0.0f;
  // The methods' other quality knobs (the defaults are the ones docs/benchmarks.md measures;
  // out-of-range values are clamped to the ranges given):
  // relief: halvings of the linear-search step that crossed the surface (survey 4.4.1), 0..64.
  int binary_steps = 8;
  // relaxed-cone: halvings of the cone step that crossed the surface (survey 4.4.3), 0..64.
  int bisection_steps = 24;
  // dig: the least widening of a block's depth interval above its corners' depths (the depth-
  // interval-grid paper's epsilon_1, eq. 1), as a fraction of the slab's height, 0..1.
  float dig_epsilon = 0.1f;
  // dig: where a block's corner rays are more than this many texels apart across the ray's
  // path (minified regions, from the UV derivatives), features between them go unseen, and the
  // block's pixels search the whole slab as POM does. 0: never. Measured in docs/benchmarks.md.
  float dig_fallback_texels = 8.0f;
  // tessellation's adaptive edge tests (survey section 3; tess.tesc): an edge is cut at every
  // texel where the displacement sampled at tess_edge_samples + 1 points along it (1..64)
  // departs from the straight line between its ends by more than tess_displacement of the
  // height range; at least every tess_normal_angle degrees (> 0) of change between its end
  // normals; never into segments shorter than tess_pixels on screen (> 0).
  float tess_displacement = 0.02f;
  float tess_normal_angle = 5.0f;
  float tess_pixels = 2.0f;
  int tess_edge_samples = 8;
  // A line of text drawn over the frame at its top left (white on a dark band; ASCII; the
  // window's status line, see preview_status_line). Empty: none. The fetch counts do not see it.
  std::string status_line;
};

// The window's on-screen line for `options`: the method, its budget and its own knobs, the
// view angle, shadows and silhouettes, and the frame time `ms`.
std::string preview_status_line(const PreviewOptions& options, double ms);

// Method names this build renders: per vertex mesh, tessellation; per pixel in the order of
// the survey; then vdm (per pixel, vdm.exr) and dstream (per vertex, dstream.bin).
const std::vector<std::string>& preview_methods();

// Renders one frame off screen. Returns RGBA float pixels, top row first; alpha is 1 on
// the mesh and 0 on the background. Throws UsageError for an unknown method and
// InternalError when no OpenGL 4.5 context can be had.
Image render_headless(const Mesh& base, const PreviewMaps& maps, const PreviewOptions& options);

// An off-screen OpenGL 4.5 context (EGL) with the mesh and maps uploaded once, for rendering
// many frames of the same scene (render_headless makes one and renders once). `base` and
// `maps` must outlive it. Throws InternalError when no OpenGL 4.5 context can be had.
class HeadlessPreview {
 public:
  HeadlessPreview(const Mesh& base, const PreviewMaps& maps);
  ~HeadlessPreview();
  HeadlessPreview(const HeadlessPreview&) = delete;
  HeadlessPreview& operator=(const HeadlessPreview&) = delete;

  // One frame, as render_headless. With `fetches`, also the method's work per pixel: 2
  // channels, R = texture fetches the shader made to find the visible point (every lookup of
  // the height map and of the method's stream, and of the normal map where slope and
  // iterative parallax search with it; a filtered lookup counts one like a texelFetch; the
  // shading's own lookups are not counted), G = 1 on the mesh, 0 on the background.
  // Throws UsageError for an unknown method or one whose stream is not in the maps.
  Image render(const PreviewOptions& options, Image* fetches = nullptr);

  // Throws UsageError when this OpenGL cannot render frames of this size (before any other
  // work that would be lost).
  void check_size(int width, int height);

  // Wall time of one draw of `options` (clear, draw, glFinish) measured on the CPU clock, in
  // milliseconds: the median of `repetitions` draws after one unmeasured warm-up draw (Mesa
  // compiles shader variants on first use).
  double time_draw(const PreviewOptions& options, int repetitions = 5);

  // The dstream method's displaced vertices for `options` (the level and morph it would
  // draw), as its vertex shader computes them (captured by transform feedback), in the
  // level's order in dstream.bin; to check the GPU decoder against
  // decode_displacement_level(). Empty when no dstream is loaded.
  std::vector<Vec3f> dstream_positions(const PreviewOptions& options);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// ---- The measuring instrument: a CPU reference of the true displaced surface ----

struct ReferenceOptions {
  // Flat parts of the base (connected by shared edges, every vertex normal of the part's
  // triangles within 1e-6 of the others at the same triangle) are not tessellated: the surface
  // over them is the bilinear interpolation of the height texels displaced along their normal,
  // which the reference intersects exactly, texel cell by texel cell (one Embree user
  // primitive per cell a triangle overlaps, a quadratic along the ray in each). This is the
  // surface the per-pixel methods trace. A part with one curved triangle is tessellated
  // whole, so that no exact triangle meets a tessellated one (their edges would not match). false: tessellate them too (the reference before
  // the exact patches, kept to measure what the tessellation changes).
  bool bilinear_patches = true;
  // Each curved base triangle (or every one, without bilinear_patches) is cut by longest-edge bisection, edges measured in texels of the
  // displacement map (u W, v H), until no sub-triangle edge is longer than this.
  double max_edge_texels = 0.5;
  // Cap on the total count of sub-triangles and cells. When the flat triangles' cells (counted
  // over their UV boxes) exceed it, every triangle is tessellated. While the mesh would need more, max_edge_texels
  // doubles (up to 8 times), then the bisection depth is limited; max_edge_texels() reports
  // what was reached. Memory: about 110 bytes per triangle with Embree's structure (the
  // demo's 1024 x 1024 map at 0.5 texel: 28 M triangles, 3.1 GB).
  size_t max_triangles = size_t(1) << 25;
};

// The TRUE displaced surface ray traced with Embree 3: every base point p(b) moved along its
// normalised interpolated vertex normal by the displacement map sampled at its UV exactly as
// the shaders' GL_LINEAR lookups do (texel centres at +0.5; border clamp, or wrap when a
// loaded stream was made with --wrap): exactly over flat base triangles, tessellated over
// curved ones as described in ReferenceOptions. Pieces of flat triangles reach 1e-9 texel past
// their cell and triangle edges, so rays through shared edges and corners always hit. A
// sub-triangle edge is cut at its midpoint exactly when it is longer than the target, which
// depends on the edge alone, so neighbouring triangles cut shared edges alike, and points on
// an edge between base triangles with the same UVs there are computed bitwise alike from
// both sides: the surface has no cracks except where the displaced surface itself is torn
// (UV seams whose two sides' heights differ). `base` must outlive the renderer (it needs
// vertex normals and UVs); the maps are copied.
class ReferenceRenderer {
 public:
  ReferenceRenderer(const Mesh& base, const PreviewMaps& maps, const ReferenceOptions& options = {});
  ~ReferenceRenderer();
  ReferenceRenderer(const ReferenceRenderer&) = delete;
  ReferenceRenderer& operator=(const ReferenceRenderer&) = delete;

  // The same image as render_headless for options.width x height, camera and shade, pixel
  // centres and camera identical to the OpenGL renderer's (frame_camera), rows from the top,
  // RGBA float, alpha 1 where the ray hits the displaced surface and 0 elsewhere (RGB 0):
  //   uv:     R, G = the hit's UV (exact on a flat triangle, interpolated along the
  //           sub-triangle on a curved one), B = 0;
  //   height: R = the displacement map at the hit's UV (the shader's lookup);
  //   lit:    the shader's Lambert term with the normal map at the hit's UV decoded in the
  //           base frame at the hit's base point, flipped on base faces turned away from
  //           the eye (as gl_FrontFacing does), sRGB encoded.
  // options.method and options.iterations are ignored. Parallel over rows (TBB); the
  // result does not depend on the number of threads.
  Image render(const PreviewOptions& options) const;

  size_t triangle_count() const;  // sub-triangles of the curved base triangles
  size_t patch_count() const;     // cells of the flat ones, intersected exactly
  // The longest UV edge of any sub-triangle (0 when every triangle is flat), in texels of the displacement map.
  double max_edge_texels() const;
  // Wall time of the tessellation and the Embree build, milliseconds.
  double build_ms() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// One reference frame (builds a ReferenceRenderer with default options and renders).
Image render_reference(const Mesh& base, const PreviewMaps& maps, const PreviewOptions& options);

// ---- Method against reference ----

struct CompareOptions {
  // Methods to compare, in this order; empty: every method of preview_methods() whose
  // stream is in the maps.
  std::vector<std::string> methods;
  // width, height, camera and iteration budget; the method is ignored, the shade only
  // chooses Comparison::reference_view.
  PreviewOptions view;
  double uv_tolerance_texels = 1.0;  // a visible point farther from the reference's is a wrong hit
  int repetitions = 5;             // timed draws per method (median)
  ReferenceOptions reference;
};

struct MethodComparison {
  std::string name;
  size_t pixels = 0;  // pixels covered by the reference or the method (or both)
  size_t wrong_hits = 0;
  // wrong_hits / pixels: pixels covered by one of the two only, or whose visible points'
  // UVs differ by more than uv_tolerance_texels (Euclidean, in texels of the displacement
  // map; across the border of a tiling map the shorter way round).
  double wrong_hit_fraction = 0;
  // Of the lit images over the same pixels (a pixel off one image counts with that image's
  // transparent black), RGB, on the sRGB-encoded values in [0, 1] (1 = 255 in the PNG),
  // unquantised; psnr = 20 log10(1 / rmse) dB, infinite when the images are equal.
  // NaN (wrong_hit_fraction too) when `pixels` is 0: nothing was measured.
  double rmse = 0, psnr = 0;
  // Texture fetches per pixel on the method's mesh pixels (HeadlessPreview::render's
  // `fetches`): mean and 99th percentile (nearest rank); NaN when the method covers no pixel.
  double mean_iterations = 0, p99_iterations = 0;
  double max_iterations = 0;
  double ms = 0;  // HeadlessPreview::time_draw of the lit frame
  Image fetches;  // the per-pixel counts (2 channels, see HeadlessPreview::render)
};

struct Comparison {
  size_t reference_triangles = 0;
  size_t reference_patches = 0;
  double reference_max_edge_texels = 0;
  double reference_build_ms = 0;
  double reference_ms = 0;  // ray tracing the uv frame (the lit frame takes as long)
  PreviewOptions view;
  double uv_tolerance_texels = 1.0;
  std::vector<MethodComparison> methods;
  Image reference_uv, reference_lit;
  Image reference_view;  // the reference in CompareOptions::view.shade
};

// Renders the reference once (uv and lit shades) and each method (uv and lit, with its
// fetch counts, then timed), and measures each against the reference. Throws UsageError
// for an unknown method or one whose stream is not in the maps, InternalError without
// OpenGL 4.5.
Comparison compare_methods(const Mesh& base, const PreviewMaps& maps, const CompareOptions& options);

// The comparison as a JSON object (what `meso preview --compare --json` prints):
//   {"reference": {"triangles", "max_edge_texels", "build_ms", "ms"},
//    "width", "height", "view_angle", "azimuth", "zoom", "iterations", "uv_tolerance_texels",
//    "methods": [{"name", "pixels", "wrong_hit_fraction", "rmse", "psnr", "mean_iterations",
//                 "p99_iterations", "max_iterations", "ms"}, ...]}
// NaN and infinite figures are null.
std::string comparison_json(const Comparison& comparison);

// The fetch statistics of MethodComparison from HeadlessPreview::render's `fetches`: mean,
// 99th percentile (nearest rank: the ceil(0.99 n)-th smallest) and maximum over the pixels
// the method covers; NaN when it covers none.
void fetch_statistics(const Image& fetches, MethodComparison& r);

// A colour picture of fetch counts (HeadlessPreview::render's `fetches`): RGBA, the viridis
// ramp (dark blue 0, green, yellow at `max_fetches` and above) over
// log2(1 + fetches) / log2(1 + max_fetches); alpha 1 on the mesh, 0 (and black) elsewhere.
Image fetch_heatmap(const Image& fetches, double max_fetches);

// Opens a window and renders interactively until it is closed: left drag orbits, wheel
// zooms, 1-9 and 0 choose among the first ten methods, Tab (Shift+Tab) goes to the next
// (previous) method, +/- change the iteration budget, S cycles the shadows (none, hard,
// soft), C toggles silhouettes, the arrow keys move the light; methods whose stream was not loaded are skipped; the
// on-screen line (and the title) shows the method, its budget and knobs, the view angle, the
// shadows and the frame time. With `frames` > 0 it closes itself after that many frames and
// returns the last one as drawn (RGBA float, top row first, read back before the swap; alpha
// as the window's framebuffer has it), for scripted runs and tests.
// Throws InternalError when no display is available.
struct WindowRun {
  int frames = 0;          // frames drawn
  double median_ms = 0;    // draw time per frame, median of the last 256 (CPU clock around draw and glFinish)
  Image last_frame;        // with frames > 0 only
};
WindowRun run_window(const Mesh& base, const PreviewMaps& maps, const PreviewOptions& options, int frames = 0);

}  // namespace meso
