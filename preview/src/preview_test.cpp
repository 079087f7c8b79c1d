// Headless rendering on whatever EGL offers (Mesa llvmpipe in CI), checked against the
// closed-form answers of flat height fields seen through the centre pixel.
#include "meso/preview/preview.hpp"

#include "meso/core/error.hpp"
#include "meso/streams/cone_map.hpp"
#include "meso/streams/distance_field.hpp"
#include "renderer.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

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

// Adds the cone maps of the displacement (as meso streams cone / relaxed-cone make them).
void add_cone_maps(PreviewMaps& maps, Border border) {
  const HeightField field = make_height_field(maps.displacement, border);
  maps.cone = build_cone_map(field, ConeMapOptions{});
  ConeMapOptions relaxed;
  relaxed.kind = ConeKind::relaxed;
  maps.relaxed_cone = build_cone_map(field, relaxed);
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
  for (const char* method : {"parallax", "iterative-parallax", "steep", "relief", "pom", "cone", "relaxed-cone"}) {
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
  for (const auto& [method, tolerance] : {std::pair<const char*, double>{"relief", 2e-4}, {"pom", 2e-4}, {"cone", 2e-4}, {"relaxed-cone", 2e-4}, {"sphere-tracing", 5e-4}}) {
    PreviewOptions opt = centre_uv_options(method, 50.0f);
    opt.iterations = 128;
    const Image img = render_headless(quad, maps, opt);
    EXPECT_NEAR(img.at(32, 32, 0), expect, tolerance) << method;
    if (std::string(method) == "sphere-tracing") {
      EXPECT_GE(img.at(32, 32, 0), expect - 5e-4) << "the safe phase stops before the surface";
    }
  }
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
  for (const auto& method : preview_methods()) {
    for (float angle : {0.0f, 89.9f}) {
      PreviewOptions o;
      o.method = method;
      o.width = 40;
      o.height = 30;
      o.camera.view_angle = angle;
      for (PreviewShade shade : {PreviewShade::lit, PreviewShade::uv}) {
        o.shade = shade;
        const Image img = render_headless(cylinder, maps, o);
        size_t covered = 0;
        for (size_t i = 0; i < img.texel_count(); ++i) {
          for (int c = 0; c < 4; ++c) ASSERT_TRUE(std::isfinite(img.pixels[4 * i + static_cast<size_t>(c)])) << method << " " << angle;
          covered += img.pixels[4 * i + 3] > 0.5f;
        }
        if (angle == 0.0f) {
          EXPECT_GT(covered, img.texel_count() / 4) << method;
        }
      }
    }
  }
}

TEST(Preview, MethodsNeedTheirStreams) {
  const Mesh quad = test::make_grid(1, 1);
  PreviewMaps maps = maps_with_height([](float u) { return 0.1f * u; });
  for (const char* method : {"sphere-tracing", "cone", "relaxed-cone"}) {
    EXPECT_THROW(render_headless(quad, maps, centre_uv_options(method, 30.0f)), UsageError) << method;
  }
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
TEST(Preview, ConeSteppingAgreesWithADenseReliefSearch) {
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
          for (const char* method : {"cone", "relaxed-cone"}) {
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
TEST(Preview, ConeSteppingMatchesTheReferenceTracer) {
  const Mesh quad = test::make_grid(1, 1);
  for (const auto& [scene, border] : {std::pair{ConeScene::rough, Border::clamp}, std::pair{ConeScene::rough, Border::wrap},
                                      std::pair{ConeScene::plateau, Border::clamp}}) {
    const PreviewMaps maps = cone_maps(scene, border);
    const HeightField field = make_height_field(maps.displacement, border);
    for (const auto& [method, kind] : {std::pair<const char*, ConeKind>{"cone", ConeKind::conservative}, {"relaxed-cone", ConeKind::relaxed}}) {
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
          const HeightHit hit = trace_cone_map(field, cone, kind, ray);
          if (!hit.hit) continue;
          ++hits;
          const double s = s_top + hit.t;
          const double du = img.at(x, y, 0) - (u0 + v[0] * s), dv = img.at(x, y, 1) - (v0 + v[1] * s);
          ++a.pixels;
          a.within += std::max(std::abs(du), std::abs(dv)) <= 0.01 / 64;
        }
      std::printf("%s %s %s: %zu of %zu traced pixels within 0.01 texel of the CPU tracer (%.4f)\n", method,
                  scene == ConeScene::plateau ? "plateau" : "rough", border_name(border), a.within, a.pixels, a.fraction());
      EXPECT_GT(hits, 96u * 96u / 4) << method;
      EXPECT_GE(a.fraction(), 0.995) << method << " " << border_name(border);
    }
  }
}

// With a budget the trace never exhausts, the budget does not matter: 256 and 4096 loop
// passes give the same image. With a small one, relaxed cones get further.
TEST(Preview, ConeSteppingDoesNotDependOnAGenerousBudget) {
  const Mesh quad = test::make_grid(1, 1);
  const PreviewMaps maps = cone_maps(ConeScene::plateau, Border::clamp);
  std::array<double, 2> converged_at_8{};
  for (const char* method : {"cone", "relaxed-cone"}) {
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
    converged_at_8[std::string(method) == "cone" ? 0 : 1] = f;
  }
  EXPECT_GT(converged_at_8[1], converged_at_8[0] + 0.03) << "relaxed cones take longer steps";
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

}  // namespace
}  // namespace meso
