#include "meso/bake/curvature.hpp"

#include "meso/core/mesh_arrays.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

namespace meso {

namespace {

using Vec3d = OpenMesh::Vec3d;

// Least-squares fit of h = a u^2 + b u v + c v^2 + d u + e v (coefficients in that order);
// false when the points do not determine it. The linear terms absorb the difference between
// the vertex normal and the surface's normal, which otherwise biases the curvature where the
// neighbourhood is lopsided (anisotropic meshes).
bool fit_quadric(const std::vector<Eigen::Vector3d>& uvh, Eigen::Matrix<double, 5, 1>& coef) {
  if (uvh.size() < 5) return false;
  double scale = 0;
  for (const auto& p : uvh) scale = std::max(scale, p.x() * p.x() + p.y() * p.y());
  if (!(scale > 0)) return false;
  const double s = std::sqrt(scale);
  // Fit in coordinates scaled to the neighbourhood's size (u' = u/s, h' = h/s), so the
  // conditioning test is unitless; then a = a'/s, ..., d = d'.
  Eigen::MatrixXd A(static_cast<Eigen::Index>(uvh.size()), 5);
  Eigen::VectorXd h(static_cast<Eigen::Index>(uvh.size()));
  for (size_t i = 0; i < uvh.size(); ++i) {
    const double u = uvh[i].x() / s, v = uvh[i].y() / s;
    A.row(static_cast<Eigen::Index>(i)) << u * u, u * v, v * v, u, v;
    h[static_cast<Eigen::Index>(i)] = uvh[i].z() / s;
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const auto& sv = svd.singularValues();
  // Ill-conditioned (e.g. all neighbours near one line, or a lopsided ring on an anisotropic
  // mesh): the coefficients would follow rounding rather than the surface. Measured: a
  // condition number near 1e3 let -O1 and -O2 builds differ by 8% in curvature.
  if (!(sv[4] > 1e-2 * sv[0])) return false;
  coef = svd.solve(h);
  coef.head<3>() /= s;
  return coef.allFinite();
}

}  // namespace

std::vector<VertexCurvature> fit_curvature(const Mesh& mesh) {
  std::vector<VertexCurvature> out(mesh.n_vertices());
  std::vector<int> mark(mesh.n_vertices(), -1);
  std::vector<VertexHandle> ring;
  std::vector<Eigen::Vector3d> uvh;
  for (auto v : mesh.vertices()) {
    Vec3d n = OpenMesh::vector_cast<Vec3d>(mesh.normal(v));
    if (!(n.norm() > 0)) continue;
    n.normalize();
    const Vec3d t = any_perpendicular(n), b = OpenMesh::cross(n, t);
    const Vec3d p = OpenMesh::vector_cast<Vec3d>(mesh.point(v));
    // Gather the 1-ring, then grow ring by ring (2, then 3) while the neighbourhood does not
    // determine the fit.
    ring.clear();
    mark[static_cast<size_t>(v.idx())] = v.idx();
    for (auto w : mesh.vv_range(v)) {
      if (mark[static_cast<size_t>(w.idx())] == v.idx()) continue;
      mark[static_cast<size_t>(w.idx())] = v.idx();
      ring.push_back(w);
    }
    Eigen::Matrix<double, 5, 1> coef;
    int rings = 0;
    size_t frontier = 0;  // the vertices the last ring added start here
    for (int r = 1; r <= 3 && rings == 0; ++r) {
      if (r >= 2) {
        const size_t end = ring.size();
        for (size_t i = frontier; i < end; ++i)
          for (auto w : mesh.vv_range(ring[i])) {
            if (mark[static_cast<size_t>(w.idx())] == v.idx()) continue;
            mark[static_cast<size_t>(w.idx())] = v.idx();
            ring.push_back(w);
          }
        frontier = end;
      }
      if (r == 1 && ring.size() < 8) continue;  // 5 unknowns: want real redundancy
      uvh.clear();
      for (auto w : ring) {
        const Vec3d d = OpenMesh::vector_cast<Vec3d>(mesh.point(w)) - p;
        uvh.emplace_back(OpenMesh::dot(d, t), OpenMesh::dot(d, b), OpenMesh::dot(d, n));
      }
      if (fit_quadric(uvh, coef)) rings = r;
    }
    if (rings == 0) continue;
    // The fitted graph x(u, v) = p + u t + v b + h(u, v) n at the origin: tangents
    // x_u = t + d n, x_v = b + e n; first fundamental form I = [[1+d^2, de], [de, 1+e^2]];
    // second, with the unit normal N = (n - d t - e b) / sqrt(1 + d^2 + e^2):
    // II = [[2a, b], [b, 2c]] / sqrt(1 + d^2 + e^2). The shape operator is I^-1 II; the
    // curvature is its negative (convex positive: the surface bends away from N).
    const double a = coef[0], bb = coef[1], cc = coef[2], du = coef[3], dv = coef[4];
    const double g = std::sqrt(1 + du * du + dv * dv);
    Eigen::Matrix2d I, II;
    I << 1 + du * du, du * dv, du * dv, 1 + dv * dv;
    II << -2 * a / g, -bb / g, -bb / g, -2 * cc / g;
    // Symmetrise with the Cholesky factor I = L L^T: L^-1 II L^-T has the same eigenvalues,
    // and eigenvectors y map back to (u, v) directions as L^-T y.
    const Eigen::Matrix2d L = I.llt().matrixL();
    const Eigen::Matrix2d Li = L.inverse();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(Li * II * Li.transpose());  // ascending
    // Beyond float (features ~1e-39 across on a mesh of ordinary size): no fit, as where the
    // rings cannot determine one, rather than Inf in the mesh's _CURVATURE.
    if (!std::isfinite(static_cast<float>(eig.eigenvalues()[0])) || !std::isfinite(static_cast<float>(eig.eigenvalues()[1]))) continue;
    VertexCurvature& c = out[static_cast<size_t>(v.idx())];
    c.k1 = static_cast<float>(eig.eigenvalues()[1]);
    c.k2 = static_cast<float>(eig.eigenvalues()[0]);
    const Eigen::Vector2d e1 = Li.transpose() * eig.eigenvectors().col(1);
    // The direction in the vertex normal's tangent plane (what the exported NORMAL and
    // TANGENT span): the in-plane part of the fitted surface's direction.
    const Vec3d d1 = (t * e1[0] + b * e1[1]).normalize();
    c.d1 = OpenMesh::vector_cast<Vec3f>(d1);
    c.d2 = OpenMesh::vector_cast<Vec3f>(OpenMesh::cross(n, d1));
    c.rings = rings;
  }
  return out;
}

void store_curvature(Mesh& mesh, const std::vector<VertexCurvature>& curvature) {
  OpenMesh::VPropHandleT<OpenMesh::Vec2f> k;
  OpenMesh::VPropHandleT<OpenMesh::Vec3f> d;
  if (!mesh.get_property_handle(k, kCurvatureProperty)) mesh.add_property(k, kCurvatureProperty);
  if (!mesh.get_property_handle(d, kPrincipalDirectionProperty)) mesh.add_property(d, kPrincipalDirectionProperty);
  for (auto v : mesh.vertices()) {
    const auto& c = curvature[static_cast<size_t>(v.idx())];
    mesh.property(k, v) = OpenMesh::Vec2f(c.k1, c.k2);
    mesh.property(d, v) = c.d1;
  }
}

}  // namespace meso
