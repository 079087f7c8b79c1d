// Flat arrays derived from a Mesh, in the one place where stages get them.
#pragma once

#include "meso/core/mesh.hpp"

#include <cstdint>
#include <vector>

namespace meso {

// Positions and triangles as plain arrays, faces in the mesh's face order and each
// triangle's corners in the order of face_halfedges(). `positions` holds 3 floats per
// vertex followed by one float of padding, since Embree reads vertices with 16-byte loads.
struct MeshArrays {
  std::vector<float> positions;
  std::vector<uint32_t> triangles;
  size_t vertex_count() const { return (positions.size() - 1) / 3; }
  size_t triangle_count() const { return triangles.size() / 3; }
};
MeshArrays flatten(const Mesh& mesh);

// Per-corner attributes (UVs, tangents) make one welded vertex into several GPU/file
// vertices. split_corners() gives each group of corners at a vertex whose attributes are
// equal one output vertex; output vertices are numbered in order of first use by
// faces in face order, so the result does not depend on halfedge numbering.
struct CornerSplit {
  std::vector<uint32_t> triangles;          // 3 output vertex indices per face, face order
  std::vector<HalfedgeHandle> corner;       // per output vertex: one halfedge pointing to it
  std::vector<uint32_t> vertex;             // per output vertex: the mesh vertex it came from
};
// Attributes compared: halfedge UVs when present, and the halfedge tangent property
// (meso:tangent, see tangent_frame.hpp in bake/) when present.
CornerSplit split_corners(const Mesh& mesh);

// The halfedge property in which `meso frames` stores per-corner tangents:
// (tx, ty, tz, sign) with the MikkTSpace meaning, bitangent = sign * cross(normal, tangent).
inline constexpr const char* kTangentProperty = "meso:tangent";
bool has_tangents(const Mesh& mesh);

// Vertex properties in which `meso frames` stores curvature: (k1, k2) as Vec2f and the unit
// direction of k1 as Vec3f (see curvature.hpp in bake/).
inline constexpr const char* kCurvatureProperty = "meso:curvature";
inline constexpr const char* kPrincipalDirectionProperty = "meso:principal_direction";
OpenMesh::HPropHandleT<OpenMesh::Vec4f> tangent_property(const Mesh& mesh);  // invalid if absent
OpenMesh::HPropHandleT<OpenMesh::Vec4f> add_tangent_property(Mesh& mesh);

}  // namespace meso
