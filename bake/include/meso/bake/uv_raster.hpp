// Which base-mesh point each texel samples: the texel centre located in the mesh's UV
// layout (see image.hpp for the texel/UV convention).
#pragma once

#include "meso/core/huge_pages.hpp"
#include "meso/core/mesh.hpp"

#include <array>
#include <cstdint>
#include <vector>

namespace meso {

struct TexelSample {
  int32_t face = -1;                   // -1: no triangle touches this texel
  std::array<float, 3> bary{0, 0, 0};  // weights of the face's corners, face_halfedges() order
  bool centre_inside = false;          // the texel centre lies in the face (else: border texel)
};

// For every texel of a width x height image, the base-surface point it samples:
//  1. the first face (in face order) whose UV triangle contains the texel centre, edges
//     included, at the centre's barycentric coordinates;
//  2. for a texel no centre test claimed but whose square some face touches (a chart's
//     border, or a triangle smaller than a texel), the first such face, at its point
//     nearest to the texel centre. So every texel a chart touches holds that chart's data,
//     whatever the share of the texel the triangle covers; the ring beyond, which bilinear
//     lookups at the chart's edge also read, is filled by dilation.
// Faces with zero UV area cover nothing. Row-major, top row first.
LargeVector<TexelSample> rasterize_uv(const Mesh& mesh, int width, int height);

// The same rules, a band of rows at a time: the faces' UV triangles are prepared once, and
// rows(y0, y1) returns rows [y0, y1) of rasterize_uv's result (row-major, y0 first) without
// the memory of the whole image (supersampled bakes rasterise at K times the resolution).
// Thread-safe: rows() only reads.
class UvRasterizer {
 public:
  UvRasterizer(const Mesh& mesh, int width, int height);
  std::vector<TexelSample> rows(int y0, int y1) const;
  // rows(y0, y1) written to out[0 .. (y1 - y0) * width) instead, which must hold default
  // TexelSamples (no copy of the band).
  void rows_into(int y0, int y1, TexelSample* out) const;

 private:
  struct Face {
    int index;
    double px[3], py[3], area;
    double x_min, x_max, y_min, y_max;  // pixel bounds of the UV triangle
  };
  int width_, height_;
  std::vector<Face> faces_;  // faces with UV area, in face order
};

}  // namespace meso
