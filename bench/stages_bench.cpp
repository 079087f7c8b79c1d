// Google Benchmark programs for the pipeline stages on the bundled example asset.
// Run: build/release/bench/meso_bench --benchmark_counters_tabular=true
// Figures and the commands that reproduce them: docs/benchmarks.md.
#include "meso/bake/bake.hpp"
#include "meso/bake/dilate.hpp"
#include "meso/examples/brick_wall.hpp"
#include "meso/meshreduce/meshreduce.hpp"
#include "meso/streams/cone_map.hpp"
#include "meso/streams/distance_field.hpp"
#include "meso/streams/dilation_erosion.hpp"
#include "meso/streams/pyramid.hpp"
#include "meso/uvpack/uv_check.hpp"

#include "bench_maps.hpp"

#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

namespace meso {
namespace {

const Mesh& high_wall() {
  static const Mesh mesh = make_brick_wall(BrickWallOptions{});  // 262,144 triangles
  return mesh;
}

const Mesh& base_wall() {
  // The ideal base: the cylinder section itself, 64 x 32 quads (4,096 triangles).
  static const Mesh mesh = make_brick_wall_base(BrickWallOptions{}, 64, 32);
  return mesh;
}

void BM_Bake(benchmark::State& state) {
  BakeOptions o;
  o.width = o.height = static_cast<int>(state.range(0));
  size_t rays = 0;
  for (auto _ : state) {
    const BakeResult r = bake(base_wall(), high_wall(), o);
    rays += 2 * r.covered_texels;  // two rays per covered texel (outward and inward)
    benchmark::DoNotOptimize(r.displacement.pixels.data());
  }
  state.counters["rays/s"] = benchmark::Counter(static_cast<double>(rays), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Bake)->Arg(1024)->Arg(2048)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_MeshReduce(benchmark::State& state) {
  ReduceOptions o;
  o.target_faces = high_wall().n_faces() / static_cast<size_t>(state.range(0));
  for (auto _ : state) {
    const Mesh out = reduce_mesh(high_wall(), o);
    benchmark::DoNotOptimize(out.n_faces());
  }
  state.counters["input_faces"] = static_cast<double>(high_wall().n_faces());
  state.counters["output_faces"] = static_cast<double>(o.target_faces);
}
BENCHMARK(BM_MeshReduce)->Arg(10)->Arg(100)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

HeightField brick_height_field(int n) { return bench::bench_height_field(bench::BenchMap::bricks, n); }

void BM_MinMaxPyramid(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const HeightField f = brick_height_field(n);
  for (auto _ : state) {
    const MinMaxPyramid p = build_min_max_pyramid(f);
    benchmark::DoNotOptimize(p.levels.size());
  }
  state.counters["texels/s"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * n * n, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_MinMaxPyramid)->Arg(2048)->Unit(benchmark::kMillisecond)->UseRealTime();

// The bake's dilation (the maps' unwritten texels from the nearest written one) at 2048²,
// 3 channels, a quarter of the texels written (chart-like blocks of 100 x 60 with 28-texel
// gaps): its cost does not grow with the radius (arg; -1 = the whole map), since the nearest
// written texel comes from one exact distance transform, not from radius passes of a filter.
void BM_Dilate(benchmark::State& state) {
  const int n = 2048, radius = static_cast<int>(state.range(0));
  Image image(n, n, 3, 0.0f);
  std::vector<uint8_t> written(static_cast<size_t>(n) * n, 0);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      if (x % 128 < 100 && y % 128 < 60) {
        written[static_cast<size_t>(y) * n + static_cast<size_t>(x)] = 1;
        for (int c = 0; c < 3; ++c) image.at(x, y, c) = static_cast<float>(x + y + c);
      }
  for (auto _ : state) {
    state.PauseTiming();
    Image im = image;
    std::vector<uint8_t> w = written;
    state.ResumeTiming();
    dilate(im, w, radius);
    benchmark::DoNotOptimize(im.pixels.data());
  }
}
BENCHMARK(BM_Dilate)->Arg(2)->Arg(16)->Arg(128)->Arg(-1)->Unit(benchmark::kMillisecond)->UseRealTime();

// Dilation/erosion maps: the footprint min-max of level 0 plus the running min/max, whose
// cost does not depend on the radius (args: size, radius).
void BM_DilationErosion(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const HeightField f = brick_height_field(n);
  for (auto _ : state) {
    const Image m = dilation_erosion_map(f, static_cast<int>(state.range(1)));
    benchmark::DoNotOptimize(m.pixels.data());
  }
  state.counters["texels/s"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * n * n, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_DilationErosion)->Args({2048, 0})->Args({2048, 4})->Args({2048, 64})->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_DistanceField(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const HeightField f = brick_height_field(n);
  DistanceFieldOptions o;
  o.depth = 32;
  for (auto _ : state) {
    const DistanceField df = build_distance_field(f, o);
    benchmark::DoNotOptimize(df.distance.data());
  }
  state.counters["voxels/s"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * n * n * o.depth, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_DistanceField)->Arg(256)->Arg(1024)->Unit(benchmark::kMillisecond)->UseRealTime();

// Height maps for the cone benchmarks (bench_maps.hpp): 0 = bricks, 1 = noise, 2 = bumps.
HeightField cone_input(int kind, int n) { return bench::bench_height_field(static_cast<bench::BenchMap>(kind), n); }

void BM_ConeMap(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const HeightField f = cone_input(static_cast<int>(state.range(1)), n);
  ConeMapOptions o;
  o.kind = state.range(2) != 0 ? ConeKind::relaxed : ConeKind::conservative;
  for (auto _ : state) {
    const Image cone = build_cone_map(f, o);
    benchmark::DoNotOptimize(cone.pixels.data());
  }
  state.counters["texels/s"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * n * n, benchmark::Counter::kIsRate);
}
// Args: size, map (0 bricks, 1 noise, 2 bumps), relaxed.
BENCHMARK(BM_ConeMap)
    ->Args({256, 0, 0})->Args({256, 1, 0})->Args({256, 2, 0})
    ->Args({256, 0, 1})->Args({256, 1, 1})->Args({256, 2, 1})
    ->Args({1024, 0, 0})->Args({1024, 1, 0})->Args({1024, 0, 1})->Args({1024, 1, 1})
    ->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

// The brute force of the literature's definition, for scale: every texel against every
// texel centre (not even the filtered surface between them), one core.
void BM_ConeMapBruteForce(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const HeightField f = cone_input(static_cast<int>(state.range(1)), n);
  const auto& h = f.height.pixels;
  std::vector<float> ratio(h.size());
  for (auto _ : state) {
    for (int p = 0; p < n * n; ++p) {
      double best = 1e30;
      for (int q = 0; q < n * n; ++q) {
        const double dh = h[static_cast<size_t>(q)] - h[static_cast<size_t>(p)];
        if (dh <= 0) continue;
        const double dx = q % n - p % n, dy = q / n - p / n;
        best = std::min(best, std::sqrt(dx * dx + dy * dy) / dh);
      }
      ratio[static_cast<size_t>(p)] = static_cast<float>(best);
    }
    benchmark::DoNotOptimize(ratio.data());
  }
  state.counters["texels/s"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * n * n, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_ConeMapBruteForce)->Args({128, 0})->Args({256, 0})->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

void BM_UvCheck(benchmark::State& state) {
  UvCheckOptions o;
  o.size = static_cast<int>(state.range(0));
  for (auto _ : state) {
    const UvCheckReport r = check_uv_mapping(high_wall(), o);
    benchmark::DoNotOptimize(r.texels_touched);
  }
}
BENCHMARK(BM_UvCheck)->Arg(2048)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace meso

BENCHMARK_MAIN();
