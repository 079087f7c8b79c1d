#include "meso/bake/tangent_frame.hpp"

#include "meso/core/mesh_arrays.hpp"

#include <algorithm>
#include <cmath>

namespace meso {

namespace {

using Vec3d = OpenMesh::Vec3d;

struct FaceGradient {
  Vec3d dpdu{0, 0, 0}, dpdv{0, 0, 0};
  bool valid = false;
  bool mirrored = false;
};

// Survey eq. 5: solve [p1 - p0, p2 - p0] = [T B] [uv1 - uv0, uv2 - uv0] for T = dp/du, B = dp/dv.
FaceGradient face_gradient(const Mesh& mesh, FaceHandle f) {
  const auto hs = face_halfedges(mesh, f);
  Vec3d p[3];
  double u[3], v[3];
  for (int i = 0; i < 3; ++i) {
    p[i] = OpenMesh::vector_cast<Vec3d>(mesh.point(mesh.to_vertex_handle(hs[static_cast<size_t>(i)])));
    const Vec2f t = mesh.texcoord2D(hs[static_cast<size_t>(i)]);
    u[i] = t[0];
    v[i] = t[1];
  }
  const Vec3d e1 = p[1] - p[0], e2 = p[2] - p[0];
  const double du1 = u[1] - u[0], dv1 = v[1] - v[0], du2 = u[2] - u[0], dv2 = v[2] - v[0];
  const double det = du1 * dv2 - du2 * dv1;
  FaceGradient g;
  // A UV triangle whose area is tiny relative to its edges has no meaningful gradient.
  const double scale = std::max({std::abs(du1), std::abs(dv1), std::abs(du2), std::abs(dv2)});
  if (!(std::abs(det) > 1e-12 * scale * scale) || scale == 0) return g;
  g.dpdu = (e1 * dv2 - e2 * dv1) / det;
  g.dpdv = (e2 * du1 - e1 * du2) / det;
  g.valid = std::isfinite(g.dpdu.sqrnorm()) && std::isfinite(g.dpdv.sqrnorm());
  g.mirrored = det < 0;
  return g;
}

double corner_angle(const Mesh& mesh, HalfedgeHandle h) {
  const Vec3d c = OpenMesh::vector_cast<Vec3d>(mesh.point(mesh.to_vertex_handle(h)));
  const Vec3d a = OpenMesh::vector_cast<Vec3d>(mesh.point(mesh.from_vertex_handle(h))) - c;
  const Vec3d b = OpenMesh::vector_cast<Vec3d>(mesh.point(mesh.to_vertex_handle(mesh.next_halfedge_handle(h)))) - c;
  const double la = a.norm(), lb = b.norm();
  if (!(la > 0 && lb > 0)) return 0;
  return std::acos(std::clamp(OpenMesh::dot(a, b) / (la * lb), -1.0, 1.0));
}

}  // namespace

std::vector<TangentFrame> compute_tangent_frames(const Mesh& mesh) {
  std::vector<TangentFrame> frames(mesh.n_halfedges());
  if (!has_uvs(mesh) || !mesh.has_vertex_normals()) return frames;
  std::vector<FaceGradient> grad(mesh.n_faces());
  for (auto f : mesh.faces()) grad[static_cast<size_t>(f.idx())] = face_gradient(mesh, f);

  std::vector<HalfedgeHandle> incoming;
  for (auto v : mesh.vertices()) {
    Vec3d n = OpenMesh::vector_cast<Vec3d>(mesh.normal(v));
    if (!(n.norm() > 0)) n = Vec3d(0, 0, 1);
    n.normalize();
    incoming.clear();
    for (auto h : mesh.vih_range(v)) {
      if (!mesh.is_boundary(h)) incoming.push_back(h);
    }
    for (auto h : incoming) {
      const auto& gh = grad[static_cast<size_t>(mesh.face_handle(h).idx())];
      // Sum over corners at v that share this corner's UV and mirroring.
      Vec3d t_sum(0, 0, 0), b_sum(0, 0, 0);
      double du_sum = 0, dv_sum = 0, w_sum = 0;
      for (auto g : incoming) {
        const auto& gg = grad[static_cast<size_t>(mesh.face_handle(g).idx())];
        if (!same_uv(mesh, g, h)) continue;
        if (!gg.valid || gg.mirrored != gh.mirrored) continue;
        const double w = corner_angle(mesh, g);
        Vec3d t = gg.dpdu - n * OpenMesh::dot(n, gg.dpdu);
        const double tl = t.norm();
        if (tl > 0) t_sum += t * (w / tl);
        b_sum += gg.dpdv * w;
        du_sum += gg.dpdu.norm() * w;
        dv_sum += gg.dpdv.norm() * w;
        w_sum += w;
      }
      TangentFrame fr;
      Vec3d t = t_sum;
      if (!(t.norm() > 1e-20)) {
        // No usable UV gradient here (degenerate UVs): any tangent in the plane, so the
        // frame stays orthonormal and finite; the decoded normal is then still n for (0,0,1).
        t = any_perpendicular(n);
      }
      t.normalize();
      fr.tangent = OpenMesh::vector_cast<Vec3f>(t);
      const Vec3d b_ortho = OpenMesh::cross(n, t);
      fr.sign = OpenMesh::dot(b_ortho, b_sum) < 0 ? -1.0f : 1.0f;
      if (w_sum > 0) {
        fr.du_length = static_cast<float>(du_sum / w_sum);
        fr.dv_length = static_cast<float>(dv_sum / w_sum);
      }
      frames[static_cast<size_t>(h.idx())] = fr;
    }
  }
  return frames;
}

void store_tangents(Mesh& mesh, const std::vector<TangentFrame>& frames) {
  const auto prop = add_tangent_property(mesh);
  for (auto h : mesh.halfedges()) {
    const auto& f = frames[static_cast<size_t>(h.idx())];
    mesh.property(prop, h) = OpenMesh::Vec4f(f.tangent[0], f.tangent[1], f.tangent[2], f.sign);
  }
}

}  // namespace meso
