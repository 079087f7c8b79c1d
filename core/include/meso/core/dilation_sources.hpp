// The nearest written texel of every texel of a grid: the one rule by which the bake's
// dilation fills the texels outside every chart (bake/dilate.hpp) and by which uvpack's
// checker predicts what those texels will hold (uv_check.hpp, mip-safe padding).
#pragma once

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

}  // namespace meso
