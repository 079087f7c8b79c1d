// Exact, resolution-independent UV overlap and padding checks (course notes, "Unique
// Mapping Checker"): a box-intersection broad phase (CGAL box_intersection_d) and exact
// orientation predicates (CGAL, Exact_predicates_inexact_constructions_kernel).
#pragma once

#include "meso/core/mesh.hpp"

#include <utility>
#include <vector>

namespace meso {

struct ChartGap {
  int chart_a = 0, chart_b = 0;  // chart_a < chart_b
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
// padding is measured at.
UvOverlapReport find_uv_overlaps(const Mesh& mesh, const std::vector<int>& chart, int size, double padding_texels);

}  // namespace meso
