// bake_compare: the angular difference between meso's tangent-space normal map and Blender's
// (bench/bake_peers.sh, bench/bake_blender.py), over the texels both wrote.
//
//   bake_compare --meso DIR/normal_ts.png --coverage DIR/coverage.png --blender normal.rgba32f
//                [--diff diff.png] [--max-degrees D]
//
// meso: normal_ts.png (n * 0.5 + 0.5, top row first) and coverage.png (1 = hit, 0.75 =
// ambiguous hit, 0.5 = miss, 0 = outside the charts): texels with a hit count. Blender: raw
// float32 RGBA, bottom row first, n * 0.5 + 0.5, unwritten texels (0, 0, 0, 0), the same size.
// Both in MikkTSpace tangent space, +X = +u, +Y = +v. Prints one JSON object: texel counts,
// mean, median, p99 and max of the angle in degrees. --diff writes the angle as an 8-bit grey
// PNG (white = --max-degrees, default 5).
#include "meso/core/image.hpp"
#include "meso/formats/image_io.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  std::string meso_path, coverage_path, blender_path, diff_path;
  double max_degrees = 5.0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "bake_compare: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--meso") meso_path = next();
    else if (a == "--coverage") coverage_path = next();
    else if (a == "--blender") blender_path = next();
    else if (a == "--diff") diff_path = next();
    else if (a == "--max-degrees") max_degrees = std::atof(next().c_str());
    else {
      std::fprintf(stderr, "bake_compare: unknown argument %s\n", a.c_str());
      return 2;
    }
  }
  if (meso_path.empty() || coverage_path.empty() || blender_path.empty()) {
    std::fprintf(stderr, "usage: bake_compare --meso normal_ts.png --coverage coverage.png --blender normal.rgba32f [--diff out.png]\n");
    return 2;
  }
  try {
    const meso::Image normal = meso::read_image(meso_path);
    const meso::Image coverage = meso::read_image(coverage_path);
    const int w = normal.width, h = normal.height;
    if (coverage.width != w || coverage.height != h || normal.channels < 3) {
      std::fprintf(stderr, "bake_compare: %s and %s differ in size or channels\n", meso_path.c_str(), coverage_path.c_str());
      return 3;
    }
    std::vector<float> blender(static_cast<size_t>(w) * static_cast<size_t>(h) * 4);
    std::ifstream in(blender_path, std::ios::binary);
    in.read(reinterpret_cast<char*>(blender.data()), static_cast<std::streamsize>(blender.size() * sizeof(float)));
    if (!in || in.peek() != std::char_traits<char>::eof()) {
      std::fprintf(stderr, "bake_compare: %s is not %d x %d float32 RGBA\n", blender_path.c_str(), w, h);
      return 3;
    }
    std::vector<double> angles;
    size_t meso_hits = 0, blender_written = 0, both = 0;
    meso::Image diff(w, h, 1, 0.0f);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const float* b = &blender[4 * (static_cast<size_t>(h - 1 - y) * static_cast<size_t>(w) + static_cast<size_t>(x))];
        const bool b_written = b[0] != 0.0f || b[1] != 0.0f || b[2] != 0.0f;
        const bool m_hit = coverage.at(x, y, 0) > 0.7f;
        meso_hits += m_hit;
        blender_written += b_written;
        if (!m_hit || !b_written) continue;
        ++both;
        double m[3], n[3], mm = 0, nn = 0, dot = 0;
        for (int c = 0; c < 3; ++c) {
          m[c] = 2.0 * normal.at(x, y, c) - 1.0;
          n[c] = 2.0 * b[c] - 1.0;
          mm += m[c] * m[c];
          nn += n[c] * n[c];
          dot += m[c] * n[c];
        }
        const double angle = std::acos(std::clamp(dot / std::sqrt(mm * nn), -1.0, 1.0)) * 180.0 / M_PI;
        angles.push_back(angle);
        diff.at(x, y) = static_cast<float>(std::min(1.0, angle / max_degrees));
      }
    double mean = 0;
    for (double a : angles) mean += a;
    mean = angles.empty() ? 0 : mean / static_cast<double>(angles.size());
    std::sort(angles.begin(), angles.end());
    auto q = [&](double p) {
      return angles.empty() ? 0.0 : angles[std::min(angles.size() - 1, static_cast<size_t>(p * static_cast<double>(angles.size())))];
    };
    size_t over1 = 0;
    for (double a : angles) over1 += a > 1.0;
    std::printf("{\"size\": %d, \"meso_hits\": %zu, \"blender_written\": %zu, \"compared\": %zu, \"mean_deg\": %.5f, "
                "\"median_deg\": %.5f, \"p99_deg\": %.5f, \"max_deg\": %.5f, \"over_1deg\": %zu}\n",
                w, meso_hits, blender_written, both, mean, q(0.5), q(0.99), angles.empty() ? 0.0 : angles.back(), over1);
    if (!diff_path.empty()) meso::write_image(diff, diff_path, meso::PixelFormat::uint8);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bake_compare: %s\n", e.what());
    return 3;
  }
  return 0;
}
