// A small driver over build_cone_map on the maps of BM_ConeMap, for instruction counts
// (valgrind --tool=callgrind) and for checking that outputs stay byte-identical:
//   cone_time MAP SIZE RELAXED [THREADS [OUT.raw [TOLERANCE]]]
// MAP: 0 = the example's bricks, 1 = uniform noise, 2 = smooth bumps (as bench/stages_bench.cpp);
// and planar cases, where cones touch the surface along whole rays (the exact plane test and
// its tolerance concede what first-order bounds cannot settle): 3 = a ramp, 4 = a pyramid,
// 5 = terraces (steps on a gentle slope), 6 = a cone.
// RELAXED: 0 conservative, 1 relaxed, 2 relaxed with ConeMapOptions::exact_fans false.
// OUT.raw receives the cone map's float pixels as they are in memory ("-": none); TOLERANCE
// is ConeMapOptions::tolerance.
#include "meso/streams/cone_map.hpp"

#include "bench_maps.hpp"

#include <tbb/global_control.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

int main(int argc, char** argv) {
  using namespace meso;
  if (argc < 4) {
    std::fprintf(stderr, "usage: cone_time MAP SIZE RELAXED [THREADS [OUT.raw [TOLERANCE]]]\n");
    return 2;
  }
  const int kind = std::atoi(argv[1]), n = std::atoi(argv[2]);
  const bool relaxed = std::atoi(argv[3]) != 0;
  const int threads = argc > 4 ? std::atoi(argv[4]) : 1;
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(threads));
  HeightField f;
  if (kind < 3) {
    f = bench::bench_height_field(static_cast<bench::BenchMap>(kind), n);
  } else {
    Image img(n, n, 1);
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const double u = (x + 0.5) / n - 0.5, v = (y + 0.5) / n - 0.5;
        img.at(x, y) = kind == 3 ? static_cast<float>(0.3 * x / n + 0.2 * y / n)                       // a ramp
                       : kind == 4 ? static_cast<float>(1 - 2 * std::max(std::abs(u), std::abs(v)))  // a pyramid
                       : kind == 5 ? static_cast<float>(std::floor(8.0 * x / n) / 8 + 0.05 * y / n)  // terraces
                                   : static_cast<float>(1 - 2 * std::sqrt(u * u + v * v));            // a cone
      }
    f = make_height_field(img, Border::clamp);
  }
  ConeMapOptions o;
  o.kind = relaxed ? ConeKind::relaxed : ConeKind::conservative;
  o.exact_fans = std::atoi(argv[3]) != 2;
  if (argc > 6) o.tolerance = std::atof(argv[6]);
  const auto start = std::chrono::steady_clock::now();
  const Image cone = build_cone_map(f, o);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("map %d %dx%d %s: %.3f s\n", kind, n, n, relaxed ? (o.exact_fans ? "relaxed" : "relaxed, fans bound") : "conservative", seconds);
  if (argc > 5 && std::string(argv[5]) != "-") {
    std::FILE* out = std::fopen(argv[5], "wb");
    if (out == nullptr) return 3;
    std::fwrite(cone.pixels.data(), sizeof(float), cone.pixels.size(), out);
    std::fclose(out);
  }
  return 0;
}
