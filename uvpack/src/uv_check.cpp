#include "meso/uvpack/uv_check.hpp"

#include "meso/core/uv_texels.hpp"

#include <algorithm>
#include <utility>
#include <cmath>
#include <numeric>

namespace meso {

UvCheckReport check_uv_mapping(const Mesh& mesh, const UvCheckOptions& o) {
  UvCheckReport r;
  r.width = r.height = o.size;
  const std::vector<int> chart = uv_charts(mesh, &r.charts);
  const size_t n = static_cast<size_t>(o.size) * static_cast<size_t>(o.size);
  std::vector<int> first_chart(n, -1);
  std::vector<uint8_t> shared(n, 0);

  auto for_each_touched = [&](FaceHandle f, auto&& fn) {
    for_each_touched_texel(uv_triangle_in_pixels(mesh, f, o.size, o.size), o.size, o.size, [&](int x, int y) {
      fn(static_cast<size_t>(y) * static_cast<size_t>(o.size) + static_cast<size_t>(x));
    });
  };

  for (auto f : mesh.faces()) {
    bool outside = false;
    for (auto h : face_halfedges(mesh, f)) {
      const Vec2f t = mesh.texcoord2D(h);
      outside |= t[0] < 0 || t[0] > 1 || t[1] < 0 || t[1] > 1;
    }
    if (outside) r.outside_faces.push_back(f.idx());
    if (uv_double_area(mesh, f) == 0.0f) {
      r.degenerate_faces.push_back(f.idx());
      continue;
    }
    const int c = chart[static_cast<size_t>(f.idx())];
    for_each_touched(f, [&](size_t i) {
      if (first_chart[i] < 0) first_chart[i] = c;
      else if (first_chart[i] != c) shared[i] = 1;
    });
  }
  for (auto f : mesh.faces()) {
    if (uv_double_area(mesh, f) == 0.0f) continue;
    bool shares = false;
    for_each_touched(f, [&](size_t i) { shares |= shared[i] != 0; });
    if (shares) r.shared_texel_faces.push_back(f.idx());
  }

  // Exact overlaps and padding.
  UvOverlapReport exact = find_uv_overlaps(mesh, chart, o.size, o.padding);
  r.overlap_pairs = std::move(exact.overlap_pairs);
  r.padding_violations = std::move(exact.padding_violations);
  for (const auto& [a, b] : r.overlap_pairs) {
    r.overlapping_faces.push_back(a);
    r.overlapping_faces.push_back(b);
  }
  std::sort(r.overlapping_faces.begin(), r.overlapping_faces.end());
  r.overlapping_faces.erase(std::unique(r.overlapping_faces.begin(), r.overlapping_faces.end()), r.overlapping_faces.end());

  // Winding per chart, and texel density: UV area (texels^2) against surface area.
  std::vector<double> signed_area(r.charts, 0.0), uv_area(r.charts, 0.0), surface_area(r.charts, 0.0);
  for (auto f : mesh.faces()) {
    const size_t c = static_cast<size_t>(chart[static_cast<size_t>(f.idx())]);
    const double a = uv_double_area(mesh, f);
    signed_area[c] += a;
    uv_area[c] += std::abs(a) * 0.5 * o.size * o.size;
    const auto hs = face_halfedges(mesh, f);
    const Vec3f p0 = mesh.point(mesh.to_vertex_handle(hs[0])), p1 = mesh.point(mesh.to_vertex_handle(hs[1])),
                p2 = mesh.point(mesh.to_vertex_handle(hs[2]));
    surface_area[c] += 0.5 * static_cast<double>(OpenMesh::cross(p1 - p0, p2 - p0).norm());
  }
  for (auto f : mesh.faces()) {
    const double a = uv_double_area(mesh, f);
    const double chart_sign = signed_area[static_cast<size_t>(chart[static_cast<size_t>(f.idx())])];
    if (a != 0 && chart_sign != 0 && (a > 0) != (chart_sign > 0)) r.flipped_faces.push_back(f.idx());
  }
  for (size_t c = 0; c < r.charts; ++c) {
    if (surface_area[c] > 0) r.texel_density.push_back({static_cast<int>(c), std::sqrt(uv_area[c] / surface_area[c])});
  }
  if (o.overlay) r.overlay = Image(o.size, o.size, 4, 0.0f);
  for (size_t i = 0; i < n; ++i) {
    r.texels_shared += shared[i];
    r.texels_touched += first_chart[i] >= 0;
    if (!o.overlay) continue;
    float* px = r.overlay.pixels.data() + 4 * i;
    if (shared[i]) {
      px[0] = 1;
      px[3] = 1;
    } else if (first_chart[i] >= 0) {
      px[2] = 1;
      px[3] = 0.35f;
    }
  }
  r.utilization = n ? static_cast<double>(r.texels_touched) / static_cast<double>(n) : 0.0;
  return r;
}

}  // namespace meso
