// Headless rendering on whatever EGL offers (Mesa llvmpipe in CI), checked against the
// closed-form answers of flat height fields seen through the centre pixel.
#include "meso/preview/preview.hpp"

#include "meso/core/error.hpp"
#include "meso/streams/distance_field.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>

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
  const PreviewMaps maps = maps_with_height([](float) { return 0.05f; });
  for (const char* method : {"parallax", "iterative-parallax", "steep", "relief", "pom"}) {
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
  const double a = 50.0 * kPi / 180.0, k = 0.1;
  const double dx = -std::sin(a), dz = -std::cos(a);
  const double expect = 0.5 + dx * (0.5 * k / (dz - k * dx));
  for (const auto& [method, tolerance] : {std::pair<const char*, double>{"relief", 2e-4}, {"pom", 2e-4}, {"sphere-tracing", 5e-4}}) {
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
  const PreviewMaps maps = maps_with_height([](float) { return 0.0f; });
  EXPECT_THROW(render_headless(quad, maps, centre_uv_options("sphere-tracing", 30.0f)), UsageError);
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
