// Garland-Heckbert error quadrics and the placement of a collapsed edge's kept vertex.
//
// Q(x) = x^T A x + 2 b^T x + c, the weighted sum of squared distances from x to a set of
// planes. meshreduce evaluates quadrics in coordinates normalised to a unit box (see
// reduce_mesh), so their entries stay within a few orders of magnitude of 1 whatever the
// input's units.
#pragma once

#include <OpenMesh/Core/Geometry/VectorT.hh>

#include <algorithm>
#include <cmath>

namespace meso::reduce {

using Vec3d = OpenMesh::Vec3d;

struct Quadric {
  double a00 = 0, a01 = 0, a02 = 0, a11 = 0, a12 = 0, a22 = 0;
  double b0 = 0, b1 = 0, b2 = 0;
  double c = 0;

  // The plane n.x + d = 0 (n unit), weighted by w.
  static Quadric plane(const Vec3d& n, double d, double w) {
    Quadric q;
    q.a00 = w * n[0] * n[0];
    q.a01 = w * n[0] * n[1];
    q.a02 = w * n[0] * n[2];
    q.a11 = w * n[1] * n[1];
    q.a12 = w * n[1] * n[2];
    q.a22 = w * n[2] * n[2];
    q.b0 = w * d * n[0];
    q.b1 = w * d * n[1];
    q.b2 = w * d * n[2];
    q.c = w * d * d;
    return q;
  }

  Quadric& operator+=(const Quadric& o) {
    a00 += o.a00, a01 += o.a01, a02 += o.a02, a11 += o.a11, a12 += o.a12, a22 += o.a22;
    b0 += o.b0, b1 += o.b1, b2 += o.b2;
    c += o.c;
    return *this;
  }
  friend Quadric operator+(Quadric a, const Quadric& b) { return a += b; }

  Vec3d A(const Vec3d& x) const {
    return Vec3d(a00 * x[0] + a01 * x[1] + a02 * x[2], a01 * x[0] + a11 * x[1] + a12 * x[2],
                 a02 * x[0] + a12 * x[1] + a22 * x[2]);
  }
  Vec3d b() const { return Vec3d(b0, b1, b2); }

  // Q(x), clamped at 0 (rounding can make it slightly negative).
  double operator()(const Vec3d& x) const {
    const double v = OpenMesh::dot(x, A(x)) + 2.0 * OpenMesh::dot(b(), x) + c;
    return std::max(0.0, v);
  }
};

// Regularisation of the placement: the minimiser of Q(x) + eps |x - mid|^2 with
// eps = kRegularisation * trace(A), refined once. Along directions the quadric constrains
// well (eigenvalues >> eps) this is the quadric's minimiser; along the ones it does not
// constrain (flat or straight-crease neighbourhoods) it stays at the edge's midpoint, like
// Lindstrom & Turk's pseudo-inverse, without an eigen-decomposition. (A + eps I) is positive
// definite, so the 3x3 solve by cofactors is always well conditioned.
inline constexpr double kRegularisation = 1e-3;

// Solves (A + eps I) x = r by cofactors; false when the system is degenerate.
inline bool solve_shifted(const Quadric& q, double eps, const Vec3d& r, Vec3d& x) {
  const double a = q.a00 + eps, b = q.a01, c = q.a02, d = q.a11 + eps, e = q.a12, f = q.a22 + eps;
  const double c00 = d * f - e * e, c01 = c * e - b * f, c02 = b * e - c * d;
  const double det = a * c00 + b * c01 + c * c02;
  if (!(std::abs(det) > 0) || !std::isfinite(det)) return false;
  const double c11 = a * f - c * c, c12 = b * c - a * e, c22 = a * d - b * b;
  const double inv = 1.0 / det;
  x = Vec3d((c00 * r[0] + c01 * r[1] + c02 * r[2]) * inv, (c01 * r[0] + c11 * r[1] + c12 * r[2]) * inv,
            (c02 * r[0] + c12 * r[1] + c22 * r[2]) * inv);
  return std::isfinite(x[0]) && std::isfinite(x[1]) && std::isfinite(x[2]);
}

// The minimiser of q nearest to `mid` in the directions q does not constrain, or false if q
// constrains no direction at all.
inline bool quadric_minimiser(const Quadric& q, const Vec3d& mid, Vec3d& out) {
  const double trace = q.a00 + q.a11 + q.a22;
  if (!(trace > 0) || !std::isfinite(trace)) return false;
  const double eps = kRegularisation * trace;
  // Solve for the step from mid: (A + eps I) s = -(A mid + b), then refine once with the
  // residual of the unregularised gradient.
  Vec3d s;
  if (!solve_shifted(q, eps, -(q.A(mid) + q.b()), s)) return false;
  Vec3d x = mid + s, s2;
  if (!solve_shifted(q, eps, -(q.A(x) + q.b()), s2)) return false;
  out = x + s2;
  return true;
}

// The placement of the vertex kept by collapsing edge (p0, p1): the quadric's minimiser
// when it exists and stays near the edge, otherwise (or when better) the best of p0, p1 and
// the midpoint. Returns the cost Q(x).
inline double optimal_placement(const Quadric& q, const Vec3d& p0, const Vec3d& p1, Vec3d& x) {
  const Vec3d mid = (p0 + p1) * 0.5;
  const double c0 = q(p0), c1 = q(p1), cm = q(mid);
  double best = cm;
  x = mid;
  if (c0 < best) best = c0, x = p0;
  if (c1 < best) best = c1, x = p1;
  Vec3d opt;
  if (quadric_minimiser(q, mid, opt)) {
    // A minimiser far from the edge comes from an ill-conditioned quadric: keep the fallback.
    const double reach = 2.0 * (p1 - p0).norm();
    if ((opt - mid).norm() <= reach) {
      const double co = q(opt);
      if (co <= best) best = co, x = opt;
    }
  }
  return best;
}

// The minimiser of q on the segment p0 + t (p1 - p0), t in [0, 1]; t = 0.5 where q does not
// vary along the segment. Returns the cost.
inline double segment_placement(const Quadric& q, const Vec3d& p0, const Vec3d& p1, double& t) {
  const Vec3d d = p1 - p0;
  const double dad = OpenMesh::dot(d, q.A(d));
  const double slope = OpenMesh::dot(d, q.A(p0) + q.b());
  const double scale = (q.a00 + q.a11 + q.a22) * OpenMesh::dot(d, d);
  if (dad > 1e-9 * scale && std::isfinite(dad)) {
    t = std::clamp(-slope / dad, 0.0, 1.0);
  } else {
    t = 0.5;
  }
  return q(p0 + d * t);
}

}  // namespace meso::reduce
