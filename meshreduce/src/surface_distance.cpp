// The surface distance: closest-point queries through an Embree BVH (rtcPointQuery), the
// distances themselves in double precision.
#include "meso/meshreduce/surface_distance.hpp"

#include "closest_triangles.hpp"
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

using reduce::ClosestTriangles;
using reduce::Triangle;
using reduce::Vec3d;
using reduce::point;

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

// The measure works on coordinates scaled by a power of two that brings a's largest
// coordinate into [0.5, 1): Embree's BVH squares distances in float, which overflows for a
// mesh near 1e30 and underflows to 0 near 1e-30. A power of two scales every double and
// float operation below exactly (sums, products, square roots, the BVH's float corners), so
// the figures are those of the unscaled computation, bit for bit, wherever that one was
// finite, and are finite now at any scale a float can hold.
struct UnitScale {
  double to_unit = 1, from_unit = 1;
  UnitScale() = default;
  explicit UnitScale(const TriangleSoup& a) {
    float largest = 0;
    for (const Vec3f& p : a.points)
      for (int j = 0; j < 3; ++j)
        if (std::isfinite(p[j])) largest = std::max(largest, std::abs(p[j]));
    if (!(largest > 0)) return;
    const int e = std::ilogb(largest) + 1;  // largest / 2^e in [0.5, 1)
    to_unit = std::ldexp(1.0, -e);
    from_unit = std::ldexp(1.0, e);
  }
  Vec3d operator()(const Vec3f& p) const { return point(p) * to_unit; }
};

Triangle triangle(const TriangleSoup& m, const std::array<uint32_t, 3>& t, const UnitScale& s) {
  return Triangle{s(m.points[t[0]]), s(m.points[t[1]]), s(m.points[t[2]])};
}

std::vector<Triangle> triangles(const TriangleSoup& m, const UnitScale& s) {
  std::vector<Triangle> out;
  out.reserve(m.triangles.size());
  for (const auto& t : m.triangles) {
    const Triangle tri = triangle(m, t, s);
    if (!tri.degenerate()) out.push_back(tri);
  }
  return out;
}

// Every point used by a non-degenerate triangle, plus `n` points spread over the triangles by
// area. (The corners of degenerate ones are left out as they are from the triangles measured
// against: a zero-area spike's tip had been a sample, 1 unit from the other mesh's surface
// even when that mesh was the same.)
std::vector<Vec3d> sample(const TriangleSoup& m, const std::vector<Triangle>& tris, size_t n, uint64_t seed, const UnitScale& s) {
  std::vector<Vec3d> out;
  std::vector<char> used(m.points.size(), 0);
  for (const auto& t : m.triangles)
    if (!triangle(m, t, s).degenerate())
      for (const uint32_t i : t) used[i] = 1;
  for (size_t i = 0; i < m.points.size(); ++i)
    if (used[i]) out.push_back(s(m.points[i]));
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
  UnitScale scale;  // a's, applied to b too
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
  r.scale = UnitScale(a);
  r.triangles = triangles(a, r.scale);
  r.samples_n = sample_count(options, a.triangles.size(), a.triangles.size());
  r.samples = sample(a, r.triangles, r.samples_n, options.seed, r.scale);
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
  if (n != r.samples_n) resampled = sample(r.soup, r.triangles, n, r.options.seed, r.scale);
  const std::vector<Vec3d>& sa = n != r.samples_n ? resampled : r.samples;
  const std::vector<Triangle> tb = triangles(b, r.scale);
  const std::vector<Vec3d> sb = sample(b, tb, n, r.options.seed + 1, r.scale);
  const ClosestTriangles tree_b(tb);
  SurfaceDistance d;
  distances(sa, tree_b, d.forward, d.rms_forward);
  distances(sb, *r.tree, d.backward, d.rms_backward);
  for (double* x : {&d.forward, &d.rms_forward, &d.backward, &d.rms_backward}) *x *= r.scale.from_unit;
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
  const UnitScale scale(sa);
  const std::vector<Triangle> ta = triangles(sa, scale);
  // b's triangles, the degenerate ones included (they keep distance 0), in face order.
  std::vector<Triangle> tb;
  tb.reserve(sb.triangles.size());
  for (const auto& t : sb.triangles) tb.push_back(triangle(sb, t, scale));
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
      out[live_face[i]] = std::sqrt(worst) * scale.from_unit;
    }
  });
  // a's samples, attributed to the face of b nearest to them.
  const std::vector<Vec3d> pa = sample(sa, ta, n, options.seed, scale);
  std::vector<std::pair<double, size_t>> nearest(pa.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, pa.size(), 2048), [&](const tbb::blocked_range<size_t>& r) {
    int64_t hint = -1;
    for (size_t i = r.begin(); i < r.end(); ++i) {
      const auto [d2, id] = tree_b.nearest(pa[i], hint);
      // id < 0 only for a sample no triangle is near (a NaN coordinate): attributed nowhere.
      nearest[i] = {std::sqrt(d2) * scale.from_unit, id >= 0 ? live_face[static_cast<size_t>(id)] : SIZE_MAX};
      if (id >= 0) hint = id;
    }
  });
  for (const auto& [d, f] : nearest)  // sequential: any thread count
    if (f != SIZE_MAX) out[f] = std::max(out[f], d);
  return out;
}

}  // namespace meso
