// Whether a mesh's coordinates are within what float arithmetic holds: the one check that
// every reader of meshes (mesh files, progressive meshes) applies.
#pragma once

#include "meso/core/mesh.hpp"

#include <string>

namespace meso {

// The bounding-box diagonal of a mesh's face vertices must lie in [kMinMeshSpan, kMaxMeshSpan]
// (0 is allowed: a mesh without extent): beyond it float distances, areas and curvatures
// overflow to Inf (3e38: every displacement texel) or vanish into denormals (1e-39: Inf
// curvatures).
constexpr double kMinMeshSpan = 1e-30, kMaxMeshSpan = 1e36;

// The median step per edge (MeshExtent::step_per_edge) beyond which readers refuse the mesh
// (its faces have folded and welded together: a 2-unit mesh 1e6 units from the origin, where
// floats step by 0.0625), and beyond which the commands warn. The warning's 1/256 is a
// choice, not a measured threshold; one point measured above it: the demo's meshes scaled by
// 1e3 and moved 1e6 (a step of 1.6 % of the high mesh's median edge) baked a displacement off
// by up to 1.7 % of its range, 0.13 % on average.
constexpr double kMaxFloatStepPerEdge = 0.25, kWarnFloatStepPerEdge = 1.0 / 256;

// Float precision where the mesh lies: the diagonal of its face vertices' box, its largest
// coordinate (absolute) and the step between 32-bit floats there (object units), and the
// median over its edges of the step at the edge's place (its larger coordinate) over the
// edge's length (0 for a mesh without extent).
struct MeshExtent {
  double span = 0, largest_coordinate = 0, float_step = 0, step_per_edge = 0;
};

// Measures `mesh` and throws InputError naming `name` when it has no face, its span is outside
// [kMinMeshSpan, kMaxMeshSpan], or its step per edge exceeds kMaxFloatStepPerEdge.
MeshExtent check_mesh_extent(const Mesh& mesh, const std::string& name);

}  // namespace meso
