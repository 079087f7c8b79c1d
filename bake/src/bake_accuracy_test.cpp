// The accuracy claims of issue 5 that bake_test.cpp does not cover:
//  - identity bake on a curved mesh with UV seams and a mirrored half, through the PNG
//    encoder the CLI uses for normal_ts.png, in 8 and 16 bits;
//  - round trip: the baked tangent-space map, decoded the way the previewer's shader does,
//    reproduces the analytic normals of the high surface;
//  - known answers at K samples per texel: a flat quad over a sine height field, a coarse
//    sphere band over a bumpy one, against the exact triangulated surface and the smooth one;
//  - padding across MIP levels: after the bake's dilation, box-filtered levels
//    0..floor(log2(P/2 + 1)) of an atlas packed with padding P never mix two charts in a texel
//    a chart reads; with uvpack's --mip-safe K, levels 0..K never mix in a texel a chart's
//    bilinear lookups read, and uv_check predicts exactly which texels mix.
#include "meso/bake/bake.hpp"
#include "meso/bake/tangent_frame.hpp"
#include "meso/bake/uv_raster.hpp"
#include "meso/formats/image_io.hpp"
#include "meso/uvpack/uv_check.hpp"
#include "meso/uvpack/uv_pack.hpp"
#include "bumpy_torus.hpp"
#include "test_support.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <set>
#include <tuple>
#include <vector>

namespace meso {
namespace {

using test::BumpyTorus;
using test::mirror_half;

constexpr double kPi = 3.14159265358979323846;

size_t mirrored_faces(const Mesh& m) {
  const auto frames = compute_tangent_frames(m);
  size_t n = 0;
  for (auto f : m.faces()) n += frames[static_cast<size_t>(face_halfedges(m, f)[0].idx())].sign < 0;
  return n;
}

// The normal map as the CLI writes normal_ts.png (encode_normal_map, then write_image at the
// given bit depth), read back as integer codes.
std::vector<long> png_codes(const Image& normal_ts, PixelFormat format, const test::TempDir& dir, double& max_code) {
  const auto path = dir / (format == PixelFormat::uint8 ? "normal_ts8.png" : "normal_ts16.png");
  write_image(encode_normal_map(normal_ts), path, format);
  const Image back = read_image(path);
  EXPECT_EQ(back.width, normal_ts.width);
  EXPECT_EQ(back.height, normal_ts.height);
  EXPECT_EQ(back.channels, 3);
  max_code = format == PixelFormat::uint8 ? 255.0 : 65535.0;
  return test::image_codes(back, max_code);
}

// Identity bake: high = low, a curved mesh with UV seams and a mirrored half. Every covered
// texel must decode to (0, 0, 1) within half a least significant bit: the stored code lies
// within 1/2 of the exact (0.5, 0.5, 1) * max (x and y: 127 or 128 in 8 bits, 32767 or 32768
// in 16 bits; z: 255 or 65535). (Through the command line, --png-bits 8 and 16:
// CliBake.IdentityBakeDecodesToUpWithinHalfAnLsbIn8And16Bits.)
TEST(BakeAccuracy, IdentityBakeDecodesToUpWithinHalfAnLsbIn8And16Bits) {
  Mesh torus = BumpyTorus{}.mesh(48, 24);
  mirror_half(torus);
  ASSERT_EQ(mirrored_faces(torus), torus.n_faces() / 2) << "the layout's premise: one half mirrored";
  size_t charts = 0;
  uv_charts(torus, &charts);
  ASSERT_EQ(charts, 2u);
  BakeOptions o;
  o.width = o.height = 256;
  const BakeResult r = bake(torus, torus, o);
  ASSERT_GT(r.covered_texels, 256u * 256u / 2);
  EXPECT_EQ(r.misses, 0u);
  test::TempDir dir;
  for (const PixelFormat format : {PixelFormat::uint8, PixelFormat::uint16}) {
    double max_code = 0;
    const std::vector<long> codes = png_codes(r.normal_ts, format, dir, max_code);
    const char* bits = max_code == 255 ? " 8" : "16";
    const test::UpCodesCheck check = test::check_codes_decode_to_up(codes, r.coverage, max_code, std::string(bits) + "-bit");
    EXPECT_EQ(check.checked, r.covered_texels);
    EXPECT_EQ(check.bad, 0u);
    std::printf("[ identity ] %s-bit: %zu covered texels, largest code offsets from the ideal x %.2f y %.2f z %.2f LSB\n", bits,
                check.checked, check.worst[0], check.worst[1], check.worst[2]);
  }
}

// The base point a texel samples, its interpolated normal and frame, as bake.cpp and the
// previewer's shader (surface.frag) form them: p, n, t interpolated without normalising,
// b = sign * cross(n, t).
struct BasePoint {
  Eigen::Vector3d p, n, t, b;
  double sign = 1;
  // The shader's decoding of a tangent-space normal m: normalize(m.x t + m.y b + m.z n).
  Eigen::Vector3d decode(const Eigen::Vector3d& m) const { return Eigen::Vector3d(m.x() * t + m.y() * b + m.z() * n).normalized(); }
};
BasePoint base_point(const Mesh& base, const std::vector<TangentFrame>& frames, const TexelSample& s) {
  BasePoint bp;
  bp.p = bp.n = bp.t = Eigen::Vector3d::Zero();
  const auto hs = face_halfedges(base, FaceHandle(s.face));
  for (size_t k = 0; k < 3; ++k) {
    const auto v = base.to_vertex_handle(hs[k]);
    const Vec3f& pv = base.point(v);
    const Vec3f& nv = base.normal(v);
    const Vec3f& tv = frames[static_cast<size_t>(hs[k].idx())].tangent;
    bp.p += s.bary[k] * Eigen::Vector3d(pv[0], pv[1], pv[2]);
    bp.n += s.bary[k] * Eigen::Vector3d(nv[0], nv[1], nv[2]);
    bp.t += s.bary[k] * Eigen::Vector3d(tv[0], tv[1], tv[2]);
  }
  bp.sign = frames[static_cast<size_t>(hs[0].idx())].sign;
  bp.b = bp.sign * bp.n.cross(bp.t);
  return bp;
}

double angle_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180 / kPi;
}

// Where the ray org + t dir (t in [lo, hi]) meets the triangles of a grid mesh from
// make_parametric (no wrap in t; cell (i, j) = faces 2 (j columns + i) and the next), looking
// at the cells within one of (ci, cj) (wrapping i when wrap_s): the exact answer for the
// triangulated surface, in double from its float vertices. NaN when none is hit.
double facet_hit(const Mesh& m, int columns, int rows, int ci, int cj, bool wrap_s, const Eigen::Vector3d& org, const Eigen::Vector3d& dir) {
  double best = std::numeric_limits<double>::quiet_NaN();
  for (int dj = -1; dj <= 1; ++dj)
    for (int di = -1; di <= 1; ++di) {
      int i = ci + di;
      const int j = cj + dj;
      if (wrap_s) i = (i + columns) % columns;
      if (i < 0 || j < 0 || i >= columns || j >= rows) continue;
      for (int k = 0; k < 2; ++k) {
        const FaceHandle f(2 * (j * columns + i) + k);
        std::array<Eigen::Vector3d, 3> v;
        size_t c = 0;
        for (auto vh : m.fv_range(f)) {
          const Vec3f& q = m.point(vh);
          v[c++] = Eigen::Vector3d(q[0], q[1], q[2]);
        }
        // Moller-Trumbore, both sides.
        const Eigen::Vector3d e1 = v[1] - v[0], e2 = v[2] - v[0], pv = dir.cross(e2);
        const double det = e1.dot(pv);
        if (std::abs(det) < 1e-300) continue;
        const Eigen::Vector3d tv = org - v[0];
        const double u = tv.dot(pv) / det;
        const Eigen::Vector3d qv = tv.cross(e1);
        const double w = dir.dot(qv) / det, t = e2.dot(qv) / det;
        if (u < -1e-12 || w < -1e-12 || u + w > 1 + 1e-12) continue;
        if (std::isnan(best) || std::abs(t) < std::abs(best)) best = t;
      }
    }
  return best;
}

// A smooth height field over the plane: A (sin(2 pi x + 0.7) cos(2 pi y - 0.4)
// + 0.5 sin(pi (x + 2 y) + 1.1)), slopes up to ~11 degrees at A = 0.02, its gradient exact.
struct SineField {
  double A = 0.02;
  double h(double x, double y) const {
    return A * (std::sin(2 * kPi * x + 0.7) * std::cos(2 * kPi * y - 0.4) + 0.5 * std::sin(kPi * (x + 2 * y) + 1.1));
  }
  Eigen::Vector3d normal(double x, double y) const {
    const double c = 0.5 * kPi * std::cos(kPi * (x + 2 * y) + 1.1);
    const double hx = A * (2 * kPi * std::cos(2 * kPi * x + 0.7) * std::cos(2 * kPi * y - 0.4) + c);
    const double hy = A * (-2 * kPi * std::sin(2 * kPi * x + 0.7) * std::sin(2 * kPi * y - 0.4) + 2 * c);
    return Eigen::Vector3d(-hx, -hy, 1).normalized();
  }
};

// Sets every vertex normal of `m` to normal(point): the high surface's true normals, so the
// test measures the bake and not the mesh's normal estimate.
void set_normals(Mesh& m, const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& normal) {
  for (auto v : m.vertices()) {
    const Vec3f& q = m.point(v);
    const Eigen::Vector3d n = normal(Eigen::Vector3d(q[0], q[1], q[2]));
    m.set_normal(v, Vec3f(static_cast<float>(n.x()), static_cast<float>(n.y()), static_cast<float>(n.z())));
  }
}

// Known answer: the flat unit quad (UV = xy, frame = the axes) over a 416 x 416 grid of the
// sine field on [-0.02, 1.02]^2 (spacing 1/400). Each texel's value is the box filter of its
// K = n x n samples at the sub-texel centres: the mean displacement, the renormalised mean
// normal. The rays are vertical, so the mesh's answer at a sample is the height of the
// triangle above it, known exactly (facet_hit); the smooth field's is h. Against the facets
// the displacement is held to 2e-6 A (float heights: 1 ulp of 0.02 is 1e-7 A; measured
// 2.4e-7 A). The facets themselves differ from h by up to ~9e-5 A at this spacing (linear
// interpolation, |D^2 h| <= ~64 A; measured 9.0e-5 A, deterministic), within issue 5's
// 1e-4 A. The normals (the mesh's vertex normals are the field's, interpolated): issue 5
// asks 0.5 degrees against the box filter of the field's normals; held to 0.01 (measured
// 0.0008).
TEST(BakeAccuracy, SineFieldUnderAFlatQuadMatchesTheAnalyticAnswerAtKSamples) {
  const SineField field;
  const int cells = 416;
  const double x0 = -0.02, span = 1.04;
  Mesh high = test::make_parametric(
      cells, cells,
      [&](double s, double t) {
        const double x = x0 + span * s, y = x0 + span * t;
        return Vec3f(static_cast<float>(x), static_cast<float>(y), static_cast<float>(field.h(x, y)));
      },
      false, false);
  set_normals(high, [&](const Eigen::Vector3d& q) { return field.normal(q.x(), q.y()); });
  const Mesh low = test::make_grid(1, 1);
  const int n = 48;
  for (const int k : {4, 16}) {
    BakeOptions o;
    o.width = o.height = n;
    o.front = o.back = 0.1f;
    o.samples = k;
    const BakeResult r = bake(low, high, o);
    ASSERT_EQ(r.samples, k);
    EXPECT_EQ(r.misses, 0u);
    const int sub = static_cast<int>(std::lround(std::sqrt(k)));
    double worst_facet = 0, worst_smooth = 0, worst_angle = 0;
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        double facet = 0, smooth = 0;
        Eigen::Vector3d normal = Eigen::Vector3d::Zero();
        for (int b = 0; b < sub; ++b)
          for (int a = 0; a < sub; ++a) {
            const double u = texel_center_u(x * sub + a, n * sub), v = texel_center_v(y * sub + b, n * sub);
            const int ci = static_cast<int>(std::floor((u - x0) / span * cells)), cj = static_cast<int>(std::floor((v - x0) / span * cells));
            const double t = facet_hit(high, cells, cells, ci, cj, false, Eigen::Vector3d(u, v, 0), Eigen::Vector3d(0, 0, 1));
            ASSERT_FALSE(std::isnan(t)) << u << "," << v;
            facet += t;
            smooth += field.h(u, v);
            normal += field.normal(u, v);
          }
        facet /= k;
        smooth /= k;
        const double d = r.displacement.at(x, y);
        worst_facet = std::max(worst_facet, std::abs(d - facet));
        worst_smooth = std::max(worst_smooth, std::abs(d - smooth));
        const Eigen::Vector3d m(r.normal_ts.at(x, y, 0), r.normal_ts.at(x, y, 1), r.normal_ts.at(x, y, 2));
        worst_angle = std::max(worst_angle, angle_deg(m, normal.normalized()));
      }
    std::printf("[ sine field K=%d ] worst |d - facets| %.3g A, |d - h| %.3g A, normal %.4f deg\n", k, worst_facet / field.A,
                worst_smooth / field.A, worst_angle);
    EXPECT_LT(worst_facet, 2e-6 * field.A) << "K = " << k;
    EXPECT_LT(worst_smooth, 1e-4 * field.A) << "K = " << k;
    EXPECT_LT(worst_angle, 0.01) << "K = " << k;
  }
}

// A bumpy sphere band, radius r + a sin(3 phi) sin(4 theta) at polar angle theta, azimuth phi.
struct BumpySphere {
  double r = 1.0, a = 0.02;
  double radius(double th, double ph) const { return r + a * std::sin(3 * ph) * std::sin(4 * th); }
  Eigen::Vector3d point(double th, double ph) const {
    return radius(th, ph) * Eigen::Vector3d(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
  }
  // normalize(P_theta x P_phi) = normalize(R sin(theta) e_r - R_theta sin(theta) e_theta - R_phi e_phi).
  Eigen::Vector3d normal(double th, double ph) const {
    const double R = radius(th, ph), Rt = 4 * a * std::sin(3 * ph) * std::cos(4 * th), Rp = 3 * a * std::cos(3 * ph) * std::sin(4 * th);
    const Eigen::Vector3d er(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
    const Eigen::Vector3d et(std::cos(th) * std::cos(ph), std::cos(th) * std::sin(ph), -std::sin(th));
    const Eigen::Vector3d ep(-std::sin(ph), std::cos(ph), 0);
    return (R * std::sin(th) * er - Rt * std::sin(th) * et - Rp * ep).normalized();
  }
  static void angles(const Eigen::Vector3d& q, double& th, double& ph) {
    th = std::acos(std::clamp(q.z() / q.norm(), -1.0, 1.0));
    ph = std::atan2(q.y(), q.x());
  }
};

// A band of a coarse UV sphere (32 x 10 quads, polar angle 30..150 degrees, UV seam at
// phi = 0; smooth normals: the sphere's radial ones) over the bumpy sphere on 20..160 degrees
// (768 x 240 quads, its true normals at the vertices). The poles are left out: their fans
// of degenerate UV triangles are another test's subject (collapsed UVs). For every texel
// whose centre lies in a face, 3 texels or more from the chart's border (the seam and the
// band's edges), the displacement is the exact distance to the triangulated surface along the
// interpolated normal (facet_hit) within 2e-5 a (float positions near radius 1), and within
// the facets' chord error of the smooth one: diagonal^2 / 8 * curvature = 2.1e-5 * (<= 1.3),
// held to 5e-5; the decoded normal (the shader's decoding) within 0.01 degrees of the smooth
// surface's normal at the hit (issue 5 asks 0.5).
TEST(BakeAccuracy, CoarseSphereOverABumpySphereMatchesTheExactSurface) {
  const BumpySphere sphere;
  const double th0 = 30 * kPi / 180, th1 = 150 * kPi / 180, hth0 = 20 * kPi / 180, hth1 = 160 * kPi / 180;
  auto band = [](double lo, double hi, const std::function<Eigen::Vector3d(double, double)>& f) {
    return [lo, hi, f](double s, double t) {
      const Eigen::Vector3d q = f(lo + (hi - lo) * t, 2 * kPi * s);
      return Vec3f(static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z()));
    };
  };
  Mesh base = test::make_parametric(32, 10, band(th0, th1, [](double th, double ph) { return BumpySphere{1.0, 0.0}.point(th, ph); }), true, false);
  set_normals(base, [](const Eigen::Vector3d& q) { return q.normalized(); });
  const int hc = 768, hr = 240;
  Mesh high = test::make_parametric(hc, hr, band(hth0, hth1, [&](double th, double ph) { return sphere.point(th, ph); }), true, false);
  set_normals(high, [&](const Eigen::Vector3d& q) {
    double th = 0, ph = 0;
    BumpySphere::angles(q, th, ph);
    return sphere.normal(th, ph);
  });
  const int n = 128;
  BakeOptions o;
  o.width = o.height = n;
  o.front = o.back = 0.1f;
  const BakeResult r = bake(base, high, o);
  EXPECT_EQ(r.misses, 0u);
  const auto samples = rasterize_uv(base, n, n);
  const auto frames = compute_tangent_frames(base);
  double worst_facet = 0, worst_smooth = 0, worst_angle = 0;
  size_t measured = 0;
  for (int y = 3; y < n - 3; ++y)
    for (int x = 3; x < n - 3; ++x) {
      const TexelSample& s = samples[static_cast<size_t>(y) * n + static_cast<size_t>(x)];
      ASSERT_GE(s.face, 0);
      if (!s.centre_inside) continue;
      const BasePoint bp = base_point(base, frames, s);
      const Eigen::Vector3d dir = bp.n.normalized();
      const double d = r.displacement.at(x, y);
      const Eigen::Vector3d hit = bp.p + d * dir;
      double th = 0, ph = 0;
      BumpySphere::angles(hit, th, ph);
      const double ps = (ph < 0 ? ph + 2 * kPi : ph) / (2 * kPi), pt = (th - hth0) / (hth1 - hth0);
      const double facet = facet_hit(high, hc, hr, static_cast<int>(std::floor(ps * hc)), static_cast<int>(std::floor(pt * hr)), true, bp.p, dir);
      ASSERT_FALSE(std::isnan(facet)) << x << "," << y;
      // The smooth surface along the same ray: |p + t dir| = radius(angles), by Newton from
      // the facet answer (a few steps converge to 1e-15 from that close).
      double t = facet;
      for (int it = 0; it < 20; ++it) {
        const auto g = [&](double tt) {
          const Eigen::Vector3d q = bp.p + tt * dir;
          double a = 0, b = 0;
          BumpySphere::angles(q, a, b);
          return q.norm() - sphere.radius(a, b);
        };
        const double step = 1e-7, slope = (g(t + step) - g(t - step)) / (2 * step);
        t -= g(t) / slope;
      }
      worst_facet = std::max(worst_facet, std::abs(d - facet));
      worst_smooth = std::max(worst_smooth, std::abs(d - t));
      const Eigen::Vector3d m(r.normal_ts.at(x, y, 0), r.normal_ts.at(x, y, 1), r.normal_ts.at(x, y, 2));
      worst_angle = std::max(worst_angle, angle_deg(bp.decode(m), sphere.normal(th, ph)));
      ++measured;
    }
  std::printf("[ bumpy sphere ] %zu texels: worst |d - facets| %.3g (%.3g a), |d - smooth| %.3g (%.3g a), normal %.4f deg\n",
              measured, worst_facet, worst_facet / sphere.a, worst_smooth, worst_smooth / sphere.a, worst_angle);
  EXPECT_GT(measured, static_cast<size_t>(n) * n * 3 / 4);
  EXPECT_LT(worst_facet, 2e-5 * sphere.a);
  EXPECT_LT(worst_smooth, 5e-5);
  EXPECT_LT(worst_angle, 0.01);
}

struct AngleStats {
  std::vector<double> deg;
  double mean() const {
    double s = 0;
    for (double d : deg) s += d;
    return deg.empty() ? 0 : s / static_cast<double>(deg.size());
  }
  double quantile(double q) const {
    if (deg.empty()) return 0;
    std::vector<double> v = deg;
    const size_t k = std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())));
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
    return v[k];
  }
  double max() const { return deg.empty() ? 0 : *std::max_element(deg.begin(), deg.end()); }
};

// Round trip: a coarse torus base (one half mirrored in UV) over a finely tessellated bumpy
// torus. Each covered texel of the 16-bit normal_ts.png is decoded as the previewer's shader
// does (surface.frag: m = 2 c - 1, N = normalize(m.x t + m.y b + m.z n) with the corner
// frames interpolated without normalising, b = sign * cross(n, t)) at the base point the
// texel sampled, and compared with the analytic normal of the bumpy torus at the ray's hit.
// Away from seams (texels whose centre lies in a face and whose 5 x 5 neighbourhood belongs
// to one chart): mean < 0.5 degrees, p99 < 2 degrees. The seam band is reported.
TEST(BakeAccuracy, RoundTripThroughTheShadersDecodingReproducesTheHighNormals) {
  BumpyTorus high_surface;
  high_surface.amp = 0.012;  // slopes up to ~8 degrees
  Mesh base = BumpyTorus{}.mesh(64, 32);
  mirror_half(base);
  ASSERT_EQ(mirrored_faces(base), base.n_faces() / 2);
  const Mesh high = high_surface.mesh(768, 384);
  const int n = 512;
  BakeOptions o;
  o.width = o.height = n;
  o.front = o.back = 0.05f;
  const BakeResult r = bake(base, high, o);
  EXPECT_EQ(r.misses, 0u);
  EXPECT_EQ(r.ambiguous, 0u);
  test::TempDir dir;
  double max_code = 0;
  const std::vector<long> codes = png_codes(r.normal_ts, PixelFormat::uint16, dir, max_code);

  const auto samples = rasterize_uv(base, n, n);
  const auto frames = compute_tangent_frames(base);
  const std::vector<int> chart = uv_charts(base);
  auto chart_at = [&](int x, int y) {
    if (x < 0 || y < 0 || x >= n || y >= n) return -1;
    const int f = samples[static_cast<size_t>(y) * n + static_cast<size_t>(x)].face;
    return f < 0 ? -1 : chart[static_cast<size_t>(f)];
  };
  AngleStats interior, seam, interior_float;
  size_t mirrored_interior = 0;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const size_t i = static_cast<size_t>(y) * n + static_cast<size_t>(x);
      const TexelSample& s = samples[i];
      if (s.face < 0) continue;
      ASSERT_EQ(r.coverage.pixels[i], 1.0f) << x << "," << y;
      const BasePoint bp = base_point(base, frames, s);
      // The analytic normal where the ray met the high surface.
      const Eigen::Vector3d hit = bp.p + static_cast<double>(r.displacement.pixels[i]) * bp.n.normalized();
      double hs_s = 0, hs_t = 0;
      high_surface.params(hit, hs_s, hs_t);
      const Eigen::Vector3d truth = high_surface.normal(hs_s, hs_t);
      Eigen::Vector3d m;
      for (int c = 0; c < 3; ++c) m[c] = 2.0 * static_cast<double>(codes[3 * i + static_cast<size_t>(c)]) / max_code - 1.0;
      const double angle = std::acos(std::clamp(bp.decode(m).dot(truth), -1.0, 1.0)) * 180 / kPi;
      bool away = s.centre_inside;
      const int own = chart[static_cast<size_t>(s.face)];
      for (int dy = -2; dy <= 2 && away; ++dy)
        for (int dx = -2; dx <= 2 && away; ++dx) away = chart_at(x + dx, y + dy) == own;
      (away ? interior : seam).deg.push_back(angle);
      if (away) {
        mirrored_interior += bp.sign < 0;
        const Eigen::Vector3d mf(r.normal_ts.at(x, y, 0), r.normal_ts.at(x, y, 1), r.normal_ts.at(x, y, 2));
        interior_float.deg.push_back(std::acos(std::clamp(bp.decode(mf).dot(truth), -1.0, 1.0)) * 180 / kPi);
      }
    }
  std::printf("[ round trip ] away from seams: %zu texels (%zu mirrored), mean %.4f deg, p99 %.4f deg, max %.4f deg "
              "(float map: mean %.4f, p99 %.4f)\n",
              interior.deg.size(), mirrored_interior, interior.mean(), interior.quantile(0.99), interior.max(),
              interior_float.mean(), interior_float.quantile(0.99));
  std::printf("[ round trip ] seam band (border texels and within 2 texels of another chart or none): %zu texels, "
              "mean %.4f deg, p99 %.4f deg, max %.4f deg\n",
              seam.deg.size(), seam.mean(), seam.quantile(0.99), seam.max());
  ASSERT_GT(interior.deg.size(), static_cast<size_t>(n) * n / 2);
  EXPECT_GT(mirrored_interior, interior.deg.size() / 3) << "the mirrored half is measured too";
  EXPECT_LT(interior.mean(), 0.5);
  EXPECT_LT(interior.quantile(0.99), 2.0);
  EXPECT_GT(seam.deg.size(), 0u);
}

// A mesh of separate flat patches (each its own UV chart and its own vertices, so every
// patch's vertex normals are its plane's normal), far apart in space, each facing its own
// direction; sizes and shapes vary. UVs are the patches' local coordinates, to be packed.
// `grow` extends every patch by that much beyond its sides (a high mesh that covers the base
// patches' borders: rays from a patch's very edge then hit inside a face, not on its edge).
Mesh make_patches(int count, std::vector<Eigen::Vector3d>& normals, double grow = 0.0) {
  Mesh m;
  m.request_halfedge_texcoords2D();
  normals.clear();
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  for (int c = 0; c < count; ++c) {
    // Directions spread over the sphere (Fibonacci), so any two differ by many degrees.
    const double z = 1.0 - 2.0 * (c + 0.5) / count, rad = std::sqrt(1.0 - z * z), a = golden * c;
    const Eigen::Vector3d nz(rad * std::cos(a), rad * std::sin(a), z);
    const Eigen::Vector3d any = std::abs(nz.x()) < 0.9 ? Eigen::Vector3d(1, 0, 0) : Eigen::Vector3d(0, 1, 0);
    const Eigen::Vector3d ex = nz.cross(any).normalized(), ey = nz.cross(ex);
    const Eigen::Vector3d centre(10.0 * c, 0, 0);
    normals.push_back(nz);
    // A grid of cols x rows quads of varied extent; every third patch an L (a corner cut out),
    // every fifth one a thin strip.
    const int cols = 2 + c % 4, rows = 1 + (c * 7) % 3;
    const double w = c % 5 == 4 ? 1.6 : 0.4 + 0.13 * (c % 6), h = c % 5 == 4 ? 0.15 : 0.3 + 0.11 * ((c * 5) % 7);
    std::vector<VertexHandle> vs;
    std::vector<Vec2f> uvs;
    for (int j = 0; j <= rows; ++j)
      for (int i = 0; i <= cols; ++i) {
        const double lx = (w + 2 * grow) * i / cols - grow, ly = (h + 2 * grow) * j / rows - grow;
        const Eigen::Vector3d p = centre + lx * ex + ly * ey;
        vs.push_back(m.add_vertex(Vec3f(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()))));
        uvs.emplace_back(static_cast<float>(lx), static_cast<float>(ly));
      }
    for (int j = 0; j < rows; ++j)
      for (int i = 0; i < cols; ++i) {
        if (grow == 0 && c % 3 == 0 && rows > 1 && i == cols - 1 && j == rows - 1) continue;  // the L's missing corner (the grown high patch keeps it)
        const size_t q[4] = {static_cast<size_t>(j * (cols + 1) + i), static_cast<size_t>(j * (cols + 1) + i + 1),
                             static_cast<size_t>((j + 1) * (cols + 1) + i + 1), static_cast<size_t>((j + 1) * (cols + 1) + i)};
        for (const auto& tri : {std::array<size_t, 3>{q[0], q[1], q[2]}, std::array<size_t, 3>{q[0], q[2], q[3]}}) {
          const FaceHandle f = m.add_face(vs[tri[0]], vs[tri[1]], vs[tri[2]]);
          for (auto he : face_halfedges(m, f))
            for (size_t k = 0; k < 3; ++k)
              if (m.to_vertex_handle(he) == vs[tri[k]]) m.set_texcoord2D(he, uvs[tri[k]]);
        }
      }
  }
  compute_angle_weighted_normals(m);
  return m;
}

// Per texel of an n x n bake of make_patches: source, the chart whose value it holds (by its
// object-space normal: every chart faces its own way), and touched, the chart whose UVs touch it
// (rasterize_uv's faces, -1 for none); the two must agree where a chart touches.
void chart_texels(const Mesh& mesh, const BakeResult& r, const std::vector<Eigen::Vector3d>& normals, const std::vector<int>& face_chart, int n,
                  std::vector<int>& source, std::vector<int>& touched) {
  source.assign(static_cast<size_t>(n) * n, -1);
  for (size_t i = 0; i < source.size(); ++i) {
    const Eigen::Vector3d v(r.normal_os.pixels[3 * i], r.normal_os.pixels[3 * i + 1], r.normal_os.pixels[3 * i + 2]);
    for (size_t c = 0; c < normals.size(); ++c)
      if (v.dot(normals[c]) > 0.9999) source[i] = static_cast<int>(c);
    ASSERT_GE(source[i], 0) << "texel " << i << " holds no chart's normal";
  }
  const auto samples = rasterize_uv(mesh, n, n);
  touched.assign(samples.size(), -1);
  for (size_t i = 0; i < samples.size(); ++i)
    if (samples[i].face >= 0) {
      touched[i] = face_chart[static_cast<size_t>(samples[i].face)];
      ASSERT_EQ(source[i], touched[i]) << "texel " << i;
    }
}

// Padding across MIP levels. An atlas of 24 charts packed with padding P (pack_uv_charts),
// baked over the same patches (slightly grown) with the bake's own dilation over the whole map: each texel's object-
// space normal then names the chart its value came from (every chart faces its own way).
// The MIP chain is the box filter (each level the mean of 2 x 2 texels of the one below, as
// glGenerateMipmap on power-of-two sizes). A texel whose footprint (its 2^k x 2^k texels of
// level 0) contains a texel chart C touches must hold C's normal alone: C reads no other
// chart's values there. Dilation gives each empty texel of a gap of P to the nearer chart, so
// a footprint may reach 2^k - 1 texels past C's last texel only while 2^k - 1 <= P / 2:
// levels k <= floor(log2(P/2 + 1)) (P = 2, 4: levels 0-1; P = 8: 0-2; measured: the next level
// mixes, 186 of 3,339 read texels at P = 4). Level log2(P), as the issue asks, needs charts 2P
// apart (uvpack --mip-safe, the next test). Chart ids come from rasterising the UVs (rasterize_uv's
// faces, uv_charts).
TEST(BakeAccuracy, DilatedPaddingKeepsChartsApartDownToMipLevelLog2OfHalfPPlusOne) {
  std::vector<Eigen::Vector3d> normals;
  const Mesh patches = make_patches(24, normals);
  const Mesh high = make_patches(24, normals, 0.05);
  size_t charts = 0;
  const std::vector<int> face_chart = uv_charts(patches, &charts);
  ASSERT_EQ(charts, 24u);
  for (const int padding : {2, 4, 8}) {
    SCOPED_TRACE("padding " + std::to_string(padding));
    const int n = 256;
    Mesh mesh = patches;
    UvPackOptions po;
    po.size = n;
    po.padding = padding;
    pack_uv_charts(mesh, po);
    BakeOptions o;
    o.width = o.height = n;
    o.front = o.back = 0.05f;
    o.dilate = -1;  // the CLI's default: the whole map
    const BakeResult r = bake(mesh, high, o);
    ASSERT_EQ(r.misses, 0u);
    std::vector<int> source, touched;
    chart_texels(mesh, r, normals, face_chart, n, source, touched);
    if (HasFatalFailure()) return;
    // The box-filtered chain and the check, level by level.
    Image level = r.normal_os;
    int levels_checked = 0;
    for (int k = 0, block = 1; block - 1 <= padding / 2; ++k, block *= 2) {
      if (k > 0) {
        Image next(level.width / 2, level.height / 2, 3);
        for (int y = 0; y < next.height; ++y)
          for (int x = 0; x < next.width; ++x)
            for (int c = 0; c < 3; ++c)
              next.at(x, y, c) = 0.25f * (level.at(2 * x, 2 * y, c) + level.at(2 * x + 1, 2 * y, c) + level.at(2 * x, 2 * y + 1, c) +
                                          level.at(2 * x + 1, 2 * y + 1, c));
        level = std::move(next);
      }
      size_t read = 0, mixed = 0;
      for (int y = 0; y < level.height; ++y)
        for (int x = 0; x < level.width; ++x) {
          // The charts that read this texel, and the charts its footprint's values came from.
          std::vector<int> readers, sources;
          for (int yy = y * block; yy < (y + 1) * block; ++yy)
            for (int xx = x * block; xx < (x + 1) * block; ++xx) {
              const size_t i = static_cast<size_t>(yy) * n + static_cast<size_t>(xx);
              if (touched[i] >= 0) readers.push_back(touched[i]);
              sources.push_back(source[i]);
            }
          if (readers.empty()) continue;
          ++read;
          std::sort(readers.begin(), readers.end());
          readers.erase(std::unique(readers.begin(), readers.end()), readers.end());
          std::sort(sources.begin(), sources.end());
          sources.erase(std::unique(sources.begin(), sources.end()), sources.end());
          if (k == 0) {
            ASSERT_EQ(readers.size(), 1u) << "two charts touch one texel (the packer guarantees none)";
          }
          const Eigen::Vector3d& want = normals[static_cast<size_t>(readers[0])];
          const Eigen::Vector3d got(level.at(x, y, 0), level.at(x, y, 1), level.at(x, y, 2));
          // Mixed: the footprint's values come from another chart too (the labels, exact), or
          // the filtered value strays from the chart's normal (float noise of the patches'
          // normals is ~1e-4; one texel of another chart among 64 moves it by > 5e-3).
          if (readers.size() > 1 || sources.size() > 1 || (got - want).norm() > 2e-3) {
            if (mixed++ < 3)
              ADD_FAILURE() << "level " << k << " texel " << x << "," << y << " (level-0 texels " << x * block << ".." << (x + 1) * block - 1
                            << " x " << y * block << ".." << (y + 1) * block - 1 << ") is read by chart " << readers[0] << " but mixes "
                            << sources.size() << " charts' values";
          }
        }
      std::printf("[ mip padding ] P=%d level %d: %zu texels read by a chart, %zu mix another chart's values\n", padding, k, read,
                  mixed);
      EXPECT_EQ(mixed, 0u) << "level " << k;
      ++levels_checked;
    }
    EXPECT_EQ(levels_checked, static_cast<int>(std::floor(std::log2(padding / 2 + 1))) + 1);
  }
}

// uvpack --mip-safe K, end to end through the real bake: an atlas of 24 charts packed with
// mip_safe K, baked with the bake's dilation over the whole map, box-filtered as above. At every
// level k <= K, each texel a bilinear lookup inside chart C reads (the level-k texels within one
// of a level-k texel C touches) holds C's values alone. And uv_check's mip check, which predicts
// the dilation from the UVs alone, finds exactly the texels that mix in the real maps, at every
// level, for the mip-safe atlas (none) and for a plain padding-2 atlas (some from level 1 on).
TEST(BakeAccuracy, MipSafePackingKeepsBilinearReadsApartAndTheCheckerPredictsTheMixing) {
  std::vector<Eigen::Vector3d> normals;
  const Mesh patches = make_patches(24, normals);
  const Mesh high = make_patches(24, normals, 0.05);
  size_t charts = 0;
  const std::vector<int> face_chart = uv_charts(patches, &charts);
  const int n = 256, levels = 3;
  for (const int mip_safe : {3, -1}) {
    SCOPED_TRACE("mip_safe " + std::to_string(mip_safe));
    Mesh mesh = patches;
    UvPackOptions po;
    po.size = n;
    po.padding = 2;
    po.mip_safe = mip_safe;
    pack_uv_charts(mesh, po);
    BakeOptions o;
    o.width = o.height = n;
    o.front = o.back = 0.05f;
    o.dilate = -1;
    const BakeResult r = bake(mesh, high, o);
    ASSERT_EQ(r.misses, 0u);
    // Per level-0 texel: the chart whose value it holds and the chart touching it.
    std::vector<int> source, touched;
    chart_texels(mesh, r, normals, face_chart, n, source, touched);
    if (HasFatalFailure()) return;
    UvCheckOptions co;
    co.size = n;
    co.overlay = false;
    co.mip_safe = levels;
    const UvCheckReport check = check_uv_mapping(mesh, co);
    size_t mixed_total = 0;
    for (int k = 0, b = 1; k <= levels; ++k, b *= 2) {
      const int cn = n / b;
      // The charts whose values each level-k texel averages, and the charts touching it.
      std::vector<std::set<int>> holds(static_cast<size_t>(cn) * cn), readers(holds.size());
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
          const size_t i = static_cast<size_t>(y) * n + static_cast<size_t>(x), ci = static_cast<size_t>(y / b) * cn + static_cast<size_t>(x / b);
          holds[ci].insert(source[i]);
          if (touched[i] >= 0) readers[ci].insert(touched[i]);
        }
      std::set<std::tuple<size_t, int, int>> mixes;  // (level-k texel, reading chart, other chart)
      for (int cy = 0; cy < cn; ++cy)
        for (int cx = 0; cx < cn; ++cx)
          for (int reader : readers[static_cast<size_t>(cy) * cn + static_cast<size_t>(cx)])
            for (int ny = std::max(0, cy - 1); ny <= std::min(cn - 1, cy + 1); ++ny)
              for (int nx = std::max(0, cx - 1); nx <= std::min(cn - 1, cx + 1); ++nx) {
                const size_t ni = static_cast<size_t>(ny) * cn + static_cast<size_t>(nx);
                for (int other : holds[ni])
                  if (other != reader) mixes.insert({ni, reader, other});
              }
      size_t predicted = 0;
      for (const auto& v : check.mip_violations)
        if (v.level == k) predicted += v.texels;
      std::printf("[ mip-safe ] mip_safe %d, level %d: %zu (texel, chart, other chart) mixes in the baked maps, %zu predicted\n", mip_safe, k,
                  mixes.size(), predicted);
      EXPECT_EQ(predicted, mixes.size()) << "level " << k;
      if (mip_safe >= k) {
        EXPECT_TRUE(mixes.empty()) << "level " << k;
      }
      mixed_total += mixes.size();
    }
    if (mip_safe >= 0) {
      EXPECT_TRUE(check.mip_violations.empty());
      EXPECT_EQ(check.mip_safe_levels, levels);
    } else {
      EXPECT_GT(mixed_total, 0u) << "padding 2 alone is not mip-safe to level 3: the test would prove nothing";
      EXPECT_LT(check.mip_safe_levels, levels);
    }
  }
}

}  // namespace
}  // namespace meso
