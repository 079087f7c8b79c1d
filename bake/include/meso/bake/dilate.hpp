// Dilation: texels outside every chart take the value of a nearby written texel, so that
// filtering and mip-mapping never read undefined data.
#pragma once

#include "meso/core/image.hpp"

#include <cstdint>
#include <vector>

namespace meso {

// For every texel of a width x height grid, the texel it takes its value from: itself when
// written (written[i] != 0), else a written texel at the least Euclidean distance (exact:
// Felzenszwalb & Huttenlocher's separable transform, rows then columns; among equally near
// ones the choice is fixed by that order, so the result is deterministic), or -1 when none
// lies within `radius` texels (radius < 0: no limit). Linear in the texel count whatever
// the radius.
std::vector<int32_t> dilation_sources(const std::vector<uint8_t>& written, int width, int height, int radius);

// Copies every texel's value from its source; texels without one keep their value.
void apply_dilation(Image& image, const std::vector<int32_t>& sources);

// Both in one: fills unwritten texels up to `radius` away and marks them written.
void dilate(Image& image, std::vector<uint8_t>& written, int radius);

}  // namespace meso
