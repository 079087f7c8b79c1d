// uvpack pack --unwrap: cut a mesh into charts and flatten each one (course notes, "Unique
// Texture Mapping"), so that a mesh without UVs, or with an unusable mapping, can be packed.
//
// Charts grow over faces whose normals stay within a cone around the chart's mean normal
// (bounded normal deviation bounds the projection's distortion); each chart is made a
// topological disk and flattened with CGAL's Surface_mesh_parameterization: LSCM (Lévy,
// Petitjean, Ray, Maillot 2002, "Least Squares Conformal Maps for Automatic Texture Atlas
// Generation") or ARAP (Liu, Zhang, Xu, Gotsman, Gortler 2008, "A Local/Global Approach to
// Mesh Parameterization"). Distortion is measured with Sander, Snyder, Gortler, Hoppe 2001
// ("Texture Mapping Progressive Meshes"): the singular values Γ ≥ γ of the Jacobian of the
// map from texture to surface, after each chart is scaled to the surface area it covers.
// Charts whose L2 stretch exceeds a bound, that fold over (a flipped triangle) or overlap
// themselves are split in two and flattened again, recursively (a single triangle is
// mapped isometrically, so this ends).
#pragma once

#include "meso/core/mesh.hpp"

#include <cstddef>
#include <vector>

namespace meso {

enum class UnwrapMethod {
  lscm,  // least squares conformal maps: angles kept, one sparse solve per chart
  arap,  // as-rigid-as-possible (local/global iterations from a mean-value start): areas kept better, ~15x slower
};

struct UvUnwrapOptions {
  UnwrapMethod method = UnwrapMethod::lscm;
  // A face joins a growing chart while its normal is within this angle (degrees) of the
  // chart's area-weighted mean normal.
  double max_chart_angle = 60;
  // Bound on each chart's L2 stretch (Sander et al. 2001; 1 = isometric, which planar and
  // developable charts reach). Charts above it are split.
  double max_stretch = 1.1;
  // Charts stop growing at this many faces (0: no cap); bounds the size of one solve.
  int max_chart_faces = 0;
};

// Distortion of one chart, measured after scaling it to its surface area.
struct UnwrapChart {
  int faces = 0;
  double area = 0;          // surface area, object units^2
  double stretch_l2 = 1;    // sqrt(area-weighted mean of (Γ² + γ²) / 2)
  double stretch_linf = 1;  // max Γ over its faces
};

struct UvUnwrapReport {
  size_t charts = 0;
  size_t grown_charts = 0;      // charts out of region growing, before any split
  size_t topology_splits = 0;   // charts that were not a disk
  size_t stretch_splits = 0;    // L2 stretch above the bound, or a flipped triangle
  size_t overlap_splits = 0;    // charts overlapping themselves in UV
  size_t failure_splits = 0;    // the solver failed (or gave non-finite UVs)
  // Whole mesh, each chart scaled to its surface area (one texel density everywhere):
  double stretch_l2 = 1;        // sqrt(area-weighted mean over faces of (Γ² + γ²) / 2)
  double stretch_linf = 1;      // max Γ over faces
  double max_chart_stretch_l2 = 1;
  double angle_distortion_mean = 1;  // Γ / γ, area-weighted mean (1 = conformal)
  double angle_distortion_max = 1;
  double area_distortion_mean = 1;   // max(r, 1/r), r = UV area / surface area, area-weighted mean
  size_t degenerate_faces = 0;       // zero surface area: mapped alone to a zero-area UV triangle
  // Per chart, indexed like uv_charts() numbers the result (by first face in face order).
  std::vector<UnwrapChart> per_chart;
};

// Replaces the mesh's UVs (adding halfedge UVs if it has none) with a fresh chart layout:
// charts as above, each scaled to its surface area (one density for all), laid out side by
// side without overlap and the whole layout scaled uniformly into [0,1]^2; pack_uv_charts()
// then places them in an atlas. Each chart is a UV-connected component (uv_charts() finds
// exactly these charts), mapped one-to-one: no flipped triangle, no overlap inside a chart,
// counter-clockwise UVs for counter-clockwise faces. Deterministic whatever the thread
// count (charts are flattened in parallel, results combined in chart order). Requires a
// compacted mesh (no deleted elements), as read_mesh() returns.
UvUnwrapReport unwrap_uv_charts(Mesh& mesh, const UvUnwrapOptions& options);

}  // namespace meso
