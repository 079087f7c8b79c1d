// Grouping the faces of a reduced mesh that are farther from the input than a threshold into
// connected regions, for the report: where the base mesh fails the bake's assumption that it
// stays close to the high mesh.
#include "meso/meshreduce/surface_distance.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace meso {

std::vector<ErrorRegion> error_regions(const Mesh& b, const std::vector<double>& face_distance, double threshold) {
  // Distances below the float resolution of b's coordinates are rounding (an unreduced mesh
  // measures about 1e-16 from itself), not departures: `--error 0` must not report them.
  float largest = 0;
  for (auto v : b.vertices())
    for (int k = 0; k < 3; ++k) largest = std::max(largest, std::abs(b.point(v)[k]));
  threshold = std::max(threshold, static_cast<double>(std::numeric_limits<float>::epsilon()) * largest);
  std::vector<ErrorRegion> regions;
  std::vector<int> region_of(b.n_faces(), -1);
  std::vector<int> stack;
  for (auto seed : b.faces()) {
    const size_t s = static_cast<size_t>(seed.idx());
    if (s >= face_distance.size() || !(face_distance[s] > threshold) || region_of[s] >= 0) continue;
    // Faces in increasing index order seed regions, so first_face is the seed.
    ErrorRegion r;
    r.first_face = seed.idx();
    const int id = static_cast<int>(regions.size());
    double cx = 0, cy = 0, cz = 0;
    region_of[s] = id;
    stack.assign(1, seed.idx());
    while (!stack.empty()) {
      const FaceHandle f(stack.back());
      stack.pop_back();
      const size_t fi = static_cast<size_t>(f.idx());
      ++r.faces;
      r.max_distance = std::max(r.max_distance, face_distance[fi]);
      const auto hs = face_halfedges(b, f);
      const Vec3f p0 = b.point(b.to_vertex_handle(hs[0])), p1 = b.point(b.to_vertex_handle(hs[1])), p2 = b.point(b.to_vertex_handle(hs[2]));
      const double area = face_area(b, f);
      const Vec3f c = (p0 + p1 + p2) / 3.0f;
      r.area += area;
      cx += area * c[0];
      cy += area * c[1];
      cz += area * c[2];
      for (auto h : hs) {
        const auto g = b.opposite_face_handle(h);
        if (!g.is_valid()) continue;
        const size_t gi = static_cast<size_t>(g.idx());
        if (region_of[gi] < 0 && face_distance[gi] > threshold) {
          region_of[gi] = id;
          stack.push_back(g.idx());
        }
      }
    }
    if (r.area > 0) r.centroid = Vec3f(static_cast<float>(cx / r.area), static_cast<float>(cy / r.area), static_cast<float>(cz / r.area));
    regions.push_back(r);
  }
  std::stable_sort(regions.begin(), regions.end(), [](const ErrorRegion& x, const ErrorRegion& y) { return x.max_distance > y.max_distance; });
  return regions;
}

}  // namespace meso
