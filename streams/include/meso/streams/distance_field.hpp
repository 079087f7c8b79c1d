// 3D distance field over a height field, for sphere tracing (survey section 4.3.4; Donnelly,
// "Per-Pixel Displacement Mapping with Distance Functions", GPU Gems 2).
#pragma once

#include "meso/core/huge_pages.hpp"
#include "meso/core/progress.hpp"
#include "meso/streams/height_field.hpp"

#include <vector>

namespace meso {

struct DistanceFieldOptions {
  int depth = 32;  // slices along the height axis
  // The height range expressed in the units of u: the box over the map is 1 wide, H/W deep
  // and `relief` high. It fixes the anisotropy between texel size and slice spacing.
  float relief = 0.1f;
};

// Voxel (x, y, k) has its centre at u = (x+0.5)/W, v-row (y+0.5)/H, normalised height
// (k+0.5)/D. Its value is the Euclidean distance, in units of u (fractions of the map's
// width), from that centre to the solid S' = union over texels of the box
// [texel footprint] x [0, M], where M is the maximum of the bilinearly filtered surface over
// the footprint (the pyramid's level-0 maximum). S' contains everything below the filtered
// surface, so the value never exceeds the distance to it: a sphere of that radius around the
// voxel centre is empty (0 inside S'). With Border::wrap the map is taken as one tile of a
// periodic surface, and boxes of the neighbouring tiles count too. Exact: computed as the
// lower envelope of parabolas (Felzenszwalb & Huttenlocher 2012) over the texel edges and the
// query's own texel centre, where every nearest point of a box to a texel centre lies;
// O(W H D), parallel over slices, deterministic.
struct DistanceField {
  int width = 0, height = 0, depth = 0;
  float relief = 0.1f;
  // (k * height + y) * width + x, units of u. In 2 MiB pages (core/huge_pages.hpp): at
  // 1024² x 32 the page faults of 4 KiB pages were 14 % of the build.
  LargeVector<float> distance;
  float at(int x, int y, int k) const {
    return distance[(static_cast<size_t>(k) * static_cast<size_t>(height) + static_cast<size_t>(y)) * static_cast<size_t>(width) +
                    static_cast<size_t>(x)];
  }
};

// `progress` counts slices as they are done.
DistanceField build_distance_field(const HeightField& field, const DistanceFieldOptions& options, Progress& progress = null_progress());

// The field as one image, as `meso streams sdf` writes it: width W, height H * D, slice k in
// rows [k H, (k+1) H), slice 0 the lowest, one channel; metadata: the height field's
// (height_field_metadata) plus depth, relief, quantity, channels, layout. Takes the field's
// buffer (the layout is the same): pass std::move(field) to avoid a copy of it.
Image distance_field_image(DistanceField field, const HeightField& source);

// Rounds every distance of such an image down to a value a half float holds, saturating at
// 65504, so that a file written with --half keeps its spheres empty (the writer rounds to
// nearest, half the time up, and overflows to Inf above 65504).
void round_distances_to_half(Image& distance_field);

}  // namespace meso
