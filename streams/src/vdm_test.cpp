#include "meso/streams/vdm.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <random>

namespace meso {
namespace {

HeightField constant(int w, int h, float height, Border border = Border::wrap) {
  HeightField f;
  f.height = Image(w, h, 1, height);
  f.scale = 1;
  f.border = border;
  return f;
}

HeightField noise(int w, int h, unsigned seed, Border border = Border::wrap) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> d(0.0f, 1.0f);
  Image img(w, h, 1);
  for (float& v : img.pixels) v = d(rng);
  return make_height_field(img, border);
}

double theta_of(const VdmOptions& o, int i) { return (i + 0.5) / o.theta * o.theta_max * M_PI / 180.0; }

// Over a flat field at height h0 the ray meets the plane where its drop, relief (1 - h0),
// equals s / tan(theta) - c s^2 / 2: s = relief (1 - h0) tan(theta) when flat; on a curved
// base the smaller root, or nothing when the surface falls away faster (a silhouette).
TEST(Vdm, FlatFieldMatchesTheClosedForm) {
  VdmOptions o;
  o.theta = 6;
  o.phi = 4;
  o.relief = 0.05f;
  o.curvatures = {0.0f, 2.0f, -3.0f, 40.0f};
  const float h0 = 0.3f;
  const VdmTable t = build_vdm(constant(8, 8, h0), o);
  ASSERT_EQ(t.directions(), 6 * 4 * 4);
  const double depth = o.relief * (1 - h0);
  int misses = 0;
  for (int k = 0; k < 4; ++k)
    for (int i = 0; i < o.theta; ++i) {
      const double a = 1 / std::tan(theta_of(o, i)), c = o.curvatures[static_cast<size_t>(k)];
      // c s^2 / 2 - a s + depth = 0
      const double disc = a * a - 2 * c * depth;
      const double expected = c == 0 ? depth / a : (disc < 0 ? kVdmMiss : (a - std::sqrt(disc)) / c);
      misses += expected == kVdmMiss;
      for (int j = 0; j < o.phi; ++j)
        for (size_t texel : {size_t{0}, size_t{27}, size_t{63}}) {
          const float got = t.at(texel, (k * o.theta + i) * o.phi + j);
          if (expected == kVdmMiss) {
            EXPECT_EQ(got, kVdmMiss) << k << " " << i;
          } else {
            EXPECT_NEAR(got, expected, 1e-5 * (1 + expected)) << "curvature " << c << " theta " << i;
          }
        }
    }
  EXPECT_GT(misses, 0) << "the strongly convex slice has silhouettes";
}

// On a rough field every recorded point is on the surface, at the ray's height there.
TEST(Vdm, RecordedPointsLieOnTheSurface) {
  VdmOptions o;
  o.theta = 5;
  o.phi = 6;
  o.relief = 0.2f;
  o.curvatures = {0.0f, 1.5f};
  const HeightField f = noise(12, 10, 3);
  const VdmTable t = build_vdm(f, o);
  const double w = f.height.width;
  int hits = 0;
  for (int y = 0; y < 10; ++y)
    for (int x = 0; x < 12; ++x)
      for (int k = 0; k < 2; ++k)
        for (int i = 0; i < o.theta; ++i)
          for (int j = 0; j < o.phi; ++j) {
            const float d = t.at(static_cast<size_t>(y * 12 + x), (k * o.theta + i) * o.phi + j);
            if (d == kVdmMiss) continue;
            ++hits;
            const double phi = 2 * M_PI * j / o.phi, s = d;  // units of u
            const double px = x + 0.5 + s * w * std::cos(phi), py = y + 0.5 - s * w * std::sin(phi);
            const double ray = 1 - (s / std::tan(theta_of(o, i)) - o.curvatures[static_cast<size_t>(k)] * s * s / 2) / o.relief;
            EXPECT_NEAR(f.bilinear(px, py), ray, 2e-5) << x << "," << y << " dir " << k << " " << i << " " << j;
          }
  EXPECT_GT(hits, 1000);
}

TEST(Vdm, CompressionMeetsItsErrorAndReportsIt) {
  VdmOptions o;
  o.theta = 6;
  o.phi = 8;
  o.relief = 0.1f;
  const VdmTable t = build_vdm(noise(16, 16, 5), o);
  int previous_rank = -1;
  for (double target : {0.05, 0.01, 0.002}) {
    const CompressedVdm c = compress_vdm(t, target, t.directions());
    EXPECT_LE(c.rms_error, target * 1.001 + 1e-6) << target;
    EXPECT_GT(c.rank, previous_rank) << "a smaller error needs a larger rank";
    previous_rank = c.rank;
    double worst = 0, sq = 0;
    for (size_t i = 0; i < 256; ++i)
      for (int j = 0; j < t.directions(); ++j) {
        const double e = std::abs(c.value(i, j) - t.at(i, j));
        worst = std::max(worst, e);
        sq += e * e;
      }
    EXPECT_NEAR(c.max_error, worst, 1e-9);
    EXPECT_NEAR(c.rms_error, std::sqrt(sq / (256.0 * t.directions())), 1e-9);
    EXPECT_LT(c.bytes(), t.distance.size() * sizeof(float));
  }
  const CompressedVdm full = compress_vdm(t, 0.0, t.directions());
  EXPECT_LT(full.max_error, 1e-4) << "full rank reproduces the table";
  const CompressedVdm flat = compress_vdm(build_vdm(constant(4, 4, 0.5f), o), 1e-6, 8);
  EXPECT_EQ(flat.rank, 0) << "every texel sees the same: the mean is the table";
  EXPECT_LT(flat.max_error, 1e-6);
}

TEST(Vdm, SameBytesWhateverTheThreadCount) {
  VdmOptions o;
  o.theta = 3;
  o.phi = 5;
  o.curvatures = {0.0f, 4.0f};
  const HeightField f = noise(20, 7, 9, Border::clamp);
  VdmTable one;
  CompressedVdm one_c;
  {
    tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    one = build_vdm(f, o);
    one_c = compress_vdm(one, 0.01, 8);
  }
  const VdmTable many = build_vdm(f, o);
  const CompressedVdm many_c = compress_vdm(many, 0.01, 8);
  EXPECT_EQ(one.distance, many.distance);
  EXPECT_EQ(one_c.weights, many_c.weights);
  EXPECT_EQ(one_c.basis, many_c.basis);
}

// Curvature slices from a mesh: a few extreme vertices do not set the range; a flat mesh
// needs one slice at 0; values are per unit of u.
TEST(Vdm, CurvatureSlicesIgnoreAFewSharpVertices) {
  std::vector<float> k1(100, 0.5f), k2(100, 0.0f);
  k1[3] = 500.0f;   // a bevel
  k2[7] = -300.0f;
  const std::vector<float> s = vdm_curvature_slices(k1, k2, 2.0, 3);
  ASSERT_EQ(s.size(), 3u);
  EXPECT_FLOAT_EQ(s[0], 0.0f);
  EXPECT_FLOAT_EQ(s[1], 0.5f);
  EXPECT_FLOAT_EQ(s[2], 1.0f);
  const std::vector<float> flat = vdm_curvature_slices(std::vector<float>(10, 0.0f), std::vector<float>(10, 0.0f), 2.0, 4);
  ASSERT_EQ(flat.size(), 1u);
  EXPECT_EQ(flat[0], 0.0f);
  const std::vector<float> one = vdm_curvature_slices(k1, k2, 2.0, 1);
  ASSERT_EQ(one.size(), 1u);
  EXPECT_FLOAT_EQ(one[0], 0.5f);  // the median mean curvature 0.25, times 2
}

// A sphere-like mesh curves one way only: the slices span its curvatures, not down to 0
// (the range had been widened to include 0, the slices spread where no vertex is).
TEST(Vdm, CurvatureSlicesSpanTheMeshNotZero) {
  std::vector<float> k1, k2;
  for (int i = 0; i <= 100; ++i) {
    k1.push_back(1.0f + 0.001f * static_cast<float>(i));  // 1 .. 1.1
    k2.push_back(0.9f + 0.001f * static_cast<float>(i));  // 0.9 .. 1.0
  }
  const std::vector<float> s = vdm_curvature_slices(k1, k2, 2.0, 3);
  ASSERT_EQ(s.size(), 3u);
  EXPECT_FLOAT_EQ(s[0], 2.0f * 0.905f);  // 5th percentile of k2, per unit of u
  EXPECT_FLOAT_EQ(s[2], 2.0f * 1.095f);  // 95th of k1
  // A range narrow against its distance from 0: 64 steps over 1 +- 3e-6 are fewer distinct
  // floats; each is kept once, increasing (repeats had gone into the file).
  std::vector<float> n1, n2;
  for (int i = 0; i <= 100; ++i) {
    n1.push_back(1.0f + 3e-6f * static_cast<float>(i) / 100);
    n2.push_back(1.0f - 3e-6f * static_cast<float>(i) / 100);
  }
  const std::vector<float> narrow = vdm_curvature_slices(n1, n2, 1.0, 64);
  ASSERT_GE(narrow.size(), 2u);
  EXPECT_LT(narrow.size(), 64u);
  for (size_t i = 1; i < narrow.size(); ++i) EXPECT_GT(narrow[i], narrow[i - 1]) << i;
}

// The same mesh at 1e12 units: curvatures 1e-12 as large, length per u 1e12 larger; the
// slices per unit of u are the same (they had collapsed to one, the range taken as flat).
TEST(Vdm, CurvatureSlicesDoNotDependOnTheUnits) {
  for (const double scale : {1e12, 1e-12}) {
    std::vector<float> k1(100, static_cast<float>(0.5 / scale)), k2(100, 0.0f);
    const std::vector<float> s = vdm_curvature_slices(k1, k2, 2.0 * scale, 3);
    ASSERT_EQ(s.size(), 3u) << scale;
    EXPECT_FLOAT_EQ(s[0], 0.0f);
    EXPECT_NEAR(s[1], 0.5f, 1e-6f);
    EXPECT_NEAR(s[2], 1.0f, 1e-6f);
  }
}

}  // namespace
}  // namespace meso
