#include "meso/streams/pyramid.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

namespace meso {

Image footprint_min_max(const HeightField& f) {
  const int w = f.height.width, h = f.height.height;
  Image level0(w, h, 2);
  tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y < rows.end(); ++y) {
      for (int x = 0; x < w; ++x) {
        // The 9 points of the texel (pixel units): corners average four texels, edge
        // midpoints two, the centre is the texel itself.
        float lo = f.texel(x, y), hi = lo;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            if (dx == 0 && dy == 0) continue;
            const float v = f.bilinear(x + 0.5 + 0.5 * dx, y + 0.5 + 0.5 * dy);
            lo = std::min(lo, v);
            hi = std::max(hi, v);
          }
        }
        level0.at(x, y, 0) = lo;
        level0.at(x, y, 1) = hi;
      }
    }
  });
  return level0;
}

MinMaxPyramid build_min_max_pyramid(const HeightField& f) {
  MinMaxPyramid p;
  p.levels.push_back(footprint_min_max(f));
  while (p.levels.back().width > 1 || p.levels.back().height > 1) {
    const Image& fine = p.levels.back();
    const int fw = fine.width, fh = fine.height;
    const int cw = std::max(1, fw / 2), ch = std::max(1, fh / 2);
    Image coarse(cw, ch, 2);
    tbb::parallel_for(tbb::blocked_range<int>(0, ch), [&](const tbb::blocked_range<int>& rows) {
      for (int y = rows.begin(); y < rows.end(); ++y) {
        // Fine texels overlapping [y/ch, (y+1)/ch]: from floor(y fh / ch) to ceil((y+1) fh / ch) - 1.
        const int y0 = static_cast<int>(static_cast<long>(y) * fh / ch);
        const int y1 = static_cast<int>((static_cast<long>(y + 1) * fh + ch - 1) / ch) - 1;
        for (int x = 0; x < cw; ++x) {
          const int x0 = static_cast<int>(static_cast<long>(x) * fw / cw);
          const int x1 = static_cast<int>((static_cast<long>(x + 1) * fw + cw - 1) / cw) - 1;
          float lo = fine.at(x0, y0, 0), hi = fine.at(x0, y0, 1);
          for (int yy = y0; yy <= y1; ++yy)
            for (int xx = x0; xx <= x1; ++xx) {
              lo = std::min(lo, fine.at(xx, yy, 0));
              hi = std::max(hi, fine.at(xx, yy, 1));
            }
          coarse.at(x, y, 0) = lo;
          coarse.at(x, y, 1) = hi;
        }
      }
    });
    p.levels.push_back(std::move(coarse));
  }
  return p;
}

}  // namespace meso
