#include "meso/streams/half_rounding.hpp"

#include <Imath/half.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace meso {
namespace {

// Every finite half value, ascending: the brute-force answer for both directions.
std::vector<float> finite_halves() {
  std::vector<float> all;
  for (unsigned bits = 0; bits < 0x10000; ++bits) {
    Imath::half h;
    h.setBits(static_cast<unsigned short>(bits));
    if (h.isFinite()) all.push_back(static_cast<float>(h));
  }
  std::sort(all.begin(), all.end());
  all.erase(std::unique(all.begin(), all.end()), all.end());  // +0 and -0
  return all;
}

TEST(HalfRounding, TightAgainstEveryHalfValue) {
  const std::vector<float> all = finite_halves();
  std::vector<float> probes;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> wide(-65000.0f, 65000.0f), narrow(-1.0f, 1.0f), tiny(-1e-6f, 1e-6f);
  for (int i = 0; i < 20000; ++i) probes.insert(probes.end(), {wide(rng), narrow(rng), tiny(rng)});
  for (size_t i = 0; i + 1 < all.size(); i += 97) {  // the halves, their neighbours and midpoints
    probes.insert(probes.end(), {all[i], std::nextafter(all[i], -1e9f), std::nextafter(all[i], 1e9f), 0.5f * (all[i] + all[i + 1])});
  }
  probes.insert(probes.end(), {1.0f / 3.0f, -1.0f / 3.0f, 0.0f, -0.0f, 65504.0f, -65504.0f});
  for (float v : probes) {
    if (v < all.front() || v > all.back()) continue;  // beyond the range: SaturatesInsteadOfInf
    const auto above = std::lower_bound(all.begin(), all.end(), v);  // first >= v
    const auto below = std::upper_bound(all.begin(), all.end(), v) - 1;  // last <= v
    EXPECT_EQ(half_above(v), *above) << v;
    EXPECT_EQ(half_below(v), *below) << v;
  }
}

// Distances and cone ratios beyond half's range become its largest finite value when rounded
// down: still a bound, never Inf.
TEST(HalfRounding, SaturatesInsteadOfInf) {
  EXPECT_EQ(half_below(65519.0f), 65504.0f);
  EXPECT_EQ(half_below(65520.0f), 65504.0f) << "to nearest overflows here";
  EXPECT_EQ(half_below(1e30f), 65504.0f);
  EXPECT_EQ(half_above(-1e30f), -65504.0f);
  EXPECT_TRUE(std::isinf(half_above(65505.0f)));
  EXPECT_TRUE(std::isinf(half_below(-65505.0f)));
  EXPECT_EQ(half_below(1.0f / 3.0f), static_cast<float>(Imath::half(1.0f / 3.0f))) << "nearest is below here";
  EXPECT_GT(half_above(1.0f / 3.0f), 1.0f / 3.0f);
}

}  // namespace
}  // namespace meso
