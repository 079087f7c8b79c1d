// The surface distance: closest-point queries through an Embree BVH (rtcPointQuery), the
// distances themselves in double precision.
#include "meso/meshreduce/surface_distance.hpp"

#include "geometry.hpp"

#include "meso/core/error.hpp"

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

namespace meso {

namespace {

using reduce::Vec3d;

// splitmix64: a portable generator, so samples are the same on every platform.
struct Random {
  uint64_t state;
  uint64_t next() {
    uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
};

struct Triangle {
  Vec3d a, b, c;
  double area() const { return 0.5 * OpenMesh::cross(b - a, c - a).norm(); }
  // Collinear corners (zero cross product): no area, no plane; left out of the measure.
  bool degenerate() const { return OpenMesh::cross(b - a, c - a).sqrnorm() == 0; }
};

Vec3d point(const Vec3f& p) { return Vec3d(p[0], p[1], p[2]); }

Triangle triangle(const TriangleSoup& m, const std::array<uint32_t, 3>& t) {
  return Triangle{point(m.points[t[0]]), point(m.points[t[1]]), point(m.points[t[2]])};
}

std::vector<Triangle> triangles(const TriangleSoup& m) {
  std::vector<Triangle> out;
  out.reserve(m.triangles.size());
  for (const auto& t : m.triangles) {
    const Triangle tri = triangle(m, t);
    if (!tri.degenerate()) out.push_back(tri);
  }
  return out;
}

// The squared distance from p to triangle t: Ericson's closest point (reduce::closest_point_sqr),
// guarded. On a sliver its region tests can disagree in rounding and reach the interior case
// with weights outside [0, 1]: a point of the plane beyond the triangle, nearer than the
// triangle, which would break the search's pruning below; the nearest edge is the answer then.
double distance_sqr(const Vec3d& p, const Triangle& t) {
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

  // The squared distance from p to the nearest triangle and that triangle's index (infinity
  // and -1 for an empty set). `hint`, a triangle likely to be near (e.g. the previous
  // sample's nearest; -1: none), starts the search with its distance as the radius, which
  // prunes from the first node on; the answer is the same with any hint. Thread-safe.
  std::pair<double, int64_t> nearest(const Vec3d& p, int64_t hint = -1) const {
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
    return {q.best2, q.best};
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

  const std::vector<Triangle>& tris_;
  std::vector<float> vertices_;
  std::vector<uint32_t> indices_;
  Vec3d centre_{0, 0, 0};
  double extent_ = 1;
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
};

// Every point used by a triangle, plus `n` points spread over the triangles by area.
std::vector<Vec3d> sample(const TriangleSoup& m, const std::vector<Triangle>& tris, size_t n, uint64_t seed) {
  std::vector<Vec3d> out;
  std::vector<char> used(m.points.size(), 0);
  for (const auto& t : m.triangles)
    for (const uint32_t i : t) used[i] = 1;
  for (size_t i = 0; i < m.points.size(); ++i)
    if (used[i]) out.push_back(point(m.points[i]));
  double total = 0;
  for (const auto& t : tris) total += t.area();
  if (!(total > 0)) return out;
  out.reserve(out.size() + n + tris.size());
  Random rng{seed};
  for (const auto& t : tris) {
    const double expected = static_cast<double>(n) * t.area() / total;
    const size_t count = static_cast<size_t>(expected + rng.uniform());  // stochastic rounding
    for (size_t i = 0; i < count; ++i) {
      const double r1 = std::sqrt(rng.uniform()), r2 = rng.uniform();
      out.push_back(t.a * (1 - r1) + t.b * (r1 * (1 - r2)) + t.c * (r1 * r2));
    }
  }
  return out;
}

// Max and RMS of the distances from `points` to the triangles of `tree`.
void distances(const std::vector<Vec3d>& points, const ClosestTriangles& tree, double& max, double& rms) {
  if (points.empty()) {
    max = rms = 0;
    return;
  }
  if (tree.empty()) {
    max = rms = std::numeric_limits<double>::infinity();
    return;
  }
  std::vector<double> d2(points.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), 2048), [&](const tbb::blocked_range<size_t>& r) {
    // Consecutive samples lie on one triangle or neighbours: the previous one's nearest
    // triangle is a good first guess (ClosestTriangles::nearest).
    int64_t hint = -1;
    for (size_t i = r.begin(); i < r.end(); ++i) {
      const auto [dd, id] = tree.nearest(points[i], hint);
      d2[i] = dd;
      hint = id;
    }
  });
  // Sequential reduction: the same sum whatever the thread count.
  double m = 0, sum = 0;
  for (const double d : d2) {
    m = std::max(m, d);
    sum += d;
  }
  max = std::sqrt(m);
  rms = std::sqrt(sum / static_cast<double>(d2.size()));
}

}  // namespace

TriangleSoup triangle_soup(const Mesh& m) {
  TriangleSoup s;
  s.points.assign(m.points(), m.points() + m.n_vertices());
  s.triangles.reserve(m.n_faces());
  for (auto f : m.faces()) {
    if (m.status(f).deleted()) continue;
    const auto hs = face_halfedges(m, f);
    s.triangles.push_back({static_cast<uint32_t>(m.to_vertex_handle(hs[0]).idx()), static_cast<uint32_t>(m.to_vertex_handle(hs[1]).idx()),
                           static_cast<uint32_t>(m.to_vertex_handle(hs[2]).idx())});
  }
  return s;
}

SurfaceDistance measure_surface_distance(const Mesh& a, const Mesh& b, const SurfaceDistanceOptions& options) {
  return measure_surface_distance(triangle_soup(a), triangle_soup(b), options);
}

namespace {

// Samples on the faces of each mesh besides its vertices (SurfaceDistanceOptions::samples).
size_t sample_count(const SurfaceDistanceOptions& options, size_t faces_a, size_t faces_b) {
  return options.samples ? options.samples : std::clamp<size_t>(2 * std::max(faces_a, faces_b), 100000, 4000000);
}

}  // namespace

struct SurfaceDistanceReference::Impl {
  SurfaceDistanceOptions options;
  TriangleSoup soup;  // a, to sample again for a b with more faces (the count depends on both)
  std::vector<Triangle> triangles;
  std::unique_ptr<ClosestTriangles> tree;  // over `triangles`
  size_t samples_n = 0;  // a's samples for any b with at most as many faces as a
  std::vector<Vec3d> samples;
};

SurfaceDistanceReference::SurfaceDistanceReference(const TriangleSoup& a, const SurfaceDistanceOptions& options)
    : impl_(std::make_unique<Impl>()) {
  Impl& r = *impl_;
  r.options = options;
  r.soup = a;
  r.triangles = triangles(a);
  r.samples_n = sample_count(options, a.triangles.size(), a.triangles.size());
  r.samples = sample(a, r.triangles, r.samples_n, options.seed);
  r.tree = std::make_unique<ClosestTriangles>(r.triangles);  // built now: measure() is const and may run concurrently
}

SurfaceDistanceReference::SurfaceDistanceReference(const Mesh& a, const SurfaceDistanceOptions& options)
    : SurfaceDistanceReference(triangle_soup(a), options) {}

SurfaceDistanceReference::~SurfaceDistanceReference() = default;

SurfaceDistance SurfaceDistanceReference::measure(const Mesh& b) const { return measure(triangle_soup(b)); }

SurfaceDistance SurfaceDistanceReference::measure(const TriangleSoup& b) const {
  const auto t0 = std::chrono::steady_clock::now();
  const Impl& r = *impl_;
  const size_t n = sample_count(r.options, r.soup.triangles.size(), b.triangles.size());
  std::vector<Vec3d> resampled;
  if (n != r.samples_n) resampled = sample(r.soup, r.triangles, n, r.options.seed);
  const std::vector<Vec3d>& sa = n != r.samples_n ? resampled : r.samples;
  const std::vector<Triangle> tb = triangles(b);
  const std::vector<Vec3d> sb = sample(b, tb, n, r.options.seed + 1);
  const ClosestTriangles tree_b(tb);
  SurfaceDistance d;
  distances(sa, tree_b, d.forward, d.rms_forward);
  distances(sb, *r.tree, d.backward, d.rms_backward);
  d.hausdorff = std::max(d.forward, d.backward);
  d.samples_a = sa.size();
  d.samples_b = sb.size();
  const double total = static_cast<double>(sa.size() + sb.size());
  d.rms = total > 0 ? std::sqrt((d.rms_forward * d.rms_forward * static_cast<double>(sa.size()) +
                                 d.rms_backward * d.rms_backward * static_cast<double>(sb.size())) / total)
                    : 0.0;
  d.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return d;
}

SurfaceDistance measure_surface_distance(const TriangleSoup& a, const TriangleSoup& b, const SurfaceDistanceOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  SurfaceDistance d = SurfaceDistanceReference(a, options).measure(b);
  d.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return d;
}

std::vector<double> face_distances(const Mesh& a, const Mesh& b, const SurfaceDistanceOptions& options) {
  const TriangleSoup sa = triangle_soup(a), sb = triangle_soup(b);
  const size_t n = sample_count(options, sa.triangles.size(), sb.triangles.size());
  const std::vector<Triangle> ta = triangles(sa);
  // b's triangles, the degenerate ones included (they keep distance 0), in face order.
  std::vector<Triangle> tb;
  tb.reserve(sb.triangles.size());
  for (const auto& t : sb.triangles) tb.push_back(triangle(sb, t));
  std::vector<Triangle> tb_live;
  std::vector<size_t> live_face;
  for (size_t f = 0; f < tb.size(); ++f)
    if (!tb[f].degenerate()) {
      tb_live.push_back(tb[f]);
      live_face.push_back(f);
    }
  std::vector<double> out(tb.size(), 0.0);
  if (ta.empty() || tb_live.empty()) return out;
  const ClosestTriangles tree_a(ta), tree_b(tb_live);

  // b's own samples, per face: corners, centroid, and points by area (fixed seed per face).
  double total = 0;
  for (const auto& t : tb_live) total += t.area();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, tb_live.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) {
      const Triangle& t = tb_live[i];
      Random rng{options.seed + 0x51ED2701ull * (live_face[i] + 1)};
      const size_t count = static_cast<size_t>(static_cast<double>(n) * t.area() / total + rng.uniform());
      double worst = 0;
      int64_t hint = -1;  // the previous sample's nearest (ClosestTriangles::nearest)
      auto at = [&](double wa, double wb, double wc) {
        const auto [d2, id] = tree_a.nearest(t.a * wa + t.b * wb + t.c * wc, hint);
        worst = std::max(worst, d2);
        hint = id;
      };
      at(1, 0, 0);
      at(0, 1, 0);
      at(0, 0, 1);
      at(1.0 / 3, 1.0 / 3, 1.0 / 3);
      for (size_t k = 0; k < count; ++k) {
        const double r1 = std::sqrt(rng.uniform()), r2 = rng.uniform();
        at(1 - r1, r1 * (1 - r2), r1 * r2);
      }
      out[live_face[i]] = std::sqrt(worst);
    }
  });
  // a's samples, attributed to the face of b nearest to them.
  const std::vector<Vec3d> pa = sample(sa, ta, n, options.seed);
  std::vector<std::pair<double, size_t>> nearest(pa.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, pa.size(), 2048), [&](const tbb::blocked_range<size_t>& r) {
    int64_t hint = -1;
    for (size_t i = r.begin(); i < r.end(); ++i) {
      const auto [d2, id] = tree_b.nearest(pa[i], hint);
      // id < 0 only for a sample no triangle is near (a NaN coordinate): attributed nowhere.
      nearest[i] = {std::sqrt(d2), id >= 0 ? live_face[static_cast<size_t>(id)] : SIZE_MAX};
      if (id >= 0) hint = id;
    }
  });
  for (const auto& [d, f] : nearest)  // sequential: any thread count
    if (f != SIZE_MAX) out[f] = std::max(out[f], d);
  return out;
}

}  // namespace meso
