// The one translation unit of uvpack that includes CGAL (compile time).
#include "meso/uvpack/uv_overlaps.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/box_intersection_d.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

namespace meso {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_2;
using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 2, int>;

std::array<Point, 3> uv_points(const Mesh& mesh, FaceHandle f) {
  const auto hs = face_halfedges(mesh, f);
  std::array<Point, 3> p;
  for (size_t i = 0; i < 3; ++i) {
    const Vec2f t = mesh.texcoord2D(hs[i]);
    p[i] = Point(t[0], t[1]);  // float -> double is exact
  }
  return p;
}

// Interiors of two non-degenerate triangles intersect iff no edge line of either triangle
// has the other triangle entirely on its closed outer side (separating axis theorem; for
// triangles a separating line can be taken through an edge). Exact orientation predicates.
bool separated_by_an_edge_of(const std::array<Point, 3>& t, const std::array<Point, 3>& other) {
  const auto o = CGAL::orientation(t[0], t[1], t[2]);
  for (int i = 0; i < 3; ++i) {
    const Point& p = t[static_cast<size_t>(i)];
    const Point& q = t[static_cast<size_t>((i + 1) % 3)];
    bool outside = true;
    for (const Point& v : other) {
      if (CGAL::orientation(p, q, v) == o) {
        outside = false;
        break;
      }
    }
    if (outside) return true;
  }
  return false;
}

bool interiors_overlap(const std::array<Point, 3>& a, const std::array<Point, 3>& b) {
  return !separated_by_an_edge_of(a, b) && !separated_by_an_edge_of(b, a);
}

double point_segment_distance(double px, double py, double ax, double ay, double bx, double by) {
  const double ex = bx - ax, ey = by - ay, len2 = ex * ex + ey * ey;
  const double s = len2 > 0 ? std::clamp(((px - ax) * ex + (py - ay) * ey) / len2, 0.0, 1.0) : 0.0;
  return std::hypot(ax + s * ex - px, ay + s * ey - py);
}

// Closest approach of two triangles that do not overlap: a vertex of one to an edge of the
// other. In texels: UVs scaled by the texture size.
double triangle_distance(const std::array<Point, 3>& a, const std::array<Point, 3>& b, double size) {
  double best = INFINITY;
  for (int pass = 0; pass < 2; ++pass) {
    const auto& s = pass ? b : a;
    const auto& t = pass ? a : b;
    for (const Point& v : s)
      for (size_t i = 0; i < 3; ++i) {
        const Point& p = t[i];
        const Point& q = t[(i + 1) % 3];
        best = std::min(best, point_segment_distance(v.x() * size, v.y() * size, p.x() * size, p.y() * size, q.x() * size, q.y() * size));
      }
  }
  return best;
}

}  // namespace

UvOverlapReport find_uv_overlaps(const Mesh& mesh, const std::vector<int>& chart, int size, double padding_texels, bool wrap) {
  UvOverlapReport r;
  std::vector<std::array<Point, 3>> tri(mesh.n_faces());
  // Each box is a face, as stored or (wrap) moved by a whole texture: `copies` holds
  // (face, shift), shift 4 = (0, 0), else 3 (dv + 1) + (du + 1).
  std::vector<Box> boxes;
  std::vector<std::pair<int, int>> copies;
  boxes.reserve(mesh.n_faces());
  constexpr int kUnmoved = 4;
  // Boxes grown by half the padding (in UV units), so charts closer than it meet.
  const double grow = padding_texels > 0 ? 0.5 * padding_texels / size : 0.0;
  for (auto f : mesh.faces()) {
    if (uv_double_area(mesh, f) == 0.0) continue;
    const size_t i = static_cast<size_t>(f.idx());
    tri[i] = uv_points(mesh, f);
    const CGAL::Bbox_2 b = tri[i][0].bbox() + tri[i][1].bbox() + tri[i][2].bbox();
    for (int shift = 0; shift < 9; ++shift) {
      if (shift != kUnmoved && !(wrap && padding_texels > 0)) continue;
      const double du = shift % 3 - 1, dv = shift / 3 - 1;
      const CGAL::Bbox_2 moved(b.xmin() + du - grow, b.ymin() + dv - grow, b.xmax() + du + grow, b.ymax() + dv + grow);
      // A moved copy only matters where it comes near the texture (where the faces are).
      if (shift != kUnmoved && (moved.xmax() < -grow || moved.xmin() > 1 + grow || moved.ymax() < -grow || moved.ymin() > 1 + grow))
        continue;
      boxes.emplace_back(moved, static_cast<int>(copies.size()));
      copies.emplace_back(f.idx(), shift);
    }
  }
  std::map<std::pair<int, int>, double> gaps;
  CGAL::box_self_intersection_d(boxes.begin(), boxes.end(), [&](const Box& ba, const Box& bb) {
    auto [fa, sa] = copies[static_cast<size_t>(ba.info())];
    auto [fb, sb] = copies[static_cast<size_t>(bb.info())];
    // Pairs of two moved copies are the pair of one unmoved face and the other moved by the
    // difference, which comes in on its own where it is near the texture.
    if (sa != kUnmoved && sb != kUnmoved) return;
    if (sa != kUnmoved) std::swap(fa, fb), std::swap(sa, sb);  // fb the moved one, if any
    const bool across = sb != kUnmoved;
    if (!across && fa > fb) std::swap(fa, fb);
    const auto& ta = tri[static_cast<size_t>(fa)];
    std::array<Point, 3> tb = tri[static_cast<size_t>(fb)];
    if (across)
      // In double: exact for a float UV unless it is below 2^-29 in magnitude (then within 2^-53).
      for (Point& p : tb) p = Point(p.x() + (sb % 3 - 1), p.y() + (sb / 3 - 1));
    const bool overlap = interiors_overlap(ta, tb);
    if (overlap && !across) r.overlap_pairs.emplace_back(fa, fb);
    int ca = chart[static_cast<size_t>(fa)], cb = chart[static_cast<size_t>(fb)];
    if (padding_texels <= 0 || (ca == cb && !across)) return;
    const double d = overlap ? 0.0 : triangle_distance(ta, tb, size);
    if (d >= padding_texels) return;
    if (ca > cb) std::swap(ca, cb);
    auto [it, inserted] = gaps.try_emplace({ca, cb}, d);
    if (!inserted) it->second = std::min(it->second, d);
  });
  // The broad phase reports pairs in an order that depends on its internal sorting: sort.
  std::sort(r.overlap_pairs.begin(), r.overlap_pairs.end());
  for (const auto& [k, d] : gaps) r.padding_violations.push_back({k.first, k.second, d});
  return r;
}

}  // namespace meso
