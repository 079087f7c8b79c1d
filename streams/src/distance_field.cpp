#include "meso/streams/distance_field.hpp"

#include "meso/core/lower_envelope.hpp"
#include "meso/streams/half_rounding.hpp"
#include "meso/streams/pyramid.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <utility>

namespace meso {

DistanceField build_distance_field(const HeightField& field, const DistanceFieldOptions& o, Progress& progress) {
  const int w = field.height.width, h = field.height.height, d = std::max(1, o.depth);
  DistanceField df;
  df.width = w;
  df.height = h;
  df.depth = d;
  df.relief = o.relief;
  // Left unwritten here (LargeVector): pass 2 writes every voxel, each slice's pages first
  // touched by the thread that fills them.
  df.distance.resize(static_cast<size_t>(w) * static_cast<size_t>(h) * static_cast<size_t>(d));
  if (w <= 0 || h <= 0) return df;  // nothing to transform (and no edge or row to index)

  // Box heights: the maximum of the filtered surface over each texel footprint.
  const Image top = footprint_min_max(field);
  // A tiling map (Border::wrap) is surrounded by copies of itself: pad the domain by `pad`
  // texels of wrapped boxes. No box farther than relief * W texels can be nearest, since every
  // voxel is at most that far above the floor of its own box.
  // A nearer periodic copy of any box lies within half a period, which caps the padding.
  const double reach = std::ceil(static_cast<double>(o.relief) * w) + 1;
  const int pad_x = field.border == Border::wrap ? static_cast<int>(std::min(reach, w / 2.0 + 1)) : 0;
  const int pad_y = field.border == Border::wrap ? static_cast<int>(std::min(reach, h / 2.0 + 1)) : 0;
  const int we = w + 2 * pad_x, he = h + 2 * pad_y;
  const size_t W = static_cast<size_t>(w), WE = static_cast<size_t>(we), HE = static_cast<size_t>(he);

  // The nearest point of box [X, X+1] x [Y, Y+1] (padded texel coordinates) to a texel centre
  // (x + 1/2, y + 1/2) is the centre itself when X = x, else a point on the line x = X or
  // x = X + 1, and likewise in y: so distances are minima over the half-texel grid, each grid
  // point carrying the tallest box it touches. A centre of another column is never the only
  // nearest point: the edge of its box on the query's side is nearer and no lower (it touches
  // that box too). So each pass of Felzenszwalb & Huttenlocher's transform needs the texel
  // edges (W + 1 points of a row) plus the query's own centre, half of the full grid.
  // edge_top[y][e]: the tallest box of padded row y touching edge e (boxes e - 1 and e).
  std::vector<float> box(WE * HE), edge_top((WE + 1) * HE);
  std::vector<float> row_low(HE);  // lowest box of each padded row
  for (int y = 0; y < he; ++y) {
    const int sy = ((y - pad_y) % h + h) % h;
    float* b = box.data() + static_cast<size_t>(y) * WE;
    for (int x = 0; x < we; ++x) b[x] = top.at(((x - pad_x) % w + w) % w, sy, 1);
    float* e = edge_top.data() + static_cast<size_t>(y) * (WE + 1);
    e[0] = b[0];
    e[we] = b[we - 1];
    for (int x = 1; x < we; ++x) e[x] = std::max(b[x - 1], b[x]);
    row_low[static_cast<size_t>(y)] = *std::min_element(b, b + we);
  }
  // Units: texels horizontally; the height axis scaled so that normalised height 1 spans
  // relief * W texels.
  const double z_scale = static_cast<double>(o.relief) * w;
  const double to_u = 1.0 / w;  // texels -> units of u

  // Pass 1 stores its rows in strips of kStrip columns, [strip][y][column in strip], one
  // cache line per (strip, row): pass 2 then reads each strip as one block that stays in
  // cache while its columns are transformed. (Stored row by row, or transposed, pass 1's
  // output is 64 MiB per thread at 4096², and reading it down the columns missed the cache on
  // every access: 17 % of perf's samples at 4096², gone with the strips.)
  constexpr size_t kStrip = 16;
  const size_t strips = (W + kStrip - 1) / kStrip;
  // Working buffers per thread, not per task: the tasks are many, and fresh memory is dear
  // here (first touches fault in pages the kernel must zero: 64 MiB of rows per task at 4096²).
  struct Buffers {
    std::vector<double> line;  // one row or column of squared distances
    std::vector<float> rows;   // after the x pass: [strip][y][x % kStrip]
    std::vector<float> out;    // one strip's results, [x % kStrip][y]
    LowerEnvelope env;
  };
  tbb::enumerable_thread_specific<Buffers> buffers([&] {
    return Buffers{std::vector<double>(std::max(WE, HE) + 1), std::vector<float>(strips * HE * kStrip),
                   std::vector<float>(kStrip * static_cast<size_t>(h)), LowerEnvelope{}};
  });
  progress.begin("distance field", static_cast<uint64_t>(d));
  tbb::parallel_for(tbb::blocked_range<int>(0, d), [&](const tbb::blocked_range<int>& slices) {
    Buffers& buf = buffers.local();
    std::vector<double>& line = buf.line;
    std::vector<float>& rows = buf.rows;
    std::vector<float>& out = buf.out;
    LowerEnvelope& env = buf.env;
    for (int k = slices.begin(); k < slices.end(); ++k) {
      const double zk = (k + 0.5) / d;
      const auto gap2 = [&](float t) {
        const double dz = std::max(0.0, zk - static_cast<double>(t)) * z_scale;
        return dz * dz;
      };
      // Pass 1, along x on every padded row: squared distances in the xz plane to the row's
      // boxes, at the unpadded texel centres. A row whose every box reaches the slice is 0.
      for (size_t y = 0; y < HE; ++y) {
        float* r = rows.data() + y * kStrip;  // x at r[(x / kStrip) * HE * kStrip + x % kStrip]
        const auto at = [&](size_t x) -> float& { return r[(x / kStrip) * HE * kStrip + x % kStrip]; };
        if (static_cast<double>(row_low[y]) >= zk) {
          for (size_t x = 0; x < W; ++x) at(x) = 0.0f;
          continue;
        }
        const float* e = edge_top.data() + y * (WE + 1);
        const float* b = box.data() + y * WE + static_cast<size_t>(pad_x);
        for (size_t a = 0; a <= WE; ++a) line[a] = gap2(e[a]);
        env.build(line.data(), we + 1, 1);
        LowerEnvelope::Cursor c;
        for (size_t x = 0; x < W; ++x) {
          const double q = static_cast<double>(x) + pad_x + 0.5;
          at(x) = static_cast<float>(std::min(env.eval(line.data(), 1, q, c), gap2(b[x])));
        }
      }
      // Pass 2, along y on every texel-centre column: the same reduction, with the value on
      // edge j the smaller of the two rows beside it (an edge point touches both rows' boxes).
      float* slice = df.distance.data() + static_cast<size_t>(k) * static_cast<size_t>(h) * W;
      for (size_t x0 = 0; x0 < W; x0 += kStrip) {
        const size_t n = std::min(kStrip, W - x0);
        for (size_t c = 0; c < n; ++c) {
          const float* col = rows.data() + (x0 / kStrip) * HE * kStrip + c;  // row y at col[y * kStrip]
          line[0] = col[0];
          line[HE] = col[(HE - 1) * kStrip];
          for (size_t j = 1; j < HE; ++j) line[j] = std::min(col[(j - 1) * kStrip], col[j * kStrip]);
          env.build(line.data(), he + 1, 1);
          LowerEnvelope::Cursor cur;
          for (int y = 0; y < h; ++y) {
            const size_t yp = static_cast<size_t>(y + pad_y);
            const double r = std::min(env.eval(line.data(), 1, static_cast<double>(yp) + 0.5, cur), static_cast<double>(col[yp * kStrip]));
            out[c * static_cast<size_t>(h) + static_cast<size_t>(y)] = static_cast<float>(std::sqrt(r) * to_u);
          }
        }
        for (size_t y = 0; y < static_cast<size_t>(h); ++y)
          for (size_t c = 0; c < n; ++c) slice[y * W + x0 + c] = out[c * static_cast<size_t>(h) + y];
      }
      progress.advance(1);
    }
  });
  progress.end();
  return df;
}

Image distance_field_image(DistanceField field, const HeightField& source) {
  Image img;
  img.width = field.width;
  img.height = field.height * field.depth;
  img.channels = 1;
  img.pixels = std::move(field.distance);  // the same layout: no copy
  img.metadata = height_field_metadata(source);
  img.metadata["quantity"] = std::string("distance field");
  img.metadata["channels"] = std::string("Y = distance from the voxel centre to the solid under the filtered height surface, units of u");
  img.metadata["depth"] = field.depth;
  img.metadata["relief"] = field.relief;
  img.metadata["layout"] =
      std::string("slice k in rows [k H, (k+1) H), slice 0 lowest; voxel centre (x+0.5)/W, (y+0.5)/H, (k+0.5)/depth");
  return img;
}

void round_distances_to_half(Image& distance_field) {
  for (float& v : distance_field.pixels) v = half_below(v);
}

}  // namespace meso
