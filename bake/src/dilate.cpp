#include "meso/bake/dilate.hpp"

#include <algorithm>

namespace meso {

void dilate(Image& image, std::vector<uint8_t>& written, int radius) {
  const int w = image.width, h = image.height;
  std::vector<int32_t> queue;
  queue.reserve(image.texel_count());
  std::vector<int32_t> dist(image.texel_count(), -1);
  for (int32_t i = 0; i < static_cast<int32_t>(image.texel_count()); ++i) {
    if (written[static_cast<size_t>(i)]) {
      queue.push_back(i);
      dist[static_cast<size_t>(i)] = 0;
    }
  }
  const size_t c = static_cast<size_t>(image.channels);
  for (size_t head = 0; head < queue.size(); ++head) {
    const int32_t i = queue[head];
    const int d = dist[static_cast<size_t>(i)];
    if (radius >= 0 && d >= radius) continue;
    const int x = i % w, y = i / w;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const int nx = x + dx, ny = y + dy;
        if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
        const int32_t j = ny * w + nx;
        if (dist[static_cast<size_t>(j)] >= 0) continue;
        dist[static_cast<size_t>(j)] = d + 1;
        std::copy_n(image.pixels.data() + static_cast<size_t>(i) * c, c, image.pixels.data() + static_cast<size_t>(j) * c);
        written[static_cast<size_t>(j)] = 1;
        queue.push_back(j);
      }
    }
  }
}

}  // namespace meso
