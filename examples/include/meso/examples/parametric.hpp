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

// A torus (major radius 1, minor 0.35) with a gentle smooth wave on the tube, named "torus":
// smooth everywhere, curvature varying; UV = (s, t) with seams where s and t wrap. The
// meshreduce bench's and tests' smooth surface.
Mesh make_smooth_torus(int columns, int rows);

}  // namespace meso
