// Golden images: every preview method renders a fixed scene (a 64 x 64 bumpy height map on a
// curved patch, lit, 64 x 48 pixels) and the frame is compared with the PNG stored in
// preview/testdata/golden/<method>.png. The checks that come with a closed-form answer live in
// preview_test.cpp; these catch any other change in what a method draws.
//
// Tolerance (llvmpipe's JIT may round differently on other CPUs): on the 8-bit sRGB values,
// at most 1 % of the pixels may differ by more than 4/255 in any channel (coverage included:
// alpha is a channel). A wrong shading, frame or search moves far more than that.
// To regenerate after an intended change: MESO_UPDATE_GOLDEN=1 build/release/preview/meso_preview_tests
// --gtest_filter='Golden.*', then look at the images before committing them.
#include "meso/formats/image_io.hpp"
#include "meso/preview/preview.hpp"
#include "meso/streams/cone_map.hpp"
#include "meso/streams/distance_field.hpp"
#include "meso/streams/pyramid.hpp"
#include "meso/streams/vdm.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace meso {
namespace {

struct Scene {
  Mesh base;
  Mesh high;
  PreviewMaps maps;
};

const Scene& scene() {
  static const Scene s = [] {
    Scene out;
    out.base = test::make_parametric(8, 8, [](double u, double v) {
      const double a = 1.0 * (u - 0.5);
      return Vec3f(float(std::sin(a)), float(v), float(std::cos(a) - 1.0));
    }, false, false);
    // The high surface for dstream: the patch lifted by 0.03 along its normal (radius 1.03).
    out.high = test::make_parametric(40, 40, [](double u, double v) {
      const double a = 1.2 * (u - 0.5);
      return Vec3f(float(1.03 * std::sin(a)), float(1.2 * v - 0.1), float(1.03 * std::cos(a) - 1.0));
    }, false, false);
    PreviewMaps& m = out.maps;
    m.displacement = Image(64, 64, 1);
    m.normal_ts = Image(64, 64, 3);
    const double two_pi = 6.283185307179586;
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 64; ++x) {
        const double u = (x + 0.5) / 64, v = 1 - (y + 0.5) / 64;
        const double h = 0.03 * std::abs(std::sin(two_pi * 3 * u) * std::cos(two_pi * 2 * v)) + 0.01 * std::sin(two_pi * (u + 2 * v));
        m.displacement.at(x, y) = static_cast<float>(h);
        const double nx = -0.5 * std::cos(two_pi * 3 * u), ny = 0.3 * std::sin(two_pi * 2 * v);
        const double nz = std::sqrt(1 - nx * nx - ny * ny);
        m.normal_ts.at(x, y, 0) = static_cast<float>(nx * 0.5 + 0.5);
        m.normal_ts.at(x, y, 1) = static_cast<float>(ny * 0.5 + 0.5);
        m.normal_ts.at(x, y, 2) = static_cast<float>(nz * 0.5 + 0.5);
      }
    const HeightField field = make_height_field(m.displacement, Border::clamp);
    m.cone = build_cone_map(field, ConeMapOptions{});
    ConeMapOptions relaxed;
    relaxed.kind = ConeKind::relaxed;
    m.relaxed_cone = build_cone_map(field, relaxed);
    m.pyramid = footprint_min_max(field);
    m.pyramid.metadata = height_field_metadata(field);
    m.sdf = distance_field_image(build_distance_field(field, DistanceFieldOptions{}), field);
    VdmOptions vdm;
    vdm.theta = 4;
    vdm.phi = 8;
    vdm.relief = 0.04f;
    const std::vector<Image> parts = vdm_images(compress_vdm(build_vdm(field, vdm), 1e-4, 16), field, vdm);
    m.vdm_weights = parts[0];
    m.vdm_basis = parts[1];
    DisplacementStreamOptions d;
    d.levels = 3;
    m.dstream = encode_displacement_stream(sample_displacement_stream(out.base, out.high, d));
    return out;
  }();
  return s;
}

TEST(Golden, EveryMethodDrawsItsStoredImage) {
  const std::filesystem::path dir = MESO_GOLDEN_DIR;
  const bool update = std::getenv("MESO_UPDATE_GOLDEN") != nullptr;
  HeadlessPreview gpu(scene().base, scene().maps);
  for (const std::string& method : preview_methods()) {
    PreviewOptions o;
    o.method = method;
    o.width = 64;
    o.height = 48;
    o.camera.view_angle = 50.0f;
    o.camera.azimuth = 30.0f;
    o.camera.zoom = 1.3f;
    o.iterations = 16;
    o.shadows = PreviewShadows::hard;
    o.shadow_steps = 8;
    const Image frame = gpu.render(o);
    const std::filesystem::path file = dir / (method + ".png");
    if (update) {
      write_image(frame, file, PixelFormat::uint8);
      continue;
    }
    ASSERT_TRUE(std::filesystem::exists(file)) << file << " missing (MESO_UPDATE_GOLDEN=1 makes it)";
    const Image golden = read_image(file);
    ASSERT_EQ(golden.width, frame.width);
    ASSERT_EQ(golden.height, frame.height);
    ASSERT_EQ(golden.channels, 4);
    size_t off = 0;
    for (size_t i = 0; i < frame.texel_count(); ++i) {
      bool differs = false;
      for (size_t c = 0; c < 4; ++c) {
        const double a = std::round(std::clamp(frame.pixels[4 * i + c], 0.0f, 1.0f) * 255.0), b = std::round(golden.pixels[4 * i + c] * 255.0);
        differs |= std::abs(a - b) > 4.0;
      }
      off += differs;
    }
    EXPECT_LE(off, frame.texel_count() / 100) << method << ": " << off << " of " << frame.texel_count() << " pixels differ from " << file;
  }
}

}  // namespace
}  // namespace meso
