// Height fields and brute-force references the streams' tests share (test-only header;
// bench/streams.cpp includes it too, for its brute-force mode).
#pragma once

#include "meso/streams/height_field.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <utility>
#include <vector>

// Brute-force cases that take seconds in a release build run 5-8 times slower under
// AddressSanitizer (the asan preset); the heaviest are skipped there, saying so. GCC defines
// __SANITIZE_ADDRESS__, Clang answers __has_feature(address_sanitizer).
#if defined(__SANITIZE_ADDRESS__)
#define MESO_TEST_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define MESO_TEST_UNDER_ASAN 1
#endif
#endif
#ifndef MESO_TEST_UNDER_ASAN
#define MESO_TEST_UNDER_ASAN 0
#endif

namespace meso::test {

// A w x h field from f(x, y), normalised by make_height_field.
inline HeightField field_from(int w, int h, Border border, const std::function<float(int, int)>& f) {
  Image img(w, h, 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img.at(x, y) = f(x, y);
  return make_height_field(img, border);
}

// Uniform noise in [0, 1].
inline HeightField noise(int w, int h, Border border, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> d(0.0f, 1.0f);
  return field_from(w, h, border, [&](int, int) { return d(rng); });
}

// Smooth bumps: one sine period across, two cosine periods down (tiles seamlessly).
inline HeightField bumps(int w, int h, Border border) {
  return field_from(w, h, border, [&](int x, int y) {
    return static_cast<float>(std::sin(6.2831853 * x / w) * std::cos(6.2831853 * 2 * y / h));
  });
}

// Staircase steps of 4 heights across both axes (clamped or tiling as `border` says; the
// pattern itself does not tile).
inline HeightField steps(int w, int h, Border border = Border::clamp) {
  return field_from(w, h, border, [](int x, int y) { return static_cast<float>(((x / 3) + (y / 5)) % 4); });
}

// A flat map with one texel at 1.
inline HeightField spike(int w, int h, Border border, int sx, int sy) {
  return field_from(w, h, border, [=](int x, int y) { return x == sx && y == sy ? 1.0f : 0.0f; });
}

// The two flat extremes of the normalised range. Any constant input normalises to all-zero
// (make_height_field: scale 0), so the all-one field, a flat surface at the top of the box,
// is built directly: the streams accept any heights in [0, 1].
inline HeightField all_zero(int w, int h, Border border) {
  return field_from(w, h, border, [](int, int) { return 0.0f; });
}
inline HeightField all_one(int w, int h, Border border) {
  HeightField f;
  f.height = Image(w, h, 1, 1.0f);
  f.border = border;
  return f;
}

// Cone maps' brute force over the definition: psi = sup (S(y) - T_p) / dist(y, F_p) over
// the surface, sampled at n x n points of every quarter-texel piece (the pieces' corners
// included), over `tiles` copies of the map each way when it wraps. Relaxed: only points some
// corner of F_p sees descending (the piece's own gradient, as at a crease the ray comes from
// that side). The widest safe cone has ratio 1 / psi texels per unit height (0: unbounded).
inline double brute_psi(const HeightField& f, int i, int j, double top, bool relaxed, int n, int tiles) {
  const int w = f.height.width, h = f.height.height;
  double psi = 0;
  for (int ty = -tiles; ty <= tiles; ++ty)
    for (int tx = -tiles; tx <= tiles; ++tx)
      for (int b = 0; b < 2 * h; ++b)
        for (int a = 0; a < 2 * w; ++a) {
          const double px = 0.5 * a, py = 0.5 * b;
          const double v00 = f.bilinear(px, py), v10 = f.bilinear(px + 0.5, py), v01 = f.bilinear(px, py + 0.5),
                       v11 = f.bilinear(px + 0.5, py + 0.5);
          if (std::max({v00, v10, v01, v11}) <= top) continue;
          // Pieces within a texel of F: 8 times denser, where psi changes fastest.
          const double gap_x = std::max({i - (px + 0.5 + tx * w), 0.0, px + tx * w - (i + 1)});
          const double gap_y = std::max({j - (py + 0.5 + ty * h), 0.0, py + ty * h - (j + 1)});
          // plus points closing in on the piece's edges, where limits toward F's boundary live.
          const bool near = std::hypot(gap_x, gap_y) < 1;
          const int m = near ? 8 * n : n;
          std::vector<double> at;
          for (int k = 0; k <= m; ++k) at.push_back(static_cast<double>(k) / m);
          if (near)
            for (double e : {1e-6, 1e-4, 1e-3}) {
              at.push_back(e);
              at.push_back(1 - e);
            }
          std::vector<std::pair<double, double>> points;
          for (double t : at)
            for (double s : at) points.emplace_back(s, t);
          if (near)
            // Fans of directions out of each corner of the piece: where S reaches T on F's
            // boundary, psi's supremum is a limit along one direction out of that point.
            for (double cs : {0.0, 1.0})
              for (double ct : {0.0, 1.0})
                for (int k = 0; k <= 256; ++k) {
                  const double angle = 1.5707963267948966 * k / 256, r = 1e-5;
                  points.emplace_back(std::abs(cs - r * std::cos(angle)), std::abs(ct - r * std::sin(angle)));
                }
          for (const auto& [s, t] : points) {
            const double v = v00 + (v10 - v00) * s + (v01 - v00) * t + (v00 - v10 - v01 + v11) * s * t;
            if (v <= top) continue;
            const double x = px + 0.5 * s + tx * w, y = py + 0.5 * t + ty * h;
            const double dx = std::max({i - x, 0.0, x - (i + 1)}), dy = std::max({j - y, 0.0, y - (j + 1)});
            const double d = std::hypot(dx, dy);
            if (d <= 0) continue;
            if (relaxed) {
              const double gx = 2 * ((v10 - v00) + (v00 - v10 - v01 + v11) * t);
              const double gy = 2 * ((v01 - v00) + (v00 - v10 - v01 + v11) * s);
              bool falls = false;
              for (double fx : {static_cast<double>(i), i + 1.0})
                for (double fy : {static_cast<double>(j), j + 1.0}) falls |= gx * (x - fx) + gy * (y - fy) < 0;
              if (!falls) continue;
            }
            psi = std::max(psi, (v - top) / d);
          }
        }
  return psi;
}

}  // namespace meso::test
