// Dilation and erosion maps (Kolb and Rezk-Salama, "Efficient empty space skipping for
// per-pixel displacement mapping", VMV 2005; survey section 4.3.2): per texel, the maximum
// and the minimum of the height surface over a square neighbourhood. Together they bound a
// tangent-space axis-aligned box around every texel that holds all of the surface above
// the neighbourhood: a ray section outside every box it crosses is empty space.
#pragma once

#include "meso/streams/height_field.hpp"

namespace meso {

// Two channels, normalised heights (as HeightField::height): 0 = erosion (the minimum),
// 1 = dilation (the maximum) of the bilinearly filtered surface over the footprints of the
// (2 radius + 1)^2 texels centred on each texel, i.e. over [x - radius, x + radius + 1] x
// [y - radius, y + radius + 1] in pixel units (texel x covers [x, x + 1]). Exact, not
// sampled: the extremes of footprint_min_max (pyramid.hpp) taken over the window. Under
// Border::wrap the window wraps around the map; under Border::clamp it is cut at the map's
// edges (the surface has no texels beyond them). radius 0 gives footprint_min_max itself.
// Cost: O(texels), independent of the radius (a separable running min/max: rows, then
// columns), parallel over rows and columns; deterministic. Throws std::invalid_argument
// for a negative radius.
Image dilation_erosion_map(const HeightField& field, int radius);

}  // namespace meso
