#include "meso/bake/dilate.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cstddef>

namespace meso {

void apply_dilation(Image& image, const std::vector<int32_t>& sources) {
  const size_t c = static_cast<size_t>(image.channels);
  auto copy = [&](size_t i) {
    const int32_t s = sources[i];
    if (s < 0 || static_cast<size_t>(s) == i) return;
    std::copy_n(image.pixels.data() + static_cast<size_t>(s) * c, c, image.pixels.data() + i * c);
  };
  // When no source is itself filled from elsewhere (true of dilation_sources: sources are
  // written texels), the order of the copies does not matter: in parallel. Otherwise in
  // index order, as documented.
  std::atomic<bool> chained{false};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, sources.size(), 1 << 15), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) {
      const int32_t s = sources[i];
      if (s >= 0 && static_cast<size_t>(s) != i) {
        const int32_t ss = sources[static_cast<size_t>(s)];
        if (ss >= 0 && ss != s) chained = true;
      }
    }
  });
  if (chained) {
    for (size_t i = 0; i < sources.size(); ++i) copy(i);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<size_t>(0, sources.size(), 1 << 15), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) copy(i);
  });
}

void dilate(Image& image, std::vector<uint8_t>& written, int radius) {
  const auto sources = dilation_sources(written, image.width, image.height, radius);
  apply_dilation(image, sources);
  for (size_t i = 0; i < sources.size(); ++i) written[i] = sources[i] >= 0;
}

}  // namespace meso
