// Small geometric helpers of the collapse loop, in double precision.
#pragma once

#include <OpenMesh/Core/Geometry/VectorT.hh>

#include <algorithm>
#include <cmath>
#include <limits>

namespace meso::reduce {

using Vec3d = OpenMesh::Vec3d;
using Vec2f = OpenMesh::Vec2f;

// Squared distance from p to triangle (a, b, c) and the barycentric weights of the closest
// point (Ericson, Real-Time Collision Detection, 5.1.5).
inline double closest_point_sqr(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c, double w[3]) {
  const Vec3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = OpenMesh::dot(ab, ap), d2 = OpenMesh::dot(ac, ap);
  auto done = [&](double wa, double wb, double wc) {
    w[0] = wa, w[1] = wb, w[2] = wc;
    return (a * wa + b * wb + c * wc - p).sqrnorm();
  };
  if (d1 <= 0 && d2 <= 0) return done(1, 0, 0);
  const Vec3d bp = p - b;
  const double d3 = OpenMesh::dot(ab, bp), d4 = OpenMesh::dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return done(0, 1, 0);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return done(1 - v, v, 0);
  }
  const Vec3d cp = p - c;
  const double d5 = OpenMesh::dot(ab, cp), d6 = OpenMesh::dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return done(0, 0, 1);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double v = d2 / (d2 - d6);
    return done(1 - v, 0, v);
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double v = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return done(0, 1 - v, v);
  }
  const double denom = va + vb + vc;
  if (!(std::abs(denom) > 0)) {
    // Degenerate triangle: the best of its vertices.
    const double da = (p - a).sqrnorm(), db = (p - b).sqrnorm(), dc = (p - c).sqrnorm();
    if (da <= db && da <= dc) return done(1, 0, 0);
    return db <= dc ? done(0, 1, 0) : done(0, 0, 1);
  }
  const double v = vb / denom, ww = vc / denom;
  return done(1 - v - ww, v, ww);
}

inline double point_segment_distance(const Vec3d& p, const Vec3d& a, const Vec3d& b) {
  const Vec3d ab = b - a;
  const double l2 = ab.sqrnorm();
  const double t = l2 > 0 ? std::clamp(OpenMesh::dot(p - a, ab) / l2, 0.0, 1.0) : 0.0;
  return (p - (a + ab * t)).norm();
}

inline double point_segment_distance(const Vec2f& pf, const Vec2f& af, const Vec2f& bf) {
  const double px = pf[0], py = pf[1], ax = af[0], ay = af[1];
  const double abx = double(bf[0]) - ax, aby = double(bf[1]) - ay;
  const double l2 = abx * abx + aby * aby;
  const double t = l2 > 0 ? std::clamp(((px - ax) * abx + (py - ay) * aby) / l2, 0.0, 1.0) : 0.0;
  const double dx = px - (ax + abx * t), dy = py - (ay + aby * t);
  return std::sqrt(dx * dx + dy * dy);
}

// (1 - t) a + t b, exact at t = 0 and t = 1.
inline Vec2f lerp_uv(const Vec2f& a, const Vec2f& b, double t) {
  if (t <= 0) return a;
  if (t >= 1) return b;
  return Vec2f(static_cast<float>(double(a[0]) + (double(b[0]) - double(a[0])) * t),
               static_cast<float>(double(a[1]) + (double(b[1]) - double(a[1])) * t));
}

// Twice the signed area of the UV triangle (a, b, c).
inline double uv_cross(const Vec2f& a, const Vec2f& b, const Vec2f& c) {
  const double bx = double(b[0]) - a[0], by = double(b[1]) - a[1];
  const double cx = double(c[0]) - a[0], cy = double(c[1]) - a[1];
  return bx * cy - by * cx;
}

// A triangle's aspect ratio: longest edge squared times sqrt(3) over four times its area
// (1 for an equilateral triangle, infinite for a degenerate one).
inline double aspect_ratio(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const double l = std::max({(b - a).sqrnorm(), (c - b).sqrnorm(), (a - c).sqrnorm()});
  const double area2 = OpenMesh::cross(b - a, c - a).norm();  // twice the area
  if (!(area2 > 0)) return std::numeric_limits<double>::infinity();
  return l * std::sqrt(3.0) / (2.0 * area2);
}

}  // namespace meso::reduce
