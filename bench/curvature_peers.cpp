// meso's per-vertex curvature fit (meso::fit_curvature, bake/curvature.hpp) against a peer,
// CGAL's Monge_via_jet_fitting (Cazals & Pouget), on surfaces whose curvatures are known in
// closed form: open circular cylinders, UV spheres with their poles (regular, and with the
// non-pole vertices moved along the sphere into irregular cells), and tori.
//
// Per surface and method one Markdown row: the largest and the mean |error| of k1 and k2
// over the interior vertices that have a fit (boundary vertices have one-sided
// neighbourhoods and are skipped), in units of the largest true |k| on the surface (1/r of
// the cylinder, the sphere, the torus's tube); the interior vertices without a fit; and the
// wall time of the whole mesh's fit (every vertex, boundary ones too), best of several runs.
// meso is timed with TBB's default parallelism and with one thread; CGAL runs on one thread.
//
// Conventions: curvatures in 1/object units, k1 >= k2, positive where the surface bends
// away from the vertex normal (meso's; a sphere with outward normals has +1/r). The truth is
// signed by each vertex's own normal against the surface's outward direction, whichever way
// make_parametric_surface's winding faces a surface.
//
// The peer, per vertex: the vertex itself first (CGAL computes the Monge form at the fitted
// surface's point over the first input point) and its k-ring, fitted by a jet of degree
// d_fit and reduced to a Monge form of degree d_monge, in two configurations: (a) 2 / 2 on
// the 2-ring, (b) 4 / 2 on the 3-ring. A ring with fewer than (d_fit + 1)(d_fit + 2) / 2
// points grows by one (up to the 4-ring); past that, or when the fit is not finite, the
// vertex has no fit.
//
// Run: build/release/bench/curvature_peers [--quick]   (--quick: one timing run per row)
#include "meso/bake/curvature.hpp"
#include "meso/core/mesh.hpp"
#include "meso/examples/brick_wall.hpp"
#include "meso/examples/parametric.hpp"

#include <CGAL/Monge_via_jet_fitting.h>
#include <CGAL/Simple_cartesian.h>
#include <tbb/global_control.h>
#include <tbb/info.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <functional>
#include <string>
#include <utility>
#include <vector>

using namespace meso;

namespace {

constexpr double kPi = 3.14159265358979323846;

// ---- Surfaces with known curvatures ---------------------------------------------------------

struct Surface {
  std::string name;
  Mesh mesh;
  // The principal curvatures at a point of the surface, k1 >= k2, for outward normals.
  std::function<std::pair<double, double>(const Vec3f&)> curvatures;
  // The outward unit direction at a point (to sign the truth by each vertex normal).
  std::function<Vec3f(const Vec3f&)> outward;
  double k_scale;  // the largest true |k| on the surface: errors are given in its units
};

// An open cylinder about z: `segments` around, 6 rows along 3 units. Counter-clockwise in
// (s, t) faces outward here.
Surface cylinder(int segments) {
  const double r = 0.7;
  Surface s;
  s.name = "cylinder " + std::to_string(segments) + " seg, r 0.7";
  s.mesh = make_parametric_surface(segments, 6, [&](double u, double t) {
    const double ph = 2 * kPi * u;
    return Vec3f(float(r * std::cos(ph)), float(r * std::sin(ph)), float(3.0 * t));
  }, true, false);
  s.curvatures = [r](const Vec3f&) { return std::pair{1 / r, 0.0}; };
  s.outward = [](const Vec3f& p) { return Vec3f(p[0], p[1], 0).normalized(); };
  s.k_scale = 1 / r;
  return s;
}

Vec3f on_sphere(double r, double th, double ph) {
  return Vec3f(float(r * std::sin(th) * std::cos(ph)), float(r * std::sin(th) * std::sin(ph)), float(-r * std::cos(th)));
}

// A UV sphere of radius 2, columns x rows, with its poles. `moved`: every vertex but the
// poles moved along the sphere by a pseudo-random offset of up to +-0.2 cell in both angles
// (irregular cells, as a reduced mesh has; the same offsets on every run), normals recomputed.
Surface uv_sphere(int columns, int rows, bool moved) {
  const double r = 2.0;
  Surface s;
  s.name = "UV sphere " + std::to_string(columns) + "x" + std::to_string(rows) + (moved ? " moved" : "") + ", r 2";
  s.mesh = make_surface_with_poles(columns, rows, [&](double th, double ph) { return on_sphere(r, th, ph); });
  if (moved) {
    uint64_t seed = 12345u + static_cast<uint64_t>(columns);
    auto jitter = [&] {  // uniform in [-0.2, 0.2) (a 64-bit LCG's top 53 bits)
      seed = seed * 6364136223846793005ull + 1442695040888963407ull;
      return (static_cast<double>(seed >> 11) / static_cast<double>(1ull << 53) - 0.5) * 0.4;
    };
    const int last = static_cast<int>(s.mesh.n_vertices()) - 1;
    for (auto v : s.mesh.vertices()) {
      if (v.idx() == 0 || v.idx() == last) continue;  // the poles
      const Vec3f p = s.mesh.point(v);
      const double th = std::acos(std::clamp(-p[2] / r, -1.0, 1.0)) + jitter() * kPi / rows;
      const double ph = std::atan2(p[1], p[0]) + jitter() * 2 * kPi / columns;
      s.mesh.set_point(v, on_sphere(r, th, ph));
    }
    compute_angle_weighted_normals(s.mesh);
  }
  s.curvatures = [r](const Vec3f&) { return std::pair{1 / r, 1 / r}; };
  s.outward = [](const Vec3f& p) { return p.normalized(); };
  s.k_scale = 1 / r;
  return s;
}

// A torus about z, tube radius r around a circle of radius R, wrapped both ways. Across the
// tube k = 1/r, along the ring cos(v) / (R + r cos v), v the tube angle (0 on the outer
// equator).
Surface torus(int columns, int rows) {
  const double R = 3.0, r = 1.0;
  Surface s;
  s.name = "torus " + std::to_string(columns) + "x" + std::to_string(rows) + ", R 3 r 1";
  s.mesh = make_parametric_surface(columns, rows, [&](double a, double b) {
    const double u = 2 * kPi * a, v = 2 * kPi * b, w = R + r * std::cos(v);
    return Vec3f(float(w * std::cos(u)), float(w * std::sin(u)), float(r * std::sin(v)));
  }, true, true);
  s.curvatures = [R, r](const Vec3f& p) {
    const double v = std::atan2(double(p[2]), std::hypot(double(p[0]), double(p[1])) - R);
    const double tube = 1 / r, ring = std::cos(v) / (R + r * std::cos(v));
    return std::pair{std::max(tube, ring), std::min(tube, ring)};
  };
  s.outward = [R](const Vec3f& p) {
    const float rho = std::hypot(p[0], p[1]);
    return (p - Vec3f(p[0], p[1], 0) * static_cast<float>(R / rho)).normalized();
  };
  s.k_scale = 1 / r;
  return s;
}

// ---- The peer: CGAL's jet fitting ------------------------------------------------------------

using Kernel = CGAL::Simple_cartesian<double>;
using Jet = CGAL::Monge_via_jet_fitting<Kernel>;

struct JetConfig {
  const char* name;
  int d_fit, d_monge, rings;
};

// k1 >= k2 per vertex in meso's convention, and whether it has a fit (meso: rings > 0).
struct Fit {
  std::vector<double> k1, k2;
  std::vector<uint8_t> fitted;
};

Fit cgal_fit(const Mesh& mesh, const JetConfig& config) {
  const size_t n = mesh.n_vertices();
  Fit out{std::vector<double>(n, 0), std::vector<double>(n, 0), std::vector<uint8_t>(n, 0)};
  const size_t needed = static_cast<size_t>((config.d_fit + 1) * (config.d_fit + 2) / 2);
  // Breadth-first rings; `seen` holds the last centre vertex that reached each vertex, so it
  // needs no clearing between vertices.
  std::vector<int> seen(n, -1);
  std::vector<VertexHandle> ring;
  std::vector<Kernel::Point_3> points;
  Jet jet;
  for (auto v : mesh.vertices()) {
    ring.assign(1, v);
    seen[static_cast<size_t>(v.idx())] = v.idx();
    size_t layer_begin = 0;
    for (int k = 1; k <= 4 && (k <= config.rings || ring.size() < needed); ++k) {
      const size_t layer_end = ring.size();
      for (size_t i = layer_begin; i < layer_end; ++i)
        for (auto w : mesh.vv_range(ring[i]))
          if (seen[static_cast<size_t>(w.idx())] != v.idx()) {
            seen[static_cast<size_t>(w.idx())] = v.idx();
            ring.push_back(w);
          }
      layer_begin = layer_end;
    }
    if (ring.size() < needed) continue;  // below CGAL's precondition even on the 4-ring
    points.clear();
    for (auto w : ring) {  // the vertex itself first: the Monge form is computed over it
      const Vec3f p = mesh.point(w);
      points.emplace_back(p[0], p[1], p[2]);
    }
    Jet::Monge_form monge = jet(points.begin(), points.end(), static_cast<size_t>(config.d_fit), static_cast<size_t>(config.d_monge));
    // The Monge normal's orientation comes from a PCA of the points: turn it to the vertex
    // normal (which swaps and negates the coefficients when it flips). CGAL's curvatures are
    // then the eigenvalues of I^-1 II for the graph z = f(x, y) along that normal: positive
    // where the surface bends towards it (a sphere with outward normals: -1/r), the opposite
    // of meso's, so meso's k1 is CGAL's -k_min and meso's k2 CGAL's -k_max.
    const Vec3f nv = mesh.normal(v);
    monge.comply_wrt_given_normal(Kernel::Vector_3(nv[0], nv[1], nv[2]));
    const double k1 = -monge.principal_curvatures(1), k2 = -monge.principal_curvatures(0);
    if (!std::isfinite(k1) || !std::isfinite(k2)) continue;
    const size_t i = static_cast<size_t>(v.idx());
    out.k1[i] = k1;
    out.k2[i] = k2;
    out.fitted[i] = 1;
  }
  return out;
}

Fit from_meso(const std::vector<VertexCurvature>& c) {
  Fit out;
  for (const auto& k : c) {
    out.k1.push_back(k.k1);
    out.k2.push_back(k.k2);
    out.fitted.push_back(k.rings > 0);
  }
  return out;
}

// ---- Measuring ------------------------------------------------------------------------------

struct Errors {
  double max = 0, mean = 0;  // over k1 and k2 of the fitted interior vertices, in k_scale units
  size_t interior = 0, unfitted = 0;
};

Errors measure(const Surface& s, const Fit& fit) {
  Errors e;
  double sum = 0;
  size_t terms = 0;
  for (auto v : s.mesh.vertices()) {
    if (s.mesh.is_boundary(v)) continue;
    ++e.interior;
    const size_t i = static_cast<size_t>(v.idx());
    if (!fit.fitted[i]) {
      ++e.unfitted;
      continue;
    }
    const Vec3f p = s.mesh.point(v);
    auto [t1, t2] = s.curvatures(p);
    if (OpenMesh::dot(s.mesh.normal(v), s.outward(p)) < 0) std::tie(t1, t2) = std::pair{-t2, -t1};  // an inward normal
    for (const double err : {std::abs(fit.k1[i] - t1), std::abs(fit.k2[i] - t2)}) {
      e.max = std::max(e.max, err / s.k_scale);
      sum += err / s.k_scale;
      ++terms;
    }
  }
  e.mean = terms > 0 ? sum / static_cast<double>(terms) : 0;
  return e;
}

// Runs `fit` once for its result, then again until 3 runs and 0.2 s (at most 50 runs;
// `quick`: the one run), and returns the result with the best wall time in seconds.
template <typename F>
auto timed(F fit, bool quick) {
  using clock = std::chrono::steady_clock;
  auto start = clock::now();
  auto result = fit();
  double best = std::chrono::duration<double>(clock::now() - start).count(), total = best;
  for (int run = 1; !quick && run < 50 && (run < 3 || total < 0.2); ++run) {
    start = clock::now();
    const auto again = fit();
    const double t = std::chrono::duration<double>(clock::now() - start).count();
    best = std::min(best, t);
    total += t;
  }
  return std::pair{std::move(result), best};
}

void row(const Surface& s, const std::string& method, const Errors& e, double seconds) {
  std::printf("| %s | %zu | %zu | %s | %.2e | %.2e | %zu | %.3f |\n", s.name.c_str(), s.mesh.n_vertices(), e.interior, method.c_str(), e.max, e.mean,
              e.unfitted, seconds * 1e3);
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--quick") == 0) {
      quick = true;
    } else {
      std::fprintf(stderr, "usage: curvature_peers [--quick]\n");
      return 2;
    }
  }

  std::vector<Surface> surfaces;
  for (int segments : {8, 12, 16, 32, 64}) surfaces.push_back(cylinder(segments));
  for (bool moved : {false, true})
    for (int columns : {8, 12, 16, 32, 64}) surfaces.push_back(uv_sphere(columns, columns / 2, moved));
  for (const auto& [columns, rows] : {std::pair{24, 12}, std::pair{48, 24}, std::pair{96, 48}, std::pair{160, 64}})
    surfaces.push_back(torus(columns, rows));

  const JetConfig configs[] = {{"CGAL jet 2/2, 2-ring", 2, 2, 2}, {"CGAL jet 4/2, 3-ring", 4, 2, 3}};
  const int threads = tbb::info::default_concurrency();
  const std::string meso_all = "meso, " + std::to_string(threads) + " threads", meso_one = "meso, 1 thread";

  fit_curvature(surfaces.front().mesh);  // start TBB's workers outside the timings
  std::printf("| surface | vertices | interior | method | max err / k_max | mean err / k_max | no fit | time (ms) |\n");
  std::printf("|---|---:|---:|---|---:|---:|---:|---:|\n");
  for (const Surface& s : surfaces) {
    const auto [all, all_seconds] = timed([&] { return fit_curvature(s.mesh); }, quick);
    std::vector<VertexCurvature> one;
    double one_seconds = 0;
    {
      tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
      std::tie(one, one_seconds) = timed([&] { return fit_curvature(s.mesh); }, quick);
    }
    // The fit promises the same result whatever the threads; say so if it is not.
    if (one.size() != all.size() || std::memcmp(one.data(), all.data(), all.size() * sizeof(VertexCurvature)) != 0)
      std::fprintf(stderr, "curvature_peers: %s: meso's fit differs between 1 and %d threads\n", s.name.c_str(), threads);
    const Errors meso_errors = measure(s, from_meso(all));
    row(s, meso_all, meso_errors, all_seconds);
    row(s, meso_one, meso_errors, one_seconds);
    for (const JetConfig& config : configs) {
      const auto [fit, seconds] = timed([&] { return cgal_fit(s.mesh, config); }, quick);
      row(s, config.name, measure(s, fit), seconds);
    }
  }

  // meso's fit alone on two large meshes: the brick wall (creases everywhere, where the
  // implicit terms are tried and refused) and a fine sphere (where the quadric fits).
  std::printf("\n| mesh | vertices | meso, 1 thread (s) | meso, %d threads (s) |\n|---|---:|---:|---:|\n", threads);
  const std::pair<const char*, Mesh> large[] = {
      {"brick wall (make_brick_wall defaults)", make_brick_wall(BrickWallOptions{})},
      {"UV sphere 512 x 256, no poles", make_parametric_surface(512, 256, [](double u, double t) {
         return on_sphere(1.0, kPi * (0.02 + 0.96 * t), 2 * kPi * u);
       }, true, false)}};
  for (const auto& [name, mesh] : large) {
    const double all_seconds = timed([&] { return fit_curvature(mesh); }, quick).second;
    double one_seconds = 0;
    {
      tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
      one_seconds = timed([&] { return fit_curvature(mesh); }, quick).second;
    }
    std::printf("| %s | %zu | %.3f | %.3f |\n", name, mesh.n_vertices(), one_seconds, all_seconds);
  }
  return 0;
}
