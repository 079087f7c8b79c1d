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
  std::vector<float> pixels;  // width * height * channels, row-major, top row first
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

}  // namespace meso
