#include "meso/core/mesh.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace meso {
namespace {

struct GroupProps {
  OpenMesh::FPropHandleT<int> face_group;
  OpenMesh::MPropHandleT<std::vector<std::string>> names;
};

constexpr const char* kFaceGroup = "meso:face_group";
constexpr const char* kGroupNames = "meso:group_names";

const std::vector<std::string>& empty_names() {
  static const std::vector<std::string> names{""};
  return names;
}

}  // namespace

bool has_uvs(const Mesh& mesh) { return mesh.has_halfedge_texcoords2D(); }

void set_face_groups(Mesh& mesh, std::vector<std::string> names, const std::vector<int>& face_group) {
  GroupProps p;
  if (!mesh.get_property_handle(p.face_group, kFaceGroup)) mesh.add_property(p.face_group, kFaceGroup);
  if (!mesh.get_property_handle(p.names, kGroupNames)) mesh.add_property(p.names, kGroupNames);
  mesh.property(p.names) = std::move(names);
  for (auto f : mesh.faces()) {
    const size_t i = static_cast<size_t>(f.idx());
    mesh.property(p.face_group, f) = i < face_group.size() ? face_group[i] : 0;
  }
}

const std::vector<std::string>& group_names(const Mesh& mesh) {
  OpenMesh::MPropHandleT<std::vector<std::string>> h;
  if (!mesh.get_property_handle(h, kGroupNames)) return empty_names();
  return mesh.property(h);
}

int face_group(const Mesh& mesh, FaceHandle f) {
  OpenMesh::FPropHandleT<int> h;
  if (!mesh.get_property_handle(h, kFaceGroup)) return 0;
  return mesh.property(h, f);
}

Box3 bounding_box(const Mesh& mesh) {
  Box3 b;
  bool first = true;
  for (auto v : mesh.vertices()) {
    const Vec3f& p = mesh.point(v);
    if (first) {
      b.lo = b.hi = p;
      first = false;
    } else {
      b.lo.minimize(p);
      b.hi.maximize(p);
    }
  }
  return b;
}

std::array<HalfedgeHandle, 3> face_halfedges(const Mesh& mesh, FaceHandle f) {
  const HalfedgeHandle h0 = mesh.halfedge_handle(f);
  const HalfedgeHandle h1 = mesh.next_halfedge_handle(h0);
  const HalfedgeHandle h2 = mesh.next_halfedge_handle(h1);
  return {h0, h1, h2};
}

void compute_angle_weighted_normals(Mesh& mesh) {
  if (!mesh.has_vertex_normals()) mesh.request_vertex_normals();
  std::vector<OpenMesh::Vec3d> sum(mesh.n_vertices(), OpenMesh::Vec3d(0, 0, 0));
  for (auto f : mesh.faces()) {
    const auto hs = face_halfedges(mesh, f);
    OpenMesh::Vec3d p[3];
    int vi[3];
    for (int i = 0; i < 3; ++i) {
      vi[i] = mesh.to_vertex_handle(hs[i]).idx();
      p[i] = OpenMesh::vector_cast<OpenMesh::Vec3d>(mesh.point(mesh.to_vertex_handle(hs[i])));
    }
    OpenMesh::Vec3d n = OpenMesh::cross(p[1] - p[0], p[2] - p[0]);
    const double len = n.norm();
    if (!(len > 0)) continue;  // zero-area face: no direction to contribute
    n /= len;
    for (int i = 0; i < 3; ++i) {
      OpenMesh::Vec3d a = p[(i + 1) % 3] - p[i], b = p[(i + 2) % 3] - p[i];
      const double la = a.norm(), lb = b.norm();
      if (!(la > 0 && lb > 0)) continue;
      const double c = std::clamp(OpenMesh::dot(a, b) / (la * lb), -1.0, 1.0);
      sum[static_cast<size_t>(vi[i])] += n * std::acos(c);
    }
  }
  for (auto v : mesh.vertices()) {
    OpenMesh::Vec3d n = sum[static_cast<size_t>(v.idx())];
    const double len = n.norm();
    mesh.set_normal(v, len > 0 ? OpenMesh::vector_cast<Vec3f>(n / len) : Vec3f(0, 0, 1));
  }
}

bool is_uv_seam(const Mesh& mesh, Mesh::EdgeHandle e) {
  if (!has_uvs(mesh) || mesh.is_boundary(e)) return false;
  const HalfedgeHandle h0 = mesh.halfedge_handle(e, 0), h1 = mesh.halfedge_handle(e, 1);
  // h0 points to the vertex h1 leaves: in h1's face that corner is prev(h1). Likewise for h1.
  return !same_uv(mesh, h0, mesh.prev_halfedge_handle(h1)) || !same_uv(mesh, h1, mesh.prev_halfedge_handle(h0));
}

std::vector<uint8_t> uv_seam_vertices(const Mesh& mesh) {
  std::vector<uint8_t> seam(mesh.n_vertices(), 0);
  if (!has_uvs(mesh)) return seam;
  for (auto e : mesh.edges())
    if (is_uv_seam(mesh, e))
      for (unsigned k = 0; k < 2; ++k) seam[static_cast<size_t>(mesh.to_vertex_handle(mesh.halfedge_handle(e, k)).idx())] = 1;
  return seam;
}

double uv_double_area(const Mesh& mesh, FaceHandle f) {
  const auto hs = face_halfedges(mesh, f);
  const Vec2f a = mesh.texcoord2D(hs[0]), b = mesh.texcoord2D(hs[1]), c = mesh.texcoord2D(hs[2]);
  // Differences of floats are exact in double (for exponents less than 29 apart: any UVs
  // of one chart); then p q - r s with the rounding of r s put back (Kahan).
  const double p = static_cast<double>(b[0]) - a[0], q = static_cast<double>(c[1]) - a[1];
  const double r = static_cast<double>(b[1]) - a[1], s = static_cast<double>(c[0]) - a[0];
  const double rs = r * s;
  return std::fma(p, q, -rs) - std::fma(r, s, -rs);
}

double face_area(const Mesh& mesh, FaceHandle f) {
  const auto hs = face_halfedges(mesh, f);
  OpenMesh::Vec3d p[3];
  for (int i = 0; i < 3; ++i) p[i] = OpenMesh::vector_cast<OpenMesh::Vec3d>(mesh.point(mesh.to_vertex_handle(hs[i])));
  return 0.5 * OpenMesh::cross(p[1] - p[0], p[2] - p[0]).norm();
}

std::vector<int> uv_charts(const Mesh& mesh, size_t* count) {
  std::vector<int> parent(mesh.n_faces());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[static_cast<size_t>(x)] != x) {
      parent[static_cast<size_t>(x)] = parent[static_cast<size_t>(parent[static_cast<size_t>(x)])];
      x = parent[static_cast<size_t>(x)];
    }
    return x;
  };
  for (auto e : mesh.edges()) {
    if (mesh.is_boundary(e) || is_uv_seam(mesh, e)) continue;
    const int a = find(mesh.face_handle(mesh.halfedge_handle(e, 0)).idx());
    const int b = find(mesh.face_handle(mesh.halfedge_handle(e, 1)).idx());
    if (a != b) parent[static_cast<size_t>(std::max(a, b))] = std::min(a, b);
  }
  std::vector<int> chart(mesh.n_faces(), -1), label(mesh.n_faces(), -1);
  int next = 0;
  for (size_t f = 0; f < mesh.n_faces(); ++f) {
    const int r = find(static_cast<int>(f));
    if (label[static_cast<size_t>(r)] < 0) label[static_cast<size_t>(r)] = next++;
    chart[f] = label[static_cast<size_t>(r)];
  }
  if (count) *count = static_cast<size_t>(next);
  return chart;
}

double object_length_per_uv(const Mesh& mesh) {
  double area3 = 0, area_uv = 0;
  for (auto f : mesh.faces()) {
    area3 += face_area(mesh, f);
    area_uv += 0.5 * std::abs(static_cast<double>(uv_double_area(mesh, f)));
  }
  return area3 > 0 && area_uv > 0 ? std::sqrt(area3 / area_uv) : 0.0;
}

}  // namespace meso
