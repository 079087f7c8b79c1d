// The one mesh type of the meso pipeline.
//
// meso::Mesh is an OpenMesh TriMesh with these traits, chosen once:
//  - positions and normals are float (OpenMesh::Vec3f), in object units, right-handed;
//    the stored arrays are contiguous, so flat views (mesh_arrays.hpp) need no conversion;
//  - texture coordinates live on halfedges (OpenMesh "halfedge texcoords": the UV of the
//    corner at the halfedge's to-vertex inside the halfedge's face), so a UV seam is two
//    different UVs at one welded vertex and is represented exactly;
//    UVs follow the OpenGL convention: (0,0) is the bottom-left of the image, v grows up;
//  - vertex normals are present when requested (request_vertex_normals());
//  - every element has status bits, as the Decimater needs;
//  - each face carries a group index into the mesh's list of group names (the input's
//    mesh/node names), for match-by-name baking and for locking named parts.
// Faces keep the input file's order, so reports name faces by their 0-based index.
#pragma once

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace meso {

struct MeshTraits : public OpenMesh::DefaultTraits {
  using Point = OpenMesh::Vec3f;
  using Normal = OpenMesh::Vec3f;
  using TexCoord2D = OpenMesh::Vec2f;
  VertexAttributes(OpenMesh::Attributes::Status);
  HalfedgeAttributes(OpenMesh::Attributes::PrevHalfedge | OpenMesh::Attributes::Status);
  EdgeAttributes(OpenMesh::Attributes::Status);
  FaceAttributes(OpenMesh::Attributes::Status);
};

using Mesh = OpenMesh::TriMesh_ArrayKernelT<MeshTraits>;
using Vec3f = OpenMesh::Vec3f;
using Vec2f = OpenMesh::Vec2f;
using VertexHandle = Mesh::VertexHandle;
using FaceHandle = Mesh::FaceHandle;
using HalfedgeHandle = Mesh::HalfedgeHandle;

// Axis-aligned bounding box in object units.
struct Box3 {
  Vec3f lo{0, 0, 0};
  Vec3f hi{0, 0, 0};
  // In double, and returned as double: a float sum of squares underflows to 0 for a box near
  // 1e-30 across and overflows near 1e19, and a box near FLT_MAX across has a diagonal no
  // float holds.
  double diagonal() const {
    const double x = double(hi[0]) - lo[0], y = double(hi[1]) - lo[1], z = double(hi[2]) - lo[2];
    return std::sqrt(x * x + y * y + z * z);
  }
  Vec3f center() const { return (lo + hi) * 0.5f; }
};

// True when the mesh carries texture coordinates (on its halfedges).
bool has_uvs(const Mesh& mesh);

// Face groups: each face has an index into group_names(mesh). A mesh read from a file
// has one group per input mesh/node; a mesh built in code starts with one group "".
void set_face_groups(Mesh& mesh, std::vector<std::string> names, const std::vector<int>& face_group);
const std::vector<std::string>& group_names(const Mesh& mesh);
int face_group(const Mesh& mesh, FaceHandle f);

Box3 bounding_box(const Mesh& mesh);

// The three halfedges of a face, in the face's winding order, the first one being the
// halfedge that OpenMesh stores for the face. Corner i is the to-vertex of halfedge i.
std::array<HalfedgeHandle, 3> face_halfedges(const Mesh& mesh, FaceHandle f);

// Smooth vertex normals: the sum of incident face normals weighted by the corner angle
// (Thürmer & Wüthrich), which does not depend on how a surface is triangulated.
// Requests vertex normals if needed. Vertices without a valid face get (0,0,1).
void compute_angle_weighted_normals(Mesh& mesh);

// Whether two corners carry the same UV (value equality: +0 and -0 are the same).
inline bool same_uv(const Mesh& mesh, HalfedgeHandle a, HalfedgeHandle b) {
  return mesh.texcoord2D(a) == mesh.texcoord2D(b);
}

// A UV seam: an interior edge whose two faces give different UVs at either end. Boundary
// edges are not seams (they have one side).
bool is_uv_seam(const Mesh& mesh, Mesh::EdgeHandle e);

// Per vertex, 1 where the vertex ends a UV seam edge (is_uv_seam), else 0; all 0 without UVs.
std::vector<uint8_t> uv_seam_vertices(const Mesh& mesh);

// Charts: faces connected through edges whose two sides carry the same UVs. Returns a chart
// index per face, numbered by first face in face order; `count` receives the number.
std::vector<int> uv_charts(const Mesh& mesh, size_t* count = nullptr);

// A unit vector perpendicular to the unit vector n, continuous except across n.z = 0's sign
// flip (Duff et al. 2017, "Building an Orthonormal Basis, Revisited").
inline OpenMesh::Vec3d any_perpendicular(const OpenMesh::Vec3d& n) {
  const double s = n[2] >= 0 ? 1.0 : -1.0;
  const double a = -1.0 / (s + n[2]);
  const double b = n[0] * n[1] * a;
  return OpenMesh::Vec3d(1.0 + s * n[0] * n[0] * a, s * b, -s * n[0]);
}

// The UV-space signed double area of a face (positive for counter-clockwise UVs), computed
// in double with Kahan's 2x2 determinant (an FMA recovers the first product's rounding): its
// sign is right and it is 0 only for collinear UVs, where float arithmetic rounded slivers
// that do cover texels to 0 (and the UV checker and the baker then skipped them).
double uv_double_area(const Mesh& mesh, FaceHandle f);

// The surface area of a face in object units squared, computed in double: a float cross
// product overflows for edges past ~1e19 and its squared norm for edges past ~1e9, and
// underflows to 0 below ~1e-19 (a mesh 1e12 units across had area inf, one 1e-12 across 0).
double face_area(const Mesh& mesh, FaceHandle f);

// Object length per unit of UV: sqrt(surface area / UV area) over all faces (a mapping's
// mean scale); 0 when either area is 0.
double object_length_per_uv(const Mesh& mesh);

}  // namespace meso
