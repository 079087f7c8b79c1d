// Meshes of parametric surfaces, for tests, benchmarks and examples.
#pragma once

#include "meso/core/mesh.hpp"

#include <functional>
#include <string>

namespace meso {

// A (columns x rows)-quad grid mapped through surface(s, t), s, t in [0, 1], two triangles
// per quad, UV = (s, t). With wrap_s (wrap_t) the last column (row) of vertices is the first
// one again (a closed surface; UVs then have a seam there). One face group named `name`;
// angle-weighted vertex normals.
Mesh make_parametric_surface(int columns, int rows, const std::function<Vec3f(double, double)>& surface, bool wrap_s, bool wrap_t,
                             const std::string& name = "surface");

// A closed surface of revolution about z on a UV grid with its poles: point(theta, phi) at
// polar angle theta in [0, pi] (0: the south pole) and azimuth phi in [0, 2 pi). Each pole is
// one vertex (the first and the last), joined to all `columns` vertices of the first ring of
// latitude; the other vertices lie on a triangulated grid of `rows` - 1 rings (valence 6, 5
// on the rings next to the poles). Wound counter-clockwise seen from outside for a point()
// like the sphere's (r sin theta cos phi, r sin theta sin phi, -r cos theta); no UVs;
// angle-weighted normals. Needs columns >= 3 and rows >= 2 (std::invalid_argument).
Mesh make_surface_with_poles(int columns, int rows, const std::function<Vec3f(double, double)>& point);

// A torus (major radius 1, minor 0.35) with a gentle smooth wave on the tube, named "torus":
// smooth everywhere, curvature varying; UV = (s, t) with seams where s and t wrap. The
// meshreduce bench's and tests' smooth surface.
Mesh make_smooth_torus(int columns, int rows);

}  // namespace meso
