// Mesh files. Import through assimp (OBJ, FBX, glTF/GLB, PLY, OFF, DAE, STL, ...);
// export OBJ and PLY through OpenMesh's writers and glTF 2.0 (.gltf with an embedded
// buffer, or .glb) through meso's own writer.
#pragma once

#include "meso/core/mesh.hpp"
#include "meso/core/mesh_extent.hpp"

#include <cstddef>
#include <filesystem>
#include <string>

namespace meso {

// What import did to the file's data, for reports and warnings.
struct MeshReadReport {
  size_t file_vertices = 0;        // vertices as assimp delivered them, before welding
  size_t welded_vertices = 0;      // after welding equal positions
  size_t faces = 0;                // triangles, in file order (polygons are triangulated)
  size_t isolated_faces = 0;       // faces that would have been non-manifold or that repeat
                                   // a vertex: kept, in order, on vertices of their own
  size_t faces_without_uv = 0;     // faces of file meshes that had no UVs (given UV 0,0)
  bool had_normals = false;        // the file gave normals for every vertex
  // Float precision where the mesh lies: its largest coordinate (absolute) and the step
  // between 32-bit floats there (object units), and the median over its edges of the step at
  // the edge's place (its larger coordinate) over the edge's length (0 for a mesh without
  // extent). Over kWarnFloatStepPerEdge, rounding has taken detail that the maps would carry.
  double largest_coordinate = 0, float_step = 0, step_per_edge = 0;
};


// Reads a mesh file into the pipeline's Mesh:
//  - coordinates are the file's own (a COLLADA up_axis is not applied);
//  - the node hierarchy is flattened with each node's transform; each input mesh/node
//    becomes a face group named after the mesh (or else the node);
//  - faces keep the file's order (each polygon triangulated in place);
//  - vertices with bitwise-equal positions are welded; UV channel 0 is kept per corner on
//    halfedges, so seams survive welding; normals are averaged at welded vertices, or
//    computed (angle-weighted) when the file has none;
//  - non-manifold faces and faces with a repeated vertex are kept on separate vertices.
//  - an OBJ's `v` and `vt` numbers are the floats nearest their text (assimp's parser is one
//    float step off on some; those are put right), so an OBJ write_obj wrote reads back bit
//    for bit.
// Throws InputError naming the file when it is missing, unreadable, has no triangles, has a
// NaN/infinite coordinate, the bounding-box diagonal of its faces' vertices lies outside
// [kMinMeshSpan, kMaxMeshSpan] (0 is allowed: a mesh without extent), beyond which float
// distances, areas and curvatures overflow or vanish, or the mesh lies so far from the origin
// for its size that float rounding has taken its shape (kMaxFloatStepPerEdge; both in
// meso/core/mesh_extent.hpp, which the progressive-mesh reader applies too).
Mesh read_mesh(const std::filesystem::path& path, MeshReadReport* report = nullptr);

// Writes by extension: .obj (per-corner UVs as `vt`, normals), .ply (binary; vertices split
// at UV seams since PLY has per-vertex UVs only), .gltf / .glb (POSITION, NORMAL, TEXCOORD_0,
// TANGENT when the mesh has meso:tangent, and _CURVATURE (k1, k2) with _PRINCIPAL_DIRECTION
// (k1's direction) when it has meso:curvature). Positions are written with full float
// precision so a round trip is exact. Throws UsageError for an unknown extension and
// InternalError when the file cannot be written. Not atomic by itself: pass a path from
// OutputSet::add().
void write_mesh(const Mesh& mesh, const std::filesystem::path& path);

// True for the extensions write_mesh() accepts.
bool is_writable_mesh_extension(const std::filesystem::path& path);

}  // namespace meso
