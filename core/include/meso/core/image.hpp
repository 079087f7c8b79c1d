// The one image type of the meso pipeline.
//
// Image is a width x height grid of `channels` float samples, interleaved, rows stored
// top row first (as in image files). Texel (x, y) covers [x, x+1] x [y, y+1] in pixel
// units; its centre is at (x + 0.5, y + 0.5). In UV terms (OpenGL convention, v up):
//   u = (x + 0.5) / width,   v = 1 - (y + 0.5) / height.
// Values are whatever the producing stage documents (object units for displacement,
// [-1,1] vector components for normals, ...). Metadata are named attributes written
// into and read from the file header (EXR attributes, PNG text chunks).
#pragma once

#include "meso/core/huge_pages.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <map>
#include <string>
#include <variant>
#include <vector>

namespace meso {

using ImageAttribute = std::variant<int, float, std::string>;
using ImageMetadata = std::map<std::string, ImageAttribute>;

struct Image {
  int width = 0;
  int height = 0;
  int channels = 0;
  LargeVector<float> pixels;  // width * height * channels, row-major, top row first
  ImageMetadata metadata;

  Image() = default;
  Image(int w, int h, int c, float fill = 0.0f)
      : width(w), height(h), channels(c),
        pixels(static_cast<size_t>(w) * static_cast<size_t>(h) * static_cast<size_t>(c), fill) {}

  bool empty() const { return pixels.empty(); }
  size_t texel_count() const { return static_cast<size_t>(width) * static_cast<size_t>(height); }
  size_t index(int x, int y) const {
    return (static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)) *
           static_cast<size_t>(channels);
  }
  float& at(int x, int y, int c = 0) { return pixels[index(x, y) + static_cast<size_t>(c)]; }
  float at(int x, int y, int c = 0) const { return pixels[index(x, y) + static_cast<size_t>(c)]; }
  float* texel(int x, int y) { return pixels.data() + index(x, y); }
  const float* texel(int x, int y) const { return pixels.data() + index(x, y); }
};

// UV of the centre of texel (x, y) in an image of size w x h (see the convention above).
inline float texel_center_u(int x, int w) { return (static_cast<float>(x) + 0.5f) / static_cast<float>(w); }
inline float texel_center_v(int y, int h) { return 1.0f - (static_cast<float>(y) + 0.5f) / static_cast<float>(h); }

// Pixel coordinates of a UV (x right, y down; texel centres at +0.5).
inline double uv_to_pixel_x(float u, int w) { return static_cast<double>(u) * w; }
inline double uv_to_pixel_y(float v, int h) { return (1.0 - static_cast<double>(v)) * h; }

// Texels 0..n-1 whose centres (i + 0.5) lie in [a, b] (pixel units): [lo, hi], or false if
// none. Clamps in double before converting, so far-out coordinates are safe.
inline bool texel_centres_in(double a, double b, int n, int& lo, int& hi) {
  const double l = std::ceil(a - 0.5), r = std::floor(b - 0.5);
  if (!(l <= r) || r < 0 || l > n - 1) return false;  // also false for NaN
  lo = static_cast<int>(std::max(l, 0.0));
  hi = static_cast<int>(std::min(r, static_cast<double>(n - 1)));
  return true;
}

// Texels 0..n-1 whose squares [i, i+1] meet [a, b] (pixel units): [lo, hi], or false if none.
inline bool texels_touching(double a, double b, int n, int& lo, int& hi) {
  const double l = std::floor(a), r = std::floor(b);
  if (!(l <= r) || r < 0 || l > n - 1) return false;  // also false for NaN
  lo = static_cast<int>(std::max(l, 0.0));
  hi = static_cast<int>(std::min(r, static_cast<double>(n - 1)));
  return true;
}

}  // namespace meso
