// Curved PN triangles (Vlachos, Peters, Boyd and Mitchell, "Curved PN Triangles", I3D 2001):
// from a triangle's corner positions and normals alone, a cubic Bezier patch for the
// position and a quadratic one for the normal. meso bakes against it with --basis pn, for
// renderers that tessellate the base mesh into this surface.
#pragma once

#include <Eigen/Dense>

#include <array>

namespace meso {

// Position and (unit) normal of the PN patch at barycentrics w (corners 0, 1, 2). Normals
// need not be unit; they are normalised first.
inline void pn_triangle(const std::array<Eigen::Vector3d, 3>& p, std::array<Eigen::Vector3d, 3> n, const std::array<double, 3>& w,
                        Eigen::Vector3d& position, Eigen::Vector3d& normal) {
  for (auto& v : n)
    if (v.norm() > 0) v.normalize();
  // Control points: each edge third pushed into the corner's tangent plane (paper, eq. 2).
  auto edge = [&](int i, int j) { return (2.0 * p[i] + p[j] - (p[j] - p[i]).dot(n[i]) * n[i]) / 3.0; };
  const Eigen::Vector3d b210 = edge(0, 1), b120 = edge(1, 0), b021 = edge(1, 2), b012 = edge(2, 1), b102 = edge(2, 0), b201 = edge(0, 2);
  const Eigen::Vector3d e = (b210 + b120 + b021 + b012 + b102 + b201) / 6.0, v = (p[0] + p[1] + p[2]) / 3.0;
  const Eigen::Vector3d b111 = e + (e - v) / 2.0;
  const double u = w[0], s = w[1], t = w[2];
  position = p[0] * u * u * u + p[1] * s * s * s + p[2] * t * t * t + 3.0 * (b210 * u * u * s + b120 * u * s * s + b201 * u * u * t +
                                                                             b021 * s * s * t + b102 * u * t * t + b012 * s * t * t) +
             6.0 * b111 * u * s * t;
  // Quadratic normal: mid-edge normals reflected across the plane perpendicular to the edge
  // (eq. 3), so that inflections are captured.
  auto mid = [&](int i, int j) {
    const Eigen::Vector3d d = p[j] - p[i];
    const double len2 = d.squaredNorm();
    const double k = len2 > 0 ? 2.0 * d.dot(n[i] + n[j]) / len2 : 0.0;
    Eigen::Vector3d m = n[i] + n[j] - k * d;
    return m.norm() > 0 ? Eigen::Vector3d(m.normalized()) : Eigen::Vector3d(n[i]);
  };
  normal = n[0] * u * u + n[1] * s * s + n[2] * t * t + mid(0, 1) * u * s + mid(1, 2) * s * t + mid(2, 0) * t * u;
  if (normal.norm() > 0) normal.normalize();
}

}  // namespace meso
