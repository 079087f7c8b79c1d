// The height field that every stream is computed from (survey section 4, "normalized
// tangent space"): heights normalised to [0, 1], with the map back to object units.
#pragma once

#include "meso/core/image.hpp"

#include <string>

namespace meso {

// How a lookup outside [0,1]^2 behaves: clamp to the edge texel (GL_CLAMP_TO_EDGE) or
// repeat (a tiling map, GL_REPEAT). Streams and shaders must agree on it.
enum class Border { clamp, wrap };

const char* border_name(Border b);

struct HeightField {
  Image height;        // 1 channel, normalised heights in [0, 1]; 1 = the outermost (highest) point
  float scale = 1.0f;  // object units = bias + scale * normalised height
  float bias = 0.0f;
  Border border = Border::clamp;

  int width() const { return height.width; }
  int texel_count() const { return height.width * height.height; }
  // The texel at integer coordinates after applying the border rule.
  float texel(int x, int y) const;
  // The bilinearly filtered surface at pixel coordinates (px, py) (texel centres at +0.5),
  // as GL_LINEAR samples it.
  float bilinear(double px, double py) const;
};

// GL_LINEAR's blend of texels a (x0, y0), b (x0 + 1, y0), c (x0, y0 + 1), d (x0 + 1, y0 + 1)
// at fractions (tx, ty), in float as HeightField::bilinear computes it.
inline float bilinear_blend(float a, float b, float c, float d, float tx, float ty) {
  return (a * (1 - tx) + b * tx) * (1 - ty) + (c * (1 - tx) + d * tx) * ty;
}

// Takes channel 0 of `image` (a baked displacement.exr in object units, or any grey height
// map) and normalises it: bias = its minimum, scale = max - min (0 for a flat map, whose
// normalised heights are all 0). A map whose metadata gives height_scale and height_bias
// (bake's displacement.png: object = bias + scale * value) is taken back to object units
// first (a broken pair, see height_mapping_problem, is ignored here).
HeightField make_height_field(const Image& image, Border border);

// What is wrong with the map's own mapping to object units, or "" when it has none or a
// usable one: a height_scale or height_bias that is present but not a finite number (and a
// scale >= 0), one given without the other, or a pair whose range float cannot hold (bias +
// scale overflows, or a nonzero scale below a float step at the bias). For a loader to refuse such a map, which
// make_height_field would otherwise take as raw values.
std::string height_mapping_problem(const ImageMetadata& metadata);

// Channel 0 of `image` in object units: through the map's own mapping (bias + scale * value)
// when it records a usable one, as make_height_field takes it; else as it is. The other
// channels are left alone.
Image heights_in_object_units(Image image);

// The header attributes every stream file carries about its height field: height_scale,
// height_bias, height_units, border (docs/formats.md).
ImageMetadata height_field_metadata(const HeightField& field);

}  // namespace meso
