#include "meso/core/uv_texels.hpp"

#include <gtest/gtest.h>

#include <random>
#include <set>
#include <utility>

namespace meso {
namespace {

// for_each_touched_texel reports exactly the texels of the triangle's bounding box for
// which the separating-axis test holds: on random triangles of every size and aspect, on
// triangles with corners and edges exactly on texel lines, and on slivers; with grown texel
// squares too.
TEST(UvTexels, RowSpansGiveExactlyTheSeparatingAxisTexels) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> pos(-3.0, 40.0), size(0.01, 30.0), unit(0.0, 1.0);
  const int w = 37, h = 29;
  for (int trial = 0; trial < 20000; ++trial) {
    UvTriangle t{};
    const double cx = pos(rng), cy = pos(rng), s = size(rng);
    for (int k = 0; k < 3; ++k) {
      t.px[k] = cx + s * (unit(rng) - 0.5);
      t.py[k] = cy + s * (unit(rng) - 0.5);
      if (trial % 4 == 1) t.px[k] = std::round(t.px[k]);  // corners on texel lines
      if (trial % 4 == 2) t.py[k] = std::round(t.py[k] * 2) / 2;
    }
    if (trial % 7 == 3) {  // a sliver: the third corner almost on the first edge
      t.px[2] = t.px[0] + (t.px[1] - t.px[0]) * 0.37 + 1e-9;
      t.py[2] = t.py[0] + (t.py[1] - t.py[0]) * 0.37;
    }
    if (trial % 11 == 5) {  // exactly degenerate
      t.px[2] = t.px[0] + (t.px[1] - t.px[0]) * 0.5;
      t.py[2] = t.py[0];
      t.py[1] = t.py[0];
    }
    const double grow = trial % 3 == 2 ? 0.01 * unit(rng) : 0.0;  // texel squares grown (uv_pack's rounding margin)
    std::set<std::pair<int, int>> fast, slow;
    for_each_touched_texel(t, w, h, [&](int x, int y) { EXPECT_TRUE(fast.insert({x, y}).second) << "reported twice"; }, 0, 1 << 30, grow);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        if (triangle_overlaps_texel(t, x, y, grow)) slow.insert({x, y});
    ASSERT_EQ(fast, slow) << "trial " << trial << ": (" << t.px[0] << "," << t.py[0] << ") (" << t.px[1] << "," << t.py[1] << ") (" << t.px[2]
                          << "," << t.py[2] << ")";
  }
}

// Corners billions of texels out (UVs of 1e7 on a 4096 map, a bad export): the rows' spans
// are clamped before they become ints, so the texels the triangle covers are still all
// reported (they had overflowed int, and the row touched nothing).
TEST(UvTexels, FarOutCornersStillCoverTheGrid) {
  const int w = 9, h = 7;
  for (const double far : {1e3, 3e9, 1e15}) {
    const UvTriangle t{{-far, far, 4.5}, {-1.0, -1.0, far}};  // covers the whole grid
    std::set<std::pair<int, int>> fast, slow;
    for_each_touched_texel(t, w, h, [&](int x, int y) { fast.insert({x, y}); });
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        if (triangle_overlaps_texel(t, x, y)) slow.insert({x, y});
    EXPECT_EQ(slow.size(), static_cast<size_t>(w * h)) << far;
    EXPECT_EQ(fast, slow) << far;
  }
}

// A grown texel holds every texel the triangle touches once its corners move by up to
// `grow` per axis: random triangles, corners nudged at random by less than that. (Not a
// degenerate one: it touches nothing, but nudged it is a sliver that can touch texels.)
TEST(UvTexels, GrownTexelsHoldTheMovedTriangles) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> pos(0.0, 12.0), unit(-1.0, 1.0);
  const double grow = 1e-3;
  for (int trial = 0; trial < 5000; ++trial) {
    UvTriangle t{}, moved{};
    for (int k = 0; k < 3; ++k) {
      t.px[k] = std::round(pos(rng) * 4) / 4;  // on quarter-texel lines, where a nudge matters
      t.py[k] = std::round(pos(rng) * 4) / 4;
      moved.px[k] = t.px[k] + grow * unit(rng);
      moved.py[k] = t.py[k] + grow * unit(rng);
    }
    if ((t.px[1] - t.px[0]) * (t.py[2] - t.py[0]) == (t.py[1] - t.py[0]) * (t.px[2] - t.px[0])) continue;  // degenerate: touches nothing
    std::set<std::pair<int, int>> grown;
    for_each_touched_texel(t, 12, 12, [&](int x, int y) { grown.insert({x, y}); }, 0, 1 << 30, grow);
    for_each_touched_texel(moved, 12, 12, [&](int x, int y) { ASSERT_TRUE(grown.count({x, y})) << "trial " << trial << " texel " << x << "," << y; });
  }
}

}  // namespace
}  // namespace meso
