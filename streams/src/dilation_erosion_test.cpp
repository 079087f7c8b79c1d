#include "meso/streams/dilation_erosion.hpp"

#include "meso/streams/pyramid.hpp"
#include "test_fields.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace meso {
namespace {

// The brute-force definition: the filtered surface sampled where its extremes over each
// texel's footprint lie (the 9 points {0, 1/2, 1}^2 of the texel, pyramid.hpp), over every
// texel of the window; wrapped texel indices under wrap, the window cut at the edges under
// clamp.
void brute_force(const HeightField& f, int radius, int x, int y, float& lo, float& hi) {
  lo = std::numeric_limits<float>::infinity();
  hi = -lo;
  const int w = f.height.width, h = f.height.height;
  for (int dy = -radius; dy <= radius; ++dy)
    for (int dx = -radius; dx <= radius; ++dx) {
      int tx = x + dx, ty = y + dy;
      if (f.border == Border::clamp && (tx < 0 || ty < 0 || tx >= w || ty >= h)) continue;
      tx = ((tx % w) + w) % w;
      ty = ((ty % h) + h) % h;
      for (int j = 0; j <= 2; ++j)
        for (int i = 0; i <= 2; ++i) {
          const float s = f.bilinear(tx + 0.5 * i, ty + 0.5 * j);
          lo = std::min(lo, s);
          hi = std::max(hi, s);
        }
    }
}

TEST(DilationErosion, EqualsTheBruteForceOnStructuredAndRandomMaps) {
  for (const Border border : {Border::clamp, Border::wrap}) {
    const HeightField fields[] = {
        test::noise(13, 7, border, 3),
        test::noise(1, 9, border, 4),
        test::bumps(16, 12, border),
        test::field_from(11, 10, border, [](int x, int y) { return x == 5 && y == 4 ? 1.0f : 0.0f; }),  // one spike
        test::field_from(12, 5, border, [](int x, int) { return x < 6 ? 0.0f : 1.0f; }),                // a step
        test::field_from(6, 6, border, [](int, int) { return 0.25f; }),                                  // flat
    };
    for (const HeightField& f : fields)
      for (const int radius : {0, 1, 2, 5, 20}) {
        SCOPED_TRACE(std::string(border_name(border)) + " " + std::to_string(f.height.width) + "x" + std::to_string(f.height.height) +
                     " radius " + std::to_string(radius));
        const Image m = dilation_erosion_map(f, radius);
        ASSERT_EQ(m.width, f.height.width);
        ASSERT_EQ(m.height, f.height.height);
        ASSERT_EQ(m.channels, 2);
        for (int y = 0; y < m.height; ++y)
          for (int x = 0; x < m.width; ++x) {
            float lo, hi;
            brute_force(f, radius, x, y, lo, hi);
            EXPECT_EQ(m.at(x, y, 0), lo) << x << "," << y;
            EXPECT_EQ(m.at(x, y, 1), hi) << x << "," << y;
          }
      }
  }
}

// Radius 0 is the pyramid's level 0; a wider window only widens the bounds; the same bytes
// on one thread.
TEST(DilationErosion, NestsAndIsDeterministic) {
  const HeightField f = test::noise(64, 48, Border::wrap, 9);
  const Image zero = dilation_erosion_map(f, 0), level0 = footprint_min_max(f);
  EXPECT_EQ(zero.pixels, level0.pixels);
  Image previous = zero;
  for (const int radius : {1, 3, 8}) {
    const Image m = dilation_erosion_map(f, radius);
    for (size_t i = 0; i < m.texel_count(); ++i) {
      EXPECT_LE(m.pixels[2 * i], previous.pixels[2 * i]);
      EXPECT_GE(m.pixels[2 * i + 1], previous.pixels[2 * i + 1]);
    }
    previous = m;
  }
  const Image all_threads = dilation_erosion_map(f, 3);
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  EXPECT_EQ(dilation_erosion_map(f, 3).pixels, all_threads.pixels);
  EXPECT_THROW(dilation_erosion_map(f, -1), std::invalid_argument);
}

}  // namespace
}  // namespace meso
