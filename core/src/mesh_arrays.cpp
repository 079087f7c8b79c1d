#include "meso/core/mesh_arrays.hpp"

#include <cstring>

namespace meso {

MeshArrays flatten(const Mesh& mesh) {
  MeshArrays a;
  a.positions.resize(mesh.n_vertices() * 3 + 1, 0.0f);
  std::memcpy(a.positions.data(), mesh.points(), mesh.n_vertices() * sizeof(Vec3f));
  a.triangles.reserve(mesh.n_faces() * 3);
  for (auto f : mesh.faces()) {
    for (auto h : face_halfedges(mesh, f)) a.triangles.push_back(static_cast<uint32_t>(mesh.to_vertex_handle(h).idx()));
  }
  return a;
}

bool has_tangents(const Mesh& mesh) { return tangent_property(mesh).is_valid(); }

OpenMesh::HPropHandleT<OpenMesh::Vec4f> tangent_property(const Mesh& mesh) {
  OpenMesh::HPropHandleT<OpenMesh::Vec4f> h;
  mesh.get_property_handle(h, kTangentProperty);
  return h;
}

OpenMesh::HPropHandleT<OpenMesh::Vec4f> add_tangent_property(Mesh& mesh) {
  auto h = tangent_property(mesh);
  if (!h.is_valid()) mesh.add_property(h, kTangentProperty);
  return h;
}

CornerSplit split_corners(const Mesh& mesh) {
  const bool uv = has_uvs(mesh);
  const auto tan = tangent_property(mesh);
  auto same = [&](HalfedgeHandle a, HalfedgeHandle b) {
    if (uv && !same_uv(mesh, a, b)) return false;
    if (tan.is_valid() && mesh.property(tan, a) != mesh.property(tan, b))
      return false;
    return true;
  };
  CornerSplit s;
  s.triangles.reserve(mesh.n_faces() * 3);
  // Output vertices already made for each mesh vertex (usually one or two).
  std::vector<std::vector<uint32_t>> made(mesh.n_vertices());
  for (auto f : mesh.faces()) {
    for (auto h : face_halfedges(mesh, f)) {
      const auto v = mesh.to_vertex_handle(h);
      auto& list = made[static_cast<size_t>(v.idx())];
      uint32_t out = UINT32_MAX;
      for (uint32_t o : list) {
        if (same(s.corner[o], h)) {
          out = o;
          break;
        }
      }
      if (out == UINT32_MAX) {
        out = static_cast<uint32_t>(s.corner.size());
        s.corner.push_back(h);
        s.vertex.push_back(static_cast<uint32_t>(v.idx()));
        list.push_back(out);
      }
      s.triangles.push_back(out);
    }
  }
  return s;
}

}  // namespace meso
