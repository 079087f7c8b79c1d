#include "meso/bake/curvature.hpp"

#include "meso/core/mesh_arrays.hpp"

#include <Eigen/Dense>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace meso {

namespace {

using Vec3d = OpenMesh::Vec3d;

// Which terms a fit takes beyond h = a u^2 + b u v + c v^2 + d u + e v.
struct FitTerms {
  bool long_axis = false;  // f v'^3 + g v'^4 along the neighbourhood's long axis v'
  // The implicit terms (see fit_quadric): kNone; kSphere, k h^2; kSurface, k h^2 + (m u' + n v') h.
  enum Implicit { kNone, kSphere, kSurface } implicit = kNone;
};

// The least-squares fit of h = a' u'^2 + b' u' v' + c' v'^2 + d' u' + e' v' (+ the `terms`)
// in whitened coordinates (u', v') = W (u, v), v' along the long axis. `height_scale`
// (object units, > 0) divides h in the implicit terms' columns: the root of the mean h^4
// puts them on the scale of the whitened ones, so that the conditioning test asks whether
// the points determine their coefficients, not how small they are (scaling a column does
// not change the fit). Returns the graph's second-order Taylor coefficients at the vertex,
// a..e back in (u, v), and the norm of the fit's residual (infinite where implicit terms fit
// the points on another sheet than the vertex's); false when the points do not determine
// the fit.
bool solve_whitened(const std::vector<Eigen::Vector3d>& uvh, const Eigen::Matrix2d& W, FitTerms terms, double height_scale,
                    Eigen::Matrix<double, 5, 1>& coef, double& residual) {
  const Eigen::Index rows = static_cast<Eigen::Index>(uvh.size());
  const Eigen::Index implicit_cols = terms.implicit == FitTerms::kSurface ? 3 : terms.implicit == FitTerms::kSphere ? 1 : 0;
  const Eigen::Index cols = 5 + (terms.long_axis ? 2 : 0) + implicit_cols;
  if (rows < cols) return false;
  Eigen::MatrixXd A(rows, cols);
  Eigen::VectorXd h(rows);
  for (Eigen::Index i = 0; i < rows; ++i) {
    const auto& p = uvh[static_cast<size_t>(i)];
    const Eigen::Vector2d w = W * p.head<2>();
    const double u = w.x(), v = w.y();
    A(i, 0) = u * u;
    A(i, 1) = u * v;
    A(i, 2) = v * v;
    A(i, 3) = u;
    A(i, 4) = v;
    Eigen::Index col = 5;
    if (terms.long_axis) {
      A(i, col++) = v * v * v;
      A(i, col++) = v * v * v * v;
    }
    const double hn = p.z() / height_scale;
    if (implicit_cols >= 1) A(i, col++) = hn * hn;
    if (implicit_cols == 3) {
      A(i, col++) = u * hn;
      A(i, col++) = v * hn;
    }
    h[i] = p.z();
  }
  // Normal equations: A's singular values are the roots of A^T A's eigenvalues, and with the
  // conditioning below (at most 100 in A, 1e4 in A^T A) the solution keeps 12 digits. With a
  // Jacobi SVD of A the fit took 3 times as long on the brick wall (docs/benchmarks.md).
  const Eigen::MatrixXd N = A.transpose() * A;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(N);  // ascending
  const Eigen::VectorXd& lambda = eig.eigenvalues();
  // Ill-conditioned (the neighbours in two rows through the vertex, say): the coefficients
  // would follow rounding rather than the surface. Measured before whitening: a condition
  // number near 1e3 let -O1 and -O2 builds differ by 8% in curvature.
  if (!(lambda[0] > 1e-4 * lambda[cols - 1])) return false;  // sigma_min > 1e-2 sigma_max
  const Eigen::VectorXd c = eig.eigenvectors() * ((eig.eigenvectors().transpose() * (A.transpose() * h)).cwiseQuotient(lambda));
  residual = (A * c - h).norm();
  // Back to (u, v): h = x'^T P x' + g^T x' + ... with x' = W x, so P_uv = W^T P W and
  // g_uv = W^T g (the long axis's cubic and quartic terms do not reach the second order).
  Eigen::Matrix2d P;
  P << c[0], c[1] / 2, c[1] / 2, c[2];
  Eigen::Matrix2d P_uv = W.transpose() * P * W;
  const Eigen::Vector2d g_uv = W.transpose() * Eigen::Vector2d(c[3], c[4]);
  if (implicit_cols > 0) {
    // h = x^T P x + g . x + k h^2 + (w . x) h, with k and w in (u, v) and object units:
    // differentiated twice at the vertex (h = 0, grad h = g), the graph's Hessian is
    // 2 P + 2 k g g^T + w g^T + g w^T.
    const Eigen::Index first = 5 + (terms.long_axis ? 2 : 0);
    const double k = c[first] / (height_scale * height_scale);
    const Eigen::Vector2d w = implicit_cols == 3 ? Eigen::Vector2d(W.transpose() * Eigen::Vector2d(c[first + 1], c[first + 2]) / height_scale)
                                                 : Eigen::Vector2d::Zero();
    // Every point on the sheet through the vertex: F = q + g . x + k h^2 + (w . x) h - h has
    // dF/dh = 2 k h + w . x - 1, -1 at the vertex. On a sphere it reaches 0 at 90 degrees
    // from the vertex and 0.5 at 120 (the 2-ring of a 6-segment cylinder); above 0.75 the
    // points lie on the quadric's far side. At a step (heights 0 and s), a crease or a spike
    // the terms had fitted the heights with both sheets, h = 0 and h = 1 / k, and P = 0: zero
    // curvature where the quadric sees the feature.
    for (const auto& p : uvh)
      if (!(2 * k * p.z() + w.dot(p.head<2>()) - 1 <= 0.75)) {
        residual = std::numeric_limits<double>::infinity();  // determined, but not the surface's
        return true;
      }
    P_uv += k * g_uv * g_uv.transpose() + 0.5 * (w * g_uv.transpose() + g_uv * w.transpose());
  }
  coef << P_uv(0, 0), 2 * P_uv(0, 1), P_uv(1, 1), g_uv[0], g_uv[1];
  return coef.allFinite();
}

// What fit_quadric found: no fit, the quadric, the quadric with implicit terms, or the
// quadric where the points cannot tell whether the sphere term is needed.
enum class Fit { kNone, kQuadric, kImplicit, kUndecided };

// Least-squares fit of h = a u^2 + b u v + c v^2 + d u + e v (coefficients in that order);
// Fit::kNone when the points do not determine it. The linear terms absorb the difference between
// the vertex normal and the surface's normal, which otherwise biases the curvature where the
// neighbourhood is lopsided (anisotropic meshes).
//
// Long thin cells. Whether the points determine the fit does not depend on how (u, v) are
// scaled or sheared: a linear change of (u, v) maps the five monomials onto combinations of
// themselves. So the fit runs in whitened coordinates (u', v') = W (u, v), in which the
// points' second moments are the identity, and the conditioning test sees only what the points
// leave undetermined (all on a line, in two rows through the vertex, ...), not the cells'
// shape (a test on one isotropic scale had found every vertex of a cylinder with cells 8
// times longer than wide "undetermined"). But a neighbourhood R times longer than wide sees
// the surface's quartic term along its long axis at R^2 times the size of the quadratic
// term across it, and least squares spreads that residual into the cross coefficients (on a
// cylinder whose cells are 20 times wider around than along the axis: 0.71 of 1/r along the
// flat axis). Where the neighbourhood is more than twice as long as wide, the fit therefore
// also takes v'^3 and v'^4 along its long axis (a jet of degree 4 there, Cazals and Pouget
// 2003), which leave the second order at the vertex alone: the same cylinder then has errors
// of 0.0009 of 1/r. Where those terms are not determined (too few distinct positions along
// the axis) the plain quadric is fitted.
//
// Coarse meshes. A low-poly base mesh's rings span tens of degrees of its surface, and a
// paraboloid through them is not the surface: the quadric gave 1.30 / r on a 12-segment
// cylinder (its 2-ring 60 degrees wide) and 1.16 / r on a 16-segment one. A sphere of radius
// r tangent at the vertex, u^2 + v^2 + h^2 = 2 r h, is exactly h = (u^2 + v^2) / (2 r) +
// h^2 / (2 r), a circular cylinder likewise with the square of the coordinate across its
// axis in place of u^2 + v^2, and a tilted vertex normal only adds linear terms: with a
// term k h^2 the fit is exact on spheres and cylinders whatever the rings' width. With
// (m u + n v) h as well it is the general quadric surface through the vertex, exact on cones,
// spheroids and the other quadrics too (a circular cone of 8 segments: the quadric's error
// 0.56 of its curvature, now 5e-7). These implicit terms are of third and fourth order in
// (u, v) and change only what the fit attributes to the second order (solve_whitened reads
// the graph's Taylor coefficients off the implicit form). They are kept only where they fit
// the heights ten times better than the quadric (below), k h^2 alone first: on a sphere the
// two more columns let rounding in (2e-3 of 1/r at a vertex of a 128 x 64 sphere with
// irregular cells, against 1e-5 with k h^2 alone).
Fit fit_quadric(const std::vector<Eigen::Vector3d>& uvh, Eigen::Matrix<double, 5, 1>& coef) {
  if (uvh.size() < 5) return Fit::kNone;
  Eigen::Matrix2d moments = Eigen::Matrix2d::Zero();
  for (const auto& p : uvh) moments += p.head<2>() * p.head<2>().transpose();
  moments /= static_cast<double>(uvh.size());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> axes(moments);  // ascending: v' is the long axis
  const Eigen::Vector2d lambda = axes.eigenvalues();
  // Cells more than 1000 times longer than wide (or points on one line): the thin direction's
  // coordinates carry the positions' float rounding at 1e-4 of their size and more.
  if (!(lambda[1] > 0) || !(lambda[0] > 1e-6 * lambda[1])) return Fit::kNone;
  // W = diag(lambda)^(-1/2) Q^T.
  const Eigen::Matrix2d W = lambda.cwiseSqrt().cwiseInverse().asDiagonal() * axes.eigenvectors().transpose();
  // Measured on the cylinder: 1.5 and 2 give the same fits; 3 leaves cells twice as wide as
  // long at 0.009 of 1/r instead of 0.0035.
  const double long_axis = 2;
  const bool elongated = lambda[1] > long_axis * long_axis * lambda[0];
  double residual = 0;
  Eigen::Index quadric_cols = 7;
  if (!(elongated && solve_whitened(uvh, W, {true, FitTerms::kNone}, 1, coef, residual))) {
    quadric_cols = 5;
    if (!solve_whitened(uvh, W, {false, FitTerms::kNone}, 1, coef, residual)) return Fit::kNone;
  }
  // Where the quadric leaves more than 1e-4 of the heights unexplained, the implicit terms
  // are tried (below that, the quadric's curvature was within 6e-3 of 1/r on 128 x 64 spheres
  // whose vertices were moved by up to 0.2 of a cell), and kept where their residual per
  // degree of freedom is a tenth of the quadric's or less, with three points to spare at
  // least (with none, a fit of as many terms as points passes through them all; three is a
  // margin chosen, not measured). On the tori
  // of Curvature.CoarseTorusKeepsTheQuadricsFit and of the test before it (160 x 64 down to
  // 24 x 12) k h^2 left 0.47 of the quadric's residual at best, and its fits were worse than
  // the quadric's near the top of the tube (0.41 / r instead of 1.11 / r on 24 x 12, against
  // 1 / r): a torus is not a quadric.
  double norm = 0, height = 0, h4 = 0;
  for (const auto& p : uvh) {
    norm += p.z() * p.z();
    height = std::max(height, std::abs(p.z()));
    h4 += p.z() * p.z() * p.z() * p.z();
  }
  const double size = std::sqrt(lambda[1]);
  const bool misfit = residual > 1e-4 * std::sqrt(norm);
  // The quadric explains the heights, and they are too low for a sphere's quartic term to
  // matter: through a circle of radius rho at height h the paraboloid's curvature is the
  // sphere's times 1 + (h / rho)^2, here 1 + 1e-3 at most. (At 1e-2 of the size, every
  // vertex of a 512 x 256 sphere tried k h^2 for 1e-4 of curvature, and the fit, then solved
  // by an SVD, took 2.5 times as long.)
  if (!misfit && !(height > 0.03 * size)) return Fit::kQuadric;
  const double scale = std::sqrt(std::sqrt(h4 / static_cast<double>(uvh.size())));
  const double points = static_cast<double>(uvh.size());
  // The fit with implicit `terms` (`cols` columns), where the points determine it with three
  // to spare: its coefficients and its residual per degree of freedom (infinite when it is
  // not determined or not the vertex's surface).
  struct Implicit {
    bool determined = false;
    Eigen::Matrix<double, 5, 1> coef;
    double residual = std::numeric_limits<double>::infinity();
  };
  auto fit = [&](FitTerms::Implicit terms, double cols) {
    Implicit f;
    double r = 0;
    f.determined = points >= cols + 3 && solve_whitened(uvh, W, {false, terms}, scale, f.coef, r);
    if (f.determined) f.residual = r / std::sqrt(points - cols);
    return f;
  };
  const double quadric_residual = residual / std::sqrt(points - static_cast<double>(quadric_cols));
  const Implicit sphere = fit(FitTerms::kSphere, 6);
  if (misfit) {
    // The general surface where it fits ten times better than k h^2 alone too (a cylinder
    // whose vertex normal tilts along its axis), else k h^2 where it fits ten times better
    // than the quadric.
    const Implicit surface = fit(FitTerms::kSurface, 8);
    const Implicit& best = surface.residual <= 0.1 * sphere.residual || std::isinf(sphere.residual) ? surface : sphere;
    if (std::isfinite(best.residual) && best.residual <= 0.1 * quadric_residual) {
      coef = best.coef;
      return Fit::kImplicit;
    }
    // Too few points to tell whether the implicit terms would fit (a coarse sphere's pole
    // has 8 neighbours): the next ring decides.
    return sphere.determined || surface.determined ? Fit::kQuadric : Fit::kUndecided;
  }
  // The quadric explains the heights, which are high enough for the sphere term to matter,
  // but the term is not determined: the points cannot tell the two apart (a pole's 1-ring,
  // on one circle, through which a sphere and a paraboloid both pass).
  return sphere.determined ? Fit::kQuadric : Fit::kUndecided;
}

// fit_vertex's working memory, reused from vertex to vertex.
struct FitScratch {
  std::vector<VertexHandle> ring;
  std::vector<Eigen::Vector3d> uvh;
};

// fit_curvature's work for vertex v, which depends on v's rings only (so the result does not
// depend on the threads).
VertexCurvature fit_vertex(const Mesh& mesh, VertexHandle v, FitScratch& scratch) {
  std::vector<VertexHandle>& ring = scratch.ring;
  std::vector<Eigen::Vector3d>& uvh = scratch.uvh;
  VertexCurvature out;
  Vec3d n = OpenMesh::vector_cast<Vec3d>(mesh.normal(v));
  if (!(n.norm() > 0)) return out;
  n.normalize();
  const Vec3d t = any_perpendicular(n), b = OpenMesh::cross(n, t);
  const Vec3d p = OpenMesh::vector_cast<Vec3d>(mesh.point(v));
  // Without a fit the directions are still a frame of the tangent plane (k1 = k2 = 0 leaves
  // them arbitrary, but a consumer that builds a frame from d1 gets a valid one).
  out.d1 = OpenMesh::vector_cast<Vec3f>(t);
  out.d2 = OpenMesh::vector_cast<Vec3f>(b);
  // Gather the 1-ring, then grow ring by ring (2, then 3) while the neighbourhood does not
  // determine the fit, or cannot tell whether it needs the sphere term.
  // Rings hold tens of vertices (a few hundred around a pole): a linear search keeps each
  // once, in the order found, without per-vertex marks over the whole mesh.
  ring.clear();
  auto take = [&](VertexHandle w) {
    if (w != v && std::find(ring.begin(), ring.end(), w) == ring.end()) ring.push_back(w);
  };
  for (auto w : mesh.vv_range(v)) take(w);
  Eigen::Matrix<double, 5, 1> coef, wider;
  int rings = 0;
  bool undecided = false;  // the fit's ring cannot tell a sphere from its quadric
  size_t frontier = 0;     // the vertices the last ring added start here
  for (int r = 1; r <= 3 && (rings == 0 || undecided); ++r) {
    if (r >= 2) {
      const size_t end = ring.size();
      for (size_t i = frontier; i < end; ++i)
        for (auto w : mesh.vv_range(ring[i])) take(w);
      frontier = end;
    }
    if (r == 1 && ring.size() < 8) continue;  // 5 unknowns: want real redundancy
    uvh.clear();
    for (auto w : ring) {
      const Vec3d d = OpenMesh::vector_cast<Vec3d>(mesh.point(w)) - p;
      uvh.emplace_back(OpenMesh::dot(d, t), OpenMesh::dot(d, b), OpenMesh::dot(d, n));
    }
    if (rings == 0) {
      const Fit fit = fit_quadric(uvh, coef);
      rings = fit == Fit::kNone ? 0 : r;
      undecided = fit == Fit::kUndecided;
    } else {
      // The next ring decides an undecided fit, and replaces it only with an implicit one:
      // the poles of a coarse UV sphere (16 x 8: the paraboloid through the pole's ring gave
      // 1.04 / r) get the sphere, the apex of a paraboloid keeps its 1-ring.
      if (fit_quadric(uvh, wider) == Fit::kImplicit) {
        coef = wider;
        rings = r;
      }
      undecided = false;
    }
  }
  if (rings == 0) return out;
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
  if (!std::isfinite(static_cast<float>(eig.eigenvalues()[0])) || !std::isfinite(static_cast<float>(eig.eigenvalues()[1]))) return out;
  // + 0: a flat neighbourhood's -0 (a plane's fit gives either sign) is written as 0.
  out.k1 = static_cast<float>(eig.eigenvalues()[1]) + 0.0f;
  out.k2 = static_cast<float>(eig.eigenvalues()[0]) + 0.0f;
  const Eigen::Vector2d e1 = Li.transpose() * eig.eigenvectors().col(1);
  // The direction in the vertex normal's tangent plane (what the exported NORMAL and
  // TANGENT span): the in-plane part of the fitted surface's direction.
  const Vec3d d1 = (t * e1[0] + b * e1[1]).normalize();
  out.d1 = OpenMesh::vector_cast<Vec3f>(d1);
  out.d2 = OpenMesh::vector_cast<Vec3f>(OpenMesh::cross(n, d1));
  out.rings = rings;
  return out;
}

}  // namespace

std::vector<VertexCurvature> fit_curvature(const Mesh& mesh) {
  std::vector<VertexCurvature> out(mesh.n_vertices());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.n_vertices(), 256), [&](const tbb::blocked_range<size_t>& range) {
    FitScratch scratch;
    for (size_t i = range.begin(); i != range.end(); ++i) out[i] = fit_vertex(mesh, VertexHandle(static_cast<int>(i)), scratch);
  });
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
