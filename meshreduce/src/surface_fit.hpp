// Fitting a reduced mesh's vertex positions to the surface it replaces (internal to
// meshreduce; `--quality best` uses it).
//
// Hoppe, DeRose, Duchamp, McDonald and Stuetzle, "Mesh Optimization" (SIGGRAPH 1993),
// section 4.2 (their E_dist with the connectivity fixed): with each sample x_i of the input
// surface attached to its closest point on the output, sum_k b_ik v_k (face f_i, barycentric
// weights b_ik), the positions V that minimise
//     E(V) = sum_i w_i |x_i - sum_k b_ik v_k|^2 + lambda sum_j |v_j - v_j'|^2
// solve a sparse linear least-squares problem, three right-hand sides (x, y, z), one normal
// matrix; then the samples are attached anew and the solve repeats (their alternation,
// which never increases E for fixed weights; here the weights change between solves and
// refused moves are undone, so the best iterate is kept instead of the last). The second term is a weak pull toward the current positions
// v_j' (in place of their spring energy), so that a vertex whose faces attract no sample
// stays where it is and the system is positive definite. Quadric placement puts a collapsed
// vertex where the removed faces' planes meet, off the surface on curved parts (outside on
// convex ones); the fit lets the coarse surface straddle the fine one instead, which lowers
// the RMS distance and, usually, the Hausdorff distance (the caller measures and decides).
#pragma once

#include "geometry.hpp"

#include "meso/core/mesh.hpp"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace meso::reduce {

// The surface to fit to: points on it with weights (object units^2): its vertices (a third
// of their faces' area each) and its face centroids (a third of the face's area each; the
// weights sum to 4/3 of the area), about one and a half per face on a regular mesh, enough
// for an output with far fewer faces; and its triangles, for the distance the other way.
class SurfaceFitTarget {
 public:
  explicit SurfaceFitTarget(const Mesh& input);
  ~SurfaceFitTarget();
  SurfaceFitTarget(const SurfaceFitTarget&) = delete;
  SurfaceFitTarget& operator=(const SurfaceFitTarget&) = delete;

  struct Impl;
  const Impl& impl() const { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

struct SurfaceFitOptions {
  // Solves. 10 rather than 6: more steps of the reweighting at high powers; on the bench
  // the seamed torus at 0.1 % went 0.906 -> 0.861 % of the diagonal, the bricks at 1 % and
  // 0.1 % 0.300 -> 0.293 and 1.166 -> 1.143 (at 10 %: torus 0.0099 -> 0.0102, bricks
  // 0.0402 -> 0.0405), for 0.16-0.7 s more per candidate on 262k input faces, the most at 26k output
  // faces (measured under load 3; docs/benchmarks.md).
  int iterations = 10;
  // Residuals weighted by (distance / RMS distance)^(power - 2), raised from 2 (least
  // squares) to `power` over the iterations: iteratively reweighted least squares toward
  // the L_power norm, which leans toward the largest distances (the Hausdorff distance is
  // the L_infinity one).
  double power = 5.0;
  // Input samples used: about this many (every k-th, weighted by k; all when fewer, or
  // when 0), each costing a closest-point query per iteration.
  size_t max_samples = 50000;
  // As ReduceOptions::max_aspect_ratio: a move may not make a face a needle beyond this
  // (unless it already was one). 0: off.
  float max_aspect_ratio = 40.0f;
  // Vertices flagged here (one flag per vertex; empty: none) end at most `tether` (object
  // units) from where they were before the fit: best tethers UV-seam vertices, which the
  // reduction leaves on the input's seam, to within seam_tolerance of it.
  std::vector<uint8_t> tethered;
  double tether = 0;
};

struct SurfaceFitReport {
  int iterations = 0;     // solves made
  size_t free_vertices = 0;
  size_t held_back = 0;   // vertex moves undone (summed over iterations): see fit_to_surface
  // Faces left facing away from the input under them (the reduction's test of a flip,
  // NoFlip::flipped_faces): those that did before the fit, none it turned.
  size_t facing_away = 0;
};

// Moves the vertices of `mesh` (compacted: no deleted elements) whose `fixed` flag is 0
// (one flag per vertex; std::invalid_argument otherwise) toward the least-squares fit above.
// UVs are kept as they are: a moved vertex keeps the UV of each of its corners (on a seam,
// one per side; the faces of both sides move with it, so no chart tears; the moves are of
// the order of the distance to the input). Guarantees: fixed vertices keep their positions bit for bit;
// connectivity and UVs are unchanged; no face's normal turns by 90 degrees or more against
// its normal before the fit, no face becomes degenerate, and no face's aspect ratio rises
// beyond max_aspect_ratio (moves that would are undone, vertex by vertex); vertex normals
// are recomputed (angle-weighted); tethered vertices end within `tether` of where they were.
// Deterministic whatever the thread count.
SurfaceFitReport fit_to_surface(Mesh& mesh, const SurfaceFitTarget& target, const std::vector<uint8_t>& fixed,
                                const SurfaceFitOptions& options = {});

}  // namespace meso::reduce
