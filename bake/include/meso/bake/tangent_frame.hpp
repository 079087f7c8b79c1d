// Tangent frames per corner, shared by `meso frames`, `meso bake` and `meso preview`, so a
// normal map is decoded with exactly the frame it was encoded with.
//
// Convention (MikkTSpace's): per corner a unit tangent t and a sign s; the shader
// interpolates the vertex normal n and t linearly across the triangle WITHOUT
// normalising, forms b = s * cross(n, t), and decodes a tangent-space normal m as
//   N = normalize(m.x * t + m.y * b + m.z * n).
// The baker encodes with the exact inverse of the same interpolated matrix [t b n].
// Tangent space is right-handed with +z along the surface normal (out of the surface),
// +x along increasing u and +y along increasing v (OpenGL / glTF "Y+" normal maps).
#pragma once

#include "meso/core/mesh.hpp"

#include <vector>

namespace meso {

struct TangentFrame {
  Vec3f tangent{1, 0, 0};  // unit, perpendicular to the vertex normal
  float sign = 1.0f;       // +1, or -1 where the UV mapping is mirrored
  // Object units per UV unit along u and along v (lengths of dp/du and dp/dv, survey eq. 5),
  // averaged like the tangent. Per-pixel displacement needs them to step in UV space.
  float du_length = 1.0f, dv_length = 1.0f;
};

// One frame per halfedge (indexed by halfedge idx; halfedges without a face get the
// default). Requires UVs and vertex normals. Tangents come from each triangle's UV
// gradients (survey eq. 5), projected onto the vertex normal's plane and averaged with
// corner-angle weights over the triangles around the vertex that share the corner's UV and
// mirroring (so frames split at UV seams and mirror lines). A triangle with degenerate UVs
// contributes nothing; a corner with no usable contribution gets a tangent built from the
// normal alone, never NaN. The result does not depend on face or halfedge order beyond
// floating-point summation order, which follows the vertex's halfedge circulation.
std::vector<TangentFrame> compute_tangent_frames(const Mesh& mesh);

// Writes the frames into the meso:tangent halfedge property (glTF TANGENT on export).
void store_tangents(Mesh& mesh, const std::vector<TangentFrame>& frames);

}  // namespace meso
