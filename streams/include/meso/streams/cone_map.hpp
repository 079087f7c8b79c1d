// Cone maps for cone step mapping (survey section 4.3.5, Dummer 2006) and relaxed cone
// stepping (survey section 4.4.3, Policarpo & Oliveira 2007), exact for the bilinearly
// filtered height surface and safe for every point a shader can sample, following the
// analysis of Ban, Valasek et al., "Robust Cone Step Mapping" (EGSR 2024): cones that are
// empty only as seen from texel centres are not safe once a shader samples in between.
//
// Units and conventions. Horizontal positions are pixel units (texel (i, j) covers
// [i, i+1] x [j, j+1], x right, y down the rows, centres at +0.5); heights are the height
// field's normalised heights in [0, 1], 1 = the outermost point (the macro surface sits at 0).
// S(x, y) is the bilinearly filtered surface (GL_LINEAR through the texel centres, with the
// field's border rule). A stored ratio is horizontal distance per unit of normalised height,
// in units of u (texels are square: a distance of n texels in any direction is n / W).
//
// The cone of texel p. F_p is p's footprint, T_p = max S over F_p (its apex height: the
// highest point of the surface over the texel, the pyramid's level-0 maximum). With ratio m
// the cone is the region
//     E_p(m) = { (y, w) : dist(y, F_p) <= m (w - T_p) },
// the union of the upright cones of ratio m whose apex is any point (x, T_p), x in F_p. A
// tracer at a point (x, z) with x in F_p and z >= T_p may therefore use the apex (x, T_p),
// whatever sub-texel position x has, and the map is read with nearest-texel fetches (never
// interpolated: an interpolated ratio is not a cone of anything).
//
// Conservative cone (Dummer): the widest m for which E_p(m) contains no point of the surface
// above T_p:   m_p = inf { dist(y, F_p) / (S(y) - T_p) : S(y) > T_p }.
//
// Relaxed cone: the widest m for which no point of the surface inside E_p(m) descends as seen
// from the footprint, i.e. every y with S(y) > T_p inside the cone has
// grad S(y) . (y - x) >= 0 for every x in F_p (one-sided gradients of the bilinear pieces).
// Then a ray from any point (x, z), x in F_p, z >= T_p, to the boundary of the cone of apex
// (x, T_p) crosses the surface at most once, from above to below: a second crossing would
// leave the solid at a point where the surface falls away from x. So stepping to the cone's
// boundary and, when the end point is below the surface, bisecting, finds the first
// intersection (Policarpo & Oliveira's search, with cones that are right; the original
// preprocessing only tested rays through texel centres).
//
// Exactness. Both infima run over the continuous surface: quarter-texel pieces on which S is
// one bilinear polynomial, searched with a max quadtree of the apex heights and bounded by
// branch and bound. Side pieces (beside the footprint) are exact at their corners. Corner
// pieces are exact on their boundary (closed-form maxima along the edges) unless the piece's
// polynomial is concave along the rays out of F's corner, where they are refined until the
// bound is within `tolerance` (relative) of a value attained. Relaxed cones need no such
// refinement: the slope has no local maximum inside the set seen descending (proof in
// cone_map.cpp), so a piece is settled on its edges and on the edge of that set (arcs of a
// hyperbola: beside F in closed form, off its corner searched in one dimension to the
// tolerance). Where the apex height is reached on F's side and the descending set fans out
// of that point, the supremum is a limit there, taken in closed form.
// The stored ratio is always <= the exact one (safe) and, except where noted below, >= exact /
// (1 + tolerance): within 2.1e-4 of a refined brute force for both kinds, as measured
// (ConeBruteForce asserts 5e-4). Relaxed cones may keep a looser bound (still safe) where no exact treatment applies:
// a fan out of F's corner (an arc of that edge ending at the corner) and degenerate edges;
// there the conservative cone, never narrower, is searched as well and the wider of the two
// kept. A texel no higher point can see (the top of the map, a flat map) stores kConeRatioCap.
// Cost. Exact relaxed cones of smooth maps whose features span hundreds of texels cost more
// than conservative ones: every crest in reach that comes within a texel's slope of the cone
// is searched per texel, best-first (docs/benchmarks.md: 4 x 3 sine periods, about the
// conservative cones' time at 1024², 1.3x at 4096²); ConeMapOptions::exact_fans = false trades
// those texels' width for less time still (half the exact time at 4096²).
//
// Determinism. Texels are searched in fixed 4 x 4 blocks, each seeded from the block on its
// left and the one above it, which are searched first (a wavefront): the output is the same,
// byte for byte, whatever the thread count and schedule. Within the tolerance it depends on
// the search order, so it may change (within the tolerance, never wider than exact) when the
// search changes.
#pragma once

#include "meso/core/progress.hpp"
#include "meso/streams/height_field.hpp"
#include "meso/streams/height_ray.hpp"

#include <vector>

namespace meso {

enum class ConeKind { conservative, relaxed };
const char* cone_kind_name(ConeKind k);

// The largest stored ratio (units of u per unit height): "unbounded", finite in any format.
inline constexpr float kConeRatioCap = 1.0e4f;

struct ConeMapOptions {
  ConeKind kind = ConeKind::conservative;
  double tolerance = 1e-4;  // relative gap allowed between the stored and the exact ratio
  // Round what is stored to half floats, conservatively: the heights are quantised first
  // and the cones computed for the quantised surface; ratios round down, apexes up.
  bool half = false;
  // Relaxed cones: where the apex is reached on F's side and the set seen descending fans out
  // of that point, take the supremum's limit there exactly (true), or keep a safe bound and
  // the conservative cone where that is wider (false: narrower cones at those texels, as
  // before 2026-12-03, faster on smooth maps whose features span hundreds of texels;
  // docs/benchmarks.md measures both).
  bool exact_fans = true;
};

// Channels per texel: 0 = the texel's height (as read by GL_LINEAR to form S), 1 = the cone
// ratio (units of u per unit height), 2 = the apex height T_p. Metadata: the height field's
// plus quantity, kind, channels, ratio_units, texels_per_u.
// `progress` counts 4 x 4 blocks of texels as they are done.
Image build_cone_map(const HeightField& field, const ConeMapOptions& options, Progress& progress = null_progress());

// The MIP chain of a cone map (OpenGL sizes, as build_min_max_pyramid): a coarse texel takes
// the maximum height and apex and the minimum ratio of every finer texel its footprint
// overlaps, which keeps its cone safe for the union footprint (never averaged).
std::vector<Image> cone_map_levels(Image level0);

// Reference CPU tracer of a cone map (level 0), the algorithm the previewer's shaders run:
// at (x, z) over texel p, step to the boundary of the cone of apex (x, T_p); when that step
// would not leave F_p, intersect the ray exactly with S over F_p (four bilinear pieces, a
// quadratic each) and move on to the next texel. Relaxed maps bisect a step whose end is
// below the surface. Rays leaving [0, W] x [0, H] under Border::clamp miss.
HeightHit trace_cone_map(const HeightField& field, const Image& cone, ConeKind kind, const HeightRay& ray, int max_steps = 4096);

}  // namespace meso
