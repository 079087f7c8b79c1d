#include "meso/streams/dilation_erosion.hpp"

#include "meso/streams/pyramid.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <stdexcept>
#include <utility>
#include <vector>

namespace meso {

namespace {

// The running extreme of a window of `radius` either side over a line of n values read with
// get(i) (0 <= i < n), written with put(i, value): van Herk / Gil-Werman, three comparisons
// per value whatever the radius. Under wrap the line is periodic (a window wider than the
// line covers all of it); under clamp the window is cut at the ends. `better(a, b)`: a wins.
template <class Get, class Put, class Better>
void running_extreme(int n, int radius, bool wrap, Get get, Put put, Better better, std::vector<float>& scratch) {
  // Under clamp a radius of n - 1 already reaches both ends from every position: a larger one
  // is the same window, and would only pad the line (2^20 per side: 82 s on a 16384 x 1 map).
  if (!wrap) radius = std::min(radius, std::max(0, n - 1));
  const int w = 2 * radius + 1;
  if (wrap && w >= n) {
    // The window always holds the whole periodic line. (Under clamp a window wider than the
    // line is cut at both ends: the general case below, with neutral padding.)
    float all = get(0);
    for (int i = 1; i < n; ++i) all = better(get(i), all) ? get(i) : all;
    for (int i = 0; i < n; ++i) put(i, all);
    return;
  }
  // Values over the padded line: index j in [0, n + 2 radius) is line position j - radius,
  // wrapped or (clamp) a neutral value that never wins: the window is cut there.
  const int m = n + 2 * radius;
  const int blocks = (m + w - 1) / w;
  const int padded = blocks * w;
  scratch.resize(3 * static_cast<size_t>(padded));
  float* v = scratch.data();
  float* prefix = v + padded;
  float* suffix = prefix + padded;
  bool have_neutral = false;
  float neutral = 0;
  for (int j = 0; j < padded; ++j) {
    int i = j - radius;
    if (i >= 0 && i < n) {
      v[j] = get(i);
    } else if (wrap) {
      i %= n;
      if (i < 0) i += n;
      v[j] = get(i);
    } else {
      // Clamp: outside the map. The line's own worst value never beats anything in it.
      if (!have_neutral) {
        neutral = get(0);
        for (int k = 1; k < n; ++k) neutral = better(neutral, get(k)) ? get(k) : neutral;
        have_neutral = true;
      }
      v[j] = neutral;
    }
  }
  for (int b = 0; b < blocks; ++b) {
    const int s = b * w;
    prefix[s] = v[s];
    for (int j = s + 1; j < s + w; ++j) prefix[j] = better(v[j], prefix[j - 1]) ? v[j] : prefix[j - 1];
    suffix[s + w - 1] = v[s + w - 1];
    for (int j = s + w - 2; j >= s; --j) suffix[j] = better(v[j], suffix[j + 1]) ? v[j] : suffix[j + 1];
  }
  // The window of line position i is padded [i, i + w - 1]: the suffix of its first block
  // and the prefix of its last.
  for (int i = 0; i < n; ++i) {
    const float a = suffix[i], b = prefix[i + w - 1];
    put(i, better(a, b) ? a : b);
  }
}

}  // namespace

Image dilation_erosion_map(const HeightField& field, int radius) {
  if (radius < 0) throw std::invalid_argument("dilation_erosion_map: negative radius");
  Image out = footprint_min_max(field);  // channel 0 min, 1 max over each texel's footprint
  if (radius == 0) return out;
  const int width = out.width, height = out.height;
  const bool wrap = field.border == Border::wrap;
  // Channel 0 keeps the lower value, channel 1 the higher.
  auto better = [](int c) { return [c](float a, float b) { return c == 0 ? a < b : a > b; }; };
  // One pass of running extremes along every line: rows (along x) from `out` into `rows`,
  // then columns (along y) from `rows` back into `out`; the separable filter of a square.
  Image rows = out;
  auto pass = [&](bool along_x, const Image& from, Image& to) {
    const int lines = along_x ? height : width, length = along_x ? width : height;
    tbb::parallel_for(tbb::blocked_range<int>(0, lines, 16), [&](const tbb::blocked_range<int>& r) {
      std::vector<float> scratch;
      for (int l = r.begin(); l < r.end(); ++l)
        for (int c = 0; c < 2; ++c) {
          auto at = [&](int i) { return along_x ? std::pair{i, l} : std::pair{l, i}; };
          running_extreme(
              length, radius, wrap, [&](int i) { const auto [x, y] = at(i); return from.at(x, y, c); },
              [&](int i, float value) { const auto [x, y] = at(i); to.at(x, y, c) = value; }, better(c), scratch);
        }
    });
  };
  pass(true, out, rows);
  pass(false, rows, out);
  return out;
}

}  // namespace meso
