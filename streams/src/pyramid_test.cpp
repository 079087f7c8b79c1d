#include "meso/streams/pyramid.hpp"

#include "test_fields.hpp"

#include <Imath/half.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <string>

namespace meso {
namespace {

HeightField random_field(int w, int h, Border border, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> d(-3.0f, 5.0f);
  Image img(w, h, 1);
  for (float& v : img.pixels) v = d(rng);
  return make_height_field(img, border);
}

TEST(HeightField, NormalisesWithScaleAndBias) {
  Image img(3, 1, 1);
  img.pixels = {-0.5f, 0.0f, 1.5f};
  const HeightField f = make_height_field(img, Border::clamp);
  EXPECT_EQ(f.bias, -0.5f);
  EXPECT_EQ(f.scale, 2.0f);
  EXPECT_EQ(f.height.pixels, (LargeVector<float>{0.0f, 0.25f, 1.0f}));
  const HeightField flat = make_height_field(Image(4, 4, 1, 7.0f), Border::wrap);
  EXPECT_EQ(flat.bias, 7.0f);
  EXPECT_EQ(flat.scale, 0.0f);
  for (float v : flat.height.pixels) EXPECT_EQ(v, 0.0f);
}

// A map that records its mapping to object units (bake's displacement.png, with the numbers
// as PNG text) gives the field of the object-unit map it encodes.
TEST(HeightField, TakesARecordedMappingBackToObjectUnits) {
  Image png(3, 1, 1);
  png.pixels = {0.0f, 0.25f, 1.0f};
  png.metadata = {{"height_bias", std::string("-0.5")}, {"height_scale", std::string("2")}};
  const HeightField f = make_height_field(png, Border::clamp);
  EXPECT_EQ(f.bias, -0.5f);
  EXPECT_EQ(f.scale, 2.0f);
  EXPECT_EQ(f.height.pixels, (LargeVector<float>{0.0f, 0.25f, 1.0f}));
  png.pixels = {0.25f, 0.5f, 0.75f};  // not spanning [0, 1]: object heights 0, 0.5, 1
  png.metadata = {{"height_bias", -0.5f}, {"height_scale", 2.0f}};
  const HeightField g = make_height_field(png, Border::clamp);
  EXPECT_EQ(g.bias, 0.0f);
  EXPECT_EQ(g.scale, 1.0f);
  EXPECT_EQ(g.height.pixels, (LargeVector<float>{0.0f, 0.5f, 1.0f}));
}

TEST(Pyramid, SpikeHasTheKnownBilinearBounds) {
  Image img(5, 5, 1, 0.0f);
  img.at(2, 2) = 1.0f;
  const MinMaxPyramid p = build_min_max_pyramid(make_height_field(img, Border::clamp));
  const Image& l0 = p.levels[0];
  EXPECT_EQ(l0.at(2, 2, 1), 1.0f);
  EXPECT_EQ(l0.at(2, 2, 0), 0.25f) << "corners average the spike with three zeros";
  EXPECT_EQ(l0.at(3, 2, 1), 0.5f) << "the shared edge's midpoint";
  EXPECT_EQ(l0.at(3, 3, 1), 0.25f) << "the shared corner";
  EXPECT_EQ(l0.at(4, 2, 1), 0.0f) << "two texels away the filtered surface is flat";
  // Sizes follow OpenGL's mip chain: 5 -> 2 -> 1.
  ASSERT_EQ(p.levels.size(), 3u);
  EXPECT_EQ(p.levels[1].width, 2);
  EXPECT_EQ(p.levels[2].width, 1);
  EXPECT_EQ(p.levels[2].at(0, 0, 1), 1.0f);
  EXPECT_EQ(p.levels[2].at(0, 0, 0), 0.0f);
}

// Samples the filtered surface on a quarter-texel grid over a footprint given in level-0
// pixel units; the grid holds every texel's 9 extreme points when the footprint is aligned.
void sampled_range(const HeightField& f, double x0, double x1, double y0, double y1, float& lo, float& hi) {
  lo = 1e30f;
  hi = -1e30f;
  for (double y = y0; y <= y1 + 1e-9; y += 0.25)
    for (double x = x0; x <= x1 + 1e-9; x += 0.25) {
      const float v = f.bilinear(x, y);
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
}

// The map families: noise (heights outside [0, 1] before normalising), steps, a
// single-texel spike, all-zero and all-one.
enum class PyramidMap { noise, steps, spike, zero, one };

struct PyramidCase {
  int w, h;
  Border border;
  PyramidMap map = PyramidMap::noise;
};

HeightField pyramid_input(const PyramidCase& c) {
  switch (c.map) {
    case PyramidMap::noise: return random_field(c.w, c.h, c.border, 42u + static_cast<unsigned>(c.w));
    case PyramidMap::steps: return test::steps(c.w, c.h, c.border);
    case PyramidMap::spike: return test::spike(c.w, c.h, c.border, c.w / 3, c.h / 2);
    case PyramidMap::zero: return test::all_zero(c.w, c.h, c.border);
    case PyramidMap::one: return test::all_one(c.w, c.h, c.border);
  }
  return {};
}

std::string pyramid_case_name(const ::testing::TestParamInfo<PyramidCase>& info) {
  static const char* const maps[] = {"noise", "steps", "spike", "zero", "one"};
  const PyramidCase& c = info.param;
  return std::string(maps[static_cast<int>(c.map)]) + std::to_string(c.w) + "x" + std::to_string(c.h) + "_" + border_name(c.border);
}

class PyramidBounds : public ::testing::TestWithParam<PyramidCase> {};

// Brute force over the definition: every level's [min, max] contains the filtered surface
// over the texel's footprint, and equals its extremes exactly where footprints are aligned
// to level-0 texels (level 0 always; every level when the size is a power of two).
TEST_P(PyramidBounds, ExactAndConservative) {
  const auto c = GetParam();
  const HeightField f = pyramid_input(c);
  const MinMaxPyramid p = build_min_max_pyramid(f);
  const bool pot = (c.w & (c.w - 1)) == 0 && (c.h & (c.h - 1)) == 0;
  for (size_t k = 0; k < p.levels.size(); ++k) {
    const Image& l = p.levels[k];
    for (int y = 0; y < l.height; ++y)
      for (int x = 0; x < l.width; ++x) {
        const double sx = double(c.w) / l.width, sy = double(c.h) / l.height;
        float lo, hi;
        sampled_range(f, x * sx, (x + 1) * sx, y * sy, (y + 1) * sy, lo, hi);
        ASSERT_LE(l.at(x, y, 0), lo + 1e-6f) << "level " << k << " texel " << x << "," << y;
        ASSERT_GE(l.at(x, y, 1), hi - 1e-6f) << "level " << k << " texel " << x << "," << y;
        if (k == 0 || pot) {
          ASSERT_NEAR(l.at(x, y, 0), lo, 1e-6f) << "level " << k << " texel " << x << "," << y;
          ASSERT_NEAR(l.at(x, y, 1), hi, 1e-6f) << "level " << k << " texel " << x << "," << y;
        }
      }
  }
}

INSTANTIATE_TEST_SUITE_P(Sizes, PyramidBounds,
                         ::testing::Values(PyramidCase{16, 16, Border::clamp}, PyramidCase{16, 8, Border::wrap},
                                           PyramidCase{13, 7, Border::clamp}, PyramidCase{13, 7, Border::wrap},
                                           PyramidCase{1, 9, Border::clamp},
                                           // The sizes (32², 64²): every level's footprint is aligned,
                                           // so every level is checked for exactness.
                                           PyramidCase{32, 32, Border::clamp}, PyramidCase{64, 64, Border::wrap},
                                           PyramidCase{64, 64, Border::clamp, PyramidMap::steps},
                                           PyramidCase{32, 32, Border::wrap, PyramidMap::steps},
                                           PyramidCase{64, 64, Border::clamp, PyramidMap::spike},
                                           PyramidCase{32, 32, Border::wrap, PyramidMap::spike},
                                           PyramidCase{32, 32, Border::clamp, PyramidMap::zero},
                                           PyramidCase{64, 64, Border::wrap, PyramidMap::zero},
                                           PyramidCase{32, 32, Border::wrap, PyramidMap::one},
                                           PyramidCase{64, 64, Border::clamp, PyramidMap::one}),
                         pyramid_case_name);

}  // namespace
}  // namespace meso

namespace meso {
namespace {

// --half: minima round down and maxima up to half values (the writer rounds to nearest,
// which had stored a maximum of 1/3 as 0.333252, under the surface), exactly representable so
// the file holds them as they are.
TEST(Pyramid, HalfRoundingStaysConservative) {
  Image m(4, 1, 2);
  const float values[4] = {1.0f / 3.0f, 0.6f, 0.0f, 1.0f};
  for (int x = 0; x < 4; ++x) m.at(x, 0, 0) = m.at(x, 0, 1) = values[x];
  Image rounded = m;
  round_min_max_to_half(rounded);
  for (int x = 0; x < 4; ++x) {
    const float lo = rounded.at(x, 0, 0), hi = rounded.at(x, 0, 1);
    EXPECT_LE(lo, values[x]) << x;
    EXPECT_GE(hi, values[x]) << x;
    EXPECT_EQ(static_cast<float>(Imath::half(lo)), lo) << x;
    EXPECT_EQ(static_cast<float>(Imath::half(hi)), hi) << x;
    EXPECT_LT(hi - lo, 1e-3f) << x;
  }
  EXPECT_EQ(rounded.at(2, 0, 0), 0.0f);
  EXPECT_EQ(rounded.at(3, 0, 1), 1.0f) << "exact values stay";
  EXPECT_GT(static_cast<float>(Imath::half(1.0f / 3.0f)), 0.0f);
  EXPECT_LT(static_cast<float>(Imath::half(1.0f / 3.0f)), 1.0f / 3.0f) << "to nearest is below 1/3: the case this guards";
}

}  // namespace
}  // namespace meso
