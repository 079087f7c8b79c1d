// The nearest triangle of a set to a point, through an Embree BVH (internal to meshreduce:
// the surface distance and the surface fit share it).
#pragma once

#include "geometry.hpp"

#include "meso/core/error.hpp"
#include "meso/core/mesh.hpp"

#include <embree3/rtcore.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <mutex>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

namespace meso::reduce {

struct Triangle {
  Vec3d a, b, c;
  double area() const { return 0.5 * OpenMesh::cross(b - a, c - a).norm(); }
  // Collinear corners (zero cross product): no area, no plane; left out of the measure.
  bool degenerate() const { return OpenMesh::cross(b - a, c - a).sqrnorm() == 0; }
};

inline Vec3d point(const Vec3f& p) { return Vec3d(p[0], p[1], p[2]); }

// The squared distance from p to triangle t: Ericson's closest point (reduce::closest_point_sqr),
// guarded. On a sliver its region tests can disagree in rounding and reach the interior case
// with weights outside [0, 1]: a point of the plane beyond the triangle, nearer than the
// triangle, which would break the search's pruning below; the nearest edge is the answer then.
inline double distance_sqr(const Vec3d& p, const Triangle& t) {
  double w[3];
  const double d2 = reduce::closest_point_sqr(p, t.a, t.b, t.c, w);
  if (w[0] >= 0 && w[1] >= 0 && w[2] >= 0 && w[0] <= 1 && w[1] <= 1 && w[2] <= 1) return d2;
  const double ab = reduce::point_segment_distance(p, t.a, t.b), bc = reduce::point_segment_distance(p, t.b, t.c),
               ca = reduce::point_segment_distance(p, t.c, t.a);
  const double e = std::min({ab, bc, ca});
  return e * e;
}

// The nearest of a set of triangles to a point: an Embree BVH over them, queried with a
// sphere that shrinks to each closer triangle found (rtcPointQuery). Embree tests boxes in
// float, on corners stored relative to the set's centre; the sphere's radius is the exact
// (double) distance found so far plus a slack of 1e-6 of the coordinates' magnitude, well
// above the float rounding of the boxes and of the query point, so the nearest triangle is
// never culled. The distance is distance_sqr (Ericson's closest point, guarded), and
// ties go to the lowest index: the answer does not depend on the order Embree visits leaves.
class ClosestTriangles {
 public:
  explicit ClosestTriangles(const std::vector<Triangle>& tris) : tris_(tris) {
    if (tris.empty()) return;
    Vec3d lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
    for (const Triangle& t : tris)
      for (const Vec3d& p : {t.a, t.b, t.c}) lo.minimize(p), hi.maximize(p);
    centre_ = (lo + hi) * 0.5;
    extent_ = std::max((hi - lo).max_abs() * 0.5, std::numeric_limits<double>::min());
    vertices_.resize(9 * tris.size() + 1, 0.0f);  // + 1: Embree reads 16 bytes at the last vertex
    indices_.resize(3 * tris.size());
    for (size_t i = 0; i < tris.size(); ++i) {
      const Vec3d corners[3] = {tris[i].a, tris[i].b, tris[i].c};
      for (size_t k = 0; k < 3; ++k) {
        for (int j = 0; j < 3; ++j) vertices_[9 * i + 3 * k + static_cast<size_t>(j)] = static_cast<float>(corners[k][j] - centre_[j]);
        indices_[3 * i + k] = static_cast<uint32_t>(3 * i + k);
      }
    }
    device_ = rtcNewDevice(nullptr);
    if (!device_) throw InternalError("Embree: cannot create a device");
    scene_ = rtcNewScene(device_);
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_MEDIUM);
    RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, vertices_.data(), 0, 3 * sizeof(float), 3 * tris.size());
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, indices_.data(), 0, 3 * sizeof(uint32_t), tris.size());
    rtcCommitGeometry(geom);
    rtcAttachGeometry(scene_, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(scene_);
    if (rtcGetDeviceError(device_) != RTC_ERROR_NONE) {
      rtcReleaseScene(scene_);
      rtcReleaseDevice(device_);
      throw InternalError("Embree: cannot build the distance queries' BVH (out of memory?)");
    }
  }
  ~ClosestTriangles() {
    if (scene_) rtcReleaseScene(scene_);
    if (device_) rtcReleaseDevice(device_);
  }
  ClosestTriangles(const ClosestTriangles&) = delete;
  ClosestTriangles& operator=(const ClosestTriangles&) = delete;

  bool empty() const { return tris_.empty(); }
  const Triangle& triangle(int64_t i) const { return tris_[static_cast<size_t>(i)]; }

  // The squared distance from p to the nearest triangle and that triangle's index (infinity
  // and -1 for an empty set). `hint`, a triangle likely to be near (e.g. the previous
  // sample's nearest; -1: none), starts the search with its distance as the radius, which
  // prunes from the first node on; the answer is the same with any hint. Thread-safe.
  // With `against`: of the triangles as near as the nearest (within 1e-9 of its squared
  // distance: triangles sharing the nearest vertex or edge, whose distances differ only in
  // rounding), the one whose normal (cross product) has the least dot product with *against
  // (ties: the lowest index). A second search with that distance fixed picks it, so the
  // answer does not depend on the order either. A triangle with a reversed copy (find_twins)
  // is a two-sided sheet: it competes by its better side, and that side is returned.
  std::pair<double, int64_t> nearest(const Vec3d& p, int64_t hint = -1, const Vec3d* against = nullptr) const {
    Query q{this, p, std::numeric_limits<double>::infinity(), -1, 0};
    if (tris_.empty()) return {q.best2, q.best};
    const Vec3d r = p - centre_;
    q.slack = 1e-6 * std::max(extent_, r.max_abs());
    float radius = std::numeric_limits<float>::infinity();
    if (hint >= 0 && static_cast<size_t>(hint) < tris_.size()) {
      q.best2 = distance_sqr(p, tris_[static_cast<size_t>(hint)]);
      q.best = hint;
      radius = q.radius(q.best2);
    }
    RTCPointQuery query;
    query.x = static_cast<float>(r[0]);
    query.y = static_cast<float>(r[1]);
    query.z = static_cast<float>(r[2]);
    query.time = 0.0f;
    query.radius = radius;
    RTCPointQueryContext context;
    rtcInitPointQueryContext(&context);
    rtcPointQuery(scene_, &query, &context, &ClosestTriangles::visit, &q);
    if (!against || q.best < 0) return {q.best2, q.best};
    std::call_once(twins_built_, [this] { find_twins(); });
    Ties t{this, p, q.best2 * (1 + 1e-9), *against, q.best, 0};
    t.best_dot = t.sheet_dot(q.best);
    query.radius = q.radius(t.within2);  // fixed: the ball holds every tie
    rtcInitPointQueryContext(&context);
    rtcPointQuery(scene_, &query, &context, &ClosestTriangles::visit_ties, &t);
    const int64_t twin = twin_[static_cast<size_t>(t.best)];
    if (twin >= 0 && t.dot(twin) > t.dot(t.best)) t.best = twin;  // the side of the sheet facing that way
    return {q.best2, t.best};
  }

 private:
  struct Query {
    const ClosestTriangles* self;
    Vec3d p;
    double best2;
    int64_t best;
    double slack;
    // The search radius for a squared distance d2: its root, plus 1e-6 of it and the slack.
    float radius(double d2) const { return static_cast<float>(std::sqrt(d2) * (1 + 1e-6) + slack); }
  };

  static bool visit(RTCPointQueryFunctionArguments* args) {
    Query& q = *static_cast<Query*>(args->userPtr);
    const int64_t id = args->primID;
    const double d2 = distance_sqr(q.p, q.self->tris_[static_cast<size_t>(id)]);
    if (d2 > q.best2 || (d2 == q.best2 && id > q.best)) return false;
    q.best2 = d2;
    q.best = id;
    const float radius = q.radius(d2);
    if (!(radius < args->query->radius)) return false;
    args->query->radius = radius;
    return true;
  }

  // nearest()'s second search: among the triangles within within2 (squared), the least dot
  // product of the normal with `against`.
  struct Ties {
    const ClosestTriangles* self;
    Vec3d p;
    double within2;
    Vec3d against;
    int64_t best;
    double best_dot;
    double dot(int64_t id) const {
      const Triangle& t = self->tris_[static_cast<size_t>(id)];
      return OpenMesh::dot(against, OpenMesh::cross(t.b - t.a, t.c - t.a));
    }
    // A triangle with a reversed twin is one two-sided sheet, which faces every way: its
    // value is the better side's.
    double sheet_dot(int64_t id) const {
      const double d = dot(id);
      return self->twin_[static_cast<size_t>(id)] >= 0 ? std::abs(d) : d;
    }
  };

  // Pairs each triangle with another of the same three corners in the reverse orientation
  // (a two-sided sheet: import keeps the second face as an isolated one). Without this, the
  // ties' rule counted every face over such a sheet as facing away from it (the reversed copy
  // is always the tied triangle most against the face): a 3,200-face grid with 500 reversed
  // copies took 6 passes, 68 s, and reported 265 flipped faces.
  void find_twins() const {
    twin_.assign(tris_.size(), -1);
    // Corners sorted and hashed; equal hashes sorted next to each other, then compared
    // exactly (a hash map cost 5 % of a fast reduction of the 262k bricks, its allocations).
    using Corners = std::array<std::array<double, 3>, 3>;
    auto corners = [&](size_t i) {
      const Triangle& t = tris_[i];
      Corners c = {{{t.a[0], t.a[1], t.a[2]}, {t.b[0], t.b[1], t.b[2]}, {t.c[0], t.c[1], t.c[2]}}};
      std::sort(c.begin(), c.end());
      return c;
    };
    std::vector<std::pair<uint64_t, int64_t>> keys(tris_.size());
    for (size_t i = 0; i < tris_.size(); ++i) {
      const Corners c = corners(i);
      uint64_t h = 1469598103934665603ull;
      for (const auto& p : c)
        for (double x : p) {
          uint64_t b;
          std::memcpy(&b, &x, sizeof b);
          h = (h ^ b) * 1099511628211ull;
        }
      keys[i] = {h, static_cast<int64_t>(i)};
    }
    std::sort(keys.begin(), keys.end());
    for (size_t g = 0; g < keys.size();) {
      size_t e = g + 1;
      while (e < keys.size() && keys[e].first == keys[g].first) ++e;
      // Within a group (almost always of one), each triangle pairs with the first earlier
      // unpaired one of the same corners facing the other way.
      for (size_t x = g + 1; x < e; ++x)
        for (size_t y = g; y < x; ++y) {
          const size_t a = static_cast<size_t>(keys[y].second), b = static_cast<size_t>(keys[x].second);
          if (twin_[a] >= 0 || twin_[b] >= 0 || corners(a) != corners(b)) continue;
          const Triangle &t = tris_[a], &u = tris_[b];
          if (OpenMesh::dot(OpenMesh::cross(t.b - t.a, t.c - t.a), OpenMesh::cross(u.b - u.a, u.c - u.a)) < 0) {
            twin_[a] = static_cast<int64_t>(b);
            twin_[b] = static_cast<int64_t>(a);
          }
        }
      g = e;
    }
  }

  static bool visit_ties(RTCPointQueryFunctionArguments* args) {
    Ties& t = *static_cast<Ties*>(args->userPtr);
    const int64_t id = args->primID;
    if (distance_sqr(t.p, t.self->tris_[static_cast<size_t>(id)]) > t.within2) return false;
    const double dot = t.sheet_dot(id);
    if (dot < t.best_dot || (dot == t.best_dot && id < t.best)) {
      t.best_dot = dot;
      t.best = id;
    }
    return false;
  }

  const std::vector<Triangle>& tris_;
  mutable std::once_flag twins_built_;
  mutable std::vector<int64_t> twin_;  // find_twins(): a reversed copy, or -1
  std::vector<float> vertices_;
  std::vector<uint32_t> indices_;
  Vec3d centre_{0, 0, 0};
  double extent_ = 1;
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
};

// The mean edge length of a set of triangles (1 for an empty set): faces_away's sample spacing.
inline double mean_edge(const std::vector<Triangle>& tris) {
  if (tris.empty()) return 1.0;
  double edges = 0;
  for (const Triangle& t : tris) edges += (t.b - t.a).norm() + (t.c - t.b).norm() + (t.a - t.c).norm();
  return edges / (3.0 * static_cast<double>(tris.size()));
}

// faces_away()'s test: the cosine below which a face faces away, its sampling (k x k with k
// the face's longest edge over the mean edge, clamped to [min_k, max_k]), and whether a
// sample tied between triangles (nearest to a vertex or an edge they share) counts the one
// facing most against the face instead of the lowest index.
struct AwayTest {
  double min_cos;
  int min_k = 2, max_k = 16;
  bool worst_ties = false;
};

// Whether triangle (a, b, c), of normal n, faces away from the set's surface under it: the
// cosine between n and the summed (area-weighted) normals of the set's triangles nearest to
// the centroids of its k x k subdivision is below t.min_cos. With min_cos 0 and k in [4, 64]
// this is a flip as bench/meshreduce_peers counts it, up to its ties: at a brick's convex
// corner every triangle sharing the nearest vertex is nearest, and the bench counts any one
// of them (CGAL's pick); worst_ties makes the test hold whichever it picks. A face nearly
// perpendicular to the input is on the edge of that count, hence the callers' margins.
inline bool faces_away(const ClosestTriangles& set, const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& n, double mean_edge,
                       const AwayTest& test) {
  const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
  const int k = static_cast<int>(std::clamp(std::ceil(longest / mean_edge), static_cast<double>(test.min_k), static_cast<double>(test.max_k)));
  Vec3d m(0, 0, 0);
  int64_t hint = -1;
  for (int up = 1; up <= 2; ++up)  // upright sub-triangles, then the inverted ones
    for (int i = 0; i + up <= k; ++i)
      for (int j = 0; i + j + up <= k; ++j) {
        const double u = (i + up / 3.0) / k, v = (j + up / 3.0) / k;
        hint = set.nearest(a + u * (b - a) + v * (c - a), hint, test.worst_ties ? &n : nullptr).second;
        if (hint < 0) return false;
        const Triangle& t = set.triangle(hint);
        m += OpenMesh::cross(t.b - t.a, t.c - t.a);
      }
  return OpenMesh::dot(n, m) < test.min_cos * n.norm() * m.norm();
}

// The bench's flip test, screened: the full test (k in [4, 64] as the bench samples, ties
// counted against the face, below min_cos) only where a coarse look (k in [2, 8], ties to the
// lowest index) finds the face below screen_cos. Sampling every face fully cost `fast` on the
// 262k-face bricks at 1 % a fifth to a third of its time; counting ties in the coarse look
// too made `best` at 10 % a fifth slower and found no more flips (docs/benchmarks.md).
inline bool faces_away_screened(const ClosestTriangles& set, const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& n, double mean_edge,
                                double min_cos, double screen_cos) {
  return faces_away(set, a, b, c, n, mean_edge, AwayTest{screen_cos, 2, 8, false}) && faces_away(set, a, b, c, n, mean_edge, AwayTest{min_cos, 4, 64, true});
}

// A face that the reductions and best's fit report as flipped (ReduceReport::flipped_faces):
// faces_away_screened below cos 0.05 (3 degrees short of the bench's flip), screened at cos
// 0.8 (at 0.5 the screen let a flip through on the 96 x 48 wall at 3x relief).
constexpr double kFlippedCos = 0.05, kFlippedScreenCos = 0.8;

}  // namespace meso::reduce
