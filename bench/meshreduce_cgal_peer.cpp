// CGAL's edge-collapse simplification as a meshreduce peer, and the flipped-face count
// (see meshreduce_cgal_peer.hpp). All of the bench's CGAL is here.
#include "meshreduce_cgal_peer.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Bounded_normal_change_filter.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/GarlandHeckbert_plane_policies.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>

#include <algorithm>
#include <cmath>
#include <chrono>
#include <cstdio>

namespace meso::bench {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;
namespace SMS = CGAL::Surface_mesh_simplification;

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

// CGAL 5.5 has no Face_count_stop_predicate; its Count_stop_predicate counts
// edges, which for the open brick wall is not 1.5 x faces. Surface_mesh's number_of_faces()
// leaves out removed faces, so asking the mesh stops at the same face count as the others.
class FaceCountStop {
 public:
  FaceCountStop(const SurfaceMesh& mesh, size_t target) : mesh_(&mesh), target_(target) {}
  template <typename F, typename Profile>
  bool operator()(const F&, const Profile&, std::size_t, std::size_t) const {
    return mesh_->number_of_faces() <= target_;
  }

 private:
  const SurfaceMesh* mesh_;
  size_t target_;
};

SurfaceMesh to_surface_mesh(const TriangleSoup& in) {
  SurfaceMesh mesh;
  std::vector<SurfaceMesh::Vertex_index> vertex;
  vertex.reserve(in.points.size());
  for (const auto& p : in.points) vertex.push_back(mesh.add_vertex(Point(p[0], p[1], p[2])));
  size_t rejected = 0;
  for (const auto& t : in.triangles)
    if (mesh.add_face(vertex[t[0]], vertex[t[1]], vertex[t[2]]) == SurfaceMesh::null_face()) ++rejected;
  // meso's meshes are manifold, so this does not happen for the bench's inputs; say so if a
  // --mesh file makes it happen, since CGAL then reduces a different surface.
  if (rejected > 0) std::fprintf(stderr, "meshreduce_peers: CGAL rejected %zu non-manifold input faces\n", rejected);
  return mesh;
}

TriangleSoup to_soup(SurfaceMesh& mesh) {
  mesh.collect_garbage();
  TriangleSoup soup;
  soup.points.reserve(mesh.number_of_vertices());
  for (auto v : mesh.vertices()) {
    const Point& p = mesh.point(v);
    soup.points.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
  }
  for (auto f : mesh.faces()) {
    std::array<uint32_t, 3> t{};
    int k = 0;
    for (auto v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) t[k++ % 3] = static_cast<uint32_t>(v.idx());
    soup.triangles.push_back(t);
  }
  return soup;
}

K::Vector_3 normal(const TriangleSoup& s, const std::array<uint32_t, 3>& t) {
  auto point = [&](uint32_t i) { return Point(s.points[i][0], s.points[i][1], s.points[i][2]); };
  return CGAL::cross_product(point(t[1]) - point(t[0]), point(t[2]) - point(t[0]));
}

}  // namespace

CgalResult run_cgal_garland_heckbert(const TriangleSoup& in, size_t target_faces, int repeat) {
  CgalResult r;
  r.seconds = 1e30;
  SurfaceMesh mesh;
  for (int i = 0; i < repeat; ++i) {
    mesh = to_surface_mesh(in);
    const double t0 = now();
    // The policies compute every vertex's quadric when constructed: part of the peer's work.
    SMS::GarlandHeckbert_plane_policies<SurfaceMesh, K> policies(mesh);
    FaceCountStop stop(mesh, target_faces);
    // Not applied by default in 5.5, whose own check only rejects collapses that fold two
    // adjacent triangles onto each other; this one also rejects any face whose normal turns
    // by more than 90°.
    SMS::Bounded_normal_change_filter<> filter;
    r.collapses = static_cast<size_t>(SMS::edge_collapse(
        mesh, stop,
        CGAL::parameters::get_cost(policies.get_cost()).get_placement(policies.get_placement()).filter(filter)));
    r.seconds = std::min(r.seconds, now() - t0);
  }
  r.out = to_soup(mesh);
  return r;
}

FlipCount count_flipped(const TriangleSoup& input, const TriangleSoup& output) {
  std::vector<K::Triangle_3> triangles;
  triangles.reserve(input.triangles.size());
  auto point = [&](const TriangleSoup& s, uint32_t i) { return Point(s.points[i][0], s.points[i][1], s.points[i][2]); };
  for (const auto& t : input.triangles) {
    K::Triangle_3 tri(point(input, t[0]), point(input, t[1]), point(input, t[2]));
    if (!tri.is_degenerate()) triangles.push_back(tri);
  }
  using Primitive = CGAL::AABB_triangle_primitive<K, std::vector<K::Triangle_3>::const_iterator>;
  CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>> tree(triangles.cbegin(), triangles.cend());
  tree.accelerate_distance_queries();
  double edges = 0;
  for (const auto& t : triangles)
    for (int e = 0; e < 3; ++e) edges += std::sqrt(CGAL::squared_distance(t[e], t[(e + 1) % 3]));
  const double mean_edge = triangles.empty() ? 1.0 : edges / (3.0 * static_cast<double>(triangles.size()));
  FlipCount c;
  for (const auto& t : output.triangles) {
    const K::Vector_3 n = normal(output, t);
    if (n.squared_length() == 0) {
      ++c.degenerate;
      continue;
    }
    // The centroids of the face's k x k subdivision, k its longest edge over the input's mean
    // edge length (at least 4, at most 64): about one sample per input triangle it covers.
    // Barycentric ((i + 1/3) / k, (j + 1/3) / k) for i + j <= k - 1 (upright sub-triangles)
    // and ((i + 2/3) / k, (j + 2/3) / k) for i + j <= k - 2.
    const Point a = point(output, t[0]), b = point(output, t[1]), cc = point(output, t[2]);
    const double longest = std::sqrt(std::max({CGAL::squared_distance(a, b), CGAL::squared_distance(b, cc), CGAL::squared_distance(cc, a)}));
    const int k = static_cast<int>(std::clamp(std::ceil(longest / mean_edge), 4.0, 64.0));
    K::Vector_3 m(0, 0, 0);
    for (int up = 1; up <= 2; ++up)
      for (int i = 0; i + up <= k; ++i)
        for (int j = 0; i + j + up <= k; ++j) {
          const double u = (i + up / 3.0) / k, v = (j + up / 3.0) / k;
          const Point p = a + u * (b - a) + v * (cc - a);
          const K::Triangle_3& tri = *tree.closest_point_and_primitive(p).second;
          m = m + CGAL::cross_product(tri[1] - tri[0], tri[2] - tri[0]);
        }
    if (n * m < 0) ++c.flipped;
  }
  return c;
}

}  // namespace meso::bench
