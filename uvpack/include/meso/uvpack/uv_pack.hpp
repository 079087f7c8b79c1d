// uvpack pack: place a mesh's UV charts into a square atlas with padding (course notes,
// "Unique Mapping Packer"), the way xatlas does: rasterised chart footprints dilated by the
// padding, four orientations, placement by bitmap search, largest chart first.
#pragma once

#include "meso/core/mesh.hpp"

#include <cstddef>

namespace meso {

struct UvPackOptions {
  int size = 1024;     // texels per side of the atlas
  int padding = 2;     // texels kept between charts (and to the atlas border: half of it)
  bool rotate = true;  // try 0, 90, 180 and 270 degrees per chart
};

struct UvPackReport {
  size_t charts = 0;
  double scale = 0;           // texels per unit of the input UVs (one scale for every chart)
  double utilization = 0;     // texels touched by charts / all texels
  int attempts = 0;           // packings tried while searching the scale
};

// Moves every chart (uv_charts) rigidly: rotation by a multiple of 90 degrees, one common
// scale (relative chart sizes are kept), translation to integer texel offsets. Guarantees,
// at options.size: no texel is touched (conservatively: the triangle meets its square) by
// two charts, and touched texels of different charts are at least `padding` texels apart
// (Chebyshev, hence also Euclidean) and at least padding / 2 from the atlas border. The
// scale is the largest (within 1 %) for which the greedy placement succeeds. Charts with
// no UV area keep a single texel. Deterministic. Requires UVs; throws InputError-free
// std::invalid_argument when the charts cannot fit even at the smallest scale tried.
UvPackReport pack_uv_charts(Mesh& mesh, const UvPackOptions& options);

}  // namespace meso
