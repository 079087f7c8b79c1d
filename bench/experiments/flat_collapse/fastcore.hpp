// EXPERIMENT (not for landing): meso's `fast` collapse loop on flat arrays instead of
// OpenMesh halfedges. Garland & Heckbert 1997 quadrics (meso's quadric.hpp math), meso's
// constraint set re-implemented on a vertex->triangle CSR.
//
// Collapse policy: passes. Each pass rebuilds the vertex->triangle CSR from the live
// triangle list, enumerates every edge once (classing it interior / boundary / UV seam,
// counting feature edges per vertex), evaluates its cost at its placement (meso's rules:
// optimal inside a chart, onto a seam/boundary vertex, slide along a seam/boundary), sorts
// the keys, then collapses greedily in cost order, re-checking topology and geometry on the
// current arrays; a collapse marks its two ends and every vertex of their faces "dirty" for
// the rest of the pass (their CSR lists and features are stale), and edges touching a dirty
// vertex wait for the next pass. A pass stops after removing `pass_goal` of the faces still
// in excess of the target, or after scanning `pass_scan` of its sorted candidates.
#pragma once

#include <OpenMesh/Core/Geometry/VectorT.hh>

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace fastcore {

using Vec3f = OpenMesh::Vec3f;
using Vec2f = OpenMesh::Vec2f;

struct Options {
  size_t target_faces = 0;
  double boundary_weight = 100.0;  // meso ReduceOptions defaults
  double seam_weight = 1e4;
  double boundary_tolerance = 1e-3;  // fraction of the bbox diagonal
  double seam_tolerance = 1e-2;
  double uv_tolerance = 1e-4;
  double max_aspect_ratio = 40.0;
  bool optimal_placement = true;  // false: endpoint placement (cheapest endpoint)
  double pass_goal = 0.5;         // fraction of the excess faces a pass may remove
  double pass_scan = 1.0;         // fraction of the sorted candidates a pass may look at
  bool radix = true;              // radix sort of keys (else std::sort)
  bool lean = true;               // plain-double placement, UV re-projection on fl/fr first, root-free needle test
  bool refine = true;             // meso's refinement step of the regularised minimiser
  bool rank_cheap = false;        // rank edges by min(Q(p0), Q(p1), Q(mid)); optimal placement only when collapsing
  bool fast_key = false;          // endpoint placement: rank with Q0(p)+Q1(p) (no candidate, no quadric sum)
  bool steep_test = false;        // meso NoFlip's steep-face test against the input (Embree BVH of the input)
  bool post_check = false;        // meso's final flip check of every output face (counted in Stats::post_flipped, no re-run)
  bool input_normal_test = true;  // meso NoFlip's test against the summed input normals of each face
  bool post_check_steep_only = false;  // post_check only the faces over 60 degrees from their input-normal sum
  bool lazy_bvh = false;          // build the input BVH only when a steep face or a post-check needs it
  bool cache = true;              // keep keys of edges whose ends did not change in the last pass
  bool ring_lock = false;         // lock the one-ring of a collapse for the rest of the pass (else its two ends)
};

struct Stats {
  size_t passes = 0, collapses = 0, evaluated = 0, attempted = 0;
  size_t skipped_dirty = 0, rej_link = 0, rej_chart = 0, rej_flip = 0, rej_needle = 0, rej_uv = 0, rej_steep = 0, post_flipped = 0;
};

struct Output {
  std::vector<Vec3f> points;  // all input vertices (unmoved ones bit for bit), moved ones rewritten
  std::vector<std::array<uint32_t, 3>> triangles;
  std::vector<std::array<Vec2f, 3>> uvs;  // per corner (empty without UVs)
};

// uvs: per corner, 3 per triangle, or null.
Output reduce(const Vec3f* points, size_t n_points, const std::array<uint32_t, 3>* triangles, size_t n_triangles,
              const std::array<Vec2f, 3>* uvs, const Options& options, Stats* stats = nullptr);

}  // namespace fastcore
