#include "meso/bake/uv_raster.hpp"

#include "meso/core/uv_texels.hpp"

#include <algorithm>
#include <cmath>

namespace meso {

std::vector<TexelSample> rasterize_uv(const Mesh& mesh, int width, int height) {
  std::vector<TexelSample> out(static_cast<size_t>(width) * static_cast<size_t>(height));
  auto at = [&](int x, int y) -> TexelSample& {
    return out[static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)];
  };
  // Pass 1: texel centres inside a face.
  for (auto f : mesh.faces()) {
    // A face with no UV area covers nothing (the same rule as uvpack's degenerate faces).
    if (uv_double_area(mesh, f) == 0.0f) continue;
    const UvTriangle t = uv_triangle_in_pixels(mesh, f, width, height);
    const double* px = t.px;
    const double* py = t.py;
    const double area = (px[1] - px[0]) * (py[2] - py[0]) - (py[1] - py[0]) * (px[2] - px[0]);
    if (!(std::abs(area) > 0)) continue;
    int x0, x1, y0, y1;
    if (!texel_centres_in(std::min({px[0], px[1], px[2]}), std::max({px[0], px[1], px[2]}), width, x0, x1)) continue;
    if (!texel_centres_in(std::min({py[0], py[1], py[2]}), std::max({py[0], py[1], py[2]}), height, y0, y1)) continue;
    // A centre exactly on an edge shared by two faces must be taken by one of them: each
    // barycentric is computed from its own edge function and accepted down to -kTie (far
    // below a texel, far above rounding), then clamped; the first face in order wins.
    constexpr double kTie = 1e-9;
    for (int y = y0; y <= y1; ++y) {
      const double cy = y + 0.5;
      for (int x = x0; x <= x1; ++x) {
        const double cx = x + 0.5;
        const double w0 = ((px[1] - cx) * (py[2] - cy) - (py[1] - cy) * (px[2] - cx)) / area;
        const double w1 = ((px[2] - cx) * (py[0] - cy) - (py[2] - cy) * (px[0] - cx)) / area;
        const double w2 = ((px[0] - cx) * (py[1] - cy) - (py[0] - cy) * (px[1] - cx)) / area;
        if (w0 < -kTie || w1 < -kTie || w2 < -kTie) continue;
        TexelSample& s = at(x, y);
        if (s.face >= 0) continue;  // first face in face order wins: deterministic
        const double c0 = std::max(w0, 0.0), c1 = std::max(w1, 0.0), c2 = std::max(w2, 0.0), sum = c0 + c1 + c2;
        s.face = f.idx();
        s.bary = {static_cast<float>(c0 / sum), static_cast<float>(c1 / sum), static_cast<float>(c2 / sum)};
        s.centre_inside = true;
      }
    }
  }
  // Pass 2: texels a face touches whose centre no face contains.
  for (auto f : mesh.faces()) {
    if (uv_double_area(mesh, f) == 0.0f) continue;
    const UvTriangle t = uv_triangle_in_pixels(mesh, f, width, height);
    const double area = (t.px[1] - t.px[0]) * (t.py[2] - t.py[0]) - (t.py[1] - t.py[0]) * (t.px[2] - t.px[0]);
    if (!(std::abs(area) > 0)) continue;  // as in pass 1: no barycentrics without area
    for_each_touched_texel(t, width, height, [&](int x, int y) {
      TexelSample& s = at(x, y);
      if (s.face >= 0) return;
      const auto b = nearest_barycentrics(t, x + 0.5, y + 0.5);
      s.face = f.idx();
      s.bary = {static_cast<float>(b[0]), static_cast<float>(b[1]), static_cast<float>(b[2])};
    });
  }
  return out;
}

}  // namespace meso
