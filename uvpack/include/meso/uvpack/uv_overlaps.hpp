// Exact, resolution-independent UV overlap and padding checks (course notes, "Unique
// Mapping Checker"): a box-intersection broad phase (CGAL box_intersection_d) and exact
// orientation predicates (CGAL, Exact_predicates_inexact_constructions_kernel).
#pragma once

#include "meso/core/mesh.hpp"

#include <utility>
#include <vector>

namespace meso {

struct ChartGap {
  int chart_a = 0, chart_b = 0;  // chart_a < chart_b; equal only across a border (wrap)
  double distance = 0;           // closest approach, texels at the checked size
};

struct UvOverlapReport {
  // Face pairs (a < b, sorted) whose UV triangles share interior points: decided exactly on
  // the UVs as stored, whatever the texture size. Faces with zero UV area take no part.
  std::vector<std::pair<int, int>> overlap_pairs;
  // Chart pairs closer than the padding (padding_texels > 0), with their closest approach;
  // overlapping charts are at distance 0. Sorted by chart pair.
  std::vector<ChartGap> padding_violations;
};

// `chart` gives each face's chart (uv_charts()); `size` the texture size in texels that the
// padding is measured at. `wrap`: the texture is sampled with repeat addressing, so the
// padding is also measured across its borders, against the charts moved by one texture in
// u, v or both (so for UVs within one texture of [0, 1]: faces farther out are reported as
// outside by uv_check, not measured); there a chart that comes closer than the padding to
// itself (its two sides meet across the border) is the pair (a, a). Overlaps stay those of
// the UVs as stored.
UvOverlapReport find_uv_overlaps(const Mesh& mesh, const std::vector<int>& chart, int size, double padding_texels, bool wrap = false);

}  // namespace meso
