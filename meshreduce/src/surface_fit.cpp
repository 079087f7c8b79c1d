#include "surface_fit.hpp"
#include "meso/core/float_rounding.hpp"

#include "closest_triangles.hpp"

#include <Eigen/Sparse>
#include <Eigen/IterativeLinearSolvers>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <stdexcept>

namespace meso::reduce {

namespace {

Vec3d position(const Mesh& mesh, VertexHandle v) { return point(mesh.point(v)); }

// A face's corners (face_halfedges order).
struct FaceCorners {
  std::array<int, 3> v;
};

std::vector<FaceCorners> face_corners(const Mesh& mesh) {
  std::vector<FaceCorners> out(mesh.n_faces());
  for (auto f : mesh.faces()) {
    const auto hs = face_halfedges(mesh, f);
    for (size_t k = 0; k < 3; ++k) out[static_cast<size_t>(f.idx())].v[k] = mesh.to_vertex_handle(hs[k]).idx();
  }
  return out;
}

Vec3d normal_of(const std::vector<Vec3d>& p, const FaceCorners& f) {
  const Vec3d& a = p[static_cast<size_t>(f.v[0])];
  return OpenMesh::cross(p[static_cast<size_t>(f.v[1])] - a, p[static_cast<size_t>(f.v[2])] - a);
}

// The mean normals of the input where a face is (unit; zero if unknown): over its own
// attached samples, and over its corners' faces' samples.
struct Facing {
  Vec3d own{0, 0, 0}, ring{0, 0, 0};
};

// Whether moving a face's corners from `before` to `after` keeps it acceptable: it neither
// turns by 90 degrees or more (from `before`, nor from the `original` positions before the
// fit) nor degenerates; its cosine to facing.own does not fall below min(its cosine before,
// cos 60 degrees), nor its cosine to facing.ring below min(before, 0); and it does not
// become a needle beyond the bound (or a worse one).
bool acceptable(const std::vector<Vec3d>& original, const std::vector<Vec3d>& before, const std::vector<Vec3d>& after, const FaceCorners& f,
                const Facing& facing, double max_aspect) {
  const Vec3d n0 = normal_of(before, f), n1 = normal_of(after, f);
  if (!(OpenMesh::dot(n0, n1) > 0) || !(OpenMesh::dot(normal_of(original, f), n1) > 0) || !(n1.sqrnorm() > 0)) return false;
  auto keeps = [&](const Vec3d& m, double floor) {
    if (!(m.sqrnorm() > 0)) return true;
    const double c0 = OpenMesh::dot(n0, m) / n0.norm(), c1 = OpenMesh::dot(n1, m) / n1.norm();
    return c1 >= std::min(c0, floor);
  };
  if (!keeps(facing.own, 0.5) || !keeps(facing.ring, 0.0)) return false;
  if (max_aspect <= 0) return true;
  auto aspect = [&](const std::vector<Vec3d>& p) {
    return aspect_ratio(p[static_cast<size_t>(f.v[0])], p[static_cast<size_t>(f.v[1])], p[static_cast<size_t>(f.v[2])]);
  };
  const double a1 = aspect(after);
  return a1 <= max_aspect || a1 <= aspect(before);
}

}  // namespace

struct SurfaceFitTarget::Impl {
  std::vector<Vec3d> points;
  std::vector<double> weights;
  std::vector<Vec3d> normals;  // of the input at each point (unit; area-weighted at vertices)
  std::vector<Triangle> triangles;  // non-degenerate ones
  std::unique_ptr<ClosestTriangles> tree;
  double mean_edge = 1;  // of those triangles
};

SurfaceFitTarget::SurfaceFitTarget(const Mesh& input) : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  std::vector<double> vertex_weight(input.n_vertices(), 0.0);
  std::vector<Vec3d> vertex_normal(input.n_vertices(), Vec3d(0, 0, 0));
  for (auto f : input.faces()) {
    const auto hs = face_halfedges(input, f);
    std::array<Vec3d, 3> c;
    for (size_t k = 0; k < 3; ++k) c[k] = position(input, input.to_vertex_handle(hs[k]));
    const Triangle t{c[0], c[1], c[2]};
    if (t.degenerate()) continue;
    s.triangles.push_back(t);
    const double area = t.area();
    const Vec3d n = OpenMesh::cross(c[1] - c[0], c[2] - c[0]);  // twice the area long
    for (size_t k = 0; k < 3; ++k) {
      const size_t v = static_cast<size_t>(input.to_vertex_handle(hs[k]).idx());
      vertex_weight[v] += area / 3;
      vertex_normal[v] += n;
    }
    s.points.push_back((c[0] + c[1] + c[2]) / 3.0);
    s.weights.push_back(area / 3);
    s.normals.push_back(n / n.norm());
  }
  for (auto v : input.vertices()) {
    const double w = vertex_weight[static_cast<size_t>(v.idx())];
    if (!(w > 0)) continue;
    const Vec3d n = vertex_normal[static_cast<size_t>(v.idx())];
    s.points.push_back(position(input, v));
    s.weights.push_back(w);
    s.normals.push_back(n.sqrnorm() > 0 ? Vec3d(n / n.norm()) : Vec3d(0, 0, 0));
  }
  s.tree = std::make_unique<ClosestTriangles>(s.triangles);
  s.mean_edge = mean_edge(s.triangles);
}

SurfaceFitTarget::~SurfaceFitTarget() = default;

SurfaceFitReport fit_to_surface(Mesh& mesh, const SurfaceFitTarget& target, const std::vector<uint8_t>& fixed,
                                const SurfaceFitOptions& options) {
  SurfaceFitReport rep;
  const SurfaceFitTarget::Impl& in = target.impl();
  const size_t nv = mesh.n_vertices();
  if (fixed.size() != nv) throw std::invalid_argument("fit_to_surface: one fixed flag per vertex");
  if (!options.tethered.empty() && options.tethered.size() != nv) throw std::invalid_argument("fit_to_surface: one tethered flag per vertex");
  // Unknowns: the free vertices, numbered in vertex order.
  std::vector<int> unknown(nv, -1);
  int n_free = 0;
  for (size_t i = 0; i < nv; ++i)
    if (!fixed[i] && !mesh.is_isolated(VertexHandle(static_cast<int>(i)))) unknown[i] = n_free++;
  rep.free_vertices = static_cast<size_t>(n_free);
  if (n_free == 0 || in.points.empty() || mesh.n_faces() == 0) return rep;

  const std::vector<FaceCorners> faces = face_corners(mesh);
  std::vector<std::vector<int>> vertex_faces(nv);
  for (size_t f = 0; f < faces.size(); ++f)
    for (const int v : faces[f].v) vertex_faces[static_cast<size_t>(v)].push_back(static_cast<int>(f));
  std::vector<Vec3d> pos(nv);
  for (size_t i = 0; i < nv; ++i) pos[i] = position(mesh, VertexHandle(static_cast<int>(i)));
  double total_weight = 0;
  for (const double w : in.weights) total_weight += w;
  // The pull toward the current positions: a hundredth of the weight a vertex attracts on
  // average, so that it decides only where the samples do not.
  const double lambda = 1e-2 * total_weight / static_cast<double>(n_free);

  // One residual: a point of the output, sum_k b_k v_k over a face's corners, and where it
  // should be. Forward rows: an input sample and its closest point on the output (Hoppe et
  // al.'s E_dist). Backward rows: fixed points of each output face and their closest points
  // on the input, so that the fit also sees output that stands off the input (the other
  // half of the Hausdorff distance).
  struct Row {
    int face = -1;
    double b[3] = {0, 0, 0};
    Vec3d goal{0, 0, 0};
    double weight = 0, distance = 0;
    int64_t near = -1;  // the nearest triangle last time: the next search's first guess
  };
  // Corners, edge midpoints and centroid: where a flat face stands off a curved surface
  // most (corners and edges) and its middle.
  static constexpr int kBackwardPoints = 7, kCentroid = 6;
  static constexpr double kBackward[kBackwardPoints][3] = {{1, 0, 0},     {0, 1, 0},     {0, 0, 1},          {0.5, 0.5, 0},
                                                           {0, 0.5, 0.5}, {0.5, 0, 0.5}, {1.0 / 3, 1.0 / 3, 1.0 / 3}};
  // Forward rows: every stride-th input sample, weighted by the stride, about max_samples.
  const size_t stride = options.max_samples == 0 ? 1 : std::max<size_t>(1, (in.points.size() + options.max_samples - 1) / options.max_samples);
  const size_t n_forward = (in.points.size() + stride - 1) / stride;
  std::vector<Row> rows(n_forward + kBackwardPoints * faces.size());
  struct FaceBlock {
    double m[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    Vec3d goal[3] = {Vec3d(0, 0, 0), Vec3d(0, 0, 0), Vec3d(0, 0, 0)};
  };
  std::vector<FaceBlock> block(faces.size());
  std::vector<Facing> facing(faces.size());
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(9 * faces.size() + static_cast<size_t>(n_free));
  // The positions whose largest sampled distance (both ways) was the smallest: the
  // reweighting can overshoot, and the last iterate is not always the best.
  const std::vector<Vec3d> original = pos;
  std::vector<Vec3d> best_pos = pos;
  double best_max = std::numeric_limits<double>::infinity();
  for (int it = 0; it <= options.iterations; ++it) {
    // Forward: attach every input sample to its closest point on the current output.
    std::vector<Triangle> tris;
    std::vector<int> tri_face;
    std::vector<int64_t> face_tri(faces.size(), -1);
    tris.reserve(faces.size());
    for (size_t f = 0; f < faces.size(); ++f) {
      const Triangle t{pos[static_cast<size_t>(faces[f].v[0])], pos[static_cast<size_t>(faces[f].v[1])], pos[static_cast<size_t>(faces[f].v[2])]};
      if (t.degenerate()) continue;
      face_tri[f] = static_cast<int64_t>(tris.size());
      tris.push_back(t);
      tri_face.push_back(static_cast<int>(f));
    }
    if (tris.empty()) break;
    const ClosestTriangles tree(tris);
    // First guesses (ClosestTriangles::nearest: the answer does not depend on them): the
    // sample's face last time, else the previous sample's nearest.
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n_forward, 2048), [&](const tbb::blocked_range<size_t>& r) {
      int64_t hint = -1;
      for (size_t i = r.begin(); i < r.end(); ++i) {
        const size_t si = i * stride;
        Row& row = rows[i];
        if (row.face >= 0 && face_tri[static_cast<size_t>(row.face)] >= 0) hint = face_tri[static_cast<size_t>(row.face)];
        const auto [d2, id] = tree.nearest(in.points[si], hint);
        hint = id;
        row.face = -1;
        if (id < 0) continue;
        const Triangle& t = tris[static_cast<size_t>(id)];
        double w[3];
        closest_point_sqr(in.points[si], t.a, t.b, t.c, w);
        // A sliver's rounding can leave the weights slightly outside [0, 1]: clamp them.
        double sum = 0;
        for (double& x : w) sum += (x = std::clamp(x, 0.0, 1.0));
        if (!(sum > 0)) continue;
        row.face = tri_face[static_cast<size_t>(id)];
        for (int k = 0; k < 3; ++k) row.b[k] = w[k] / sum;
        row.goal = in.points[si];
        row.weight = in.weights[si] * static_cast<double>(stride);
        row.distance = std::sqrt(d2);
      }
    });
    // Which way the input faces where each face is: the mean normal of the input samples
    // attached to it, and of those attached to it and the faces sharing a corner with it (a
    // face's own samples can all lie on one side of a ridge; its neighbourhood's see the
    // surface it belongs to).
    std::vector<Vec3d> own(faces.size(), Vec3d(0, 0, 0));
    for (size_t i = 0; i < n_forward; ++i)
      if (rows[i].face >= 0) own[static_cast<size_t>(rows[i].face)] += rows[i].weight * in.normals[i * stride];
    std::vector<Vec3d> around(nv, Vec3d(0, 0, 0));
    for (size_t f = 0; f < faces.size(); ++f)
      for (const int v : faces[f].v) around[static_cast<size_t>(v)] += own[f];
    for (size_t f = 0; f < faces.size(); ++f) {
      Vec3d m(0, 0, 0);
      for (const int v : faces[f].v) m += around[static_cast<size_t>(v)];
      facing[f].own = own[f].sqrnorm() > 0 ? Vec3d(own[f] / own[f].norm()) : Vec3d(0, 0, 0);
      facing[f].ring = m.sqrnorm() > 0 ? Vec3d(m / m.norm()) : Vec3d(0, 0, 0);
    }
    // Backward: points of each output face to their closest points on the input.
    tbb::parallel_for(tbb::blocked_range<size_t>(0, faces.size(), 512), [&](const tbb::blocked_range<size_t>& r) {
      int64_t hint = -1;
      for (size_t f = r.begin(); f < r.end(); ++f) {
        const FaceCorners& fc = faces[f];
        const Vec3d& a = pos[static_cast<size_t>(fc.v[0])];
        const Vec3d& b = pos[static_cast<size_t>(fc.v[1])];
        const Vec3d& c = pos[static_cast<size_t>(fc.v[2])];
        const double area = 0.5 * OpenMesh::cross(b - a, c - a).norm();
        for (int j = 0; j < kBackwardPoints; ++j) {
          Row& row = rows[n_forward + kBackwardPoints * f + static_cast<size_t>(j)];
          row.face = -1;
          if (!(area > 0)) {
            row.near = -1;
            continue;
          }
          const Vec3d x = a * kBackward[j][0] + b * kBackward[j][1] + c * kBackward[j][2];
          if (row.near >= 0) hint = row.near;
          const auto [d2, id] = in.tree->nearest(x, hint);
          hint = row.near = id;
          if (id < 0) continue;
          const Triangle& t = in.triangles[static_cast<size_t>(id)];
          double w[3];
          closest_point_sqr(x, t.a, t.b, t.c, w);
          row.face = static_cast<int>(f);
          for (int k = 0; k < 3; ++k) row.b[k] = kBackward[j][k];
          row.goal = t.a * w[0] + t.b * w[1] + t.c * w[2];
          row.weight = area / kBackwardPoints;
          row.distance = std::sqrt(d2);
        }
      }
    });
    double max_distance = 0;
    for (const Row& row : rows)
      if (row.face >= 0) max_distance = std::max(max_distance, row.distance);
    if (max_distance < best_max) {
      best_max = max_distance;
      best_pos = pos;
    }
    if (it == options.iterations) break;  // the last pass only measures
    // IRLS toward the L_p norm: p from 2 up to options.power over the iterations.
    const double p = options.iterations > 1 ? 2.0 + (options.power - 2.0) * it / (options.iterations - 1) : 2.0;
    double sum_w = 0, sum_wd2 = 0;
    for (const Row& row : rows)
      if (row.face >= 0) sum_w += row.weight, sum_wd2 += row.weight * row.distance * row.distance;
    const double rms = sum_w > 0 ? std::sqrt(sum_wd2 / sum_w) : 0;

    // The normal equations (A^T W A + lambda I) v = A^T W x + lambda v', gathered per face
    // first (a row touches one face's three corners: a 3 x 3 block and three goals), in row
    // order: the same sums whatever the threads. Fixed corners go to the right-hand side.
    std::fill(block.begin(), block.end(), FaceBlock{});
    for (const Row& row : rows) {
      if (row.face < 0) continue;
      double w = row.weight;
      if (p > 2 && rms > 0) w *= std::pow(std::max(row.distance / rms, 0.1), p - 2);
      FaceBlock& fb = block[static_cast<size_t>(row.face)];
      for (int j = 0; j < 3; ++j) {
        for (int k = 0; k < 3; ++k) fb.m[j][k] += w * row.b[j] * row.b[k];
        fb.goal[j] += (w * row.b[j]) * row.goal;
      }
    }
    triplets.clear();
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n_free, 3);
    for (size_t f = 0; f < faces.size(); ++f) {
      const FaceBlock& fb = block[f];
      for (int j = 0; j < 3; ++j) {
        const int uj = unknown[static_cast<size_t>(faces[f].v[j])];
        if (uj < 0) continue;
        Vec3d r = fb.goal[j];
        for (int k = 0; k < 3; ++k) {
          const int uk = unknown[static_cast<size_t>(faces[f].v[k])];
          if (uk >= 0) triplets.emplace_back(uj, uk, fb.m[j][k]);
          else r -= fb.m[j][k] * pos[static_cast<size_t>(faces[f].v[k])];
        }
        for (int c = 0; c < 3; ++c) rhs(uj, c) += r[c];
      }
    }
    for (size_t i = 0; i < nv; ++i) {
      const int u = unknown[i];
      if (u < 0) continue;
      triplets.emplace_back(u, u, lambda);
      for (int c = 0; c < 3; ++c) rhs(u, c) += lambda * pos[i][c];
    }
    Eigen::SparseMatrix<double> normal(n_free, n_free);
    normal.setFromTriplets(triplets.begin(), triplets.end());
    // Conjugate gradients from the current positions (the system is symmetric positive
    // definite: lambda > 0): linear work and memory per iteration, where a sparse Cholesky
    // factor of a million-vertex mesh fills in far beyond the matrix. Eigen's sparse
    // products run in a fixed order: the same bits whatever TBB does.
    Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper> solver;
    solver.setTolerance(1e-10);
    solver.setMaxIterations(500);
    solver.compute(normal);
    if (solver.info() != Eigen::Success) break;
    Eigen::MatrixXd guess(n_free, 3);
    for (size_t i = 0; i < nv; ++i)
      if (unknown[i] >= 0)
        for (int c = 0; c < 3; ++c) guess(unknown[i], c) = pos[i][c];
    const Eigen::MatrixXd solution = solver.solveWithGuess(rhs, guess);
    if (!solution.allFinite()) break;
    ++rep.iterations;

    // Move, then undo the moves of the corners of any face the move made unacceptable,
    // until none is left (each round undoes at least one vertex, so this ends).
    std::vector<Vec3d> next = pos;
    for (size_t i = 0; i < nv; ++i) {
      if (unknown[i] < 0) continue;
      // As it will be stored (float), so that the checks below hold for the output itself.
      const Eigen::Index u = unknown[i];
      Vec3d goal(solution(u, 0), solution(u, 1), solution(u, 2));
      if (!options.tethered.empty() && options.tethered[i]) {
        // Back along the move to the tether, less a margin for the rounding to float below.
        const Vec3d move = goal - original[i];
        const double length = move.norm(), reach = 0.999 * options.tether;
        if (length > reach) goal = original[i] + move * (reach / length);
      }
      next[i] = point(Vec3f(round_to_float(goal[0]), round_to_float(goal[1]), round_to_float(goal[2])));  // (float_rounding.hpp)
    }
    // A face must also keep facing the input where it lies, as the bench counts flips: its
    // normal against that of the input triangle nearest its centroid (unless it faced away
    // before the move too).
    // (The centroid's backward row holds the input triangle nearest it before the move: the
    // answer for `pos`, and the first guess for `next`.)
    auto faces_input = [&](bool moved, size_t f) {
      const std::vector<Vec3d>& at = moved ? next : pos;
      const FaceCorners& fc = faces[f];
      // (As the centroid's row computes it, so that `before` is its answer exactly.)
      const Vec3d centroid = at[static_cast<size_t>(fc.v[0])] * kBackward[kCentroid][0] + at[static_cast<size_t>(fc.v[1])] * kBackward[kCentroid][1] +
                             at[static_cast<size_t>(fc.v[2])] * kBackward[kCentroid][2];
      const int64_t before = rows[n_forward + kBackwardPoints * f + kCentroid].near;
      const int64_t id = !moved && before >= 0 ? before : in.tree->nearest(centroid, before).second;
      if (id < 0) return true;
      const Triangle& t = in.triangles[static_cast<size_t>(id)];
      return OpenMesh::dot(normal_of(at, fc), OpenMesh::cross(t.b - t.a, t.c - t.a)) >= 0;
    };
    auto ok = [&](size_t f) {
      return acceptable(original, pos, next, faces[f], facing[f], options.max_aspect_ratio) && (faces_input(true, f) || !faces_input(false, f));
    };
    std::vector<uint8_t> check(faces.size(), 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, faces.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t f = r.begin(); f < r.end(); ++f) check[f] = !ok(f);
    });
    for (bool changed = true; changed;) {
      changed = false;
      for (size_t f = 0; f < faces.size(); ++f) {
        if (!check[f]) continue;
        check[f] = 0;
        if (ok(f)) continue;
        for (const int v : faces[f].v) {
          const size_t vi = static_cast<size_t>(v);
          if (next[vi] == pos[vi]) continue;
          next[vi] = pos[vi];
          ++rep.held_back;
          for (const int g : vertex_faces[vi]) check[static_cast<size_t>(g)] = 1;
          changed = true;
        }
      }
    }
    pos = std::move(next);
  }
  pos = std::move(best_pos);
  // Last, every face moved against the input triangles nearest samples over it
  // (faces_away_screened, the bench's measure of a flip with a margin: past 84 degrees),
  // screened at 60 degrees (the reduction's screen, 37 degrees, cost `best` 0.3 s more on
  // the bricks at 10 % and found no more flips in the sweeps; the trigger before, the
  // input's mean normal under the centroid, missed faces on walls with twice the relief:
  // docs/benchmarks.md). The checks above test the centroid only: a face that
  // now faces away and did not before the fit gets its corners back where the fit found
  // them. So does any face that this makes unacceptable (every state the iterations kept is
  // acceptable against the original positions: each check bounds a face by its state before
  // and the original), until none is left (each round puts back at least one vertex).
  auto away_from_input = [&](const std::vector<Vec3d>& at, size_t f, double min_cos) {
    const FaceCorners& fc = faces[f];
    const Vec3d n = normal_of(at, fc);
    return faces_away_screened(*in.tree, at[static_cast<size_t>(fc.v[0])], at[static_cast<size_t>(fc.v[1])], at[static_cast<size_t>(fc.v[2])], n,
                               in.mean_edge, min_cos, 0.5);
  };
  // Whether face f turned away in the fit (it did not face away before it).
  auto turned_away = [&](size_t f) { return away_from_input(pos, f, 0.1) && !away_from_input(original, f, 0.0); };
  // A face is tested when one of its corners moved (first all at once, in parallel) and
  // again only when one is put back (-1: to test; on the 262k-face bricks at 10 %, testing
  // every face every round, one face at a time, added 30 % to `best`).
  std::vector<int8_t> away(faces.size(), 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, faces.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t f = r.begin(); f < r.end(); ++f) {
      bool moved = false;
      for (const int v : faces[f].v) moved |= pos[static_cast<size_t>(v)] != original[static_cast<size_t>(v)];
      away[f] = moved && turned_away(f);
    }
  });
  for (bool changed = true; changed;) {
    changed = false;
    for (size_t f = 0; f < faces.size(); ++f) {
      if (away[f] < 0) away[f] = turned_away(f);
      if (acceptable(original, original, pos, faces[f], facing[f], options.max_aspect_ratio) && !away[f]) continue;
      for (const int v : faces[f].v) {
        const size_t vi = static_cast<size_t>(v);
        if (pos[vi] == original[vi]) continue;
        pos[vi] = original[vi];
        ++rep.held_back;
        changed = true;
        for (const int g : vertex_faces[vi]) away[static_cast<size_t>(g)] = -1;
      }
    }
  }
  // The faces left facing away from the input under them, counted as the reduction counts
  // its own (NoFlip::flipped_faces): those that faced away before the fit and those a
  // put-back corner could not turn around.
  std::vector<uint8_t> left_away(faces.size(), 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, faces.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t f = r.begin(); f < r.end(); ++f) {
      const FaceCorners& fc = faces[f];
      const Vec3d n = normal_of(pos, fc);
      left_away[f] = n.sqrnorm() > 0 && faces_away_screened(*in.tree, pos[static_cast<size_t>(fc.v[0])], pos[static_cast<size_t>(fc.v[1])],
                                                            pos[static_cast<size_t>(fc.v[2])], n, in.mean_edge, kFlippedCos, kFlippedScreenCos);
    }
  });
  rep.facing_away = static_cast<size_t>(std::count(left_away.begin(), left_away.end(), uint8_t{1}));
  for (size_t i = 0; i < nv; ++i)
    if (unknown[i] >= 0)  // exactly representable: rounded to float above
      mesh.set_point(VertexHandle(static_cast<int>(i)), Vec3f(static_cast<float>(pos[i][0]), static_cast<float>(pos[i][1]), static_cast<float>(pos[i][2])));
  compute_angle_weighted_normals(mesh);
  return rep;
}

}  // namespace meso::reduce
