#include "meso/bake/uv_raster.hpp"

#include "meso/core/image.hpp"

#include <algorithm>
#include <cmath>

namespace meso {

std::vector<TexelSample> rasterize_uv(const Mesh& mesh, int width, int height) {
  std::vector<TexelSample> out(static_cast<size_t>(width) * static_cast<size_t>(height));
  for (auto f : mesh.faces()) {
    const auto hs = face_halfedges(mesh, f);
    // Pixel coordinates of the corners: x = u * W, y = (1 - v) * H, texel centres at +0.5.
    double px[3], py[3];
    for (int i = 0; i < 3; ++i) {
      const Vec2f t = mesh.texcoord2D(hs[static_cast<size_t>(i)]);
      px[i] = static_cast<double>(t[0]) * width;
      py[i] = (1.0 - static_cast<double>(t[1])) * height;
    }
    const double area = (px[1] - px[0]) * (py[2] - py[0]) - (py[1] - py[0]) * (px[2] - px[0]);
    if (!(std::abs(area) > 0)) continue;
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({px[0], px[1], px[2]}) - 0.5)));
    const int x1 = std::min(width - 1, static_cast<int>(std::ceil(std::max({px[0], px[1], px[2]}) - 0.5)));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({py[0], py[1], py[2]}) - 0.5)));
    const int y1 = std::min(height - 1, static_cast<int>(std::ceil(std::max({py[0], py[1], py[2]}) - 0.5)));
    for (int y = y0; y <= y1; ++y) {
      const double cy = y + 0.5;
      for (int x = x0; x <= x1; ++x) {
        const double cx = x + 0.5;
        // Edge functions, normalised by the signed area so they are the barycentrics.
        const double w0 = ((px[1] - cx) * (py[2] - cy) - (py[1] - cy) * (px[2] - cx)) / area;
        const double w1 = ((px[2] - cx) * (py[0] - cy) - (py[2] - cy) * (px[0] - cx)) / area;
        const double w2 = 1.0 - w0 - w1;
        if (w0 < 0 || w1 < 0 || w2 < 0) continue;
        TexelSample& s = out[static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)];
        if (s.face >= 0) continue;  // first face in face order wins: deterministic
        s.face = f.idx();
        s.bary = {static_cast<float>(w0), static_cast<float>(w1), static_cast<float>(w2)};
      }
    }
  }
  return out;
}

}  // namespace meso
