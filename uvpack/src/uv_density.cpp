#include "meso/uvpack/uv_density.hpp"

#include "meso/core/uv_texels.hpp"

#include <algorithm>
#include <cmath>

namespace meso {

std::vector<ChartDetail> measure_chart_detail(const Mesh& mesh, const Image& map, double max_factor) {
  size_t count = 0;
  const std::vector<int> chart_of = uv_charts(mesh, &count);
  std::vector<ChartDetail> out(count);
  for (size_t c = 0; c < count; ++c) out[c].chart = static_cast<int>(c);
  const int w = map.width, h = map.height;
  if (w <= 0 || h <= 0 || count == 0) return out;
  // The chart each texel belongs to: -1 none, -2 several (their data mixes: not used).
  constexpr int kShared = -2;
  std::vector<int> owner(static_cast<size_t>(w) * static_cast<size_t>(h), -1);
  for (auto f : mesh.faces()) {
    if (uv_double_area(mesh, f) == 0.0) continue;
    const int c = chart_of[static_cast<size_t>(f.idx())];
    for_each_touched_texel(uv_triangle_in_pixels(mesh, f, w, h), w, h, [&](int x, int y) {
      int& o = owner[static_cast<size_t>(y) * static_cast<size_t>(w) + static_cast<size_t>(x)];
      o = (o == -1 || o == c) ? c : kShared;
    });
  }
  auto belongs = [&](int x, int y, int c) {
    return x >= 0 && y >= 0 && x < w && y < h && owner[static_cast<size_t>(y) * static_cast<size_t>(w) + static_cast<size_t>(x)] == c;
  };
  // The derivative along one axis in map values per texel, squared and summed over channels.
  auto axis = [&](int x, int y, int dx, int dy, int c) {
    const bool fwd = belongs(x + dx, y + dy, c), back = belongs(x - dx, y - dy, c);
    if (!fwd && !back) return 0.0;
    const int x1 = fwd ? x + dx : x, y1 = fwd ? y + dy : y, x0 = back ? x - dx : x, y0 = back ? y - dy : y;
    const double step = (fwd && back) ? 2.0 : 1.0;
    double sum = 0;
    for (int k = 0; k < map.channels; ++k) {
      const double d = (static_cast<double>(map.at(x1, y1, k)) - map.at(x0, y0, k)) / step;
      sum += d * d;
    }
    return sum;
  };
  std::vector<double> energy(count, 0.0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int c = owner[static_cast<size_t>(y) * static_cast<size_t>(w) + static_cast<size_t>(x)];
      if (c < 0) continue;
      // Per UV unit: a texel is 1/w of u and 1/h of v.
      const double gx = axis(x, y, 1, 0, c) * double(w) * w, gy = axis(x, y, 0, 1, c) * double(h) * h;
      if (!std::isfinite(gx + gy)) continue;
      energy[static_cast<size_t>(c)] += gx + gy;
      ++out[static_cast<size_t>(c)].texels;
    }
  double weighted = 0;
  size_t texels = 0;
  for (size_t c = 0; c < count; ++c) {
    if (out[c].texels == 0) continue;
    out[c].detail = std::sqrt(energy[c] / static_cast<double>(out[c].texels));
    weighted += out[c].detail * out[c].detail * static_cast<double>(out[c].texels);
    texels += out[c].texels;
  }
  const double reference = texels ? std::sqrt(weighted / static_cast<double>(texels)) : 0.0;
  if (!(reference > 0)) return out;  // a constant map: every scale stays 1
  const double lo = 1.0 / max_factor, hi = max_factor;
  for (auto& d : out)
    if (d.texels > 0) d.scale = std::clamp(d.detail / reference, lo, hi);
  return out;
}

}  // namespace meso
