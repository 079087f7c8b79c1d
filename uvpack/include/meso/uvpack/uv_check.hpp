// uvpack check: is the UV mapping unique at a given texture resolution? (Course notes,
// "Unique Texture Mapping" and "Unique Mapping Checker".)
#pragma once

#include "meso/core/image.hpp"
#include "meso/core/mesh.hpp"

#include <cstddef>
#include <vector>

namespace meso {

struct UvCheckOptions {
  int size = 1024;  // texels per side of the square texture
};

struct UvCheckReport {
  int width = 0, height = 0;
  size_t charts = 0;                   // UV-connected components (faces sharing UVs across an edge)
  std::vector<int> overlapping_faces;  // faces touching a texel that another chart also touches; sorted
  std::vector<int> degenerate_faces;   // zero UV area; sorted
  std::vector<int> outside_faces;      // a UV outside [0,1]; sorted
  size_t texels_touched = 0;           // texels touched by at least one face
  size_t texels_shared = 0;            // texels touched by two or more charts
  double utilization = 0;              // texels_touched / all texels
  // RGBA overlay, [0,1]: opaque red where charts share a texel, translucent blue where one
  // chart touches it, transparent elsewhere.
  Image overlay;
};

// Conservative rasterisation: a texel is touched by a face when the face's UV triangle and
// the texel's square share interior points (bilinear filtering reads every such texel).
// Face indices are 0-based in the mesh's face order (the input file's order). Requires UVs
// and a compacted mesh (no deleted elements), as read_mesh() and reduce_mesh() return.
UvCheckReport check_uv_mapping(const Mesh& mesh, const UvCheckOptions& options);

// Charts: faces connected through edges whose two sides carry the same UVs. Returns a chart
// index per face, numbered by first face in face order; `count` receives the number.
std::vector<int> uv_charts(const Mesh& mesh, size_t* count = nullptr);

}  // namespace meso
