#include "meso/streams/pyramid.hpp"

#include "meso/streams/cone_map.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace meso {

Image footprint_min_max(const HeightField& f) {
  const int w = f.height.width, h = f.height.height;
  Image level0(w, h, 2);
  tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y < rows.end(); ++y) {
      for (int x = 0; x < w; ++x) {
        // The 9 points of the texel (pixel units): corners average four texels, edge
        // midpoints two, the centre is the texel itself.
        float lo = f.texel(x, y), hi = lo;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            if (dx == 0 && dy == 0) continue;
            const float v = f.bilinear(x + 0.5 + 0.5 * dx, y + 0.5 + 0.5 * dy);
            lo = std::min(lo, v);
            hi = std::max(hi, v);
          }
        }
        level0.at(x, y, 0) = lo;
        level0.at(x, y, 1) = hi;
      }
    }
  });
  return level0;
}

MinMaxPyramid build_min_max_pyramid(const HeightField& f) {
  MinMaxPyramid p;
  p.levels.push_back(footprint_min_max(f));
  while (p.levels.back().width > 1 || p.levels.back().height > 1) {
    const Image& fine = p.levels.back();
    const int fw = fine.width, fh = fine.height;
    const int cw = std::max(1, fw / 2), ch = std::max(1, fh / 2);
    Image coarse(cw, ch, 2);
    tbb::parallel_for(tbb::blocked_range<int>(0, ch), [&](const tbb::blocked_range<int>& rows) {
      for (int y = rows.begin(); y < rows.end(); ++y) {
        // Fine texels overlapping [y/ch, (y+1)/ch]: from floor(y fh / ch) to ceil((y+1) fh / ch) - 1.
        const int y0 = static_cast<int>(static_cast<long>(y) * fh / ch);
        const int y1 = static_cast<int>((static_cast<long>(y + 1) * fh + ch - 1) / ch) - 1;
        for (int x = 0; x < cw; ++x) {
          const int x0 = static_cast<int>(static_cast<long>(x) * fw / cw);
          const int x1 = static_cast<int>((static_cast<long>(x + 1) * fw + cw - 1) / cw) - 1;
          float lo = fine.at(x0, y0, 0), hi = fine.at(x0, y0, 1);
          for (int yy = y0; yy <= y1; ++yy)
            for (int xx = x0; xx <= x1; ++xx) {
              lo = std::min(lo, fine.at(xx, yy, 0));
              hi = std::max(hi, fine.at(xx, yy, 1));
            }
          coarse.at(x, y, 0) = lo;
          coarse.at(x, y, 1) = hi;
        }
      }
    });
    p.levels.push_back(std::move(coarse));
  }
  return p;
}

namespace {

struct PyramidTracer {
  const HeightField& field;
  const MinMaxPyramid& pyramid;
  const HeightRay& r;
  int steps = 0;

  // The ray's parameter interval over [x0, x1] x [y0, y1] (pixels), intersected with [t0, t1].
  bool clip(double x0, double x1, double y0, double y1, double& t0, double& t1) const {
    auto slab = [&](double o, double d, double lo, double hi) {
      if (d == 0) return o >= lo && o <= hi;
      double a = (lo - o) / d, b = (hi - o) / d;
      if (a > b) std::swap(a, b);
      t0 = std::max(t0, a);
      t1 = std::min(t1, b);
      return t0 <= t1;
    };
    return slab(r.x, r.dx, x0, x1) && slab(r.y, r.dy, y0, y1);
  }

  // First hit inside texel (x, y) of level l for t in [t0, t1], or false.
  bool visit(int l, int x, int y, double t0, double t1, double& t_hit) {
    const Image& level = pyramid.levels[static_cast<size_t>(l)];
    const double sx = static_cast<double>(pyramid.levels[0].width) / level.width;
    const double sy = static_cast<double>(pyramid.levels[0].height) / level.height;
    const double x0 = x * sx, x1 = (x + 1) * sx, y0 = y * sy, y1 = (y + 1) * sy;
    if (!clip(x0, x1, y0, y1, t0, t1)) return false;
    ++steps;
    // Below the box's top from t_top on (the ray descends).
    const double top = level.at(x, y, 1);
    t0 = std::max(t0, (r.z - top) / -r.dz);
    if (t0 > t1) return false;
    if (l == 0) return intersect_footprint(field, x, y, r, t0, t1, t_hit);
    // Finer texels overlapping this footprint, in the order the ray meets them.
    const Image& fine = pyramid.levels[static_cast<size_t>(l - 1)];
    const int fx0 = static_cast<int>(std::floor(x0 * fine.width / pyramid.levels[0].width));
    const int fx1 = std::min(fine.width - 1, static_cast<int>(std::ceil(x1 * fine.width / pyramid.levels[0].width)) - 1);
    const int fy0 = static_cast<int>(std::floor(y0 * fine.height / pyramid.levels[0].height));
    const int fy1 = std::min(fine.height - 1, static_cast<int>(std::ceil(y1 * fine.height / pyramid.levels[0].height)) - 1);
    std::array<std::pair<double, std::array<int, 2>>, 16> kids;  // at most 3 x 3 overlap
    int n = 0;
    const double fsx = static_cast<double>(pyramid.levels[0].width) / fine.width;
    const double fsy = static_cast<double>(pyramid.levels[0].height) / fine.height;
    for (int cy = fy0; cy <= fy1; ++cy)
      for (int cx = fx0; cx <= fx1; ++cx) {
        double a = t0, b = t1;
        if (clip(cx * fsx, (cx + 1) * fsx, cy * fsy, (cy + 1) * fsy, a, b) && n < 16) kids[static_cast<size_t>(n++)] = {a, {cx, cy}};
      }
    std::sort(kids.begin(), kids.begin() + n, [](const auto& p, const auto& q) { return p.first < q.first; });
    for (int k = 0; k < n; ++k)
      if (visit(l - 1, kids[static_cast<size_t>(k)].second[0], kids[static_cast<size_t>(k)].second[1], t0, t1, t_hit)) return true;
    return false;
  }
};

}  // namespace

HeightHit trace_min_max_pyramid(const HeightField& field, const MinMaxPyramid& pyramid, const HeightRay& r) {
  HeightHit out;
  if (!(r.dz < 0) || pyramid.levels.empty()) return out;
  PyramidTracer tracer{field, pyramid, r};
  const double t0 = r.z > 1 ? (r.z - 1) / -r.dz : 0.0, t1 = r.z / -r.dz;  // from height 1 down to 0
  const int top = static_cast<int>(pyramid.levels.size()) - 1;
  const Image& root = pyramid.levels.back();
  double t_hit = 0;
  for (int y = 0; y < root.height && !out.hit; ++y)
    for (int x = 0; x < root.width && !out.hit; ++x)
      if (tracer.visit(top, x, y, t0, t1, t_hit)) {
        out.hit = true;
        out.t = t_hit;
      }
  out.steps = tracer.steps;
  return out;
}

}  // namespace meso
