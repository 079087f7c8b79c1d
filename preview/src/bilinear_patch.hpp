// The reference renderer's exact surface over a flat base triangle: the bilinear
// interpolation of the height texels (GL_LINEAR's surface, the one the per-pixel methods
// trace), displaced along the triangle's one normal, intersected cell by cell in closed form.
// No OpenGL and no Embree here, so that tests can check the intersection directly.
#pragma once

#include "meso/core/mesh.hpp"

#include <array>
#include <vector>

namespace meso {

// Texel coordinates, sample_linear's convention (sampling.hpp): x = u W - 1/2, y = (1 - v) H
// - 1/2, so texel (i, j) (column i, row j from the top) has its centre at integer (i, j), and
// cell (i, j) = [i, i+1] x [j, j+1] lies between the centres of texels i, i+1 and j, j+1,
// where the filtered height is one bilinear polynomial of the four (fx = x - i, fy = y - j):
//   h(fx, fy) = (a (1 - fx) + b fx) (1 - fy) + (c (1 - fx) + d fx) fy,
// a, b, c, d = texels (i, j), (i+1, j), (i, j+1), (i+1, j+1) under the border rule.
struct CellHeights {
  double a = 0, b = 0, c = 0, d = 0;
};

// A flat base triangle in texel coordinates: its base point at texel position (x, y) is
// p0 + (x - x0) px + (y - y0) py (the affine map through the three corners' UVs), displaced
// by height s along the unit normal n; to_local maps a point X to (x - x0, y - y0, s) =
// to_local (X - p0); bary[k] = (constant, d/dx, d/dy) of corner k's barycentric weight.
struct FlatPatchFrame {
  OpenMesh::Vec3d p0, px, py, n;
  double x0 = 0, y0 = 0;
  std::array<std::array<double, 3>, 3> to_local{};
  std::array<std::array<double, 3>, 3> bary{};
};

// The frame of the triangle with corners p[k], texel coordinates xy[k] and unit normal n, or
// false where it has none: UVs of zero area, or n in the triangle's plane.
bool make_flat_patch_frame(const std::array<OpenMesh::Vec3d, 3>& p, const std::array<OpenMesh::Vec2d, 3>& xy, const OpenMesh::Vec3d& n,
                           FlatPatchFrame& frame);

// The texel-coordinate polygon where the triangle (corners xy) overlaps cell (i, j)
// (Sutherland-Hodgman clipping against the cell's four sides); empty when they do not overlap
// or only touch (no area).
std::vector<OpenMesh::Vec2d> clip_to_cell(const std::array<OpenMesh::Vec2d, 3>& xy, int i, int j);

struct PatchHit {
  double t = 0;        // along the ray
  double fx = 0, fy = 0;  // the hit's position in the cell, in [0, 1]
};

// The first point of the ray org + t dir, t in [t_min, t_max], on the displaced surface over
// the part of cell (i, j) inside the triangle. In local coordinates the ray is a line
// (x, y, s)(t) (to_local is linear), so g(t) = s(t) - h(fx(t), fy(t)) is a quadratic in t,
// solved in closed form (the cancellation-free pair of roots q / A and C / q) over the
// interval where the ray is over the piece and inside the cell's height slab; a sign change
// that rounding hides from the formula is bisected. The piece is closed and grown by 1e-9
// texel (and barycentric weight) on every side, so that rays through shared cell edges, texel
// corners (texel centres) and triangle edges hit at least one of the pieces that meet there.
// Tangential touches (a double root) may be missed: they cover no area.
bool intersect_bilinear_cell(const FlatPatchFrame& frame, int i, int j, const CellHeights& h, const OpenMesh::Vec3d& org,
                             const OpenMesh::Vec3d& dir, double t_min, double t_max, PatchHit& hit);

}  // namespace meso
