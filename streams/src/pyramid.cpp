#include "meso/streams/pyramid.hpp"

#include "meso/streams/cone_map.hpp"
#include "meso/streams/half_rounding.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

namespace meso {

Image footprint_min_max(const HeightField& f) {
  const int w = f.height.width, h = f.height.height;
  Image level0(w, h, 2);
  tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y < rows.end(); ++y) {
      for (int x = 0; x < w; ++x) {
        // The 9 points of the texel (pixel units): corners average four texels, edge
        // midpoints two, the centre is the texel itself. Each is f.bilinear() at
        // (x + 0.5 + 0.5 dx, y + 0.5 + 0.5 dy), the same blend of the same texels, read once
        // from the 3 x 3 neighbourhood: bilinear() blends texels ix, ix + 1 at weight tx with
        // (ix, tx) = (x - 1, 1/2), (x, 0), (x, 1/2) for dx = -1, 0, 1 (and so in y).
        float n[3][3];
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) n[dy + 1][dx + 1] = f.texel(x + dx, y + dy);
        float lo = n[1][1], hi = lo;
        for (int dy = -1; dy <= 1; ++dy) {
          const int iy = dy < 0 ? 0 : 1;
          const float ty = dy == 0 ? 0.0f : 0.5f;
          for (int dx = -1; dx <= 1; ++dx) {
            if (dx == 0 && dy == 0) continue;
            const int ix = dx < 0 ? 0 : 1;
            const float tx = dx == 0 ? 0.0f : 0.5f;
            const float v = bilinear_blend(n[iy][ix], n[iy][ix + 1], n[iy + 1][ix], n[iy + 1][ix + 1], tx, ty);
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

MinMaxPyramid build_min_max_pyramid(const HeightField& f) { return min_max_pyramid_from_level0(footprint_min_max(f)); }

MinMaxPyramid min_max_pyramid_from_level0(Image level0) {
  MinMaxPyramid p;
  p.levels.push_back(std::move(level0));
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

constexpr double kInf = std::numeric_limits<double>::infinity();

// The smallest root of a t^2 + b t + c = 0 in (lo, hi], or +inf.
double first_root(double a, double b, double c, double lo, double hi) {
  double best = kInf;
  if (a == 0) {
    if (b != 0) {
      const double t = -c / b;
      if (t > lo && t <= hi) best = t;
    }
    return best;
  }
  const double disc = b * b - 4 * a * c;
  if (disc < 0) return best;
  const double q = -0.5 * (b + std::copysign(std::sqrt(disc), b));
  for (double t : {q / a, q != 0 ? c / q : kInf})
    if (t > lo && t <= hi) best = std::min(best, t);
  return best;
}

struct PyramidTracer {
  const HeightField& field;
  const MinMaxPyramid& pyramid;
  const HeightRay& r;  // its origin in the tile traversed (pixels of level 0)
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

  // The lowest height of the ray over [t0, t1].
  double lowest(double t0, double t1) const {
    double z = std::min(r.z_at(t0), r.z_at(t1));
    if (r.ddz > 0) {
      const double vertex = -r.dz / (2 * r.ddz);
      if (vertex > t0 && vertex < t1) z = std::min(z, r.z_at(vertex));
    }
    return z;
  }

  // First hit inside texel (x, y) of level l for t in [t0, t1], or false.
  bool visit(int l, int x, int y, double t0, double t1, double& t_hit) {
    const Image& level = pyramid.levels[static_cast<size_t>(l)];
    const double sx = static_cast<double>(pyramid.levels[0].width) / level.width;
    const double sy = static_cast<double>(pyramid.levels[0].height) / level.height;
    const double x0 = x * sx, x1 = (x + 1) * sx, y0 = y * sy, y1 = (y + 1) * sy;
    if (!clip(x0, x1, y0, y1, t0, t1)) return false;
    ++steps;
    const double top = level.at(x, y, 1);
    if (lowest(t0, t1) > top) return false;  // the ray passes over the box
    // A straight ray is below the box's top from one point on (it descends).
    if (r.ddz == 0) t0 = std::max(t0, (r.z - top) / -r.dz);
    if (t0 > t1) return false;
    if (l == 0) {
      return intersect_footprint(field, x, y, r, t0, t1, t_hit);
    }
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
        if (clip(cx * fsx, (cx + 1) * fsx, cy * fsy, (cy + 1) * fsy, a, b) && n < 16)
          kids[static_cast<size_t>(n++)] = {a, {cx, cy}};
      }
    std::sort(kids.begin(), kids.begin() + n, [](const auto& p, const auto& q) { return p.first < q.first; });
    for (int k = 0; k < n; ++k)
      if (visit(l - 1, kids[static_cast<size_t>(k)].second[0], kids[static_cast<size_t>(k)].second[1], t0, t1, t_hit)) return true;
    return false;
  }
};

}  // namespace

void round_min_max_to_half(Image& min_max) {
  const int channels = std::min(2, min_max.channels);
  for (size_t i = 0; i < min_max.texel_count(); ++i)
    for (int c = 0; c < channels; ++c) {
      float& v = min_max.pixels[i * static_cast<size_t>(min_max.channels) + static_cast<size_t>(c)];
      v = c == 0 ? half_below(v) : half_above(v);
    }
}

HeightHit trace_min_max_pyramid(const HeightField& field, const MinMaxPyramid& pyramid, const HeightRay& r) {
  HeightHit out;
  if (!(r.dz < 0) || pyramid.levels.empty() || pyramid.levels[0].empty()) return out;
  // S lies between the map's lowest and highest points (the top level's box): the ray is
  // followed from where it comes down to the highest (or its start) to where it reaches the
  // lowest, where it is at or below S, or, bent upward, where it rises back above the highest
  // (it has left the height field). Only that stretch is traced: over a tiling map a steep
  // relief and a grazing ray would otherwise cross tiles by the million above or below S.
  const Image& apex = pyramid.levels.back();
  const double lowest_s = apex.at(0, 0, 0), highest_s = apex.at(0, 0, 1);
  const double t0 = r.z > highest_s ? first_root(r.ddz, r.dz, r.z - highest_s, -1e-300, kInf) : 0.0;
  if (!std::isfinite(t0)) return out;
  const double below = r.z > lowest_s ? std::max(t0, first_root(r.ddz, r.dz, r.z - lowest_s, -1e-300, kInf)) : 0.0;
  const double above = r.ddz > 0 ? first_root(r.ddz, r.dz, r.z - highest_s, t0 + 1e-12 * (1 + t0), kInf) : kInf;
  const double t1 = std::min(below, above);
  if (!std::isfinite(t1)) return out;
  const int top = static_cast<int>(pyramid.levels.size()) - 1;
  const double w = pyramid.levels[0].width, h = pyramid.levels[0].height;
  // The tiles the ray's path crosses, in order (one tile under Border::clamp), each traced
  // with the ray's origin moved into the tile: texel numbers stay those of one tile. The walk
  // ends with t >= t1 unless it stopped early: leaving a clamped map, or a path too far out
  // for its steps to progress in double.
  double t = t0;
  while (t < t1) {
    const double x = r.x + (t + 1e-12 * (1 + t)) * r.dx, y = r.y + (t + 1e-12 * (1 + t)) * r.dy;
    double a = std::floor(x / w), b = std::floor(y / h);
    if (field.border == Border::clamp) {
      // The one tile, closed: a ray along its far edge (y = H) is over the map.
      if (!(x >= 0 && x <= w && y >= 0 && y <= h)) break;
      a = b = 0;
    }
    HeightRay local = r;
    local.x -= a * w;
    local.y -= b * h;
    PyramidTracer tracer{field, pyramid, local};
    double ta = t, tb = t1;
    tracer.clip(0, w, 0, h, ta, tb);
    double t_hit = 0;
    const bool hit = tracer.visit(top, 0, 0, t, tb, t_hit);
    out.steps += tracer.steps;
    if (hit) {
      out.hit = true;
      out.t = t_hit;
      return out;
    }
    if (!(tb > t)) break;  // no progress (a degenerate path): stop
    t = tb;
  }
  // Walked over the map (t reached t1) down to S's lowest point, the ray is at or below S: it met S by then.
  // Found here when rounding put the ray a hair above a floor at exactly that height (a flat
  // map, or a pit at the map's minimum), where the tiles' tests see z(below) ~ +1e-16 over it.
  if (t >= t1 && below <= above) {
    const double x = r.x + below * r.dx, y = r.y + below * r.dy;
    if (field.border == Border::wrap || (x >= 0 && x <= w && y >= 0 && y <= h)) {
      out.hit = true;
      out.t = below;
    }
  }
  return out;
}

}  // namespace meso
