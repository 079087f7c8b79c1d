#include "meso/bake/uv_raster.hpp"

#include "meso/core/uv_texels.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace meso {

UvRasterizer::UvRasterizer(const Mesh& mesh, int width, int height) : width_(width), height_(height) {
  for (auto f : mesh.faces()) {
    // A face with no UV area covers nothing (the same rule as uvpack's degenerate faces).
    if (uv_double_area(mesh, f) == 0.0) continue;
    const UvTriangle t = uv_triangle_in_pixels(mesh, f, width, height);
    Face face{};
    face.index = f.idx();
    std::copy(t.px, t.px + 3, face.px);
    std::copy(t.py, t.py + 3, face.py);
    face.area = (t.px[1] - t.px[0]) * (t.py[2] - t.py[0]) - (t.py[1] - t.py[0]) * (t.px[2] - t.px[0]);
    if (!(std::abs(face.area) > 0)) continue;
    face.x_min = std::min({t.px[0], t.px[1], t.px[2]});
    face.x_max = std::max({t.px[0], t.px[1], t.px[2]});
    face.y_min = std::min({t.py[0], t.py[1], t.py[2]});
    face.y_max = std::max({t.py[0], t.py[1], t.py[2]});
    faces_.push_back(face);
  }
}

std::vector<TexelSample> UvRasterizer::rows(int row0, int row1) const {
  row0 = std::max(row0, 0);
  row1 = std::min(row1, height_);
  std::vector<TexelSample> out(static_cast<size_t>(std::max(row1 - row0, 0)) * static_cast<size_t>(width_));
  if (row1 > row0) rows_into(row0, row1, out.data());
  return out;
}

void UvRasterizer::rows_into(int row0, int row1, TexelSample* out) const {
  row0 = std::max(row0, 0);
  row1 = std::min(row1, height_);
  if (row1 <= row0) return;
  auto at = [&](int x, int y) -> TexelSample& {
    return out[static_cast<size_t>(y - row0) * static_cast<size_t>(width_) + static_cast<size_t>(x)];
  };
  // The band [row0, row1] in pixels, and the faces that can touch it.
  auto meets_band = [&](const Face& f) { return f.y_max >= row0 && f.y_min <= row1; };
  // Pass 1: texel centres inside a face.
  for (const Face& f : faces_) {
    if (!meets_band(f)) continue;
    int x0, x1, y0, y1;
    if (!texel_centres_in(f.x_min, f.x_max, width_, x0, x1)) continue;
    if (!texel_centres_in(f.y_min, f.y_max, height_, y0, y1)) continue;
    y0 = std::max(y0, row0);
    y1 = std::min(y1, row1 - 1);
    const double* px = f.px;
    const double* py = f.py;
    // A centre exactly on an edge shared by two faces must be taken by one of them: each
    // barycentric is computed from its own edge function and accepted down to -kTie (far
    // below a texel, far above rounding), then clamped; the first face in order wins.
    constexpr double kTie = 1e-9;
    const double sign = f.area > 0 ? 1.0 : -1.0;
    for (int y = y0; y <= y1; ++y) {
      const double cy = y + 0.5;
      // The row's centres the test below can accept: where every edge function is at least
      // -kTie. Edge i's numerator is linear in cx, n_i = a_i + b_i cx with b_i = py_j - py_k
      // (pixels); an edge with |b_i| >= 1e-3 bounds cx on one side. The bounds are widened by
      // two texels, a margin of at least 2e-3 in the numerator against its rounding (below
      // 1e-6 for coordinates up to 10^5 pixels), so the span holds every centre the test
      // accepts and the test alone decides, texel for texel: the result is that of testing the
      // whole box, at the cost of about the triangle's texels instead of its box's.
      double lo = x0, hi = x1;  // in double: the bounds may lie far outside int's range
      for (int i = 0; i < 3; ++i) {
        const int j = (i + 1) % 3, k = (i + 2) % 3;
        const double b = sign * (py[j] - py[k]);
        if (!(std::abs(b) >= 1e-3)) continue;
        const double a = sign * (px[j] * (py[k] - cy) - (py[j] - cy) * px[k]);
        const double bound = (-kTie * std::abs(f.area) - a) / b - 0.5;  // in x (cx = x + 0.5)
        if (!std::isfinite(bound)) continue;
        if (b > 0) lo = std::max(lo, std::floor(bound) - 2.0);
        else hi = std::min(hi, std::ceil(bound) + 2.0);
      }
      if (!(lo <= hi)) continue;  // then x0 <= lo <= hi <= x1
      for (int x = static_cast<int>(lo), xb = static_cast<int>(hi); x <= xb; ++x) {
        TexelSample& s = at(x, y);
        if (s.face >= 0) continue;  // first face in face order wins: deterministic
        const double cx = x + 0.5;
        const double w0 = ((px[1] - cx) * (py[2] - cy) - (py[1] - cy) * (px[2] - cx)) / f.area;
        const double w1 = ((px[2] - cx) * (py[0] - cy) - (py[2] - cy) * (px[0] - cx)) / f.area;
        const double w2 = ((px[0] - cx) * (py[1] - cy) - (py[0] - cy) * (px[1] - cx)) / f.area;
        if (w0 < -kTie || w1 < -kTie || w2 < -kTie) continue;
        const double c0 = std::max(w0, 0.0), c1 = std::max(w1, 0.0), c2 = std::max(w2, 0.0), sum = c0 + c1 + c2;
        s.face = f.index;
        s.bary = {static_cast<float>(c0 / sum), static_cast<float>(c1 / sum), static_cast<float>(c2 / sum)};
        s.centre_inside = true;
      }
    }
  }
  // Pass 2: texels a face touches whose centre no face contains.
  for (const Face& f : faces_) {
    if (!meets_band(f)) continue;
    UvTriangle t{};
    std::copy(f.px, f.px + 3, t.px);
    std::copy(f.py, f.py + 3, t.py);
    // for_each_touched_texel's texels, skipping those already claimed before the overlap
    // test (the test decides nothing for them).
    int x0, x1, y0, y1;
    if (!texels_touching(f.x_min, f.x_max, width_, x0, x1)) continue;
    if (!texels_touching(f.y_min, f.y_max, height_, y0, y1)) continue;
    y0 = std::max(y0, row0);
    y1 = std::min(y1, row1 - 1);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        TexelSample& s = at(x, y);
        if (s.face >= 0 || !triangle_overlaps_texel(t, x, y)) continue;
        const auto b = nearest_barycentrics(t, x + 0.5, y + 0.5);
        s.face = f.index;
        s.bary = {static_cast<float>(b[0]), static_cast<float>(b[1]), static_cast<float>(b[2])};
      }
  }
}

LargeVector<TexelSample> rasterize_uv(const Mesh& mesh, int width, int height) {
  // Bands of rows in parallel: a texel's sample depends only on the faces in face order,
  // not on the band it is computed in.
  const UvRasterizer raster(mesh, width, height);
  LargeVector<TexelSample> out(static_cast<size_t>(std::max(width, 0)) * static_cast<size_t>(std::max(height, 0)));
  tbb::parallel_for(tbb::blocked_range<int>(0, std::max(height, 0), 8), [&](const tbb::blocked_range<int>& band) {
    raster.rows_into(band.begin(), band.end(), out.data() + static_cast<size_t>(band.begin()) * static_cast<size_t>(width));
  });
  return out;
}

}  // namespace meso
