#include "meso/bake/dilate.hpp"

#include "meso/core/lower_envelope.hpp"

#include <algorithm>

namespace meso {

std::vector<int32_t> dilation_sources(const std::vector<uint8_t>& written, int w, int h, int radius) {
  const size_t n = static_cast<size_t>(w) * static_cast<size_t>(h);
  std::vector<int32_t> source(n, -1);
  // "No written texel": far beyond any squared distance on the map, yet finite.
  constexpr double kFar = 1e20;
  // Pass 1, along each row: squared distance to the nearest written texel of the row, and its column.
  std::vector<double> row_d2(n), f(static_cast<size_t>(std::max(w, h)));
  std::vector<int32_t> row_x(n);
  LowerEnvelope env;
  for (int y = 0; y < h; ++y) {
    const size_t base = static_cast<size_t>(y) * static_cast<size_t>(w);
    for (int x = 0; x < w; ++x) f[static_cast<size_t>(x)] = written[base + static_cast<size_t>(x)] ? 0.0 : kFar;
    env.build(f.data(), w, 1);
    LowerEnvelope::Cursor c;
    for (int x = 0; x < w; ++x) {
      const int p = env.root(x, c);
      row_x[base + static_cast<size_t>(x)] = p;
      row_d2[base + static_cast<size_t>(x)] = double(x - p) * (x - p) + f[static_cast<size_t>(p)];
    }
  }
  // Pass 2, along each column over the rows' answers: the exact nearest written texel.
  for (int x = 0; x < w; ++x) {
    for (int y = 0; y < h; ++y) f[static_cast<size_t>(y)] = row_d2[static_cast<size_t>(y) * static_cast<size_t>(w) + static_cast<size_t>(x)];
    env.build(f.data(), h, 1);
    LowerEnvelope::Cursor c;
    for (int y = 0; y < h; ++y) {
      const int q = env.root(y, c);
      const double d2 = double(y - q) * (y - q) + f[static_cast<size_t>(q)];
      if (d2 >= kFar) continue;  // nothing written anywhere
      if (radius >= 0 && d2 > double(radius) * radius) continue;
      const size_t from = static_cast<size_t>(q) * static_cast<size_t>(w);
      source[static_cast<size_t>(y) * static_cast<size_t>(w) + static_cast<size_t>(x)] =
          static_cast<int32_t>(from + static_cast<size_t>(row_x[from + static_cast<size_t>(x)]));
    }
  }
  return source;
}

void apply_dilation(Image& image, const std::vector<int32_t>& sources) {
  const size_t c = static_cast<size_t>(image.channels);
  for (size_t i = 0; i < sources.size(); ++i) {
    const int32_t s = sources[i];
    if (s < 0 || static_cast<size_t>(s) == i) continue;
    std::copy_n(image.pixels.data() + static_cast<size_t>(s) * c, c, image.pixels.data() + i * c);
  }
}

void dilate(Image& image, std::vector<uint8_t>& written, int radius) {
  const auto sources = dilation_sources(written, image.width, image.height, radius);
  apply_dilation(image, sources);
  for (size_t i = 0; i < sources.size(); ++i) written[i] = sources[i] >= 0;
}

}  // namespace meso
