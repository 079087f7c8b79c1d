#include "meso/uvpack/uv_unwrap.hpp"

#include "meso/uvpack/uv_check.hpp"
#include "meso/uvpack/uv_pack.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>

namespace meso {
namespace {

// The packed result of an unwrap is a unique mapping with the padding, as the checker sees
// it: no overlap, no shared texel, no flip, nothing outside, no chart too close.
void expect_unique_after_pack(Mesh& m, int size, int padding, size_t charts) {
  UvPackOptions o;
  o.size = size;
  o.padding = padding;
  const UvPackReport p = pack_uv_charts(m, o);
  EXPECT_EQ(p.charts, charts);
  UvCheckOptions check;
  check.size = size;
  check.padding = padding;
  check.overlay = false;
  const UvCheckReport c = check_uv_mapping(m, check);
  EXPECT_EQ(c.charts, charts);
  EXPECT_TRUE(c.overlapping_faces.empty()) << c.overlapping_faces.size();
  EXPECT_TRUE(c.shared_texel_faces.empty()) << c.shared_texel_faces.size();
  EXPECT_TRUE(c.flipped_faces.empty()) << c.flipped_faces.size();
  EXPECT_TRUE(c.outside_faces.empty()) << c.outside_faces.size();
  EXPECT_TRUE(c.padding_violations.empty()) << c.padding_violations.size();
}

Mesh without_uvs(Mesh m) {
  m.release_halfedge_texcoords2D();
  return m;
}

// Six planar sides, each a chart: LSCM maps a planar chart isometrically (up to the
// similarity the chart scaling removes), so every distortion figure is 1.
TEST(UvUnwrap, CubeGivesSixIsometricCharts) {
  for (const UnwrapMethod method : {UnwrapMethod::lscm, UnwrapMethod::arap}) {
    Mesh m = without_uvs(test::make_seamed_cube());
    UvUnwrapOptions o;
    o.method = method;
    const UvUnwrapReport r = unwrap_uv_charts(m, o);
    ASSERT_TRUE(has_uvs(m));
    EXPECT_EQ(r.charts, 6u);
    EXPECT_EQ(r.grown_charts, 6u);
    EXPECT_EQ(r.topology_splits + r.stretch_splits + r.overlap_splits + r.failure_splits, 0u);
    ASSERT_EQ(r.per_chart.size(), 6u);
    for (const auto& c : r.per_chart) {
      EXPECT_EQ(c.faces, 2);
      EXPECT_NEAR(c.area, 1.0, 1e-9);
      EXPECT_NEAR(c.stretch_l2, 1.0, 1e-6);
      EXPECT_NEAR(c.stretch_linf, 1.0, 1e-6);
    }
    EXPECT_NEAR(r.stretch_l2, 1.0, 1e-6);
    EXPECT_NEAR(r.angle_distortion_max, 1.0, 1e-6);
    EXPECT_NEAR(r.area_distortion_mean, 1.0, 1e-6);
    size_t charts = 0;
    uv_charts(m, &charts);
    EXPECT_EQ(charts, 6u);
    // One texel density: every side covers the same UV area.
    std::vector<double> side_area(6, 0);
    const auto chart = uv_charts(m);
    for (auto f : m.faces()) side_area[static_cast<size_t>(chart[static_cast<size_t>(f.idx())])] += uv_double_area(m, f);
    for (double a : side_area) EXPECT_NEAR(a, side_area[0], 1e-5 * side_area[0]);
    expect_unique_after_pack(m, 128, 2, 6);
  }
}

// A closed cylinder band (an annulus around the axis, not a disk) is cut into strips that
// unroll with no distortion; a sphere (poles included, degenerate triangles there) keeps
// every chart under the stretch bound; a torus (genus 1) needs cuts.
TEST(UvUnwrap, CurvedSurfacesStayUnderTheStretchBound) {
  const double pi = std::acos(-1.0);
  struct Case {
    const char* name;
    Mesh mesh;
  };
  std::vector<Case> cases;
  cases.push_back({"cylinder", test::make_parametric(48, 12, [&](double s, double t) {
                     return Vec3f(float(std::cos(2 * pi * s)), float(std::sin(2 * pi * s)), float(2 * t));
                   }, true, false)});
  cases.push_back({"sphere", test::make_parametric(48, 24, [&](double s, double t) {
                     const double th = pi * t, ph = 2 * pi * s;
                     return Vec3f(float(std::sin(th) * std::cos(ph)), float(std::sin(th) * std::sin(ph)), float(-std::cos(th)));
                   }, true, false)});
  cases.push_back({"torus", test::make_parametric(48, 16, [&](double s, double t) {
                     const double a = 2 * pi * s, b = 2 * pi * t, r = 1 + 0.4 * std::cos(b);
                     return Vec3f(float(r * std::cos(a)), float(r * std::sin(a)), float(0.4 * std::sin(b)));
                   }, true, true)});
  for (auto& [name, mesh] : cases) {
    Mesh m = without_uvs(mesh);
    UvUnwrapOptions o;
    const UvUnwrapReport r = unwrap_uv_charts(m, o);
    SCOPED_TRACE(name);
    EXPECT_LE(r.max_chart_stretch_l2, o.max_stretch);
    EXPECT_GE(r.stretch_l2, 1.0);
    EXPECT_LT(r.charts - r.degenerate_faces, 40u);  // the poles' zero-area triangles are charts alone
    if (std::string(name) == "cylinder") {
      EXPECT_NEAR(r.stretch_l2, 1.0, 1e-3);  // developable: only the polygonal facets bend
      EXPECT_LE(r.charts, 4u);
    }
    size_t charts = 0;
    uv_charts(m, &charts);
    EXPECT_EQ(charts, r.charts);
    expect_unique_after_pack(m, 512, 2, r.charts);
  }
}

// The flattening does not depend on the units: a bumpy sheet in millimetres far from the
// origin (x 10^4, offset 5 x 10^4) unwraps as in metres (ARAP lost 4 % utilisation and
// stretched 1.3x at 10^4, LSCM did not); areas are reported in the mesh's own units.
TEST(UvUnwrap, UnitsDoNotMatter) {
  auto sheet = [](double scale, double offset) {
    return test::make_parametric(16, 16, [=](double s, double t) {
      const double z = 0.05 * std::sin(7 * s) * std::cos(5 * t);
      return Vec3f(float(offset + scale * s), float(offset + scale * t), float(scale * z));
    }, false, false);
  };
  for (const UnwrapMethod method : {UnwrapMethod::lscm, UnwrapMethod::arap}) {
    UvUnwrapOptions o;
    o.method = method;
    Mesh m1 = without_uvs(sheet(1, 0)), mm = without_uvs(sheet(1e4, 5e4));
    const UvUnwrapReport r1 = unwrap_uv_charts(m1, o), rm = unwrap_uv_charts(mm, o);
    ASSERT_EQ(r1.charts, rm.charts);
    EXPECT_NEAR(rm.stretch_l2, r1.stretch_l2, 1e-3 * r1.stretch_l2);
    EXPECT_NEAR(rm.stretch_linf, r1.stretch_linf, 1e-3 * r1.stretch_linf);
    EXPECT_NEAR(rm.per_chart[0].area, 1e8 * r1.per_chart[0].area, 1e-3 * 1e8 * r1.per_chart[0].area);
  }
}

// A tight bound forces splits and is met; the result does not depend on the thread count.
TEST(UvUnwrap, TightBoundSplitsAndResultIsThreadIndependent) {
  const double pi = std::acos(-1.0);
  const Mesh sphere = without_uvs(test::make_parametric(32, 16, [&](double s, double t) {
    const double th = pi * t, ph = 2 * pi * s;
    return Vec3f(float(std::sin(th) * std::cos(ph)), float(std::sin(th) * std::sin(ph)), float(-std::cos(th)));
  }, true, false));
  UvUnwrapOptions o;
  o.max_stretch = 1.01;
  Mesh a = sphere, b = sphere;
  UvUnwrapReport ra, rb;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    ra = unwrap_uv_charts(a, o);
  }
  rb = unwrap_uv_charts(b, o);
  EXPECT_GT(ra.stretch_splits, 0u);
  EXPECT_LE(ra.max_chart_stretch_l2, 1.01);
  EXPECT_EQ(ra.charts, rb.charts);
  bool same = true;
  for (auto h : a.halfedges())
    if (!a.is_boundary(h) && a.texcoord2D(h) != b.texcoord2D(h)) same = false;
  EXPECT_TRUE(same);
}

}  // namespace
}  // namespace meso
