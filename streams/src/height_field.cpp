#include "meso/streams/height_field.hpp"

#include <algorithm>
#include <cmath>

namespace meso {

const char* border_name(Border b) { return b == Border::wrap ? "wrap" : "clamp"; }

namespace {
int address(int i, int n, Border b) {
  if (b == Border::wrap) return ((i % n) + n) % n;
  return std::clamp(i, 0, n - 1);
}
}  // namespace

float HeightField::texel(int x, int y) const {
  return height.at(address(x, height.width, border), address(y, height.height, border));
}

float HeightField::bilinear(double px, double py) const {
  const double fx = px - 0.5, fy = py - 0.5;
  const double x0 = std::floor(fx), y0 = std::floor(fy);
  const float tx = static_cast<float>(fx - x0), ty = static_cast<float>(fy - y0);
  const int ix = static_cast<int>(x0), iy = static_cast<int>(y0);
  const float a = texel(ix, iy), b = texel(ix + 1, iy), c = texel(ix, iy + 1), d = texel(ix + 1, iy + 1);
  return bilinear_blend(a, b, c, d, tx, ty);
}

ImageMetadata height_field_metadata(const HeightField& field) {
  return {{"height_scale", field.scale},
          {"height_bias", field.bias},
          {"height_units", std::string("normalised: object = bias + scale * value")},
          {"border", std::string(border_name(field.border))}};
}

HeightField make_height_field(const Image& image, Border border) {
  HeightField hf;
  hf.border = border;
  hf.height = Image(image.width, image.height, 1);
  float lo = image.pixels.empty() ? 0.0f : image.pixels[0], hi = lo;
  for (size_t i = 0; i < image.texel_count(); ++i) {
    const float v = image.pixels[i * static_cast<size_t>(image.channels)];
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  hf.bias = lo;
  hf.scale = hi - lo;
  for (size_t i = 0; i < image.texel_count(); ++i) {
    const float v = image.pixels[i * static_cast<size_t>(image.channels)];
    hf.height.pixels[i] = hf.scale > 0 ? std::clamp((v - lo) / hf.scale, 0.0f, 1.0f) : 0.0f;
  }
  return hf;
}

}  // namespace meso
