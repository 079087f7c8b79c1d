#include "collapse_loop.hpp"

#include "geometry.hpp"
#include "halfedge_collapse.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace meso::reduce {

namespace {

// A small bias towards short edges, so that ties on flat, zero-cost regions go to the
// shortest edge first (more even triangles) instead of to the lowest edge index.
constexpr double kLengthBias = 1e-12;

Vec3d to_d(const Vec3f& p) { return Vec3d(p[0], p[1], p[2]); }

size_t ix(int i) { return static_cast<size_t>(i); }

}  // namespace

CollapseLoop::CollapseLoop(Mesh& mesh, const LoopOptions& options) : mesh_(mesh), options_(options) {
  const size_t nv = mesh_.n_vertices(), ne = mesh_.n_edges();
  // Normalise to the unit box: centre on the box, scale by a power of two so that the
  // extent is in (0.5, 1]. Unmoved points convert back exactly.
  Vec3d lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
  for (auto v : mesh_.vertices()) {
    const Vec3d p = to_d(mesh_.point(v));
    lo.minimize(p);
    hi.maximize(p);
  }
  if (nv == 0) lo = hi = Vec3d(0, 0, 0);
  center_ = (lo + hi) * 0.5;
  const double extent = (hi - lo).max();
  scale_ = 1.0;
  if (extent > 0 && std::isfinite(extent)) {
    int e = 0;
    std::frexp(extent, &e);  // extent = m * 2^e, m in [0.5, 1)
    scale_ = std::ldexp(1.0, -e);
  }
  pos_.resize(nv);
  for (auto v : mesh_.vertices()) pos_[ix(v.idx())] = (to_d(mesh_.point(v)) - center_) * scale_;
  moved_.assign(nv, 0);
  pinned_.assign(nv, 0);

  efeat_.assign(ne, 0);
  for (auto e : mesh_.edges()) efeat_[ix(e.idx())] = mesh_.is_boundary(e) || seam(e);
  vdeg_.assign(nv, 0);
  for (auto v : mesh_.vertices()) vdeg_[ix(v.idx())] = feature_degree(v);

  // Area-weighted plane quadrics, plus planes through feature edges perpendicular to their
  // faces, weighted by boundary_weight (seams: seam_weight) times the edge's squared length.
  quadric_.assign(nv, Quadric());
  faces_ = 0;
  double mean_area = 0;  // uniform_planes: every face plane gets this weight
  if (options_.uniform_planes) {
    size_t n = 0;
    for (auto f : mesh_.faces()) {
      const auto hs = face_halfedges(mesh_, f);
      const Vec3d& a = pos_[ix(mesh_.to_vertex_handle(hs[0]).idx())];
      const Vec3d& b = pos_[ix(mesh_.to_vertex_handle(hs[1]).idx())];
      const Vec3d& c = pos_[ix(mesh_.to_vertex_handle(hs[2]).idx())];
      mean_area += 0.5 * OpenMesh::cross(b - a, c - a).norm();
      ++n;
    }
    mean_area /= static_cast<double>(std::max<size_t>(1, n));
  }
  for (auto f : mesh_.faces()) {
    ++faces_;
    const auto hs = face_halfedges(mesh_, f);
    const VertexHandle v[3] = {mesh_.to_vertex_handle(hs[0]), mesh_.to_vertex_handle(hs[1]), mesh_.to_vertex_handle(hs[2])};
    const Vec3d& a = pos_[ix(v[0].idx())];
    const Vec3d& b = pos_[ix(v[1].idx())];
    const Vec3d& c = pos_[ix(v[2].idx())];
    Vec3d n = OpenMesh::cross(b - a, c - a);
    const double len = n.norm();
    if (!(len > 0)) continue;
    n /= len;
    const Quadric q = Quadric::plane(n, -OpenMesh::dot(n, a), options_.uniform_planes ? mean_area : 0.5 * len);
    for (auto vh : v) quadric_[ix(vh.idx())] += q;
    for (auto h : hs) {
      if (!efeat_[ix(mesh_.edge_handle(h).idx())]) continue;
      const VertexHandle from = mesh_.from_vertex_handle(h), to = mesh_.to_vertex_handle(h);
      const Vec3d& p = pos_[ix(from.idx())];
      const Vec3d d = pos_[ix(to.idx())] - p;
      Vec3d cn = OpenMesh::cross(d, n);
      const double cl = cn.norm();
      if (!(cl > 0)) continue;
      cn /= cl;
      const double weight = mesh_.is_boundary(mesh_.edge_handle(h)) ? options_.boundary_weight : options_.seam_weight;
      const Quadric cq = Quadric::plane(cn, -OpenMesh::dot(cn, p), weight * d.sqrnorm());
      quadric_[ix(from.idx())] += cq;
      quadric_[ix(to.idx())] += cq;
    }
  }

  hpos_.assign(ne, -1);
  ring_mark_.assign(nv, 0);
  heap_.reserve(ne);
  fan_.reserve(64);
  around_.reserve(64);
}

// The topological test of collapsing h (v0 = from, v1 = to), with the answers of OpenMesh's
// TriConnectivity::is_collapse_ok: the link condition of Dey et al. (the one-rings of v0 and
// v1 meet only in the opposite corners vl and vr of the two faces at the edge), no face
// whose other two edges are both on the boundary, no interior edge between two boundary
// vertices. Why not OpenMesh's: Debian builds libOpenMeshCore with assertions on, and their
// property type checks (string comparisons, allocations) made that one call 16 % of the
// reduction; here the one-ring intersection is a stamp per vertex instead of status tags.
bool CollapseLoop::collapse_ok(HalfedgeHandle h) {
  if (mesh_.status(mesh_.edge_handle(h)).deleted()) return false;
  const HalfedgeHandle o = mesh_.opposite_halfedge_handle(h);
  const VertexHandle v0 = mesh_.to_vertex_handle(o), v1 = mesh_.to_vertex_handle(h);
  if (mesh_.status(v0).deleted() || mesh_.status(v1).deleted()) return false;
  VertexHandle vl, vr;
  if (!mesh_.is_boundary(h)) {
    const HalfedgeHandle h1 = mesh_.next_halfedge_handle(h), h2 = mesh_.next_halfedge_handle(h1);
    vl = mesh_.to_vertex_handle(h1);
    if (mesh_.is_boundary(mesh_.opposite_halfedge_handle(h1)) && mesh_.is_boundary(mesh_.opposite_halfedge_handle(h2))) return false;
  }
  if (!mesh_.is_boundary(o)) {
    const HalfedgeHandle h1 = mesh_.next_halfedge_handle(o), h2 = mesh_.next_halfedge_handle(h1);
    vr = mesh_.to_vertex_handle(h1);
    if (mesh_.is_boundary(mesh_.opposite_halfedge_handle(h1)) && mesh_.is_boundary(mesh_.opposite_halfedge_handle(h2))) return false;
  }
  if (vl == vr) return false;  // equal, or both invalid (an isolated edge)
  if (++ring_stamp_ == 0) {      // wrapped: clear the stamps once every 2^32 tests
    std::fill(ring_mark_.begin(), ring_mark_.end(), 0u);
    ring_stamp_ = 1;
  }
  for (auto w : mesh_.vv_range(v1)) ring_mark_[ix(w.idx())] = ring_stamp_;
  for (auto w : mesh_.vv_range(v0))
    if (ring_mark_[ix(w.idx())] == ring_stamp_ && w != vl && w != vr) return false;
  if (mesh_.is_boundary(v0) && mesh_.is_boundary(v1) && !mesh_.is_boundary(h) && !mesh_.is_boundary(o)) return false;
  return true;
}

bool CollapseLoop::seam(Mesh::EdgeHandle e) const {
  if (!options_.has_uvs || mesh_.is_boundary(e)) return false;
  const HalfedgeHandle h0 = mesh_.halfedge_handle(e, 0), h1 = mesh_.halfedge_handle(e, 1);
  return !(mesh_.texcoord2D(h0) == mesh_.texcoord2D(mesh_.prev_halfedge_handle(h1))) ||
         !(mesh_.texcoord2D(h1) == mesh_.texcoord2D(mesh_.prev_halfedge_handle(h0)));
}

uint16_t CollapseLoop::feature_degree(VertexHandle v) const {
  int n = 0;
  for (auto h : mesh_.voh_range(v)) n += efeat_[ix(mesh_.edge_handle(h).idx())];
  return static_cast<uint16_t>(n);
}

bool CollapseLoop::evaluate(Mesh::EdgeHandle e, Candidate& c) {
  if (mesh_.status(e).deleted()) return false;
  const HalfedgeHandle h0 = mesh_.halfedge_handle(e, 0), h1 = mesh_.halfedge_handle(e, 1);
  const uint16_t da = vdeg_[ix(mesh_.from_vertex_handle(h0).idx())], db = vdeg_[ix(mesh_.to_vertex_handle(h0).idx())];
  // A pinned vertex (a lock) behaves like a corner of the seam network: it is never the
  // removed end, and the other end collapses onto it. With both ends pinned, the edge keeps
  // its usual placement and the lock module refuses it.
  const bool pa = pinned_[ix(mesh_.from_vertex_handle(h0).idx())] != 0, pb = pinned_[ix(mesh_.to_vertex_handle(h0).idx())] != 0;
  HalfedgeHandle h;
  bool fixed = false;  // slide onto v1 (a corner of the feature network, or pinned)
  if (efeat_[ix(e.idx())]) {
    c.placement = Placement::slide;
    if (da == 2 && (!pa || pb)) {
      h = h0;
      fixed = db != 2 || pb;
    } else if (db == 2) {
      h = h1;
      fixed = true;
    } else {
      return false;  // both ends are corners of the seam/boundary network
    }
  } else if (da == 0 && db == 0) {
    c.placement = pa == pb ? Placement::optimal : Placement::onto;
    h = pa && !pb ? h1 : h0;
  } else if (da == 0) {
    c.placement = Placement::onto;
    h = h0;
  } else if (db == 0) {
    c.placement = Placement::onto;
    h = h1;
  } else {
    return false;  // would pinch a chart or the outline
  }
  c.e = e;
  c.h = h;
  c.v0 = mesh_.from_vertex_handle(h);
  c.v1 = mesh_.to_vertex_handle(h);
  c.fl = mesh_.face_handle(h);
  c.fr = mesh_.face_handle(mesh_.opposite_halfedge_handle(h));
  c.p0 = pos_[ix(c.v0.idx())];
  c.p1 = pos_[ix(c.v1.idx())];
  const Quadric q = quadric_[ix(c.v0.idx())] + quadric_[ix(c.v1.idx())];
  switch (c.placement) {
    case Placement::optimal:
      c.t = -1;
      c.cost = optimal_placement(q, c.p0, c.p1, c.q);
      break;
    case Placement::onto:
      c.t = 1;
      c.q = c.p1;
      c.cost = q(c.p1);
      break;
    case Placement::slide:
      if (fixed) {
        c.t = 1;
      } else {
        segment_placement(q, c.p0, c.p1, c.t);
      }
      c.q = c.t == 1 ? c.p1 : c.t == 0 ? c.p0 : c.p0 + (c.p1 - c.p0) * c.t;
      c.cost = q(c.q);
      break;
  }
  if (!std::isfinite(c.cost)) return false;
  return true;
}

static float key_of(const Candidate& c) {
  return static_cast<float>(c.cost + kLengthBias * (c.p1 - c.p0).sqrnorm());
}

void CollapseLoop::push_edge(Mesh::EdgeHandle e) {
  Candidate c;
  if (evaluate(e, c)) heap_set(e.idx(), key_of(c));
}

void CollapseLoop::walk(Candidate& c, VertexHandle v, HalfedgeHandle start, int start_side, bool from_v0) {
  const bool track_other = from_v0 || vdeg_[ix(v.idx())] == 2;
  HalfedgeHandle cur = start;
  int side = start_side;
  const Vec3d& pv = pos_[ix(v.idx())];
  for (int guard = 0; guard < (1 << 16); ++guard) {
    const FaceHandle f = mesh_.face_handle(cur);
    const HalfedgeHandle pe = mesh_.prev_halfedge_handle(cur);  // into v
    if (f.is_valid() && f != c.fl && f != c.fr) {
      FanFace ff;
      ff.f = f;
      ff.corner = pe;
      ff.old_p = pv;
      const HalfedgeHandle nx = mesh_.next_halfedge_handle(cur);
      ff.b = pos_[ix(mesh_.to_vertex_handle(cur).idx())];
      ff.c = pos_[ix(mesh_.to_vertex_handle(nx).idx())];
      if (options_.has_uvs) {
        ff.old_uv = mesh_.texcoord2D(pe);
        ff.uv_b = mesh_.texcoord2D(cur);
        ff.uv_c = mesh_.texcoord2D(nx);
      }
      const FaceHandle fa = mesh_.face_handle(mesh_.opposite_halfedge_handle(cur));
      const FaceHandle fb = mesh_.face_handle(mesh_.opposite_halfedge_handle(pe));
      ff.adjacent_fl = c.fl.is_valid() && (fa == c.fl || fb == c.fl);
      ff.adjacent_fr = c.fr.is_valid() && (fa == c.fr || fb == c.fr);
      ff.new_uv = ff.old_uv;
      ff.side = static_cast<uint8_t>(side & 1);
      ff.from_v0 = from_v0;
      fan_.push_back(ff);
    }
    const auto pe_edge = mesh_.edge_handle(pe);
    if (efeat_[ix(pe_edge.idx())]) {
      if (pe_edge != c.e && track_other && c.placement == Placement::slide) {
        const VertexHandle o = mesh_.from_vertex_handle(pe);
        Vec2f* uvo = from_v0 ? c.uv_other0 : c.uv_other1;
        (from_v0 ? c.other0 : c.other1) = o;
        if (options_.has_uvs) {
          if (f.is_valid()) uvo[side & 1] = mesh_.texcoord2D(mesh_.prev_halfedge_handle(pe));
          const HalfedgeHandle op = mesh_.opposite_halfedge_handle(pe);
          if (mesh_.face_handle(op).is_valid()) uvo[(side + 1) & 1] = mesh_.texcoord2D(op);
        }
      }
      ++side;
    }
    cur = mesh_.opposite_halfedge_handle(pe);
    if (cur == start) break;
  }
}

void CollapseLoop::gather_fan(Candidate& c) {
  fan_.clear();
  c.other0 = c.other1 = VertexHandle();
  const HalfedgeHandle o = mesh_.opposite_halfedge_handle(c.h);
  c.side_valid[0] = c.fl.is_valid();
  c.side_valid[1] = c.fr.is_valid();
  if (options_.has_uvs) {
    if (c.fl.is_valid()) {
      c.uv0[0] = mesh_.texcoord2D(mesh_.prev_halfedge_handle(c.h));
      c.uv1[0] = mesh_.texcoord2D(c.h);
    }
    if (c.fr.is_valid()) {
      c.uv0[1] = mesh_.texcoord2D(o);
      c.uv1[1] = mesh_.texcoord2D(mesh_.prev_halfedge_handle(o));
    }
  }
  walk(c, c.v0, c.h, 0, true);
  walk(c, c.v1, o, 1, false);
  c.fan = &fan_;
  if (!options_.has_uvs) return;
  switch (c.placement) {
    case Placement::optimal: {
      // The UV of the new position re-projected onto the old neighbourhood; where that
      // folds a UV triangle (the position left the old surface over a steep or curved
      // part), the UV at q's projection on the edge, then either endpoint's.
      const Vec3d d = c.p1 - c.p0;
      const double l2 = d.sqrnorm();
      const double s = l2 > 0 ? std::clamp(OpenMesh::dot(c.q - c.p0, d) / l2, 0.0, 1.0) : 0.5;
      const Vec2f options[4] = {reproject_uv(c), lerp_uv(c.uv0[0], c.uv1[0], s), c.uv1[0], c.uv0[0]};
      Vec2f uv = options[0];
      for (const Vec2f& option : options) {
        if (!folds(option)) {
          uv = option;
          break;
        }
      }
      for (auto& ff : fan_) ff.new_uv = uv;
      break;
    }
    case Placement::onto: {
      // v0 is inside one chart, which holds fl and fr: its corners take v1's UV there.
      const Vec2f uv = c.fl.is_valid() ? c.uv1[0] : c.uv1[1];
      for (auto& ff : fan_)
        if (ff.from_v0) ff.new_uv = uv;
      break;
    }
    case Placement::slide:
      for (auto& ff : fan_) {
        if (!ff.from_v0 && c.t == 1) continue;  // v1 stays: its corners keep their UVs
        const int s = ff.side;
        if (!c.side_valid[s]) continue;
        ff.new_uv = lerp_uv(c.uv0[s], c.uv1[s], c.t);
      }
      break;
  }
}

bool CollapseLoop::folds(const Vec2f& uv) const {
  for (const auto& ff : fan_) {
    const double before = uv_cross(ff.old_uv, ff.uv_b, ff.uv_c);
    if (before != 0 && uv_cross(uv, ff.uv_b, ff.uv_c) * before <= 0) return true;
  }
  return false;
}

Vec2f CollapseLoop::reproject_uv(const Candidate& c) const {
  // The closest point to q on the old triangles around v0 and v1 (fan, fl, fr), and the
  // UV interpolated there.
  double best = std::numeric_limits<double>::max();
  Vec2f uv = c.fl.is_valid() ? c.uv1[0] : c.uv1[1];
  auto consider = [&](const Vec3d& a, const Vec3d& b, const Vec3d& cc, const Vec2f& ua, const Vec2f& ub, const Vec2f& uc) {
    double w[3];
    const double d2 = closest_point_sqr(c.q, a, b, cc, w);
    if (d2 < best) {
      best = d2;
      uv = Vec2f(static_cast<float>(w[0] * ua[0] + w[1] * ub[0] + w[2] * uc[0]),
                 static_cast<float>(w[0] * ua[1] + w[1] * ub[1] + w[2] * uc[1]));
    }
  };
  for (const auto& ff : fan_) consider(ff.old_p, ff.b, ff.c, ff.old_uv, ff.uv_b, ff.uv_c);
  for (const HalfedgeHandle h : {c.h, mesh_.opposite_halfedge_handle(c.h)}) {
    if (!mesh_.face_handle(h).is_valid()) continue;
    const HalfedgeHandle n = mesh_.next_halfedge_handle(h), p = mesh_.prev_halfedge_handle(h);
    consider(pos_[ix(mesh_.from_vertex_handle(h).idx())], pos_[ix(mesh_.to_vertex_handle(h).idx())],
             pos_[ix(mesh_.to_vertex_handle(n).idx())], mesh_.texcoord2D(p), mesh_.texcoord2D(h), mesh_.texcoord2D(n));
  }
  return uv;
}

void CollapseLoop::apply(const Candidate& c) {
  // Edges around v0 and v1 give back their feature counts (the survivors, now around w,
  // count again below); they stay in the heap, where the deleted ones are removed and the
  // others get new keys after the collapse.
  around_.clear();
  for (auto v : {c.v0, c.v1}) {
    for (auto h : mesh_.voh_range(v)) {
      const auto e = mesh_.edge_handle(h);
      uint8_t& f = efeat_[ix(e.idx())];
      if (v == c.v0 || mesh_.to_vertex_handle(h) != c.v0) around_.push_back(e.idx());
      if (!f) continue;
      f = 0;
      --vdeg_[ix(mesh_.from_vertex_handle(h).idx())];
      --vdeg_[ix(mesh_.to_vertex_handle(h).idx())];
    }
  }
  const size_t i0 = ix(c.v0.idx()), i1 = ix(c.v1.idx());
  quadric_[i1] += quadric_[i0];
  if (c.q == c.p1) {
    // v1 stays.
  } else if (c.q == c.p0) {
    moved_[i1] = moved_[i0];
    mesh_.set_point(c.v1, mesh_.point(c.v0));
  } else {
    moved_[i1] = 1;
  }
  pos_[i1] = c.q;
  faces_ -= static_cast<size_t>(c.fl.is_valid()) + static_cast<size_t>(c.fr.is_valid());
  const int collapsed = c.h.idx();
  HalfedgeCollapser(mesh_).collapse(c.h);
  const VertexHandle w = c.v1;
  if (options_.has_uvs) {
    // Set every corner at w from the face it belongs to (collapse moves halfedges of the
    // removed faces into their neighbours, carrying the removed faces' UVs).
    for (auto h : mesh_.vih_range(w)) {
      const FaceHandle f = mesh_.face_handle(h);
      if (!f.is_valid()) continue;
      for (const auto& ff : fan_) {
        if (ff.f == f) {
          mesh_.set_texcoord2D(h, ff.new_uv);
          break;
        }
      }
    }
  }
  if (record_) {
    // After the UVs: the replay sets the same corners, in the same (circulator) order.
    ProgressiveMesh::Collapse r;
    r.halfedge = static_cast<uint32_t>(collapsed);
    r.position = object_point(w);
    record_->collapses.push_back(r);
    if (options_.has_uvs)
      for (auto h : mesh_.vih_range(w))
        if (mesh_.face_handle(h).is_valid()) record_->uvs.push_back(mesh_.texcoord2D(h));
  }
  update_features_around(w);
  for (const int e : around_) {
    if (mesh_.status(Mesh::EdgeHandle(e)).deleted()) heap_remove(e);
  }
  for (auto h : mesh_.voh_range(w)) {
    const auto e = mesh_.edge_handle(h);
    if (options_.lazy && hpos_[ix(e.idx())] >= 0) continue;  // re-evaluated when popped
    Candidate n;
    if (evaluate(e, n)) {
      heap_set(e.idx(), key_of(n));
    } else {
      heap_remove(e.idx());
    }
  }
  // Edges refused before may be legal now that their neighbourhood changed (also with lazy
  // keys: leaving them out until they are around a kept vertex saved 5 % of the
  // instructions but let a face on the bricks turn 25 degrees past perpendicular over
  // several collapses, each within the flip test).
  for (auto n : mesh_.vv_range(w)) {
    for (auto h : mesh_.voh_range(n)) {
      const auto e = mesh_.edge_handle(h);
      if (hpos_[ix(e.idx())] < 0 && mesh_.to_vertex_handle(h) != w) push_edge(e);
    }
  }
}

void CollapseLoop::update_features_around(VertexHandle w) {
  for (auto h : mesh_.voh_range(w)) {
    const auto e = mesh_.edge_handle(h);
    const bool f = mesh_.is_boundary(e) || seam(e);
    efeat_[ix(e.idx())] = f;
    if (f) {
      ++vdeg_[ix(w.idx())];
      ++vdeg_[ix(mesh_.to_vertex_handle(h).idx())];
    }
  }
}

size_t CollapseLoop::run(Progress& progress) {
  for (auto m = modules_.begin(); m != modules_.end(); ++m) (*m)->initialize(*this);
  // Build the heap bottom-up (linear time).
  heap_.clear();
  {
    Candidate c0;
    for (auto e : mesh_.edges()) {
      if (!evaluate(e, c0)) continue;
      hpos_[ix(e.idx())] = static_cast<int>(heap_.size());
      heap_.push_back(Slot{key_of(c0), e.idx()});
    }
  }
  for (size_t i = heap_.size() / kHeapArity + 1; i-- > 0;)
    if (i < heap_.size()) sift_down(i);

  const size_t target = options_.target_faces;
  const uint64_t total = faces_ > target ? (faces_ - target) : 0;
  const uint64_t step = std::max<uint64_t>(1, total / 200);
  const size_t start_faces = faces_;
  uint64_t reported = 0;
  progress.begin(options_.label, total);
  size_t collapses = 0;
  Candidate c;
  while (faces_ > target && !heap_.empty()) {
    const Slot top = heap_[0];
    heap_remove(top.edge);
    const Mesh::EdgeHandle e(top.edge);
    if (!evaluate(e, c)) continue;
    const float key = key_of(c);
    if (key > top.key) {  // stale: its neighbourhood changed since it was queued
      heap_set(top.edge, key);
      continue;
    }
    if (!collapse_ok(c.h)) {
      if (c.placement != Placement::optimal) continue;
      // Either direction gives the same result but the topology test may differ.
      const HalfedgeHandle o = mesh_.opposite_halfedge_handle(c.h);
      if (!collapse_ok(o)) continue;
      c.h = o;
      std::swap(c.v0, c.v1);
      std::swap(c.fl, c.fr);
      std::swap(c.p0, c.p1);
    }
    gather_fan(c);
    bool ok = true;
    for (auto& m : modules_) {
      if (!m->allow(c)) {
        ++m->rejected;
        ok = false;
        break;
      }
    }
    if (!ok) continue;
    for (auto& m : modules_) m->commit(c);
    max_cost_ = std::max(max_cost_, c.cost);
    apply(c);
    ++collapses;
    const uint64_t done = start_faces - faces_;
    if (done >= reported + step) {
      progress.advance(std::min(done, total) - reported);
      reported = std::min(done, total);
    }
  }
  progress.end();
  return collapses;
}

Vec3f CollapseLoop::object_point(VertexHandle v) const {
  const size_t i = ix(v.idx());
  if (!moved_[i]) return mesh_.point(v);
  const Vec3d p = pos_[i] / scale_ + center_;
  return Vec3f(static_cast<float>(p[0]), static_cast<float>(p[1]), static_cast<float>(p[2]));
}

void CollapseLoop::write_back() {
  for (auto v : mesh_.vertices()) {
    if (!moved_[ix(v.idx())] || mesh_.status(v).deleted()) continue;
    mesh_.set_point(v, object_point(v));
  }
}

// ---- indexed 4-ary heap ----

void CollapseLoop::heap_set(int edge, float key) {
  const int at = hpos_[ix(edge)];
  if (at < 0) {
    heap_.push_back(Slot{key, edge});
    hpos_[ix(edge)] = static_cast<int>(heap_.size() - 1);
    sift_up(heap_.size() - 1);
    return;
  }
  const Slot old = heap_[ix(at)];
  heap_[ix(at)].key = key;
  if (less(heap_[ix(at)], old)) {
    sift_up(ix(at));
  } else {
    sift_down(ix(at));
  }
}

void CollapseLoop::heap_remove(int edge) {
  const int at = hpos_[ix(edge)];
  if (at < 0) return;
  hpos_[ix(edge)] = -1;
  const Slot last = heap_.back();
  heap_.pop_back();
  if (ix(at) == heap_.size()) return;
  place(ix(at), last);
  sift_up(ix(at));
  sift_down(ix(hpos_[ix(last.edge)]));
}

void CollapseLoop::sift_up(size_t i) {
  const Slot s = heap_[i];
  while (i > 0) {
    const size_t parent = (i - 1) / kHeapArity;
    if (!less(s, heap_[parent])) break;
    place(i, heap_[parent]);
    i = parent;
  }
  place(i, s);
}

void CollapseLoop::sift_down(size_t i) {
  const Slot s = heap_[i];
  const size_t n = heap_.size();
  for (;;) {
    const size_t first = kHeapArity * i + 1;
    if (first >= n) break;
    size_t child = first;
    const size_t end = std::min(first + kHeapArity, n);
    for (size_t k = first + 1; k < end; ++k)
      if (less(heap_[k], heap_[child])) child = k;
    if (!less(heap_[child], s)) break;
    place(i, heap_[child]);
    i = child;
  }
  place(i, s);
}

}  // namespace meso::reduce
