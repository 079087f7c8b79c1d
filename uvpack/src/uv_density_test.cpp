#include "meso/uvpack/uv_density.hpp"

#include "meso/uvpack/uv_pack.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>

namespace meso {
namespace {

// Two equal square charts side by side in UV: A on u in [0.05, 0.45], B on [0.55, 0.95],
// v in [0.3, 0.7].
Mesh two_squares() {
  Mesh m;
  m.request_halfedge_texcoords2D();
  for (int c = 0; c < 2; ++c) {
    const float u0 = c == 0 ? 0.05f : 0.55f, u1 = u0 + 0.4f, v0 = 0.3f, v1 = 0.7f, z = static_cast<float>(c);
    const VertexHandle p = m.add_vertex(Vec3f(u0, v0, z)), q = m.add_vertex(Vec3f(u1, v0, z)), r = m.add_vertex(Vec3f(u1, v1, z)),
                       s = m.add_vertex(Vec3f(u0, v1, z));
    for (const auto& tri : {std::array<VertexHandle, 3>{p, q, r}, std::array<VertexHandle, 3>{p, r, s}}) {
      const FaceHandle f = m.add_face(tri[0], tri[1], tri[2]);
      for (auto h : face_halfedges(m, f)) {
        const Vec3f x = m.point(m.to_vertex_handle(h));
        m.set_texcoord2D(h, Vec2f(x[0], x[1]));
      }
    }
  }
  compute_angle_weighted_normals(m);
  return m;
}

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
