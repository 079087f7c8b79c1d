// CPU mirrors of what the preview shaders' texture units do, for the reference renderer.
#pragma once

#include "meso/preview/preview.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace meso {

// Whether the height and normal maps repeat (GL_REPEAT) rather than clamp for a method that
// reads no stream: when any loaded stream was made with border wrap (SurfaceRenderer::draw's
// rule; a method with a stream follows its own stream's border).
bool maps_tile(const PreviewMaps& maps);
// Whether they repeat for `method`: its own stream's border when it reads one (sdf, cone,
// relaxed-cone, pyramid, vdm), else maps_tile. The same rule as SurfaceRenderer::draw.
bool method_tiles(const PreviewMaps& maps, const std::string& method);

// The texel that integer position k (a texel centre's coordinate, possibly outside the map)
// reads on an n-texel axis: the map tiled (wrap) or its edge texel repeated (clamp).
inline int texel_index(double k, int n, bool wrap) {
  if (wrap) {
    double m = std::fmod(k, static_cast<double>(n));
    if (m < 0) m += n;
    return std::min(static_cast<int>(m), n - 1);
  }
  return static_cast<int>(std::clamp(k, 0.0, static_cast<double>(n - 1)));
}

// Channel `c` of `img` at (u, v) as GL_LINEAR samples a texture uploaded by the previewer
// (rows flipped so that v = 0 is the image's bottom row): bilinear through the texel centres
// at pixel coordinates (u W, (1 - v) H), edge texels repeated (clamp) or the map tiled (wrap).
inline double sample_linear(const Image& img, int c, double u, double v, bool wrap) {
  const int w = img.width, h = img.height;
  // Far-out coordinates: clamping first keeps the conversions to int defined (the lookup
  // there means nothing anyway).
  const double fx = std::clamp(u * w - 0.5, -1e9, 1e9), fy = std::clamp((1.0 - v) * h - 0.5, -1e9, 1e9);
  const double x0 = std::floor(fx), y0 = std::floor(fy);
  const double tx = fx - x0, ty = fy - y0;
  const int xa = texel_index(x0, w, wrap), xb = texel_index(x0 + 1, w, wrap), ya = texel_index(y0, h, wrap),
            yb = texel_index(y0 + 1, h, wrap);
  const double a = img.at(xa, ya, c), b = img.at(xb, ya, c), cc = img.at(xa, yb, c), d = img.at(xb, yb, c);
  return (a * (1 - tx) + b * tx) * (1 - ty) + (cc * (1 - tx) + d * tx) * ty;
}

}  // namespace meso
