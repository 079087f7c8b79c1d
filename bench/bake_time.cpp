// bake_time: times meso's bake() call alone on two mesh files (the meshes read as `meso bake`
// reads them), for bench/bake_peers.sh's comparison with Blender's bake call.
//
//   bake_time LOW HIGH SIZE FRONT BACK [REPEATS]
//
// Prints one JSON object: the best and the median of REPEATS (default 3) runs of bake() at
// SIZE x SIZE with 1 sample and the default maps (displacement, tangent- and object-space
// normals, coverage and the dilation are all part of bake()), texels, the Embree queries the
// last call cast ("rays", as `meso bake --json` counts them: each intersect, occluded and
// multi-hit collect is one) and rays/s at the median time, and the median process CPU time per call (user + system, all threads, in
// seconds: on a machine shared with other jobs it moves less than the wall time, which
// waits for the cores). Threads: TBB's default (limit it with taskset, as the script does,
// or run on a machine of that size). "output_hash" is a 64-bit FNV-1a hash of the last
// call's maps (displacement, tangent- and object-space normals, coverage: their float bits)
// and counts, computed outside the timing: equal hashes say two builds bake the same bits.
// "maps_hash" is the same without the ray count: equal for two builds that cast different
// queries to the same answers.
#include "meso/bake/bake.hpp"
#include "meso/core/error.hpp"
#include "meso/formats/mesh_io.hpp"

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include <sys/resource.h>

namespace {

// User plus system CPU time of the whole process so far, in seconds.
double process_cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  auto s = [](const timeval& t) { return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec); };
  return s(u.ru_utime) + s(u.ru_stime);
}

// FNV-1a over raw bytes, 64 bits.
void fnv1a(uint64_t& h, const void* data, size_t bytes) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < bytes; ++i) {
    h ^= p[i];
    h *= 0x100000001b3ULL;
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 6) {
    std::fprintf(stderr, "usage: bake_time LOW HIGH SIZE FRONT BACK [REPEATS]\n");
    return 2;
  }
  try {
    const meso::Mesh low = meso::read_mesh(argv[1]);
    const meso::Mesh high = meso::read_mesh(argv[2]);
    meso::BakeOptions o;
    o.width = o.height = std::atoi(argv[3]);
    o.front = static_cast<float>(std::atof(argv[4]));
    o.back = static_cast<float>(std::atof(argv[5]));
    const int repeats = argc > 6 ? std::max(1, std::atoi(argv[6])) : 3;
    std::vector<double> seconds, cpu;
    size_t covered = 0, hits = 0;
    uint64_t rays = 0;
    uint64_t hash = 0xcbf29ce484222325ULL, maps_hash = 0;
    for (int i = 0; i < repeats; ++i) {
      const double c0 = process_cpu_seconds();
      const auto t0 = std::chrono::steady_clock::now();
      const meso::BakeResult r = meso::bake(low, high, o);
      seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      cpu.push_back(process_cpu_seconds() - c0);
      covered = r.covered_texels;
      hits = r.hits;
      rays = r.rays;
      if (i + 1 == repeats) {
        for (const meso::Image* m : {&r.displacement, &r.normal_ts, &r.normal_os, &r.coverage}) fnv1a(hash, m->pixels.data(), m->pixels.size() * sizeof(float));
        for (const size_t n : {r.covered_texels, r.hits, r.misses, r.ambiguous}) fnv1a(hash, &n, sizeof n);
        maps_hash = hash;
        fnv1a(hash, &r.rays, sizeof r.rays);
      }
    }
    std::sort(seconds.begin(), seconds.end());
    std::sort(cpu.begin(), cpu.end());
    std::printf("{\"size\": %d, \"low_faces\": %zu, \"high_faces\": %zu, \"covered_texels\": %zu, \"hits\": %zu, \"rays\": %llu, \"repeats\": %d, "
                "\"best_seconds\": %.4f, \"median_seconds\": %.4f, \"median_cpu_seconds\": %.4f, \"rays_per_second\": %.4g, \"output_hash\": \"%016llx\", \"maps_hash\": \"%016llx\"}\n",
                o.width, low.n_faces(), high.n_faces(), covered, hits, static_cast<unsigned long long>(rays), repeats, seconds.front(), seconds[seconds.size() / 2], cpu[cpu.size() / 2],
                static_cast<double>(rays) / seconds[seconds.size() / 2], static_cast<unsigned long long>(hash), static_cast<unsigned long long>(maps_hash));
  } catch (const meso::Error& e) {
    std::fprintf(stderr, "bake_time: %s\n", e.what());
    return static_cast<int>(e.code());
  }
  return 0;
}
