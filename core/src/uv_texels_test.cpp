#include "meso/core/uv_texels.hpp"

#include <gtest/gtest.h>

#include <random>
#include <set>
#include <utility>

namespace meso {
namespace {

// for_each_touched_texel reports exactly the texels of the triangle's bounding box for
// which the separating-axis test holds: on random triangles of every size and aspect, on
// triangles with corners and edges exactly on texel lines, and on slivers.
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
    std::set<std::pair<int, int>> fast, slow;
    for_each_touched_texel(t, w, h, [&](int x, int y) { EXPECT_TRUE(fast.insert({x, y}).second) << "reported twice"; });
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        if (triangle_overlaps_texel(t, x, y)) slow.insert({x, y});
    ASSERT_EQ(fast, slow) << "trial " << trial << ": (" << t.px[0] << "," << t.py[0] << ") (" << t.px[1] << "," << t.py[1] << ") (" << t.px[2]
                          << "," << t.py[2] << ")";
  }
}

}  // namespace
}  // namespace meso
