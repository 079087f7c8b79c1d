// Rays over a height field, shared by the streams' reference tracers (cone_map.hpp,
// pyramid.hpp) and the view-dependent displacement precomputation (vdm.hpp). Units: pixels
// of level 0 horizontally (texel centres at +0.5), normalised height vertically.
#pragma once

#include "meso/streams/height_field.hpp"

namespace meso {

// A ray over the height field: origin (x, y) in pixel units, z normalised height; direction
// in the same units, dz < 0 (descending).
struct HeightRay {
  double x = 0, y = 0, z = 1, dx = 0, dy = 0, dz = -1;
  // Bending: z(t) = z + dz t + ddz t^2. A height field laid on a surface curved by c along
  // the ray's horizontal direction sees a straight ray as this parabola, ddz = c / 2 in
  // consistent units (view-dependent displacement; positive: the surface falls away).
  double ddz = 0;
  double z_at(double t) const { return z + (dz + ddz * t) * t; }
};

struct HeightHit {
  bool hit = false;
  double t = 0;   // the first intersection is origin + t * direction
  int steps = 0;  // cone steps and footprint tests taken
};

// The first intersection of the ray with S over texel (i, j)'s footprint for t in [t0, t1]
// (the ray's horizontal path must stay within the footprint there), exact up to rounding.
bool intersect_footprint(const HeightField& field, int i, int j, const HeightRay& ray, double t0, double t1, double& t_hit);

}  // namespace meso
