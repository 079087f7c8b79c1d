// uvpack check: is the UV mapping unique at a given texture resolution? (Course notes,
// "Unique Texture Mapping" and "Unique Mapping Checker".)
#pragma once

#include "meso/core/image.hpp"
#include "meso/core/mesh.hpp"
#include "meso/uvpack/uv_overlaps.hpp"

#include <cstddef>
#include <utility>
#include <vector>

namespace meso {

struct UvCheckOptions {
  int size = 1024;       // texels per side of the square texture
  double padding = 0.0;  // texels charts must keep between them (0: no padding check)
  bool overlay = true;   // make the overlay image (size^2 RGBA floats)
};

// Texels per object-space unit of one chart: sqrt(UV area in texels^2 / surface area).
struct ChartDensity {
  int chart = 0;
  double texels_per_unit = 0;
};

struct UvCheckReport {
  int width = 0, height = 0;
  size_t charts = 0;                   // UV-connected components (faces sharing UVs across an edge)
  // Exact and resolution-independent: faces whose UV interiors overlap another face's
  // (uv_overlaps.hpp), and the pairs. Sorted.
  std::vector<int> overlapping_faces;
  std::vector<std::pair<int, int>> overlap_pairs;
  // At this resolution: faces touching a texel that another chart also touches (bilinear
  // filtering would mix the charts there). Sorted.
  std::vector<int> shared_texel_faces;
  std::vector<int> flipped_faces;      // UV winding against the majority (by area) of their chart; sorted
  std::vector<int> degenerate_faces;   // zero UV area; sorted
  std::vector<int> outside_faces;      // a UV outside [0,1]; sorted
  std::vector<ChartGap> padding_violations;  // chart pairs closer than options.padding texels
  std::vector<ChartDensity> texel_density;   // per chart with surface area
  size_t texels_touched = 0;           // texels touched by at least one face
  size_t texels_shared = 0;            // texels touched by two or more charts
  double utilization = 0;              // texels_touched / all texels
  // RGBA overlay, [0,1]: opaque red where charts share a texel, translucent blue where one
  // chart touches it, transparent elsewhere.
  Image overlay;
};

// Conservative rasterisation: a texel is touched by a face when the face's UV triangle and
// the texel's square share interior points. Bilinear filtering of a chart also reads one
// more ring of texels around those, so charts that must not mix under filtering need
// --padding of at least 1 texel (2 with the bake's dilation), which the padding check verifies.
// Face indices are 0-based in the mesh's face order (the input file's order). Requires UVs
// and a compacted mesh (no deleted elements), as read_mesh() and reduce_mesh() return.
UvCheckReport check_uv_mapping(const Mesh& mesh, const UvCheckOptions& options);

}  // namespace meso
