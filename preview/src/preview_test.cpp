// Headless rendering on whatever EGL offers (Mesa llvmpipe in CI), checked against the
// closed-form answers of flat height fields seen through the centre pixel.
#include "meso/preview/preview.hpp"

#include "meso/core/error.hpp"
#include "meso/streams/cone_map.hpp"
#include "meso/streams/distance_field.hpp"
#include "meso/streams/pyramid.hpp"
#include "meso/streams/vdm.hpp"
#include "renderer.hpp"
#include "sampling.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>

namespace meso {
namespace {

constexpr double kPi = 3.14159265358979323846;

PreviewMaps maps_with_height(float (*height)(float u)) {
  PreviewMaps maps;
  maps.displacement = Image(64, 64, 1);
  maps.normal_ts = Image(4, 4, 3);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) maps.displacement.at(x, y) = height(texel_center_u(x, 64));
  for (size_t i = 0; i < maps.normal_ts.texel_count(); ++i) {
    maps.normal_ts.pixels[3 * i] = 0.5f;  // encoded (0, 0, 1)
    maps.normal_ts.pixels[3 * i + 1] = 0.5f;
    maps.normal_ts.pixels[3 * i + 2] = 1.0f;
  }
  return maps;
}

// pyramid.exr's level 0 as meso streams pyramid writes it.
Image pyramid_image(const HeightField& field) {
  Image level0 = footprint_min_max(field);
  level0.metadata = height_field_metadata(field);
  return level0;
}

// Adds the cone maps and the max pyramid of the displacement (as meso streams cone /
// relaxed-cone / pyramid make them).
void add_cone_maps(PreviewMaps& maps, Border border) {
  const HeightField field = make_height_field(maps.displacement, border);
  maps.cone = build_cone_map(field, ConeMapOptions{});
  ConeMapOptions relaxed;
  relaxed.kind = ConeKind::relaxed;
  maps.relaxed_cone = build_cone_map(field, relaxed);
  maps.pyramid = pyramid_image(field);
}

// vdm.exr's two parts for the displacement (as meso streams vdm makes them).
void add_vdm(PreviewMaps& maps, Border border, const VdmOptions& options, double max_rms = 1e-5) {
  const HeightField field = make_height_field(maps.displacement, border);
  const std::vector<Image> parts = vdm_images(compress_vdm(build_vdm(field, options), max_rms, 64), field, options);
  maps.vdm_weights = parts[0];
  maps.vdm_basis = parts[1];
}

// dstream.bin's levels for `base` sampled against `high` (as meso streams dstream makes them).
void add_dstream(PreviewMaps& maps, const Mesh& base, const Mesh& high, int levels) {
  DisplacementStreamOptions o;
  o.levels = levels;
  maps.dstream = encode_displacement_stream(sample_displacement_stream(base, high, o));
}

// Of an RGBA render `img`: its drawn pixels (alpha above 1/2), the pixels drawn in `base` (a
// bump render: the base mesh's own triangles) but not in it, and its non-finite samples.
struct Coverage {
  size_t covered = 0, holes = 0, non_finite = 0;
};
Coverage coverage(const Image& img, const Image& base) {
  Coverage c;
  for (size_t i = 0; i < img.texel_count(); ++i) {
    for (size_t k = 0; k < 4; ++k) c.non_finite += !std::isfinite(img.pixels[4 * i + k]);
    const bool on = img.pixels[4 * i + 3] > 0.5f;
    c.covered += on;
    c.holes += !on && base.pixels[4 * i + 3] > 0.5f;
  }
  return c;
}

// A size x size frame of the visible points' UVs from `angle` degrees off the normal.
PreviewOptions uv_view(int size, float angle, float azimuth) {
  PreviewOptions o;
  o.width = o.height = size;
  o.camera.view_angle = angle;
  o.camera.azimuth = azimuth;
  o.shade = PreviewShade::uv;
  return o;
}

// 65 x 65 pixels: the centre pixel's ray goes exactly through the look-at point, the centre
// of the unit quad, UV (0.5, 0.5). With view angle a and azimuth 0 the eye lies toward +x.
PreviewOptions centre_uv_options(const std::string& method, float view_angle) {
  PreviewOptions o;
  o.method = method;
  o.width = o.height = 65;
  o.camera.view_angle = view_angle;
  o.iterations = 64;
  o.shade = PreviewShade::uv;
  return o;
}

TEST(Preview, ConstantHeightShiftsTheVisiblePointByHTanTheta) {
  const Mesh quad = test::make_grid(1, 1);
  PreviewMaps maps = maps_with_height([](float) { return 0.05f; });
  add_cone_maps(maps, Border::clamp);  // a flat field: height scale 0
  for (const char* method : {"parallax", "iterative-parallax", "steep", "relief", "pom", "cone", "relaxed-cone", "pyramid", "dig"}) {
    for (float angle : {0.0f, 30.0f, 60.0f}) {
      const Image img = render_headless(quad, maps, centre_uv_options(method, angle));
      const double expect_u = 0.5 + 0.05 * std::tan(angle * kPi / 180.0);
      EXPECT_NEAR(img.at(32, 32, 0), expect_u, 2e-4) << method << " at " << angle << " degrees";
      EXPECT_NEAR(img.at(32, 32, 1), 0.5, 2e-4) << method;
    }
  }
  const Image bump = render_headless(quad, maps, centre_uv_options("bump", 60.0f));
  EXPECT_NEAR(bump.at(32, 32, 0), 0.5, 1e-5) << "bump mapping does not move the texture coordinate";
}

// Offset limiting (and the slope variant on a flat normal map) drops the division by V_z:
// the shift is h sin(theta), never more than h.
TEST(Preview, OffsetLimitedShiftsByHSinTheta) {
  const Mesh quad = test::make_grid(1, 1);
  const PreviewMaps maps = maps_with_height([](float) { return 0.05f; });
  for (const char* method : {"offset-limited", "slope"}) {
    for (float angle : {0.0f, 45.0f, 80.0f}) {
      const Image img = render_headless(quad, maps, centre_uv_options(method, angle));
      EXPECT_NEAR(img.at(32, 32, 0), 0.5 + 0.05 * std::sin(angle * kPi / 180.0), 2e-4) << method << " at " << angle;
    }
  }
}

TEST(Preview, SafeAndRefiningMethodsFindTheCrossingOfALinearRamp) {
  const Mesh quad = test::make_grid(1, 1);
  PreviewMaps maps = maps_with_height([](float u) { return 0.1f * u; });
  const HeightField field = make_height_field(maps.displacement, Border::clamp);
  DistanceFieldOptions o;
  o.depth = 32;
  o.relief = 0.1f;
  maps.sdf = distance_field_image(build_distance_field(field, o), field);
  add_cone_maps(maps, Border::clamp);
  const double a = 50.0 * kPi / 180.0, k = 0.1;
  const double dx = -std::sin(a), dz = -std::cos(a);
  const double expect = 0.5 + dx * (0.5 * k / (dz - k * dx));
  for (const auto& [method, tolerance] : {std::pair<const char*, double>{"relief", 2e-4}, {"pom", 2e-4}, {"cone", 2e-4}, {"relaxed-cone", 2e-4}, {"pyramid", 2e-4}, {"dig", 2e-4}, {"sphere-tracing", 2e-4}}) {
    PreviewOptions opt = centre_uv_options(method, 50.0f);
    opt.iterations = 128;
    const Image img = render_headless(quad, maps, opt);
    EXPECT_NEAR(img.at(32, 32, 0), expect, tolerance) << method;
  }
}

// Panning slides the picture: straight on, a flat quad's points all lie at the depth of the
// point looked at, so the quad moves by pan x cos(20 deg) of the half-width (the framing's
// 40 degree field of view, zoom 1): left for a positive pan x (the view moves right), and as
// far across the rows for pan y.
TEST(Preview, PanSlidesTheViewAcrossTheScreen) {
  const Mesh quad = test::make_grid(1, 1);
  const PreviewMaps maps = maps_with_height([](float) { return 0.0f; });
  auto centroid = [&](float pan_x, float pan_y) {
    PreviewOptions o;
    o.method = "bump";
    o.width = o.height = 64;
    o.camera.view_angle = 0.0f;
    o.camera.pan_x = pan_x;
    o.camera.pan_y = pan_y;
    const Image img = render_headless(quad, maps, o);
    double sx = 0, sy = 0, n = 0;
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x)
        if (img.at(x, y, 3) > 0.5f) sx += x, sy += y, n += 1;
    EXPECT_GT(n, 100);
    return std::array<double, 2>{sx / n, sy / n};
  };
  const auto c0 = centroid(0, 0), c1 = centroid(0.25f, 0), c2 = centroid(0, -0.25f);
  const double shift = 0.25 * std::cos(20.0 * kPi / 180.0) * 32.0;  // pixels
  EXPECT_NEAR(c1[0] - c0[0], -shift, 0.5);
  EXPECT_NEAR(c1[1] - c0[1], 0.0, 0.5);
  EXPECT_NEAR(c2[0] - c0[0], 0.0, 0.5);
  EXPECT_NEAR(std::abs(c2[1] - c0[1]), shift, 0.5);
}

// The window's on-screen line: what it says, and that drawing it changes only the top left of
// the frame (white glyphs on a dark band) and none of the fetch counts.
TEST(Preview, StatusLineIsDrawnAtTheTopLeftOnly) {
  PreviewOptions o = uv_view(256, 30.0f, 0.0f);
  o.method = "relief";
  o.shade = PreviewShade::lit;
  const std::string line = preview_status_line(o, 12.345);
  EXPECT_NE(line.find("relief"), std::string::npos) << line;
  EXPECT_NE(line.find("8 halvings"), std::string::npos) << line;
  EXPECT_NE(line.find("12.35 ms"), std::string::npos) << line;
  o.method = "tessellation";
  EXPECT_NE(preview_status_line(o, 1).find("5 deg"), std::string::npos) << preview_status_line(o, 1);
  o.method = "relief";
  const Mesh quad = test::make_grid(1, 1);
  const PreviewMaps maps = maps_with_height([](float u) { return 0.05f * u; });
  HeadlessPreview gpu(quad, maps);
  Image plain_fetches, lined_fetches;
  const Image plain = gpu.render(o, &plain_fetches);
  o.status_line = line;
  const Image lined = gpu.render(o, &lined_fetches);
  EXPECT_EQ(plain_fetches.pixels, lined_fetches.pixels);
  size_t changed = 0, white = 0;
  int lowest = -1;
  for (int y = 0; y < plain.height; ++y)
    for (int x = 0; x < plain.width; ++x) {
      bool differs = false;
      for (int c = 0; c < 4; ++c) differs |= plain.at(x, y, c) != lined.at(x, y, c);
      if (!differs) continue;
      ++changed;
      lowest = std::max(lowest, y);
      white += lined.at(x, y, 0) == 1.0f && lined.at(x, y, 1) == 1.0f && lined.at(x, y, 2) == 1.0f && lined.at(x, y, 3) == 1.0f;
    }
  std::printf("status line: %zu pixels changed (%zu white glyph pixels), rows 0-%d\n", changed, white, lowest);
  EXPECT_GT(white, 100u);
  EXPECT_GT(changed, 3 * white);
  EXPECT_LT(lowest, 20) << "one line of text at the top";
}

// Every method, straight on and at 89.9 degrees, on a rough height field over a curved base:
// finite pixels only, and the mesh where it should be.
TEST(Preview, EveryMethodIsStableStraightOnAndGrazing) {
  const Mesh cylinder = test::make_parametric(32, 8, [](double s, double t) {
    const double a = 1.2 * (s - 0.5);
    return Vec3f(float(std::sin(a)), float(t), float(std::cos(a) - 1.0));
  }, false, false);
  PreviewMaps maps;
  maps.displacement = Image(32, 32, 1);
  maps.normal_ts = Image(32, 32, 3);
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) {
      maps.displacement.at(x, y) = 0.05f * std::abs(std::sin(0.9f * x) * std::cos(1.3f * y));
      const float nx = 0.4f * std::sin(0.3f * x), ny = 0.3f * std::cos(0.5f * y);
      maps.normal_ts.at(x, y, 0) = nx * 0.5f + 0.5f;
      maps.normal_ts.at(x, y, 1) = ny * 0.5f + 0.5f;
      maps.normal_ts.at(x, y, 2) = std::sqrt(1 - nx * nx - ny * ny) * 0.5f + 0.5f;
    }
  const HeightField field = make_height_field(maps.displacement, Border::clamp);
  maps.sdf = distance_field_image(build_distance_field(field, DistanceFieldOptions{}), field);
  add_cone_maps(maps, Border::clamp);
  VdmOptions vdm;
  vdm.theta = 4;
  vdm.phi = 8;
  vdm.curvatures = {0.0f, 1.0f};
  add_vdm(maps, Border::clamp, vdm, 1e-3);
  add_dstream(maps, cylinder, cylinder, 3);
  // No holes: a per-pixel method draws every pixel of the base mesh's own triangles (bump's
  // coverage), straight on and at 89.9 degrees alike, unless it discards on purpose (vdm:
  // rays that leave its bent height field; silhouettes are off). The per-vertex methods'
  // geometry moves with the heights, so their coverage is only required to be substantial.
  HeadlessPreview gpu(cylinder, maps);
  const std::set<std::string> per_vertex = {"mesh", "tessellation", "dstream"};
  for (float angle : {0.0f, 89.9f}) {
    PreviewOptions o;
    o.width = 40;
    o.height = 30;
    o.camera.view_angle = angle;
    o.method = "bump";
    const Image base = gpu.render(o);
    for (const auto& method : preview_methods()) {
      o.method = method;
      for (PreviewShade shade : {PreviewShade::lit, PreviewShade::uv}) {
        o.shade = shade;
        const Image img = gpu.render(o);
        const auto [covered, holes, non_finite] = coverage(img, base);
        ASSERT_EQ(non_finite, 0u) << method << " " << angle;
        if (angle == 0.0f) {
          EXPECT_GT(covered, img.texel_count() / 4) << method;
        }
        if (!per_vertex.count(method) && method != "vdm") {
          EXPECT_EQ(holes, 0u) << method << " at " << angle;
        } else {
          EXPECT_GT(covered, 0u) << method << " at " << angle;
        }
      }
    }
  }
}

// The per-pixel rays' frame (each triangle's dp/du and dp/dv with the interpolated normal)
// has fallbacks: a triangle whose UVs have no area, or collinear ones, has no dp/du; a normal
// that lies almost in its triangle's plane makes the frame singular. Neither may leave a
// hole (the parallax family's depth estimate had fallen behind the far plane: 24 pixels of
// offset limiting before the frame changed, 6 after) or a non-finite pixel, nor may normals
// that lean far but not that far (iterative parallax, whose steps assumed a height rate of at
// most 1, diverged: maps away, or NaN).
TEST(Preview, DegenerateUvsAndNormalsInTheTrianglesPlaneStayFinite) {
  Mesh grid = test::make_grid(2, 2);
  int face = 0;
  for (auto f : grid.faces()) {
    int corner = 0;
    for (auto h : grid.fh_range(f)) {
      if (face == 0) grid.set_texcoord2D(h, Vec2f(0.3f, 0.3f));  // one point
      if (face == 1) grid.set_texcoord2D(h, Vec2f(0.2f + 0.1f * static_cast<float>(corner), 0.6f));  // one line
      ++corner;
    }
    ++face;
  }
  // Every normal leans 80 degrees off the grid's plane (seen straight on, a ray climbs 5.8
  // units of height per unit of length), the centre's 89.4 degrees (the frame's fallback).
  for (auto v : grid.vertices()) grid.set_normal(v, Vec3f(0.0f, std::sin(80.0f * kPi / 180), std::cos(80.0f * kPi / 180)));
  grid.set_normal(VertexHandle(4), Vec3f(1.0f, 0.0f, 0.01f).normalized());
  PreviewMaps maps = maps_with_height([](float u) { return 0.05f * std::sin(20.0f * u); });
  add_cone_maps(maps, Border::clamp);
  const HeightField field = make_height_field(maps.displacement, Border::clamp);
  maps.sdf = distance_field_image(build_distance_field(field, DistanceFieldOptions{}), field);
  HeadlessPreview gpu(grid, maps);
  for (float angle : {0.0f, 60.0f, 89.9f}) {
    PreviewOptions o;
    o.width = o.height = 32;
    o.camera.view_angle = angle;
    o.camera.azimuth = 20.0f;
    o.iterations = 64;
    o.method = "bump";
    const Image base = gpu.render(o);
    o.shade = PreviewShade::uv;
    const Image base_uv = gpu.render(o);
    for (const auto& method : preview_methods()) {
      if (method == "mesh" || method == "tessellation" || method == "dstream" || method == "vdm") continue;
      o.method = method;
      for (PreviewShade shade : {PreviewShade::lit, PreviewShade::uv}) {
        o.shade = shade;
        const Image img = gpu.render(o);
        const Coverage drawn = coverage(img, base);
        size_t bad = drawn.non_finite;
        for (size_t i = 0; i < img.texel_count(); ++i) {
          // The methods that step by the height (offset limiting, slope, iterative parallax)
          // stay within reach of their base point; a diverging iteration lands maps away.
          // (Parallax and the searches may go far where the height rate nearly vanishes.)
          if (shade == PreviewShade::uv && img.pixels[4 * i + 3] > 0.5f &&
              (method == "offset-limited" || method == "slope" || method == "iterative-parallax"))
            bad += std::abs(img.pixels[4 * i] - 0.5f) > 1.5f || std::abs(img.pixels[4 * i + 1] - 0.5f) > 1.5f;
          // Offset limiting (and slope, which scales it by n_z <= 1) moves the visible point by
          // at most the height, 0.05 object units, along the base: 0.05 in UV on this grid,
          // where UV is position (it moved 0.28 when the lean made V_z 5.8).
          if (shade == PreviewShade::uv && img.pixels[4 * i + 3] > 0.5f && (method == "offset-limited" || method == "slope"))
            bad += std::hypot(img.pixels[4 * i] - base_uv.pixels[4 * i], img.pixels[4 * i + 1] - base_uv.pixels[4 * i + 1]) > 0.0501;
        }
        EXPECT_EQ(bad, 0u) << method << " at " << angle << (shade == PreviewShade::uv ? " uv" : " lit");
        EXPECT_EQ(drawn.holes, 0u) << method << " at " << angle;
      }
    }
  }
}

TEST(Preview, MethodsNeedTheirStreams) {
  const Mesh quad = test::make_grid(1, 1);
  PreviewMaps maps = maps_with_height([](float u) { return 0.1f * u; });
  for (const char* method : {"sphere-tracing", "cone", "relaxed-cone", "pyramid", "vdm", "dstream"}) {
    EXPECT_THROW(render_headless(quad, maps, centre_uv_options(method, 30.0f)), UsageError) << method;
    EXPECT_FALSE(has_stream(maps, method)) << method;
  }
  EXPECT_TRUE(has_stream(maps, "pom"));
  EXPECT_EQ(required_stream("vdm"), "vdm.exr");
  EXPECT_EQ(required_stream("dstream"), "dstream.bin");
  {
    // A VDM of another height map, or with its parts swapped, is refused.
    PreviewMaps other = maps;
    VdmOptions vdm;
    vdm.theta = 2;
    vdm.phi = 4;
    add_vdm(other, Border::clamp, vdm);
    EXPECT_NO_THROW(check_vdm_matches(other.vdm_weights, other.vdm_basis, maps.displacement, "vdm.exr"));
    EXPECT_THROW(check_vdm_matches(other.vdm_basis, other.vdm_weights, maps.displacement, "vdm.exr"), InputError);
    Image doubled = maps.displacement;
    for (float& v : doubled.pixels) v *= 2.0f;
    EXPECT_THROW(check_vdm_matches(other.vdm_weights, other.vdm_basis, doubled, "vdm.exr"), InputError);
  }
  EXPECT_EQ(required_stream("pyramid"), "pyramid.exr");
  // A pyramid of another height map is refused; this map's renders.
  const HeightField own = make_height_field(maps.displacement, Border::clamp);
  Image doubled = maps.displacement;
  for (float& v : doubled.pixels) v *= 2.0f;
  EXPECT_THROW(check_pyramid_matches(pyramid_image(make_height_field(doubled, Border::clamp)), maps.displacement, "pyramid.exr"), InputError);
  EXPECT_THROW(check_stream_matches("pyramid", maps.cone, maps.displacement, "pyramid.exr"), InputError);
  maps.pyramid = pyramid_image(own);
  EXPECT_NO_THROW(render_headless(quad, maps, centre_uv_options("pyramid", 30.0f)));
  maps.pyramid = Image();
  EXPECT_EQ(required_stream("cone"), "cone.exr");
  EXPECT_EQ(required_stream("relaxed-cone"), "relaxed-cone.exr");
  EXPECT_EQ(required_stream("sphere-tracing"), "sdf.exr");
  EXPECT_EQ(required_stream("pom"), "");
  // Each cone method needs its own kind: a conservative map does not stand in for a relaxed one.
  const HeightField field = make_height_field(maps.displacement, Border::clamp);
  maps.cone = build_cone_map(field, ConeMapOptions{});
  EXPECT_NO_THROW(render_headless(quad, maps, centre_uv_options("cone", 30.0f)));
  EXPECT_THROW(render_headless(quad, maps, centre_uv_options("relaxed-cone", 30.0f)), UsageError);
  EXPECT_NO_THROW(check_cone_matches(maps.cone, maps.displacement, "conservative", "cone.exr"));
  EXPECT_THROW(check_cone_matches(maps.cone, maps.displacement, "relaxed", "relaxed-cone.exr"), InputError);
  EXPECT_THROW(check_stream_matches("relaxed-cone", maps.cone, maps.displacement, "relaxed-cone.exr"), InputError);
  // A cone map of another height map (other size, other height range) is refused.
  Image other = maps.displacement;
  for (float& v : other.pixels) v *= 2.0f;
  EXPECT_THROW(check_cone_matches(build_cone_map(make_height_field(other, Border::clamp), ConeMapOptions{}), maps.displacement,
                                  "conservative", "cone.exr"),
               InputError);
  EXPECT_THROW(check_cone_matches(build_cone_map(make_height_field(Image(32, 64, 1, 0.0f), Border::clamp), ConeMapOptions{}),
                                  maps.displacement, "conservative", "cone.exr"),
               InputError);
  // Values that contradict the stream's definition are refused, naming the first such texel
  // (they had been drawn): a ratio above meso:ratio_cap, an apex below its texel, a pyramid
  // minimum above its maximum, a negative distance, a distance field of two channels.
  const Image good_cone = build_cone_map(field, ConeMapOptions{});
  auto expect_refused = [](auto check, const std::string& message) {
    try {
      check();
      ADD_FAILURE() << message;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  };
  for (const auto& [channel, value] : {std::pair<int, float>{1, 2e4f}, {1, -1.0f}, {2, -0.5f}, {0, 1.5f}}) {
    Image cone = good_cone;
    cone.at(3, 2, channel) = value;
    expect_refused([&] { check_cone_matches(cone, maps.displacement, "conservative", "cone.exr"); },
                   "cone.exr: texel (3, 2) breaks a cone map's values");
  }
  Image pyramid = pyramid_image(own);
  pyramid.at(1, 1, 0) = 0.9f;  // min above max
  pyramid.at(1, 1, 1) = 0.1f;
  expect_refused([&] { check_pyramid_matches(pyramid, maps.displacement, "pyramid.exr"); }, "pyramid.exr: texel (1, 1) breaks a min-max pyramid's values");
  const Image sdf = distance_field_image(build_distance_field(own, DistanceFieldOptions{}), own);
  EXPECT_NO_THROW(check_sdf_matches(sdf, maps.displacement, "sdf.exr"));
  Image negative = sdf;
  negative.at(0, 5) = -0.25f;
  expect_refused([&] { check_sdf_matches(negative, maps.displacement, "sdf.exr"); }, "sdf.exr: texel (0, 5) breaks a distance field's values");
  Image two(sdf.width, sdf.height, 2, 0.0f);
  two.metadata = sdf.metadata;
  expect_refused([&] { check_sdf_matches(two, maps.displacement, "sdf.exr"); }, "sdf.exr: needs 1 channel");
  // Streams of another height map with the same range (this ramp mirrored: the same values,
  // so check_height_range passes) are refused at the first texel whose height differs; the
  // mirror's own streams match the mirror.
  Image mirrored = maps.displacement;
  for (int y = 0; y < mirrored.height; ++y)
    for (int x = 0; x < mirrored.width; ++x) mirrored.at(x, y) = maps.displacement.at(mirrored.width - 1 - x, y);
  const HeightField mirror = make_height_field(mirrored, Border::clamp);
  const Image mirror_cone = build_cone_map(mirror, ConeMapOptions{}), mirror_pyramid = pyramid_image(mirror);
  const Image mirror_sdf = distance_field_image(build_distance_field(mirror, DistanceFieldOptions{}), mirror);
  const std::string differs = "the height at texel (0, 0) differs from displacement.exr's";
  expect_refused([&] { check_cone_matches(mirror_cone, maps.displacement, "conservative", "cone.exr"); }, "cone.exr: " + differs);
  expect_refused([&] { check_pyramid_matches(mirror_pyramid, maps.displacement, "pyramid.exr"); }, "pyramid.exr: " + differs);
  expect_refused([&] { check_sdf_matches(mirror_sdf, maps.displacement, "sdf.exr"); }, "sdf.exr: " + differs);
  EXPECT_NO_THROW(check_cone_matches(mirror_cone, mirrored, "conservative", "cone.exr"));
  EXPECT_NO_THROW(check_pyramid_matches(mirror_pyramid, mirrored, "pyramid.exr"));
  EXPECT_NO_THROW(check_sdf_matches(mirror_sdf, mirrored, "sdf.exr"));
  // A tiling map moved by one texel (the same values, so the same range): its pyramid and
  // distance field are refused as well as its cone map (their footprint extremes differ),
  // and the map's own streams pass.
  Image tile(64, 64, 1), moved(64, 64, 1);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      tile.at(x, y) = static_cast<float>(0.05 * std::sin(2 * kPi * texel_center_u(x, 64)));
      moved.at(x, y) = static_cast<float>(0.05 * std::sin(2 * kPi * texel_center_u((x + 1) % 64, 64)));
    }
  const HeightField tile_field = make_height_field(tile, Border::wrap), moved_field = make_height_field(moved, Border::wrap);
  const Image moved_pyramid = pyramid_image(moved_field), tile_pyramid = pyramid_image(tile_field);
  const Image moved_sdf = distance_field_image(build_distance_field(moved_field, DistanceFieldOptions{}), moved_field);
  const Image tile_sdf = distance_field_image(build_distance_field(tile_field, DistanceFieldOptions{}), tile_field);
  EXPECT_THROW(check_cone_matches(build_cone_map(moved_field, ConeMapOptions{}), tile, "conservative", "cone.exr"), InputError);
  EXPECT_THROW(check_pyramid_matches(moved_pyramid, tile, "pyramid.exr"), InputError);
  EXPECT_THROW(check_sdf_matches(moved_sdf, tile, "sdf.exr"), InputError);
  EXPECT_NO_THROW(check_pyramid_matches(tile_pyramid, tile, "pyramid.exr"));
  EXPECT_NO_THROW(check_sdf_matches(tile_sdf, tile, "sdf.exr"));
  maps.cone = Image();
  EXPECT_THROW(render_headless(quad, maps, centre_uv_options("cone", 30.0f)), UsageError);
}

// ---- cone stepping ----

// Height fields for the cone methods on a 64 x 64 map, periodic so that a tiling (wrap)
// field is continuous across its border, with their cone maps; normal maps flat.
//   rough: bumps a few texels across, steep enough to occlude at 60 degrees;
//   plateau: a box 24 x 16 texels, 0.1 high: relaxed cones from the plain see its front
//   walls rising and reach into them, so relaxed steps end inside it and bisect.
enum class ConeScene { rough, plateau };

PreviewMaps cone_maps(ConeScene scene, Border border) {
  PreviewMaps maps = maps_with_height([](float) { return 0.0f; });
  const double two_pi = 2 * kPi;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      const double u = texel_center_u(x, 64), v = texel_center_v(y, 64);
      const double h = scene == ConeScene::plateau ? (x >= 20 && x < 44 && y >= 24 && y < 40 ? 0.1 : 0.0)
                                                   : 0.04 * std::abs(std::sin(two_pi * 5 * u) * std::cos(two_pi * 3 * v)) +
                                                         0.02 * std::sin(two_pi * (2 * u + v)) + 0.015 * std::cos(two_pi * 7 * v);
      maps.displacement.at(x, y) = static_cast<float>(h);
    }
  add_cone_maps(maps, border);
  return maps;
}

PreviewOptions view_options(const std::string& method, float angle, float azimuth, int iterations, PreviewShade shade) {
  PreviewOptions o;
  o.method = method;
  o.width = o.height = 96;
  o.camera.view_angle = angle;
  o.camera.azimuth = azimuth;
  o.camera.zoom = 1.3f;
  o.iterations = iterations;
  o.shade = shade;
  return o;
}

struct Agreement {
  size_t pixels = 0, within = 0;
  double fraction() const { return pixels ? static_cast<double>(within) / static_cast<double>(pixels) : 0.0; }
};

// Pixels on the mesh in both images whose first `channels` channels differ by at most
// `tolerance`; with `inside`, a uv render, only pixels whose visible point there is on the map.
Agreement agreement(const Image& a, const Image& b, int channels, double tolerance, const Image* inside = nullptr) {
  Agreement r;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      if (a.at(x, y, 3) < 0.5f || b.at(x, y, 3) < 0.5f) continue;
      if (inside && (std::min(inside->at(x, y, 0), inside->at(x, y, 1)) < 0.0f || std::max(inside->at(x, y, 0), inside->at(x, y, 1)) > 1.0f))
        continue;
      ++r.pixels;
      double d = 0;
      for (int c = 0; c < channels; ++c) d = std::max(d, std::abs(static_cast<double>(a.at(x, y, c)) - b.at(x, y, c)));
      r.within += d <= tolerance;
    }
  return r;
}

// Relief mapping with a dense linear search (2048 steps, then 8 halvings) is the brute-force
// reference: on this field it samples every texel the ray crosses about 30 times. Under the
// clamp rule the cone methods keep the point where a ray leaves the map (their cones say
// nothing beyond it) while relief mapping goes on over the clamped surface: pixels whose
// reference point lies off the map are not compared.
TEST(Preview, ConeAndPyramidTracersAgreeWithADenseReliefSearch) {
  const Mesh quad = test::make_grid(1, 1);
  for (ConeScene scene : {ConeScene::rough, ConeScene::plateau}) {
    for (Border border : {Border::clamp, Border::wrap}) {
      const PreviewMaps maps = cone_maps(scene, border);
      const auto [lo, hi] = std::minmax_element(maps.displacement.pixels.begin(), maps.displacement.pixels.end());
      const double range = static_cast<double>(*hi - *lo);
      for (float angle : {30.0f, 65.0f}) {
        const Image reference_uv = render_headless(quad, maps, view_options("relief", angle, 35.0f, 2048, PreviewShade::uv));
        const Image* on_map = border == Border::clamp ? &reference_uv : nullptr;
        for (PreviewShade shade : {PreviewShade::uv, PreviewShade::height}) {
          const bool uv = shade == PreviewShade::uv;
          if (!uv && scene == ConeScene::plateau) continue;  // two heights only: the uv is the finer test
          const Image reference = uv ? reference_uv : render_headless(quad, maps, view_options("relief", angle, 35.0f, 2048, shade));
          for (const char* method : {"cone", "relaxed-cone", "pyramid"}) {
            const Image img = render_headless(quad, maps, view_options(method, angle, 35.0f, 256, shade));
            // uv: a hundredth of a texel; height: a thousandth of the relief's range (measured
            // on llvmpipe: at most 4e-5 texel apart).
            const Agreement a = agreement(img, reference, uv ? 2 : 1, uv ? 0.01 / 64 : 0.001 * range, on_map);
            const char* scene_name = scene == ConeScene::plateau ? "plateau" : "rough";
            std::printf("%s %s %s %.0f deg %s: %zu of %zu pixels agree (%.4f)\n", method, scene_name, border_name(border),
                        static_cast<double>(angle), uv ? "uv" : "height", a.within, a.pixels, a.fraction());
            EXPECT_GT(a.pixels, 96u * 96u / 4) << method;
            EXPECT_GE(a.fraction(), 0.995) << method << " " << scene_name << " " << border_name(border) << " at " << angle
                                           << (uv ? " uv" : " height");
          }
        }
      }
    }
  }
}

// Sphere tracing is safe whatever the distance field's resolution: where the field allows no
// step, the ray is intersected exactly with the filtered surface over the texel it is in and
// walks on texel by texel, so with 2 slices (boxes far above the surface, a field that allows
// few steps) as with 32 it finds the points of the cone tracer (exact, checked above).
TEST(Preview, SphereTracingFindsTheConeTracersPointsWhateverTheSliceCount) {
  const Mesh quad = test::make_grid(1, 1);
  for (Border border : {Border::clamp, Border::wrap}) {
    PreviewMaps maps = cone_maps(ConeScene::rough, border);
    const HeightField field = make_height_field(maps.displacement, border);
    for (int depth : {2, 32}) {
      DistanceFieldOptions o;
      o.depth = depth;
      maps.sdf = distance_field_image(build_distance_field(field, o), field);
      for (float angle : {30.0f, 65.0f}) {
        const Image cone = render_headless(quad, maps, view_options("cone", angle, 35.0f, 256, PreviewShade::uv));
        const Image traced = render_headless(quad, maps, view_options("sphere-tracing", angle, 35.0f, 2048, PreviewShade::uv));
        // Clamped, the cone tracer starts where the ray comes over the map, while the distance
        // field also holds the clamped surface beyond it: pixels whose traced point is on the map.
        const Agreement a = agreement(traced, cone, 2, 0.01 / 64, border == Border::clamp ? &traced : nullptr);
        std::printf("sphere-tracing, %d slices, %s, %.0f deg: %zu of %zu pixels agree with cone (%.4f)\n", depth, border_name(border),
                    static_cast<double>(angle), a.within, a.pixels, a.fraction());
        EXPECT_GT(a.pixels, 96u * 96u / 4);
        EXPECT_GE(a.fraction(), 0.995) << depth << " slices, " << border_name(border) << " at " << angle;
      }
    }
  }
}

// 4 x 4 matrices, column-major (OpenGL's layout), inverted in double.
std::array<double, 16> inverse(const std::array<float, 16>& m) {
  std::array<double, 32> a{};  // [m | I], rows
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) {
      a[static_cast<size_t>(r * 8 + c)] = m[static_cast<size_t>(c * 4 + r)];
      a[static_cast<size_t>(r * 8 + 4 + c)] = r == c ? 1.0 : 0.0;
    }
  for (int c = 0; c < 4; ++c) {
    int pivot = c;
    for (int r = c + 1; r < 4; ++r)
      if (std::abs(a[static_cast<size_t>(r * 8 + c)]) > std::abs(a[static_cast<size_t>(pivot * 8 + c)])) pivot = r;
    for (int k = 0; k < 8; ++k) std::swap(a[static_cast<size_t>(c * 8 + k)], a[static_cast<size_t>(pivot * 8 + k)]);
    const double d = a[static_cast<size_t>(c * 8 + c)];
    for (int k = 0; k < 8; ++k) a[static_cast<size_t>(c * 8 + k)] /= d;
    for (int r = 0; r < 4; ++r) {
      if (r == c) continue;
      const double f = a[static_cast<size_t>(r * 8 + c)];
      for (int k = 0; k < 8; ++k) a[static_cast<size_t>(r * 8 + k)] -= f * a[static_cast<size_t>(c * 8 + k)];
    }
  }
  std::array<double, 16> inv{};
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) inv[static_cast<size_t>(c * 4 + r)] = a[static_cast<size_t>(r * 8 + 4 + c)];
  return inv;
}

// The shader runs trace_cone_map's algorithm: through every pixel of the unit quad
// (UV = xy, frame = the axes), rebuild the view ray in double, trace it on the CPU from where
// it enters the top of the height volume and compare the visible points.
TEST(Preview, ConeAndPyramidTracersMatchTheCpuTracers) {
  const Mesh quad = test::make_grid(1, 1);
  for (const auto& [scene, border] : {std::pair{ConeScene::rough, Border::clamp}, std::pair{ConeScene::rough, Border::wrap},
                                      std::pair{ConeScene::plateau, Border::clamp}}) {
    const PreviewMaps maps = cone_maps(scene, border);
    const HeightField field = make_height_field(maps.displacement, border);
    const MinMaxPyramid pyramid = min_max_pyramid_from_level0(maps.pyramid);
    for (const std::string method : {"cone", "relaxed-cone", "pyramid"}) {
      const ConeKind kind = method == "relaxed-cone" ? ConeKind::relaxed : ConeKind::conservative;
      const Image& cone = kind == ConeKind::relaxed ? maps.relaxed_cone : maps.cone;
      const PreviewOptions o = view_options(method, 55.0f, 35.0f, 512, PreviewShade::uv);
      const Image img = render_headless(quad, maps, o);
      const CameraPose pose = frame_camera(quad, o.camera, 1.0f);
      const std::array<double, 16> inv = inverse(pose.view_projection);
      auto unproject = [&](double nx, double ny, double nz) {
        std::array<double, 4> p{};
        for (int r = 0; r < 4; ++r)
          p[static_cast<size_t>(r)] = inv[static_cast<size_t>(r)] * nx + inv[static_cast<size_t>(4 + r)] * ny +
                                      inv[static_cast<size_t>(8 + r)] * nz + inv[static_cast<size_t>(12 + r)];
        return std::array<double, 3>{p[0] / p[3], p[1] / p[3], p[2] / p[3]};
      };
      Agreement a;
      size_t hits = 0;
      for (int y = 0; y < o.height; ++y)
        for (int x = 0; x < o.width; ++x) {
          if (img.at(x, y, 3) < 0.5f) continue;
          const double nx = 2.0 * (x + 0.5) / o.width - 1.0, ny = 1.0 - 2.0 * (y + 0.5) / o.height;
          const auto p0 = unproject(nx, ny, -1.0), p1 = unproject(nx, ny, 1.0);
          std::array<double, 3> v{p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
          const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
          for (double& c : v) c /= len;
          const double k = -p0[2] / v[2];  // the base point on z = 0: UV = (x, y)
          const double u0 = p0[0] + k * v[0], v0 = p0[1] + k * v[1];
          if (u0 < 0 || u0 > 1 || v0 < 0 || v0 > 1) continue;
          // Per unit length s along the view ray: (u, v, h) advance by v; in the tracer's
          // units x = u W, y = (1 - v) H, z = (h - bias) / scale.
          const double s_top = (field.bias + field.scale) / v[2];
          HeightRay ray;
          ray.dx = v[0] * 64;
          ray.dy = -v[1] * 64;
          ray.dz = v[2] / field.scale;
          ray.x = (u0 + v[0] * s_top) * 64;
          ray.y = (1 - (v0 + v[1] * s_top)) * 64;
          ray.z = 1;
          const HeightHit hit = method == "pyramid" ? trace_min_max_pyramid(field, pyramid, ray) : trace_cone_map(field, cone, kind, ray);
          if (!hit.hit) continue;
          ++hits;
          const double s = s_top + hit.t;
          const double du = img.at(x, y, 0) - (u0 + v[0] * s), dv = img.at(x, y, 1) - (v0 + v[1] * s);
          ++a.pixels;
          a.within += std::max(std::abs(du), std::abs(dv)) <= 0.01 / 64;
        }
      std::printf("%s %s %s: %zu of %zu traced pixels within 0.01 texel of the CPU tracer (%.4f)\n", method.c_str(),
                  scene == ConeScene::plateau ? "plateau" : "rough", border_name(border), a.within, a.pixels, a.fraction());
      EXPECT_GT(hits, 96u * 96u / 4) << method;
      EXPECT_GE(a.fraction(), 0.995) << method << " " << border_name(border);
    }
  }
}

// With a budget the trace never exhausts, the budget does not matter: 256 and 4096 loop
// passes give the same image. With a small one, relaxed cones get further (on a tiling map:
// off a clamped one a relaxed ray crosses the border's rows one pass each, and at 70 degrees
// 8 passes converge 0.75 of the pixels, against cone stepping's 0.84).
TEST(Preview, ConeSteppingDoesNotDependOnAGenerousBudget) {
  const Mesh quad = test::make_grid(1, 1);
  const PreviewMaps maps = cone_maps(ConeScene::plateau, Border::wrap);
  std::array<double, 2> converged_at_8{};
  for (const char* method : {"cone", "relaxed-cone", "pyramid"}) {
    const Image a = render_headless(quad, maps, view_options(method, 70.0f, 35.0f, 256, PreviewShade::uv));
    const Image b = render_headless(quad, maps, view_options(method, 70.0f, 35.0f, 4096, PreviewShade::uv));
    const Agreement same = agreement(a, b, 2, 0.0);
    EXPECT_EQ(same.within, same.pixels) << method;
    EXPECT_GT(same.pixels, 96u * 96u / 8) << method;
    // Few passes are not enough: the test would notice a budget that is ignored.
    const Image starved = render_headless(quad, maps, view_options(method, 70.0f, 35.0f, 8, PreviewShade::uv));
    const double f = agreement(starved, b, 2, 0.0).fraction();
    std::printf("%s: %.4f of the pixels have converged after 8 passes\n", method, f);
    EXPECT_LT(f, 0.97) << method;
    if (std::string(method) != "pyramid") converged_at_8[std::string(method) == "cone" ? 0 : 1] = f;
  }
  EXPECT_GT(converged_at_8[1], converged_at_8[0] + 0.03) << "relaxed cones take longer steps";
}

// DIG-DM bounds each pixel's search by its block's corner rays: on fields with relief a few
// texels across it agrees with the dense search almost everywhere (it is not a safe method:
// features between corner rays can be missed), and its fetches, the grid pass's included
// (amortised over each block), stay below relief mapping's at the same linear step (the same
// linear search and bisection over the whole slab; POM adapts its steps to the view).
TEST(Preview, DigAgreesWithADenseSearchAndFetchesLessThanRelief) {
  const Mesh quad = test::make_grid(1, 1);
  for (ConeScene scene : {ConeScene::rough, ConeScene::plateau}) {
    const PreviewMaps maps = cone_maps(scene, Border::clamp);
    HeadlessPreview preview(quad, maps);
    for (float angle : {30.0f, 65.0f}) {
      const Image reference = preview.render(view_options("relief", angle, 35.0f, 2048, PreviewShade::uv));
      std::array<double, 2> mean{};
      for (int k = 0; k < 2; ++k) {
        Image fetches;
        const Image img = preview.render(view_options(k ? "relief" : "dig", angle, 35.0f, 64, PreviewShade::uv), &fetches);
        double sum = 0;
        size_t n = 0;
        for (size_t i = 0; i < fetches.texel_count(); ++i)
          if (fetches.pixels[2 * i + 1] > 0.5f) {
            sum += fetches.pixels[2 * i];
            ++n;
          }
        mean[static_cast<size_t>(k)] = sum / static_cast<double>(std::max<size_t>(n, 1));
        const Agreement a = agreement(img, reference, 2, 0.5 / 64);
        std::printf("%s %s %.0f deg: %.4f of pixels within half a texel of the dense search, %.1f fetches per pixel\n",
                    k ? "relief" : "dig", scene == ConeScene::plateau ? "plateau" : "rough", static_cast<double>(angle), a.fraction(),
                    mean[static_cast<size_t>(k)]);
        EXPECT_GE(a.fraction(), 0.96) << (k ? "relief" : "dig") << " at " << angle;
      }
      EXPECT_LT(mean[0], 0.8 * mean[1]) << "dig against relief at " << angle;
      EXPECT_GT(mean[0], 8.0) << "the binary search alone takes 8";
    }
  }
}

// Minified (the rough map tiled 4 x 4 on the quad: a block's corner rays ~10 texels apart
// across their paths), a one-texel feature fits between DIG-DM's corner rays and rises above
// all four: its interval misses it, whatever epsilon_1. Those blocks search the whole slab
// (dig_fallback_texels), which brings DIG-DM back to the dense search.
TEST(Preview, DigSearchesTheWholeSlabWhereItsCornerRaysAreFarApart) {
  Mesh quad = test::make_grid(1, 1);
  for (auto h : quad.halfedges())
    if (!quad.is_boundary(h)) quad.set_texcoord2D(h, quad.texcoord2D(h) * 4.0f);
  const PreviewMaps maps = cone_maps(ConeScene::rough, Border::wrap);
  HeadlessPreview preview(quad, maps);
  for (float angle : {45.0f, 65.0f}) {
    const Image reference = preview.render(view_options("relief", angle, 35.0f, 2048, PreviewShade::uv));
    PreviewOptions dig = view_options("dig", angle, 35.0f, 64, PreviewShade::uv);
    dig.dig_fallback_texels = 0.0f;  // never: the intervals alone
    const Agreement intervals = agreement(preview.render(dig), reference, 2, 0.5 / 64);
    dig.dig_fallback_texels = 8.0f;  // the default
    const Agreement fallback = agreement(preview.render(dig), reference, 2, 0.5 / 64);
    std::printf("dig minified %.0f deg: %.4f of pixels within half a texel of the dense search with the fallback, %.4f without\n",
                static_cast<double>(angle), fallback.fraction(), intervals.fraction());
    EXPECT_GE(fallback.fraction(), 0.95) << angle;
    EXPECT_GT(fallback.fraction(), intervals.fraction() + 0.02) << angle;
  }
}

TEST(Preview, PomFindsTheExactCrossingOfALinearRamp) {
  const Mesh quad = test::make_grid(1, 1);
  const float k = 0.1f;
  const PreviewMaps maps = maps_with_height([](float u) { return 0.1f * u; });
  const double a = 40.0 * kPi / 180.0;
  const double dx = -std::sin(a), dz = -std::cos(a);  // view ray in (u, v, h) per unit length
  const double s = 0.5 * k / (dz - k * dx);           // dz s = k (0.5 + dx s)
  const Image img = render_headless(quad, maps, centre_uv_options("pom", 40.0f));
  EXPECT_NEAR(img.at(32, 32, 0), 0.5 + dx * s, 2e-4);
}

TEST(Preview, LitFlatSurfaceMatchesLambert) {
  const Mesh quad = test::make_grid(1, 1);
  const PreviewMaps maps = maps_with_height([](float) { return 0.0f; });
  PreviewOptions o = centre_uv_options("pom", 20.0f);
  o.shade = PreviewShade::lit;
  const Image img = render_headless(quad, maps, o);
  // Light toward normalize(n + 0.6 e2 - 0.4 e1) = normalize(-0.4, 0.6, 1) for this quad.
  const double ndotl = 1.0 / std::sqrt(0.16 + 0.36 + 1.0);
  const double albedo[3] = {0.78, 0.74, 0.70};
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(img.at(32, 32, c), std::pow(albedo[c] * (0.12 + 0.88 * ndotl), 1 / 2.2), 1e-3);
  EXPECT_EQ(img.at(32, 32, 3), 1.0f);
  EXPECT_EQ(img.at(0, 0, 3), 0.0f) << "background is transparent";
}

TEST(Preview, UnknownMethodIsAUsageError) {
  const Mesh quad = test::make_grid(1, 1);
  const PreviewMaps maps = maps_with_height([](float) { return 0.0f; });
  PreviewOptions o;
  o.method = "no-such-method";
  EXPECT_THROW(render_headless(quad, maps, o), UsageError);
}

// ---- the measuring instrument ----

// The view ray through pixel (x, y) (rows from the top) rebuilt from the OpenGL matrix alone:
// origin on the near plane, unit direction.
struct ViewRay {
  std::array<double, 3> o, d;
};
ViewRay view_ray(const std::array<double, 16>& inv, int x, int y, int width, int height) {
  auto unproject = [&](double nx, double ny, double nz) {
    std::array<double, 4> p{};
    for (int r = 0; r < 4; ++r)
      p[static_cast<size_t>(r)] = inv[static_cast<size_t>(r)] * nx + inv[static_cast<size_t>(4 + r)] * ny +
                                  inv[static_cast<size_t>(8 + r)] * nz + inv[static_cast<size_t>(12 + r)];
    return std::array<double, 3>{p[0] / p[3], p[1] / p[3], p[2] / p[3]};
  };
  const double nx = 2.0 * (x + 0.5) / width - 1.0, ny = 1.0 - 2.0 * (y + 0.5) / height;
  const auto p0 = unproject(nx, ny, -1.0), p1 = unproject(nx, ny, 1.0);
  std::array<double, 3> v{p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
  const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  for (double& c : v) c /= len;
  return {p0, v};
}

// The analytic check of the reference: through every pixel of a view of the unit quad
// (UV = xy, normal +z), the ray rebuilt from the OpenGL matrix meets the displaced plane
// z = h(x) where the reference says, for a flat and for a linear displacement.
TEST(Measure, ReferenceSeesPlanesWhereTheRaysMeetThem) {
  const Mesh quad = test::make_grid(1, 1);
  struct Case {
    const char* name;
    float (*height)(float u);
    double k, c;  // h = k u + c
  };
  for (const Case& test_case : {Case{"flat", [](float) { return 0.05f; }, 0.0, 0.05}, Case{"ramp", [](float u) { return 0.1f * u; }, 0.1, 0.0}}) {
    const PreviewMaps maps = maps_with_height(test_case.height);
    for (float angle : {0.0f, 35.0f, 65.0f}) {
      PreviewOptions o;
      o.width = 64;
      o.height = 48;  // not square: the aspect ratio must match the GPU's too
      o.camera.view_angle = angle;
      o.camera.azimuth = 20.0f;
      const ReferenceRenderer reference(quad, maps);
      o.shade = PreviewShade::uv;
      const Image uv = reference.render(o);
      o.shade = PreviewShade::height;
      const Image height = reference.render(o);
      o.shade = PreviewShade::lit;
      const Image lit = reference.render(o);
      ASSERT_EQ(uv.width, 64);
      ASSERT_EQ(uv.height, 48);
      const std::array<double, 16> inv = inverse(frame_camera(quad, o.camera, 64.0f / 48.0f).view_projection);
      size_t inside = 0, checked = 0;
      double worst = 0;
      for (int y = 0; y < o.height; ++y)
        for (int x = 0; x < o.width; ++x) {
          const ViewRay r = view_ray(inv, x, y, o.width, o.height);
          // z0 + s dz = k (x0 + s dx) + c; the ramp is linear between the outer texel centres.
          const double s = (test_case.k * r.o[0] + test_case.c - r.o[2]) / (r.d[2] - test_case.k * r.d[0]);
          const double px = r.o[0] + s * r.d[0], py = r.o[1] + s * r.d[1];
          const double lo = test_case.k != 0 ? 1.0 / 64 : 0.002;
          const bool in = px > lo && px < 1 - lo && py > 0.002 && py < 0.998;
          const bool out = px < -0.002 || px > 1.002 || py < -0.002 || py > 1.002;
          if (out) {
            EXPECT_EQ(uv.at(x, y, 3), 0.0f) << test_case.name << " pixel " << x << "," << y;
          }
          if (!in) continue;
          ++inside;
          ASSERT_EQ(uv.at(x, y, 3), 1.0f) << test_case.name << " pixel " << x << "," << y;
          worst = std::max({worst, std::abs(uv.at(x, y, 0) - px), std::abs(uv.at(x, y, 1) - py)});
          EXPECT_NEAR(height.at(x, y, 0), test_case.k * px + test_case.c, 1e-5) << test_case.name;
          if (test_case.k == 0) {
            // A flat normal map: the Lambert constant of LitFlatSurfaceMatchesLambert.
            const double ndotl = 1.0 / std::sqrt(0.16 + 0.36 + 1.0), albedo[3] = {0.78, 0.74, 0.70};
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(lit.at(x, y, c), std::pow(albedo[c] * (0.12 + 0.88 * ndotl), 1 / 2.2), 1e-5);
          }
          ++checked;
        }
      std::printf("%s at %.0f deg: %zu pixels, visible points within %.2g of the analytic ones\n", test_case.name,
                  static_cast<double>(angle), checked, worst);
      EXPECT_GT(inside, 64u * 48u / 10) << test_case.name;
      EXPECT_LT(worst, 1e-6) << test_case.name << " at " << angle;  // exact cells: float output rounding only
    }
  }
}

// A rough map over a flat base whose triangles differ in size: every ray that enters and
// leaves the height slab over the inside of the base must hit (a crack would let it through),
// and the image does not depend on the number of threads; both with the exact cells (rays
// through the pieces' shared edges) and tessellated (neighbours cut to different depths).
TEST(Measure, ReferenceIsWatertightAndDeterministic) {
  const Mesh sheet = test::make_parametric(9, 7, [](double s, double t) {
    return Vec3f(static_cast<float>(0.4 * s + 0.6 * s * s), static_cast<float>(t * t * 0.5 + 0.5 * t), 0.0f);
  }, false, false);
  const PreviewMaps maps = cone_maps(ConeScene::rough, Border::clamp);
  const auto [lo, hi] = std::minmax_element(maps.displacement.pixels.begin(), maps.displacement.pixels.end());
  const double side = sheet.normal(VertexHandle(0))[2] > 0 ? 1.0 : -1.0;  // displacement along +z or -z
  const double z_a = side * static_cast<double>(*lo), z_b = side * static_cast<double>(*hi);
  for (const bool exact : {true, false}) {
    for (float angle : {0.0f, 50.0f}) {
      const PreviewOptions o = uv_view(80, angle, 25.0f);
      ReferenceOptions ro;
      ro.bilinear_patches = exact;
      const ReferenceRenderer reference(sheet, maps, ro);
      EXPECT_LE(reference.max_edge_texels(), 0.5);
      EXPECT_EQ(reference.patch_count() > 0, exact);
      EXPECT_EQ(reference.triangle_count() > 0, !exact);
      const Image img = reference.render(o);
      const std::array<double, 16> inv = inverse(frame_camera(sheet, o.camera, 1.0f).view_projection);
      size_t must_hit = 0;
      for (int y = 0; y < o.height; ++y)
        for (int x = 0; x < o.width; ++x) {
          const ViewRay r = view_ray(inv, x, y, o.width, o.height);
          bool inside = true;
          for (double z : {z_a, z_b}) {
            const double s = (z - r.o[2]) / r.d[2];
            const double px = r.o[0] + s * r.d[0], py = r.o[1] + s * r.d[1];
            inside = inside && px > 0.01 && px < 0.99 && py > 0.01 && py < 0.99;
          }
          if (!inside) continue;
          ++must_hit;
          EXPECT_EQ(img.at(x, y, 3), 1.0f) << "a crack at pixel " << x << "," << y << ", " << angle << " degrees, exact " << exact;
        }
      EXPECT_GT(must_hit, 80u * 80u / 5);
      Image single;
      {
        tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        single = ReferenceRenderer(sheet, maps, ro).render(o);
      }
      EXPECT_EQ(single.pixels, img.pixels) << "the reference depends on the thread count";
    }
  }
}

// The reference does not depend on the mesh's scale: the same sheet and displacement scaled
// by 2^-24 (a mesh 6e-8 units across, whose half-texel triangles fell under Embree's absolute
// floors and were missed) and by 2^24 sees the same points, exact cells and tessellated.
TEST(Measure, ReferenceDoesNotDependOnTheMeshScale) {
  const Mesh sheet = test::make_parametric(9, 7, [](double s, double t) {
    return Vec3f(static_cast<float>(0.4 * s + 0.6 * s * s), static_cast<float>(t * t * 0.5 + 0.5 * t), 0.0f);
  }, false, false);
  const Mesh bent = test::make_parametric(8, 4, [](double s, double t) {
    return Vec3f(static_cast<float>(s), static_cast<float>(t), static_cast<float>(0.3 * s * s));
  }, false, false);
  const PreviewMaps maps = cone_maps(ConeScene::rough, Border::clamp);
  for (const Mesh* base : {&sheet, &bent}) {
    const PreviewOptions o = uv_view(64, 50.0f, 25.0f);
    const Image unscaled = ReferenceRenderer(*base, maps).render(o);
    for (const float scale : {std::ldexp(1.0f, -24), std::ldexp(1.0f, 24)}) {
      Mesh m = *base;
      for (auto v : m.vertices()) m.set_point(v, m.point(v) * scale);
      PreviewMaps scaled = maps;
      for (float& h : scaled.displacement.pixels) h *= scale;
      const ReferenceRenderer reference(m, scaled);
      EXPECT_EQ(reference.patch_count() > 0, base == &sheet);
      const Image img = reference.render(o);
      size_t covered = 0;
      for (int y = 0; y < o.height; ++y)
        for (int x = 0; x < o.width; ++x) {
          ASSERT_EQ(img.at(x, y, 3), unscaled.at(x, y, 3)) << "pixel " << x << "," << y << " at scale " << scale;
          covered += img.at(x, y, 3) > 0.5f;
          for (int c = 0; c < 2; ++c) EXPECT_NEAR(img.at(x, y, c), unscaled.at(x, y, c), 1e-6) << "pixel " << x << "," << y << " at scale " << scale;
        }
      EXPECT_GT(covered, 64u * 64u / 5);
    }
  }
}

// Exact cells only where a whole connected part of the base is flat: a sheet flat on one half
// and bent on the other is tessellated whole (an exact triangle beside a tessellated one would
// leave a crack along their edge), and the bent half's reference still sees the flat half.
TEST(Measure, ReferenceIsExactOnlyOverWhollyFlatParts) {
  const PreviewMaps maps = cone_maps(ConeScene::rough, Border::clamp);
  const Mesh flat = test::make_grid(4, 4);
  const Mesh bent = test::make_parametric(8, 4, [](double s, double t) {
    const double b = std::max(0.0, s - 0.5);
    return Vec3f(static_cast<float>(s), static_cast<float>(t), static_cast<float>(0.8 * b * b));
  }, false, false);
  const ReferenceRenderer exact(flat, maps), mixed(bent, maps);
  EXPECT_EQ(exact.triangle_count(), 0u);
  EXPECT_GE(exact.patch_count(), 64u * 64u);
  EXPECT_EQ(mixed.patch_count(), 0u);
  EXPECT_GT(mixed.triangle_count(), 64u * 64u);
  PreviewOptions o;
  o.width = o.height = 48;
  o.shade = PreviewShade::uv;
  const Image img = mixed.render(o);
  size_t covered = 0;
  for (int y = 0; y < o.height; ++y)
    for (int x = 0; x < o.width; ++x) covered += img.at(x, y, 3) > 0.5f;
  EXPECT_GT(covered, 48u * 48u / 4);
}

// The exact cells follow the tessellated reference's conventions (texel centres at +1/2, rows
// from the top, the map tiled when the streams were made with wrap): on a quad over which the
// rough map tiles twice, a fine tessellation (1/4 texel) finds the same visible points but
// where its chords cut a ridge differently.
TEST(Measure, ExactAndTessellatedReferencesAgreeOnATilingMap) {
  Mesh quad = test::make_grid(1, 1);
  for (auto h : quad.halfedges())
    if (!quad.is_boundary(h)) quad.set_texcoord2D(h, quad.texcoord2D(h) * 2.0f);
  const PreviewMaps maps = cone_maps(ConeScene::rough, Border::wrap);
  ASSERT_TRUE(maps_tile(maps));
  ReferenceOptions fine;
  fine.bilinear_patches = false;
  fine.max_edge_texels = 0.25;
  const ReferenceRenderer exact(quad, maps), tessellated(quad, maps, fine);
  ASSERT_GT(exact.patch_count(), 0u);
  ASSERT_EQ(tessellated.patch_count(), 0u);
  for (float angle : {20.0f, 60.0f}) {
    const PreviewOptions o = uv_view(96, angle, 30.0f);
    const Image a = exact.render(o), b = tessellated.render(o);
    size_t both = 0, close = 0, coverage_differs = 0;
    for (int y = 0; y < o.height; ++y)
      for (int x = 0; x < o.width; ++x) {
        const bool ca = a.at(x, y, 3) > 0.5f, cb = b.at(x, y, 3) > 0.5f;
        coverage_differs += ca != cb;
        if (!ca || !cb) continue;
        ++both;
        const double d = std::hypot((a.at(x, y, 0) - b.at(x, y, 0)) * 64.0, (a.at(x, y, 1) - b.at(x, y, 1)) * 64.0);
        close += d < 0.05;
      }
    std::printf("%.0f deg: %zu of %zu pixels within 0.05 texel, coverage differs at %zu\n", static_cast<double>(angle), close, both,
                coverage_differs);
    EXPECT_GT(both, 96u * 96u / 5);
    EXPECT_GE(static_cast<double>(close), 0.99 * static_cast<double>(both)) << angle;
    EXPECT_LE(coverage_differs, 96u * 96u / 200) << angle;
  }
}

// The measure tests' comparison: 96 x 96 pixels at azimuth 35 degrees, one repetition.
CompareOptions measure_options(std::vector<std::string> methods, float view_angle, float zoom, int iterations) {
  CompareOptions o;
  o.methods = std::move(methods);
  o.view.width = o.view.height = 96;
  o.view.camera.view_angle = view_angle;
  o.view.camera.azimuth = 35.0f;
  o.view.camera.zoom = zoom;
  o.view.iterations = iterations;
  o.repetitions = 1;
  return o;
}

PreviewMaps rough_maps_with_sdf() {
  PreviewMaps maps = cone_maps(ConeScene::rough, Border::clamp);
  const HeightField field = make_height_field(maps.displacement, Border::clamp);
  maps.sdf = distance_field_image(build_distance_field(field, DistanceFieldOptions{}), field);
  return maps;
}

// The search methods with generous budgets find the reference's visible points: at moderate
// angles, zoomed in so that the quad's border (where the displaced sheet outgrows the base
// mesh's silhouette, which no per-pixel method can draw) stays out of the frame.
TEST(Measure, SearchMethodsAgreeWithTheReference) {
  const Mesh quad = test::make_grid(1, 1);
  const PreviewMaps maps = rough_maps_with_sdf();
  for (float angle : {30.0f, 45.0f}) {
    const CompareOptions o = measure_options({"mesh", "tessellation", "bump", "parallax", "offset-limited", "slope", "iterative-parallax", "steep",
                                              "relief", "pom", "cone", "relaxed-cone", "pyramid", "sphere-tracing", "dig"},
                                             angle, angle > 40 ? 5.0f : 3.0f, 256);
    const Comparison c = compare_methods(quad, maps, o);
    ASSERT_EQ(c.methods.size(), o.methods.size());
    // The quad is flat: all of it is intersected exactly, one piece per texel cell.
    EXPECT_EQ(c.reference_triangles, 0u);
    EXPECT_GE(c.reference_patches, 64u * 64u);
    for (const MethodComparison& m : c.methods) {
      std::printf("%.0f deg %-15s wrong hits %.4f (%zu of %zu), rmse %.4f, fetches mean %.1f p99 %.0f, %.2f ms\n",
                  static_cast<double>(angle), m.name.c_str(), m.wrong_hit_fraction, m.wrong_hits, m.pixels, m.rmse,
                  m.mean_iterations, m.p99_iterations, m.ms);
      EXPECT_GT(m.pixels, 96u * 96u / 2) << m.name;
      EXPECT_TRUE(std::isfinite(m.ms) && m.ms > 0) << m.name;
      EXPECT_EQ(m.fetches.width, 96);
      EXPECT_EQ(m.fetches.channels, 2);
      // Per vertex: amortised; bump reads no heights at all.
      EXPECT_GE(m.mean_iterations, m.name == "bump" ? 0.0 : m.name == "mesh" || m.name == "tessellation" ? 0.1 : 1.0) << m.name;
      EXPECT_GE(m.p99_iterations, m.mean_iterations) << m.name;
      EXPECT_GE(m.max_iterations, m.p99_iterations) << m.name;
      if (m.name == "parallax") {
        // The instrument tells methods apart: one parallax step misses most bumps.
        EXPECT_GT(m.wrong_hit_fraction, 0.03) << "at " << angle;
      }
      // The approximations without a search: their known error on this map, with a margin
      // (measured at 30 / 45 degrees: bump 0.31 / 0.45, parallax 0.05 / 0.22, offset limiting
      // and slope 0.07 / 0.20, iterative parallax with 512 steps 0.003 / 0.032), so that a
      // regression shows; the ones with a search are held to the limits below.
      const std::map<std::string, double> approximation = {
          {"bump", 0.6}, {"parallax", 0.3}, {"offset-limited", 0.28}, {"slope", 0.28}, {"iterative-parallax", 0.05}};
      if (const auto it = approximation.find(m.name); it != approximation.end()) {
        EXPECT_LE(m.wrong_hit_fraction, it->second) << m.name << " at " << angle;
        EXPECT_LT(m.rmse, 0.01) << m.name;
        continue;
      }
      // Per-vertex methods at about a texel per segment (linear between the texel centres they
      // sample, where the reference is bilinear) and DIG-DM (not a safe method) miss a little. The
      // safe methods trace the very surface the reference intersects (the bilinear one, exactly
      // on this flat quad): not one pixel may differ.
      const bool approximate = m.name == "mesh" || m.name == "tessellation" || m.name == "dig";
      const bool safe = m.name == "cone" || m.name == "relaxed-cone" || m.name == "pyramid" || m.name == "sphere-tracing";
      EXPECT_LE(m.wrong_hit_fraction, approximate ? 0.03 : 0.002) << m.name << " at " << angle;
      if (safe) {
        EXPECT_EQ(m.wrong_hits, 0u) << m.name << " at " << angle;
      }
      EXPECT_LT(m.rmse, approximate ? 0.03 : 0.01) << m.name;  // the normal map is flat: lit images differ only where coverage does
    }
  }
}

// The per-pixel methods trace the displaced surface P(uv) + h N in the coordinates of the
// triangle's own dp/du and dp/dv (surface.frag's uvh_from_object), not in an orthonormalised
// tangent frame: on a quad whose UV axes are not orthogonal (a parallelogram in space over the
// unit square in UV) and whose vertex normals all lean 23 degrees off its normal (as a coarse
// base's do), the surface is still exactly the bilinear one the tracers assume, so the safe
// methods miss no pixel of the reference (zoomed in so that the quad's border, beyond which no
// per-pixel method draws, stays out of the frame). With the orthonormal frame 13 % of the
// pixels were wrong at 30 degrees and 33 % at 50: its axes are not the mapping's.
TEST(Measure, SearchMethodsFollowTheTrianglesUvMappingAndTheLeaningNormal) {
  Mesh quad = test::make_grid(1, 1);
  const Vec3f lean = Vec3f(0.3f, -0.3f, 1.0f).normalized();
  for (auto v : quad.vertices()) {
    const Vec3f p = quad.point(v);
    quad.set_point(v, Vec3f(p[0] + 0.45f * p[1], 0.8f * p[1], 0.0f));
    quad.set_normal(v, lean);
  }
  const PreviewMaps maps = rough_maps_with_sdf();
  for (float angle : {30.0f, 50.0f}) {
    const CompareOptions o =
        measure_options({"relief", "pom", "cone", "relaxed-cone", "pyramid", "sphere-tracing", "dig"}, angle, 8.0f, 256);
    const Comparison c = compare_methods(quad, maps, o);
    ASSERT_EQ(c.methods.size(), o.methods.size());
    EXPECT_EQ(c.reference_triangles, 0u);  // one normal: intersected exactly, cell by cell
    for (const MethodComparison& m : c.methods) {
      std::printf("%.0f deg %-15s wrong hits %.4f (%zu of %zu)\n", static_cast<double>(angle), m.name.c_str(), m.wrong_hit_fraction,
                  m.wrong_hits, m.pixels);
      EXPECT_GT(m.pixels, 96u * 96u / 2) << m.name;
      const bool safe = m.name == "cone" || m.name == "relaxed-cone" || m.name == "pyramid" || m.name == "sphere-tracing";
      if (safe) {
        EXPECT_EQ(m.wrong_hits, 0u) << m.name << " at " << angle;
      } else {
        EXPECT_LE(m.wrong_hit_fraction, m.name == "dig" ? 0.03 : 0.002) << m.name << " at " << angle;
      }
    }
  }
}

// The lit images agree too where the normal map is not flat: the GPU's tangent frames and
// normal decoding are the reference's (bake.cpp's conventions: MikkTSpace frames, +Y = +v),
// so a tilted normal shades the same on both; with the green channel read the other way
// round, the lit image would differ where the normals lean along v.
TEST(Measure, LitImagesAgreeWithATiltedNormalMap) {
  const Mesh quad = test::make_grid(1, 1);
  PreviewMaps maps = rough_maps_with_sdf();
  maps.normal_ts = Image(32, 32, 3);
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) {
      const float nx = 0.5f * std::sin(0.4f * static_cast<float>(x)), ny = 0.6f * std::cos(0.3f * static_cast<float>(y));
      const float nz = std::sqrt(1.0f - nx * nx - ny * ny);
      maps.normal_ts.at(x, y, 0) = 0.5f * nx + 0.5f;
      maps.normal_ts.at(x, y, 1) = 0.5f * ny + 0.5f;
      maps.normal_ts.at(x, y, 2) = 0.5f * nz + 0.5f;
    }
  const CompareOptions o = measure_options({"mesh", "cone", "pyramid"}, 30.0f, 3.0f, 256);
  const Comparison c = compare_methods(quad, maps, o);
  for (const MethodComparison& m : c.methods) {
    std::printf("%s: wrong hits %.4f, rmse %.5f\n", m.name.c_str(), m.wrong_hit_fraction, m.rmse);
    EXPECT_LT(m.rmse, 0.01) << m.name;
  }
}

// Fetch counts are exact for the fixed-step methods; linear searches fetch more with a larger
// budget; the methods that stop when they have found the surface do not.
TEST(Measure, FetchCounts) {
  const Mesh quad = test::make_grid(1, 1);
  {
    const PreviewMaps maps = maps_with_height([](float) { return 0.05f; });
    HeadlessPreview gpu(quad, maps);
    for (const auto& [method, expect] : {std::pair<const char*, float>{"bump", 0.0f}, {"parallax", 1.0f}, {"offset-limited", 1.0f},
                                         {"slope", 2.0f}, {"iterative-parallax", 14.0f}}) {
      PreviewOptions o = centre_uv_options(method, 30.0f);
      o.iterations = 7;
      Image fetches;
      const Image img = gpu.render(o, &fetches);
      ASSERT_EQ(fetches.channels, 2);
      size_t covered = 0;
      for (size_t i = 0; i < img.texel_count(); ++i) {
        const bool on = img.pixels[4 * i + 3] > 0.5f;
        covered += on;
        ASSERT_EQ(fetches.pixels[2 * i + 1], on ? 1.0f : 0.0f) << method;
        ASSERT_EQ(fetches.pixels[2 * i], on ? expect : 0.0f) << method << " pixel " << i;
      }
      EXPECT_GT(covered, img.texel_count() / 4);
    }
  }
  const PreviewMaps maps = rough_maps_with_sdf();
  HeadlessPreview gpu(quad, maps);
  auto mean_fetches = [&](const std::string& method, int iterations, Image* out = nullptr) {
    Image fetches;
    gpu.render(view_options(method, 45.0f, 35.0f, iterations, PreviewShade::uv), &fetches);
    double sum = 0;
    size_t n = 0;
    for (size_t i = 0; i < fetches.texel_count(); ++i)
      if (fetches.pixels[2 * i + 1] > 0.5f) {
        EXPECT_TRUE(std::isfinite(fetches.pixels[2 * i]) && fetches.pixels[2 * i] >= 1.0f) << method;
        sum += fetches.pixels[2 * i];
        ++n;
      }
    if (out) *out = fetches;
    return n ? sum / static_cast<double>(n) : 0.0;
  };
  for (const char* method : {"steep", "pom", "relief", "iterative-parallax"}) {
    const double a = mean_fetches(method, 8), b = mean_fetches(method, 32), c = mean_fetches(method, 128);
    std::printf("%s: mean fetches %.1f, %.1f, %.1f at 8, 32, 128 steps\n", method, a, b, c);
    EXPECT_LT(a, b) << method;
    EXPECT_LT(b, c) << method;
  }
  // Relief is steep parallax's linear search plus its 8 halvings wherever it found a crossing.
  Image steep, relief;
  mean_fetches("steep", 32, &steep);
  mean_fetches("relief", 32, &relief);
  for (size_t i = 0; i < steep.texel_count(); ++i) {
    const float d = relief.pixels[2 * i] - steep.pixels[2 * i];
    ASSERT_TRUE(d == 0.0f || d == 8.0f) << d;
  }
  // POM adapts its steps to the view: fewer fetches straight on than at a grazing angle.
  auto pom_at = [&](float angle) {
    Image fetches;
    gpu.render(view_options("pom", angle, 35.0f, 64, PreviewShade::uv), &fetches);
    double sum = 0;
    size_t n = 0;
    for (size_t i = 0; i < fetches.texel_count(); ++i)
      if (fetches.pixels[2 * i + 1] > 0.5f) sum += fetches.pixels[2 * i], ++n;
    return sum / static_cast<double>(std::max<size_t>(n, 1));
  };
  EXPECT_LT(pom_at(0.0f), 0.5 * pom_at(75.0f));
  EXPECT_LE(pom_at(0.0f), 16.0 + 1.0 + 1e-9) << "a quarter of the budget straight on";
  const double steep_1024 = mean_fetches("steep", 1024);
  for (const char* method : {"cone", "relaxed-cone", "pyramid", "sphere-tracing"}) {
    const double a = mean_fetches(method, 256), b = mean_fetches(method, 1024);
    std::printf("%s: mean fetches %.1f at 256 and %.1f at 1024 passes (steep at 1024 steps: %.1f)\n", method, a, b, steep_1024);
    EXPECT_EQ(a, b) << method << " stops when it has found the surface";
    EXPECT_LT(b, steep_1024 / 4) << method;
  }
}

// The methods' other quality knobs (PreviewOptions) do what preview.hpp says, measured by
// their fetches: relief's halvings and relaxed cones' bisections cost their count wherever a
// crossing is refined and nothing elsewhere; a wider DIG interval costs fetches; the edge
// tests' samples, thresholds and screen length set how many vertices tessellation makes.
TEST(Measure, QualityKnobsDoWhatTheySay) {
  const Mesh quad = test::make_grid(1, 1);
  const PreviewMaps maps = rough_maps_with_sdf();
  HeadlessPreview gpu(quad, maps);
  auto fetches = [&](const PreviewOptions& o) {
    Image f;
    gpu.render(o, &f);
    return f;
  };
  auto mean = [](const Image& f) {
    double sum = 0;
    size_t n = 0;
    for (size_t i = 0; i < f.texel_count(); ++i)
      if (f.pixels[2 * i + 1] > 0.5f) sum += f.pixels[2 * i], ++n;
    return n ? sum / static_cast<double>(n) : 0.0;
  };
  // Per pixel: the fetches of `o` with knob value k, minus those with 0, are 0 or k times one
  // pixel's unit cost (the same for every refined pixel); returns the refined pixels.
  auto refined_pixels = [&](PreviewOptions o, int PreviewOptions::*knob, int k) {
    o.*knob = 0;
    const Image none = fetches(o);
    o.*knob = k;
    const Image some = fetches(o);
    size_t refined = 0;
    float unit = 0;
    for (size_t i = 0; i < none.texel_count(); ++i) {
      const float d = some.pixels[2 * i] - none.pixels[2 * i];
      if (d == 0.0f) continue;
      if (unit == 0.0f) unit = d / static_cast<float>(k);
      EXPECT_EQ(d, unit * static_cast<float>(k)) << "pixel " << i;
      ++refined;
    }
    EXPECT_GE(unit, 1.0f);
    return refined;
  };
  const PreviewOptions relief = view_options("relief", 45.0f, 35.0f, 32, PreviewShade::uv);
  EXPECT_GT(refined_pixels(relief, &PreviewOptions::binary_steps, 3), relief.width * relief.height / 4);
  const PreviewOptions relaxed = view_options("relaxed-cone", 45.0f, 35.0f, 256, PreviewShade::uv);
  EXPECT_GT(refined_pixels(relaxed, &PreviewOptions::bisection_steps, 5), 0u);
  EXPECT_EQ(refined_pixels(relaxed, &PreviewOptions::bisection_steps, 5), refined_pixels(relaxed, &PreviewOptions::bisection_steps, 20));

  PreviewOptions dig = view_options("dig", 60.0f, 35.0f, 32, PreviewShade::uv);
  dig.dig_epsilon = 0.0f;
  const double dig_0 = mean(fetches(dig));
  dig.dig_epsilon = 0.1f;
  const double dig_default = mean(fetches(dig));
  dig.dig_epsilon = 1.0f;
  const double dig_1 = mean(fetches(dig));
  std::printf("dig mean fetches: %.2f, %.2f, %.2f at epsilon 0, 0.1, 1\n", dig_0, dig_default, dig_1);
  EXPECT_LE(dig_0, dig_default);
  EXPECT_LT(dig_default, dig_1);

  auto vertex_fetches = [&](HeadlessPreview& g, const PreviewOptions& o) {
    Image f;
    g.render(o, &f);
    double sum = 0;
    for (size_t i = 0; i < f.texel_count(); ++i) sum += f.pixels[2 * i];
    return sum;
  };
  // Two triangles, three edge tests each with samples + 1 fetches, plus 6 corners when no
  // edge is cut: the displacement threshold out of reach or segments of a million pixels.
  PreviewOptions tess = view_options("tessellation", 45.0f, 35.0f, 64, PreviewShade::uv);
  const double tess_default = vertex_fetches(gpu, tess);
  tess.tess_edge_samples = 3;
  const double tess_3 = vertex_fetches(gpu, tess);
  tess.tess_displacement = 1e6f;
  EXPECT_NEAR(vertex_fetches(gpu, tess), 2 * 3 + 2 * 3 * 4, 0.5);
  tess.tess_displacement = 0.02f;
  tess.tess_pixels = 1e6f;
  EXPECT_NEAR(vertex_fetches(gpu, tess), 2 * 3 + 2 * 3 * 4, 0.5);
  tess.tess_pixels = 8.0f;
  const double tess_8px = vertex_fetches(gpu, tess);
  std::printf("tessellation vertex fetches: %.0f default, %.0f with 3 samples, %.0f with 8-pixel segments\n", tess_default, tess_3,
              tess_8px);
  EXPECT_GT(tess_3, 2 * 3 + 2 * 3 * 4 + 100.0);
  EXPECT_LT(tess_8px, tess_3 / 2);
  // Normal change alone (the displacement test out of reach) on a curved base: finer angles,
  // more vertices; on the flat quad none.
  const Mesh band = test::make_sphere_band(8, 4);
  HeadlessPreview band_gpu(band, maps);
  PreviewOptions curved = view_options("tessellation", 30.0f, 35.0f, 64, PreviewShade::uv);
  curved.tess_displacement = 1e6f;
  curved.tess_pixels = 0.01f;
  curved.tess_normal_angle = 30.0f;
  const double coarse = vertex_fetches(band_gpu, curved);
  curved.tess_normal_angle = 2.0f;
  const double fine = vertex_fetches(band_gpu, curved);
  std::printf("sphere band vertex fetches: %.0f at 30 degrees, %.0f at 2 degrees\n", coarse, fine);
  EXPECT_GT(fine, 4 * coarse);
}

// The per-vertex methods fetch in the vertex stages: one height per generated vertex (plus
// the adaptive edge tests' samples), spread over the mesh's pixels. The brute-force mesh
// generates a vertex per texel whatever the budget; adaptive tessellation no more vertices
// than that, fewer with a smaller budget, and none beyond the corners on a flat map.
TEST(Measure, PerVertexFetchCounts) {
  const Mesh quad = test::make_grid(1, 1);
  const PreviewMaps maps = rough_maps_with_sdf();
  HeadlessPreview gpu(quad, maps);
  auto total = [&](const std::string& method, int iterations) {
    Image fetches;
    gpu.render(view_options(method, 45.0f, 35.0f, iterations, PreviewShade::uv), &fetches);
    double sum = 0;
    for (size_t i = 0; i < fetches.texel_count(); ++i) sum += fetches.pixels[2 * i];
    return sum;
  };
  const double mesh = total("mesh", 4), mesh_64 = total("mesh", 64), tess_4 = total("tessellation", 4), tess_64 = total("tessellation", 64);
  std::printf("vertex fetches: mesh %.0f, tessellation %.0f at 4 and %.0f at 64 segments per edge\n", mesh, tess_4, tess_64);
  // Two triangles at 64 segments per edge: at least 2 x (64 + 1)(64 + 2) / 2 vertices (the
  // counter counts evaluations: a vertex shared by several triangles may be evaluated again,
  // at most once per triangle corner).
  EXPECT_GE(mesh, 2 * 65 * 66 / 2);
  EXPECT_LE(mesh, 2 * 64 * 64 * 3);
  EXPECT_EQ(mesh, mesh_64);
  EXPECT_LT(tess_4, tess_64 / 4);
  EXPECT_LE(tess_64, mesh + 2 * 3 * 9 + 1);  // + the edge tests' samples
  const PreviewMaps flat = maps_with_height([](float) { return 0.05f; });
  HeadlessPreview flat_gpu(quad, flat);
  Image fetches;
  flat_gpu.render(view_options("tessellation", 45.0f, 35.0f, 64, PreviewShade::uv), &fetches);
  double sum = 0;
  for (size_t i = 0; i < fetches.texel_count(); ++i) sum += fetches.pixels[2 * i];
  EXPECT_NEAR(sum, 2 * 3 + 2 * 3 * 9, 0.5) << "a flat map needs no vertex but the corners";
}

// The mesh method makes a segment per texel along every edge however long: GL cuts a patch
// edge into at most 64 segments, so the renderer cuts the base triangles first. A quad with a
// 256 x 256 map (edges of 256 texels, the diagonal 362): each triangle's interior needs at
// least (256 + 1)(256 + 2) / 2 vertices, where 64 segments per edge would give (64 + 1)(64 + 2)
// / 2. Every patch is drawn (llvmpipe drops a draw's patches beyond about 2^16 vertices): seen
// straight on, the per-vertex methods cover the pixels the base triangles cover, but for the
// mesh's border, which the heights make ragged in perspective.
TEST(Measure, PerVertexMethodsDrawEveryPatchAndMeshASegmentPerTexel) {
  PreviewMaps maps;
  maps.displacement = Image(256, 256, 1);
  for (int y = 0; y < 256; ++y)
    for (int x = 0; x < 256; ++x)
      maps.displacement.at(x, y) = 0.02f * std::sin(0.3f * static_cast<float>(x)) * std::cos(0.2f * static_cast<float>(y));
  maps.normal_ts = Image(1, 1, 3);
  maps.normal_ts.pixels = {0.5f, 0.5f, 1.0f};
  for (const int cells : {1, 8}) {
    const Mesh grid = test::make_grid(cells, cells);
    HeadlessPreview gpu(grid, maps);
    PreviewOptions o = view_options("bump", 0.0f, 0.0f, 64, PreviewShade::uv);
    o.width = o.height = 160;
    o.camera.zoom = 1.4f;
    o.tess_displacement = 0.0f;  // tessellation: a segment per texel on every edge, as mesh
    o.tess_pixels = 0.01f;
    const Image flat = gpu.render(o);
    for (const char* method : {"mesh", "tessellation"}) {
      o.method = method;
      Image fetches;
      const Image img = gpu.render(o, &fetches);
      double sum = 0;
      for (size_t i = 0; i < fetches.texel_count(); ++i) sum += fetches.pixels[2 * i];
      std::printf("%d x %d cells, %s: %.0f vertex fetches\n", cells, cells, method, sum);
      if (cells == 1 && std::string(method) == "mesh") {
        EXPECT_GE(sum, 2.0 * 257 * 258 / 2);
        EXPECT_LE(sum, 2.0 * 256 * 256 * 3 * 2);
      }
      size_t missing = 0, inside = 0;
      for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
          const float u = flat.at(x, y, 0), v = flat.at(x, y, 1);
          if (flat.at(x, y, 3) < 0.5f || u < 0.02f || u > 0.98f || v < 0.02f || v > 0.98f) continue;
          ++inside;
          missing += img.at(x, y, 3) < 0.5f;
        }
      EXPECT_GT(inside, img.texel_count() / 3);
      EXPECT_EQ(missing, 0u) << cells << " x " << cells << " cells, " << method;
    }
  }
}

// The tessellated surface is watertight: seen straight on, every pixel inside the quad is
// covered, whatever the heights do along the shared diagonal.
TEST(Measure, TessellationIsCrackFree) {
  const Mesh grid = test::make_grid(3, 3);
  const PreviewMaps maps = rough_maps_with_sdf();
  for (const char* method : {"mesh", "tessellation"}) {
    PreviewOptions o = view_options(method, 0.0f, 0.0f, 64, PreviewShade::uv);
    o.width = o.height = 160;
    o.camera.zoom = 1.4f;
    const Image img = render_headless(grid, maps, o);
    size_t holes = 0, covered = 0;
    for (int y = 1; y + 1 < img.height; ++y)
      for (int x = 1; x + 1 < img.width; ++x) {
        const bool on = img.at(x, y, 3) > 0.5f;
        covered += on;
        // A hole: a pixel off the mesh between covered pixels on both sides, in a row or a column.
        if (!on && ((img.at(x - 1, y, 3) > 0.5f && img.at(x + 1, y, 3) > 0.5f) || (img.at(x, y - 1, 3) > 0.5f && img.at(x, y + 1, 3) > 0.5f)))
          ++holes;
      }
    EXPECT_GT(covered, img.texel_count() / 3) << method;
    EXPECT_EQ(holes, 0u) << method;
  }
}

// Silhouettes: on a flat base curved rays are straight (same image inside the map); visible
// points that parallax pushes off a map that does not tile are discarded; on a convex base an
// inward displacement lets grazing rays pass under the surface's lowest point and leave it.
TEST(Preview, SilhouettesDiscardRaysThatLeaveTheSurface) {
  const Mesh quad = test::make_grid(1, 1);
  const PreviewMaps raised = maps_with_height([](float u) { return 0.05f + 0.05f * u; });
  PreviewOptions o = view_options("pom", 60.0f, 20.0f, 64, PreviewShade::uv);
  const Image plain = render_headless(quad, raised, o);
  o.silhouettes = true;
  const Image cut = render_headless(quad, raised, o);
  size_t plain_on = 0, cut_on = 0, outside = 0, differ = 0;
  for (size_t i = 0; i < cut.texel_count(); ++i) {
    plain_on += plain.pixels[4 * i + 3] > 0.5f;
    const bool on = cut.pixels[4 * i + 3] > 0.5f;
    cut_on += on;
    if (!on) continue;
    const float u = cut.pixels[4 * i], v = cut.pixels[4 * i + 1];
    outside += u < 0 || u > 1 || v < 0 || v > 1;
    differ += std::abs(u - plain.pixels[4 * i]) + std::abs(v - plain.pixels[4 * i + 1]) > 0;
  }
  EXPECT_EQ(outside, 0u);
  EXPECT_EQ(differ, 0u) << "a flat base bends no ray";
  EXPECT_LT(cut_on, plain_on);
  EXPECT_GT(cut_on, plain_on / 2);

  const Mesh cylinder = test::make_parametric(24, 20, [](double s, double t) {
    const double a = 2.4 * (s - 0.5);
    return Vec3f(float(0.5 * std::sin(a)), float(t), float(0.5 * (std::cos(a) - 1.0)));
  }, false, false);
  const PreviewMaps sunk = maps_with_height([](float) { return -0.04f; });  // a sunken layer
  PreviewOptions g = view_options("relief", 70.0f, 0.0f, 64, PreviewShade::uv);
  const Image straight = render_headless(cylinder, sunk, g);
  g.silhouettes = true;
  const Image bent = render_headless(cylinder, sunk, g);
  size_t straight_on = 0, bent_on = 0, escaped = 0;
  for (size_t i = 0; i < bent.texel_count(); ++i) {
    straight_on += straight.pixels[4 * i + 3] > 0.5f;
    bent_on += bent.pixels[4 * i + 3] > 0.5f;
    // Discarded although the straight ray's point was well inside the map: an escape.
    const float u = straight.pixels[4 * i], v = straight.pixels[4 * i + 1];
    escaped += straight.pixels[4 * i + 3] > 0.5f && bent.pixels[4 * i + 3] < 0.5f && u > 0.05f && u < 0.95f && v > 0.05f && v < 0.95f;
    for (int c = 0; c < 4; ++c) ASSERT_TRUE(std::isfinite(bent.pixels[4 * i + static_cast<size_t>(c)]));
  }
  std::printf("silhouettes: flat %zu -> %zu pixels, cylinder %zu -> %zu (%zu escaped)\n", plain_on, cut_on, straight_on, bent_on, escaped);
  EXPECT_LT(bent_on, straight_on);
  EXPECT_GT(escaped, 0u) << "rays that pass under the bent surface leave it";
}

// The safe methods and DIG-DM bend their rays on a curved base as relief mapping does
// (section 5.1): with silhouettes on, on a convex and on a concave cylinder seen at 70
// degrees, cone and relaxed cone stepping, the pyramid, sphere tracing and DIG-DM (at this
// budget; it is not a safe method) find the visible points of a dense bent relief search
// (2048 steps), and on the convex base rays that pass under the surface escape (discarded)
// as relief's do. Pixels whose reference point is off the map (clamp: the
// cones know nothing beyond it) are not compared.
TEST(Preview, SafeMethodsAndDigBendRaysOnCurvedBasesAsADenseReliefSearch) {
  // The rough field sunk below the base (as in the silhouettes test), so that grazing rays
  // over the convex base can pass under all of it.
  PreviewMaps maps = cone_maps(ConeScene::rough, Border::clamp);
  for (float& h : maps.displacement.pixels) h -= 0.06f;
  add_cone_maps(maps, Border::clamp);
  const HeightField field = make_height_field(maps.displacement, Border::clamp);
  maps.sdf = distance_field_image(build_distance_field(field, DistanceFieldOptions{}), field);
  for (const double side : {1.0, -1.0}) {  // convex (the base falls away from its normal), concave
    const Mesh cylinder = test::make_parametric(24, 20, [side](double s, double t) {
      const double a = 2.4 * (s - 0.5);
      return Vec3f(float(0.5 * std::sin(a)), float(t), float(side * 0.5 * (std::cos(a) - 1.0)));
    }, false, false);
    PreviewOptions o = view_options("relief", 70.0f, 0.0f, 2048, PreviewShade::uv);
    o.silhouettes = true;
    const Image reference = render_headless(cylinder, maps, o);
    size_t reference_on = 0;
    for (size_t i = 0; i < reference.texel_count(); ++i) reference_on += reference.pixels[4 * i + 3] > 0.5f;
    for (const char* method : {"cone", "relaxed-cone", "pyramid", "sphere-tracing", "dig"}) {
      o.method = method;
      o.iterations = 512;
      o.silhouettes = true;
      const Image bent = render_headless(cylinder, maps, o);
      o.silhouettes = false;
      const Image straight = render_headless(cylinder, maps, o);
      size_t coverage_differs = 0, escaped = 0, moved = 0;
      for (size_t i = 0; i < bent.texel_count(); ++i) {
        for (int c = 0; c < 4; ++c) ASSERT_TRUE(std::isfinite(bent.pixels[4 * i + static_cast<size_t>(c)])) << method;
        const bool on = bent.pixels[4 * i + 3] > 0.5f, reference_hit = reference.pixels[4 * i + 3] > 0.5f;
        coverage_differs += on != reference_hit;
        escaped += straight.pixels[4 * i + 3] > 0.5f && !on;
        moved += on && straight.pixels[4 * i + 3] > 0.5f &&
                 std::max(std::abs(bent.pixels[4 * i] - straight.pixels[4 * i]), std::abs(bent.pixels[4 * i + 1] - straight.pixels[4 * i + 1])) > 0.05f / 64;
      }
      const Agreement a = agreement(bent, reference, 2, 0.05 / 64, &reference);
      std::printf("bent rays, %s base, %-14s: %zu of %zu pixels agree to 1/20 texel, coverage differs at %zu of %zu, %zu escaped, "
                  "%zu moved by bending\n",
                  side > 0 ? "convex" : "concave", method, a.within, a.pixels, coverage_differs, reference_on, escaped, moved);
      EXPECT_GT(moved, reference_on / 40) << method << ": the bending is seen";
      EXPECT_GE(a.fraction(), 0.99) << method;
      EXPECT_LE(coverage_differs, reference_on / 200) << method;
      if (side > 0) {
        EXPECT_GT(escaped, 0u) << method << ": rays that pass under the bent surface leave it";
      }
    }
  }
  // A flat map (no relief: the streams hold a plane) sunk below the convex base: the safe
  // methods meet the bent ray's plane in closed form, all four the same, and rays that pass
  // over it escape. Relief's linear search ends exactly on that plane (the slab's bottom),
  // where rounding loses some crossings: it finds a subset of the pixels, at the same points.
  PreviewMaps flat = maps_with_height([](float) { return -0.05f; });
  add_cone_maps(flat, Border::clamp);
  const HeightField flat_field = make_height_field(flat.displacement, Border::clamp);
  flat.sdf = distance_field_image(build_distance_field(flat_field, DistanceFieldOptions{}), flat_field);
  const Mesh convex = test::make_parametric(24, 20, [](double s, double t) {
    const double a = 2.4 * (s - 0.5);
    return Vec3f(float(0.5 * std::sin(a)), float(t), float(0.5 * (std::cos(a) - 1.0)));
  }, false, false);
  PreviewOptions f = view_options("relief", 70.0f, 0.0f, 2048, PreviewShade::uv);
  f.silhouettes = true;
  const Image flat_reference = render_headless(convex, flat, f);
  f.method = "cone";
  f.silhouettes = false;
  const Image flat_straight = render_headless(convex, flat, f);
  f.silhouettes = true;
  const Image flat_cone = render_headless(convex, flat, f);
  for (const char* method : {"cone", "relaxed-cone", "pyramid", "sphere-tracing"}) {
    f.method = method;
    f.iterations = 512;
    const Image img = render_headless(convex, flat, f);
    size_t on = 0, reference_only = 0, escaped = 0;
    for (size_t i = 0; i < img.texel_count(); ++i) {
      const bool hit = img.pixels[4 * i + 3] > 0.5f;
      on += hit;
      reference_only += !hit && flat_reference.pixels[4 * i + 3] > 0.5f;
      escaped += !hit && flat_straight.pixels[4 * i + 3] > 0.5f;
    }
    const Agreement a = agreement(img, flat_reference, 2, 0.05 / 64, &flat_reference);
    std::printf("bent rays over a flat map, %-14s: %zu on, %zu escaped; relief's %zu points: %zu agree, %zu not found here\n", method, on, escaped,
                a.pixels, a.within, reference_only);
    EXPECT_EQ(img.pixels, flat_cone.pixels) << method << ": the same closed form";
    EXPECT_GT(escaped, 0u) << method;
    EXPECT_EQ(reference_only, 0u) << method;
    EXPECT_GE(a.fraction(), 0.95) << method;
  }
}

// ---- vdm and dstream (issue 8) ----

// On a flat base the view-dependent displacement map finds the reference's visible points:
// the table holds exact ray casts, so what remains is the interpolation between its samples.
// The visible UV moves with the view as parallax does (not a texture on the base).
TEST(Measure, VdmAgreesWithTheReferenceOnAFlatBase) {
  const Mesh quad = test::make_grid(1, 1);
  PreviewMaps maps = cone_maps(ConeScene::rough, Border::wrap);
  VdmOptions vdm;
  vdm.theta = 16;
  vdm.phi = 32;
  const auto [lo, hi] = std::minmax_element(maps.displacement.pixels.begin(), maps.displacement.pixels.end());
  vdm.relief = *hi - *lo;  // object units = units of u on the unit quad
  add_vdm(maps, Border::wrap, vdm, 1e-4);
  const CompareOptions o = measure_options({"vdm", "pom", "bump"}, 40.0f, 3.0f, 64);
  const Comparison c = compare_methods(quad, maps, o);
  for (const MethodComparison& m : c.methods)
    std::printf("vdm test: %-5s wrong hits %.4f, rmse %.4f, fetches %.1f\n", m.name.c_str(), m.wrong_hit_fraction, m.rmse, m.mean_iterations);
  EXPECT_LE(c.methods[0].wrong_hit_fraction, 0.08);
  EXPECT_GT(c.methods[2].wrong_hit_fraction, 3 * c.methods[0].wrong_hit_fraction + 0.02) << "bump mapping ignores parallax";
  // Fetches: rank/4 weight lookups and up to 8 directions of (rank + 1) basis terms.
  const int rank = std::get<int>(maps.vdm_weights.metadata.at("rank"));
  // The table is compressed to rank 64 (the previewer's limit): on these rough bumps that
  // leaves an RMS error of about a texel, most of the wrong hits.
  std::printf("vdm test: rank %d, table RMS error %g u\n", rank, static_cast<double>(std::get<float>(maps.vdm_weights.metadata.at("rms_error"))));
  EXPECT_GT(rank, 0);
  EXPECT_LE(c.methods[0].max_iterations, 8.0 * (rank + 1) + (rank + 3) / 4 + 0.5);
}

// On a curved base the table's curvature slices bend the rays: seen at a grazing angle, a
// cylinder rendered with vdm loses the pixels whose rays leave the bent height field (its
// silhouette moves inward), which no flat-base method draws.
TEST(Preview, VdmCurvatureMakesSilhouettes) {
  const double radius = 0.5;
  const Mesh cylinder = test::make_parametric(24, 20, [radius](double s, double t) {
    const double a = 2.4 * (s - 0.5);
    return Vec3f(float(radius * std::sin(a)), float(t), float(radius * (std::cos(a) - 1.0)));
  }, false, false);
  // Sparse ridges: between them a grazing ray meets nothing before the bent surface falls away.
  PreviewMaps maps = maps_with_height([](float u) { return 0.03f * std::pow(std::max(0.0f, std::sin(12.0f * u)), 16.0f); });
  const double per_u = object_length_per_uv(cylinder);
  VdmOptions flat, curved;
  flat.theta = curved.theta = 16;
  flat.phi = curved.phi = 16;
  flat.relief = curved.relief = static_cast<float>(0.03 / per_u);
  curved.curvatures = {0.0f, static_cast<float>(per_u / radius)};
  PreviewMaps flat_maps = maps, curved_maps = maps;
  add_vdm(flat_maps, Border::clamp, flat, 1e-4);
  add_vdm(curved_maps, Border::clamp, curved, 1e-4);
  PreviewOptions o = view_options("vdm", 75.0f, 0.0f, 32, PreviewShade::uv);
  auto covered = [&](const PreviewMaps& m) {
    const Image img = render_headless(cylinder, m, o);
    size_t n = 0;
    for (size_t i = 0; i < img.texel_count(); ++i) n += img.pixels[4 * i + 3] > 0.5f;
    return n;
  };
  const size_t with_flat = covered(flat_maps), with_curvature = covered(curved_maps);
  std::printf("vdm silhouettes: %zu pixels with a flat table, %zu with curvature\n", with_flat, with_curvature);
  EXPECT_LT(with_curvature, with_flat);
  EXPECT_GT(with_curvature, with_flat / 2);
}

// The dstream vertex shader decodes what the CPU decodes, within the quantisation bound (plus
// float rounding); morph 0 puts every vertex the coarser level has where that level puts it;
// and the surface it draws is the reference's when stream and map hold the same displacement.
TEST(Measure, DstreamDecodesAsTheCpuAndMorphsToTheCoarserLevel) {
  const Mesh base = test::make_parametric(6, 4, [](double s, double t) {
    const double a = 1.4 * (s - 0.5);
    return Vec3f(float(std::sin(a)), float(t), float(std::cos(a) - 1.0));
  }, false, false);
  const Mesh high = test::make_parametric(60, 40, [](double s, double t) {
    const double a = 1.6 * (s - 0.5), r = 1.04 + 0.02 * std::sin(9 * s) * std::cos(7 * t);
    return Vec3f(float(r * std::sin(a)), float(1.2 * t - 0.1), float(r * std::cos(a) - 1.0));
  }, false, false);
  PreviewMaps maps = maps_with_height([](float) { return 0.0f; });
  add_dstream(maps, base, high, 4);
  HeadlessPreview gpu(base, maps);
  const double bound = (maps.dstream.max_value - maps.dstream.min_value) / (2.0 * kDisplacementSteps);
  PreviewOptions o = view_options("dstream", 30.0f, 0.0f, 8, PreviewShade::uv);
  for (int level = 0; level < 4; ++level) {
    o.iterations = 1 << level;
    const std::vector<Vec3f> g = gpu.dstream_positions(o), c = decode_displacement_level(base, maps.dstream, level);
    ASSERT_EQ(g.size(), c.size());
    double worst = 0;
    for (size_t k = 0; k < g.size(); ++k) worst = std::max(worst, static_cast<double>((g[k] - c[k]).norm()));
    EXPECT_LE(worst, 1e-5) << "level " << level << " (quantisation step " << 2 * bound << ")";
  }
  o.iterations = 8;
  o.morph = 0.0f;
  const std::vector<Vec3f> morphed = gpu.dstream_positions(o);
  o.iterations = 4;
  o.morph = 1.0f;
  const std::vector<Vec3f> coarse = gpu.dstream_positions(o);
  const int n = 8, c = 4, per = (n + 1) * (n + 2) / 2, cper = (c + 1) * (c + 2) / 2;
  size_t shared = 0;
  for (int t = 0; t < static_cast<int>(base.n_faces()); ++t)
    for (int i = 0, k = 0; i <= n; ++i)
      for (int j = 0; j <= n - i; ++j, ++k)
        if (i % 2 == 0 && j % 2 == 0) {
          const int ci = i / 2, cj = j / 2;
          const Vec3f a = morphed[static_cast<size_t>(t * per + k)], b = coarse[static_cast<size_t>(t * cper + ci * (c + 1) - ci * (ci - 1) / 2 + cj)];
          EXPECT_LE((a - b).norm(), 1e-6f) << t << " " << i << "," << j;
          ++shared;
        }
  EXPECT_EQ(shared, base.n_faces() * static_cast<size_t>(cper));

  // Against the reference: a stream and a map of the same constant displacement.
  const Mesh quad = test::make_grid(2, 2);
  const Mesh lifted = test::make_parametric(4, 4, [](double s, double t) { return Vec3f(float(4 * s - 1.5), float(4 * t - 1.5), 0.05f); }, false, false);
  PreviewMaps same = maps_with_height([](float) { return 0.05f; });
  add_dstream(same, quad, lifted, 3);
  CompareOptions co;
  co.methods = {"dstream"};
  co.view.width = co.view.height = 64;
  co.view.camera.view_angle = 50.0f;
  co.view.iterations = 4;
  co.repetitions = 1;
  const Comparison cmp = compare_methods(quad, same, co);
  EXPECT_LE(cmp.methods[0].wrong_hit_fraction, 0.01);
  EXPECT_GT(cmp.methods[0].mean_iterations, 0.0) << "stream reads are counted";
  // Morphing by distance: near the eye the level's own values, far away the coarser level's.
  o.iterations = 8;
  PreviewOptions full = o;
  full.morph = 1.0f;
  o.morph = -1.0f;
  o.lod_distance = 1e6f;
  EXPECT_EQ(gpu.dstream_positions(o), gpu.dstream_positions(full));
  o.lod_distance = 1e-6f;
  EXPECT_EQ(gpu.dstream_positions(o), morphed);
}

// Two previews at once (compare_methods makes its own while the caller holds one): each
// draws into its own context, before and after the other is gone.
TEST(Measure, PreviewsCoexist) {
  const Mesh quad = test::make_grid(1, 1);
  const PreviewMaps maps = maps_with_height([](float) { return 0.05f; });
  HeadlessPreview first(quad, maps);
  const PreviewOptions o = centre_uv_options("pom", 30.0f);
  const Image before = first.render(o);
  {
    HeadlessPreview second(quad, maps);
    EXPECT_EQ(second.render(o).pixels, before.pixels);
    EXPECT_EQ(first.render(o).pixels, before.pixels);
  }
  EXPECT_EQ(first.render(o).pixels, before.pixels) << "the first preview draws after the second is gone";
}

// Depth correction: a ramp 0.1 u high on a quad at z = 0, and above it a second quad at
// z = 0.05 whose UVs all read the ramp's foot (u in [0, 0.001], height ~0). Seen from above, the
// displaced ramp rises through the second quad at u ~ 0.5: where u > 0.5 the ramp is in
// front, although its base quad lies behind the other one.
TEST(Preview, DepthCorrectionLetsDisplacedSurfacesIntersect) {
  Mesh two = test::make_grid(1, 1);
  std::vector<Mesh::VertexHandle> v;
  for (const auto& [x, y] : {std::pair{0.0f, 0.0f}, {1.0f, 0.0f}, {1.0f, 1.0f}, {0.0f, 1.0f}}) v.push_back(two.add_vertex(Vec3f(x, y, 0.05f)));
  for (const auto& f : {two.add_face(v[0], v[1], v[2]), two.add_face(v[0], v[2], v[3])})
    for (auto h : two.fh_range(f)) {
      const Vec3f p = two.point(two.to_vertex_handle(h));
      two.set_texcoord2D(h, Vec2f(0.001f * p[0], p[1]));  // within the ramp's flat first half texel
    }
  compute_angle_weighted_normals(two);
  const PreviewMaps maps = maps_with_height([](float u) { return 0.1f * u; });
  for (const char* method : {"parallax", "pom", "relief"}) {
    PreviewOptions o = view_options(method, 0.0f, 0.0f, 64, PreviewShade::uv);
    const Image img = render_headless(two, maps, o);
    const std::array<double, 16> inv = inverse(frame_camera(two, o.camera, 1.0f).view_projection);
    size_t ramp = 0, ramp_ok = 0, flat = 0, flat_ok = 0;
    for (int y = 0; y < o.height; ++y)
      for (int x = 0; x < o.width; ++x) {
        if (img.at(x, y, 3) < 0.5f) continue;
        const ViewRay r = view_ray(inv, x, y, o.width, o.height);
        const double s = (0.05 - r.o[2]) / r.d[2], u = r.o[0] + s * r.d[0];  // where the ray meets z = 0.05
        // Away from the quads' borders at both heights (a per-pixel method draws nothing
        // beyond its base triangle).
        const double s0 = -r.o[2] / r.d[2], x0 = r.o[0] + s0 * r.d[0], y0 = r.o[1] + s0 * r.d[1], y1 = r.o[1] + s * r.d[1];
        if (std::min({x0, y0, y1}) < 0.02 || std::max({x0, y0, y1}) > 0.98) continue;
        if (u > 0.55 && u < 0.98) {
          ++ramp;
          const bool ok = std::abs(img.at(x, y, 0) - u) < 0.05;  // the ramp's own u, near u
          ramp_ok += ok;
        } else if (u > 0.02 && u < 0.45) {
          ++flat;
          flat_ok += img.at(x, y, 0) < 0.002f;  // the upper quad
        }
      }
    EXPECT_GT(ramp, 400u) << method;
    EXPECT_GT(flat, 400u) << method;
    EXPECT_EQ(ramp_ok, ramp) << method << ": the ramp shows where it rises above the upper quad";
    EXPECT_EQ(flat_ok, flat) << method << ": the upper quad hides the ramp where the ramp is lower";
  }
}

// Self-shadowing: a box 0.1 high lit from 20 degrees above the plane. Hard shadows darken the
// plain behind it and never brighten anything; soft shadows darken no more than none, less
// than hard on the whole, and leave penumbra pixels between lit and shadowed.
TEST(Preview, ShadowsDarkenBehindABoxAndSoftOnesLieBetween) {
  const Mesh quad = test::make_grid(1, 1);
  const PreviewMaps maps = cone_maps(ConeScene::plateau, Border::clamp);
  PreviewOptions o = view_options("relief", 30.0f, 35.0f, 256, PreviewShade::lit);
  o.camera.light_elevation = 20.0f;
  o.camera.light_azimuth = 0.0f;  // toward +x of the frame: shadows fall toward -x
  HeadlessPreview gpu(quad, maps);
  const Image none = gpu.render(o);
  o.shadows = PreviewShadows::hard;
  const Image hard = gpu.render(o);
  o.shadows = PreviewShadows::soft;
  const Image soft = gpu.render(o);
  size_t darker = 0, covered = 0, penumbra = 0;
  double sum_none = 0, sum_hard = 0, sum_soft = 0;
  for (size_t i = 0; i < none.texel_count(); ++i) {
    if (none.pixels[4 * i + 3] < 0.5f) continue;
    ++covered;
    const float n = none.pixels[4 * i], h = hard.pixels[4 * i], s = soft.pixels[4 * i];
    ASSERT_LE(h, n + 1e-6f) << "pixel " << i;
    ASSERT_LE(s, n + 1e-6f) << "pixel " << i;
    darker += h < n - 0.05f;
    penumbra += s < n - 0.02f && s > 0.2f * n;  // partly lit (ambient alone is ~0.4 of lit after sRGB)
    sum_none += n;
    sum_hard += h;
    sum_soft += s;
  }
  std::printf("hard shadows darken %zu of %zu pixels; mean red none %.4f, soft %.4f, hard %.4f; %zu penumbra pixels\n", darker, covered,
              sum_none / static_cast<double>(covered), sum_soft / static_cast<double>(covered), sum_hard / static_cast<double>(covered), penumbra);
  EXPECT_GT(darker, covered / 50);
  EXPECT_LT(darker, covered / 2);
  EXPECT_LT(sum_soft, sum_none);
  EXPECT_GT(sum_soft, sum_hard);
  EXPECT_GT(penumbra, 0u);
}

// Streams that disagree on the border: cone.exr made with --wrap, pyramid.exr with --clamp.
// Each method is measured against a reference with its own border, so pyramid's figures do
// not depend on which methods it is compared with (beside cone they had been measured against
// the tiling reference the cone's stream asked for). The wrong hits left are at the quad's
// outline, where the displaced sheet outgrows the base mesh.
TEST(Measure, EachMethodAgainstAReferenceWithItsOwnBorder) {
  const Mesh quad = test::make_grid(1, 1);
  PreviewMaps maps = maps_with_height([](float u) { return 0.1f * u; });  // a cliff where it tiles
  // 8 x 8 texels: the half texel at each edge, where the borders differ, spans 6 pixels.
  Image coarse(8, 8, 1);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) coarse.at(x, y) = 0.1f * texel_center_u(x, 8);
  maps.displacement = coarse;
  const HeightField wrapped = make_height_field(maps.displacement, Border::wrap);
  maps.cone = build_cone_map(wrapped, ConeMapOptions{});
  maps.pyramid = pyramid_image(make_height_field(maps.displacement, Border::clamp));
  CompareOptions o;
  o.view.width = o.view.height = 96;
  o.view.camera.view_angle = 0;
  o.repetitions = 1;
  o.methods = {"pyramid"};
  PreviewMaps without_cone = maps;  // as `meso preview --compare --method pyramid` loads them
  without_cone.cone = Image();
  const MethodComparison alone = compare_methods(quad, without_cone, o).methods[0];
  o.methods = {"pyramid", "cone"};
  const Comparison both = compare_methods(quad, maps, o);
  const MethodComparison& beside = both.methods[0];
  EXPECT_EQ(beside.wrong_hits, alone.wrong_hits);
  EXPECT_EQ(beside.rmse, alone.rmse);
  EXPECT_EQ(beside.pixels, alone.pixels);
  std::printf("pyramid alone: %zu wrong of %zu, rmse %.6g; beside cone: %zu, %.6g; cone: %zu, %.6g\n", alone.wrong_hits, alone.pixels,
              alone.rmse, beside.wrong_hits, beside.rmse, both.methods[1].wrong_hits, both.methods[1].rmse);
  // A view that misses the mesh measures nothing: null, not a perfect 0 (as it had been).
  o.view.camera.pan_x = o.view.camera.pan_y = 50;
  const Comparison away = compare_methods(quad, maps, o);
  const auto json = nlohmann::json::parse(comparison_json(away));
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(away.methods[i].pixels, 0u);
    for (const char* key : {"wrong_hit_fraction", "rmse", "psnr", "mean_iterations", "p99_iterations", "max_iterations"})
      EXPECT_TRUE(json["methods"][i][key].is_null()) << key << " " << json["methods"][i][key];
  }
}

TEST(Measure, ComparisonReport) {
  const Mesh quad = test::make_grid(1, 1);
  PreviewMaps maps = maps_with_height([](float u) { return 0.1f * u; });
  CompareOptions o;
  o.view.width = 40;
  o.view.height = 32;
  o.repetitions = 3;
  // Without --method: every method whose stream is there (none is: the eleven without one).
  Comparison c = compare_methods(quad, maps, o);
  ASSERT_EQ(c.methods.size(), 11u);
  EXPECT_EQ(c.methods.front().name, "mesh");
  EXPECT_EQ(c.methods[9].name, "pom");
  EXPECT_EQ(c.methods.back().name, "dig");
  const auto json = nlohmann::json::parse(comparison_json(c));
  for (const char* key : {"triangles", "patches", "ms", "max_edge_texels", "build_ms"}) EXPECT_TRUE(json["reference"].contains(key)) << key;
  EXPECT_EQ(json["reference"]["triangles"].get<size_t>(), c.reference_triangles);
  EXPECT_EQ(json["reference"]["patches"].get<size_t>(), c.reference_patches);
  for (const char* key : {"width", "height", "view_angle", "azimuth", "zoom", "iterations", "uv_tolerance_texels"})
    EXPECT_TRUE(json.contains(key)) << key;
  ASSERT_EQ(json["methods"].size(), 11u);
  for (size_t i = 0; i < 11; ++i) {
    const auto& m = json["methods"][i];
    for (const char* key : {"name", "pixels", "wrong_hit_fraction", "rmse", "psnr", "mean_iterations", "p99_iterations", "max_iterations", "ms"})
      EXPECT_TRUE(m.contains(key)) << key;
    EXPECT_EQ(m["name"].get<std::string>(), c.methods[i].name);
    EXPECT_NEAR(m["wrong_hit_fraction"].get<double>(), c.methods[i].wrong_hit_fraction, 1e-8);
    EXPECT_EQ(m["pixels"].get<size_t>(), c.methods[i].pixels);
    EXPECT_EQ(m["psnr"].is_null(), c.methods[i].rmse == 0.0);
  }
  o.methods = {"pom", "no-such-method"};
  EXPECT_THROW(compare_methods(quad, maps, o), UsageError);
  o.methods = {"sphere-tracing"};
  EXPECT_THROW(compare_methods(quad, maps, o), UsageError) << "no distance field loaded";

  // The heatmap's ramp: dark blue at 0, yellow at the top, transparent off the mesh.
  Image fetches(3, 1, 2);
  fetches.pixels = {0.0f, 1.0f, 100.0f, 1.0f, 7.0f, 0.0f};
  const Image heat = fetch_heatmap(fetches, 100.0);
  EXPECT_NEAR(heat.at(0, 0, 0), 68 / 255.0, 1e-6);
  EXPECT_NEAR(heat.at(0, 0, 2), 84 / 255.0, 1e-6);
  EXPECT_NEAR(heat.at(1, 0, 0), 253 / 255.0, 1e-6);
  EXPECT_NEAR(heat.at(1, 0, 1), 231 / 255.0, 1e-6);
  EXPECT_EQ(heat.at(1, 0, 3), 1.0f);
  EXPECT_EQ(heat.at(2, 0, 3), 0.0f);
}


}  // namespace
}  // namespace meso
