// uvpack pack: place a mesh's UV charts into a square atlas with padding (course notes,
// "Unique Mapping Packer"), the way xatlas does: rasterised chart footprints dilated by the
// padding, four orientations, placement by bitmap search, largest chart first.
#pragma once

#include <algorithm>

#include "meso/core/mesh.hpp"

#include <cstddef>
#include <vector>

namespace meso {

// Search effort against utilisation: fast tries two orientations (0 and 90 degrees) and
// stops the scale search within 4 %; balanced four orientations and 1 %, then tries 6 variants
// (3 chart orders: box area, longest side, UV area; each placed by lowest top or lowest bottom)
// at scales above the one found, in at most min(18, 2400 / charts) more packings; best stops
// within 0.25 % and tries 8 variants (also box perimeter) in at most min(64, 24000 / charts).
enum class PackQuality { fast, balanced, best };

struct UvPackOptions {
  int size = 1024;     // texels per side of the atlas
  int padding = 2;     // texels kept between charts (and to the atlas border: see wrap)
  // How the atlas will be sampled at its border. true (repeat, GL_REPEAT, glTF's default):
  // every chart keeps ceil(padding / 2) texels from the border, so that charts at opposite
  // borders are at least `padding` apart across the wrap, and with mip_safe = K at least 2^K
  // (atlas_border_margin). false (clamp-to-edge): a lookup
  // past the border reads the border texel itself, so charts may touch the border (xatlas
  // packs this way, whatever the sampler).
  bool wrap = true;
  bool rotate = true;  // try quarter turns per chart (how many: quality)
  // With rotate: also try the quarter turns of each chart's minimum-area orientation (the turn
  // that makes its bounding box smallest), when that box is 1-10 % smaller than the input's, or
  // only those when it is smaller still.
  bool min_area_orientation = true;
  PackQuality quality = PackQuality::balanced;
  // Mip-safe padding down to level K (>= 0; -1: off). The guarantee below, which uv_check's
  // mip_safe verifies exactly; `size` must be a multiple of 2^K.
  int mip_safe = -1;
  // Relative linear scale per chart (uv_charts() index; empty: all 1), e.g. from
  // measure_chart_detail (uv_density.hpp): chart c's UVs are scaled by scale * chart_scale[c].
  std::vector<double> chart_scale;
};

struct UvPackReport {
  size_t charts = 0;
  double scale = 0;           // texels per unit of the input UVs (one scale for every chart)
  double utilization = 0;     // the charts' UV triangle areas / the atlas area (padding and touched-only texels not counted)
  // Texels reserved for charts / all texels: those their triangles touch (conservatively, as
  // uv_check counts them) plus the few within the float rounding margin of the written UVs
  // (rounding_margin in uv_pack.cpp): at least uv_check's texel_coverage, above it by ~1e-4.
  double texel_coverage = 0;
  int attempts = 0;           // packings tried while searching the scale
};

// Moves every chart (uv_charts) rigidly: rotation by a multiple of 90 degrees (of the input's
// orientation, or of the chart's minimum-area orientation: min_area_orientation), one common
// scale (relative chart sizes are kept, or changed by exactly chart_scale), translation to
// integer texel offsets. Guarantees,
// at options.size, for the UVs as written (rounded to float): no texel is touched
// (conservatively: the triangle meets its square) by two charts, and touched texels of different charts are at least `padding` texels apart
// (Chebyshev, hence also Euclidean) and, with wrap, at least atlas_border_margin texels from
// the atlas border, so also `padding` apart across it. The
// scale is one at which the greedy placement succeeds, within the quality's tolerance of one at
// which it fails (each packing's fill aims the next: 4-6 packings where bisection took 9), or a
// larger one at which a variant succeeds (PackQuality). Charts with
// no UV area keep a single texel. Deterministic.
//
// With mip_safe = K >= 0, also: no texel of MIP levels 0..K that a bilinear lookup inside a
// chart reads (the 2 x 2 texels around the lookup, so the level-k texels within one of a
// level-k texel the chart touches) holds another chart's values, for box-filtered levels
// (level k+1 the mean of 2 x 2 texels of level k) of a map whose empty texels were dilated
// from their nearest written texel (meso bake's dilation), with clamp-to-edge addressing, or
// with repeat (wrap), where the border margin keeps every such lookup from wrapping around.
// How: at level 0 touched texels of two charts are at least 3 apart (padding >= 2); at level
// k >= 1 the level-k texels that two charts touch are at least m_k apart (Chebyshev, in level-k
// texels), m_1 = 4, m_k = 5 beyond. Then every level-0 texel of a level-k texel that chart c
// reads is at most sqrt(2) (2^(k+1) - 1) from c's nearest touched texel and at least
// (m_k - 2) 2^k + 1 from any other chart's, which is farther: dilation fills it from c. It
// costs about 4 * 2^K texels between charts. Anisotropic filtering reads farther and is not covered. Requires UVs; throws InputError-free
// std::invalid_argument when the charts cannot fit even at the smallest scale tried.
UvPackReport pack_uv_charts(Mesh& mesh, const UvPackOptions& options);

// The texels every chart keeps free along each side of the atlas (UvPackOptions::wrap): half
// the padding, rounded up, so that charts at opposite sides keep the padding across the
// border; with mip_safe = K at least 2^K, so that no bilinear lookup of levels 0..K wraps
// around: the bake's dilation fills the texels along a side from the charts on that side, so
// a lookup that wrapped would read another chart's values (then the guarantee above holds as
// in the plane).
inline int atlas_border_margin(const UvPackOptions& o) {
  if (!o.wrap) return 0;
  const int half = o.padding > 0 ? (o.padding + 1) / 2 : 0;
  return o.mip_safe >= 0 ? std::max(half, 1 << o.mip_safe) : half;
}

}  // namespace meso
