// meshreduce: quadric-error (Garland & Heckbert 1997) edge-collapse reduction of a
// high-poly mesh to a base mesh, built on OpenMesh's Decimater with composed modules.
#pragma once

#include "meso/core/mesh.hpp"
#include "meso/core/progress.hpp"

#include <cstddef>

namespace meso {

struct ReduceOptions {
  size_t target_faces = 0;          // stop at this many faces (or the closest reachable count)
  // A vertex on a mesh boundary or UV seam may only slide along it, and only where the
  // boundary is straight: its distance to the chord of its two boundary neighbours, in
  // object units and in UV units, must stay below these tolerances.
  float boundary_tolerance = 1e-3f;  // as a fraction of the bounding-box diagonal
  float uv_tolerance = 1e-4f;        // in UV units
};

struct ReduceReport {
  size_t input_vertices = 0, input_faces = 0;
  size_t output_vertices = 0, output_faces = 0;
  size_t collapses = 0;
  bool target_reached = false;  // false when constraints stopped reduction before the target
  double seconds = 0;
};

// Returns the reduced mesh. Guarantees:
//  - every collapse keeps the surface orientation (no face normal flips) and, when the input
//    has UVs, keeps every UV triangle's orientation (no chart folds) and the UVs of the kept
//    vertex exact (the kept vertex keeps its position and its UVs: collapses go onto an
//    existing vertex, OpenMesh's ModQuadric placement);
//  - boundaries and UV seams are never torn; their vertices only slide along straight parts;
//  - output faces are compacted (no deleted elements), groups kept per face.
// The input is not modified.
Mesh reduce_mesh(const Mesh& input, const ReduceOptions& options, ReduceReport* report = nullptr,
                 Progress& progress = null_progress());

}  // namespace meso
