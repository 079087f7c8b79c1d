#include "meso/core/float_rounding.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>

namespace meso {
namespace {

// Two roundings packed into a pair of doubles: the pattern whose plain static_cast<float>
// Debian 12's GCC 12.2 drops at -O2 (float_rounding.hpp). noipa and volatile inputs, so
// that the optimiser sees only the pattern, not the constants.
__attribute__((noipa)) std::array<double, 2> packed(double a, double r) { return {round_to_float(r + a), round_to_float(r * a)}; }

TEST(FloatRounding, SurvivesThePackingGcc12Folded) {
  volatile double va = 1.0 / 3.0, vr = std::sqrt(2.0);
  const double a = va, r = vr;
  const std::array<double, 2> p = packed(a, r);
  volatile float sum = static_cast<float>(r + a), product = static_cast<float>(r * a);  // rounded through memory
  EXPECT_EQ(p[0], static_cast<double>(sum));
  EXPECT_EQ(p[1], static_cast<double>(product));
  EXPECT_NE(p[0], r + a) << "the values are not floats";
}

}  // namespace
}  // namespace meso
