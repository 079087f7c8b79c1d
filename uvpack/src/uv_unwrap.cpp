// Charting and parameterisation (uv_unwrap.hpp). The one translation unit of uvpack that
// includes CGAL's Surface_mesh_parameterization (compile time; uv_overlaps.cpp has the
// predicates).
//
// Each chart is copied into a small CGAL::Surface_mesh before flattening rather than cut
// in place with a Seam_mesh over meso::Mesh: the copy makes a chart's corners that meet
// only at a vertex (a "bow tie") separate vertices, so the disk test is a plain Euler
// characteristic, and charts share no mutable state, so they are flattened in parallel.
// Seams stay exact: UVs go back on meso::Mesh's halfedges, one UV per chart corner.
#include "meso/uvpack/uv_unwrap.hpp"

#include "meso/uvpack/uv_overlaps.hpp"

#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_parameterization/ARAP_parameterizer_3.h>
#include <CGAL/Surface_mesh_parameterization/LSCM_parameterizer_3.h>
#include <CGAL/Surface_mesh_parameterization/Two_vertices_parameterizer_3.h>
#include <CGAL/Surface_mesh_parameterization/parameterize.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <exception>
#include <limits>
#include <numeric>
#include <queue>
#include <utility>
#include <vector>

namespace meso {

namespace {

using Vec3d = OpenMesh::Vec3d;
using Kernel = CGAL::Simple_cartesian<double>;
using ChartMesh = CGAL::Surface_mesh<Kernel::Point_3>;
namespace SMP = CGAL::Surface_mesh_parameterization;

// The mesh as flat arrays, read-only while charts are flattened. Corner c = 3f + k is the
// to-vertex of face f's k-th halfedge (face_halfedges() order), as meso::Mesh stores UVs.
struct Geometry {
  std::vector<HalfedgeHandle> corner_halfedge;
  std::vector<int> corner_vertex;
  std::vector<int> corner_opposite;  // corner of the opposite halfedge in its face, -1 on the border
  std::vector<Vec3d> position;
  std::vector<Vec3d> normal;         // unit; zero for degenerate faces
  std::vector<double> area;
  std::vector<uint8_t> degenerate;
  // Positions are the mesh's, centred on its bounding box and scaled by a power of two that
  // brings the box's longest side into [0.5, 1): the flattening and its tests then see one
  // size whatever the units (ARAP at 1e4 units lost 4 % utilisation and stretched 1.3x, at
  // 1e15 half the utilisation). Areas reported in object units are divided by unit^2.
  double unit = 1;
  size_t faces() const { return area.size(); }
};

Geometry make_geometry(const Mesh& mesh) {
  Geometry g;
  const size_t nf = mesh.n_faces();
  g.corner_halfedge.resize(3 * nf);
  g.corner_vertex.resize(3 * nf);
  g.corner_opposite.assign(3 * nf, -1);
  g.normal.assign(nf, Vec3d(0, 0, 0));
  g.area.assign(nf, 0);
  g.degenerate.assign(nf, 0);
  g.position.resize(mesh.n_vertices());
  const Box3 box = bounding_box(mesh);
  const Vec3d centre = (Vec3d(box.lo[0], box.lo[1], box.lo[2]) + Vec3d(box.hi[0], box.hi[1], box.hi[2])) * 0.5;
  const double side = std::max({double(box.hi[0]) - box.lo[0], double(box.hi[1]) - box.lo[1], double(box.hi[2]) - box.lo[2]});
  if (side > 0 && std::isfinite(side)) g.unit = std::ldexp(1.0, -(std::ilogb(side) + 1));
  for (auto v : mesh.vertices()) {
    const Vec3f p = mesh.point(v);
    g.position[static_cast<size_t>(v.idx())] = (Vec3d(p[0], p[1], p[2]) - centre) * g.unit;
  }
  std::vector<int> corner_of_halfedge(mesh.n_halfedges(), -1);
  for (auto f : mesh.faces()) {
    const auto hs = face_halfedges(mesh, f);
    for (size_t k = 0; k < 3; ++k) {
      const size_t c = 3 * static_cast<size_t>(f.idx()) + k;
      g.corner_halfedge[c] = hs[k];
      g.corner_vertex[c] = mesh.to_vertex_handle(hs[k]).idx();
      corner_of_halfedge[static_cast<size_t>(hs[k].idx())] = static_cast<int>(c);
    }
  }
  for (size_t c = 0; c < 3 * nf; ++c) {
    const HalfedgeHandle o = mesh.opposite_halfedge_handle(g.corner_halfedge[c]);
    if (!mesh.is_boundary(o)) g.corner_opposite[c] = corner_of_halfedge[static_cast<size_t>(o.idx())];
  }
  for (size_t f = 0; f < nf; ++f) {
    const Vec3d& a = g.position[static_cast<size_t>(g.corner_vertex[3 * f])];
    const Vec3d& b = g.position[static_cast<size_t>(g.corner_vertex[3 * f + 1])];
    const Vec3d& c = g.position[static_cast<size_t>(g.corner_vertex[3 * f + 2])];
    const Vec3d n = OpenMesh::cross(b - a, c - a);
    const double len = n.norm();
    const double longest = std::max({(b - a).sqrnorm(), (c - b).sqrnorm(), (a - c).sqrnorm()});
    g.area[f] = 0.5 * len;
    // A triangle whose sine of its largest angle is below 1e-12 has no usable plane: LSCM's
    // per-triangle frame would be NaN. Such faces are charts of their own.
    // They count as zero area (their UVs are too).
    if (!std::isfinite(len) || !(len > 1e-12 * longest)) {
      g.degenerate[f] = 1;
      g.area[f] = 0;
      continue;
    }
    g.normal[f] = n / len;
  }
  return g;
}

constexpr int prev_corner(int c) { return c - c % 3 + (c % 3 + 2) % 3; }

// Region growing by normal cone: from the first unassigned face (face order, so the result
// is deterministic), faces join while their normal is within max_chart_angle of the
// chart's area-weighted mean normal, most aligned first. Degenerate faces are charts alone.
std::vector<std::vector<int>> grow_charts(const Geometry& g, const UvUnwrapOptions& o) {
  const size_t nf = g.faces();
  const double cos_max = std::cos(o.max_chart_angle * M_PI / 180.0);
  const size_t cap = o.max_chart_faces > 0 ? static_cast<size_t>(o.max_chart_faces) : nf;
  std::vector<int> owner(nf, -1);
  std::vector<std::vector<int>> charts;
  using Entry = std::pair<double, int>;  // (-alignment at push time, face): smallest first
  for (size_t seed = 0; seed < nf; ++seed) {
    if (owner[seed] >= 0) continue;
    const int id = static_cast<int>(charts.size());
    charts.push_back({static_cast<int>(seed)});
    owner[seed] = id;
    if (g.degenerate[seed]) continue;
    std::vector<int>& faces = charts.back();
    Vec3d sum = g.normal[seed] * g.area[seed];
    std::priority_queue<Entry, std::vector<Entry>, std::greater<>> heap;
    auto push_neighbours = [&](int f) {
      const Vec3d mean = sum.normalized();
      for (int k = 0; k < 3; ++k) {
        const int o_c = g.corner_opposite[static_cast<size_t>(3 * f + k)];
        if (o_c < 0) continue;
        const int nb = o_c / 3;
        if (owner[static_cast<size_t>(nb)] >= 0 || g.degenerate[static_cast<size_t>(nb)]) continue;
        heap.emplace(-OpenMesh::dot(g.normal[static_cast<size_t>(nb)], mean), nb);
      }
    };
    push_neighbours(static_cast<int>(seed));
    while (!heap.empty() && faces.size() < cap) {
      const int f = heap.top().second;
      heap.pop();
      if (owner[static_cast<size_t>(f)] >= 0) continue;
      // The mean has moved since the push: test against the current one.
      if (OpenMesh::dot(g.normal[static_cast<size_t>(f)], sum.normalized()) < cos_max) continue;
      owner[static_cast<size_t>(f)] = id;
      faces.push_back(f);
      sum += g.normal[static_cast<size_t>(f)] * g.area[static_cast<size_t>(f)];
      push_neighbours(f);
    }
  }
  return charts;
}

struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[static_cast<size_t>(x)] != x) {
      parent[static_cast<size_t>(x)] = parent[static_cast<size_t>(parent[static_cast<size_t>(x)])];
      x = parent[static_cast<size_t>(x)];
    }
    return x;
  }
  void unite(int a, int b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[static_cast<size_t>(std::max(a, b))] = std::min(a, b);
  }
};

enum class Outcome { done, topology, stretch, overlap, failure };

// A flattened chart: 3 UVs per face (in `faces` order), scaled so that its UV area equals
// its surface area, and its distortion.
struct FlatChart {
  std::vector<int> faces;
  std::vector<std::array<double, 2>> uv;
  UnwrapChart stats;
  double angle_sum = 0, angle_max = 1, area_sum = 0;  // area-weighted sums over faces
  double lo[2] = {0, 0}, hi[2] = {0, 0};
};

// Scales the chart to its surface area, fixes its orientation and measures it. False when a
// face with surface area maps to zero or negative UV area (a fold).
bool measure(const Geometry& g, FlatChart& c) {
  double area3 = 0, area_uv = 0;
  const size_t n = c.faces.size();
  auto uv_area = [&](size_t i) {
    const auto& a = c.uv[3 * i];
    const auto& b = c.uv[3 * i + 1];
    const auto& d = c.uv[3 * i + 2];
    return 0.5 * ((b[0] - a[0]) * (d[1] - a[1]) - (b[1] - a[1]) * (d[0] - a[0]));
  };
  for (size_t i = 0; i < n; ++i) {
    area3 += g.area[static_cast<size_t>(c.faces[i])];
    area_uv += uv_area(i);
  }
  if (!std::isfinite(area_uv)) return false;
  // LSCM/ARAP may return the mirror image: make UVs counter-clockwise where faces are.
  const double mirror = area_uv < 0 ? -1.0 : 1.0;
  const double s = area_uv != 0 ? std::sqrt(area3 / std::abs(area_uv)) : 1.0;
  for (auto& p : c.uv) {
    p[0] *= s * mirror;
    p[1] *= s;
  }
  c.stats = UnwrapChart{};
  c.stats.faces = static_cast<int>(n);
  c.stats.area = area3;
  double l2_sum = 0;
  c.angle_sum = c.area_sum = 0;
  c.angle_max = 1;
  for (size_t i = 0; i < n; ++i) {
    const size_t f = static_cast<size_t>(c.faces[i]);
    const double a3 = g.area[f];
    const double auv = uv_area(i);
    if (a3 == 0) continue;  // degenerate, alone in its chart
    if (!(auv > 0)) return false;
    // Sander et al. 2001: S_s, S_t are the partial derivatives of the surface point with
    // respect to the texture coordinates; Γ, γ the singular values of [S_s S_t].
    const Vec3d& q1 = g.position[static_cast<size_t>(g.corner_vertex[3 * f])];
    const Vec3d& q2 = g.position[static_cast<size_t>(g.corner_vertex[3 * f + 1])];
    const Vec3d& q3 = g.position[static_cast<size_t>(g.corner_vertex[3 * f + 2])];
    const auto& p1 = c.uv[3 * i];
    const auto& p2 = c.uv[3 * i + 1];
    const auto& p3 = c.uv[3 * i + 2];
    const Vec3d ss = (q1 * (p2[1] - p3[1]) + q2 * (p3[1] - p1[1]) + q3 * (p1[1] - p2[1])) / (2 * auv);
    const Vec3d st = (q1 * (p3[0] - p2[0]) + q2 * (p1[0] - p3[0]) + q3 * (p2[0] - p1[0])) / (2 * auv);
    const double a = OpenMesh::dot(ss, ss), b = OpenMesh::dot(ss, st), d = OpenMesh::dot(st, st);
    const double root = std::sqrt((a - d) * (a - d) + 4 * b * b);
    const double big = std::sqrt(std::max(0.0, 0.5 * (a + d + root)));
    const double small = std::sqrt(std::max(0.0, 0.5 * (a + d - root)));
    l2_sum += a3 * 0.5 * (a + d);
    c.stats.stretch_linf = std::max(c.stats.stretch_linf, big);
    const double angle = small > 0 ? big / small : std::numeric_limits<double>::infinity();
    c.angle_sum += a3 * angle;
    c.angle_max = std::max(c.angle_max, angle);
    const double r = auv / a3;
    c.area_sum += a3 * std::max(r, 1 / r);
  }
  c.stats.stretch_l2 = area3 > 0 ? std::sqrt(l2_sum / area3) : 1.0;
  // Planar charts come out isometric up to rounding; do not report 0.9999999 as below 1.
  if (area3 > 0) c.stats.stretch_l2 = std::max(1.0, c.stats.stretch_l2);
  if (area3 == 0) c.area_sum = c.angle_sum = 0;
  return std::isfinite(c.stats.stretch_l2);
}

// LSCM and ARAP leave no triangle flipped here (measure() checked) but a chart's border may
// still run over itself. Exact test (uv_overlaps.hpp) on the chart alone, as a triangle
// soup at its own origin (the most float precision): interiors meeting, adjacency aside.
bool overlaps_itself(const FlatChart& c) {
  double lo[2] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  for (const auto& p : c.uv)
    for (size_t a = 0; a < 2; ++a) lo[a] = std::min(lo[a], p[a]);
  Mesh soup;
  soup.request_halfedge_texcoords2D();
  const size_t n = c.faces.size();
  for (size_t i = 0; i < n; ++i) {
    std::array<VertexHandle, 3> v;
    for (size_t k = 0; k < 3; ++k) v[k] = soup.add_vertex(Vec3f(0, 0, 0));
    const FaceHandle f = soup.add_face(v[0], v[1], v[2]);
    const auto hs = face_halfedges(soup, f);
    for (size_t k = 0; k < 3; ++k) {
      const auto& p = c.uv[3 * i + k];
      soup.set_texcoord2D(hs[k], Vec2f(static_cast<float>(p[0] - lo[0]), static_cast<float>(p[1] - lo[1])));
    }
  }
  return !find_uv_overlaps(soup, std::vector<int>(n, 0), 1, 0.0).overlap_pairs.empty();
}

// One triangle mapped isometrically (a degenerate one onto a segment or a point).
void flatten_single(const Geometry& g, FlatChart& c) {
  const size_t f = static_cast<size_t>(c.faces[0]);
  const Vec3d& a = g.position[static_cast<size_t>(g.corner_vertex[3 * f])];
  const Vec3d& b = g.position[static_cast<size_t>(g.corner_vertex[3 * f + 1])];
  const Vec3d& d = g.position[static_cast<size_t>(g.corner_vertex[3 * f + 2])];
  const Vec3d e1 = b - a, e2 = d - a;
  const double l1 = e1.norm();
  c.uv.assign(3, {0.0, 0.0});
  if (l1 > 0) {
    const Vec3d x = e1 / l1;
    c.uv[1] = {l1, 0.0};
    c.uv[2] = {OpenMesh::dot(e2, x), OpenMesh::cross(e1, e2).norm() / l1};
  } else {
    c.uv[2] = {e2.norm(), 0.0};
  }
  measure(g, c);
}

// Flattens one chart with CGAL. `local` gives, for every face of this chart, its index in
// c.faces; `owner` which work item a face belongs to (faces of other charts are cut).
Outcome flatten(const Geometry& g, const std::vector<int>& owner, const std::vector<int>& local, int id, UnwrapMethod method,
                double max_stretch, FlatChart& c) {
  const size_t n = c.faces.size();
  if (n == 1) {
    flatten_single(g, c);
    return Outcome::done;
  }
  // Chart vertices: corners glued across the chart's inner edges. A mesh vertex where the
  // chart meets itself only at that vertex becomes two chart vertices (one per fan).
  UnionFind uf(3 * n);
  size_t border = 0;
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      const int gc = 3 * c.faces[i] + k;
      const int go = g.corner_opposite[static_cast<size_t>(gc)];
      if (go < 0 || owner[static_cast<size_t>(go / 3)] != id) {
        ++border;
        continue;
      }
      const int lc = static_cast<int>(3 * i) + k;
      const int lo = 3 * local[static_cast<size_t>(go / 3)] + go % 3;
      uf.unite(lc, prev_corner(lo));   // both at this halfedge's to-vertex
      uf.unite(prev_corner(lc), lo);   // both at its from-vertex
    }
  }
  std::vector<int> vertex_of(3 * n, -1), root_vertex(3 * n, -1);
  int nv = 0;
  std::vector<int> first_corner;
  for (size_t lc = 0; lc < 3 * n; ++lc) {
    const int r = uf.find(static_cast<int>(lc));
    if (root_vertex[static_cast<size_t>(r)] < 0) {
      root_vertex[static_cast<size_t>(r)] = nv++;
      first_corner.push_back(static_cast<int>(lc));
    }
    vertex_of[lc] = root_vertex[static_cast<size_t>(r)];
  }
  // The chart is edge-connected (grown or split over edges) and its edges have at most two
  // faces, so it is a disk exactly when V - E + F = 1 (a connected orientable surface has
  // 2 - 2 genus - boundaries). LSCM and ARAP need a disk.
  const long edges = static_cast<long>((3 * n + border) / 2);
  if (static_cast<long>(nv) - edges + static_cast<long>(n) != 1) return Outcome::topology;

  ChartMesh sm;
  sm.reserve(static_cast<ChartMesh::size_type>(nv), static_cast<ChartMesh::size_type>(edges), static_cast<ChartMesh::size_type>(n));
  for (int v = 0; v < nv; ++v) {
    const int gc = 3 * c.faces[static_cast<size_t>(first_corner[static_cast<size_t>(v)] / 3)] + first_corner[static_cast<size_t>(v)] % 3;
    const Vec3d& p = g.position[static_cast<size_t>(g.corner_vertex[static_cast<size_t>(gc)])];
    sm.add_vertex(Kernel::Point_3(p[0], p[1], p[2]));
  }
  for (size_t i = 0; i < n; ++i) {
    const auto f = sm.add_face(ChartMesh::Vertex_index(static_cast<ChartMesh::size_type>(vertex_of[3 * i])),
                               ChartMesh::Vertex_index(static_cast<ChartMesh::size_type>(vertex_of[3 * i + 1])),
                               ChartMesh::Vertex_index(static_cast<ChartMesh::size_type>(vertex_of[3 * i + 2])));
    if (f == ChartMesh::null_face()) return Outcome::failure;
  }
  ChartMesh::Halfedge_index border_halfedge;
  for (auto h : sm.halfedges()) {
    if (sm.is_border(h)) {
      border_halfedge = h;
      break;
    }
  }
  if (border_halfedge == ChartMesh::null_halfedge()) return Outcome::topology;
  auto uvmap = sm.add_property_map<ChartMesh::Vertex_index, Kernel::Point_2>("v:uv", Kernel::Point_2(0, 0)).first;
  auto solve = [&](UnwrapMethod m) {
    try {
      if (m == UnwrapMethod::arap) {
        // λ = 1000 (CGAL's default): shape preservation weighs far above angles. CGAL
        // starts the iterations from mean-value coordinates on a circle (one border).
        SMP::ARAP_parameterizer_3<ChartMesh> arap;
        return SMP::parameterize(sm, arap, border_halfedge, uvmap);
      }
      // Two pinned vertices (the chart's extremes) fix LSCM's similarity freedom; the
      // border is free (Lévy et al. 2002, section 3.3).
      SMP::LSCM_parameterizer_3<ChartMesh, SMP::Two_vertices_parameterizer_3<ChartMesh>> lscm;
      return SMP::parameterize(sm, lscm, border_halfedge, uvmap);
    } catch (const std::exception&) {  // CGAL's precondition checks, when enabled
      return SMP::ERROR_CANNOT_SOLVE_LINEAR_SYSTEM;
    }
  };
  auto solved = [&](UnwrapMethod m) {
    if (solve(m) != SMP::OK) return false;
    c.uv.resize(3 * n);
    for (size_t lc = 0; lc < 3 * n; ++lc) {
      const Kernel::Point_2& p = uvmap[ChartMesh::Vertex_index(static_cast<ChartMesh::size_type>(vertex_of[lc]))];
      if (!std::isfinite(p.x()) || !std::isfinite(p.y())) return false;
      c.uv[lc] = {p.x(), p.y()};
    }
    return true;
  };
  // ARAP's mean-value start needs interior vertices (a strip of triangles has none; CGAL
  // then returns NaNs): LSCM gives such a chart instead.
  if (!solved(method) && !(method == UnwrapMethod::arap && solved(UnwrapMethod::lscm))) return Outcome::failure;
  if (!measure(g, c)) return Outcome::stretch;
  if (c.stats.stretch_l2 > max_stretch) return Outcome::stretch;
  if (overlaps_itself(c)) return Outcome::overlap;
  return Outcome::done;
}

// Splits an edge-connected chart into two edge-connected parts: the two faces farthest
// apart (double sweep of breadth-first search over face adjacency) grow at the same pace,
// each face going to the one that reaches it first. `mark` is scratch of one int per mesh
// face, all -1 on entry and on return.
std::array<std::vector<int>, 2> split_in_two(const Geometry& g, const std::vector<int>& faces, std::vector<int>& mark) {
  const size_t n = faces.size();
  for (size_t i = 0; i < n; ++i) mark[static_cast<size_t>(faces[i])] = static_cast<int>(i);
  std::vector<int> label(n);
  std::vector<int> queue;
  queue.reserve(n);
  auto sweep = [&](std::vector<int> sources) {
    std::fill(label.begin(), label.end(), -1);
    queue.clear();
    for (size_t s = 0; s < sources.size(); ++s) {
      label[static_cast<size_t>(sources[s])] = static_cast<int>(s);
      queue.push_back(sources[s]);
    }
    for (size_t head = 0; head < queue.size(); ++head) {
      const int i = queue[head];
      for (int k = 0; k < 3; ++k) {
        const int go = g.corner_opposite[static_cast<size_t>(3 * faces[static_cast<size_t>(i)] + k)];
        if (go < 0) continue;
        const int j = mark[static_cast<size_t>(go / 3)];
        if (j < 0 || label[static_cast<size_t>(j)] >= 0) continue;
        label[static_cast<size_t>(j)] = label[static_cast<size_t>(i)];
        queue.push_back(j);
      }
    }
    return queue.back();  // the last face reached: a farthest one
  };
  const int a = sweep({0});
  const int b = sweep({a});
  sweep({a, b});
  std::array<std::vector<int>, 2> parts;
  for (size_t i = 0; i < n; ++i) {
    // A face the sweep did not reach (cannot happen for a connected chart) goes to part 0.
    parts[label[i] == 1 ? 1 : 0].push_back(faces[i]);
    mark[static_cast<size_t>(faces[i])] = -1;
  }
  return parts;
}

struct Unwrapper {
  const Geometry& g;
  const UvUnwrapOptions& o;
  UvUnwrapReport& report;
  std::vector<int> owner, local, mark;
  std::vector<FlatChart> done;

  Unwrapper(const Geometry& geometry, const UvUnwrapOptions& options, UvUnwrapReport& r)
      : g(geometry), o(options), report(r), owner(g.faces(), -1), local(g.faces(), -1), mark(g.faces(), -1) {}

  // Flattens every chart of `work`, splitting those that fail, until all are done.
  void run(std::vector<std::vector<int>> work) {
    while (!work.empty()) {
      for (size_t w = 0; w < work.size(); ++w) {
        for (size_t i = 0; i < work[w].size(); ++i) {
          owner[static_cast<size_t>(work[w][i])] = static_cast<int>(w);
          local[static_cast<size_t>(work[w][i])] = static_cast<int>(i);
        }
      }
      std::vector<FlatChart> flat(work.size());
      std::vector<Outcome> outcome(work.size(), Outcome::failure);
      // Each chart writes only its own slot: the result does not depend on scheduling.
      tbb::parallel_for(size_t(0), work.size(), [&](size_t w) {
        flat[w].faces = work[w];
        outcome[w] = flatten(g, owner, local, static_cast<int>(w), o.method, o.max_stretch, flat[w]);
      });
      std::vector<std::vector<int>> next;
      for (size_t w = 0; w < work.size(); ++w) {
        switch (outcome[w]) {
          case Outcome::done: done.push_back(std::move(flat[w])); continue;
          case Outcome::topology: ++report.topology_splits; break;
          case Outcome::stretch: ++report.stretch_splits; break;
          case Outcome::overlap: ++report.overlap_splits; break;
          case Outcome::failure: ++report.failure_splits; break;
        }
        auto parts = split_in_two(g, work[w], mark);
        next.push_back(std::move(parts[0]));
        next.push_back(std::move(parts[1]));
      }
      // Work item numbers are reused next round: no face may keep a stale one.
      for (const auto& faces : work)
        for (int f : faces) owner[static_cast<size_t>(f)] = -1;
      work = std::move(next);
    }
  }
};

// Charts side by side in rows (in chart order), a gap apart, the whole scaled into [0,1]^2.
void lay_out(Mesh& mesh, const Geometry& g, std::vector<FlatChart>& charts) {
  double bbox_area = 0, widest = 0;
  for (auto& c : charts) {
    c.lo[0] = c.lo[1] = std::numeric_limits<double>::infinity();
    c.hi[0] = c.hi[1] = -std::numeric_limits<double>::infinity();
    for (const auto& p : c.uv) {
      for (int a = 0; a < 2; ++a) {
        c.lo[a] = std::min(c.lo[a], p[static_cast<size_t>(a)]);
        c.hi[a] = std::max(c.hi[a], p[static_cast<size_t>(a)]);
      }
    }
    bbox_area += (c.hi[0] - c.lo[0]) * (c.hi[1] - c.lo[1]);
    widest = std::max(widest, c.hi[0] - c.lo[0]);
  }
  const double mean_side = std::sqrt(bbox_area / static_cast<double>(std::max<size_t>(1, charts.size())));
  // The gap only keeps charts apart (pack_uv_charts moves them anyway); it must survive
  // the rounding of UVs to float, hence the floor relative to the layout's size.
  const double row_width = std::max(widest, std::sqrt(bbox_area) * 1.2);
  const double gap = std::max({0.05 * mean_side, 1e-4 * row_width, 1e-30});
  std::vector<std::array<double, 2>> offset(charts.size());
  double x = 0, y = 0, row_height = 0, width = 0;
  for (size_t i = 0; i < charts.size(); ++i) {
    const double w = charts[i].hi[0] - charts[i].lo[0], h = charts[i].hi[1] - charts[i].lo[1];
    if (x > 0 && x + w > row_width) {
      y += row_height + gap;
      x = row_height = 0;
    }
    offset[i] = {x - charts[i].lo[0], y - charts[i].lo[1]};
    x += w + gap;
    width = std::max(width, x);
    row_height = std::max(row_height, h);
  }
  const double extent = std::max({width, y + row_height, 1e-30});
  const double scale = 1.0 / extent;
  if (!mesh.has_halfedge_texcoords2D()) mesh.request_halfedge_texcoords2D();
  // Border halfedges belong to no face but writers may still see their UVs (OpenMesh's OBJ
  // writer lists every halfedge's): give them a fixed value, not whatever memory held.
  for (auto h : mesh.halfedges())
    if (mesh.is_boundary(h)) mesh.set_texcoord2D(h, Vec2f(0, 0));
  for (size_t i = 0; i < charts.size(); ++i) {
    const FlatChart& c = charts[i];
    for (size_t j = 0; j < c.faces.size(); ++j) {
      for (size_t k = 0; k < 3; ++k) {
        const auto& p = c.uv[3 * j + k];
        const float u = static_cast<float>(std::clamp((p[0] + offset[i][0]) * scale, 0.0, 1.0));
        const float v = static_cast<float>(std::clamp((p[1] + offset[i][1]) * scale, 0.0, 1.0));
        mesh.set_texcoord2D(g.corner_halfedge[3 * static_cast<size_t>(c.faces[j]) + k], Vec2f(u, v));
      }
    }
  }
}

}  // namespace

UvUnwrapReport unwrap_uv_charts(Mesh& mesh, const UvUnwrapOptions& options) {
  UvUnwrapReport report;
  const Geometry g = make_geometry(mesh);
  auto grown = grow_charts(g, options);
  report.grown_charts = grown.size();
  Unwrapper u(g, options, report);
  u.run(std::move(grown));

  // Faces in face order within each chart (their UVs with them), charts numbered by first
  // face, as uv_charts() numbers the result.
  for (auto& c : u.done) {
    std::vector<size_t> idx(c.faces.size());
    std::iota(idx.begin(), idx.end(), size_t(0));
    std::sort(idx.begin(), idx.end(), [&](size_t a, size_t b) { return c.faces[a] < c.faces[b]; });
    FlatChart s = c;
    for (size_t i = 0; i < idx.size(); ++i) {
      s.faces[i] = c.faces[idx[i]];
      for (size_t k = 0; k < 3; ++k) s.uv[3 * i + k] = c.uv[3 * idx[i] + k];
    }
    c = std::move(s);
  }
  std::sort(u.done.begin(), u.done.end(), [](const FlatChart& a, const FlatChart& b) { return a.faces[0] < b.faces[0]; });
  lay_out(mesh, g, u.done);

  report.charts = u.done.size();
  double area = 0, l2 = 0, angle = 0, area_d = 0;  // weights in the unit-box scale, as the sums
  for (const FlatChart& c : u.done) {
    report.per_chart.push_back(c.stats);
    report.per_chart.back().area /= g.unit * g.unit;  // object units^2 again
    area += c.stats.area;
    l2 += c.stats.area * c.stats.stretch_l2 * c.stats.stretch_l2;
    angle += c.angle_sum;
    area_d += c.area_sum;
    report.stretch_linf = std::max(report.stretch_linf, c.stats.stretch_linf);
    report.max_chart_stretch_l2 = std::max(report.max_chart_stretch_l2, c.stats.stretch_l2);
    report.angle_distortion_max = std::max(report.angle_distortion_max, c.angle_max);
  }
  for (size_t f = 0; f < g.faces(); ++f) report.degenerate_faces += g.degenerate[f];
  if (area > 0) {
    report.stretch_l2 = std::sqrt(l2 / area);
    report.angle_distortion_mean = angle / area;
    report.area_distortion_mean = area_d / area;
  }
  return report;
}

}  // namespace meso
