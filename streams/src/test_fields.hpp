// Height fields and brute-force references the streams' tests share (test-only header;
// bench/streams.cpp includes it too, for its brute-force mode).
#pragma once

#include "meso/core/progress.hpp"
#include "meso/streams/height_field.hpp"

#include <algorithm>
#include <atomic>
#include <cstdint>
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

// Records what a long operation reports: its phases, their totals, and the units advanced.
struct CountingProgress final : Progress {
  int begins = 0, ends = 0;
  uint64_t total = 0;
  std::atomic<uint64_t> done{0};
  void begin(const std::string&, uint64_t t) override {
    ++begins;
    total += t;
  }
  void advance(uint64_t units) override { done += units; }
  void end() override { ++ends; }
};

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
// The sampled supremum lies below the true one by up to a sample spacing's worth of slope
// (a few per cent at n = 4 where the supremum is a limit on a piece's edge, as relaxed cones'
// often are): the best samples' pieces are then searched again around them on grids 8, 64
// and 512 times finer (measured on ConeBruteForce's maps: the library's cones, exact within
// their 1e-4 tolerance, then sit within 2.1e-4 of it; within 6 % before the refinement).
inline double brute_psi(const HeightField& f, int i, int j, double top, bool relaxed, int n, int tiles) {
  const int w = f.height.width, h = f.height.height;
  // One piece: its origin in pixels (copy offset included) and its four corner values.
  struct Piece {
    double px, py, v00, v10, v01, v11;
  };
  // psi at local (s, t) of a piece, or 0 where the point does not count.
  auto eval = [&](const Piece& p, double s, double t) {
    const double v = p.v00 + (p.v10 - p.v00) * s + (p.v01 - p.v00) * t + (p.v00 - p.v10 - p.v01 + p.v11) * s * t;
    if (v <= top) return 0.0;
    const double x = p.px + 0.5 * s, y = p.py + 0.5 * t;
    const double dx = std::max({i - x, 0.0, x - (i + 1)}), dy = std::max({j - y, 0.0, y - (j + 1)});
    const double d = std::hypot(dx, dy);
    if (d <= 0) return 0.0;
    if (relaxed) {
      const double gx = 2 * ((p.v10 - p.v00) + (p.v00 - p.v10 - p.v01 + p.v11) * t);
      const double gy = 2 * ((p.v01 - p.v00) + (p.v00 - p.v10 - p.v01 + p.v11) * s);
      bool falls = false;
      for (double fx : {static_cast<double>(i), i + 1.0})
        for (double fy : {static_cast<double>(j), j + 1.0}) falls |= gx * (x - fx) + gy * (y - fy) < 0;
      if (!falls) return 0.0;
    }
    return (v - top) / d;
  };
  double psi = 0;
  // The best sample of each piece that has one, kept for the refinement.
  struct Best {
    double psi;
    Piece p;
    double s, t, spacing;
  };
  std::vector<Best> best;
  for (int ty = -tiles; ty <= tiles; ++ty)
    for (int tx = -tiles; tx <= tiles; ++tx)
      for (int b = 0; b < 2 * h; ++b)
        for (int a = 0; a < 2 * w; ++a) {
          const double px = 0.5 * a, py = 0.5 * b;
          const Piece p{px + tx * w, py + ty * h, f.bilinear(px, py), f.bilinear(px + 0.5, py), f.bilinear(px, py + 0.5), f.bilinear(px + 0.5, py + 0.5)};
          if (std::max({p.v00, p.v10, p.v01, p.v11}) <= top) continue;
          // Pieces within a texel of F: 8 times denser, where psi changes fastest.
          const double gap_x = std::max({i - (p.px + 0.5), 0.0, p.px - (i + 1)});
          const double gap_y = std::max({j - (p.py + 0.5), 0.0, p.py - (j + 1)});
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
          Best here{0, p, 0, 0, 1.0 / m};
          for (const auto& [s, t] : points) {
            const double v = eval(p, s, t);
            if (v > here.psi) here = {v, p, s, t, 1.0 / m};
          }
          if (here.psi > 0) best.push_back(here);
          psi = std::max(psi, here.psi);
        }
  // The refinement: the pieces whose best sample is within 10 % of the best, each on three
  // finer grids centred on its best point so far (clipped to the piece).
  for (Best& c : best) {
    if (c.psi < 0.9 * psi) continue;
    double window = c.spacing;
    for (int round = 0; round < 3; ++round) {
      const double s0 = c.s, t0 = c.t;
      for (int v = -8; v <= 8; ++v)
        for (int u = -8; u <= 8; ++u) {
          const double s = std::clamp(s0 + window * u / 8, 0.0, 1.0), t = std::clamp(t0 + window * v / 8, 0.0, 1.0);
          const double x = eval(c.p, s, t);
          if (x > c.psi) {
            c.psi = x;
            c.s = s;
            c.t = t;
          }
        }
      window /= 8;
    }
    psi = std::max(psi, c.psi);
  }
  return psi;
}

}  // namespace meso::test
