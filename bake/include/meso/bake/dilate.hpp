// Dilation: texels outside every chart take the value of a nearby written texel, so that
// filtering and mip-mapping never read undefined data.
#pragma once

#include "meso/core/image.hpp"

#include <cstdint>
#include <vector>

namespace meso {

// Fills unwritten texels (written[i] == 0) up to `radius` texels away (radius < 0: all),
// each from the written texel reached first by a breadth-first search over 8-connected
// neighbours seeded with every written texel in row-major order: a nearest written texel
// in the chessboard metric, ties broken by that order, so the result is deterministic.
// Cost is linear in the texel count whatever the radius. Marks filled texels as written.
void dilate(Image& image, std::vector<uint8_t>& written, int radius);

}  // namespace meso
