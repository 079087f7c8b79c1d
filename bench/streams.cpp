// bench/streams: every stream of `meso streams` through its library calls, on the benchmark
// maps (bench_maps.hpp) at several sizes, with time, output size and working memory; and a
// brute-force mode that checks cone maps against their definition at a size the unit tests
// cannot afford. Figures and commands: docs/benchmarks.md, "streams: one bench for every stream".
//
//   streams_bench [--sizes 256,1024,4096] [--maps bricks,noise,bumps]
//                 [--streams pyramid,dilate-erode,cone,relaxed-cone,sdf] [--radius 4] [--depth 32]
//   streams_bench --brute-force N [--maps ...] [--samples 4]
//
// Each stream runs in a child process of its own (fork), so one stream's peak, or memory the
// allocator kept from an earlier one, is not another's: the child resets its peak RSS to what
// it inherited (writing 5 to /proc/self/clear_refs) and reports VmHWM - VmRSS at the start,
// the memory the stream's call needed at its peak, output included. The parent makes the map
// without TBB, so the child starts TBB afresh (a fork copies only the calling thread).
//
// Exit status: 0, or 1 when the brute-force mode finds a cone wider than the surface allows
// (or a capped cone where the definition finds a limit), or a child fails; 2 on bad usage.
#include "bench_args.hpp"
#include "meso/streams/cone_map.hpp"
#include "meso/streams/dilation_erosion.hpp"
#include "meso/streams/distance_field.hpp"
#include "meso/streams/pyramid.hpp"

#include "bench_maps.hpp"
#include "test_fields.hpp"  // brute_psi: the unit tests' reference (streams/src)

#include <tbb/parallel_for.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace meso {
namespace {

using bench::BenchMap;

const char* const kStreams[] = {"pyramid", "dilate-erode", "cone", "relaxed-cone", "sdf"};

// A field of /proc/self/status in kB (VmRSS, VmHWM), -1 when absent.
long status_kb(const char* key) {
  std::ifstream in("/proc/self/status");
  const size_t n = std::strlen(key);
  for (std::string line; std::getline(in, line);)
    if (line.compare(0, n, key) == 0 && line.size() > n && line[n] == ':') return std::atol(line.c_str() + n + 1);
  return -1;
}

struct Measure {
  double seconds = 0;
  double output_bytes = 0;
  long growth_kb = -1;  // peak RSS over the RSS at the start of the call
  bool ok = false;
};

double image_bytes(const Image& img) { return static_cast<double>(img.pixels.size()) * sizeof(float); }

// Runs one stream the way `meso streams NAME` computes it (without reading and writing the
// files), returning the size of what it would write, as float32.
double run_stream(const std::string& stream, const HeightField& f, int radius, int depth) {
  if (stream == "pyramid") {
    double bytes = 0;
    for (const Image& l : build_min_max_pyramid(f).levels) bytes += image_bytes(l);
    return bytes;
  }
  if (stream == "dilate-erode") return image_bytes(dilation_erosion_map(f, radius));
  if (stream == "cone" || stream == "relaxed-cone") {
    ConeMapOptions o;
    o.kind = stream == "cone" ? ConeKind::conservative : ConeKind::relaxed;
    double bytes = 0;
    for (const Image& l : cone_map_levels(build_cone_map(f, o))) bytes += image_bytes(l);
    return bytes;
  }
  DistanceFieldOptions o;
  o.depth = depth;
  return image_bytes(distance_field_image(build_distance_field(f, o), f));
}

// The stream in a child process; see the file comment for what is measured.
Measure measure_in_child(const std::string& stream, const HeightField& f, int radius, int depth) {
  int fds[2];
  Measure m;
  if (pipe(fds) != 0) return m;
  std::fflush(stdout);
  const pid_t pid = fork();
  if (pid < 0) return m;
  if (pid == 0) {
    close(fds[0]);
    {
      std::ofstream clear("/proc/self/clear_refs");
      clear << "5";  // resets VmHWM to the current RSS (Linux >= 4.0)
    }
    Measure r;
    const long rss0 = status_kb("VmRSS");
    const auto start = std::chrono::steady_clock::now();
    r.output_bytes = run_stream(stream, f, radius, depth);
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const long hwm = status_kb("VmHWM");
    r.growth_kb = rss0 >= 0 && hwm >= 0 ? hwm - rss0 : -1;
    r.ok = true;
    const ssize_t written = write(fds[1], &r, sizeof r);
    _exit(written == static_cast<ssize_t>(sizeof r) ? 0 : 1);
  }
  close(fds[1]);
  const ssize_t got = read(fds[0], &m, sizeof m);
  close(fds[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  if (got != static_cast<ssize_t>(sizeof m) || !WIFEXITED(status) || WEXITSTATUS(status) != 0) m.ok = false;
  return m;
}

int bench_streams(const std::vector<int>& sizes, const std::vector<BenchMap>& maps, const std::vector<std::string>& streams, int radius,
                  int depth) {
  const double mib = 1024.0 * 1024.0;
  // working: the peak growth less the output (what the computation needs beyond what it
  // writes), against the map's own size (n² float32): the "a few times its own size".
  std::printf("| map | size | stream | seconds | output MiB | peak growth MiB | growth / output | working / map | rate |\n");
  std::printf("|---|---:|---|---:|---:|---:|---:|---:|---:|\n");
  int failures = 0;
  for (const int n : sizes)
    for (const BenchMap map : maps) {
      const HeightField f = bench::bench_height_field(map, n);
      for (const std::string& stream : streams) {
        const Measure m = measure_in_child(stream, f, radius, depth);
        const std::string label = stream == "dilate-erode" ? stream + " r" + std::to_string(radius)
                                  : stream == "sdf"        ? stream + " " + std::to_string(depth)
                                                           : stream;
        if (!m.ok) {
          std::printf("| %s | %d² | %s | failed |  |  |  |  |  |\n", bench::bench_map_name(map), n, label.c_str());
          ++failures;
          continue;
        }
        const double texels = static_cast<double>(n) * n;
        char rate[64];
        if (stream == "sdf")
          std::snprintf(rate, sizeof rate, "%.1f M voxels/s", texels * depth / m.seconds / 1e6);
        else
          std::snprintf(rate, sizeof rate, "%.1f M texels/s", texels / m.seconds / 1e6);
        const double growth = m.growth_kb / 1024.0;
        const double map_mib = texels * sizeof(float) / mib;
        std::printf("| %s | %d² | %s | %.3f | %.1f | %.1f | %.2f | %.2f | %s |\n", bench::bench_map_name(map), n, label.c_str(), m.seconds,
                    m.output_bytes / mib, growth, growth / (m.output_bytes / mib), std::max(0.0, growth - m.output_bytes / mib) / map_mib, rate);
        std::fflush(stdout);
      }
    }
  return failures == 0 ? 0 : 1;
}

// Cone maps of n x n maps against brute_psi (the unit tests' ConeBruteForce at a size they
// cannot afford). Safe: never wider than the brute force (which can only overestimate the
// widest cone, sampling the surface); a texel where the brute force finds no limit must hold
// the cap. Reports the gaps 1 - stored / brute, which measure tightness.
int bench_brute_force(int n, const std::vector<BenchMap>& maps, int samples) {
  std::printf("| map | size | kind | library s | brute force s | texels limited | median gap | worst gap | wider | cap wrong |\n");
  std::printf("|---|---:|---|---:|---:|---:|---:|---:|---:|---:|\n");
  int unsafe = 0;
  for (const BenchMap map : maps) {
    const HeightField f = bench::bench_height_field(map, n);
    for (const ConeKind kind : {ConeKind::conservative, ConeKind::relaxed}) {
      auto start = std::chrono::steady_clock::now();
      const Image cone = build_cone_map(f, {kind, 1e-4, false});
      const double library_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      start = std::chrono::steady_clock::now();
      std::vector<double> psi(static_cast<size_t>(n) * n);
      // One texel per slot: the result does not depend on the split.
      tbb::parallel_for(0, n, [&](int j) {
        for (int i = 0; i < n; ++i)
          psi[static_cast<size_t>(j) * n + i] = test::brute_psi(f, i, j, cone.at(i, j, 2), kind == ConeKind::relaxed, samples, 0);
      });
      const double brute_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      std::vector<double> gaps;
      int wider = 0, cap_wrong = 0;
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          const double p = psi[static_cast<size_t>(j) * n + i];
          if (p == 0) {
            cap_wrong += cone.at(i, j, 1) != kConeRatioCap;
            continue;
          }
          // Ratios in texels per unit height, as the unit test compares them.
          const double stored = static_cast<double>(cone.at(i, j, 1)) * n;
          const double brute = std::min(1.0 / p, static_cast<double>(kConeRatioCap) * n);
          wider += stored > brute * (1 + 1e-6);
          gaps.push_back(1 - stored / brute);
        }
      std::sort(gaps.begin(), gaps.end());
      const double median = gaps.empty() ? 0 : gaps[gaps.size() / 2], worst = gaps.empty() ? 0 : gaps.back();
      std::printf("| %s | %d² | %s | %.3f | %.1f | %zu | %.2e | %.2e | %d | %d |\n", bench::bench_map_name(map), n, cone_kind_name(kind), library_s,
                  brute_s, gaps.size(), median, worst, wider, cap_wrong);
      std::fflush(stdout);
      unsafe += wider + cap_wrong;
    }
  }
  if (unsafe > 0) std::printf("UNSAFE: %d texels' cones are wider than the brute force allows, or wrongly capped\n", unsafe);
  return unsafe == 0 ? 0 : 1;
}

int usage() {
  std::fprintf(stderr,
               "usage: streams_bench [--sizes 256,1024,4096] [--maps bricks,noise,bumps]\n"
               "                     [--streams pyramid,dilate-erode,cone,relaxed-cone,sdf] [--radius 4] [--depth 32]\n"
               "       streams_bench --brute-force N [--maps bricks,noise,bumps] [--samples 4]\n");
  return 2;
}

}  // namespace
}  // namespace meso

int main(int argc, char** argv) {
  using namespace meso;
  std::vector<int> sizes = {256, 1024, 4096};
  std::vector<BenchMap> maps = {BenchMap::bricks, BenchMap::noise, BenchMap::bumps};
  std::vector<std::string> streams(std::begin(kStreams), std::end(kStreams));
  int radius = 4, depth = 32, brute = 0, samples = 4;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    if (a + 1 >= argc) return usage();
    const std::string value = argv[++a];
    if (arg == "--sizes") {
      sizes.clear();
      for (const std::string& s : bench::split_commas(value)) sizes.push_back(std::atoi(s.c_str()));
    } else if (arg == "--maps") {
      maps.clear();
      for (const std::string& s : bench::split_commas(value)) {
        if (s == "bricks") maps.push_back(BenchMap::bricks);
        else if (s == "noise") maps.push_back(BenchMap::noise);
        else if (s == "bumps") maps.push_back(BenchMap::bumps);
        else return usage();
      }
    } else if (arg == "--streams") {
      streams = bench::split_commas(value);
      for (const std::string& s : streams)
        if (std::find(std::begin(kStreams), std::end(kStreams), s) == std::end(kStreams)) return usage();
    } else if (arg == "--radius") {
      radius = std::atoi(value.c_str());
    } else if (arg == "--depth") {
      depth = std::atoi(value.c_str());
    } else if (arg == "--brute-force") {
      brute = std::atoi(value.c_str());
    } else if (arg == "--samples") {
      samples = std::atoi(value.c_str());
    } else {
      return usage();
    }
  }
  for (const int n : sizes)
    if (n < 1) return usage();
  if (radius < 0 || depth < 1 || samples < 1 || brute < 0 || maps.empty()) return usage();
  if (brute > 0) return bench_brute_force(brute, maps, samples);
  return bench_streams(sizes, maps, streams, radius, depth);
}
