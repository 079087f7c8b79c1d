#include "meso/core/huge_pages.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <numeric>

namespace meso {
namespace {

// Large blocks start on a 2 MiB boundary (the whole block can be backed by huge pages) and
// behave as any vector's memory; small ones are ordinary allocations. Both deallocation
// paths run (a sanitizer build checks them).
TEST(HugePages, LargeBlocksAreAlignedAndHoldTheirValues) {
  LargeVector<float> big(kHugePageThreshold / sizeof(float) + 1, 1.5f);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(big.data()) % (std::uintptr_t(2) << 20), 0u);
  std::iota(big.begin(), big.end(), 0.0f);
  EXPECT_EQ(big[12345], 12345.0f);
  big.resize(big.size() * 2, -1.0f);  // reallocation copies across blocks
  EXPECT_EQ(big[12345], 12345.0f);
  EXPECT_EQ(big.back(), -1.0f);

  LargeVector<uint8_t> small(100, 7);
  EXPECT_EQ(small[99], 7);
  small.shrink_to_fit();
  LargeVector<uint8_t> copy = small;
  EXPECT_EQ(copy, small);
}

// Elements made without a value are default-initialised: a type with member initialisers
// gets them (bake's TexelSample relies on it), and a value given still fills.
TEST(HugePages, ElementsWithoutAValueAreDefaultInitialised) {
  struct Sample {
    int face = -1;
    float weight = 0.25f;
  };
  LargeVector<Sample> samples(kHugePageThreshold / sizeof(Sample) + 1);
  EXPECT_EQ(samples.back().face, -1);
  EXPECT_EQ(samples[samples.size() / 2].weight, 0.25f);
  LargeVector<float> zeros(kHugePageThreshold / sizeof(float) + 1, 0.0f);
  EXPECT_EQ(zeros.back(), 0.0f);
  zeros.resize(zeros.size() + 10, 2.0f);
  EXPECT_EQ(zeros.back(), 2.0f);
}

}  // namespace
}  // namespace meso
