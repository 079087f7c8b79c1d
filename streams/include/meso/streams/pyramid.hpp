// Min-max height pyramid (survey section 4.3.3, pyramidal displacement mapping; the
// depth-interval-grid paper's interval bounds): per texel of every mip level, the exact
// minimum and maximum of the bilinearly filtered height surface over that texel's footprint.
#pragma once

#include "meso/streams/height_field.hpp"
#include "meso/streams/height_ray.hpp"

#include <vector>

namespace meso {

struct MinMaxPyramid {
  // levels[0] has the height field's size; level k+1 has max(1, floor(n_k / 2)) texels per
  // side (OpenGL's mip sizes). Two channels: 0 = minimum, 1 = maximum, normalised heights.
  std::vector<Image> levels;
};

// Footprint semantics: texel x of a level with n texels covers u in [x/n, (x+1)/n]. The
// filtered surface over a level-0 texel is bilinear on four sub-rectangles split at the texel
// centre, so its extremes lie on the 9 points {0, 1/2, 1} x {0, 1/2, 1} of the texel
// (centre, edge midpoints, corners), evaluated with the field's border rule. A coarser
// texel takes the min/max over every finer texel whose footprint overlaps its own, so each
// level bounds the surface exactly and conservatively whatever the sizes (powers of two
// or not). Cost: O(texels), parallel over rows; deterministic.
MinMaxPyramid build_min_max_pyramid(const HeightField& field);

// The coarser levels of a pyramid from its level 0 (footprint_min_max's image, or level 0 of
// pyramid.exr as read back), exactly as build_min_max_pyramid makes them.
MinMaxPyramid min_max_pyramid_from_level0(Image level0);

// Level 0 alone: per texel, the exact min (channel 0) and max (channel 1) of the filtered
// surface over the texel's footprint.
Image footprint_min_max(const HeightField& field);

// Rounds a min-max image (channel 0 = minimum, channel 1 = maximum, as the pyramid's levels
// and dilation_erosion's map) outward to values a half float holds: minima down, maxima up,
// so that a file written with --half stays conservative (writing rounds to nearest, which put
// a maximum of 1/3 at 0.333252, under the surface).
void round_min_max_to_half(Image& min_max);

// Reference CPU tracer of the max pyramid (pyramidal displacement mapping, survey 4.3.3):
// descends the quadtree front to back along the ray, skipping every texel whose box
// [footprint] x [0, max] the ray misses, and intersects S exactly inside level-0 footprints
// (intersect_footprint). Finds the first intersection (up to rounding); units as in
// height_ray.hpp. Bent rays (ddz != 0) are exact too: a node is skipped when the lowest
// point of the ray over it is above its maximum. Under Border::clamp a ray leaving
// [0, W] x [0, H] misses; under Border::wrap it goes on through the neighbouring tiles.
// The ray is followed from where it comes down to S's highest point until it reaches S's
// lowest (the hit is there at the latest) or, bent upward, rises back above the highest
// (then it has left the height field: no hit); over a flat map nothing is walked, whatever
// relief. `steps` counts the texels visited.
HeightHit trace_min_max_pyramid(const HeightField& field, const MinMaxPyramid& pyramid, const HeightRay& ray);

}  // namespace meso
