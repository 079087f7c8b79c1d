#include "meso/streams/distance_field.hpp"

#include "meso/core/lower_envelope.hpp"
#include "meso/streams/pyramid.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <utility>

namespace meso {

DistanceField build_distance_field(const HeightField& field, const DistanceFieldOptions& o) {
  const int w = field.height.width, h = field.height.height, d = std::max(1, o.depth);
  DistanceField df;
  df.width = w;
  df.height = h;
  df.depth = d;
  df.relief = o.relief;
  df.distance.assign(static_cast<size_t>(w) * static_cast<size_t>(h) * static_cast<size_t>(d), 0.0f);

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
  // Grid of half-texel spacing over the padded domain: point (a, b) sits at (a/2, b/2)
  // texels from the padded corner. Its height is the tallest box it belongs to (a corner
  // touches up to four).
  const int gw = 2 * we + 1, gh = 2 * he + 1;
  std::vector<float> grid_top(static_cast<size_t>(gw) * static_cast<size_t>(gh), -1.0f);
  for (int y = 0; y < he; ++y)
    for (int x = 0; x < we; ++x) {
      const int sx = ((x - pad_x) % w + w) % w, sy = ((y - pad_y) % h + h) % h;
      const float m = top.at(sx, sy, 1);
      for (int b = 2 * y; b <= 2 * y + 2; ++b)
        for (int a = 2 * x; a <= 2 * x + 2; ++a) {
          float& g = grid_top[static_cast<size_t>(b) * static_cast<size_t>(gw) + static_cast<size_t>(a)];
          g = std::max(g, m);
        }
    }
  // Units: half texels horizontally; the height axis scaled so that normalised height 1 spans
  // relief * W texels = 2 relief W half-texels.
  const double z_scale = 2.0 * static_cast<double>(o.relief) * w;
  const double to_u = 1.0 / (2.0 * w);  // half texels -> units of u

  const size_t W = static_cast<size_t>(w), GW = static_cast<size_t>(gw), GH = static_cast<size_t>(gh);
  tbb::parallel_for(tbb::blocked_range<int>(0, d), [&](const tbb::blocked_range<int>& slices) {
    std::vector<double> line(std::max(GW, GH));  // one row or column of squared distances
    std::vector<float> inter(W * GH);            // after the x pass, transposed: [x][b]
    LowerEnvelope env;
    for (int k = slices.begin(); k < slices.end(); ++k) {
      const double zk = (k + 0.5) / d;
      // Pass 1, along x on every grid row; f is the squared height gap to the row's boxes.
      // Evaluated only at texel centres a = 2x + 1 and stored transposed, so that pass 2
      // reads contiguous columns.
      // Only the rows through texel centres (odd b) need an envelope: a point on a texel
      // edge row touches exactly the boxes of the two centre rows beside it, so its top is
      // their maximum, its f their minimum, and the minimum over a of (x - a)^2 + f commutes
      // with that: the edge row's result is the smaller of its neighbours' results.
      for (size_t b = 1; b < GH; b += 2) {
        const float* tops = grid_top.data() + b * GW;
        for (size_t a = 0; a < GW; ++a) {
          const double dz = std::max(0.0, zk - static_cast<double>(tops[a])) * z_scale;
          line[a] = dz * dz;
        }
        env.build(line.data(), gw, 1);
        LowerEnvelope::Cursor c;
        for (size_t x = 0; x < W; ++x)
          inter[x * GH + b] = static_cast<float>(env.eval(line.data(), 1, 2.0 * (static_cast<double>(x) + pad_x) + 1, c));
      }
      for (size_t x = 0; x < W; ++x) {
        float* col = inter.data() + x * GH;
        col[0] = col[1];
        col[GH - 1] = col[GH - 2];
        for (size_t b = 2; b + 1 < GH; b += 2) col[b] = std::min(col[b - 1], col[b + 1]);
      }
      // Pass 2, along y on every texel-centre column; evaluated at b = 2y + 1.
      float* slice = df.distance.data() + static_cast<size_t>(k) * static_cast<size_t>(h) * W;
      for (size_t x = 0; x < W; ++x) {
        const float* col = inter.data() + x * GH;
        std::copy(col, col + GH, line.begin());
        env.build(line.data(), gh, 1);
        LowerEnvelope::Cursor c;
        for (int y = 0; y < h; ++y)
          slice[static_cast<size_t>(y) * W + x] =
              static_cast<float>(std::sqrt(env.eval(line.data(), 1, 2.0 * (y + pad_y) + 1, c)) * to_u);
      }
    }
  });
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

}  // namespace meso
