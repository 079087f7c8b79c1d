// The base surface's second fundamental form per texel, in the texel's tangent frame: the
// per-texel form of the per-vertex curvatures (curvature.hpp), for effects that need the
// curvature along an arbitrary tangent direction where the shader has only a texture fetch
// (curved-ray silhouettes and view-dependent displacement, survey section 5.1: the height of
// the local quadric along a direction w is 1/2 w^T K w times the squared distance).
//
// Texels: the ones rasterize_uv (uv_raster.hpp) gives a face, at the same base point, so the
// map lines up texel for texel with the bake's displacement.exr. Texel centres at +0.5,
// v up (core/image.hpp).
//
// Frame: the frame the previewer and the bake interpolate (tangent_frame.hpp), made
// orthonormal: n^ = normalize(sum w_k n_k) from the vertex normals, t^ = the interpolated
// corner tangent sum w_k t_k with its n^ component removed, normalised, and
// b^ = sign * cross(n^, t^). b^ points the way of the shader's b = sign * cross(n, t)
// (cross(n, t) only depends on t's part across n), so (t^, b^) spans the same tangent plane
// with +t^ toward +u and +b^ toward +v, just without the skew a non-orthogonal UV mapping
// gives the shader's t and b.
//
// Value: per vertex the shape tensor S = k1 d1 d1^T + k2 d2 d2^T (object space, 3x3,
// symmetric, from the quadric fit: principal curvatures k1 >= k2 and directions d1, d2),
// interpolated barycentrically (a tensor, unlike d1, has no sign ambiguity to average
// across), then K = [[t^.S t^, t^.S b^], [t^.S b^, b^.S b^]]. Units 1/object unit; sign as
// _CURVATURE: positive where the surface bends away from its normal (convex with outward
// normals: a sphere of radius r has K = I / r). The curvature along a unit tangent direction
// w = wt t^ + wb b^ is wt^2 k_tt + 2 wt wb k_tb + wb^2 k_bb = (wt, wb) K (wt, wb)^T.
#pragma once

#include "meso/bake/curvature.hpp"
#include "meso/bake/tangent_frame.hpp"
#include "meso/core/image.hpp"
#include "meso/core/mesh.hpp"

#include <cstddef>
#include <vector>

namespace meso {

struct CurvatureMapOptions {
  int width = 1024, height = 1024;
  int dilate = -1;  // texels to fill around the charts (as BakeOptions::dilate); < 0: all
};

struct CurvatureMap {
  // width x height, 4 channels: R = k_tt, G = k_tb, B = k_bb (1/object units), A = 1 where
  // the texel was computed from the surface, 0 where it holds a dilated copy (or 0 when the
  // map has no computed texel at all). Metadata: quantity, units, convention, channels, min,
  // max. Never NaN or infinite.
  Image image;
  size_t texels = 0;     // computed texels (A = 1)
  size_t undefined = 0;  // texels a chart touches but with no frame there (the interpolated
                         // normal or the tangent across it vanishes): filled by dilation
  // The extremes of K's eigenvalues over the computed texels (0, 0 when there are none).
  float min = 0, max = 0;
};

// `frames` one per halfedge (compute_tangent_frames), `curvature` one per vertex
// (fit_curvature), both of this mesh; needs UVs and vertex normals. Deterministic: the same
// bytes whatever the thread count (every texel is computed by one task from its own sample;
// dilation by dilation_sources' fixed rule). Faces with zero UV area cover no texel, so
// UV-degenerate triangles produce no values of their own; a texel without a frame is
// filled like one outside the charts.
CurvatureMap bake_curvature_map(const Mesh& mesh, const std::vector<TangentFrame>& frames, const std::vector<VertexCurvature>& curvature,
                                const CurvatureMapOptions& options);

}  // namespace meso
