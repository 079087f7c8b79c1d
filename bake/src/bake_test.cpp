#include "meso/bake/bake.hpp"

#include "meso/bake/dilate.hpp"
#include "meso/bake/uv_raster.hpp"
#include "meso/core/uv_texels.hpp"
#include "meso/examples/brick_wall.hpp"
#include "test_support.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>

namespace meso {
namespace {

using test::make_layers;
using test::make_plane;

struct PlaneCase {
  float a, b, c;
};

class BakePlane : public ::testing::TestWithParam<PlaneCase> {};

// A flat unit base quad (UV = xy) over a plane: the displacement at the texel centre (u, v)
// is exactly a u + b v + c and the tangent-space normal is normalize(-a, -b, 1).
TEST_P(BakePlane, ReproducesTheAnalyticAnswer) {
  const auto [a, b, c] = GetParam();
  const Mesh low = test::make_grid(3, 2);
  const Mesh high = make_plane(a, b, c);
  BakeOptions o;
  o.width = 32;
  o.height = 16;
  o.front = o.back = 0.5f;  // the default reach (5 % of the diagonal) is shorter than the tilt
  const BakeResult r = bake(low, high, o);
  EXPECT_EQ(r.covered_texels, 32u * 16u);
  EXPECT_EQ(r.misses, 0u);
  // One ray each way at least (either a multi-hit collect or an intersect); here at most one
  // more (the occluded() check behind the hit where Embree lacks filter functions).
  EXPECT_GE(r.rays, 2u * r.covered_texels);
  EXPECT_LE(r.rays, 3u * r.covered_texels);
  const Vec3f n = Vec3f(-a, -b, 1.0f).normalized();
  for (int y = 0; y < o.height; ++y) {
    for (int x = 0; x < o.width; ++x) {
      const float u = texel_center_u(x, o.width), v = texel_center_v(y, o.height);
      ASSERT_NEAR(r.displacement.at(x, y), a * u + b * v + c, 2e-6f) << x << "," << y;
      for (int k = 0; k < 3; ++k) ASSERT_NEAR(r.normal_ts.at(x, y, k), n[k], 1e-5f) << x << "," << y;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Planes, BakePlane,
                         ::testing::Values(PlaneCase{0, 0, 0.05f}, PlaneCase{0, 0, -0.05f}, PlaneCase{0.1f, -0.05f, 0.01f},
                                           PlaneCase{-0.2f, 0.1f, -0.02f}, PlaneCase{0, 0, 0}));

// Far from the origin float coordinates are coarse (2^-7 at 65536). Here every vertex is
// exactly representable there (multiples of 1/4, heights multiples of 2^-7) but texel centres
// (multiples of 1/48) are not: a bake that casts from absolute float coordinates is off by
// up to a * 2^-8; one that works relative to the base keeps float precision of small numbers.
TEST(Bake, HugeCoordinatesKeepSmallDisplacementsExact) {
  const float a = 0.125f, b = -0.0625f, c = 0.0625f;
  const Vec3f offset(65536.0f, -65536.0f, 65536.0f);
  Mesh low = test::make_grid(4, 2);
  Mesh high = make_plane(a, b, c);
  for (auto v : low.vertices()) low.set_point(v, low.point(v) + offset);
  for (auto v : high.vertices()) high.set_point(v, high.point(v) + offset);
  BakeOptions o;
  o.width = o.height = 24;
  o.front = o.back = 0.5f;
  const BakeResult r = bake(low, high, o);
  EXPECT_EQ(r.misses, 0u);
  for (int y = 0; y < o.height; ++y)
    for (int x = 0; x < o.width; ++x) {
      const float u = texel_center_u(x, o.width), v = texel_center_v(y, o.height);
      ASSERT_NEAR(r.displacement.at(x, y), a * u + b * v + c, 2e-6f) << x << "," << y;
    }
}

// A mesh of any size a float holds bakes as at unit size (scaled into the unit box by a power
// of two, results scaled back): near 1e15 units every texel missed, near 1e-19 too.
TEST(Bake, AnyScaleAFloatHolds) {
  const float a = 0.125f, b = -0.0625f, c = 0.0625f;
  float unit_max = 0;
  for (const int e : {0, 60, 100, -70, -110}) {  // 0 first: the unit-size reference
    const float s = std::ldexp(1.0f, e);
    Mesh low = test::make_grid(4, 2), high = make_plane(a, b, c);
    for (Mesh* m : {&low, &high})
      for (auto v : m->vertices()) m->set_point(v, m->point(v) * s);
    BakeOptions o;
    o.width = o.height = 24;
    o.front = o.back = 0.5f * s;
    const BakeResult r = bake(low, high, o);
    EXPECT_EQ(r.misses, 0u) << e;
    EXPECT_EQ(r.front, o.front) << e;
    for (int y = 0; y < o.height; ++y)
      for (int x = 0; x < o.width; ++x) {
        const float u = texel_center_u(x, o.width), v = texel_center_v(y, o.height);
        ASSERT_NEAR(r.displacement.at(x, y) / s, a * u + b * v + c, 2e-6f) << e << ": " << x << "," << y;
      }
    if (e == 0) unit_max = r.max_displacement;
    EXPECT_NEAR(r.max_displacement / s, unit_max, 1e-6f) << e;
  }
}

// The value every covered texel of a flat base (z = 0, normal +z) gets over `high`.
// `result`: the whole bake, for its report.
float baked_value(const Mesh& high, const BakeOptions& base_options, size_t* ambiguous = nullptr, BakeResult* result = nullptr) {
  BakeOptions o = base_options;
  o.width = o.height = 8;
  o.front = o.back = 0.05f;
  if (o.bunch <= 0) o.bunch = 0.001f;
  BakeResult local;
  BakeResult& r = result ? *result : local;
  r = bake(test::make_grid(2, 2), high, o);
  EXPECT_EQ(r.misses, 0u);
  if (ambiguous) *ambiguous = r.ambiguous;
  const float v = r.displacement.at(4, 4);
  for (float d : r.displacement.pixels) EXPECT_EQ(d, v);
  return v;
}

// Layers above and below the base at known heights: each rule picks the one it names.
TEST(Bake, HitRulesPickTheLayerTheyName) {
  // Front-facing layers at +0.02 and -0.01, a back-facing one at +0.005.
  const Mesh high = make_layers({{0.02f, true}, {-0.01f, true}, {0.005f, false}});
  BakeOptions o;
  o.hit = HitRule::nearest;
  EXPECT_NEAR(baked_value(high, o), 0.005f, 1e-6f);
  o.hit = HitRule::furthest;
  EXPECT_NEAR(baked_value(high, o), 0.02f, 1e-6f);
  o.hit = HitRule::front_else_nearest;
  EXPECT_NEAR(baked_value(high, o), -0.01f, 1e-6f);
  o.hit = HitRule::front_only;
  EXPECT_NEAR(baked_value(high, o), -0.01f, 1e-6f);
  o.hit = HitRule::nearest;
  o.ignore_backfaces = true;
  EXPECT_NEAR(baked_value(high, o), -0.01f, 1e-6f);
  // Only back faces: front-only misses everywhere.
  BakeOptions only;
  only.hit = HitRule::front_only;
  only.width = only.height = 8;
  const BakeResult r = bake(test::make_grid(2, 2), make_layers({{0.01f, false}}), only);
  EXPECT_EQ(r.hits, 0u);
  EXPECT_EQ(r.misses, r.covered_texels);
}

// A decal floating just above the surface (closer than the bunch distance): the outermost
// of the bunch wins; two candidates as near as each other on both sides are reported.
TEST(Bake, BunchesTakeTheirOutermostHitAndTiesAreAmbiguous) {
  BakeOptions o;
  size_t ambiguous = 0;
  EXPECT_NEAR(baked_value(make_layers({{0.010f, true}, {0.0105f, true}, {-0.03f, true}}), o, &ambiguous), 0.0105f, 1e-6f);
  EXPECT_EQ(ambiguous, 0u);
  BakeResult r;
  EXPECT_NEAR(baked_value(make_layers({{0.010f, true}, {-0.0102f, true}}), o, &ambiguous, &r), 0.010f, 1e-6f);
  EXPECT_EQ(ambiguous, 64u) << "0.0100 out and 0.0102 in are within the bunch distance of each other";
  // The report: every ambiguous texel is marked 0.75 in the coverage map (and is a hit), and
  // the per-face counts add up to the total, face by face no more than the face's texels.
  for (float c : r.coverage.pixels) EXPECT_EQ(c, 0.75f);
  EXPECT_EQ(r.hits, 64u);
  ASSERT_EQ(r.face_ambiguous.size(), 8u);
  size_t per_face = 0;
  for (size_t f = 0; f < r.face_ambiguous.size(); ++f) {
    EXPECT_EQ(r.face_ambiguous[f], r.face_texels[f]) << f;
    per_face += r.face_ambiguous[f];
  }
  EXPECT_EQ(per_face, r.ambiguous);
  EXPECT_NEAR(baked_value(make_layers({{0.010f, true}, {-0.015f, true}}), o, &ambiguous), 0.010f, 1e-6f);
  EXPECT_EQ(ambiguous, 0u);
  // An exact tie goes outward, with either nearest rule and the furthest one (the inward hit
  // had won: the tie-break was an epsilon lost in the score's rounding).
  for (const HitRule rule : {HitRule::nearest, HitRule::front_else_nearest, HitRule::furthest}) {
    BakeOptions tie = o;
    tie.hit = rule;
    EXPECT_NEAR(baked_value(make_layers({{0.01f, true}, {-0.01f, true}}), tie), 0.01f, 1e-6f) << hit_rule_name(rule);
  }
  // A bunch is a chain of hits each within `bunch` of the previous one: 0.02, 0.026 and 0.032
  // are one bunch at 0.01, and its outermost hit is the value with every rule (the nearest
  // rules had stopped tracing 0.01 past the first hit and answered 0.026).
  BakeOptions chain = o;
  chain.bunch = 0.01f;
  for (const HitRule rule : {HitRule::nearest, HitRule::front_else_nearest, HitRule::front_only, HitRule::furthest}) {
    chain.hit = rule;
    EXPECT_NEAR(baked_value(make_layers({{0.02f, true}, {0.026f, true}, {0.032f, true}}), chain), 0.032f, 1e-6f) << hit_rule_name(rule);
  }
}

// Object-space normals are the high surface's: a tilted plane's normal everywhere.
TEST(Bake, ObjectSpaceNormalsAreTheHighSurfaces) {
  BakeOptions o;
  o.width = o.height = 16;
  const BakeResult r = bake(test::make_grid(2, 2), make_plane(0.3f, -0.2f, 0.01f), o);
  const Vec3f n = Vec3f(-0.3f, 0.2f, 1.0f).normalized();
  for (size_t i = 0; i < r.normal_os.texel_count(); ++i)
    for (int c = 0; c < 3; ++c) ASSERT_NEAR(r.normal_os.pixels[3 * i + static_cast<size_t>(c)], n[c], 1e-5f) << i;
}

// Supersampling: a step in the high surface a quarter of the way into a texel. With 4 x 4
// samples the texel gets the area-weighted mean (1/4 low, 3/4 high, exactly, since the
// samples sit at the sub-texel centres); with 1 sample its centre's side.
TEST(Bake, SupersamplingAveragesOverTheTexel) {
  const float step = 3.0f / 8.0f + 1.0f / 32.0f, rise = 0.01f;
  Mesh high;
  auto add_rect = [&](float x0, float x1, float z) {
    const VertexHandle a = high.add_vertex(Vec3f(x0, -0.5f, z)), b = high.add_vertex(Vec3f(x1, -0.5f, z));
    const VertexHandle c = high.add_vertex(Vec3f(x1, 1.5f, z)), d = high.add_vertex(Vec3f(x0, 1.5f, z));
    high.add_face(a, b, c);
    high.add_face(a, c, d);
  };
  add_rect(-0.5f, step, 0.0f);
  add_rect(step, 1.5f, rise);
  compute_angle_weighted_normals(high);
  BakeOptions o;
  o.width = o.height = 8;
  o.front = o.back = 0.05f;
  o.samples = 16;
  const BakeResult r = bake(test::make_grid(2, 2), high, o);
  EXPECT_EQ(r.samples, 16);
  for (int y = 0; y < 8; ++y) {
    EXPECT_NEAR(r.displacement.at(2, y), 0.0f, 1e-6f);
    EXPECT_NEAR(r.displacement.at(3, y), 0.75f * rise, 1e-6f);
    EXPECT_NEAR(r.displacement.at(4, y), rise, 1e-6f);
  }
  o.samples = 1;
  const BakeResult single = bake(test::make_grid(2, 2), high, o);
  EXPECT_NEAR(single.displacement.at(3, 0), rise, 1e-6f) << "the centre 0.4375 lies right of the step";
}

// A cage leaning (0.02, 0, 0.05) away from a flat base: rays go toward it and stop at it,
// so a layer beyond the cage is not found outward; the values stay heights along the base
// normal (they had been distances along the leaning ray, slant times too large).
TEST(Bake, CageSetsTheRaysDirectionAndOutwardReach) {
  const Mesh base = test::make_grid(2, 2);
  Mesh cage = base;
  for (auto v : cage.vertices()) cage.set_point(v, cage.point(v) + Vec3f(0.02f, 0.0f, 0.05f));
  ASSERT_TRUE(same_topology(base, cage));
  const double slant = std::sqrt(0.02 * 0.02 + 0.05 * 0.05) / 0.05;  // ray length per unit height
  BakeOptions o;
  o.width = o.height = 8;
  o.front = o.back = 0.2f;
  o.cage = &cage;
  const BakeResult near = bake(base, make_layers({{0.01f, true}}), o);
  EXPECT_EQ(near.misses, 0u);
  EXPECT_NEAR(near.displacement.at(4, 4), 0.01, 1e-6) << "along the ray it is " << 0.01 * slant;
  const BakeResult beyond = bake(base, make_layers({{0.06f, true}, {-0.03f, true}}), o);
  EXPECT_NEAR(beyond.displacement.at(4, 4), -0.03, 1e-6) << "the layer beyond the cage is out of reach";
  o.cage = nullptr;
  EXPECT_NEAR(bake(base, make_layers({{0.06f, true}, {-0.03f, true}}), o).displacement.at(4, 4), -0.03f, 1e-5f) << "nearest without cage";
  Mesh other = test::make_grid(3, 2);
  EXPECT_FALSE(same_topology(base, other));
}

// Parts paired by name: each base part only sees its own high part, even where another
// part's surface is nearer; unmatched base parts see everything and are reported.
TEST(Bake, MatchByNamePairsParts) {
  Mesh base = test::make_grid(4, 4);
  std::vector<int> low_group;
  for (auto f : base.faces()) {
    Vec3f c(0, 0, 0);
    for (auto v : base.fv_range(f)) c += base.point(v) / 3.0f;
    low_group.push_back(c[0] < 0.5f ? 0 : 1);
  }
  set_face_groups(base, {"Box_low", "Plate_LP.001"}, low_group);
  Mesh high = make_layers({{0.01f, true}, {-0.02f, true}});
  std::vector<int> high_group;
  for (auto f : high.faces()) high_group.push_back(high.point(*high.fv_range(f).begin())[2] > 0 ? 0 : 1);
  set_face_groups(high, {"box_high", "plate_high"}, high_group);
  BakeOptions o;
  o.width = o.height = 8;
  o.front = o.back = 0.05f;
  o.match_by_name = true;
  const BakeResult r = bake(base, high, o);
  EXPECT_EQ(r.matched_parts.size(), 2u);
  EXPECT_TRUE(r.unmatched_parts.empty());
  EXPECT_NEAR(r.displacement.at(1, 4), 0.01f, 1e-6f) << "box texel";
  EXPECT_NEAR(r.displacement.at(6, 4), -0.02f, 1e-6f) << "plate texel: the nearer box surface is not its part";
  o.match_by_name = false;
  EXPECT_NEAR(bake(base, high, o).displacement.at(6, 4), 0.01f, 1e-6f) << "unpaired, the nearest wins";
  set_face_groups(high, {"box_high", "other_high"}, high_group);
  o.match_by_name = true;
  const BakeResult partial = bake(base, high, o);
  ASSERT_EQ(partial.unmatched_parts.size(), 1u);
  EXPECT_EQ(partial.unmatched_parts[0], "Plate_LP.001");
  EXPECT_NEAR(partial.displacement.at(6, 4), 0.01f, 1e-6f) << "an unmatched part sees the whole high mesh";
}

// A coarse sphere base over the true sphere: the flat triangles sit well inside it, the PN
// patches (built from the radial normals) follow it far more closely.
TEST(Bake, PnBasisFollowsTheCurvedSurface) {
  const Mesh base = test::make_sphere_band(12, 4), high = test::make_sphere_band(256, 96);
  BakeOptions o;
  o.width = o.height = 64;
  o.dilate = 0;
  auto worst = [&](BakeBasis basis) {
    o.basis = basis;
    const BakeResult r = bake(base, high, o);
    float m = 0;
    for (size_t i = 0; i < r.coverage.texel_count(); ++i)
      if (r.coverage.pixels[i] == 1.0f) m = std::max(m, std::abs(r.displacement.pixels[i]));
    return m;
  };
  const float linear = worst(BakeBasis::linear), pn = worst(BakeBasis::pn);
  EXPECT_GT(linear, 0.02f) << "the flat triangles of a 12-sided band are far inside";
  EXPECT_LT(pn, 0.2f * linear) << "linear " << linear << ", pn " << pn;
}

// A detail bump on the high plane (its UVs: u = (x + 0.5) / 2): a sine across u adds
// S (b - 1/2) to the distance and tilts the normal by its slope.
TEST(Bake, DetailBumpAddsHeightAndTiltsNormals) {
  Image bump(64, 1, 1);
  for (int x = 0; x < 64; ++x) bump.at(x, 0) = static_cast<float>(0.5 + 0.5 * std::sin(2 * M_PI * (x + 0.5) / 64));
  BakeOptions o;
  o.width = o.height = 16;
  o.detail = &bump;
  o.detail_scale = 0.01f;
  const BakeResult r = bake(test::make_grid(2, 2), make_plane(0, 0, 0), o);
  for (int x = 2; x < 14; ++x) {
    const double u_high = ((x + 0.5) / 16 + 0.5) / 2;
    const double height = 0.01 * 0.5 * std::sin(2 * M_PI * u_high);
    const double slope = 0.01 * 0.5 * 2 * M_PI * std::cos(2 * M_PI * u_high) / 2;  // per unit x
    EXPECT_NEAR(r.displacement.at(x, 8), height, 2e-4) << x;
    const Eigen::Vector3d n = Eigen::Vector3d(-slope, 0, 1).normalized();
    EXPECT_NEAR(r.normal_os.at(x, 8, 0), n.x(), 2e-3) << x;
    EXPECT_NEAR(r.normal_ts.at(x, 8, 0), n.x(), 2e-3) << x << ": the grid's tangent is +x";
  }
}

TEST(Bake, IdenticalMeshesGiveZeroAndFlatNormals) {
  const Mesh cube = test::make_seamed_cube();
  BakeOptions o;
  o.width = o.height = 64;
  const BakeResult r = bake(cube, cube, o);
  EXPECT_GT(r.covered_texels, 0u);
  EXPECT_EQ(r.misses, 0u);
  for (float d : r.displacement.pixels) ASSERT_NEAR(d, 0.0f, 1e-5f);
  for (size_t i = 0; i < r.normal_ts.texel_count(); ++i) {
    ASSERT_NEAR(r.normal_ts.pixels[3 * i + 2], 1.0f, 1e-5f) << i;
  }
}

TEST(Bake, BrickWallMatchesItsHeightFunction) {
  BrickWallOptions w;
  w.bend_radius = 0;  // flat: the base is the z = 0 plane, so the answer is brick_wall_height
  w.columns = 400;
  w.rows = 200;
  const Mesh high = make_brick_wall(w);
  const Mesh low = make_brick_wall_base(w, 8, 4);
  BakeOptions o;
  o.width = 256;
  o.height = 128;
  const BakeResult r = bake(low, high, o);
  EXPECT_EQ(r.misses, 0u);
  std::vector<float> err;
  for (int y = 0; y < o.height; ++y)
    for (int x = 0; x < o.width; ++x) {
      const float u = texel_center_u(x, o.width), v = texel_center_v(y, o.height);
      err.push_back(std::abs(r.displacement.at(x, y) - brick_wall_height(w, u * w.width, v * w.height)));
    }
  std::sort(err.begin(), err.end());
  // The high mesh interpolates the height linearly between grid vertices 0.005 apart; only
  // texels near the bevels' kinks differ visibly.
  EXPECT_LT(err[err.size() / 2], 0.01f * w.amplitude);
  EXPECT_LT(err[err.size() * 95 / 100], 0.1f * w.amplitude);
}

// NormalY::down (DirectX, Unreal) is NormalY::up's map (OpenGL, glTF, Blender, Unity) with y
// negated, texel for texel, after the dilation too; everything else is identical, and the
// metadata says which.
TEST(Bake, NormalYDownNegatesGreenTexelForTexel) {
  BrickWallOptions w;
  w.columns = 60;
  w.rows = 30;
  const Mesh high = make_brick_wall(w);
  const Mesh low = make_brick_wall_base(w, 6, 3);
  BakeOptions o;
  o.width = 64;
  o.height = 48;
  o.dilate = 2;  // some texels stay unwritten: the flat (0, 0, 1) there
  const BakeResult up = bake(low, high, o);
  o.normal_y = NormalY::down;
  const BakeResult down = bake(low, high, o);
  ASSERT_GT(up.hits, 0u);
  auto bits = [](const Image& a, const Image& b) {
    return a.pixels.size() == b.pixels.size() && std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(float)) == 0;
  };
  ASSERT_EQ(up.normal_ts.pixels.size(), down.normal_ts.pixels.size());
  bool tilted = false;
  for (size_t i = 0; i < up.normal_ts.texel_count(); ++i) {
    ASSERT_EQ(down.normal_ts.pixels[3 * i], up.normal_ts.pixels[3 * i]) << i;
    ASSERT_EQ(down.normal_ts.pixels[3 * i + 1], -up.normal_ts.pixels[3 * i + 1]) << i;
    ASSERT_EQ(down.normal_ts.pixels[3 * i + 2], up.normal_ts.pixels[3 * i + 2]) << i;
    tilted |= std::abs(up.normal_ts.pixels[3 * i + 1]) > 0.1f;
  }
  EXPECT_TRUE(tilted) << "the bevels tilt normals along v";
  EXPECT_TRUE(bits(up.displacement, down.displacement));
  EXPECT_TRUE(bits(up.normal_os, down.normal_os));
  EXPECT_TRUE(bits(up.coverage, down.coverage));
  EXPECT_EQ(up.hits, down.hits);
  EXPECT_EQ(up.misses, down.misses);
  EXPECT_EQ(up.ambiguous, down.ambiguous);
  EXPECT_EQ(up.rays, down.rays);
  EXPECT_EQ(std::get<std::string>(up.normal_ts.metadata.at("normal_y")), "up");
  EXPECT_EQ(std::get<std::string>(down.normal_ts.metadata.at("normal_y")), "down");
  EXPECT_NE(std::get<std::string>(up.normal_ts.metadata.at("space")).find("+y = +v"), std::string::npos);
  EXPECT_NE(std::get<std::string>(down.normal_ts.metadata.at("space")).find("+y = -v"), std::string::npos);
}

TEST(Bake, MissesAreCountedAndFilled) {
  const Mesh low = test::make_grid(2, 2);
  Mesh high = make_plane(0, 0, 0.5f);  // out of reach
  BakeOptions o;
  o.width = o.height = 8;
  o.front = o.back = 0.1f;
  const BakeResult r = bake(low, high, o);
  EXPECT_EQ(r.hits, 0u);
  EXPECT_EQ(r.misses, 64u);
  uint32_t per_face = 0;
  for (size_t f = 0; f < r.face_misses.size(); ++f) {
    EXPECT_EQ(r.face_misses[f], r.face_texels[f]);
    per_face += r.face_misses[f];
  }
  EXPECT_EQ(per_face, 64u);
  for (float c : r.coverage.pixels) EXPECT_EQ(c, 0.5f);
  for (float d : r.displacement.pixels) EXPECT_EQ(d, 0.0f);
}

// Every sample of every map is a number (no NaN, no infinity), misses and fills included.
void expect_finite(const BakeResult& r) {
  for (const Image* img : {&r.displacement, &r.normal_ts, &r.normal_os, &r.coverage})
    for (size_t i = 0; i < img->pixels.size(); ++i) ASSERT_TRUE(std::isfinite(img->pixels[i])) << i;
  EXPECT_TRUE(std::isfinite(r.min_displacement));
  EXPECT_TRUE(std::isfinite(r.max_displacement));
}

// Grazing rays: the high plane z = 100 (x - 1/2) meets the vertical rays of a flat base at
// 0.57 degrees. Within the reach (5) the answer is still exact: texels with |100 (u - 1/2)|
// <= 5 hit at that distance with the plane's normal, the others miss (their nearest
// intersection is further than the reach; 0.47 of margin either side). A wall standing
// exactly in the plane of one column's rays (parallel: Embree may or may not report it) and
// a nearly vertical plane must still leave finite maps.
TEST(Bake, GrazingRaysHitWithinReachExactlyAndStayFinite) {
  const float k = 100.0f;
  BakeOptions o;
  o.width = o.height = 64;
  o.front = o.back = 5.0f;
  const BakeResult r = bake(test::make_grid(2, 2), make_plane(k, 0, -0.5f * k), o);
  expect_finite(r);
  EXPECT_EQ(r.hits, 6u * 64u) << "columns 29..34";
  EXPECT_EQ(r.misses, 58u * 64u);
  const Eigen::Vector3d n = Eigen::Vector3d(-k, 0, 1).normalized();
  double worst = 0;
  for (int y = 0; y < o.height; ++y)
    for (int x = 0; x < o.width; ++x) {
      const double u = texel_center_u(x, o.width), d = k * (u - 0.5);
      const bool hit = std::abs(d) <= o.front;
      ASSERT_EQ(r.coverage.at(x, y), hit ? 1.0f : 0.5f) << x << "," << y;
      if (!hit) continue;
      worst = std::max(worst, std::abs(r.displacement.at(x, y) - d));
      for (int c = 0; c < 3; ++c) ASSERT_NEAR(r.normal_ts.at(x, y, c), n[c], 1e-5) << x << "," << y;
    }
  std::printf("[ grazing ] worst displacement error %.3g (|d| up to 3.9)\n", worst);
  EXPECT_LT(worst, 1e-5) << "float coordinates of the plane reach 100 (ulp 8e-6); measured 7e-7";

  // Rays exactly in the plane of a wall (x = the texel centre of column 31) and a plane a
  // hair from vertical (1e4): finite, and nothing hits except possibly that one column.
  Mesh wall;
  const float xw = static_cast<float>(texel_center_u(31, 64));
  const VertexHandle a = wall.add_vertex(Vec3f(xw, -0.5f, -1)), b = wall.add_vertex(Vec3f(xw, 1.5f, -1));
  const VertexHandle c = wall.add_vertex(Vec3f(xw, 1.5f, 1)), d = wall.add_vertex(Vec3f(xw, -0.5f, 1));
  wall.add_face(a, b, c);
  wall.add_face(a, c, d);
  compute_angle_weighted_normals(wall);
  o.front = o.back = 0.5f;
  const BakeResult edge_on = bake(test::make_grid(2, 2), wall, o);
  expect_finite(edge_on);
  for (int y = 0; y < o.height; ++y)
    for (int x = 0; x < o.width; ++x)
      if (x != 31) {
        ASSERT_EQ(edge_on.coverage.at(x, y), 0.5f) << x << "," << y;
      }
  const BakeResult steep = bake(test::make_grid(2, 2), make_plane(1e4f, 0, -0.5e4f), o);
  expect_finite(steep);
  EXPECT_EQ(steep.hits + steep.misses, steep.covered_texels);
}

// A high plane with a square hole over [1/4, 3/4]^2: the texels whose centres lie over it
// (8 x 8 of 16 x 16) miss, are marked 0.5, are reported under the base faces they belong to,
// and are filled from their neighbours (the plane's height).
TEST(Bake, AHoleInTheHighMeshMissesPerBaseFace) {
  const Mesh high = test::without_faces(make_plane(0, 0, 0.02f), [](const Mesh& m, FaceHandle f) {
    Vec3f centroid(0, 0, 0);
    for (auto v : m.fv_range(f)) centroid += m.point(v) / 3.0f;
    return centroid[0] > 0.25f && centroid[0] < 0.75f && centroid[1] > 0.25f && centroid[1] < 0.75f;
  });
  ASSERT_EQ(high.n_faces(), 128u - 8u);
  const Mesh low = test::make_grid(2, 2);
  BakeOptions o;
  o.width = o.height = 16;
  o.front = o.back = 0.05f;
  const BakeResult r = bake(low, high, o);
  expect_finite(r);
  EXPECT_EQ(r.misses, 64u);
  EXPECT_EQ(r.hits, 256u - 64u);
  const auto samples = rasterize_uv(low, o.width, o.height);
  std::vector<uint32_t> expected(low.n_faces(), 0);
  for (int y = 0; y < o.height; ++y)
    for (int x = 0; x < o.width; ++x) {
      const bool in_hole = x >= 4 && x < 12 && y >= 4 && y < 12;
      EXPECT_EQ(r.coverage.at(x, y), in_hole ? 0.5f : 1.0f) << x << "," << y;
      EXPECT_NEAR(r.displacement.at(x, y), 0.02f, 1e-6f) << x << "," << y;
      if (in_hole) ++expected[static_cast<size_t>(samples[static_cast<size_t>(y * o.width + x)].face)];
    }
  EXPECT_EQ(r.face_misses, expected);
  EXPECT_GT(std::count_if(expected.begin(), expected.end(), [](uint32_t n) { return n > 0; }), 1) << "several faces report";
}

// The plane case of BakePlane with the whole scene scaled by s (base, high surface and
// reach): the worst displacement error as a fraction of the amplitude, and the worst error
// of a tangent-space normal component. The bake's offsets (ray start, bunch, reach) are
// relative to the meshes' size, so neither may feel the scale.
struct ScaledPlaneErrors {
  double displacement = 0, normal = 0;
};
ScaledPlaneErrors bake_scaled_plane(float s) {
  const float a = 0.1f, b = -0.05f, c = 0.05f;
  Mesh low = test::make_grid(4, 2);
  Mesh high = make_plane(a, b, c);
  for (auto v : low.vertices()) low.set_point(v, low.point(v) * s);
  for (auto v : high.vertices()) high.set_point(v, high.point(v) * s);
  BakeOptions o;
  o.width = o.height = 24;
  o.front = o.back = 0.5f * s;
  const BakeResult r = bake(low, high, o);
  EXPECT_EQ(r.misses, 0u);
  const Vec3f n = Vec3f(-a, -b, 1.0f).normalized();
  ScaledPlaneErrors e;
  for (int y = 0; y < o.height; ++y)
    for (int x = 0; x < o.width; ++x) {
      const double u = texel_center_u(x, o.width), v = texel_center_v(y, o.height);
      e.displacement = std::max(e.displacement, std::abs(r.displacement.at(x, y) - s * (a * u + b * v + c)));
      for (int k = 0; k < 3; ++k) e.normal = std::max(e.normal, static_cast<double>(std::abs(r.normal_ts.at(x, y, k) - n[k])));
    }
  e.displacement /= s * (std::abs(a) + std::abs(b) + std::abs(c));
  std::printf("[ scale %g ] worst displacement error %.3g of the amplitude, worst normal component error %.3g\n", static_cast<double>(s),
              e.displacement, e.normal);
  return e;
}

// At a scale of 1e-4 (displacements ~1e-5).
TEST(Bake, TinyCoordinatesKeepTheAnswerRelativeToTheAmplitude) {
  const ScaledPlaneErrors e = bake_scaled_plane(1e-4f);
  EXPECT_LT(e.displacement, 1e-6) << "measured 1e-7 of the amplitude";
  EXPECT_LT(e.normal, 1e-5);
}

// Coordinates around 1e5: the whole setup scaled up (a base 1e5 across, the plane's height
// 5e3 to 2e4), not a small mesh moved far away (HugeCoordinates... above).
TEST(Bake, CoordinatesAround1e5KeepTheAnswerRelativeToTheAmplitude) {
  const ScaledPlaneErrors e = bake_scaled_plane(1e5f);
  EXPECT_LT(e.displacement, 1e-6) << "measured 9e-8 of the amplitude, as at 1e-4";
  EXPECT_LT(e.normal, 1e-5) << "measured 3e-8";
}

// Supersampling keeps to the texel's chart: two charts side by side in UV, their border at
// u = 0.55 inside texel 4 of 8 (u in [0.5, 0.625]); in 3D chart 0 (z = 0) lies 0.01 under the
// high layer above it, chart 1 (z = 1) 0.03 under its own. Texel 4's centre (u = 0.5625) is
// in chart 1; of its 2 x 2 samples (u = 0.53125 and 0.59375) the left pair falls in chart 0
// and is left out (bake.cpp: a sample counts only inside a face of the texel's own chart), so
// the texel reads chart 1's 0.03, not the 0.02 of a mix across the charts. With 4 x 4
// samples, the same.
TEST(Bake, SupersamplesInAnotherChartAreLeftOut) {
  const Mesh low = test::make_uv_quads({{0.0f, 0.0f, 0.55f, 1.0f}, {0.55f, 0.0f, 1.0f, 1.0f}});
  size_t charts = 0;
  uv_charts(low, &charts);
  ASSERT_EQ(charts, 2u);
  const Mesh high = make_layers({{0.01f, true}, {1.03f, true}});
  BakeOptions o;
  o.width = 8;
  o.height = 2;
  o.front = o.back = 0.05f;
  for (const int samples : {4, 16}) {
    o.samples = samples;
    const BakeResult r = bake(low, high, o);
    EXPECT_EQ(r.misses, 0u);
    for (int y = 0; y < o.height; ++y) {
      EXPECT_NEAR(r.displacement.at(3, y), 0.01f, 1e-6f) << samples << " samples: chart 0 only";
      EXPECT_NEAR(r.displacement.at(4, y), 0.03f, 1e-6f) << samples << " samples: chart 0's samples left out";
      EXPECT_NEAR(r.displacement.at(5, y), 0.03f, 1e-6f) << samples << " samples: chart 1 only";
    }
  }
}

// Base faces whose UVs collapse (to a point, to a segment; a sliver of 1e-7 UV area) have no
// tangent frame (or a nearly singular one) and no area in the map: nothing may turn NaN, and
// the texels of the good chart are exactly those of the same bake without the bad faces.
TEST(Bake, CollapsedBaseUvsLeaveNoNanAndOtherTexelsUnchanged) {
  Mesh good = test::make_grid(2, 2);
  for (auto h : good.halfedges()) good.set_texcoord2D(h, good.texcoord2D(h) * 0.5f);  // the chart: [0, 1/2]^2
  Mesh low = good;
  auto add_triangle = [&](const std::array<Vec3f, 3>& p, const std::array<Vec2f, 3>& uv) {
    std::array<VertexHandle, 3> v;
    for (size_t k = 0; k < 3; ++k) v[k] = low.add_vertex(p[k]);
    const FaceHandle f = low.add_face(v[0], v[1], v[2]);
    for (auto h : face_halfedges(low, f))
      for (size_t k = 0; k < 3; ++k)
        if (low.to_vertex_handle(h) == v[k]) low.set_texcoord2D(h, uv[k]);
  };
  add_triangle({Vec3f(0.6f, 0.6f, 0), Vec3f(0.9f, 0.6f, 0), Vec3f(0.6f, 0.9f, 0)}, {Vec2f(0.75f, 0.75f), Vec2f(0.75f, 0.75f), Vec2f(0.75f, 0.75f)});
  add_triangle({Vec3f(0.1f, 0.6f, 0), Vec3f(0.4f, 0.6f, 0), Vec3f(0.1f, 0.9f, 0)}, {Vec2f(0.6f, 0.9f), Vec2f(0.7f, 0.9f), Vec2f(0.8f, 0.9f)});
  add_triangle({Vec3f(0.6f, 0.1f, 0), Vec3f(0.9f, 0.1f, 0), Vec3f(0.6f, 0.4f, 0)}, {Vec2f(0.6f, 0.7f), Vec2f(0.8f, 0.7f), Vec2f(0.7f, 0.7000005f)});
  compute_angle_weighted_normals(low);
  const Mesh high = make_plane(0.1f, -0.05f, 0.01f);
  BakeOptions o;
  o.width = o.height = 32;
  o.front = o.back = 0.5f;
  const BakeResult with = bake(low, high, o), without = bake(good, high, o);
  expect_finite(with);
  // Zero UV area covers no texel (uv_raster: as uvpack's degenerate faces); the sliver
  // does, and its nearly singular UV-to-3D map makes extreme tangents.
  EXPECT_EQ(with.face_texels[8], 0u);
  EXPECT_EQ(with.face_texels[9], 0u);
  EXPECT_GT(with.face_texels[10], 0u);
  size_t compared = 0;
  for (size_t i = 0; i < without.coverage.texel_count(); ++i) {
    if (without.coverage.pixels[i] == 0.0f) continue;
    ++compared;
    ASSERT_EQ(with.coverage.pixels[i], without.coverage.pixels[i]) << i;
    ASSERT_EQ(with.displacement.pixels[i], without.displacement.pixels[i]) << i;
    for (size_t c = 0; c < 3; ++c) ASSERT_EQ(with.normal_ts.pixels[3 * i + c], without.normal_ts.pixels[3 * i + c]) << i;
  }
  EXPECT_EQ(compared, 16u * 16u);
}

// Texel centres lying exactly on the diagonal shared by a quad's two triangles belong to one
// of them: no texel of a chart may fall through the crack between its faces.
TEST(UvRaster, CentresOnSharedEdgesAreCovered) {
  const Mesh quad = test::make_grid(1, 1);
  for (int n : {4, 5, 64}) {
    const auto samples = rasterize_uv(quad, n, n);
    for (size_t i = 0; i < samples.size(); ++i) {
      ASSERT_GE(samples[i].face, 0) << "texel " << i << " at " << n << "^2";
      const auto& b = samples[i].bary;
      ASSERT_NEAR(b[0] + b[1] + b[2], 1.0f, 1e-6f);
      ASSERT_TRUE(b[0] >= 0 && b[1] >= 0 && b[2] >= 0);
    }
  }
}

TEST(UvRaster, ATriangleSmallerThanATexelStillGetsItsTexel) {
  Mesh m = test::make_grid(1, 1);
  // Face 0 shrunk into texel (0, 3) of a 4 x 4 map, clear of that texel's centre (0.5, 3.5).
  const Vec2f corners[3] = {{0.1f, 0.1f}, {0.12f, 0.1f}, {0.12f, 0.12f}};
  int k = 0;
  for (auto h : face_halfedges(m, FaceHandle(0))) m.set_texcoord2D(h, corners[k++]);
  const Vec2f far_corners[3] = {{0.9f, 0.9f}, {0.95f, 0.9f}, {0.95f, 0.95f}};  // face 1 out of the way
  k = 0;
  for (auto h : face_halfedges(m, FaceHandle(1))) m.set_texcoord2D(h, far_corners[k++]);
  const auto samples = rasterize_uv(m, 4, 4);
  const TexelSample& s = samples[3 * 4 + 0];
  EXPECT_EQ(s.face, 0);
  EXPECT_FALSE(s.centre_inside);
  EXPECT_NEAR(s.bary[0] + s.bary[1] + s.bary[2], 1.0f, 1e-6f);
}

// A chart inset in the map: every texel its triangles touch is written, border texels at the
// chart's point nearest their centre, so a bake over a plane is exact there too.
TEST(Bake, BorderTexelsTakeTheNearestPointOfTheChart) {
  Mesh low = test::make_grid(2, 2);
  for (auto h : low.halfedges())
    if (!low.is_boundary(h)) low.set_texcoord2D(h, low.texcoord2D(h) * 0.55f + Vec2f(0.2f, 0.17f));
  const float a = 0.1f, b = -0.05f, c = 0.02f;
  const Mesh high = make_plane(a, b, c);
  BakeOptions o;
  o.width = o.height = 16;
  o.front = o.back = 0.5f;
  o.dilate = 0;
  const BakeResult r = bake(low, high, o);
  const auto samples = rasterize_uv(low, 16, 16);
  size_t border = 0;
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) {
      const TexelSample& s = samples[static_cast<size_t>(y) * 16 + static_cast<size_t>(x)];
      if (s.face < 0) {
        EXPECT_EQ(r.coverage.at(x, y), 0.0f);
        continue;
      }
      border += !s.centre_inside;
      ASSERT_EQ(r.coverage.at(x, y), 1.0f) << x << "," << y;
      Vec3f p(0, 0, 0);
      int k = 0;
      for (auto h : face_halfedges(low, FaceHandle(s.face))) p += low.point(low.to_vertex_handle(h)) * s.bary[static_cast<size_t>(k++)];
      ASSERT_NEAR(r.displacement.at(x, y), a * p[0] + b * p[1] + c, 2e-6f) << x << "," << y;
    }
  EXPECT_GE(border, 8u) << "the chart's bottom and top edges cut through texel rows";
  EXPECT_EQ(r.misses, 0u);
}

TEST(UvRaster, FarOutUvsAreSafe) {
  Mesh m = test::make_grid(2, 1);
  for (auto h : face_halfedges(m, FaceHandle(0))) m.set_texcoord2D(h, m.texcoord2D(h) * 1e9f + Vec2f(2e9f, 0));
  for (auto h : face_halfedges(m, FaceHandle(1))) m.set_texcoord2D(h, m.texcoord2D(h) - Vec2f(3e9f, 3e9f));
  const auto samples = rasterize_uv(m, 16, 16);
  for (const auto& s : samples) EXPECT_TRUE(s.face != 0 && s.face != 1);
}

// Against brute force on random masks: every filled texel takes a written texel at the least
// Euclidean distance, and nothing beyond the radius is filled.
TEST(Dilate, SourcesAreExactlyNearestInTheEuclideanMetric) {
  std::mt19937 rng(17);
  for (int trial = 0; trial < 6; ++trial) {
    const int w = 5 + trial * 7, h = 3 + trial * 5;
    std::vector<uint8_t> written(static_cast<size_t>(w * h), 0);
    std::bernoulli_distribution on(trial == 5 ? 0.002 : 0.08);
    for (auto& b : written) b = on(rng);
    const int radius = trial % 2 ? 3 : -1;
    const auto src = dilation_sources(written, w, h, radius);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        double best = 1e300;
        for (int yy = 0; yy < h; ++yy)
          for (int xx = 0; xx < w; ++xx)
            if (written[static_cast<size_t>(yy * w + xx)]) best = std::min(best, double((x - xx) * (x - xx) + (y - yy) * (y - yy)));
        const int32_t s = src[static_cast<size_t>(y * w + x)];
        if (best >= 1e300 || (radius >= 0 && best > radius * radius)) {
          ASSERT_EQ(s, -1) << x << "," << y;
          continue;
        }
        ASSERT_GE(s, 0) << x << "," << y;
        ASSERT_TRUE(written[static_cast<size_t>(s)]);
        const int sx = s % w, sy = s / w;
        ASSERT_EQ(double((x - sx) * (x - sx) + (y - sy) * (y - sy)), best) << x << "," << y;
      }
  }
}

TEST(Dilate, CopiesTheNearestWrittenTexelUpToTheRadius) {
  Image img(7, 1, 1, 0.0f);
  std::vector<uint8_t> written(7, 0);
  img.at(3, 0) = 5.0f;
  written[3] = 1;
  dilate(img, written, 2);
  const float expect[7] = {0, 5, 5, 5, 5, 5, 0};
  for (int x = 0; x < 7; ++x) EXPECT_EQ(img.at(x, 0), expect[x]) << x;
  EXPECT_EQ(written[0], 0);
  dilate(img, written, -1);
  EXPECT_EQ(img.at(0, 0), 5.0f);
}

// bake() splits its work among threads (rows, bands of the UV rasteriser, blocks of the
// report, dilation rows and columns): the result must not depend on how many there are, for
// every hit rule (the nearest rules take the one-traversal path, the others the hit loop),
// with misses (short reach) and dilation.
TEST(Bake, SameBitsWhateverTheThreadCount) {
  BrickWallOptions w;
  w.columns = 120;
  w.rows = 60;
  const Mesh high = make_brick_wall(w);
  const Mesh low = make_brick_wall_base(w, 12, 6);
  auto same = [](const Image& a, const Image& b) {
    return a.pixels.size() == b.pixels.size() && std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(float)) == 0;
  };
  // Every rule at both reaches with one sample per texel; with 4 (supersampling: more rays
  // per texel, samples on neighbouring faces) the nearest and furthest rules.
  for (const int samples : {1, 4})
    for (const HitRule rule : {HitRule::nearest, HitRule::furthest, HitRule::front_else_nearest, HitRule::front_only})
      for (const float reach : {0.0f, 0.002f}) {
        if (samples > 1 && (reach > 0 || rule == HitRule::front_else_nearest || rule == HitRule::front_only)) continue;
        BakeOptions o;
        o.width = 96;
        o.height = 64;
        o.hit = rule;
        o.samples = samples;
        o.front = o.back = reach;
        BakeResult one;
        {
          const tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
          one = bake(low, high, o);
        }
        const BakeResult many = bake(low, high, o);
        SCOPED_TRACE(std::string(hit_rule_name(rule)) + " reach " + std::to_string(reach) + " samples " + std::to_string(samples));
        EXPECT_GT(one.hits, 0u);
        EXPECT_EQ(one.hits, many.hits);
        EXPECT_EQ(one.misses, many.misses);
        EXPECT_EQ(one.ambiguous, many.ambiguous);
        EXPECT_EQ(one.rays, many.rays);
        EXPECT_EQ(one.face_texels, many.face_texels);
        EXPECT_EQ(one.face_misses, many.face_misses);
        EXPECT_EQ(one.face_ambiguous, many.face_ambiguous);
        EXPECT_EQ(std::memcmp(&one.min_displacement, &many.min_displacement, sizeof(float)), 0);
        EXPECT_EQ(std::memcmp(&one.max_displacement, &many.max_displacement, sizeof(float)), 0);
        EXPECT_TRUE(same(one.displacement, many.displacement));
        EXPECT_TRUE(same(one.normal_ts, many.normal_ts));
        EXPECT_TRUE(same(one.normal_os, many.normal_os));
        EXPECT_TRUE(same(one.coverage, many.coverage));
      }
}

// The coherent path (the rays of up to 64 neighbouring texels cast as Embree ray streams)
// against each texel's rays cast on their own (BakeOptions::coherent = false), on the bent
// brick wall, for the options the coherent path takes: the same queries, so the same counts
// and coverage, and the same maps within float rounding.
TEST(Bake, CoherentRaysGiveTheSingleRaysAnswers) {
  BrickWallOptions w;
  w.columns = 160;
  w.rows = 80;
  const Mesh high = make_brick_wall(w);
  const Mesh low = make_brick_wall_base(w, 12, 6);
  Mesh cage = low;
  for (auto v : cage.vertices()) cage.set_point(v, cage.point(v) + 2.0f * w.amplitude * cage.normal(v));
  for (int variant = 0; variant < 6; ++variant) {
    BakeOptions o;
    o.width = 200;  // not a multiple of the stream's 64: a short run at each row's end
    o.height = 96;
    if (variant == 1) o.hit = HitRule::front_else_nearest;
    if (variant == 2) o.hit = HitRule::front_only;
    if (variant == 3) o.front = o.back = 0.3f * w.amplitude;  // short reach: misses
    if (variant == 4) o.cage = &cage;
    if (variant == 5) o.basis = BakeBasis::pn;
    SCOPED_TRACE("variant " + std::to_string(variant));
    const BakeResult fast = bake(low, high, o);
    o.coherent = false;
    const BakeResult single = bake(low, high, o);
    ASSERT_GT(fast.hits, 0u);
    // The streams did the work: most queries went out in them (none without coherent).
    EXPECT_GT(fast.stream_rays, fast.rays / 2);
    EXPECT_EQ(single.stream_rays, 0u);
    EXPECT_EQ(fast.hits, single.hits);
    EXPECT_EQ(fast.misses, single.misses);
    EXPECT_EQ(fast.ambiguous, single.ambiguous);
    EXPECT_EQ(fast.rays, single.rays);
    EXPECT_EQ(fast.face_misses, single.face_misses);
    EXPECT_EQ(fast.coverage.pixels, single.coverage.pixels);
    size_t differ = 0;
    for (size_t i = 0; i < fast.displacement.texel_count(); ++i) {
      differ += fast.displacement.pixels[i] != single.displacement.pixels[i];
      for (int c = 0; c < 3; ++c) differ += fast.normal_ts.pixels[3 * i + c] != single.normal_ts.pixels[3 * i + c];
      ASSERT_NEAR(fast.displacement.pixels[i], single.displacement.pixels[i], 1e-6f * w.amplitude) << i;
      for (int c = 0; c < 3; ++c) {
        ASSERT_NEAR(fast.normal_ts.pixels[3 * i + c], single.normal_ts.pixels[3 * i + c], 1e-5f) << i;
        ASSERT_NEAR(fast.normal_os.pixels[3 * i + c], single.normal_os.pixels[3 * i + c], 1e-5f) << i;
      }
    }
    // Embree's packet kernels round some hits' t, u, v differently in the last bits from its
    // single-ray ones (within the tolerances above): a few values differ, no more.
    EXPECT_LT(differ, fast.displacement.texel_count() * 4 / 50) << "of " << fast.displacement.texel_count() * 4 << " values";
  }
}

// rasterize_uv works in parallel bands of rows: the same samples as one band or one row at
// a time.
TEST(UvRaster, BandsGiveTheWholeImage) {
  BrickWallOptions w;
  const Mesh low = make_brick_wall_base(w, 9, 5);
  const int width = 83, height = 47;
  const auto whole = rasterize_uv(low, width, height);
  const UvRasterizer raster(low, width, height);
  const auto one_band = raster.rows(0, height);
  ASSERT_EQ(whole.size(), one_band.size());
  for (int y = 0; y < height; ++y) {
    const auto row = raster.rows(y, y + 1);
    for (int x = 0; x < width; ++x) {
      const size_t i = static_cast<size_t>(y * width + x);
      for (const TexelSample* s : {&one_band[i], &row[static_cast<size_t>(x)]}) {
        ASSERT_EQ(whole[i].face, s->face) << x << "," << y;
        ASSERT_EQ(whole[i].centre_inside, s->centre_inside) << x << "," << y;
        ASSERT_EQ(std::memcmp(whole[i].bary.data(), s->bary.data(), sizeof(whole[i].bary)), 0) << x << "," << y;
      }
    }
  }
}

// The rasteriser tests texel centres only within a per-row span of each triangle, bounded
// with a margin: the same samples as testing every centre of the triangle's box (the rule's
// plain form, written out here), on random triangles: slivers, near-horizontal and
// near-vertical edges, triangles smaller than a texel, both windings, corners off the map.
TEST(UvRaster, SpansGiveTheWholeBoxTestsAnswer) {
  std::mt19937 rng(12345);
  std::uniform_real_distribution<float> uv(-0.1f, 1.1f), small(-0.02f, 0.02f);
  for (int trial = 0; trial < 40; ++trial) {
    Mesh m = test::make_grid(6, 6);
    for (auto f : m.faces()) {
      std::array<Vec2f, 3> c{};
      c[0] = Vec2f(uv(rng), uv(rng));
      switch (f.idx() % 4) {
        case 0: c[1] = Vec2f(uv(rng), uv(rng)); c[2] = Vec2f(uv(rng), uv(rng)); break;
        case 1: c[1] = c[0] + Vec2f(small(rng), small(rng)); c[2] = c[0] + Vec2f(small(rng), small(rng)); break;  // small
        case 2: c[1] = Vec2f(uv(rng), c[0][1] + 1e-7f * small(rng)); c[2] = Vec2f(uv(rng), uv(rng)); break;     // ~horizontal edge
        default: c[1] = Vec2f(uv(rng), uv(rng)); c[2] = c[0] + (c[1] - c[0]) * 0.5f + Vec2f(1e-4f * small(rng), 0); break;  // sliver
      }
      int k = 0;
      for (auto h : face_halfedges(m, f)) m.set_texcoord2D(h, c[static_cast<size_t>(k++)]);
    }
    const int width = 37 + trial, height = 29 + 2 * trial;
    const auto got = rasterize_uv(m, width, height);
    std::vector<TexelSample> want(static_cast<size_t>(width) * static_cast<size_t>(height));
    for (auto f : m.faces()) {
      if (uv_double_area(m, f) == 0.0f) continue;
      const UvTriangle t = uv_triangle_in_pixels(m, f, width, height);
      const double area = (t.px[1] - t.px[0]) * (t.py[2] - t.py[0]) - (t.py[1] - t.py[0]) * (t.px[2] - t.px[0]);
      if (!(std::abs(area) > 0)) continue;
      int x0, x1, y0, y1;
      if (!texel_centres_in(std::min({t.px[0], t.px[1], t.px[2]}), std::max({t.px[0], t.px[1], t.px[2]}), width, x0, x1)) continue;
      if (!texel_centres_in(std::min({t.py[0], t.py[1], t.py[2]}), std::max({t.py[0], t.py[1], t.py[2]}), height, y0, y1)) continue;
      const double* px = t.px;
      const double* py = t.py;
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          const double cx = x + 0.5, cy = y + 0.5;
          const double w0 = ((px[1] - cx) * (py[2] - cy) - (py[1] - cy) * (px[2] - cx)) / area;
          const double w1 = ((px[2] - cx) * (py[0] - cy) - (py[2] - cy) * (px[0] - cx)) / area;
          const double w2 = ((px[0] - cx) * (py[1] - cy) - (py[0] - cy) * (px[1] - cx)) / area;
          if (w0 < -1e-9 || w1 < -1e-9 || w2 < -1e-9) continue;
          TexelSample& s = want[static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)];
          if (s.face >= 0) continue;
          const double c0 = std::max(w0, 0.0), c1 = std::max(w1, 0.0), c2 = std::max(w2, 0.0), sum = c0 + c1 + c2;
          s.face = f.idx();
          s.bary = {static_cast<float>(c0 / sum), static_cast<float>(c1 / sum), static_cast<float>(c2 / sum)};
          s.centre_inside = true;
        }
    }
    size_t inside = 0;
    for (size_t i = 0; i < want.size(); ++i) {
      ASSERT_EQ(got[i].centre_inside, want[i].centre_inside) << "trial " << trial << " texel " << i;
      if (!want[i].centre_inside) continue;
      ++inside;
      ASSERT_EQ(got[i].face, want[i].face) << "trial " << trial << " texel " << i;
      ASSERT_EQ(std::memcmp(got[i].bary.data(), want[i].bary.data(), sizeof(want[i].bary)), 0) << "trial " << trial << " texel " << i;
    }
    EXPECT_GT(inside, want.size() / 4) << "trial " << trial;
  }
}

// apply_dilation copies in index order when a source is itself filled from elsewhere (it
// runs in parallel only when no source is).
TEST(Dilate, ChainedSourcesCopyInIndexOrder) {
  Image img(4, 1, 1, 0.0f);
  for (int x = 0; x < 4; ++x) img.at(x, 0) = static_cast<float>(x + 1);
  apply_dilation(img, {1, 2, 3, 3});
  const float expect[4] = {2, 3, 4, 4};
  for (int x = 0; x < 4; ++x) EXPECT_EQ(img.at(x, 0), expect[x]) << x;
}

}  // namespace
}  // namespace meso
