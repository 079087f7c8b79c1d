#include "meso/meshreduce/surface_distance.hpp"

#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace meso {
namespace {

// A flat 1 x 1 grid with one spike of height 0.3 at (0.25, 0.75): its flat reduction departs
// from it there only. The distances of the output's faces are exactly the spike's height
// where the spike stands over them (its tip's nearest point lies there) and 0 far from it;
// at a threshold of half the height one region is reported, around the spike.
TEST(ErrorRegions, ASpikeIsTheOneRegion) {
  Mesh high = test::make_grid(16, 16);
  for (auto v : high.vertices()) {
    const Vec3f p = high.point(v);
    if (std::abs(p[0] - 0.25f) < 1e-6f && std::abs(p[1] - 0.75f) < 1e-6f) high.set_point(v, Vec3f(p[0], p[1], 0.3f));
  }
  const Mesh flat = test::make_grid(4, 4);
  SurfaceDistanceOptions o;
  o.samples = 20000;
  const std::vector<double> d = face_distances(high, flat, o);
  ASSERT_EQ(d.size(), flat.n_faces());
  double worst = 0;
  size_t far_zero = 0, far = 0;
  for (auto f : flat.faces()) {
    const size_t i = static_cast<size_t>(f.idx());
    worst = std::max(worst, d[i]);
    Vec3f c(0, 0, 0);
    for (auto v : flat.fv_range(f)) c += flat.point(v) / 3.0f;
    if (std::abs(c[0] - 0.25f) > 0.3f || std::abs(c[1] - 0.75f) > 0.3f) {
      ++far;
      far_zero += d[i] < 1e-6;
    }
  }
  EXPECT_NEAR(worst, 0.3, 1e-6) << "the tip's distance, measured from the tip (a vertex sample)";
  EXPECT_EQ(far_zero, far) << "faces away from the spike lie on the input";
  const std::vector<ErrorRegion> regions = error_regions(flat, d, 0.15);
  ASSERT_EQ(regions.size(), 1u);
  EXPECT_NEAR(regions[0].max_distance, 0.3, 1e-6);
  EXPECT_NEAR(regions[0].centroid[0], 0.25f, 0.15f);
  EXPECT_NEAR(regions[0].centroid[1], 0.75f, 0.15f);
  EXPECT_GE(regions[0].faces, 1u);
  EXPECT_LT(regions[0].faces, flat.n_faces() / 4);
  EXPECT_TRUE(error_regions(flat, d, 0.31).empty());
  EXPECT_EQ(face_distances(high, flat, o), d) << "deterministic";
}

// A mesh measured against itself is about 1e-16 away (rounding in the measure): at a
// threshold of 0 that is no region, while a real departure of 1e-5 still is one.
TEST(ErrorRegions, RoundingIsNoDeparture) {
  const Mesh grid = test::make_grid(8, 8);
  std::vector<double> d(grid.n_faces(), 3e-16);
  EXPECT_TRUE(error_regions(grid, d, 0.0).empty());
  d[5] = 1e-5;
  const std::vector<ErrorRegion> r = error_regions(grid, d, 0.0);
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].faces, 1u);
  EXPECT_EQ(r[0].first_face, 5);
}

}  // namespace
}  // namespace meso
