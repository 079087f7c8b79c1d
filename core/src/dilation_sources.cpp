#include "meso/core/dilation_sources.hpp"

#include "meso/core/lower_envelope.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstddef>

namespace meso {

std::vector<int32_t> dilation_sources(const std::vector<uint8_t>& written, int w, int h, int radius) {
  const size_t n = static_cast<size_t>(w) * static_cast<size_t>(h);
  std::vector<int32_t> source(n, -1);
  // "No written texel": far beyond any squared distance on the map, yet finite.
  constexpr double kFar = 1e20;
  // Everything written: every texel is its own source (what the passes below give).
  if (std::all_of(written.begin(), written.begin() + static_cast<std::ptrdiff_t>(n), [](uint8_t b) { return b != 0; })) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1 << 16), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i < r.end(); ++i) source[i] = static_cast<int32_t>(i);
    });
    return source;
  }
  // Rows, then columns, each independent of the others: in parallel, one envelope and one
  // buffer per task. The answer does not depend on the split.
  // Pass 1, along each row: squared distance to the nearest written texel of the row, and its column.
  std::vector<double> row_d2(n);
  std::vector<int32_t> row_x(n);
  tbb::parallel_for(tbb::blocked_range<int>(0, h, 16), [&](const tbb::blocked_range<int>& rows) {
    std::vector<double> f(static_cast<size_t>(w));
    LowerEnvelope env;
    for (int y = rows.begin(); y < rows.end(); ++y) {
      const size_t base = static_cast<size_t>(y) * static_cast<size_t>(w);
      if (std::all_of(written.begin() + static_cast<std::ptrdiff_t>(base), written.begin() + static_cast<std::ptrdiff_t>(base + static_cast<size_t>(w)),
                      [](uint8_t b) { return b != 0; })) {
        // Every texel its own nearest (what the envelope gives: p = x, distance 0).
        for (int x = 0; x < w; ++x) {
          row_x[base + static_cast<size_t>(x)] = x;
          row_d2[base + static_cast<size_t>(x)] = 0.0;
        }
        continue;
      }
      for (int x = 0; x < w; ++x) f[static_cast<size_t>(x)] = written[base + static_cast<size_t>(x)] ? 0.0 : kFar;
      env.build(f.data(), w, 1);
      LowerEnvelope::Cursor c;
      for (int x = 0; x < w; ++x) {
        const int p = env.root(x, c);
        row_x[base + static_cast<size_t>(x)] = p;
        row_d2[base + static_cast<size_t>(x)] = double(x - p) * (x - p) + f[static_cast<size_t>(p)];
      }
    }
  });
  // Pass 2, along each column over the rows' answers: the exact nearest written texel.
  // Columns in blocks of kBlock: the block's values are gathered row by row (a few cache
  // lines per row rather than one per texel), then each column is solved on its own.
  constexpr int kBlock = 16;
  tbb::parallel_for(tbb::blocked_range<int>(0, (w + kBlock - 1) / kBlock), [&](const tbb::blocked_range<int>& blocks) {
    std::vector<double> gathered(static_cast<size_t>(kBlock) * static_cast<size_t>(h));
    LowerEnvelope env;
    for (int blk = blocks.begin(); blk < blocks.end(); ++blk) {
      const int xb = blk * kBlock, nb = std::min(kBlock, w - xb);
      for (int y = 0; y < h; ++y)
        for (int j = 0; j < nb; ++j)
          gathered[static_cast<size_t>(j) * static_cast<size_t>(h) + static_cast<size_t>(y)] =
              row_d2[static_cast<size_t>(y) * static_cast<size_t>(w) + static_cast<size_t>(xb + j)];
      for (int x = xb; x < xb + nb; ++x) {
        double* f = gathered.data() + static_cast<size_t>(x - xb) * static_cast<size_t>(h);
        bool all_zero = true;
        for (int y = 0; y < h; ++y) all_zero &= f[static_cast<size_t>(y)] == 0.0;
        if (all_zero) {
          // Every row's nearest lies in this column's own row (q = y, distance 0).
          for (int y = 0; y < h; ++y) {
            const size_t from = static_cast<size_t>(y) * static_cast<size_t>(w);
            source[from + static_cast<size_t>(x)] = static_cast<int32_t>(from + static_cast<size_t>(row_x[from + static_cast<size_t>(x)]));
          }
          continue;
        }
        env.build(f, h, 1);
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
    }
  });
  return source;
}

}  // namespace meso
