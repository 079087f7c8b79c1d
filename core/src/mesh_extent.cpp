#include "meso/core/mesh_extent.hpp"

#include "meso/core/error.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

namespace meso {

namespace {
std::string format_number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", v);
  return text;
}
}  // namespace

MeshExtent check_mesh_extent(const Mesh& mesh, const std::string& name) {
  if (mesh.n_faces() == 0) throw InputError(name, "contains no triangles");
  MeshExtent out;
  OpenMesh::Vec3d lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
  for (auto v : mesh.vertices()) {
    if (mesh.is_isolated(v)) continue;  // no face uses it (PLY keeps such vertices, OBJ through assimp does not)
    const OpenMesh::Vec3d p = OpenMesh::vector_cast<OpenMesh::Vec3d>(mesh.point(v));
    lo.minimize(p);
    hi.maximize(p);
  }
  out.span = (hi - lo).norm();
  if (out.span > kMaxMeshSpan || (out.span > 0 && out.span < kMinMeshSpan))
    throw InputError(name, "its vertices span " + format_number(out.span) + " units, outside the " + format_number(kMinMeshSpan) + " to " +
                               format_number(kMaxMeshSpan) + " that float arithmetic holds (rescale the mesh)");
  // Far from the origin for its size, a mesh has lost its detail to float rounding by now
  // (see kMaxFloatStepPerEdge): refused, naming the cause, instead of reduced, packed and
  // baked into garbage (the demo's meshes moved 1e6 units: the base read with 1,590
  // non-manifold or degenerate faces and 1,683 UV charts instead of 1, the bake missed 22,755
  // texels, every stage exited 0). Measured per edge, at the edge's own place (the step at its
  // larger coordinate over its length, in double: a float's square underflows below 1e-19),
  // then the median: a scene of small parts near the origin and a large one far out is
  // intact, and so are layers stacked in a box, which an "edge" estimated from the box and the
  // face count had taken for a coarse sheet.
  const double largest = std::max(lo.max_abs(), hi.max_abs());
  if (out.span > 0 && largest > 0) {
    const auto step_at = [](double m) { return m > 0 ? std::max(std::ldexp(1.0, std::ilogb(m) - 23), std::ldexp(1.0, -149)) : 0.0; };
    std::vector<double> ratios;
    ratios.reserve(mesh.n_edges());
    for (auto e : mesh.edges()) {  // (every edge is a face's: isolated vertices have none)
      const auto h = mesh.halfedge_handle(e, 0);
      const OpenMesh::Vec3d a = OpenMesh::vector_cast<OpenMesh::Vec3d>(mesh.point(mesh.from_vertex_handle(h)));
      const OpenMesh::Vec3d b = OpenMesh::vector_cast<OpenMesh::Vec3d>(mesh.point(mesh.to_vertex_handle(h)));
      const double length = (b - a).norm(), step = step_at(std::max(a.max_abs(), b.max_abs()));
      ratios.push_back(length > 0 ? step / length : std::numeric_limits<double>::infinity());
    }
    std::nth_element(ratios.begin(), ratios.begin() + static_cast<std::ptrdiff_t>(ratios.size() / 2), ratios.end());
    out.largest_coordinate = largest;
    out.float_step = step_at(largest);
    out.step_per_edge = ratios[ratios.size() / 2];
    if (out.step_per_edge > kMaxFloatStepPerEdge)
      throw InputError(name, "its coordinates reach " + format_number(largest) + ", where 32-bit floats step by " + format_number(out.float_step) +
                                 ", and at its median edge the step exceeds a quarter of the edge: the mesh lost its shape when read (move it near the origin)");
  }
  return out;
}

}  // namespace meso
