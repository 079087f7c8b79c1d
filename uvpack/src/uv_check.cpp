#include "meso/uvpack/uv_check.hpp"

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

namespace {

// Separating-axis test between a triangle and an axis-aligned box, both closed sets
// shrunk to their interiors: true when they share interior points.
bool triangle_overlaps_box(const double (&px)[3], const double (&py)[3], double x0, double y0, double x1, double y1) {
  if (std::max({px[0], px[1], px[2]}) <= x0 || std::min({px[0], px[1], px[2]}) >= x1) return false;
  if (std::max({py[0], py[1], py[2]}) <= y0 || std::min({py[0], py[1], py[2]}) >= y1) return false;
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    // Edge normal, oriented toward the third vertex.
    double nx = py[j] - py[i], ny = px[i] - px[j];
    const double side_k = nx * (px[k] - px[i]) + ny * (py[k] - py[i]);
    if (side_k < 0) {
      nx = -nx;
      ny = -ny;
    }
    // The box's farthest corner along the normal must be strictly inside the edge's half-plane.
    const double bx = nx > 0 ? x1 : x0, by = ny > 0 ? y1 : y0;
    if (nx * (bx - px[i]) + ny * (by - py[i]) <= 0) return false;
  }
  return true;
}

}  // namespace

UvCheckReport check_uv_mapping(const Mesh& mesh, const UvCheckOptions& o) {
  UvCheckReport r;
  r.width = r.height = o.size;
  const std::vector<int> chart = uv_charts(mesh, &r.charts);
  const size_t n = static_cast<size_t>(o.size) * static_cast<size_t>(o.size);
  std::vector<int> first_chart(n, -1);
  std::vector<uint8_t> shared(n, 0);

  auto for_each_touched = [&](FaceHandle f, auto&& fn) {
    const auto hs = face_halfedges(mesh, f);
    double px[3], py[3];
    for (int i = 0; i < 3; ++i) {
      const Vec2f t = mesh.texcoord2D(hs[static_cast<size_t>(i)]);
      px[i] = uv_to_pixel_x(t[0], o.size);
      py[i] = uv_to_pixel_y(t[1], o.size);
    }
    int x0, x1, y0, y1;
    if (!texels_touching(std::min({px[0], px[1], px[2]}), std::max({px[0], px[1], px[2]}), o.size, x0, x1)) return;
    if (!texels_touching(std::min({py[0], py[1], py[2]}), std::max({py[0], py[1], py[2]}), o.size, y0, y1)) return;
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x)
        if (triangle_overlaps_box(px, py, x, y, x + 1, y + 1)) fn(static_cast<size_t>(y) * static_cast<size_t>(o.size) + static_cast<size_t>(x));
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
