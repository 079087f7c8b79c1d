// Per-vertex principal curvatures of the base mesh from local quadric fits (survey section
// 5.1, eq. 13): in the vertex's frame (normal n, tangent plane axes), the neighbours'
// heights over the tangent plane are fitted by least squares with h = a u^2 + b u v + c v^2,
// extended by linear terms d u + e v so that an imprecise vertex normal does not bias it, and
// by the implicit terms k h^2 (+ (m u + n v) h) where they fit the heights far better: the
// fit is then the quadric surface through the vertex, exact on spheres, circular cylinders
// and cones however coarse the mesh.
#pragma once

#include "meso/core/mesh.hpp"

#include <vector>

namespace meso {

struct VertexCurvature {
  // Principal curvatures, k1 >= k2, in 1/object units. Positive where the surface bends away
  // from its normal (convex with outward normals): a sphere of radius r has k1 = k2 = 1/r.
  float k1 = 0, k2 = 0;
  // Unit principal directions in object space, in the vertex normal's tangent plane, d1 x d2 = n.
  // Without a fit (rings = 0): still a frame of that plane, chosen arbitrarily; (1, 0, 0) and
  // (0, 1, 0) only where the vertex has no normal.
  Vec3f d1{1, 0, 0}, d2{0, 1, 0};
  int rings = 0;                   // 1, 2 or 3: the neighbourhood that determined the fit; 0 = none
};

// One per vertex, fitted in parallel (each from its own rings: the same whatever the threads).
// Uses the 1-ring when it has at least 8 neighbours and determines the fit
// well (singular values within a factor 100 in coordinates whitened to the neighbourhood's
// second moments, so long thin cells are no obstacle up to an aspect of 1000; a neighbourhood
// more than twice as long as wide also fits cubic and quartic terms along its long axis,
// which keep that axis's higher-order terms out of the curvature across it), else the
// 2-ring, else the 3-ring (the end of a thin strip, whose 2-ring lies in two rows); a vertex
// whose 3-ring cannot determine it gets zero curvature and rings = 0, as does one whose
// curvature overflows float. The implicit terms are kept where their residual per degree of
// freedom is a tenth of the quadric's or less, with three points to spare and every point on
// the vertex's sheet of the fitted quadric, k h^2 alone tried first (spheres, cylinders and
// cones of 6 to 32 segments to float rounding, within 4e-6 of their curvature; a 24 x 12
// torus, creases, steps and spikes keep the quadric's fit); a ring too small to tell whether
// they are needed (a pole's 1-ring, on one circle) lets the next ring decide, whose fit
// replaces it only with an implicit one. Needs vertex normals. Curvatures
// are those of the fitted surface at the vertex (shape operator I^-1 II); directions are
// its principal directions projected onto the vertex normal's tangent plane.
std::vector<VertexCurvature> fit_curvature(const Mesh& mesh);

// Stores k1, k2 (vertex property meso:curvature, Vec2f) and d1 (meso:principal_direction,
// Vec3f) on the mesh, for export (glTF _CURVATURE, _PRINCIPAL_DIRECTION).
void store_curvature(Mesh& mesh, const std::vector<VertexCurvature>& curvature);

}  // namespace meso
