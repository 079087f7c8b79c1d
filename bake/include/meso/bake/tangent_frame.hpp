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
// default). Requires UVs and vertex normals. The frames are MikkTSpace's (genTangSpaceDefault,
// checked corner by corner against the reference in tests/mikktspace/):
//  - each triangle contributes the direction of its dp/du (survey eq. 5) projected onto the
//    plane of the vertex normal, weighted by its corner angle measured in that plane;
//  - contributions are averaged over the corner's group: the triangles around the vertex
//    reached from it through edges that are not UV seams (same UVs at both ends on both
//    sides) without crossing a change of UV orientation. So frames split at UV seams and at
//    mirror lines, and two charts that merely touch at one UV point keep separate frames;
//  - the sign is the UV orientation of the group's triangles: +1 where a triangle's UVs run
//    counter-clockwise in its winding order, -1 where mirrored. All three corners of a
//    triangle carry one sign, so a renderer may take it from any corner;
//  - a triangle with degenerate UVs (zero UV area, or zero dp/du or dp/dv) or two corners
//    at one position contributes nothing but joins the group around it, taking its frame;
//    between a preserving and a mirrored group it joins the preserving one (MikkTSpace lets
//    face order decide), and with no group around it, it counts as preserving. A corner whose
//    group has no usable contribution (e.g. a triangle with collapsed UVs cut off by seams)
//    gets a tangent built from the normal alone, never NaN (MikkTSpace leaves such a corner
//    undefined: it returns (1, 0, 0) with sign -1, whatever the normal).
// du_length / dv_length are the same angle-weighted averages of |dp/du|, |dp/dv| (MikkTSpace's
// fMagS / fMagT). Given the same vertex normals, the result does not depend on vertex, face
// or halfedge order at all, to the bit: each triangle's gradient starts from a canonical
// corner and each group's contributions are summed in a canonical order.
std::vector<TangentFrame> compute_tangent_frames(const Mesh& mesh);

// Writes the frames into the meso:tangent halfedge property (glTF TANGENT on export).
void store_tangents(Mesh& mesh, const std::vector<TangentFrame>& frames);

}  // namespace meso
