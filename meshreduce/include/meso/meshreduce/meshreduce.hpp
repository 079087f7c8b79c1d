// meshreduce: quadric-error (Garland & Heckbert 1997) edge-collapse reduction of a
// high-poly mesh to a base mesh.
//
// meso's own collapse loop on OpenMesh's collapse primitives (is_collapse_ok, collapse):
// per-vertex area-weighted plane quadrics, cached, summed on collapse; optimal placement of
// the kept vertex; one lean indexed heap of edges; constraints as small composable modules
// (locks, chart guard, UV folds, normal flips, normal deviation, needles, error bound) that
// are asked only about the collapse about to be made. See meshreduce/src/collapse_loop.hpp.
// Progressive meshes (the collapse sequence, any level of detail): progressive.hpp.
#pragma once

#include "meso/core/mesh.hpp"
#include "meso/core/progress.hpp"
#include "meso/meshreduce/surface_distance.hpp"

#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace meso {

struct ProgressiveMesh;  // progressive.hpp

// Speed against error (--quality). Every preset keeps every guarantee of reduce_mesh below.
//  - balanced (the default): one indexed heap of edges; after each collapse every edge around
//    the kept vertex is re-evaluated (its placement and cost from the merged quadric).
//  - fast: the same collapses are allowed, but with lazy keys: queued edges around the kept
//    vertex keep their old key until popped, when they are re-evaluated and collapsed, or
//    queued again if the key rose. Fewer evaluations per collapse (6-9 % fewer instructions
//    on the bench meshes); the order is no longer exactly cheapest-first, which there gave
//    Hausdorff distances within 0.2 % of or below balanced's and RMS within 12 % of it
//    (docs/benchmarks.md).
//  - best: balanced twice, once with each face plane weighted by its area (the other
//    presets) and once by the mean face area (Garland and Heckbert's unweighted quadrics,
//    scaled so that seam and boundary planes keep their balance), then the output with the
//    lower two-sided Hausdorff distance to the input (measure_surface_distance; area wins
//    ties). Neither weighting is better at every budget on the bench meshes (docs/
//    benchmarks.md). Each candidate's vertices are also fitted to the input surface
//    (Hoppe et al. 1993's distance energy, two-sided, reweighted toward the largest
//    distances; meshreduce/src/surface_fit.hpp) except those on boundaries and locks (seam
//    vertices move too: each corner keeps its UV), and the output is the nearest of the four meshes (ties: unfitted, then area).
//    Costs: two reductions (parallel tasks), two fits and four measurements (each parallel
//    inside; TBB; the output does not depend on the thread count). No fit above 200,000
//    output faces, where its time and memory outgrow its gain. With `progressive`, the
//    record is the chosen run's (its levels equal that weighting's balanced reduction) and
//    the output is its last level: no fit; nor with max_normal_deviation below 180 degrees,
//    which the fit does not check.
enum class ReduceQuality { fast, balanced, best };

struct ReduceOptions {
  // Targets. Reduction stops at the first one met; at least one must be set.
  size_t target_faces = 0;  // stop at this many faces (or the closest reachable count)
  // Largest allowed geometric error, in object units (< 0: none). Every collapse is checked
  // against samples both ways (input vertices, edge midpoints and three points per face to
  // the new faces; the new vertex, edge midpoints and face centroids to the input triangles)
  // held to 0.7 of this bound, since the surfaces can drift further apart between samples;
  // reduction goes on until no collapse keeps it. Measured (surface_distance.hpp): the
  // two-sided Hausdorff distance stays at or under the bound on the test and bench meshes.
  double max_error = -1;

  // A vertex on a mesh boundary or UV seam may only slide along it, and only where the
  // boundary is straight: the old outline must stay within these tolerances of the new one,
  // in object units and in UV units.
  float boundary_tolerance = 1e-3f;  // mesh boundaries, as a fraction of the bounding-box diagonal
  float seam_tolerance = 1e-2f;      // UV seams inside the surface, the same
  float uv_tolerance = 1e-4f;        // in UV units
  // Weight of the planes through boundary and seam edges, perpendicular to their faces,
  // relative to the area-weighted surface planes (Garland & Heckbert's boundary planes).
  double boundary_weight = 100.0;
  double seam_weight = 1e4;
  // Why seams differ from boundaries: a seam has surface on both sides, so sliding along a
  // curved seam moves the surface as an interior collapse would, and its quadric sees that;
  // a boundary is the outline itself. With the boundaries' strict veto, every seam vertex
  // where a seam curves froze, and at small budgets the faces went to the seams (a torus
  // with seams along both wrap lines at 262 faces: Hausdorff 3.05 % of the diagonal, against
  // 1.36 % without UVs); a 1e-2 veto with heavier seam planes lets the quadric order decide:
  // 1.39 % there, and the same figures as before at 10 % and 1 % (docs/benchmarks.md). The
  // same values on boundaries turned faces at the brick wall's ends past perpendicular.
  // Largest angle, in degrees, between an output face's normal and the normal of any input
  // face it replaced (normal cones, as OpenMesh's ModNormalDeviation). 180 (the default)
  // turns it off: a base mesh for displacement has to average away relief whose normals
  // turn by up to 90 degrees. Normal flips are refused whatever this is.
  float max_normal_deviation = 180.0f;
  // Needles: a collapse may not create a face whose aspect ratio (longest edge squared
  // times sqrt(3) over four times its area: 1 for an equilateral triangle) exceeds this,
  // unless the faces it replaces were already worse. 0 turns it off.
  float max_aspect_ratio = 40.0f;

  // Locks: these vertices are never removed and never move (collapses of free neighbours
  // onto them are allowed), so faces whose corners are all locked come out unchanged. With
  // lock_boundary, every vertex on a mesh boundary (boundary edges then never collapse);
  // with lock_groups, every corner of a face whose group name (group_names(), the input's
  // mesh/node names) is in the list. Names that match no group lock nothing. When locks
  // leave too few legal collapses, reduction stops at the closest count (target_reached
  // false).
  bool lock_boundary = false;
  std::vector<std::string> lock_groups;

  ReduceQuality quality = ReduceQuality::balanced;
};

struct ReduceReport {
  size_t input_vertices = 0, input_faces = 0;
  size_t output_vertices = 0, output_faces = 0;
  size_t collapses = 0;
  bool target_reached = false;  // false when constraints stopped reduction before the target
  double seconds = 0;
  // Candidate collapses that each constraint refused (an edge may be counted again after
  // its neighbourhood changed), by module name.
  std::map<std::string, size_t> rejected;
  // Largest quadric error of a collapse made (sum of squared, area-weighted plane distances
  // in the normalised unit box; for diagnostics).
  double max_quadric_cost = 0;
  // With max_error: the largest distance from an input sample to the output face it is
  // tracked on, in object units (-1 when not tracked).
  double tracked_error = -1;  // (also -1 when best keeps a fitted mesh: the tracking was the reduction's)
  size_t locked_vertices = 0;  // vertices pinned by lock_boundary and lock_groups
  // Reductions run (see the guarantees below): 1, or more where one left flipped faces.
  int passes = 1;
  // Output faces that the bench's measure counts as flipped (with a 3-degree margin): 0
  // unless every pass of the reduction left some (for a fitted best output, counted after
  // the fit).
  size_t flipped_faces = 0;
  // With ReduceQuality::best: the face-plane weighting chosen ("area" or "uniform") and the
  // measured Hausdorff distance of each candidate (area, uniform), object units.
  std::string planes = "area";
  std::vector<double> candidate_hausdorff;
  // With ReduceQuality::best: the kept output's measured distance to the input, the same
  // as measure_surface_distance(input, output) would give (callers need not measure again).
  std::optional<SurfaceDistance> distance;
  // With ReduceQuality::best: whether the output is a fitted candidate, and the Hausdorff
  // distance of each candidate after the fit (area, uniform; object units; empty when the
  // fit did not run).
  bool fitted = false;
  std::vector<double> fitted_hausdorff;
};

// Returns the reduced mesh. Guarantees:
//  - every collapse passes OpenMesh's topological test (is_collapse_ok: manifold, no
//    duplicate faces);
//  - no face normal flips: no collapse turns a face by 90 degrees or more, nor makes it face
//    against the input faces it replaced (its normal against the sum of their area-weighted
//    normals), nor, where it stands over 60 degrees from that sum, more than 84 degrees
//    from the input triangles nearest to samples over it (the bench's flip count, with a
//    margin). Each output face is then tested against the input under it as the bench
//    counts a flip (with a margin of 3 degrees, and where the nearest input is a vertex or
//    edge that triangles share, whichever of them faces most against it); where any faces
//    away, the reduction runs again (up to 6 passes, ReduceReport::passes), testing every
//    new face around those of the passes before, and ReduceReport::flipped_faces counts the
//    faces the last pass leaves. best's fit checks its moves against the input nearest each
//    face's centroid, then puts back the corners of any face it moved that faces away from
//    the input under it (the same sampled test), see below. No output face deviates more
//    than max_normal_deviation from the input faces it replaced. (A regression test and
//    sweeps of the brick wall, with up to 4x its relief, find no face against the input
//    under it: docs/benchmarks.md.) No collapse creates a needle beyond max_aspect_ratio (and best's
//    surface fit turns no face by 90 degrees or more and makes none a needle beyond it
//    either);
//  - when the input has UVs: no UV triangle flips or becomes degenerate, the UVs of the
//    moved vertex are re-fitted (interior vertices: barycentric re-projection of the new
//    position onto the old neighbourhood; seam/boundary vertices: linear interpolation
//    along the seam), seams are kept in every chart (best's surface fit keeps every UV: the
//    UV layout is the reduction's);
//  - boundaries and UV seams are never torn; their vertices only slide along straight parts
//    and stay on the old seam/boundary polyline; corners of the seam network stay put
//    (best's surface fit then moves seam vertices, corners included, as it moves interior
//    ones, toward the input surface, but no further than seam_tolerance from where they
//    were: they end within seam_tolerance of the input's seam; boundary vertices it leaves
//    where they are);
//  - output faces are compacted (no deleted elements), groups kept per face, vertex normals
//    recomputed (angle-weighted);
//  - locked vertices (lock_boundary, lock_groups) keep their positions bit for bit and
//    survive; faces whose corners are all locked keep their corners and UVs;
//  - deterministic: the same input and options give the same output, bit for bit.
// The input is not modified.
//
// With `progressive`, also records the input and every collapse made (progressive.hpp):
// progressive_level(*progressive, k) then equals reduce_mesh with target_faces = k, for
// every k from the output's face count to the input's, when both took one pass (the record
// is the last pass's: a reduction that ran again tested the faces around its flips in all
// its collapses, those above k included). The reduction then runs on the input
// rebuilt face by face (progressive_base_input). That is the input itself, and the output
// the same as without `progressive` (except for best, which fits only without a record),
// for meshes built by add_face in face order (the test
// meshes; read_mesh unless a face failed to add, which can leave OpenMesh's boundary links
// around a non-manifold vertex in another order).
Mesh reduce_mesh(const Mesh& input, const ReduceOptions& options, ReduceReport* report = nullptr,
                 Progress& progress = null_progress(), ProgressiveMesh* progressive = nullptr);

}  // namespace meso
