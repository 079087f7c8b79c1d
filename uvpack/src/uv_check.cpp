#include "meso/uvpack/uv_check.hpp"

#include "meso/core/uv_texels.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace meso {

std::vector<int> uv_charts(const Mesh& mesh, size_t* count) {
  std::vector<int> parent(mesh.n_faces());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[static_cast<size_t>(x)] != x) {
      parent[static_cast<size_t>(x)] = parent[static_cast<size_t>(parent[static_cast<size_t>(x)])];
      x = parent[static_cast<size_t>(x)];
    }
    return x;
  };
  for (auto e : mesh.edges()) {
    if (mesh.is_boundary(e) || is_uv_seam(mesh, e)) continue;
    const int a = find(mesh.face_handle(mesh.halfedge_handle(e, 0)).idx());
    const int b = find(mesh.face_handle(mesh.halfedge_handle(e, 1)).idx());
    if (a != b) parent[static_cast<size_t>(std::max(a, b))] = std::min(a, b);
  }
  std::vector<int> chart(mesh.n_faces(), -1), label(mesh.n_faces(), -1);
  int next = 0;
  for (size_t f = 0; f < mesh.n_faces(); ++f) {
    const int r = find(static_cast<int>(f));
    if (label[static_cast<size_t>(r)] < 0) label[static_cast<size_t>(r)] = next++;
    chart[f] = label[static_cast<size_t>(r)];
  }
  if (count) *count = static_cast<size_t>(next);
  return chart;
}

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
    const float area = uv_double_area(mesh, f);
    if (area == 0.0f) {
      r.degenerate_faces.push_back(f.idx());
      continue;
    }
    bool outside = false;
    for (auto h : face_halfedges(mesh, f)) {
      const Vec2f t = mesh.texcoord2D(h);
      outside |= t[0] < 0 || t[0] > 1 || t[1] < 0 || t[1] > 1;
    }
    if (outside) r.outside_faces.push_back(f.idx());
    const int c = chart[static_cast<size_t>(f.idx())];
    for_each_touched(f, [&](size_t i) {
      if (first_chart[i] < 0) first_chart[i] = c;
      else if (first_chart[i] != c) shared[i] = 1;
    });
  }
  for (auto f : mesh.faces()) {
    if (uv_double_area(mesh, f) == 0.0f) continue;
    bool overlapping = false;
    for_each_touched(f, [&](size_t i) { overlapping |= shared[i] != 0; });
    if (overlapping) r.overlapping_faces.push_back(f.idx());
  }
  r.overlay = Image(o.size, o.size, 4, 0.0f);
  for (size_t i = 0; i < n; ++i) {
    float* px = r.overlay.pixels.data() + 4 * i;
    if (shared[i]) {
      px[0] = 1; px[3] = 1;
      ++r.texels_shared;
    } else if (first_chart[i] >= 0) {
      px[2] = 1; px[3] = 0.35f;
    }
    if (first_chart[i] >= 0) ++r.texels_touched;
  }
  r.utilization = n ? static_cast<double>(r.texels_touched) / static_cast<double>(n) : 0.0;
  return r;
}

}  // namespace meso
