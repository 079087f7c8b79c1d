// The constraints of meshreduce, one small module each (see CollapseModule). Each looks at
// the candidate's fan: the faces that survive the collapse with v0 or v1 as a corner, their
// old corner positions and UVs, and the new position q and UVs.
#pragma once

#include "closest_triangles.hpp"
#include "collapse_loop.hpp"
#include "geometry.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

#include <tbb/parallel_for.h>

namespace meso::reduce {

inline Vec3d new_normal(const FanFace& f, const Vec3d& q) { return OpenMesh::cross(f.b - q, f.c - q); }
inline Vec3d old_normal(const FanFace& f) { return OpenMesh::cross(f.b - f.old_p, f.c - f.old_p); }

// Locks (--lock-boundary, --lock-group): the flagged vertices are never removed and never
// move, so a face whose corners are all locked comes out exactly as it went in (it can only
// be removed as fl/fr of a collapse, whose two ends are its corners). The module pins its
// vertices in the loop, whose placement then collapses free neighbours onto them (the
// region around a lock still simplifies up to its outline); what it refuses, and counts,
// is the rest: an edge between two locked vertices, or a locked end that would have to go.
class VertexLock final : public CollapseModule {
 public:
  VertexLock(const char* name, std::vector<uint8_t> locked) : name_(name), locked_(std::move(locked)) {}
  const char* name() const override { return name_; }

  void initialize(CollapseLoop& loop) override {
    for (auto v : loop.mesh().vertices())
      if (locked(v)) loop.pin(v);
  }

  bool allow(const Candidate& c) override { return !locked(c.v0) && (!locked(c.v1) || c.q == c.p1); }

 private:
  bool locked(VertexHandle v) const { return locked_[static_cast<size_t>(v.idx())] != 0; }
  const char* name_;
  std::vector<uint8_t> locked_;
};

// Keeps UV charts and the outline: a seam/boundary vertex slides only along a straight
// stretch. The outline before (... other0, v0, v1, other1 ...) must stay within the
// tolerance of the outline after (... other0, q, other1 ...), in 3D (normalised units) and
// in the UVs of each chart along the seam. Also refuses sliver wedges (both feature edges of
// a vertex in one triangle: the collapse would glue a chart's edge to another chart).
class ChartGuard final : public CollapseModule {
 public:
  // Tolerances in normalised units for boundaries and for seams (ReduceOptions), and in UV units.
  ChartGuard(const CollapseLoop& loop, double boundary_tolerance, double seam_tolerance, double uv_tolerance)
      : loop_(loop), boundary_tol_(boundary_tolerance), seam_tol_(seam_tolerance), uv_tol_(uv_tolerance) {}
  const char* name() const override { return "chart_guard"; }

  bool allow(const Candidate& c) override {
    if (c.placement != Placement::slide) return true;
    const Mesh& m = loop_.mesh();
    if (!c.other0.is_valid()) return false;
    VertexHandle vl, vr;
    if (c.fl.is_valid()) vl = m.to_vertex_handle(m.next_halfedge_handle(c.h));
    if (c.fr.is_valid()) vr = m.to_vertex_handle(m.next_halfedge_handle(m.opposite_halfedge_handle(c.h)));
    if (c.other0 == vl || c.other0 == vr || c.other0 == c.v1) return false;
    const bool v1_moves = c.t < 1 && c.other1.is_valid();
    if (c.other1.is_valid() && (c.other1 == vl || c.other1 == vr || c.other1 == c.other0 || c.other1 == c.v0)) return false;
    const double pos_tol = m.is_boundary(c.e) ? boundary_tol_ : seam_tol_;
    if (point_segment_distance(c.p0, loop_.pos(c.other0), c.q) > pos_tol) return false;
    if (v1_moves && point_segment_distance(c.p1, c.q, loop_.pos(c.other1)) > pos_tol) return false;
    if (!m.has_halfedge_texcoords2D()) return true;
    for (int s = 0; s < 2; ++s) {
      if (!c.side_valid[s]) continue;
      const Vec2f nu = lerp_uv(c.uv0[s], c.uv1[s], c.t);
      if (point_segment_distance(c.uv0[s], c.uv_other0[s], nu) > uv_tol_) return false;
      if (v1_moves && point_segment_distance(c.uv1[s], nu, c.uv_other1[s]) > uv_tol_) return false;
    }
    return true;
  }

 private:
  const CollapseLoop& loop_;
  double boundary_tol_, seam_tol_, uv_tol_;
};

// No UV triangle flips or becomes degenerate (one already degenerate cannot get worse).
class UvFoldGuard final : public CollapseModule {
 public:
  const char* name() const override { return "uv_fold"; }
  bool allow(const Candidate& c) override {
    for (const auto& f : *c.fan) {
      const double before = uv_cross(f.old_uv, f.uv_b, f.uv_c);
      if (before == 0) continue;
      const double after = uv_cross(f.new_uv, f.uv_b, f.uv_c);
      if (after * before <= 0) return false;
    }
    return true;
  }
};

// The input surface that NoFlip tests steep faces against: its triangles and their BVH, in
// the loop's normalised coordinates, built by the first module that needs them. Reductions of
// the same input normalise it the same way, so `best`'s two share one (on a 2M-face wall,
// sharing it lowered `best`'s peak from 3.27 to 2.86 GB).
struct InputSurface {
  std::once_flag built;
  std::vector<Triangle> triangles;
  std::unique_ptr<ClosestTriangles> nearest;
  double mean_edge = 1;
};

// A ball (normalised coordinates) around a face that a reduction left facing away from the
// input under it: the face's centroid, out to its farthest corner.
struct FlipBall {
  Vec3d centre;
  double radius = 0;
};

// No face normal flips and no new degenerate face. Tests per face of the fan:
//  - against its normal before this collapse (dot > 0), the classic test;
//  - against the input surface the face stands for: the sum of the area-weighted normals
//    (cross products) of the input faces merged into it, each removed face's share going
//    half to each of the fan faces that shared an edge with it (all of it when only one
//    did), so the sums over the mesh stay the input's. The first test alone lets a face
//    turn by up to 90 degrees per collapse, and turns add up: on the brick wall a few faces
//    ended up facing against the surface they replace (cos -0.29 and -0.75 against the mean
//    normal of the input nearest to them; docs/benchmarks.md);
//  - a face more than 60 degrees from that sum, against the input triangles nearest to
//    samples over it (faces_away in closest_triangles.hpp, with a margin: refused past 84
//    degrees). Over steep relief the sum can hold enough of the flanks (of bricks) to pass a
//    face that faces away from the input under it (docs/benchmarks.md, "steep faces");
//  - within the `strict` balls, where an earlier pass of the same reduction left a flipped
//    face (reduce_mesh), every face, steep or not, against the input under it sampled as
//    the bench samples it (k up to 64, ties counted against it), refused past 84 degrees.
//    On walls with 2-4x the relief the 60-degree trigger misses faces that the bench counts
//    as flipped; testing every face everywhere made `fast` 9x slower (docs/benchmarks.md).
class NoFlip final : public CollapseModule {
 public:
  // `shared`: an InputSurface to use (and build, if no one has yet); null: one of its own.
  explicit NoFlip(InputSurface* shared = nullptr, std::vector<FlipBall> strict = {}) : surface_(shared), strict_(std::move(strict)) {
    if (!surface_) {
      own_ = std::make_unique<InputSurface>();
      surface_ = own_.get();
    }
  }

  const char* name() const override { return "normal_flip"; }

  void initialize(CollapseLoop& loop) override {
    const Mesh& m = loop.mesh();
    input_.assign(m.n_faces(), Vec3d(0, 0, 0));
    corners_.assign(m.n_faces(), {0, 0, 0});
    for (auto f : m.faces()) {
      const auto hs = face_halfedges(m, f);
      const Vec3d& a = loop.pos(m.to_vertex_handle(hs[0]));
      input_[static_cast<size_t>(f.idx())] = OpenMesh::cross(loop.pos(m.to_vertex_handle(hs[1])) - a, loop.pos(m.to_vertex_handle(hs[2])) - a);
      for (size_t k = 0; k < 3; ++k) corners_[static_cast<size_t>(f.idx())][k] = m.to_vertex_handle(hs[k]).idx();
    }
    points_.resize(m.n_vertices());
    for (auto v : m.vertices()) points_[static_cast<size_t>(v.idx())] = loop.pos(v);
  }

  bool allow(const Candidate& c) override {
    int shares_l = 0, shares_r = 0;
    for (const auto& f : *c.fan) shares_l += f.adjacent_fl, shares_r += f.adjacent_fr;
    const Vec3d removed_l = c.fl.is_valid() && shares_l > 0 ? input_[static_cast<size_t>(c.fl.idx())] / shares_l : Vec3d(0, 0, 0);
    const Vec3d removed_r = c.fr.is_valid() && shares_r > 0 ? input_[static_cast<size_t>(c.fr.idx())] / shares_r : Vec3d(0, 0, 0);
    merged_.clear();
    for (const auto& f : *c.fan) {
      Vec3d input = input_[static_cast<size_t>(f.f.idx())];
      if (f.adjacent_fl) input += removed_l;
      if (f.adjacent_fr) input += removed_r;
      merged_.push_back(input);
      const Vec3d n1 = new_normal(f, c.q);
      // Facing against its input (also a face that was degenerate); where the input's normals
      // cancel out (a sum of zero: a thin fold), nothing to face.
      if (OpenMesh::dot(n1, input) < 0) return false;
      // Steep against that sum: against the input under it, refused from 84 degrees on (cos
      // 0.1), a margin over the flip itself that the fit of `best` (surface_fit.cpp) relies on.
      if (OpenMesh::dot(n1, input) < 0.5 * n1.norm() * input.norm() && faces_away(c.q, f.b, f.c, n1, kSteepTest)) return false;
      if (!strict_.empty() && in_strict(c.q, f.b, f.c) && faces_away(c.q, f.b, f.c, n1, kFullTest)) return false;
      const Vec3d n0 = old_normal(f);
      if (!(n0.sqrnorm() > 0)) continue;  // already degenerate: cannot get worse
      // Degenerate: sin of the corner angle at q below 1e-9.
      const double scale = (f.b - c.q).sqrnorm() * (f.c - c.q).sqrnorm();
      if (!(n1.sqrnorm() > 1e-18 * scale)) return false;
      if (OpenMesh::dot(n0, n1) <= 0) return false;
    }
    return true;
  }

  void commit(const Candidate& c) override {
    for (size_t i = 0; i < c.fan->size(); ++i) input_[static_cast<size_t>((*c.fan)[i].f.idx())] = merged_[i];
  }

  // The faces of the loop's mesh (live, non-degenerate) flipped as bench/meshreduce_peers
  // counts a flip, or within 3 degrees of it (faces_away_screened at kFlippedCos). In face
  // order; the faces are tested in parallel.
  std::vector<FlipBall> flipped_faces(const CollapseLoop& loop) {
    ensure_surface();
    const Mesh& m = loop.mesh();
    std::vector<std::array<Vec3d, 3>> tris;
    tris.reserve(m.n_faces());
    for (auto f : m.faces()) {
      const auto hs = face_halfedges(m, f);
      tris.push_back({loop.pos(m.to_vertex_handle(hs[0])), loop.pos(m.to_vertex_handle(hs[1])), loop.pos(m.to_vertex_handle(hs[2]))});
    }
    std::vector<uint8_t> flipped(tris.size(), 0);
    tbb::parallel_for(size_t{0}, tris.size(), [&](size_t i) {
      const auto& [a, b, c] = tris[i];
      const Vec3d n = OpenMesh::cross(b - a, c - a);
      flipped[i] = n.sqrnorm() > 0 && faces_away_screened(*surface_->nearest, a, b, c, n, surface_->mean_edge, kFlippedCos, kFlippedScreenCos);
    });
    std::vector<FlipBall> out;
    for (size_t i = 0; i < tris.size(); ++i)
      if (flipped[i]) out.push_back(ball(tris[i][0], tris[i][1], tris[i][2]));
    return out;
  }

 private:
  // allow()'s tests, refused past 84 degrees: steep faces; every face in the strict balls,
  // sampled as the bench samples, the worst of tied triangles counted (a flip whichever the
  // bench picks).
  static constexpr AwayTest kSteepTest{0.1, 2, 16, false}, kFullTest{0.1, 4, 64, true};

  static FlipBall ball(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
    const Vec3d g = (a + b + c) / 3.0;
    return {g, std::max({(a - g).norm(), (b - g).norm(), (c - g).norm()})};
  }
  // Whether triangle (a, b, c)'s ball meets a strict one.
  bool in_strict(const Vec3d& a, const Vec3d& b, const Vec3d& c) const {
    const FlipBall t = ball(a, b, c);
    for (const FlipBall& s : strict_)
      if ((t.centre - s.centre).norm() < t.radius + s.radius) return true;
    return false;
  }

  // faces_away() against the input (refused past 84 degrees: cos 0.1), whose triangles and
  // BVH are built for the first face that needs them.
  bool faces_away(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& n, const AwayTest& test) {
    ensure_surface();
    return reduce::faces_away(*surface_->nearest, a, b, c, n, surface_->mean_edge, test);
  }
  void ensure_surface() {
    std::call_once(surface_->built, [&] {
      surface_->triangles.reserve(corners_.size());
      for (const auto& t : corners_)
        surface_->triangles.push_back(
            Triangle{points_[static_cast<size_t>(t[0])], points_[static_cast<size_t>(t[1])], points_[static_cast<size_t>(t[2])]});
      surface_->nearest = std::make_unique<ClosestTriangles>(surface_->triangles);
      surface_->mean_edge = mean_edge(surface_->triangles);
    });
  }

  std::vector<Vec3d> input_;   // per face: the summed area-weighted normals of its input faces
  std::vector<Vec3d> merged_;  // allow()'s sums for the fan, kept for commit()
  // The input surface (normalised coordinates), for faces_away().
  std::vector<Vec3d> points_;
  std::vector<std::array<int, 3>> corners_;
  InputSurface* surface_;
  std::unique_ptr<InputSurface> own_;
  std::vector<FlipBall> strict_;
};

// Normal cones per face (OpenMesh's ModNormalDeviation): every face keeps the cone of the
// normals of the input faces it replaced; a collapse is refused when a new normal would lie
// more than max_deviation from any normal in its face's cone.
class NormalDeviation final : public CollapseModule {
 public:
  explicit NormalDeviation(double max_deviation_degrees) : max_(max_deviation_degrees * M_PI / 180.0) {}
  const char* name() const override { return "normal_deviation"; }

  void initialize(CollapseLoop& loop) override {
    const Mesh& m = loop.mesh();
    cones_.assign(m.n_faces(), Cone());
    for (auto f : m.faces()) {
      const auto hs = face_halfedges(m, f);
      const Vec3d& a = loop.pos(m.to_vertex_handle(hs[0]));
      Vec3d n = OpenMesh::cross(loop.pos(m.to_vertex_handle(hs[1])) - a, loop.pos(m.to_vertex_handle(hs[2])) - a);
      const double l = n.norm();
      if (l > 0) cones_[static_cast<size_t>(f.idx())] = Cone{n / l, 0.0};
    }
  }

  bool allow(const Candidate& c) override {
    merged_.clear();
    for (const auto& f : *c.fan) {
      Cone cone = cone_of(f, c);
      Vec3d n = new_normal(f, c.q);
      const double l = n.norm();
      if (!(l > 0)) return false;
      n /= l;
      if (!cone.empty() && angle(n, cone.axis) + cone.angle > max_) return false;
      cone.merge(Cone{n, 0.0});
      merged_.push_back(cone);
    }
    return true;
  }

  void commit(const Candidate& c) override {
    for (size_t i = 0; i < c.fan->size(); ++i) cones_[static_cast<size_t>((*c.fan)[i].f.idx())] = merged_[i];
  }

 private:
  struct Cone {
    Vec3d axis{0, 0, 0};
    double angle = -1;  // < 0: empty
    bool empty() const { return angle < 0; }
    void merge(const Cone& o) {
      if (o.empty()) return;
      if (empty()) {
        *this = o;
        return;
      }
      const double between = NormalDeviation::angle(axis, o.axis);
      if (between + o.angle <= angle) return;
      if (between + angle <= o.angle) {
        *this = o;
        return;
      }
      const double wide = 0.5 * (between + angle + o.angle);
      if (wide >= M_PI || between > M_PI - 1e-9) {
        angle = M_PI;
        return;
      }
      // Rotate the axis towards o's by (wide - angle) in the plane of the two axes.
      const double turn = wide - angle, s = std::sin(between);
      axis = (axis * std::sin(between - turn) + o.axis * std::sin(turn)) / s;
      axis.normalize();
      angle = wide;
    }
  };

  static double angle(const Vec3d& a, const Vec3d& b) { return std::acos(std::clamp(OpenMesh::dot(a, b), -1.0, 1.0)); }

  Cone cone_of(const FanFace& f, const Candidate& c) const {
    Cone cone = cones_[static_cast<size_t>(f.f.idx())];
    if (f.adjacent_fl) cone.merge(cones_[static_cast<size_t>(c.fl.idx())]);
    if (f.adjacent_fr) cone.merge(cones_[static_cast<size_t>(c.fr.idx())]);
    return cone;
  }

  double max_;
  std::vector<Cone> cones_;
  std::vector<Cone> merged_;
};

// No needles: a collapse may not create a face whose aspect ratio exceeds the bound unless
// the faces it replaces (around v0 and v1) already had one at least as bad.
class AspectRatioGuard final : public CollapseModule {
 public:
  AspectRatioGuard(const CollapseLoop& loop, double max_ratio) : loop_(loop), max_(max_ratio) {}
  const char* name() const override { return "aspect_ratio"; }
  bool allow(const Candidate& c) override {
    double worst_new = 0;
    for (const auto& f : *c.fan) worst_new = std::max(worst_new, aspect_ratio(c.q, f.b, f.c));
    if (worst_new <= max_) return true;
    double worst_old = 0;
    for (const auto& f : *c.fan) worst_old = std::max(worst_old, aspect_ratio(f.old_p, f.b, f.c));
    const Mesh& m = loop_.mesh();
    for (const HalfedgeHandle h : {c.h, m.opposite_halfedge_handle(c.h)}) {
      if (!m.face_handle(h).is_valid()) continue;
      worst_old = std::max(worst_old, aspect_ratio(loop_.pos(m.from_vertex_handle(h)), loop_.pos(m.to_vertex_handle(h)),
                                                   loop_.pos(m.to_vertex_handle(m.next_halfedge_handle(h)))));
    }
    return worst_new <= worst_old;
  }

 private:
  const CollapseLoop& loop_;
  double max_;
};

// The error bound, both ways, checked on the collapse's neighbourhood only.
//  - Input to output: every input vertex, every input edge's midpoint and three points
//    inside every input face (at barycentric (2/3, 1/6, 1/6) and rotations) are samples, each kept in a list on a face
//    of the current mesh within the bound of it (at first: a face it lies on). A collapse
//    re-checks the samples of the faces it touches (fan, fl, fr) against the new fan: a
//    sample stays on its face while that face (moved) is within the bound, else goes to the
//    nearest fan face; the collapse is refused when one is farther than the bound from all.
//  - Output to input: the new vertex, the centroids of the new fan faces and the midpoints
//    of their new edges must lie within the bound of the input surface (exact distance to
//    the input triangles, found through a uniform grid of cells at least the bound wide).
// Lists are linked through one array, the grid is built once: no allocation per collapse
// once the scratch vectors have grown.
class ErrorBound final : public CollapseModule {
 public:
  explicit ErrorBound(double max_error) : max_(max_error), max2_(max_error * max_error) {}
  const char* name() const override { return "error_bound"; }

  void initialize(CollapseLoop& loop) override {
    const Mesh& m = loop.mesh();
    head_.assign(m.n_faces(), -1);
    sample_.clear();
    next_.clear();
    auto add = [&](const Vec3d& p, FaceHandle f) {
      const int s = static_cast<int>(sample_.size());
      sample_.push_back(p);
      next_.push_back(head_[static_cast<size_t>(f.idx())]);
      head_[static_cast<size_t>(f.idx())] = s;
    };
    for (auto v : m.vertices()) {
      for (auto vf : m.vf_range(v)) {
        add(loop.pos(v), vf);
        break;
      }
    }
    for (auto e : m.edges()) {
      const HalfedgeHandle h = m.halfedge_handle(e, m.is_boundary(m.halfedge_handle(e, 0)) ? 1 : 0);
      add((loop.pos(m.from_vertex_handle(h)) + loop.pos(m.to_vertex_handle(h))) * 0.5, m.face_handle(h));
    }
    triangle_.clear();
    double edge_sum = 0;
    for (auto f : m.faces()) {
      const auto hs = face_halfedges(m, f);
      const std::array<Vec3d, 3> t = {loop.pos(m.to_vertex_handle(hs[0])), loop.pos(m.to_vertex_handle(hs[1])),
                                      loop.pos(m.to_vertex_handle(hs[2]))};
      triangle_.push_back(t);
      edge_sum += (t[1] - t[0]).norm() + (t[2] - t[1]).norm() + (t[0] - t[2]).norm();
      for (size_t k = 0; k < 3; ++k) add(t[k] * (2.0 / 3.0) + (t[(k + 1) % 3] + t[(k + 2) % 3]) / 6.0, f);
    }
    // The grid: cells no narrower than the bound (a query looks at 2x2x2 cells at most) nor
    // than the mean edge (a triangle spans few cells), nor than 2^-20 of the unit box.
    const double mean_edge = triangle_.empty() ? 1.0 : edge_sum / (3.0 * static_cast<double>(triangle_.size()));
    cell_ = std::max({max_, mean_edge, std::ldexp(1.0, -20)});
    cells_.clear();
    for (size_t i = 0; i < triangle_.size(); ++i) {
      const auto& t = triangle_[i];
      Vec3d lo = t[0], hi = t[0];
      for (const auto& p : t) lo.minimize(p), hi.maximize(p);
      const auto a = cell_of(lo), b = cell_of(hi);
      for (int64_t x = a[0]; x <= b[0]; ++x)
        for (int64_t y = a[1]; y <= b[1]; ++y)
          for (int64_t z = a[2]; z <= b[2]; ++z) cells_.push_back({key(x, y, z), static_cast<int>(i)});
    }
    std::sort(cells_.begin(), cells_.end(), [](const Cell& l, const Cell& r) { return l.key < r.key || (l.key == r.key && l.tri < r.tri); });
  }

  bool allow(const Candidate& c) override {
    assign_.clear();
    const auto& fan = *c.fan;
    double w[3];
    auto visit = [&](FaceHandle f, int own) {
      if (!f.is_valid()) return true;
      for (int s = head_[static_cast<size_t>(f.idx())]; s >= 0; s = next_[static_cast<size_t>(s)]) {
        const Vec3d& p = sample_[static_cast<size_t>(s)];
        if (own >= 0 && closest_point_sqr(p, c.q, fan[size_t(own)].b, fan[size_t(own)].c, w) <= max2_) {
          assign_.push_back({s, own});
          continue;
        }
        double best = std::numeric_limits<double>::max();
        int best_i = -1;
        for (size_t i = 0; i < fan.size(); ++i) {
          const double d2 = closest_point_sqr(p, c.q, fan[i].b, fan[i].c, w);
          if (d2 < best) best = d2, best_i = static_cast<int>(i);
        }
        if (best > max2_ || best_i < 0) return false;
        assign_.push_back({s, best_i});
      }
      return true;
    };
    for (size_t i = 0; i < fan.size(); ++i)
      if (!visit(fan[i].f, static_cast<int>(i))) return false;
    if (!visit(c.fl, -1) || !visit(c.fr, -1)) return false;
    // Output to input.
    if (!near_input(c.q)) return false;
    for (const auto& f : fan) {
      if (!near_input((c.q + f.b + f.c) / 3.0) || !near_input((c.q + f.b) * 0.5)) return false;
    }
    return true;
  }

  void commit(const Candidate& c) override {
    const auto& fan = *c.fan;
    for (const auto& f : fan) head_[static_cast<size_t>(f.f.idx())] = -1;
    if (c.fl.is_valid()) head_[static_cast<size_t>(c.fl.idx())] = -1;
    if (c.fr.is_valid()) head_[static_cast<size_t>(c.fr.idx())] = -1;
    for (const auto& a : assign_) {
      const size_t f = static_cast<size_t>(fan[static_cast<size_t>(a.face)].f.idx());
      next_[static_cast<size_t>(a.sample)] = head_[f];
      head_[f] = a.sample;
    }
  }

  // The largest distance from a sample to the face it is assigned to, on the final mesh
  // (normalised units): the tracked one-sided error from the input's samples.
  double tracked(const CollapseLoop& loop) const {
    const Mesh& m = loop.mesh();
    double worst = 0;
    double w[3];
    for (auto f : m.faces()) {
      if (m.status(f).deleted()) continue;
      const auto hs = face_halfedges(m, f);
      const Vec3d& a = loop.pos(m.to_vertex_handle(hs[0]));
      const Vec3d& b = loop.pos(m.to_vertex_handle(hs[1]));
      const Vec3d& cc = loop.pos(m.to_vertex_handle(hs[2]));
      for (int s = head_[static_cast<size_t>(f.idx())]; s >= 0; s = next_[static_cast<size_t>(s)])
        worst = std::max(worst, closest_point_sqr(sample_[static_cast<size_t>(s)], a, b, cc, w));
    }
    return std::sqrt(worst);
  }

 private:
  struct Assign {
    int sample, face;
  };
  struct Cell {
    uint64_t key;
    int tri;
  };

  std::array<int64_t, 3> cell_of(const Vec3d& p) const {
    return {static_cast<int64_t>(std::floor(p[0] / cell_)), static_cast<int64_t>(std::floor(p[1] / cell_)),
            static_cast<int64_t>(std::floor(p[2] / cell_))};
  }
  static uint64_t key(int64_t x, int64_t y, int64_t z) {
    const uint64_t m = (1u << 21) - 1;
    return ((static_cast<uint64_t>(x) & m) << 42) | ((static_cast<uint64_t>(y) & m) << 21) | (static_cast<uint64_t>(z) & m);
  }

  // Whether p lies within the bound of an input triangle.
  bool near_input(const Vec3d& p) const {
    const auto a = cell_of(p - Vec3d(max_)), b = cell_of(p + Vec3d(max_));
    double w[3];
    for (int64_t x = a[0]; x <= b[0]; ++x)
      for (int64_t y = a[1]; y <= b[1]; ++y)
        for (int64_t z = a[2]; z <= b[2]; ++z) {
          const uint64_t k = key(x, y, z);
          auto it = std::lower_bound(cells_.begin(), cells_.end(), k, [](const Cell& cell, uint64_t v) { return cell.key < v; });
          for (; it != cells_.end() && it->key == k; ++it) {
            const auto& t = triangle_[static_cast<size_t>(it->tri)];
            if (closest_point_sqr(p, t[0], t[1], t[2], w) <= max2_) return true;
          }
        }
    return false;
  }

  double max_, max2_;
  std::vector<Vec3d> sample_;
  std::vector<int> next_, head_;
  std::vector<std::array<Vec3d, 3>> triangle_;
  double cell_ = 1;
  std::vector<Cell> cells_;
  std::vector<Assign> assign_;
};

}  // namespace meso::reduce
