#include "meso/uvpack/uv_density.hpp"

#include "meso/uvpack/uv_pack.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>

namespace meso {
namespace {

// Two equal square charts side by side in UV: A on u in [0.05, 0.45], B on [0.55, 0.95],
// v in [0.3, 0.7].
Mesh two_squares() { return test::make_uv_quads({{0.05f, 0.3f, 0.45f, 0.7f}, {0.55f, 0.3f, 0.95f, 0.7f}}); }

double chart_uv_area(const Mesh& m, int first_face) {
  return 0.5 * std::abs(static_cast<double>(uv_double_area(m, FaceHandle(first_face)))) +
         0.5 * std::abs(static_cast<double>(uv_double_area(m, FaceHandle(first_face + 1))));
}

// A linear ramp f = a u on chart A has |grad f| = a per UV unit exactly (central and
// one-sided differences of a linear function are exact); a constant on B has 0.
TEST(UvDensity, RampMeasuresItsSlopeAndMovesTexelsToTheDetailedChart) {
  const Mesh m = two_squares();
  const int n = 64;
  const double a = 3.0;
  Image map(n, n, 1);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) map.at(x, y) = x < n / 2 ? static_cast<float>(a * (x + 0.5) / n) : 0.25f;
  const auto d = measure_chart_detail(m, map);
  ASSERT_EQ(d.size(), 2u);
  EXPECT_NEAR(d[0].detail, a, 1e-5);
  EXPECT_EQ(d[1].detail, 0.0);
  EXPECT_EQ(d[0].texels, d[1].texels);
  // Reference: RMS over equal texel counts = a / sqrt(2); A grows by sqrt(2), B shrinks to the clamp.
  EXPECT_NEAR(d[0].scale, std::sqrt(2.0), 1e-5);
  EXPECT_EQ(d[1].scale, 0.5);
  // Packed with those scales, the UV areas keep exactly that ratio.
  Mesh packed = m;
  UvPackOptions o;
  o.size = 256;
  o.chart_scale = {d[0].scale, d[1].scale};
  pack_uv_charts(packed, o);
  EXPECT_NEAR(chart_uv_area(packed, 0) / chart_uv_area(packed, 2), (d[0].scale / d[1].scale) * (d[0].scale / d[1].scale), 1e-3);
  // A map of uniform detail leaves every scale at 1; so does a constant one.
  Image uniform(n, n, 1), flat(n, n, 1, 0.5f);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) uniform.at(x, y) = static_cast<float>(x % (n / 2)) / n;
  for (const auto& c : measure_chart_detail(m, uniform)) EXPECT_NEAR(c.scale, 1.0, 1e-6);
  for (const auto& c : measure_chart_detail(m, flat)) EXPECT_EQ(c.scale, 1.0);
}

}  // namespace
}  // namespace meso
