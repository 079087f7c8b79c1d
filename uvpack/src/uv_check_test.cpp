#include "meso/uvpack/uv_check.hpp"

#include "test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <tuple>
#include <vector>

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
  // Which pairs, exactly: each moved triangle against the ones it lands on. Faces 0/2 are the
  // same triangle of the side, as are 1/3; the diagonals cross, so 0/3 and 1/2 overlap too.
  EXPECT_EQ(r.overlap_pairs, (std::vector<std::pair<int, int>>{{0, 2}, {0, 3}, {1, 2}, {1, 3}}));
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
  const UvCheckReport low = check_uv_mapping(m, o);
  EXPECT_EQ(low.shared_texel_faces, (std::vector<int>{0, 1, 2, 3}));
  EXPECT_TRUE(low.overlapping_faces.empty()) << "apart, exactly";
  o.size = 64;
  EXPECT_TRUE(check_uv_mapping(m, o).shared_texel_faces.empty());
  // Padding is measured in texels at the checked size: 0.3 texels at 16^2, 1.2 at 64^2.
  o.padding = 1.0;
  EXPECT_TRUE(check_uv_mapping(m, o).padding_violations.empty());
  o.padding = 2.0;
  const UvCheckReport padded = check_uv_mapping(m, o);
  ASSERT_EQ(padded.padding_violations.size(), 1u);
  EXPECT_EQ(padded.padding_violations[0].chart_a, 0);
  EXPECT_EQ(padded.padding_violations[0].chart_b, 1);
  EXPECT_NEAR(padded.padding_violations[0].distance, 1.2, 1e-5);
}

TEST(UvCheck, FarOutUvsAreReportedNotRasterised) {
  Mesh m = test::make_grid(2, 1);
  for (auto h : face_halfedges(m, FaceHandle(2))) m.set_texcoord2D(h, m.texcoord2D(h) * 1e9f);
  UvCheckOptions o;
  o.size = 16;
  const UvCheckReport r = check_uv_mapping(m, o);
  EXPECT_EQ(r.outside_faces, (std::vector<int>{2}));
  // Faces 0, 1 and 3 cover the left half and a quarter; face 2 is far away.
  const UvCheckReport without = check_uv_mapping(test::make_grid(2, 1), o);
  EXPECT_LT(r.texels_touched, without.texels_touched);
}

TEST(UvCheck, TouchingChartsAndNeighboursInAChartAreNotOverlaps) {
  // The grid's two cells stacked in UV space (the 3D edge between them becomes a seam), so
  // that they touch along v = 0.51, which runs through the middle of texel row 15 at 32^2.
  Mesh m = test::make_grid(2, 1);
  for (int f = 2; f <= 3; ++f)
    for (auto h : face_halfedges(m, FaceHandle(f))) {
      Vec2f uv = m.texcoord2D(h);
      uv[1] = 0.51f + uv[1] * 0.49f;  // right cell on the upper part
      m.set_texcoord2D(h, uv);
    }
  for (int f = 0; f <= 1; ++f)
    for (auto h : face_halfedges(m, FaceHandle(f))) {
      Vec2f uv = m.texcoord2D(h);
      uv[1] *= 0.51f;  // left cell on the lower part, under the right cell
      uv[0] += 0.5f;
      m.set_texcoord2D(h, uv);
    }
  size_t charts = 0;
  uv_charts(m, &charts);
  ASSERT_EQ(charts, 2u);
  UvCheckOptions o;
  o.size = 32;
  const UvCheckReport r = check_uv_mapping(m, o);
  EXPECT_TRUE(r.overlap_pairs.empty()) << "touching along an edge is not overlapping";
  EXPECT_FALSE(r.shared_texel_faces.empty()) << "but at 32^2 they share the texels along the edge";
  EXPECT_TRUE(r.flipped_faces.empty());
}

TEST(UvCheck, FoldedFacesAreFlippedWithinTheirChart) {
  // Drag the UV of the grid's centre vertex across its right-hand neighbours: the chart stays
  // connected, and exactly the triangles whose UV winding reversed are flipped.
  Mesh m = test::make_grid(2, 2);
  const VertexHandle centre(4);
  for (auto h : m.vih_range(centre))
    if (!m.is_boundary(h)) m.set_texcoord2D(h, Vec2f(1.3f, 0.5f));
  std::vector<int> reversed;
  for (auto f : m.faces())
    if (uv_double_area(m, f) < 0) reversed.push_back(f.idx());
  ASSERT_FALSE(reversed.empty());
  ASSERT_LT(reversed.size(), m.n_faces() / 2);
  UvCheckOptions o;
  o.size = 64;
  const UvCheckReport r = check_uv_mapping(m, o);
  EXPECT_EQ(r.charts, 1u);
  EXPECT_EQ(r.flipped_faces, reversed);
  EXPECT_FALSE(r.overlap_pairs.empty()) << "a fold overlaps its neighbours";
}

TEST(UvCheck, TexelDensityIsTexelsPerObjectUnit) {
  const Mesh m = test::make_grid(3, 1, 3.0f, 1.0f);  // 3 square units on the whole UV square
  UvCheckOptions o;
  o.size = 300;
  const UvCheckReport r = check_uv_mapping(m, o);
  ASSERT_EQ(r.texel_density.size(), 1u);
  EXPECT_NEAR(r.texel_density[0].texels_per_unit, std::sqrt(300.0 * 300.0 / 3.0), 1e-6);
  EXPECT_TRUE(r.flipped_faces.empty());
}

// The same sheet at 1e12 and 1e-12 units: the density scales as 1/units (it was 0 at 1e12,
// and absent at 1e-12, the surface area having underflowed in float).
TEST(UvCheck, TexelDensityAtAnyScale) {
  for (const float s : {1e12f, 1e-12f}) {
    const Mesh m = test::make_grid(3, 1, 3.0f * s, 1.0f * s);
    UvCheckOptions o;
    o.size = 300;
    const UvCheckReport r = check_uv_mapping(m, o);
    ASSERT_EQ(r.texel_density.size(), 1u) << s;
    EXPECT_NEAR(r.texel_density[0].texels_per_unit * s, std::sqrt(300.0 * 300.0 / 3.0), 1e-4) << s;
  }
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
  // A sliver of nonzero UV area whose height (1e-20 in v) double arithmetic cannot resolve in
  // pixels (1 - v = 1) touches no texel: it is reported degenerate, not silently ignored.
  const std::array<Vec2f, 3> sliver = {Vec2f(0.1f, 0.0f), Vec2f(0.3f, 0.0f), Vec2f(0.2f, 1e-20f)};
  const auto hs = face_halfedges(m, FaceHandle(0));
  for (size_t k = 0; k < 3; ++k) m.set_texcoord2D(hs[k], sliver[k]);
  ASSERT_NE(uv_double_area(m, FaceHandle(0)), 0.0);
  EXPECT_EQ(check_uv_mapping(m, o).degenerate_faces, (std::vector<int>{0, 1}));
}

// Axis-aligned UV quads, each its own chart: [x0, x1) x [y0, y1) in texels of a size^2 texture
// (rows from the top), so exactly those texels are touched.
Mesh texel_quads(const std::vector<std::array<int, 4>>& boxes, int size) {
  std::vector<std::array<float, 4>> uv;
  for (const auto& b : boxes)
    uv.push_back({static_cast<float>(b[0]) / size, 1.0f - static_cast<float>(b[3]) / size, static_cast<float>(b[1]) / size,
                  1.0f - static_cast<float>(b[2]) / size});
  return test::make_uv_quads(uv);
}

// Two 8 x 8-texel charts, 2 texels apart in x, at 64^2, worked by hand. Level 0: the gap's
// texels go to the nearer chart (16 to A, 17 to B), so bilinear reads (A: columns 7-16, B:
// 17-26) are clean. Level 1: the 2 x 2 texel at columns 16-17 holds both, and both charts
// read it (A's last level-1 column is 7, B's first 9) in level-1 rows 3-8 (the charts' rows
// 4-7 and one more either side): 6 texels each way, nothing else.
TEST(UvCheck, MipCheckOfTwoChartsTwoTexelsApart) {
  const Mesh m = texel_quads({{8, 16, 8, 16}, {18, 26, 8, 16}}, 64);
  UvCheckOptions o;
  o.size = 64;
  o.overlay = false;
  o.mip_safe = 2;
  const UvCheckReport r = check_uv_mapping(m, o);
  ASSERT_EQ(r.charts, 2u);
  EXPECT_EQ(r.texels_touched, 128u);
  EXPECT_NEAR(r.utilization, 128.0 / 4096, 1e-9);
  EXPECT_EQ(r.texel_coverage, 128.0 / 4096);
  EXPECT_EQ(r.mip_safe_levels, 0);
  std::vector<std::tuple<int, int, int, size_t>> got;
  for (const auto& v : r.mip_violations)
    if (v.level == 1) got.emplace_back(v.level, v.chart, v.reads, v.texels);
  EXPECT_EQ(got, (std::vector<std::tuple<int, int, int, size_t>>{{1, 0, 1, 6}, {1, 1, 0, 6}}));
  // 4 apart in x (B at 20-27): level 1 is clean too (16-17 go to A, 18-19 to B), level 2's
  // texel of columns 16-19 mixes.
  const UvCheckReport wider = check_uv_mapping(texel_quads({{8, 16, 8, 16}, {20, 28, 8, 16}}, 64), o);
  EXPECT_EQ(wider.mip_safe_levels, 1);
  for (const auto& v : wider.mip_violations) EXPECT_EQ(v.level, 2);
  // Touching charts fail at level 0 already.
  const UvCheckReport touching = check_uv_mapping(texel_quads({{8, 16, 8, 16}, {16, 24, 8, 16}}, 64), o);
  EXPECT_EQ(touching.mip_safe_levels, -1);
  ASSERT_FALSE(touching.mip_violations.empty());
  EXPECT_EQ(touching.mip_violations.front().level, 0);
}

// Two 8 x 8-texel charts at opposite sides of a 64^2 texture, 48 texels apart inside it and
// touching across its left/right border. Clamp-to-edge: nothing to report. Repeat (wrap):
// the padding is broken (distance 0), and at level 0 each chart's lookups at its border
// column read the other's border column in the charts' rows 8-15 and one more either side
// (rows 7-16: those texels are dilated from the nearer chart, in the plane as the bake does):
// 10 texels each way, nothing else.
TEST(UvCheck, WrapMeasuresPaddingAndMipReadsAcrossTheBorder) {
  const Mesh m = texel_quads({{0, 8, 8, 16}, {56, 64, 8, 16}}, 64);
  UvCheckOptions o;
  o.size = 64;
  o.padding = 4;
  o.overlay = false;
  o.mip_safe = 0;
  const UvCheckReport clamp = check_uv_mapping(m, o);
  ASSERT_EQ(clamp.charts, 2u);
  EXPECT_TRUE(clamp.padding_violations.empty());
  EXPECT_TRUE(clamp.mip_violations.empty());
  EXPECT_EQ(clamp.mip_safe_levels, 0);
  o.wrap = true;
  const UvCheckReport wrap = check_uv_mapping(m, o);
  ASSERT_EQ(wrap.padding_violations.size(), 1u);
  EXPECT_EQ(wrap.padding_violations[0].chart_a, 0);
  EXPECT_EQ(wrap.padding_violations[0].chart_b, 1);
  EXPECT_EQ(wrap.padding_violations[0].distance, 0.0);
  EXPECT_TRUE(wrap.overlap_pairs.empty());
  std::vector<std::tuple<int, int, int, size_t>> got;
  for (const auto& v : wrap.mip_violations) got.emplace_back(v.level, v.chart, v.reads, v.texels);
  EXPECT_EQ(got, (std::vector<std::tuple<int, int, int, size_t>>{{0, 0, 1, 10}, {0, 1, 0, 10}}));
  EXPECT_EQ(wrap.mip_safe_levels, -1);
  // 2 texels from each side: 4 apart across the border, as the padding asks; 3 apart is not.
  o.mip_safe = -1;
  EXPECT_TRUE(check_uv_mapping(texel_quads({{2, 10, 8, 16}, {54, 62, 8, 16}}, 64), o).padding_violations.empty());
  const UvCheckReport three = check_uv_mapping(texel_quads({{1, 9, 8, 16}, {54, 62, 8, 16}}, 64), o);
  ASSERT_EQ(three.padding_violations.size(), 1u);
  EXPECT_NEAR(three.padding_violations[0].distance, 3.0, 1e-4);
  // One chart across the whole width meets itself across the border: the pair (0, 0).
  const UvCheckReport wide = check_uv_mapping(texel_quads({{0, 64, 8, 16}}, 64), o);
  ASSERT_EQ(wide.padding_violations.size(), 1u);
  EXPECT_EQ(wide.padding_violations[0].chart_a, 0);
  EXPECT_EQ(wide.padding_violations[0].chart_b, 0);
}

// A small chart inside one texel of another: both charts touch that texel, both read around
// it, and the texel holds both (which one the bake writes depends on the face order). The
// verdict and the violations must not depend on which chart comes first in the file (they
// did: only the first chart touching a texel was a reader).
TEST(UvCheck, MipCheckDoesNotDependOnTheFaceOrder) {
  const float t = 1.0f / 64;
  const std::array<float, 4> big = {8 * t, 1 - 16 * t, 16 * t, 1 - 8 * t};
  const std::array<float, 4> small = {10.25f * t, 1 - 10.75f * t, 10.75f * t, 1 - 10.25f * t};
  UvCheckOptions o;
  o.size = 64;
  o.overlay = false;
  o.mip_safe = 1;
  std::vector<std::vector<std::tuple<int, int, int, size_t>>> found;
  for (const auto& boxes : {std::vector<std::array<float, 4>>{big, small}, std::vector<std::array<float, 4>>{small, big}}) {
    const UvCheckReport r = check_uv_mapping(test::make_uv_quads(boxes), o);
    ASSERT_EQ(r.charts, 2u);
    EXPECT_EQ(r.texels_shared, 1u);
    EXPECT_EQ(r.mip_safe_levels, -1);
    // In chart terms (the big chart first), so both orders compare.
    const bool big_first = boxes.front() == big;
    std::vector<std::tuple<int, int, int, size_t>> v;
    for (const auto& m : r.mip_violations) {
      const int chart = big_first ? m.chart : 1 - m.chart, reads = big_first ? m.reads : 1 - m.reads;
      v.emplace_back(m.level, chart, reads, m.texels);
    }
    std::sort(v.begin(), v.end());
    found.push_back(v);
  }
  EXPECT_EQ(found[0], found[1]);
  // Level 0: the small chart reads the 3 x 3 texels around its own, all the big chart's; the
  // big chart reads the shared texel.
  std::vector<std::tuple<int, int, int, size_t>> level0;
  for (const auto& v : found[0])
    if (std::get<0>(v) == 0) level0.push_back(v);
  EXPECT_EQ(level0, (std::vector<std::tuple<int, int, int, size_t>>{{0, 0, 1, 1}, {0, 1, 0, 9}}));
}

}  // namespace
}  // namespace meso
