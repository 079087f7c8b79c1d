#include "meso/bake/tangent_frame.hpp"

#include "meso/core/mesh_arrays.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <tuple>

namespace meso {

namespace {

using Vec3d = OpenMesh::Vec3d;

// What one triangle contributes (MikkTSpace's per-triangle data).
struct FaceGradient {
  Vec3d dpdu{0, 0, 0}, dpdv{0, 0, 0};
  // Contributes to the frames around it: non-zero UV area, non-zero dp/du and dp/dv, no two
  // corners at one position. Other triangles ("wildcards", MikkTSpace's GROUP_WITH_ANY and
  // degenerate triangles) only take the frame of the group they join.
  bool valid = false;
  // UV triangle counter-clockwise (orientation preserving); for a wildcard, the orientation
  // it adopts from its neighbours (see compute_tangent_frames).
  bool preserving = true;
};

// Survey eq. 5: solve [p1 - p0, p2 - p0] = [T B] [uv1 - uv0, uv2 - uv0] for T = dp/du, B = dp/dv.
// The corners are taken from a canonical one (the smallest position, then UV), so the result
// does not depend on which halfedge the face stores.
FaceGradient face_gradient(const Mesh& mesh, FaceHandle f) {
  const auto hs = face_halfedges(mesh, f);
  std::array<std::array<float, 5>, 3> key;
  for (size_t i = 0; i < 3; ++i) {
    const Vec3f p = mesh.point(mesh.to_vertex_handle(hs[i]));
    const Vec2f t = mesh.texcoord2D(hs[i]);
    key[i] = {p[0], p[1], p[2], t[0], t[1]};
  }
  const size_t first = static_cast<size_t>(std::min_element(key.begin(), key.end()) - key.begin());
  Vec3d p[3];
  double u[3], v[3];
  for (size_t i = 0; i < 3; ++i) {
    const auto& k = key[(first + i) % 3];
    p[i] = Vec3d(k[0], k[1], k[2]);
    u[i] = k[3];
    v[i] = k[4];
  }
  FaceGradient g;
  const Vec3d e1 = p[1] - p[0], e2 = p[2] - p[0];
  const double du1 = u[1] - u[0], dv1 = v[1] - v[0], du2 = u[2] - u[0], dv2 = v[2] - v[0];
  // Exact for float inputs (differences and products of floats fit a double).
  const double det = du1 * dv2 - du2 * dv1;
  g.preserving = det > 0;
  if (p[0] == p[1] || p[0] == p[2] || p[1] == p[2]) return g;  // MikkTSpace drops these
  // A UV triangle whose area is tiny relative to its edges has no meaningful gradient.
  const double scale = std::max({std::abs(du1), std::abs(dv1), std::abs(du2), std::abs(dv2)});
  if (!(std::abs(det) > 1e-12 * scale * scale) || scale == 0) return g;
  g.dpdu = (e1 * dv2 - e2 * dv1) / det;
  g.dpdv = (e2 * du1 - e1 * du2) / det;
  const double ls = g.dpdu.norm(), lt = g.dpdv.norm();
  g.valid = std::isfinite(ls) && std::isfinite(lt) && ls > 0 && lt > 0;
  return g;
}

Vec3d point_d(const Mesh& mesh, VertexHandle v) { return OpenMesh::vector_cast<Vec3d>(mesh.point(v)); }

// x projected onto the plane of the unit normal n, normalised (zero stays zero).
Vec3d project_unit(const Vec3d& x, const Vec3d& n) {
  Vec3d y = x - n * OpenMesh::dot(n, x);
  const double l = y.norm();
  return l > 0 ? y / l : Vec3d(0, 0, 0);
}

// MikkTSpace's weight of the corner h (incoming to its vertex): the angle between its two
// edges after projecting them onto the plane of the vertex normal n.
double corner_weight(const Mesh& mesh, HalfedgeHandle h, const Vec3d& n) {
  const Vec3d c = point_d(mesh, mesh.to_vertex_handle(h));
  const Vec3d a = project_unit(point_d(mesh, mesh.from_vertex_handle(h)) - c, n);
  const Vec3d b = project_unit(point_d(mesh, mesh.to_vertex_handle(mesh.next_halfedge_handle(h))) - c, n);
  return std::acos(std::clamp(OpenMesh::dot(a, b), -1.0, 1.0));
}

// Corners around one vertex and the pairs of them that MikkTSpace connects: faces sharing an
// edge at the vertex whose two sides carry the same UVs at both ends (not a seam).
struct Fan {
  std::vector<HalfedgeHandle> corners;  // incoming halfedges with a face
  std::vector<std::pair<int, int>> links;
};

class DisjointSets {
 public:
  void reset(size_t n) {
    parent_.resize(n);
    std::iota(parent_.begin(), parent_.end(), 0);
  }
  int find(int a) {
    while (parent(a) != a) a = parent(a) = parent(parent(a));  // path halving
    return a;
  }
  void unite(int a, int b) {
    a = find(a);
    b = find(b);
    if (a != b) parent(std::max(a, b)) = std::min(a, b);
  }

 private:
  int& parent(int a) { return parent_[static_cast<size_t>(a)]; }
  std::vector<int> parent_;
};

class FanBuilder {
 public:
  explicit FanBuilder(const Mesh& mesh) : mesh_(mesh), local_(mesh.n_halfedges(), -1) {}

  const Fan& build(VertexHandle v) {
    for (auto h : fan_.corners) local_[static_cast<size_t>(h.idx())] = -1;
    fan_.corners.clear();
    fan_.links.clear();
    for (auto h : mesh_.vih_range(v)) {
      if (mesh_.is_boundary(h)) continue;
      local_[static_cast<size_t>(h.idx())] = static_cast<int>(fan_.corners.size());
      fan_.corners.push_back(h);
    }
    for (size_t a = 0; a < fan_.corners.size(); ++a) {
      // The edge from v along next(h): on its other side, the corner at v is opp(next(h)).
      const auto h = fan_.corners[a];
      const auto out = mesh_.next_halfedge_handle(h);
      const auto in = mesh_.opposite_halfedge_handle(out);
      if (mesh_.is_boundary(in)) continue;
      const int b = local_[static_cast<size_t>(in.idx())];
      if (b < 0) continue;
      // Same UV at v (corners h and in) and at the far end (corners out and prev(in)).
      if (!same_uv(mesh_, h, in) || !same_uv(mesh_, out, mesh_.prev_halfedge_handle(in))) continue;
      fan_.links.emplace_back(static_cast<int>(a), b);
    }
    return fan_;
  }

 private:
  const Mesh& mesh_;
  std::vector<int> local_;
  Fan fan_;
};

}  // namespace

std::vector<TangentFrame> compute_tangent_frames(const Mesh& mesh) {
  std::vector<TangentFrame> frames(mesh.n_halfedges());
  if (!has_uvs(mesh) || !mesh.has_vertex_normals()) return frames;
  std::vector<FaceGradient> grad(mesh.n_faces());
  for (auto f : mesh.faces()) grad[static_cast<size_t>(f.idx())] = face_gradient(mesh, f);
  auto face_of = [&](HalfedgeHandle h) -> FaceGradient& { return grad[static_cast<size_t>(mesh.face_handle(h).idx())]; };

  FanBuilder fans(mesh);
  DisjointSets sets;

  // Pass 1: the orientation of each wildcard triangle, from the ordinary triangles it reaches
  // around its corners through other wildcards: mirrored when every one it reaches is
  // mirrored, else preserving. (MikkTSpace lets the first group that reaches it decide, the
  // only place where its result depends on face order.)
  std::vector<uint8_t> reach(mesh.n_faces(), 0);  // bit 0: reaches a preserving, bit 1: a mirrored triangle
  for (auto v : mesh.vertices()) {
    const Fan& fan = fans.build(v);
    const size_t k = fan.corners.size();
    sets.reset(k);
    bool any_wild = false;
    for (size_t a = 0; a < k; ++a) any_wild |= !face_of(fan.corners[a]).valid;
    if (!any_wild) continue;
    for (const auto& [a, b] : fan.links)
      if (!face_of(fan.corners[static_cast<size_t>(a)]).valid && !face_of(fan.corners[static_cast<size_t>(b)]).valid) sets.unite(a, b);
    std::vector<uint8_t> component_reach(k, 0);
    for (const auto& [a, b] : fan.links) {
      const auto& ga = face_of(fan.corners[static_cast<size_t>(a)]);
      const auto& gb = face_of(fan.corners[static_cast<size_t>(b)]);
      if (ga.valid == gb.valid) continue;
      const int wild = ga.valid ? b : a;
      const auto& g = ga.valid ? ga : gb;
      component_reach[static_cast<size_t>(sets.find(wild))] |= g.preserving ? 1 : 2;
    }
    for (size_t a = 0; a < k; ++a) {
      if (face_of(fan.corners[a]).valid) continue;
      reach[static_cast<size_t>(mesh.face_handle(fan.corners[a]).idx())] |= component_reach[static_cast<size_t>(sets.find(static_cast<int>(a)))];
    }
  }
  for (auto f : mesh.faces()) {
    auto& g = grad[static_cast<size_t>(f.idx())];
    if (!g.valid) g.preserving = reach[static_cast<size_t>(f.idx())] != 2;
  }

  // Pass 2: per vertex, groups of corners connected through non-seam edges between triangles
  // of one orientation (MikkTSpace's groups); each group's frame is the angle-weighted
  // average of its ordinary triangles' projected dp/du, summed in a canonical order.
  struct Contribution {
    double w, tx, ty, tz, du, dv;
    bool operator<(const Contribution& o) const {
      return std::tie(w, tx, ty, tz, du, dv) < std::tie(o.w, o.tx, o.ty, o.tz, o.du, o.dv);
    }
  };
  std::vector<std::vector<Contribution>> groups;
  for (auto v : mesh.vertices()) {
    const Fan& fan = fans.build(v);
    const size_t k = fan.corners.size();
    if (k == 0) continue;
    Vec3d n = OpenMesh::vector_cast<Vec3d>(mesh.normal(v));
    if (!(n.norm() > 0)) n = Vec3d(0, 0, 1);
    n.normalize();
    sets.reset(k);
    for (const auto& [a, b] : fan.links)
      if (face_of(fan.corners[static_cast<size_t>(a)]).preserving == face_of(fan.corners[static_cast<size_t>(b)]).preserving) sets.unite(a, b);
    if (groups.size() < k) groups.resize(k);
    for (size_t a = 0; a < k; ++a) groups[a].clear();
    for (size_t a = 0; a < k; ++a) {
      const auto& g = face_of(fan.corners[a]);
      if (!g.valid) continue;
      const Vec3d t = project_unit(g.dpdu, n);
      groups[static_cast<size_t>(sets.find(static_cast<int>(a)))].push_back(
          {corner_weight(mesh, fan.corners[a], n), t[0], t[1], t[2], g.dpdu.norm(), g.dpdv.norm()});
    }
    for (size_t a = 0; a < k; ++a) {
      auto& c = groups[a];
      if (c.size() > 1) std::sort(c.begin(), c.end());
    }
    for (size_t a = 0; a < k; ++a) {
      const auto& c = groups[static_cast<size_t>(sets.find(static_cast<int>(a)))];
      Vec3d t_sum(0, 0, 0);
      double du_sum = 0, dv_sum = 0, w_sum = 0;
      for (const auto& x : c) {
        t_sum += Vec3d(x.tx, x.ty, x.tz) * x.w;
        du_sum += x.du * x.w;
        dv_sum += x.dv * x.w;
        w_sum += x.w;
      }
      TangentFrame fr;
      Vec3d t = t_sum;
      if (!(t.norm() > 1e-20)) {
        // No usable UV gradient here (only degenerate UVs, or contributions that cancel): any
        // tangent in the plane, so the frame stays orthonormal and finite; the decoded normal
        // is then still n for (0,0,1). (The reference leaves such corners undefined.)
        t = any_perpendicular(n);
      }
      t.normalize();
      fr.tangent = OpenMesh::vector_cast<Vec3f>(t);
      fr.sign = face_of(fan.corners[a]).preserving ? 1.0f : -1.0f;
      if (w_sum > 0) {
        fr.du_length = static_cast<float>(du_sum / w_sum);
        fr.dv_length = static_cast<float>(dv_sum / w_sum);
      }
      frames[static_cast<size_t>(fan.corners[a].idx())] = fr;
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
