#include "bilinear_patch.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace meso {

namespace {

using Vec3d = OpenMesh::Vec3d;
using Vec2d = OpenMesh::Vec2d;

// How far (texels, or barycentric weight) a piece reaches past its sides: enough to cover
// the rounding of two pieces' different affine maps at a shared edge (~1e-13 for the texel
// coordinates of a map up to 16k texels), far below anything the comparison measures.
constexpr double kGrow = 1e-9;

}  // namespace

bool make_flat_patch_frame(const std::array<Vec3d, 3>& p, const std::array<Vec2d, 3>& xy, const Vec3d& n, FlatPatchFrame& f) {
  // Barycentrics from texel coordinates: (b1, b2) = T^-1 (x - x0, y - y0), T = [xy1 - xy0, xy2 - xy0].
  const double t00 = xy[1][0] - xy[0][0], t01 = xy[2][0] - xy[0][0], t10 = xy[1][1] - xy[0][1], t11 = xy[2][1] - xy[0][1];
  const double det = t00 * t11 - t01 * t10;
  const double size = std::max({std::abs(t00), std::abs(t01), std::abs(t10), std::abs(t11)});
  if (!(std::abs(det) > 1e-12 * size * size)) return false;  // no UV area (or NaN)
  const double i00 = t11 / det, i01 = -t01 / det, i10 = -t10 / det, i11 = t00 / det;
  const Vec3d e1 = p[1] - p[0], e2 = p[2] - p[0];
  f.p0 = p[0];
  f.x0 = xy[0][0];
  f.y0 = xy[0][1];
  f.px = e1 * i00 + e2 * i10;  // dP/dx = e1 db1/dx + e2 db2/dx
  f.py = e1 * i01 + e2 * i11;
  f.n = n;
  // Barycentric weights as affine functions of (x, y), about corner 0's texel position.
  f.bary[1] = {-(i00 * f.x0 + i01 * f.y0), i00, i01};
  f.bary[2] = {-(i10 * f.x0 + i11 * f.y0), i10, i11};
  f.bary[0] = {1.0 - f.bary[1][0] - f.bary[2][0], -i00 - i10, -i01 - i11};
  // to_local = [px py n]^-1 by the adjugate (rows: cross products of the other two columns).
  const Vec3d r0 = OpenMesh::cross(f.py, f.n), r1 = OpenMesh::cross(f.n, f.px), r2 = OpenMesh::cross(f.px, f.py);
  const double vol = OpenMesh::dot(f.px, r0);
  const double scale = f.px.norm() * f.py.norm() * f.n.norm();
  if (!(std::abs(vol) > 1e-9 * scale)) return false;  // n (nearly) in the triangle's plane
  for (int c = 0; c < 3; ++c) {
    f.to_local[0][static_cast<size_t>(c)] = r0[c] / vol;
    f.to_local[1][static_cast<size_t>(c)] = r1[c] / vol;
    f.to_local[2][static_cast<size_t>(c)] = r2[c] / vol;
  }
  return true;
}

std::vector<Vec2d> clip_to_cell(const std::array<Vec2d, 3>& xy, int i, int j) {
  std::vector<Vec2d> poly(xy.begin(), xy.end()), next;
  // The four sides as (axis, bound, keep the side above the bound?).
  const struct {
    int axis;
    double bound;
    bool above;
  } sides[4] = {{0, static_cast<double>(i), true}, {0, i + 1.0, false}, {1, static_cast<double>(j), true}, {1, j + 1.0, false}};
  for (const auto& s : sides) {
    next.clear();
    for (size_t k = 0; k < poly.size(); ++k) {
      const Vec2d& a = poly[k];
      const Vec2d& b = poly[(k + 1) % poly.size()];
      const double da = s.above ? a[s.axis] - s.bound : s.bound - a[s.axis];
      const double db = s.above ? b[s.axis] - s.bound : s.bound - b[s.axis];
      if (da >= 0) next.push_back(a);
      if ((da < 0 && db > 0) || (da > 0 && db < 0)) {
        Vec2d m = a + (b - a) * (da / (da - db));
        m[s.axis] = s.bound;  // exactly on the side
        next.push_back(m);
      }
    }
    poly.swap(next);
    if (poly.empty()) return poly;
  }
  double area = 0;  // twice the signed area (shoelace)
  for (size_t k = 0; k < poly.size(); ++k) {
    const Vec2d& a = poly[k];
    const Vec2d& b = poly[(k + 1) % poly.size()];
    area += a[0] * b[1] - a[1] * b[0];
  }
  if (area == 0) poly.clear();
  return poly;
}

bool intersect_bilinear_cell(const FlatPatchFrame& f, int i, int j, const CellHeights& h, const Vec3d& org, const Vec3d& dir,
                             double t_min, double t_max, PatchHit& hit) {
  // The ray in local coordinates: (x - x0, y - y0, s)(t) = q0 + t qd.
  const Vec3d rel = org - f.p0;
  double q0[3], qd[3];
  for (size_t r = 0; r < 3; ++r) {
    q0[r] = f.to_local[r][0] * rel[0] + f.to_local[r][1] * rel[1] + f.to_local[r][2] * rel[2];
    qd[r] = f.to_local[r][0] * dir[0] + f.to_local[r][1] * dir[1] + f.to_local[r][2] * dir[2];
  }
  // In the cell: fx = x - i = (q0x + x0 - i) + t qdx.
  const double fx0 = q0[0] + (f.x0 - i), fy0 = q0[1] + (f.y0 - j);
  double lo = t_min, hi = t_max;
  // Keeps t where c0 + t cd >= -grow (an affine constraint along the ray).
  auto keep = [&lo, &hi](double c0, double cd, double grow) {
    if (cd == 0) {
      if (!(c0 >= -grow)) hi = -std::numeric_limits<double>::infinity();
      return;
    }
    const double t = (-grow - c0) / cd;
    if (cd > 0)
      lo = std::max(lo, t);
    else
      hi = std::min(hi, t);
  };
  keep(fx0, qd[0], kGrow);
  keep(1 - fx0, -qd[0], kGrow);
  keep(fy0, qd[1], kGrow);
  keep(1 - fy0, -qd[1], kGrow);
  for (const auto& b : f.bary) {
    // Weight at (x, y) = b0 + bx x + by y, with x = x0 + q0x + t qdx.
    keep(b[0] + b[1] * (f.x0 + q0[0]) + b[2] * (f.y0 + q0[1]), b[1] * qd[0] + b[2] * qd[1], kGrow);
  }
  // The cell's height slab [min, max] of its texels (a bilinear polynomial stays within its
  // corners), grown a little for rounding: it bounds the interval also for rays along n.
  const double h_lo = std::min({h.a, h.b, h.c, h.d}), h_hi = std::max({h.a, h.b, h.c, h.d});
  const double slab_grow = 1e-9 * (1 + std::abs(h_lo) + std::abs(h_hi));
  keep(q0[2] - h_lo, qd[2], slab_grow);
  keep(h_hi - q0[2], -qd[2], slab_grow);
  if (!(lo <= hi)) return false;

  // g(t) = s(t) - h(fx(t), fy(t)) about the interval's middle tm (t = tm + tau) so that the
  // coefficients carry no cancellation from a far ray origin:
  //   h = a + (b - a) fx + (c - a) fy + k fx fy, k = a - b - c + d;
  //   g(tau) = A tau^2 + B tau + C with X = fx(tm), Y = fy(tm), S = s(tm):
  //   A = -k qdx qdy, B = qds - (b - a) qdx - (c - a) qdy - k (X qdy + Y qdx),
  //   C = S - h(X, Y).
  const double tm = 0.5 * (lo + hi), ta = lo - tm, tb = hi - tm;
  const double X = fx0 + tm * qd[0], Y = fy0 + tm * qd[1], S = q0[2] + tm * qd[2];
  const double k = h.a - h.b - h.c + h.d, ex = h.b - h.a, ey = h.c - h.a;
  const double A = -k * qd[0] * qd[1];
  const double B = qd[2] - ex * qd[0] - ey * qd[1] - k * (X * qd[1] + Y * qd[0]);
  const double C = S - (h.a + ex * X + ey * Y + k * X * Y);
  auto g = [&](double tau) { return (A * tau + B) * tau + C; };

  double best = std::numeric_limits<double>::infinity();
  const double slack = 1e-12 * (tb - ta);  // a root rounded just outside the interval is its end
  auto consider = [&](double root) {
    if (root >= ta - slack && root <= tb + slack) best = std::min(best, std::clamp(root, ta, tb));
  };
  if (A == 0) {
    if (B != 0) consider(-C / B);
  } else {
    const double disc = B * B - 4 * A * C;
    if (disc >= 0) {
      const double q = -0.5 * (B + std::copysign(std::sqrt(disc), B));
      consider(q / A);
      if (q != 0) consider(C / q);
    }
  }
  const double ga = g(ta), gb = g(tb);
  if (ga == 0) best = ta;
  if (!(best <= tb) && ((ga < 0 && gb >= 0) || (ga > 0 && gb <= 0))) {
    // A crossing that the formula lost to rounding: bisect the sign change.
    double l = ta, r = tb;
    for (int it = 0; it < 200; ++it) {
      const double mid = 0.5 * (l + r);
      if (mid <= l || mid >= r) break;
      ((g(mid) < 0) == (ga < 0) ? l : r) = mid;
    }
    best = r;
  }
  if (!(best <= tb)) return false;
  hit.t = tm + best;
  hit.fx = std::clamp(X + best * qd[0], 0.0, 1.0);
  hit.fy = std::clamp(Y + best * qd[1], 0.0, 1.0);
  return true;
}

}  // namespace meso
