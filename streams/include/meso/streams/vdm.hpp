// View-dependent displacement maps (survey section 6.3; Wang, Wang, Tong, Lin, Hu, Guo and
// Shum, "View-Dependent Displacement Mapping", SIGGRAPH 2003): per texel, per view direction
// and per curvature of the underlying surface along that direction, where the view ray meets
// the height field, precomputed by exact ray casting and compressed by truncated PCA.
//
// Geometry. The height field sits in a box 1 wide (units of u: texels are square, so a
// distance of n texels is n / W), H / W deep and `relief` high; normalised height 1 is its
// top (the outermost point). A view ray enters the top above texel centre p with zenith
// angle theta (from the normal) and azimuth phi (counter-clockwise from +u toward +v). On a
// base surface curved by c along the view direction (per unit of u; positive where it falls
// away from its normal, as a sphere of radius r seen from outside has c = 1/r) the height
// field bends with it, which the ray sees as its own bending by c s^2 / 2 at horizontal
// distance s (the survey's curved-surface approximation, section 5.1).
#pragma once

#include "meso/core/progress.hpp"
#include "meso/streams/height_field.hpp"

#include <cstddef>
#include <vector>

namespace meso {

struct VdmOptions {
  int theta = 8;              // view angles theta_i = (i + 1/2) / theta * theta_max
  float theta_max = 90.0f;    // degrees from the normal
  int phi = 16;               // azimuths phi_j = 360 j / phi degrees
  std::vector<float> curvatures{0.0f};  // per unit of u; a flat base needs only 0
  float relief = 0.1f;        // the height range in units of u (object height / object length per u)
};

// What a ray that meets nothing records: it left the bent height field (a silhouette).
inline constexpr float kVdmMiss = -1.0f;

// The table: entry (texel, direction) is the horizontal distance, in units of u, from the
// ray's entry point above the texel centre to the first point of the filtered surface it
// meets (bilinear, exact up to rounding; intersections found with the min-max pyramid,
// never skipped), or kVdmMiss. The visible point is then (u, v) + d (cos phi, sin phi).
// Directions are numbered (curvature k, theta i, phi j) -> (k * theta + i) * phi + j.
struct VdmTable {
  int width = 0, height = 0, theta = 0, phi = 0, curvatures = 0;
  std::vector<float> distance;  // [texel * directions() + direction], texel = y * width + x
  int directions() const { return theta * phi * curvatures; }
  float at(size_t texel, int direction) const {
    return distance[texel * static_cast<size_t>(directions()) + static_cast<size_t>(direction)];
  }
};

// Parallel over texel rows; deterministic. Border::wrap rays go on through neighbouring
// tiles; under Border::clamp a ray leaving the map is a miss.
VdmTable build_vdm(const HeightField& field, const VdmOptions& options, Progress& progress = null_progress());

// The curvature slices a base mesh needs (per unit of u), from its vertices' principal
// curvatures k1 >= k2 (1 / object units, vdm.hpp's sign) and its object length per unit of u:
// `steps` values evenly over [5th percentile of k2, 95th percentile of k1] (a few sharp
// vertices, such as a bevel's, would otherwise stretch the range and starve the rest; the
// previewer clamps curvatures outside to the nearest slice); one value, the median of
// (k1 + k2) / 2, when steps is 1 or the range is empty. Strictly increasing: steps that round
// to the same float are kept once. Deterministic.
std::vector<float> vdm_curvature_slices(const std::vector<float>& k1, const std::vector<float>& k2, double length_per_u, int steps);

// The relief (VdmOptions::relief, units of u) of a map whose height range is `height_scale`
// object units on a base mesh of `length_per_u` object units per unit of u (object_length_per_uv),
// at least 1e-6: a flatter table is flat for every view. What `meso streams vdm --mesh` uses,
// and what the previewer expects of a table for that mesh.
double vdm_relief_on_mesh(double height_scale, double length_per_u);

// Truncated PCA of the table seen as a texels x directions matrix D: D ~ m + W B^T, m the
// column means, B (directions x rank) the covariance's leading eigenvectors, W = (D - m) B.
// The rank is the smallest whose RMS error over all entries (misses counted as kVdmMiss) is
// at most `max_rms` (units of u), capped at `max_rank`. Deterministic.
struct CompressedVdm {
  int texels = 0, directions = 0, rank = 0;
  std::vector<float> mean;     // [direction]
  std::vector<float> basis;    // [direction * rank + k]
  std::vector<float> weights;  // [texel * rank + k]
  double rms_error = 0, max_error = 0;  // achieved over every entry, units of u
  float value(size_t texel, int direction) const;
  size_t bytes() const { return (mean.size() + basis.size() + weights.size()) * sizeof(float); }
};
CompressedVdm compress_vdm(const VdmTable& table, double max_rms, int max_rank);

// The two parts of vdm.exr (docs/formats.md): part 0 the weights, W x H, one channel per
// component (one zero channel at rank 0), with the height field's metadata and the sampling
// (theta, theta_max, phi, curvatures, relief, rank, rms_error, max_error, miss, layout); part 1
// (rank + 1) x directions, column 0 the mean, column k + 1 component k.
std::vector<Image> vdm_images(const CompressedVdm& vdm, const HeightField& field, const VdmOptions& options);

}  // namespace meso
