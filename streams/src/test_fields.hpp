// Height fields the streams' tests share (test-only header).
#pragma once

#include "meso/streams/height_field.hpp"

#include <cmath>
#include <functional>
#include <random>

namespace meso::test {

// A w x h field from f(x, y), normalised by make_height_field.
inline HeightField field_from(int w, int h, Border border, const std::function<float(int, int)>& f) {
  Image img(w, h, 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img.at(x, y) = f(x, y);
  return make_height_field(img, border);
}

// Uniform noise in [0, 1].
inline HeightField noise(int w, int h, Border border, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> d(0.0f, 1.0f);
  return field_from(w, h, border, [&](int, int) { return d(rng); });
}

// Smooth bumps: one sine period across, two cosine periods down (tiles seamlessly).
inline HeightField bumps(int w, int h, Border border) {
  return field_from(w, h, border, [&](int x, int y) {
    return static_cast<float>(std::sin(6.2831853 * x / w) * std::cos(6.2831853 * 2 * y / h));
  });
}

}  // namespace meso::test
