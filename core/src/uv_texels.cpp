#include "meso/core/uv_texels.hpp"

#include <algorithm>
#include <cmath>

namespace meso {

UvTriangle uv_triangle_in_pixels(const Mesh& mesh, FaceHandle f, int width, int height) {
  UvTriangle t;
  const auto hs = face_halfedges(mesh, f);
  for (int i = 0; i < 3; ++i) {
    const Vec2f uv = mesh.texcoord2D(hs[static_cast<size_t>(i)]);
    t.px[i] = uv_to_pixel_x(uv[0], width);
    t.py[i] = uv_to_pixel_y(uv[1], height);
  }
  return t;
}

bool triangle_overlaps_texel(const UvTriangle& t, int x, int y, double grow) {
  const double x0 = x - grow, y0 = y - grow, x1 = x + 1.0 + grow, y1 = y + 1.0 + grow;
  const double* px = t.px;
  const double* py = t.py;
  if (std::max({px[0], px[1], px[2]}) <= x0 || std::min({px[0], px[1], px[2]}) >= x1) return false;
  if (std::max({py[0], py[1], py[2]}) <= y0 || std::min({py[0], py[1], py[2]}) >= y1) return false;
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    // Edge normal, oriented toward the third corner.
    double nx = py[j] - py[i], ny = px[i] - px[j];
    const double side_k = nx * (px[k] - px[i]) + ny * (py[k] - py[i]);
    if (side_k == 0) return false;  // degenerate
    if (side_k < 0) {
      nx = -nx;
      ny = -ny;
    }
    // The square's farthest corner along the normal must lie strictly inside the edge's side.
    const double bx = nx > 0 ? x1 : x0, by = ny > 0 ? y1 : y0;
    if (nx * (bx - px[i]) + ny * (by - py[i]) <= 0) return false;
  }
  return true;
}

std::array<double, 3> nearest_barycentrics(const UvTriangle& t, double cx, double cy) {
  const double area = (t.px[1] - t.px[0]) * (t.py[2] - t.py[0]) - (t.py[1] - t.py[0]) * (t.px[2] - t.px[0]);
  std::array<double, 3> w;
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    w[static_cast<size_t>(i)] = ((t.px[j] - cx) * (t.py[k] - cy) - (t.py[j] - cy) * (t.px[k] - cx)) / area;
  }
  if (w[0] >= 0 && w[1] >= 0 && w[2] >= 0) return w;  // inside
  // Outside: the nearest point lies on an edge; take the closest of the three projections.
  double best = INFINITY;
  std::array<double, 3> out{1, 0, 0};
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    const double ex = t.px[j] - t.px[i], ey = t.py[j] - t.py[i];
    const double len2 = ex * ex + ey * ey;
    const double s = len2 > 0 ? std::clamp(((cx - t.px[i]) * ex + (cy - t.py[i]) * ey) / len2, 0.0, 1.0) : 0.0;
    const double qx = t.px[i] + s * ex - cx, qy = t.py[i] + s * ey - cy;
    const double d = qx * qx + qy * qy;
    if (d < best) {
      best = d;
      out = {0, 0, 0};
      out[static_cast<size_t>(i)] = 1 - s;
      out[static_cast<size_t>(j)] = s;
    }
  }
  return out;
}

}  // namespace meso
