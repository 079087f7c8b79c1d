// The height maps of the streams benchmarks (bench/stages_bench.cpp, cone_time.cpp,
// streams.cpp), made in one place so that their figures are about the same maps.
#pragma once

#include "meso/examples/brick_wall.hpp"
#include "meso/streams/height_field.hpp"

#include <cmath>
#include <random>

namespace meso::bench {

// 0 = the example's bricks (its height function over the wall's 2 x 1 extent), 1 = uniform
// noise (seed 1), 2 = smooth bumps (4 x 3 periods; the hard case for cones, which touch the
// surface along its inflections).
enum class BenchMap { bricks = 0, noise = 1, bumps = 2 };

inline const char* bench_map_name(BenchMap m) { return m == BenchMap::bricks ? "bricks" : m == BenchMap::noise ? "noise" : "bumps"; }

// The n x n map, clamped at the borders, normalised by make_height_field.
inline HeightField bench_height_field(BenchMap kind, int n) {
  Image img(n, n, 1);
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> d(0.0f, 1.0f);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      img.at(x, y) = kind == BenchMap::bricks  ? brick_wall_height(BrickWallOptions{}, 2.0f * x / n, 1.0f * y / n)
                     : kind == BenchMap::noise ? d(rng)
                                               : static_cast<float>(std::sin(6.2831853 * 4 * x / n) * std::cos(6.2831853 * 3 * y / n));
  return make_height_field(img, Border::clamp);
}

}  // namespace meso::bench
