// A binary Decimater module that keeps UV charts and boundaries intact.
//
// Legal collapses v0 -> v1 (v0 disappears, v1 stays where it is):
//  - v0 inside a chart (not on a boundary, not on a UV seam): always, provided no UV
//    triangle around v0 flips or becomes degenerate when its corner moves to v1's UV;
//  - v0 on a boundary or seam: only along that boundary/seam (v1 is one of v0's two
//    feature neighbours) and only if v0 lies within tolerance of the straight chord between
//    them, in 3D and in every UV chart it belongs to. Then removing v0 leaves the outline
//    unchanged up to the tolerance.
// postprocess_collapse() gives the halfedges that pointed to v0 the UV of v1 in their chart.
#pragma once

#include "meso/core/mesh.hpp"

#include <OpenMesh/Tools/Decimater/ModBaseT.hh>

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

namespace meso {

template <class MeshT>
class ModChartGuardT : public OpenMesh::Decimater::ModBaseT<MeshT> {
 public:
  DECIMATING_MODULE(ModChartGuardT, MeshT, ChartGuard);

  explicit ModChartGuardT(MeshT& mesh) : Base(mesh, true) {}

  void set_tolerances(float position_tol, float uv_tol) {
    pos_tol_ = position_tol;
    uv_tol_ = uv_tol;
  }

  float collapse_priority(const CollapseInfo& ci) override {
    const MeshT& m = Base::mesh();
    const bool uv = m.has_halfedge_texcoords2D();
    if (is_feature_vertex(ci.v0)) {
      // Must move along a feature edge to a feature neighbour, over a straight stretch.
      const auto e = m.edge_handle(ci.v0v1);
      if (!is_feature_edge(e)) return Base::ILLEGAL_COLLAPSE;
      typename MeshT::VertexHandle other;
      int count = 0;
      for (auto h : m.voh_range(ci.v0)) {
        if (!is_feature_edge(m.edge_handle(h))) continue;
        ++count;
        if (m.to_vertex_handle(h) != ci.v1) other = m.to_vertex_handle(h);
      }
      if (count != 2 || !other.is_valid()) return Base::ILLEGAL_COLLAPSE;  // a corner of the outline
      // Both feature edges in one triangle (a sliver wedge): the collapse would glue the
      // surviving halfedge of that triangle into the face across the other feature edge,
      // carrying the wrong chart's UV. Never worth it.
      if (other == ci.vl || other == ci.vr) return Base::ILLEGAL_COLLAPSE;
      if (distance_to_segment(m.point(ci.v0), m.point(other), m.point(ci.v1)) > pos_tol_)
        return Base::ILLEGAL_COLLAPSE;
      if (uv) {
        // In each chart around v0, v0's UV must lie on the chord of its neighbours' UVs.
        for (auto h : m.vih_range(ci.v0)) {
          if (m.is_boundary(h)) continue;
          const auto uv0 = m.texcoord2D(h);
          const auto uv1 = uv_at(ci.v1, m.face_handle(h), h);
          const auto uvo = uv_at(other, m.face_handle(h), h);
          if (!uv1 || !uvo) return Base::ILLEGAL_COLLAPSE;
          if (distance_to_segment2(uv0, *uvo, *uv1) > uv_tol_) return Base::ILLEGAL_COLLAPSE;
        }
      }
    }
    if (uv && !uv_fan_stays_valid(ci)) return Base::ILLEGAL_COLLAPSE;
    return Base::LEGAL_COLLAPSE;
  }

  void preprocess_collapse(const CollapseInfo& ci) override {
    const MeshT& m = Base::mesh();
    moved_.clear();
    if (!m.has_halfedge_texcoords2D()) return;
    // Each surviving halfedge into v0 lies in some face around v0; its new UV is v1's UV in
    // that face's chart, which is the UV of v1 at the same chart side. Walk the fan.
    for (auto h : m.vih_range(ci.v0)) {
      if (m.is_boundary(h)) continue;
      const auto f = m.face_handle(h);
      if (f == ci.fl || f == ci.fr) continue;
      const auto uv1 = uv_at(ci.v1, f, h);
      moved_.push_back({h, uv1 ? *uv1 : m.texcoord2D(h)});
    }
  }

  void postprocess_collapse(const CollapseInfo&) override {
    MeshT& m = Base::mesh();
    for (const auto& mv : moved_) m.set_texcoord2D(mv.h, mv.uv);
  }

 private:
  using Vec2 = typename MeshT::TexCoord2D;
  using Point = typename MeshT::Point;
  struct Moved {
    typename MeshT::HalfedgeHandle h;
    Vec2 uv;
  };

  // A feature edge: on the boundary or a UV seam.
  bool is_feature_edge(typename MeshT::EdgeHandle e) {
    const MeshT& m = Base::mesh();
    return m.is_boundary(e) || is_uv_seam(m, e);
  }
  bool is_feature_vertex(typename MeshT::VertexHandle v) {
    const MeshT& m = Base::mesh();
    for (auto h : m.voh_range(v)) {
      if (is_feature_edge(m.edge_handle(h))) return true;
    }
    return false;
  }

  // The UV of vertex `v` in the chart of face `f`, found by walking the faces around `v`
  // that share UVs with `f` (crossing only non-seam edges); none if no such face has v.
  std::optional<Vec2> uv_at(typename MeshT::VertexHandle v, typename MeshT::FaceHandle f, typename MeshT::HalfedgeHandle from) {
    const MeshT& m = Base::mesh();
    // v is a corner of f? Then read it directly.
    for (auto h : m.fh_range(f)) {
      if (m.to_vertex_handle(h) == v) return m.texcoord2D(h);
    }
    // Otherwise v is a neighbour of from's to-vertex: rotate around it through non-seam edges
    // until a face containing v is found.
    for (int dir = 0; dir < 2; ++dir) {
      auto h = from;  // incoming to center, in face f
      for (int guard = 0; guard < 64; ++guard) {
        // Edge to cross: dir 0 crosses next(h) (outgoing from center), dir 1 crosses h.
        const auto cross = dir == 0 ? m.next_halfedge_handle(h) : h;
        if (is_feature_edge(m.edge_handle(cross))) break;
        const auto opp = m.opposite_halfedge_handle(cross);
        if (m.is_boundary(opp)) break;
        h = dir == 0 ? opp : m.prev_halfedge_handle(opp);
        for (auto g : m.fh_range(m.face_handle(h))) {
          if (m.to_vertex_handle(g) == v) return m.texcoord2D(g);
        }
        if (m.face_handle(h) == f) break;
      }
    }
    return std::nullopt;
  }

  bool uv_fan_stays_valid(const CollapseInfo& ci) {
    const MeshT& m = Base::mesh();
    for (auto h : m.vih_range(ci.v0)) {
      if (m.is_boundary(h)) continue;
      const auto f = m.face_handle(h);
      if (f == ci.fl || f == ci.fr) continue;
      const Vec2 a = m.texcoord2D(h);
      const auto hn = m.next_halfedge_handle(h);
      const Vec2 b = m.texcoord2D(hn), c = m.texcoord2D(m.next_halfedge_handle(hn));
      const auto moved = uv_at(ci.v1, f, h);
      if (!moved) return false;
      const float before = cross2(b - a, c - a), after = cross2(b - *moved, c - *moved);
      if (before == 0.0f) continue;  // already degenerate in UV: cannot get worse
      if (after * before <= 0.0f) return false;
    }
    return true;
  }

  static float cross2(const Vec2& a, const Vec2& b) { return a[0] * b[1] - a[1] * b[0]; }
  static float distance_to_segment(const Point& p, const Point& a, const Point& b) {
    const Point ab = b - a;
    const float l2 = ab.sqrnorm();
    const float t = l2 > 0 ? std::clamp(OpenMesh::dot(p - a, ab) / l2, 0.0f, 1.0f) : 0.0f;
    return (p - (a + ab * t)).norm();
  }
  static float distance_to_segment2(const Vec2& p, const Vec2& a, const Vec2& b) {
    const Vec2 ab = b - a;
    const float l2 = ab.sqrnorm();
    const float t = l2 > 0 ? std::clamp(OpenMesh::dot(p - a, ab) / l2, 0.0f, 1.0f) : 0.0f;
    return (p - (a + ab * t)).norm();
  }

  float pos_tol_ = 0, uv_tol_ = 0;
  std::vector<Moved> moved_;
};

}  // namespace meso
