#include "meso/streams/height_field.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>
#include <variant>

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

namespace {
// A numeric attribute (EXR stores floats; PNG text chunks bring them back as text), or NaN.
float metadata_number(const ImageMetadata& m, const char* key) {
  const auto it = m.find(key);
  if (it == m.end()) return std::nanf("");
  if (const float* f = std::get_if<float>(&it->second)) return *f;
  if (const int* i = std::get_if<int>(&it->second)) return static_cast<float>(*i);
  const std::string& text = std::get<std::string>(it->second);
  char* end = nullptr;
  const float v = std::strtof(text.c_str(), &end);
  return end != text.c_str() && *end == '\0' ? v : std::nanf("");
}
}  // namespace

std::string height_mapping_problem(const ImageMetadata& metadata) {
  const bool has_scale = metadata.count("height_scale") > 0, has_bias = metadata.count("height_bias") > 0;
  if (!has_scale && !has_bias) return "";
  if (has_scale != has_bias) return std::string("its meso:") + (has_scale ? "height_scale" : "height_bias") + " comes without meso:" + (has_scale ? "height_bias" : "height_scale");
  const float scale = metadata_number(metadata, "height_scale"), bias = metadata_number(metadata, "height_bias");
  if (!(std::isfinite(scale) && scale >= 0)) return "its meso:height_scale is not a finite number >= 0";
  if (!std::isfinite(bias)) return "its meso:height_bias is not a finite number";
  // A mapping whose range float cannot hold: bias + scale overflows, or the scale is lost in
  // the bias (a bias of 3e38 had flattened every height to one value without a word).
  if (!std::isfinite(bias + scale)) return "its meso:height_bias + meso:height_scale overflows a float";
  if (scale > 0 && bias + scale == bias) return "its meso:height_scale is below a float step at its meso:height_bias";
  return "";
}

namespace {
// The map's recorded mapping to object units (object = bias + scale * value), when usable.
bool recorded_mapping(const ImageMetadata& metadata, float& scale, float& bias) {
  scale = metadata_number(metadata, "height_scale");
  bias = metadata_number(metadata, "height_bias");
  return std::isfinite(scale) && std::isfinite(bias) && scale >= 0;
}
}  // namespace

Image heights_in_object_units(Image image) {
  float scale = 0, bias = 0;
  if (!recorded_mapping(image.metadata, scale, bias)) return image;
  for (size_t i = 0; i < image.pixels.size(); i += static_cast<size_t>(image.channels)) image.pixels[i] = bias + scale * image.pixels[i];
  image.metadata.erase("height_scale");
  image.metadata.erase("height_bias");
  return image;
}

HeightField make_height_field(const Image& image, Border border) {
  HeightField hf;
  hf.border = border;
  hf.height = Image(image.width, image.height, 1);
  // A map that records its own mapping to object units (bake's displacement.png, a stream)
  // holds bias + scale * value: taken back to object units first, so that its stream has the
  // height range of the displacement.exr it came from.
  float in_scale = 0, in_bias = 0;
  const bool mapped = recorded_mapping(image.metadata, in_scale, in_bias);  // as heights_in_object_units
  const auto value = [&](size_t i) {
    const float v = image.pixels[i * static_cast<size_t>(image.channels)];
    return mapped ? in_bias + in_scale * v : v;
  };
  float lo = image.pixels.empty() ? 0.0f : value(0), hi = lo;
  for (size_t i = 0; i < image.texel_count(); ++i) {
    lo = std::min(lo, value(i));
    hi = std::max(hi, value(i));
  }
  hf.bias = lo;
  hf.scale = hi - lo;
  for (size_t i = 0; i < image.texel_count(); ++i)
    hf.height.pixels[i] = hf.scale > 0 ? std::clamp((value(i) - lo) / hf.scale, 0.0f, 1.0f) : 0.0f;
  return hf;
}

}  // namespace meso
