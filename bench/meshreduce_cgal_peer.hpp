// The parts of bench/meshreduce_peers that need CGAL, behind plain arrays: CGAL compiles
// slowly and brings -frounding-math, so it stays in one translation unit of its own
// (bench/meshreduce_cgal_peer.cpp) that the bench's main file never includes.
#pragma once

#include "meso/meshreduce/surface_distance.hpp"

#include <cstddef>

namespace meso::bench {

// CGAL's Surface_mesh_simplification::edge_collapse with the Garland–Heckbert plane
// policies (CGAL 5.5) and the Bounded_normal_change_filter, on a Surface_mesh<Epick::Point_3>
// built from `in`, until at most `target_faces` faces remain. `seconds` covers the
// edge_collapse call alone (best of `repeat`), like the other peers' library calls.
struct CgalResult {
  TriangleSoup out;
  double seconds = 0;
  size_t collapses = 0;
};
CgalResult run_cgal_garland_heckbert(const TriangleSoup& in, size_t target_faces, int repeat);

// Output faces whose normal points away from the input's: the normal of each non-degenerate
// output triangle against the input's normal around it, the sum of the area-weighted
// normals of the input triangles closest to points spread evenly over it, about one per
// input triangle it covers and at least 16 (CGAL AABB tree); negative dot product = flipped. (The input
// triangle closest to the centroid alone, the count before 2026-12-02, flags faces that span
// a sharp edge, e.g. one facing 0.9 up on the brick wall whose centroid is nearest to a
// brick's side, cos -0.02 to -0.14.) Degenerate output triangles are counted apart.
struct FlipCount {
  size_t flipped = 0, degenerate = 0;
};
FlipCount count_flipped(const TriangleSoup& input, const TriangleSoup& output);

}  // namespace meso::bench
