// UV triangles against the texel grid: the geometry shared by the UV checker (which texels
// a triangle touches) and the baker (which surface point a texel samples). Pixel units:
// x right, y down, texel (x, y) is the square [x, x+1] x [y, y+1], centre at +0.5.
#pragma once

#include "meso/core/image.hpp"
#include "meso/core/mesh.hpp"

#include <array>

namespace meso {

struct UvTriangle {
  double px[3], py[3];  // corners in face_halfedges() order, pixel units
};

UvTriangle uv_triangle_in_pixels(const Mesh& mesh, FaceHandle f, int width, int height);

// Whether the triangle and texel (x, y) share interior points. Separating-axis test; a
// degenerate triangle touches none. (Bilinear lookups inside the triangle also read the
// ring of texels around the touched ones: see uv_check.hpp on padding.)
bool triangle_overlaps_texel(const UvTriangle& t, int x, int y);

// Calls fn(x, y) for every texel of a width x height grid the triangle touches, row by row;
// only rows [row0, row1) when given.
template <class Fn>
void for_each_touched_texel(const UvTriangle& t, int width, int height, Fn&& fn, int row0 = 0, int row1 = 1 << 30) {
  int x0, x1, y0, y1;
  if (!texels_touching(std::min({t.px[0], t.px[1], t.px[2]}), std::max({t.px[0], t.px[1], t.px[2]}), width, x0, x1)) return;
  if (!texels_touching(std::min({t.py[0], t.py[1], t.py[2]}), std::max({t.py[0], t.py[1], t.py[2]}), height, y0, y1)) return;
  y0 = std::max(y0, row0);
  y1 = std::min(y1, row1 - 1);
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x)
      if (triangle_overlaps_texel(t, x, y)) fn(x, y);
}

// Barycentric coordinates (corner order, non-negative, summing to 1) of the triangle's point
// nearest to (cx, cy). The triangle must have non-zero area.
std::array<double, 3> nearest_barycentrics(const UvTriangle& t, double cx, double cy);

}  // namespace meso
