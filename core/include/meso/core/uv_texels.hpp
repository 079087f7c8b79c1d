// UV triangles against the texel grid: the geometry shared by the UV checker (which texels
// a triangle touches) and the baker (which surface point a texel samples). Pixel units:
// x right, y down, texel (x, y) is the square [x, x+1] x [y, y+1], centre at +0.5.
#pragma once

#include "meso/core/image.hpp"
#include "meso/core/mesh.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace meso {

struct UvTriangle {
  double px[3], py[3];  // corners in face_halfedges() order, pixel units
};

UvTriangle uv_triangle_in_pixels(const Mesh& mesh, FaceHandle f, int width, int height);

// Whether the triangle and texel (x, y) share interior points. Separating-axis test; a
// degenerate triangle touches none. (Bilinear lookups inside the triangle also read the
// ring of texels around the touched ones: see uv_check.hpp on padding.) With grow > 0 the
// texel's square is taken `grow` pixels larger on every side, [x - grow, x + 1 + grow]: then
// it also holds every texel a non-degenerate triangle could touch once its corners move by up
// to `grow` in x and y (the moved triangle stays within that distance of the original, per
// axis), as rounding the corners to float does.
bool triangle_overlaps_texel(const UvTriangle& t, int x, int y, double grow = 0);

// Whether the triangle is degenerate in pixel units as the rasteriser computes it (a corner on
// the opposite edge's line): such a triangle touches no texel. A UV triangle of nonzero area
// can be degenerate here when it is thinner than double arithmetic resolves at this size
// (about 1e-16 of the texture: a v of 1e-20 is 1 - v = 1).
inline bool degenerate_in_pixels(const UvTriangle& t) {
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    if ((t.py[j] - t.py[i]) * (t.px[k] - t.px[i]) + (t.px[i] - t.px[j]) * (t.py[k] - t.py[i]) == 0) return true;
  }
  return false;
}

// Calls fn(x, y) for every texel of a width x height grid the triangle touches, row by row;
// only rows [row0, row1) when given. `grow` (below 1) as triangle_overlaps_texel's.
template <class Fn>
void for_each_touched_texel(const UvTriangle& t, int width, int height, Fn&& fn, int row0 = 0, int row1 = 1 << 30, double grow = 0) {
  int x0, x1, y0, y1;
  if (!texels_touching(std::min({t.px[0], t.px[1], t.px[2]}) - grow, std::max({t.px[0], t.px[1], t.px[2]}) + grow, width, x0, x1)) return;
  if (!texels_touching(std::min({t.py[0], t.py[1], t.py[2]}) - grow, std::max({t.py[0], t.py[1], t.py[2]}) + grow, height, y0, y1)) return;
  y0 = std::max(y0, row0);
  y1 = std::min(y1, row1 - 1);
  // A degenerate triangle touches nothing: the separating-axis test rejects every texel when
  // any corner lies on the opposite edge's line (computed as it computes it).
  if (degenerate_in_pixels(t)) return;
  const double ymin = std::min({t.py[0], t.py[1], t.py[2]}), ymax = std::max({t.py[0], t.py[1], t.py[2]});
  for (int y = y0; y <= y1; ++y) {
    const double strip0 = y - grow, strip1 = y + 1.0 + grow;  // the row's (grown) squares
    if (ymax <= strip0 || ymin >= strip1) continue;  // as the test's first rejection
    // The triangle's x-extent [a, b] within the row's strip [y, y+1] (grown). Its interior
    // inside the open strip is convex with that x-projection, so a texel whose x-interval lies
    // strictly inside it is touched, and one wholly outside it is not. Texels more than one
    // texel inside are reported without a test, those more than one outside skipped (the
    // margin absorbs rounding); the few in between get the separating-axis test, so the
    // result is the test's, texel for texel, at a cost per row instead of per texel.
    double a = INFINITY, b = -INFINITY;
    for (int i = 0; i < 3; ++i) {
      const int j = (i + 1) % 3;
      if (t.py[i] >= strip0 && t.py[i] <= strip1) {
        a = std::min(a, t.px[i]);
        b = std::max(b, t.px[i]);
      }
      const double dy = t.py[j] - t.py[i];
      if (dy == 0) continue;
      for (const double line : {strip0, strip1}) {
        const double s = (line - t.py[i]) / dy;
        if (s < 0 || s > 1) continue;
        const double x = t.px[i] + s * (t.px[j] - t.px[i]);
        a = std::min(a, x);
        b = std::max(b, x);
      }
    }
    int lo = x0, hi = x1, sure0 = 1, sure1 = 0;
    if (a < b) {
      // Clamped near the texel range in double before converting: a corner 2^31 texels out
      // would overflow int (the row had then touched nothing). The clamp changes no result:
      // a below x0 - 2 leaves every texel from x0 on past the margin, as x0 - 2 does.
      const int fa = static_cast<int>(std::clamp(std::floor(a), x0 - 2.0, x1 + 2.0));
      const int cb = static_cast<int>(std::clamp(std::ceil(b), x0 - 2.0, x1 + 3.0));
      lo = std::max(x0, fa - 1);
      hi = std::min(x1, cb);
      sure0 = fa + 2;
      sure1 = cb - 3;
    }
    for (int x = lo; x <= hi; ++x)
      if ((x >= sure0 && x <= sure1) || triangle_overlaps_texel(t, x, y, grow)) fn(x, y);
  }
}

// Barycentric coordinates (corner order, non-negative, summing to 1) of the triangle's point
// nearest to (cx, cy). The triangle must have non-zero area.
std::array<double, 3> nearest_barycentrics(const UvTriangle& t, double cx, double cy);

}  // namespace meso
