#include "meso/bake/dilate.hpp"

#include <algorithm>

namespace meso {

std::vector<int32_t> dilation_sources(const std::vector<uint8_t>& written, int w, int h, int radius) {
  const size_t n = static_cast<size_t>(w) * static_cast<size_t>(h);
  std::vector<int32_t> source(n, -1), dist(n, -1), queue;
  queue.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    if (!written[i]) continue;
    source[i] = static_cast<int32_t>(i);
    dist[i] = 0;
    queue.push_back(static_cast<int32_t>(i));
  }
  for (size_t head = 0; head < queue.size(); ++head) {
    const int32_t i = queue[head];
    const int32_t d = dist[static_cast<size_t>(i)];
    if (radius >= 0 && d >= radius) continue;
    const int x = i % w, y = i / w;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const int nx = x + dx, ny = y + dy;
        if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
        const size_t j = static_cast<size_t>(ny) * static_cast<size_t>(w) + static_cast<size_t>(nx);
        if (dist[j] >= 0) continue;
        dist[j] = d + 1;
        source[j] = source[static_cast<size_t>(i)];
        queue.push_back(static_cast<int32_t>(j));
      }
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
