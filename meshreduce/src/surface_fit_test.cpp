#include "surface_fit.hpp"

#include "meso/examples/parametric.hpp"
#include "meso/meshreduce/meshreduce.hpp"
#include "meso/meshreduce/surface_distance.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace meso {
namespace {


Vec3f face_normal_of(const Mesh& m, FaceHandle f) {
  const auto hs = face_halfedges(m, f);
  const Vec3f a = m.point(m.to_vertex_handle(hs[0]));
  return OpenMesh::cross(m.point(m.to_vertex_handle(hs[1])) - a, m.point(m.to_vertex_handle(hs[2])) - a);
}

// Quadric placement leaves a coarse torus off the surface; the fit brings it closer both
// ways (RMS and Hausdorff), moves no fixed vertex, turns no face by 90 degrees, and gives the
// same bits on one thread as on all.
TEST(SurfaceFit, BringsACoarseTorusCloserAndKeepsTheFixedVertices) {
  const Mesh high = make_smooth_torus(128, 64);
  ReduceOptions o;
  o.target_faces = 400;
  const Mesh low = reduce_mesh(high, o);
  std::vector<uint8_t> fixed(low.n_vertices(), 0);
  for (size_t i = 0; i < fixed.size(); i += 17) fixed[i] = 1;
  const reduce::SurfaceFitTarget target(high);
  Mesh fitted = low;
  const reduce::SurfaceFitReport rep = reduce::fit_to_surface(fitted, target, fixed);
  EXPECT_EQ(rep.iterations, reduce::SurfaceFitOptions{}.iterations);
  EXPECT_EQ(rep.free_vertices, fixed.size() - (fixed.size() + 16) / 17);

  const SurfaceDistance before = measure_surface_distance(high, low), after = measure_surface_distance(high, fitted);
  // (Measured: Hausdorff 0.79x, RMS 0.95x: the reweighting toward L5 trades RMS for the largest distances.)
  EXPECT_LT(after.hausdorff, 0.85 * before.hausdorff) << before.hausdorff << " -> " << after.hausdorff;
  EXPECT_LT(after.rms, before.rms) << before.rms << " -> " << after.rms;
  size_t moved = 0;
  for (auto v : low.vertices()) {
    const bool same = std::memcmp(&low.point(v), &fitted.point(v), sizeof(Vec3f)) == 0;
    if (fixed[static_cast<size_t>(v.idx())]) {
      EXPECT_TRUE(same) << "fixed vertex " << v.idx() << " moved";
    }
    moved += !same;
  }
  EXPECT_GT(moved, rep.free_vertices / 2);
  for (auto f : low.faces()) EXPECT_GT(OpenMesh::dot(face_normal_of(low, f), face_normal_of(fitted, f)), 0.0f) << "face " << f.idx();
  // Connectivity and UVs untouched.
  ASSERT_EQ(fitted.n_faces(), low.n_faces());
  for (auto f : low.faces()) {
    const auto a = face_halfedges(low, f), b = face_halfedges(fitted, f);
    for (size_t k = 0; k < 3; ++k) {
      EXPECT_EQ(low.to_vertex_handle(a[k]), fitted.to_vertex_handle(b[k]));
      EXPECT_EQ(low.texcoord2D(a[k]), fitted.texcoord2D(b[k]));
    }
  }

  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  Mesh again = low;
  reduce::fit_to_surface(again, target, fixed);
  EXPECT_EQ(std::memcmp(again.points(), fitted.points(), fitted.n_vertices() * sizeof(Vec3f)), 0);
}

// Seam vertices are free in best's fit (meshreduce.cpp, fit_fixed_vertices): each corner
// keeps its UV, so the seams neither tear nor fold, and the seamed torus comes closer than
// with its seam vertices held (the bench's torus at 1 %: 1.21x -> 0.94x the best peer's
// Hausdorff distance; docs/benchmarks.md).
TEST(SurfaceFit, FreeSeamVerticesKeepTheirUvsAndBringTheSeamsCloser) {
  const Mesh high = make_smooth_torus(256, 128);
  ReduceOptions o;
  o.target_faces = 400;
  const Mesh low = reduce_mesh(high, o);
  const std::vector<uint8_t> seam = uv_seam_vertices(low);
  ASSERT_GT(std::count(seam.begin(), seam.end(), 1), 20) << "the torus has seams along both wrap lines";
  const reduce::SurfaceFitTarget target(high);
  Mesh held = low, free = low;
  reduce::fit_to_surface(held, target, seam);
  reduce::fit_to_surface(free, target, std::vector<uint8_t>(low.n_vertices(), 0));
  const double h_held = measure_surface_distance(high, held).hausdorff, h_free = measure_surface_distance(high, free).hausdorff;
  // (Measured with 10 solves: 0.0309 -> 0.0216. The gain is not universal: over 60-2000
  // faces on this torus and one half as fine, free seams were nearer in 6 of 12 cases (by
  // 7-30 %), equal within 0.3 % in 4, and further in 2 (by 1.6 % and 3 %); best keeps the
  // nearest of its candidates, fitted or not.)
  EXPECT_LT(h_free, 0.85 * h_held) << "seams held " << h_held << ", free " << h_free;
  size_t seam_moved = 0;
  for (auto v : low.vertices())
    seam_moved += seam[static_cast<size_t>(v.idx())] && std::memcmp(&low.point(v), &free.point(v), sizeof(Vec3f)) != 0;
  EXPECT_GT(seam_moved, 0u);
  // Every corner keeps its UV (both sides of each seam), and seam edges stay seams.
  for (auto h : low.halfedges()) EXPECT_EQ(low.texcoord2D(h), free.texcoord2D(h)) << "halfedge " << h.idx();
  for (auto e : low.edges()) EXPECT_EQ(is_uv_seam(low, e), is_uv_seam(free, e));
  for (auto f : low.faces()) EXPECT_GT(OpenMesh::dot(face_normal_of(low, f), face_normal_of(free, f)), 0.0f) << "face " << f.idx();
}

// With every vertex fixed there is nothing to solve: the mesh comes back unchanged.
TEST(SurfaceFit, AllFixedMovesNothing) {
  const Mesh high = make_smooth_torus(32, 16);
  ReduceOptions o;
  o.target_faces = 100;
  const Mesh low = reduce_mesh(high, o);
  Mesh fitted = low;
  const reduce::SurfaceFitReport rep =
      reduce::fit_to_surface(fitted, reduce::SurfaceFitTarget(high), std::vector<uint8_t>(low.n_vertices(), 1));
  EXPECT_EQ(rep.iterations, 0);
  EXPECT_EQ(rep.free_vertices, 0u);
  EXPECT_EQ(std::memcmp(low.points(), fitted.points(), low.n_vertices() * sizeof(Vec3f)), 0);
  EXPECT_THROW(reduce::fit_to_surface(fitted, reduce::SurfaceFitTarget(high), std::vector<uint8_t>(3, 0)), std::invalid_argument);
}

}  // namespace
}  // namespace meso
