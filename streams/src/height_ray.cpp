#include "meso/streams/height_ray.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace meso {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
}

bool intersect_footprint(const HeightField& field, int i, int j, const HeightRay& r, double t0, double t1, double& t_hit) {
  if (!(t1 >= t0)) return false;
  std::array<double, 4> cut = {t0, t1, t1, t1};
  int n = 2;
  if (r.dx != 0) {
    const double tx = (i + 0.5 - r.x) / r.dx;
    if (tx > t0 && tx < t1) cut[static_cast<size_t>(n++)] = tx;
  }
  if (r.dy != 0) {
    const double ty = (j + 0.5 - r.y) / r.dy;
    if (ty > t0 && ty < t1) cut[static_cast<size_t>(n++)] = ty;
  }
  std::sort(cut.begin(), cut.begin() + n);
  for (int k = 0; k + 1 < n; ++k) {
    const double ta = cut[static_cast<size_t>(k)], tb = cut[static_cast<size_t>(k + 1)];
    const double tm = 0.5 * (ta + tb);
    // The piece under the middle of this stretch: half-grid column and row.
    const double xm = std::clamp(r.x + tm * r.dx, static_cast<double>(i), i + 1.0);
    const double ym = std::clamp(r.y + tm * r.dy, static_cast<double>(j), j + 1.0);
    const double px = xm < i + 0.5 ? i : i + 0.5, py = ym < j + 0.5 ? j : j + 0.5;
    // S on the piece: c + a s + b u + e s u, local s = 2 (x - px), u = 2 (y - py) in [0, 1].
    const double v00 = field.bilinear(px, py), v10 = field.bilinear(px + 0.5, py), v01 = field.bilinear(px, py + 0.5),
                 v11 = field.bilinear(px + 0.5, py + 0.5);
    struct {
      double c, a, b, e;
    } p{v00, v10 - v00, v01 - v00, v00 - v10 - v01 + v11};
    // g(t) = S(ray(t)) - z(t) = A t^2 + B t + C, with s = s0 + sd t and u = u0 + ud t; the
    // ray's own bending ddz t^2 keeps it a quadratic.
    const double s0 = 2 * (r.x - px), sd = 2 * r.dx, u0 = 2 * (r.y - py), ud = 2 * r.dy;
    const double A = p.e * sd * ud - r.ddz;
    const double B = p.a * sd + p.b * ud + p.e * (s0 * ud + u0 * sd) - r.dz;
    const double C = p.c + p.a * s0 + p.b * u0 + p.e * s0 * u0 - r.z;
    auto g = [&](double t) { return (A * t + B) * t + C; };
    if (g(ta) >= 0) {
      t_hit = ta;
      return true;
    }
    double best = kInf;
    const double scale = std::abs(A) * tb * tb + std::abs(B) * tb + std::abs(C);
    if (std::abs(A) * (tb - ta) * (tb - ta) <= 1e-14 * scale) {
      if (B != 0) best = -C / B;
    } else {
      const double disc = B * B - 4 * A * C;
      if (disc >= 0) {
        const double q = -0.5 * (B + std::copysign(std::sqrt(disc), B));
        for (double root : {q / A, q != 0 ? C / q : kInf})
          if (root >= ta && root <= tb) best = std::min(best, root);
      }
    }
    if (best >= ta && best <= tb) {
      t_hit = best;
      return true;
    }
    if (g(tb) >= 0) {
      // Rounding hid the root: bisect the sign change.
      double lo = ta, hi = tb;
      for (int it = 0; it < 100 && hi - lo > 0; ++it) {
        const double mid = 0.5 * (lo + hi);
        if (mid <= lo || mid >= hi) break;
        (g(mid) >= 0 ? hi : lo) = mid;
      }
      t_hit = hi;
      return true;
    }
  }
  return false;
}

}  // namespace meso
