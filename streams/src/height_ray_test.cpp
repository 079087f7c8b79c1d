// The tracers of the streams (cone maps, min-max pyramid) against a dense reference march:
// they must find the first intersection of a ray with the filtered surface, never a later one.
#include "meso/streams/cone_map.hpp"
#include "meso/streams/pyramid.hpp"

#include "test_fields.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace meso {
namespace {

using test::bumps;
using test::field_from;
using test::noise;



// The surface at height z along the ray, minus the ray: >= 0 means at or below the surface.
double below(const HeightField& f, const HeightRay& r, double t) { return f.bilinear(r.x + t * r.dx, r.y + t * r.dy) - r.z_at(t); }

// A random ray from height 1 at elevation 0.02..1.52 rad over the map's interior.
HeightRay random_ray(const HeightField& f, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  const double elevation = 0.02 + 1.5 * u(rng);  // radians above the horizon
  const double azimuth = 6.2831853 * u(rng);
  HeightRay r;
  r.x = 2 + u(rng) * (f.height.width - 4);
  r.y = 2 + u(rng) * (f.height.height - 4);
  r.z = 1.0;
  r.dx = std::cos(azimuth) * std::cos(elevation);
  r.dy = std::sin(azimuth) * std::cos(elevation);
  r.dz = -std::sin(elevation);
  return r;
}


// A dense march (1/64 texel steps horizontally, bisection of the first sign change).
// Bent rays: until they pass below 0, or rise back above 1 past their lowest point.
bool reference_hit(const HeightField& f, const HeightRay& r, double& t_hit) {
  const double horizontal = std::hypot(r.dx, r.dy);
  // Straight: where z reaches 0. Bent: march far enough (the loop stops on leaving).
  const double t_end = r.ddz == 0 ? r.z / -r.dz : 4.0 * (f.height.width + f.height.height) / std::max(horizontal, 1e-9);
  const double dt = std::min(t_end / 64, horizontal > 0 ? (1.0 / 64) / horizontal : t_end);
  const int w = f.height.width, h = f.height.height;
  const double vertex = r.ddz > 0 ? -r.dz / (2 * r.ddz) : 1e300;
  for (double t = 0; t < t_end + dt; t += dt) {
    const double tc = std::min(t, t_end);
    if (r.z_at(tc) < 0 || (tc > vertex && r.z_at(tc) > 1)) return false;
    const double x = r.x + tc * r.dx, y = r.y + tc * r.dy;
    if (f.border == Border::clamp && (x < 0 || y < 0 || x > w || y > h)) return false;
    if (below(f, r, tc) >= 0) {
      double lo = std::max(0.0, tc - dt), hi = tc;
      for (int k = 0; k < 60; ++k) {
        const double mid = 0.5 * (lo + hi);
        (below(f, r, mid) >= 0 ? hi : lo) = mid;
      }
      t_hit = hi;
      return true;
    }
  }
  return false;
}

// Rays from above at every angle, down to grazing: the cone tracer finds the same first
// intersection as the dense march (never a later one), on the surface.
TEST(ConeTrace, FindsTheFirstIntersection) {
  for (Border border : {Border::clamp, Border::wrap}) {
    const HeightField f = border == Border::clamp ? noise(24, 20, border, 9) : bumps(16, 16, border);
    for (ConeKind kind : {ConeKind::conservative, ConeKind::relaxed}) {
      const Image cone = build_cone_map(f, {kind, 1e-4, false});
      std::mt19937 rng(17);
      int hits = 0, total_steps = 0;
      for (int k = 0; k < 400; ++k) {
        const HeightRay r = random_ray(f, rng);
        double t_ref = 0;
        const bool ref = reference_hit(f, r, t_ref);
        const HeightHit got = trace_cone_map(f, cone, kind, r);
        total_steps += got.steps;
        if (!ref) continue;
        ++hits;
        ASSERT_TRUE(got.hit) << cone_kind_name(kind) << " ray " << k << " missed";
        EXPECT_LE(got.t, t_ref + 1e-6) << cone_kind_name(kind) << " ray " << k << " skipped the first intersection";
        EXPECT_NEAR(below(f, r, got.t), 0.0, 1e-6) << cone_kind_name(kind) << " ray " << k;
        if (got.t < t_ref - 1e-3) {
          // Earlier than the march: only a grazing touch the march stepped over.
          EXPECT_GE(below(f, r, got.t), -1e-9);
        }
      }
      EXPECT_GT(hits, 200);
      EXPECT_LT(total_steps, 400 * 200) << "cone steps should skip most texels";
    }
  }
}


// The pyramid tracer on noise, a smooth map and a map whose size is not a power of two
// (coarse texels then overlap several finer ones).
TEST(PyramidTrace, FindsTheFirstIntersection) {
  for (const HeightField& f : {noise(32, 32, Border::clamp, 3), bumps(24, 40, Border::clamp), noise(13, 7, Border::clamp, 5)}) {
    const MinMaxPyramid p = build_min_max_pyramid(f);
    std::mt19937 rng(23);
    int hits = 0;
    for (int k = 0; k < 400; ++k) {
      HeightRay r = random_ray(f, rng);
      double t_ref = 0;
      const bool ref = reference_hit(f, r, t_ref);
      const HeightHit got = trace_min_max_pyramid(f, p, r);
      if (!ref) continue;
      ++hits;
      ASSERT_TRUE(got.hit) << "ray " << k << " missed";
      EXPECT_LE(got.t, t_ref + 1e-6) << "ray " << k << " skipped the first intersection";
      EXPECT_NEAR(below(f, r, got.t), 0.0, 1e-6) << "ray " << k;
    }
    EXPECT_GT(hits, 150);
  }
}

// A flat floor at exactly 0 (a constant map) is met where the ray reaches height 0, which
// rounding puts a hair above or below 0: every ray over a tiling floor hits it there, straight
// or bent (the view-dependent displacement traces such rays; a floor missed by rounding
// had become a silhouette).
TEST(PyramidTrace, FlatFloorIsAlwaysMet) {
  for (const HeightField& f : {make_height_field(Image(1, 1, 1, 0.3f), Border::wrap), make_height_field(Image(5, 3, 1, 0.7f), Border::wrap)}) {
    ASSERT_EQ(f.height.pixels[0], 0.0f);
    const MinMaxPyramid p = build_min_max_pyramid(f);
    const Image cones = build_cone_map(f, {ConeKind::conservative}), relaxed = build_cone_map(f, {ConeKind::relaxed});
    std::mt19937 rng(41);
    std::uniform_real_distribution<double> u(0, 1);
    for (int k = 0; k < 3000; ++k) {
      HeightRay r = random_ray(f, rng);
      r.x = u(rng) * f.height.width;
      r.y = u(rng) * f.height.height;
      r.ddz = k % 3 == 0 ? 0.0 : (k % 3 == 1 ? 1.0 : -1.0) * 20.0 * u(rng);  // bent both ways
      // Where it reaches height 0, if it does before rising back out of [0, 1].
      const double disc = r.dz * r.dz - 4 * r.ddz * r.z;
      if (disc < 0) continue;  // bends back up above the floor
      const double t0 = r.ddz == 0 ? -r.z / r.dz : (-r.dz - std::sqrt(disc)) / (2 * r.ddz);
      const HeightHit got = trace_min_max_pyramid(f, p, r);
      ASSERT_TRUE(got.hit) << "ray " << k << " (ddz " << r.ddz << ") missed a flat floor";
      EXPECT_NEAR(got.t, t0, 1e-9 * (1 + t0)) << "ray " << k;
      EXPECT_EQ(got.steps, 0) << "nothing to walk between the floor and the top";
      if (r.ddz != 0) continue;  // the cone tracer's rays are straight
      for (const ConeKind kind : {ConeKind::conservative, ConeKind::relaxed}) {
        const HeightHit cone = trace_cone_map(f, kind == ConeKind::conservative ? cones : relaxed, kind, r);
        ASSERT_TRUE(cone.hit) << "ray " << k << " missed a flat floor (cone tracer)";
        EXPECT_NEAR(cone.t, t0, 1e-9 * (1 + t0)) << "ray " << k;
      }
    }
  }
}

// Grazing rays over a tiling noise map, down to 0.3 degrees: the cone tracer (both kinds)
// hits wherever the exact pyramid tracer does, at the same point. A ray a rounding hair short
// of a texel edge had stalled there until max_steps, a miss (5 % of such rays).
TEST(ConeTrace, GrazingRaysDoNotStallOnTexelEdges) {
  const HeightField f = noise(16, 16, Border::wrap, 3);
  const MinMaxPyramid p = build_min_max_pyramid(f);
  for (const ConeKind kind : {ConeKind::conservative, ConeKind::relaxed}) {
    const Image cone = build_cone_map(f, {kind});
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(0, 1);
    for (int k = 0; k < 400; ++k) {
      HeightRay r;
      r.x = u(rng) * f.height.width;
      r.y = u(rng) * f.height.height;
      const double azimuth = 6.2831853 * u(rng), elevation = std::pow(10.0, -0.5 - 1.5 * u(rng));  // 0.57 to 18 degrees
      r.dx = std::cos(azimuth);
      r.dy = std::sin(azimuth);
      r.dz = -std::tan(elevation);
      const HeightHit exact = trace_min_max_pyramid(f, p, r);
      const HeightHit got = trace_cone_map(f, cone, kind, r, 1 << 20);
      ASSERT_EQ(got.hit, exact.hit) << cone_kind_name(kind) << " ray " << k << " (" << got.steps << " steps)";
      if (exact.hit) {
        EXPECT_NEAR(got.t, exact.t, 1e-6 * (1 + exact.t)) << cone_kind_name(kind) << " ray " << k;
      }
    }
  }
}

// Rays along a clamped map's edges (y = H, dy = 0: over the closed map) find the first hit,
// where the walk had stopped at once and reported one at S's minimum, past it; a ray that
// starts beyond the edge misses, as for the cone tracer; an empty map is no map.
TEST(PyramidTrace, StoppedWalksDoNotGuessAHit) {
  const HeightField f = noise(12, 8, Border::clamp, 4);
  const MinMaxPyramid p = build_min_max_pyramid(f);
  for (const double y : {8.0, 0.0, 7.999999}) {
    HeightRay r;
    r.x = 0.5;
    r.y = y;
    r.dx = 1;
    r.dz = -0.15;
    double t_ref = 0;
    const bool ref = reference_hit(f, r, t_ref);
    const HeightHit got = trace_min_max_pyramid(f, p, r);
    ASSERT_EQ(got.hit, ref) << y;
    if (got.hit) {
      EXPECT_LE(got.t, t_ref + 1e-6) << y;
      EXPECT_NEAR(below(f, r, got.t), 0.0, 1e-6) << y;
    }
  }
  HeightRay outside;  // starts beyond the clamped map's edge and enters it: a miss, as for the cone tracer
  outside.x = -3;
  outside.y = 4;
  outside.dx = 1;
  outside.dz = -0.1;
  EXPECT_FALSE(trace_min_max_pyramid(f, p, outside).hit);
  const HeightField empty = make_height_field(Image(0, 0, 1), Border::wrap);
  EXPECT_FALSE(trace_min_max_pyramid(empty, build_min_max_pyramid(empty), HeightRay{}).hit);
}

// Wrapped maps (rays crossing into neighbouring tiles) and bent rays of both signs: the
// pyramid tracer still finds the dense march's first hit, and bent-up rays that leave the
// height field miss in both.
TEST(PyramidTrace, WrapsAndBendsExactly) {
  for (const HeightField& f : {bumps(16, 16, Border::wrap), noise(12, 9, Border::wrap, 8), noise(20, 20, Border::clamp, 9)}) {
    const MinMaxPyramid p = build_min_max_pyramid(f);
    std::mt19937 rng(29);
    std::uniform_real_distribution<double> u(-1, 1);
    int hits = 0, misses = 0;
    for (int k = 0; k < 400; ++k) {
      HeightRay r = random_ray(f, rng);
      r.ddz = 0.02 * u(rng) / (1 + std::abs(r.dz));  // bends either way, some enough to leave
      double t_ref = 0;
      const bool ref = reference_hit(f, r, t_ref);
      const HeightHit got = trace_min_max_pyramid(f, p, r);
      if (!ref) {
        // The march may step over a grazing touch the exact tracer finds; it must not find
        // a crossing the march saw nothing of by more than that.
        if (got.hit) {
          EXPECT_NEAR(below(f, r, got.t), 0.0, 1e-6);
        }
        ++misses;
        continue;
      }
      ++hits;
      ASSERT_TRUE(got.hit) << "ray " << k << " missed";
      EXPECT_LE(got.t, t_ref + 1e-6) << "ray " << k << " skipped the first intersection";
      EXPECT_NEAR(below(f, r, got.t), 0.0, 1e-6) << "ray " << k;
    }
    EXPECT_GT(hits, 100);
    EXPECT_GT(misses, 0) << "some bent rays should leave the height field";
  }
}

}  // namespace
}  // namespace meso
