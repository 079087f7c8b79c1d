#include "meso/uvpack/uv_check.hpp"

#include "test_support.hpp"

#include <gtest/gtest.h>

namespace meso {
namespace {

TEST(UvCheck, SeparateChartsDoNotOverlap) {
  const Mesh cube = test::make_seamed_cube();
  UvCheckOptions o;
  o.size = 64;
  const UvCheckReport r = check_uv_mapping(cube, o);
  EXPECT_EQ(r.charts, 6u);
  EXPECT_TRUE(r.overlapping_faces.empty());
  EXPECT_TRUE(r.degenerate_faces.empty());
  EXPECT_TRUE(r.outside_faces.empty());
  EXPECT_EQ(r.texels_shared, 0u);
  EXPECT_GT(r.utilization, 0.3);
  EXPECT_LT(r.utilization, 1.0);
}

TEST(UvCheck, FindsExactlyTheOverlappingCharts) {
  Mesh cube = test::make_seamed_cube();
  // Move side 1 (faces 2 and 3) onto side 0 (faces 0 and 1): those four overlap, nothing else.
  for (int f = 2; f <= 3; ++f) {
    for (auto h : face_halfedges(cube, FaceHandle(f))) {
      Vec2f uv = cube.texcoord2D(h);
      uv[0] -= 1.0f / 3.0f;
      cube.set_texcoord2D(h, uv);
    }
  }
  UvCheckOptions o;
  o.size = 64;
  const UvCheckReport r = check_uv_mapping(cube, o);
  EXPECT_EQ(r.overlapping_faces, (std::vector<int>{0, 1, 2, 3}));
  EXPECT_GT(r.texels_shared, 0u);
  // The overlay marks shared texels opaque red.
  size_t red = 0;
  for (size_t i = 0; i < r.overlay.texel_count(); ++i) red += r.overlay.pixels[4 * i] == 1.0f && r.overlay.pixels[4 * i + 3] == 1.0f;
  EXPECT_EQ(red, r.texels_shared);
}

TEST(UvCheck, ChartsSharingATexelOverlapAtThatResolutionOnly) {
  // Two charts 0.3 texels apart inside one texel at 16^2 (left ends at u = 7.3/16, right
  // starts at 7.6/16): conservative rasterisation reports them, since bilinear filtering
  // would mix them; at 64^2 the gap spans whole texels and they are apart.
  Mesh m = test::make_grid(2, 1);
  auto remap = [&](int f, float lo, float hi) {
    for (auto h : face_halfedges(m, FaceHandle(f))) {
      Vec2f uv = m.texcoord2D(h);
      const float local = uv[0] < 0.25f ? 0.0f : uv[0] < 0.75f ? (f < 2 ? 1.0f : 0.0f) : 1.0f;
      uv[0] = lo + (hi - lo) * local;
      m.set_texcoord2D(h, uv);
    }
  };
  remap(0, 0.0f, 7.3f / 16.0f);
  remap(1, 0.0f, 7.3f / 16.0f);
  remap(2, 7.6f / 16.0f, 1.0f);
  remap(3, 7.6f / 16.0f, 1.0f);
  size_t charts = 0;
  uv_charts(m, &charts);
  ASSERT_EQ(charts, 2u);
  UvCheckOptions o;
  o.size = 16;
  EXPECT_EQ(check_uv_mapping(m, o).overlapping_faces, (std::vector<int>{0, 1, 2, 3}));
  o.size = 64;
  EXPECT_TRUE(check_uv_mapping(m, o).overlapping_faces.empty());
}

TEST(UvCheck, FarOutUvsAreReportedNotRasterised) {
  Mesh m = test::make_grid(2, 1);
  for (auto h : face_halfedges(m, FaceHandle(2))) m.set_texcoord2D(h, m.texcoord2D(h) * 1e9f);
  UvCheckOptions o;
  o.size = 16;
  const UvCheckReport r = check_uv_mapping(m, o);
  EXPECT_EQ(r.outside_faces, (std::vector<int>{2}));
}

TEST(UvCheck, ReportsDegenerateAndOutsideFaces) {
  Mesh m = test::make_grid(2, 1);
  for (auto h : face_halfedges(m, FaceHandle(1))) m.set_texcoord2D(h, Vec2f(0.2f, 0.2f));
  for (auto h : face_halfedges(m, FaceHandle(3))) {
    Vec2f uv = m.texcoord2D(h);
    m.set_texcoord2D(h, uv + Vec2f(0.5f, 0.0f));
  }
  UvCheckOptions o;
  o.size = 32;
  const UvCheckReport r = check_uv_mapping(m, o);
  EXPECT_EQ(r.degenerate_faces, (std::vector<int>{1}));
  EXPECT_EQ(r.outside_faces, (std::vector<int>{3}));
}

}  // namespace
}  // namespace meso
