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
// clamp. Each texel's 9 samples are taken once, so 64² maps with wide windows stay cheap.
class BruteForce {
 public:
  explicit BruteForce(const HeightField& f) : f_(f), lo_(f.height.width, f.height.height, 1), hi_(lo_) {
    for (int y = 0; y < f.height.height; ++y)
      for (int x = 0; x < f.height.width; ++x) {
        float lo = std::numeric_limits<float>::infinity(), hi = -lo;
        for (int j = 0; j <= 2; ++j)
          for (int i = 0; i <= 2; ++i) {
            const float s = f.bilinear(x + 0.5 * i, y + 0.5 * j);
            lo = std::min(lo, s);
            hi = std::max(hi, s);
          }
        lo_.at(x, y) = lo;
        hi_.at(x, y) = hi;
      }
  }

  void window(int radius, int x, int y, float& lo, float& hi) const {
    lo = std::numeric_limits<float>::infinity();
    hi = -lo;
    const int w = f_.height.width, h = f_.height.height;
    for (int dy = -radius; dy <= radius; ++dy)
      for (int dx = -radius; dx <= radius; ++dx) {
        int tx = x + dx, ty = y + dy;
        if (f_.border == Border::clamp && (tx < 0 || ty < 0 || tx >= w || ty >= h)) continue;
        tx = ((tx % w) + w) % w;
        ty = ((ty % h) + h) % h;
        lo = std::min(lo, lo_.at(tx, ty));
        hi = std::max(hi, hi_.at(tx, ty));
      }
  }

 private:
  const HeightField& f_;
  Image lo_, hi_;
};

void expect_brute_force(const HeightField& f, int radius) {
  SCOPED_TRACE(std::string(border_name(f.border)) + " " + std::to_string(f.height.width) + "x" + std::to_string(f.height.height) +
               " radius " + std::to_string(radius));
  const BruteForce brute(f);
  const Image m = dilation_erosion_map(f, radius);
  ASSERT_EQ(m.width, f.height.width);
  ASSERT_EQ(m.height, f.height.height);
  ASSERT_EQ(m.channels, 2);
  for (int y = 0; y < m.height; ++y)
    for (int x = 0; x < m.width; ++x) {
      float lo, hi;
      brute.window(radius, x, y, lo, hi);
      ASSERT_EQ(m.at(x, y, 0), lo) << x << "," << y;
      ASSERT_EQ(m.at(x, y, 1), hi) << x << "," << y;
    }
}

TEST(DilationErosion, EqualsTheBruteForceOnStructuredAndRandomMaps) {
  for (const Border border : {Border::clamp, Border::wrap}) {
    const HeightField fields[] = {
        test::noise(13, 7, border, 3),
        test::noise(1, 9, border, 4),
        test::bumps(16, 12, border),
        test::spike(11, 10, border, 5, 4),
        test::field_from(12, 5, border, [](int x, int) { return x < 6 ? 0.0f : 1.0f; }),  // a step
        test::field_from(6, 6, border, [](int, int) { return 0.25f; }),                  // flat
    };
    for (const HeightField& f : fields)
      for (const int radius : {0, 1, 2, 5, 20}) expect_brute_force(f, radius);
  }
  // Under clamp every radius from the map's size on is one window, the whole map (the largest
  // radius had padded each line by 2^20 a side); under wrap too.
  for (const Border border : {Border::clamp, Border::wrap}) {
    const HeightField f = test::noise(13, 7, border, 3);
    EXPECT_EQ(dilation_erosion_map(f, 1 << 20).pixels, dilation_erosion_map(f, 13).pixels);
  }
}

// The sizes and map families (32², 64²: noise, steps, a single-texel spike, all-zero,
// all-one), with windows from one texel to wider than the map.
TEST(DilationErosion, EqualsTheBruteForceAt32And64) {
  for (const Border border : {Border::clamp, Border::wrap}) {
    const HeightField fields[] = {
        test::noise(64, 64, border, 12), test::noise(32, 32, border, 13), test::steps(64, 64, border),
        test::spike(64, 64, border, 40, 9), test::spike(32, 32, border, 0, 31), test::all_zero(32, 32, border),
        test::all_one(32, 32, border),
    };
    for (const HeightField& f : fields)
      for (const int radius : {0, 1, 3, 10, 40}) expect_brute_force(f, radius);
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
