// Dilation: texels outside every chart take the value of a nearby written texel, so that
// filtering and mip-mapping never read undefined data.
#pragma once

#include "meso/core/dilation_sources.hpp"
#include "meso/core/image.hpp"

#include <cstdint>
#include <vector>

namespace meso {

// Copies every texel's value from its source; texels without one keep their value.
void apply_dilation(Image& image, const std::vector<int32_t>& sources);

// Both in one: fills unwritten texels up to `radius` away and marks them written.
void dilate(Image& image, std::vector<uint8_t>& written, int radius);

}  // namespace meso
