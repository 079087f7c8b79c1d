// Which base-mesh point each texel samples: the texel centre located in the mesh's UV
// layout (see image.hpp for the texel/UV convention).
#pragma once

#include "meso/core/mesh.hpp"

#include <array>
#include <cstdint>
#include <vector>

namespace meso {

struct TexelSample {
  int32_t face = -1;                   // -1: no triangle covers this texel centre
  std::array<float, 3> bary{0, 0, 0};  // weights of the face's corners, face_halfedges() order
};

// For every texel of a width x height image, the first face (in face order) whose UV
// triangle contains the texel centre, edges included, and the centre's barycentric
// coordinates in it. Faces with zero UV area cover nothing. Row-major, top row first.
std::vector<TexelSample> rasterize_uv(const Mesh& mesh, int width, int height);

}  // namespace meso
