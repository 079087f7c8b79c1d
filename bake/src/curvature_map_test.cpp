// The per-texel second fundamental form (curvature_map.hpp) on surfaces whose curvature is
// known in closed form: sphere, cylinder both ways round, a cylinder patch mapped at 45
// degrees (the cross term and its sign, mirrored or not), a plane; no NaN with degenerate
// UVs; the texels are the bake's; dilation is the bake's; thread count changes nothing.
#include "meso/bake/curvature_map.hpp"

#include "meso/bake/uv_raster.hpp"
#include "meso/core/dilation_sources.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <string>

namespace meso {
namespace {

constexpr double kPi = 3.14159265358979323846;

CurvatureMap bake(const Mesh& m, int w, int h) {
  CurvatureMapOptions o;
  o.width = w;
  o.height = h;
  return bake_curvature_map(m, compute_tangent_frames(m), fit_curvature(m), o);
}

// The largest deviation of each channel from the expected (k_tt, k_tb, k_bb) over the
// computed texels whose centre lies in [u0, u1] x [v0, v1] (away from seams, open borders
// and poles, where the per-vertex fits are one-sided).
struct Deviation {
  double tt = 0, tb = 0, bb = 0;
  int texels = 0;
};
Deviation deviation(const CurvatureMap& c, double u0, double u1, double v0, double v1, double ktt, double ktb, double kbb) {
  Deviation d;
  const Image& im = c.image;
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x) {
      const double u = texel_center_u(x, im.width), v = texel_center_v(y, im.height);
      if (u < u0 || u > u1 || v < v0 || v > v1 || im.at(x, y, 3) != 1.0f) continue;
      d.tt = std::max(d.tt, std::abs(im.at(x, y, 0) - ktt));
      d.tb = std::max(d.tb, std::abs(im.at(x, y, 1) - ktb));
      d.bb = std::max(d.bb, std::abs(im.at(x, y, 2) - kbb));
      ++d.texels;
    }
  return d;
}

void expect_finite(const CurvatureMap& c) {
  for (float v : c.image.pixels) ASSERT_TRUE(std::isfinite(v));
  for (size_t i = 0; i < c.image.texel_count(); ++i) {
    const float a = c.image.pixels[4 * i + 3];
    ASSERT_TRUE(a == 0.0f || a == 1.0f) << a;
  }
  EXPECT_TRUE(std::isfinite(c.min) && std::isfinite(c.max));
}

// The texels computed are exactly those the bake's rasteriser gives a face (the map lines up
// with displacement.exr) when every one has a frame.
void expect_bake_texels(const Mesh& m, const CurvatureMap& c) {
  const auto samples = rasterize_uv(m, c.image.width, c.image.height);
  size_t n = 0;
  for (size_t i = 0; i < samples.size(); ++i) {
    ASSERT_EQ(c.image.pixels[4 * i + 3] == 1.0f, samples[i].face >= 0) << "texel " << i;
    n += samples[i].face >= 0;
  }
  EXPECT_EQ(c.texels, n);
  EXPECT_EQ(c.undefined, 0u);
}

void report(const char* name, const Deviation& d, double r) {
  std::printf("[%s] %d texels, max |error| x r: k_tt %.4f  k_tb %.4f  k_bb %.4f\n", name, d.texels, d.tt * r, d.tb * r, d.bb * r);
}

Vec3f sphere(double r, double s, double t) {
  const double th = kPi * (0.05 + 0.9 * t), ph = 2 * kPi * s;  // open caps, as curvature_test
  return Vec3f(float(r * std::sin(th) * std::cos(ph)), float(r * std::sin(th) * std::sin(ph)), float(-r * std::cos(th)));
}

TEST(CurvatureMap, SphereIsIsotropicOneOverR) {
  const double r = 2.5;
  const Mesh m = test::make_parametric(96, 48, [&](double s, double t) { return sphere(r, s, t); }, true, false);
  ASSERT_GT(OpenMesh::dot(m.normal(VertexHandle(0)), m.point(VertexHandle(0))), 0) << "outward normals";
  const CurvatureMap c = bake(m, 256, 128);
  expect_finite(c);
  expect_bake_texels(m, c);
  const Deviation d = deviation(c, 0.05, 0.95, 0.1, 0.9, 1 / r, 0, 1 / r);
  report("sphere", d, r);
  EXPECT_GT(d.texels, 20000);
  EXPECT_LT(d.tt, 0.01 / r);  // measured 0.004 / r
  EXPECT_LT(d.bb, 0.01 / r);
  EXPECT_LT(d.tb, 0.01 / r);  // measured 0.003 / r
  EXPECT_NEAR(c.max, 1 / r, 0.05 / r);
  EXPECT_GT(c.min, 0.0) << "convex everywhere: positive, the sign of _CURVATURE";
  EXPECT_EQ(std::get<std::string>(c.image.metadata.at("units")), "1/object");
}

TEST(CurvatureMap, CylinderBendsAroundAndNotAlongTheAxis) {
  const double r = 0.4;
  // u around the axis: t along the circle.
  const Mesh around = test::make_parametric(64, 20, [&](double s, double t) {
    const double ph = 2 * kPi * s;
    return Vec3f(float(r * std::cos(ph)), float(r * std::sin(ph)), float(2.0 * t));
  }, true, false);
  ASSERT_GT(OpenMesh::dot(around.normal(VertexHandle(0)), Vec3f(1, 0, 0)), 0) << "outward normals";
  const CurvatureMap a = bake(around, 128, 128);
  expect_finite(a);
  expect_bake_texels(around, a);
  const Deviation da = deviation(a, 0.05, 0.95, 0.1, 0.9, 1 / r, 0, 0);
  report("cylinder, u around", da, r);
  EXPECT_GT(da.texels, 10000);
  EXPECT_LT(da.tt, 0.015 / r);  // measured 0.0073 / r
  EXPECT_LT(da.tb, 0.002 / r);  // measured 0.0002 / r
  EXPECT_LT(da.bb, 0.002 / r);

  // u along the axis, v around (clockwise in phi so the normals still face outward).
  const Mesh along = test::make_parametric(20, 64, [&](double s, double t) {
    const double ph = -2 * kPi * t;
    return Vec3f(float(r * std::cos(ph)), float(r * std::sin(ph)), float(2.0 * s));
  }, false, true);
  ASSERT_GT(OpenMesh::dot(along.normal(VertexHandle(0)), Vec3f(1, 0, 0)), 0) << "outward normals";
  const CurvatureMap b = bake(along, 128, 128);
  expect_finite(b);
  const Deviation db = deviation(b, 0.1, 0.9, 0.05, 0.95, 0, 0, 1 / r);
  report("cylinder, v around", db, r);
  EXPECT_GT(db.texels, 10000);
  EXPECT_LT(db.tt, 0.002 / r);
  EXPECT_LT(db.tb, 0.002 / r);
  EXPECT_LT(db.bb, 0.015 / r);
}

// A cylinder patch (radius r, axis z) whose UVs run at 45 degrees to the axis:
// arc length a = L (s - t), height z = L (s + t). With d_a the unit direction around,
// t^ = (d_a + d_z)/sqrt 2 and b^ = (d_z - d_a)/sqrt 2, so S = d_a d_a^T / r gives
// k_tt = k_bb = 1/(2r) and k_tb = -1/(2r). Mirrored (u -> 1 - u), t^ flips and k_tb with it.
Mesh helix_patch(double r, double length) {
  return test::make_parametric(48, 48, [=](double s, double t) {
    const double a = length * (s - t), z = length * (s + t);
    return Vec3f(float(r * std::cos(a / r)), float(r * std::sin(a / r)), float(z));
  }, false, false);
}

TEST(CurvatureMap, CrossTermOfAMappingAt45Degrees) {
  const double r = 1.0;
  Mesh m = helix_patch(r, 1.0);
  const CurvatureMap c = bake(m, 128, 128);
  expect_finite(c);
  expect_bake_texels(m, c);
  const Deviation d = deviation(c, 0.15, 0.85, 0.15, 0.85, 0.5 / r, -0.5 / r, 0.5 / r);
  report("45 degrees", d, r);
  EXPECT_GT(d.texels, 4000);
  EXPECT_LT(d.tt, 0.002 / r);  // measured 0.0003 / r
  EXPECT_LT(d.tb, 0.002 / r);
  EXPECT_LT(d.bb, 0.002 / r);
  // w^T K w: 1/r around the axis (w = (t^ - b^)/sqrt 2), 0 along it (w = (t^ + b^)/sqrt 2).
  const float* k = c.image.texel(64, 64);
  EXPECT_NEAR(0.5 * (k[0] - 2 * k[1] + k[2]), 1 / r, 0.002 / r);
  EXPECT_NEAR(0.5 * (k[0] + 2 * k[1] + k[2]), 0.0, 0.002 / r);

  for (auto h : m.halfedges())
    if (!m.is_boundary(h)) {
      const Vec2f uv = m.texcoord2D(h);
      m.set_texcoord2D(h, Vec2f(1 - uv[0], uv[1]));
    }
  const CurvatureMap mirrored = bake(m, 128, 128);
  expect_finite(mirrored);
  const Deviation dm = deviation(mirrored, 0.15, 0.85, 0.15, 0.85, 0.5 / r, 0.5 / r, 0.5 / r);
  report("45 degrees, mirrored", dm, r);
  EXPECT_GT(dm.texels, 4000);
  EXPECT_LT(dm.tt, 0.002 / r);
  EXPECT_LT(dm.tb, 0.002 / r);
  EXPECT_LT(dm.bb, 0.002 / r);
}

TEST(CurvatureMap, PlaneIsZero) {
  const Mesh m = test::make_grid(8, 8, 2.0f, 2.0f);
  const CurvatureMap c = bake(m, 64, 64);
  expect_finite(c);
  expect_bake_texels(m, c);
  EXPECT_EQ(c.texels, 64u * 64u);
  for (size_t i = 0; i < c.image.texel_count(); ++i)
    for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(c.image.pixels[4 * i + static_cast<size_t>(ch)], 0.0f, 1e-5f);
  EXPECT_NEAR(c.min, 0.0f, 1e-5f);
  EXPECT_NEAR(c.max, 0.0f, 1e-5f);
}

TEST(CurvatureMap, DegenerateUvsGiveNoNan) {
  Mesh m = test::make_parametric(24, 12, [&](double s, double t) { return sphere(1.0, s, t); }, true, false);
  int f = 0;
  for (auto fh : m.faces()) {
    const auto hs = face_halfedges(m, fh);
    if (f % 5 == 0) {  // collapsed to a point
      for (auto h : hs) m.set_texcoord2D(h, m.texcoord2D(hs[0]));
    } else if (f % 7 == 0) {  // collinear
      m.set_texcoord2D(hs[2], (m.texcoord2D(hs[0]) + m.texcoord2D(hs[1])) * 0.5f);
    } else if (f % 11 == 0) {  // two corners on one UV
      m.set_texcoord2D(hs[1], m.texcoord2D(hs[0]));
    }
    ++f;
  }
  const CurvatureMap c = bake(m, 64, 32);
  expect_finite(c);
  EXPECT_GT(c.texels, 0u);
  EXPECT_LE(c.max, 1.5f);
}

TEST(CurvatureMap, DilatedFromTheNearestComputedTexel) {
  const double r = 0.4;
  Mesh m = test::make_parametric(32, 10, [&](double s, double t) {
    const double ph = 2 * kPi * s;
    return Vec3f(float(r * std::cos(ph)), float(r * std::sin(ph)), float(2.0 * t));
  }, true, false);
  for (auto h : m.halfedges())
    if (!m.is_boundary(h)) m.set_texcoord2D(h, Vec2f(0.25f, 0.25f) + m.texcoord2D(h) * 0.5f);
  const CurvatureMap c = bake(m, 64, 64);
  expect_finite(c);
  expect_bake_texels(m, c);
  std::vector<uint8_t> written(c.image.texel_count());
  for (size_t i = 0; i < written.size(); ++i) written[i] = c.image.pixels[4 * i + 3] == 1.0f;
  const auto sources = dilation_sources(written, 64, 64, -1);
  size_t filled = 0;
  for (size_t i = 0; i < written.size(); ++i) {
    if (written[i]) continue;
    ++filled;
    ASSERT_GE(sources[i], 0);
    for (size_t ch = 0; ch < 3; ++ch) ASSERT_EQ(c.image.pixels[4 * i + ch], c.image.pixels[4 * static_cast<size_t>(sources[i]) + ch]);
  }
  EXPECT_GT(filled, 2000u);
}

TEST(CurvatureMap, IndependentOfThreadCount) {
  const Mesh m = test::make_parametric(40, 20, [&](double s, double t) { return sphere(1.0, s, t); }, true, false);
  const CurvatureMap all = bake(m, 200, 100);
  CurvatureMap one;
  {
    tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    one = bake(m, 200, 100);
  }
  EXPECT_EQ(all.image.pixels, one.image.pixels);
  EXPECT_EQ(all.min, one.min);
  EXPECT_EQ(all.max, one.max);
}

}  // namespace
}  // namespace meso
