// Dilation: texels outside every chart take the value of a nearby written texel, so that
// filtering and mip-mapping never read undefined data.
#pragma once

#include "meso/core/image.hpp"

#include <cstdint>
#include <vector>

namespace meso {

// For every texel of a width x height grid, the texel it takes its value from: itself when
// written (written[i] != 0), else the written texel reached first by a breadth-first search
// over 8-connected neighbours seeded with every written texel in row-major order (a nearest
// written texel in the chessboard metric, ties broken by that order: deterministic), or -1
// when none lies within `radius` texels (radius < 0: no limit). Linear in the texel count
// whatever the radius.
std::vector<int32_t> dilation_sources(const std::vector<uint8_t>& written, int width, int height, int radius);

// Copies every texel's value from its source; texels without one keep their value.
void apply_dilation(Image& image, const std::vector<int32_t>& sources);

// Both in one: fills unwritten texels up to `radius` away and marks them written.
void dilate(Image& image, std::vector<uint8_t>& written, int radius);

}  // namespace meso
