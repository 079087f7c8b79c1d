// bake_time: times meso's bake() call alone on two mesh files (the meshes read as `meso bake`
// reads them), for bench/bake_peers.sh's comparison with Blender's bake call.
//
//   bake_time LOW HIGH SIZE FRONT BACK [REPEATS [single|compare]]
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
// queries to the same answers. `single` times the bake with each texel's rays cast on their
// own (BakeOptions::coherent = false; the default casts neighbouring texels' rays as Embree
// ray streams); `compare` also bakes once that way after the timed runs and prints, under
// "single", how far its maps lie from the last timed call's: texels that differ, the largest
// displacement difference (object units), the largest angle between the normals (degrees,
// tangent and object space) and the largest difference of a normal's component, and its
// maps_hash.
#include "meso/bake/bake.hpp"
#include "meso/core/error.hpp"
#include "meso/formats/mesh_io.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <string>
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
    const std::string mode = argc > 7 ? argv[7] : "";
    if (mode == "single") o.coherent = false;
    meso::BakeResult last;
    std::vector<double> seconds, cpu;
    size_t covered = 0, hits = 0;
    uint64_t rays = 0;
    uint64_t hash = 0xcbf29ce484222325ULL, maps_hash = 0;
    auto maps_hash_of = [](const meso::BakeResult& r) {
      uint64_t h = 0xcbf29ce484222325ULL;
      for (const meso::Image* m : {&r.displacement, &r.normal_ts, &r.normal_os, &r.coverage}) fnv1a(h, m->pixels.data(), m->pixels.size() * sizeof(float));
      for (const size_t n : {r.covered_texels, r.hits, r.misses, r.ambiguous}) fnv1a(h, &n, sizeof n);
      return h;
    };
    for (int i = 0; i < repeats; ++i) {
      const double c0 = process_cpu_seconds();
      const auto t0 = std::chrono::steady_clock::now();
      meso::BakeResult r = meso::bake(low, high, o);
      seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      cpu.push_back(process_cpu_seconds() - c0);
      covered = r.covered_texels;
      hits = r.hits;
      rays = r.rays;
      if (i + 1 == repeats) {
        hash = maps_hash = maps_hash_of(r);
        fnv1a(hash, &r.rays, sizeof r.rays);
        last = std::move(r);
      }
    }
    std::string single;
    if (mode == "compare") {
      meso::BakeOptions s = o;
      s.coherent = false;
      const meso::BakeResult r = meso::bake(low, high, s);
      size_t differ = 0;
      double disp = 0, ts = 0, os = 0, tsc = 0, osc = 0;
      auto angle = [](const float* a, const float* b) {
        double dot = 0, na = 0, nb = 0;
        for (int c = 0; c < 3; ++c) dot += double(a[c]) * b[c], na += double(a[c]) * a[c], nb += double(b[c]) * b[c];
        return std::acos(std::clamp(dot / std::sqrt(na * nb), -1.0, 1.0)) * 180.0 / M_PI;
      };
      for (size_t t = 0; t < r.displacement.texel_count(); ++t) {
        const bool d = std::memcmp(&r.displacement.pixels[t], &last.displacement.pixels[t], sizeof(float)) != 0 ||
                       std::memcmp(&r.normal_ts.pixels[3 * t], &last.normal_ts.pixels[3 * t], 3 * sizeof(float)) != 0 ||
                       std::memcmp(&r.normal_os.pixels[3 * t], &last.normal_os.pixels[3 * t], 3 * sizeof(float)) != 0 ||
                       r.coverage.pixels[t] != last.coverage.pixels[t];
        differ += d;
        if (!d) continue;
        disp = std::max(disp, std::abs(double(r.displacement.pixels[t]) - last.displacement.pixels[t]));
        ts = std::max(ts, angle(&r.normal_ts.pixels[3 * t], &last.normal_ts.pixels[3 * t]));
        for (int c = 0; c < 3; ++c) {
          tsc = std::max(tsc, std::abs(double(r.normal_ts.pixels[3 * t + c]) - last.normal_ts.pixels[3 * t + c]));
          osc = std::max(osc, std::abs(double(r.normal_os.pixels[3 * t + c]) - last.normal_os.pixels[3 * t + c]));
        }
        os = std::max(os, angle(&r.normal_os.pixels[3 * t], &last.normal_os.pixels[3 * t]));
      }
      char buf[512];
      std::snprintf(buf, sizeof buf,
                    ", \"single\": {\"texels_differing\": %zu, \"max_displacement_difference\": %.6g, \"max_normal_ts_degrees\": %.6g, "
                    "\"max_normal_os_degrees\": %.6g, \"max_normal_ts_component_difference\": %.6g, \"max_normal_os_component_difference\": %.6g, \"rays\": %llu, \"maps_hash\": \"%016llx\"}",
                    differ, disp, ts, os, tsc, osc, static_cast<unsigned long long>(r.rays), static_cast<unsigned long long>(maps_hash_of(r)));
      single = buf;
    }
    std::sort(seconds.begin(), seconds.end());
    std::sort(cpu.begin(), cpu.end());
    std::printf("{\"size\": %d, \"low_faces\": %zu, \"high_faces\": %zu, \"covered_texels\": %zu, \"hits\": %zu, \"rays\": %llu, \"repeats\": %d, "
                "\"best_seconds\": %.4f, \"median_seconds\": %.4f, \"median_cpu_seconds\": %.4f, \"rays_per_second\": %.4g, \"output_hash\": \"%016llx\", \"maps_hash\": \"%016llx\"%s}\n",
                o.width, low.n_faces(), high.n_faces(), covered, hits, static_cast<unsigned long long>(rays), repeats, seconds.front(), seconds[seconds.size() / 2], cpu[cpu.size() / 2],
                static_cast<double>(rays) / seconds[seconds.size() / 2], static_cast<unsigned long long>(hash), static_cast<unsigned long long>(maps_hash), single.c_str());
  } catch (const meso::Error& e) {
    std::fprintf(stderr, "bake_time: %s\n", e.what());
    return static_cast<int>(e.code());
  }
  return 0;
}
