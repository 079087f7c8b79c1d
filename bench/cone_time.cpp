// A small driver over build_cone_map on the maps of BM_ConeMap, for instruction counts
// (valgrind --tool=callgrind) and for checking that outputs stay byte-identical:
//   cone_time MAP SIZE RELAXED [THREADS [OUT.raw]]
// MAP: 0 = the example's bricks, 1 = uniform noise, 2 = smooth bumps (as bench/stages_bench.cpp).
// OUT.raw receives the cone map's float pixels as they are in memory.
#include "meso/examples/brick_wall.hpp"
#include "meso/streams/cone_map.hpp"

#include <tbb/global_control.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>

int main(int argc, char** argv) {
  using namespace meso;
  if (argc < 4) {
    std::fprintf(stderr, "usage: cone_time MAP SIZE RELAXED [THREADS [OUT.raw]]\n");
    return 2;
  }
  const int kind = std::atoi(argv[1]), n = std::atoi(argv[2]);
  const bool relaxed = std::atoi(argv[3]) != 0;
  const int threads = argc > 4 ? std::atoi(argv[4]) : 1;
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(threads));
  Image img(n, n, 1);
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> d(0.0f, 1.0f);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      img.at(x, y) = kind == 0   ? brick_wall_height(BrickWallOptions{}, 2.0f * x / n, 1.0f * y / n)
                     : kind == 1 ? d(rng)
                                 : static_cast<float>(std::sin(6.2831853 * 4 * x / n) * std::cos(6.2831853 * 3 * y / n));
  const HeightField f = make_height_field(img, Border::clamp);
  ConeMapOptions o;
  o.kind = relaxed ? ConeKind::relaxed : ConeKind::conservative;
  const auto start = std::chrono::steady_clock::now();
  const Image cone = build_cone_map(f, o);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("map %d %dx%d %s: %.3f s\n", kind, n, n, relaxed ? "relaxed" : "conservative", seconds);
  if (argc > 5) {
    std::FILE* out = std::fopen(argv[5], "wb");
    if (out == nullptr) return 3;
    std::fwrite(cone.pixels.data(), sizeof(float), cone.pixels.size(), out);
    std::fclose(out);
  }
  return 0;
}
