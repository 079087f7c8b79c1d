// The measuring instrument's reference: the true displaced surface ray traced with Embree 3
// through the previewer's own camera. Over flat parts of the base (one normal at all three
// corners of every triangle) the surface is exactly the bilinear height surface the per-pixel
// methods trace, and is intersected cell by cell in closed form (bilinear_patch.hpp, Embree
// user geometry); over curved ones it is tessellated below the texel size.
#include "meso/preview/preview.hpp"

#include "bilinear_patch.hpp"
#include "camera.hpp"
#include "meso/bake/tangent_frame.hpp"
#include "meso/core/error.hpp"
#include "sampling.hpp"

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <vector>

namespace meso {

namespace {

using Vec3d = OpenMesh::Vec3d;
using Vec2d = OpenMesh::Vec2d;

// A base triangle as the tessellation reads it: corners in face_halfedges() order.
struct BaseTriangle {
  std::array<int, 3> vertex{};  // vertex indices (they orient shared edges canonically)
  std::array<Vec3d, 3> p, n;    // positions, vertex normals
  std::array<Vec2d, 3> uv;      // this face's corner UVs
  Vec3d face_normal{0, 0, 1};   // unit; where the interpolated normal vanishes
  bool valid = false;
  // Flat (its vertex normals agree): the surface over it is intersected exactly, per cell, in
  // `patch`'s frame (relative to Impl::origin), and it is not tessellated.
  bool patched = false;
  FlatPatchFrame patch;
  std::array<Vec2d, 3> xy;  // corners in texel coordinates (bilinear_patch.hpp)
};

// Vertex normals that differ by less than this (unit vectors, Euclidean) count as one: the
// float rounding of normals averaged over a plane's faces (~1e-7); the constant-normal
// surface then departs from the interpolated one by under 1e-6 of the height.
constexpr double kFlatNormalTolerance = 1e-6;

// One piece of a flat triangle's surface: the part over texel cell (i, j).
struct Piece {
  uint32_t face;
  int32_t i, j;
};

// Bisection levels at most (a sub-triangle of depth d has 1 / 2^d of its base triangle's
// area): beyond it UVs are far outside any map; the cap keeps the count in check anyway.
constexpr int kMaxDepth = 48;

bool finite(const Vec3d& v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

// A point of a base triangle by its barycentrics on corners 0, 1, 2. Bisection takes
// midpoints of dyadic weights, exactly: a point on a base edge keeps an exact 0 on the third
// corner, and both faces of that edge compute the same weights for it.
struct Bary {
  std::array<double, 3> w;
};

// The sub-triangles of one base triangle by longest-edge bisection in texel units: a
// triangle whose longest edge exceeds `target` is cut at that edge's midpoint. Every edge
// longer than `target` ends up cut at its midpoint and no shorter one is, whichever triangle
// holds it: the cut of an edge depends on the edge alone, so triangles that share an edge
// (inside a base triangle, or two base triangles with the same UVs along it) cut it alike
// and the result has no T-junctions. Depth beyond `max_depth` is not cut (the cap).
class Bisection {
 public:
  Bisection(const BaseTriangle& t, double width, double height, double target, int max_depth)
      : t_(t), w_(width), h_(height), target_(target), max_depth_(max_depth) {}

  // The UV of a point, computed on a base edge from the edge's canonical
  // orientation (the lower vertex index first), so that both faces agree bitwise.
  Vec2d uv(const Bary& b) const {
    for (size_t c = 0; c < 3; ++c) {
      if (b.w[c] != 0.0) continue;
      size_t lo = (c + 1) % 3, hi = (c + 2) % 3;
      if (t_.vertex[lo] > t_.vertex[hi]) std::swap(lo, hi);
      return t_.uv[lo] * b.w[lo] + t_.uv[hi] * b.w[hi];
    }
    return t_.uv[0] * b.w[0] + t_.uv[1] * b.w[1] + t_.uv[2] * b.w[2];
  }

  // A corner during the bisection: barycentrics, texel-space UV, and the visitor's id.
  struct Node {
    Bary b;
    Vec2d uv;
    uint32_t id;
  };

  // Visits every sub-triangle: visitor.leaf(a, b, c, longest edge) (false stops early), and
  // visitor.midpoint(x, y, m) gives the id of the midpoint m of corners x and y.
  template <class Visitor>
  bool run(Visitor& visitor) const {
    const Bary a{{1, 0, 0}}, b{{0, 1, 0}}, c{{0, 0, 1}};
    return split(Node{a, uv(a), 0}, Node{b, uv(b), 1}, Node{c, uv(c), 2}, 0, visitor);
  }

 private:
  double length(const Vec2d& a, const Vec2d& b) const { return std::hypot((b[0] - a[0]) * w_, (b[1] - a[1]) * h_); }

  template <class Visitor>
  Node midpoint(const Node& x, const Node& y, Visitor& visitor) const {
    const Bary m{{(x.b.w[0] + y.b.w[0]) * 0.5, (x.b.w[1] + y.b.w[1]) * 0.5, (x.b.w[2] + y.b.w[2]) * 0.5}};
    return Node{m, uv(m), visitor.midpoint(x, y, m)};
  }

  template <class Visitor>
  bool split(const Node& a, const Node& b, const Node& c, int depth, Visitor& visitor) const {
    const double lab = length(a.uv, b.uv), lbc = length(b.uv, c.uv), lca = length(c.uv, a.uv);
    const double longest = std::max({lab, lbc, lca});
    // NaN-safe: only a length known to exceed the target cuts.
    if (!(longest > target_) || depth >= max_depth_) return visitor.leaf(a, b, c, longest);
    if (lab == longest) {
      const Node m = midpoint(a, b, visitor);
      return split(a, m, c, depth + 1, visitor) && split(m, b, c, depth + 1, visitor);
    }
    if (lbc == longest) {
      const Node m = midpoint(b, c, visitor);
      return split(a, b, m, depth + 1, visitor) && split(a, m, c, depth + 1, visitor);
    }
    const Node m = midpoint(c, a, visitor);
    return split(a, b, m, depth + 1, visitor) && split(m, b, c, depth + 1, visitor);
  }

  const BaseTriangle& t_;
  double w_, h_, target_;
  int max_depth_;
};

// Midpoint ids by edge (the two corner ids), open addressing: an edge inside a base
// triangle is cut by both sub-triangles that share it, and must get one vertex.
class EdgeTable {
 public:
  // The id stored for edge (a, b), or `fresh` stored for it when there is none yet.
  uint32_t find_or_add(uint32_t a, uint32_t b, uint32_t fresh) {
    if (2 * (used_ + 1) > keys_.size()) grow();
    const uint64_t key = (static_cast<uint64_t>(std::min(a, b)) << 32 | std::max(a, b)) + 1;  // 0 = empty
    size_t i = slot(key);
    while (keys_[i] != 0) {
      if (keys_[i] == key) return values_[i];
      i = (i + 1) & (keys_.size() - 1);
    }
    keys_[i] = key;
    values_[i] = fresh;
    ++used_;
    return fresh;
  }

 private:
  // Fibonacci hashing: the top bits of the product.
  size_t slot(uint64_t key) const { return static_cast<size_t>((key * 0x9E3779B97F4A7C15ull) >> shift_); }
  void grow() {
    std::vector<uint64_t> keys(std::max<size_t>(64, 2 * keys_.size()), 0);
    shift_ = 64;
    for (size_t n = keys.size(); n > 1; n >>= 1) --shift_;
    std::vector<uint32_t> values(keys.size(), 0);
    keys.swap(keys_);
    values.swap(values_);
    for (size_t j = 0; j < keys.size(); ++j) {
      if (keys[j] == 0) continue;
      size_t i = slot(keys[j]);
      while (keys_[i] != 0) i = (i + 1) & (keys_.size() - 1);
      keys_[i] = keys[j];
      values_[i] = values[j];
    }
  }
  std::vector<uint64_t> keys_;
  std::vector<uint32_t> values_;
  size_t used_ = 0;
  int shift_ = 64;
};

}  // namespace

struct ReferenceRenderer::Impl {
  const Mesh& base;
  Image displacement, normal_ts;
  bool wrap = false;
  std::vector<TangentFrame> frames;
  std::vector<BaseTriangle> tris;
  Vec3d origin{0, 0, 0};  // positions are stored relative to the base's centre (bake.cpp's RayScene)
  // ... and times `unit`, a power of two (exact both ways) that brings the base's half
  // diagonal into [0.5, 1): Embree's intersectors hold absolute floors, under which the
  // half-texel triangles of a mesh 1e-6 units across fell (the demo's bricks scaled by 1e-6:
  // half of the reference's visible points moved, by up to half a texel).
  double unit = 1;
  std::vector<float> positions;   // 4 floats per vertex (Embree's 16-byte loads)
  std::vector<float> barycentrics;  // per vertex: its base barycentrics on corners 1 and 2
  std::vector<uint32_t> indices, triangle_face;
  std::vector<Piece> pieces;          // the flat triangles' cells, in face order
  std::vector<RTCBounds> piece_bounds;  // their boxes (relative to origin), for Embree's build
  unsigned patch_geometry = RTC_INVALID_GEOMETRY_ID;
  double max_edge = 0, build_ms = 0;
  double reach = 0;  // the larger of |displacement min| and |max|, object units
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;

  Impl(const Mesh& mesh, const PreviewMaps& maps, const ReferenceOptions& o)
      : base(mesh), displacement(maps.displacement), normal_ts(maps.normal_ts), wrap(maps_tile(maps)) {
    if (displacement.empty() || normal_ts.empty()) throw std::logic_error("reference: maps are empty");
    if (!has_uvs(base)) throw std::logic_error("reference: base mesh without UVs");
    {
      const auto [lo, hi] = std::minmax_element(displacement.pixels.begin(), displacement.pixels.end());
      reach = std::max(-static_cast<double>(*lo), static_cast<double>(*hi));  // frame_camera's, as the renderer's
    }
    const auto t0 = std::chrono::steady_clock::now();
    frames = compute_tangent_frames(base);
    prepare_triangles();
    const size_t cap = std::max<size_t>(o.max_triangles, 1);
    if (o.bilinear_patches) build_patches(cap);
    tessellate(o, std::max<size_t>(cap - std::min(cap, pieces.size()), 1));
    build_scene();
    build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  }
  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  double height(const Vec2d& uv) const { return sample_linear(displacement, 0, uv[0], uv[1], wrap); }

  // Cell (i, j)'s four texels under the border rule, as sample_linear reads them.
  CellHeights cell_heights(int i, int j) const {
    const int w = displacement.width, h = displacement.height;
    const int xa = texel_index(i, w, wrap), xb = texel_index(i + 1.0, w, wrap), ya = texel_index(j, h, wrap),
              yb = texel_index(j + 1.0, h, wrap);
    // In the scene's units (times `unit`), as the pieces' frames.
    return CellHeights{displacement.at(xa, ya) * unit, displacement.at(xb, ya) * unit, displacement.at(xa, yb) * unit, displacement.at(xb, yb) * unit};
  }

  // The true displaced point over base point `b` of triangle t: P + h(uv) N / |N| with P, N
  // and uv interpolated; on a base edge from the edge's canonical orientation (the lower
  // vertex index first), so that both faces of the edge compute it bitwise alike.
  Vec3d displaced(const BaseTriangle& t, const Bary& b) const {
    Vec3d p, n;
    Vec2d uv;
    size_t zero = 3;
    for (size_t c = 0; c < 3 && zero == 3; ++c)
      if (b.w[c] == 0.0) zero = c;
    if (zero < 3) {
      size_t lo = (zero + 1) % 3, hi = (zero + 2) % 3;
      if (t.vertex[lo] > t.vertex[hi]) std::swap(lo, hi);
      p = t.p[lo] * b.w[lo] + t.p[hi] * b.w[hi];
      n = t.n[lo] * b.w[lo] + t.n[hi] * b.w[hi];
      uv = t.uv[lo] * b.w[lo] + t.uv[hi] * b.w[hi];
    } else {
      p = t.p[0] * b.w[0] + t.p[1] * b.w[1] + t.p[2] * b.w[2];
      n = t.n[0] * b.w[0] + t.n[1] * b.w[1] + t.n[2] * b.w[2];
      uv = t.uv[0] * b.w[0] + t.uv[1] * b.w[1] + t.uv[2] * b.w[2];
    }
    const double len = n.norm();
    const Vec3d dir = len > 1e-12 ? n / len : t.face_normal;
    return p + dir * height(uv);
  }

  // Sub-triangles of every valid face at (target, max_depth), or false as soon as the total
  // exceeds `cap`. Deterministic: the count is exact or "too many".
  bool fits(double target, int max_depth, size_t cap) const {
    std::atomic<size_t> total{0};
    std::atomic<bool> over{false};
    const double w = displacement.width, h = displacement.height;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, tris.size()), [&](const tbb::blocked_range<size_t>& range) {
      for (size_t f = range.begin(); f < range.end() && !over.load(std::memory_order_relaxed); ++f) {
        if (!tris[f].valid || tris[f].patched) continue;
        struct Counter {
          size_t count = 0, cap;
          const std::atomic<bool>* over;
          uint32_t midpoint(const Bisection::Node&, const Bisection::Node&, const Bary&) { return 0; }
          bool leaf(const Bisection::Node&, const Bisection::Node&, const Bisection::Node&, double) {
            if ((++count & 0xFFFF) == 0 && over->load(std::memory_order_relaxed)) return false;
            return count <= cap;
          }
        } counter{0, cap, &over};
        Bisection(tris[f], w, h, target, max_depth).run(counter);
        if (total.fetch_add(counter.count) + counter.count > cap) over = true;
      }
    });
    return !over;
  }

  void prepare_triangles() {
    const size_t nf = base.n_faces();
    const double w = displacement.width, h = displacement.height;
    tris.assign(nf, BaseTriangle{});
    for (auto f : base.faces()) {
      BaseTriangle& t = tris[static_cast<size_t>(f.idx())];
      const auto hs = face_halfedges(base, f);
      bool ok = true;
      for (size_t k = 0; k < 3; ++k) {
        const auto v = base.to_vertex_handle(hs[k]);
        t.vertex[k] = v.idx();
        t.p[k] = OpenMesh::vector_cast<Vec3d>(base.point(v));
        t.n[k] = OpenMesh::vector_cast<Vec3d>(base.normal(v));
        const Vec2f uv = base.texcoord2D(hs[k]);
        t.uv[k] = Vec2d(uv[0], uv[1]);
        ok = ok && finite(t.p[k]) && finite(t.n[k]) && std::isfinite(t.uv[k][0]) && std::isfinite(t.uv[k][1]);
      }
      if (!ok) continue;  // nothing sensible to displace: left out
      t.valid = true;
      const Vec3d fn = OpenMesh::cross(t.p[1] - t.p[0], t.p[2] - t.p[0]);
      if (fn.norm() > 0) t.face_normal = fn / fn.norm();
      for (size_t k = 0; k < 3; ++k) t.xy[k] = Vec2d(t.uv[k][0] * w - 0.5, (1.0 - t.uv[k][1]) * h - 0.5);
    }
    const Box3 box = bounding_box(base);
    origin = OpenMesh::vector_cast<Vec3d>(box.center());
    const double radius = 0.5 * box.diagonal();
    if (radius > 0 && std::isfinite(radius)) unit = std::ldexp(1.0, -(std::ilogb(radius) + 1));
  }

  // The flat triangles' frames and their pieces, one per texel cell they overlap with area,
  // unless there would be more than `cap` (then every triangle is tessellated, under the cap).
  // Only whole connected parts of the mesh (faces joined by shared edges) that are flat
  // throughout are intersected exactly: along an edge between an exact and a tessellated
  // triangle the two surfaces would differ (the bilinear curve against its chords: up to
  // h'' L^2 / 8 with h'' <= |a - b - c + d| <= 2 relief along a diagonal, 1/16 of the relief
  // at L = 1/2 texel) and leave a crack.
  void build_patches(size_t cap) {
    const size_t nf = tris.size();
    for (BaseTriangle& t : tris) {
      if (!t.valid) continue;
      std::array<Vec3d, 3> normal;
      for (size_t k = 0; k < 3; ++k) normal[k] = t.n[k].norm() > 0 ? t.n[k] / t.n[k].norm() : Vec3d(0, 0, 0);
      if ((normal[1] - normal[0]).norm() > kFlatNormalTolerance || (normal[2] - normal[0]).norm() > kFlatNormalTolerance) continue;
      Vec3d n = normal[0] + normal[1] + normal[2];
      if (!(n.norm() > 0.5)) continue;  // zero normals: the tessellation falls back on the face normal
      n /= n.norm();
      const std::array<Vec3d, 3> p{(t.p[0] - origin) * unit, (t.p[1] - origin) * unit, (t.p[2] - origin) * unit};
      bool near = true;  // cell indices must fit an int
      for (const Vec2d& q : t.xy) near = near && std::abs(q[0]) < 1e8 && std::abs(q[1]) < 1e8;
      t.patched = near && make_flat_patch_frame(p, t.xy, n, t.patch);
    }
    // Connected parts with a face that is not flat (or not valid) are tessellated whole.
    std::vector<int> part_of(nf, -1);
    std::vector<size_t> stack;
    for (size_t seed = 0; seed < nf; ++seed) {
      if (part_of[seed] >= 0) continue;
      std::vector<size_t> members;
      bool all_flat = true;
      part_of[seed] = static_cast<int>(seed);
      stack.push_back(seed);
      while (!stack.empty()) {
        const size_t f = stack.back();
        stack.pop_back();
        members.push_back(f);
        all_flat = all_flat && tris[f].patched;
        for (auto g : base.ff_range(FaceHandle(static_cast<int>(f)))) {
          const size_t gi = static_cast<size_t>(g.idx());
          if (part_of[gi] >= 0) continue;
          part_of[gi] = static_cast<int>(seed);
          stack.push_back(gi);
        }
      }
      if (!all_flat)
        for (size_t f : members) tris[f].patched = false;
    }
    double cells = 0;  // an upper bound: the cells of each flat triangle's texel box
    for (const BaseTriangle& t : tris) {
      if (!t.patched) continue;
      const auto [x_lo, x_hi] = std::minmax({t.xy[0][0], t.xy[1][0], t.xy[2][0]});
      const auto [y_lo, y_hi] = std::minmax({t.xy[0][1], t.xy[1][1], t.xy[2][1]});
      cells += (std::floor(x_hi) - std::floor(x_lo) + 1) * (std::floor(y_hi) - std::floor(y_lo) + 1);
    }
    if (!(cells <= static_cast<double>(cap))) {
      for (BaseTriangle& t : tris) t.patched = false;
      return;
    }
    struct Part {
      std::vector<Piece> pieces;
      std::vector<RTCBounds> bounds;
    };
    std::vector<Part> parts(nf);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nf), [&](const tbb::blocked_range<size_t>& range) {
      for (size_t f = range.begin(); f < range.end(); ++f) {
        const BaseTriangle& t = tris[f];
        if (!t.patched) continue;
        const auto [x_lo, x_hi] = std::minmax({t.xy[0][0], t.xy[1][0], t.xy[2][0]});
        const auto [y_lo, y_hi] = std::minmax({t.xy[0][1], t.xy[1][1], t.xy[2][1]});
        for (int j = static_cast<int>(std::floor(y_lo)); j <= static_cast<int>(std::floor(y_hi)); ++j)
          for (int i = static_cast<int>(std::floor(x_lo)); i <= static_cast<int>(std::floor(x_hi)); ++i) {
            const std::vector<Vec2d> poly = clip_to_cell(t.xy, i, j);
            if (poly.empty()) continue;
            // The surface over the piece lies between the polygon's base points moved by the
            // cell's lowest and highest texel (a bilinear polynomial stays within its corners).
            const CellHeights c = cell_heights(i, j);
            const double lo = std::min({c.a, c.b, c.c, c.d}), hi = std::max({c.a, c.b, c.c, c.d});
            Vec3d bmin(std::numeric_limits<double>::infinity()), bmax(-std::numeric_limits<double>::infinity());
            for (const Vec2d& q : poly) {
              const Vec3d b = t.patch.p0 + t.patch.px * (q[0] - t.patch.x0) + t.patch.py * (q[1] - t.patch.y0);
              for (double s : {lo, hi}) {
                bmin.minimize(b + t.patch.n * s);
                bmax.maximize(b + t.patch.n * s);
              }
            }
            // Padded for the float box and the pieces' 1e-9-texel growth (bilinear_patch.hpp).
            const double pad = 1e-5 * ((bmax - bmin).max() + bmax.max_abs() + bmin.max_abs());
            parts[f].bounds.push_back(RTCBounds{static_cast<float>(bmin[0] - pad), static_cast<float>(bmin[1] - pad),
                                                static_cast<float>(bmin[2] - pad), 0.0f, static_cast<float>(bmax[0] + pad),
                                                static_cast<float>(bmax[1] + pad), static_cast<float>(bmax[2] + pad), 0.0f});
            parts[f].pieces.push_back(Piece{static_cast<uint32_t>(f), i, j});
          }
      }
    });
    for (Part& part : parts) {
      pieces.insert(pieces.end(), part.pieces.begin(), part.pieces.end());
      piece_bounds.insert(piece_bounds.end(), part.bounds.begin(), part.bounds.end());
      part = Part();
    }
  }

  void tessellate(const ReferenceOptions& o, size_t cap) {
    const size_t nf = base.n_faces();
    const double w = displacement.width, h = displacement.height;
    // The cap: the target edge doubles (up to 8 times), then the depth is limited.
    double target = o.max_edge_texels > 0 ? o.max_edge_texels : 0.5;
    int max_depth = kMaxDepth;
    bool ok = fits(target, max_depth, cap);
    for (int doubling = 0; doubling < 8 && !ok; ++doubling) {
      target *= 2;
      ok = fits(target, max_depth, cap);
    }
    if (!ok) {
      int lo = 0, hi = kMaxDepth;  // the deepest limit that fits: lo fits (or is 0), hi does not
      while (hi - lo > 1) {
        const int mid = (lo + hi) / 2;
        (fits(target, mid, cap) ? lo : hi) = mid;
      }
      max_depth = lo;
    }

    // Each face's sub-triangles with its own vertices (shared ones merged by their exact
    // barycentrics), then concatenated in face order.
    struct Part {
      std::vector<float> positions, barycentrics;
      std::vector<uint32_t> triangles;
      double longest = 0;
    };
    std::vector<Part> parts(nf);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nf), [&](const tbb::blocked_range<size_t>& range) {
      for (size_t f = range.begin(); f < range.end(); ++f) {
        if (!tris[f].valid || tris[f].patched) continue;
        struct Builder {
          const Impl& impl;
          const BaseTriangle& t;
          Part& part;
          EdgeTable edges;
          uint32_t add(const Bary& b) {
            const Vec3d q = (impl.displaced(t, b) - impl.origin) * impl.unit;
            part.positions.insert(part.positions.end(), {static_cast<float>(q[0]), static_cast<float>(q[1]), static_cast<float>(q[2]), 0.0f});
            part.barycentrics.insert(part.barycentrics.end(), {static_cast<float>(b.w[1]), static_cast<float>(b.w[2])});
            return static_cast<uint32_t>(part.positions.size() / 4 - 1);
          }
          uint32_t midpoint(const Bisection::Node& x, const Bisection::Node& y, const Bary& m) {
            const uint32_t next = static_cast<uint32_t>(part.positions.size() / 4);
            const uint32_t id = edges.find_or_add(x.id, y.id, next);
            return id == next ? add(m) : id;
          }
          bool leaf(const Bisection::Node& a, const Bisection::Node& b, const Bisection::Node& c, double longest) {
            part.triangles.insert(part.triangles.end(), {a.id, b.id, c.id});
            part.longest = std::max(part.longest, longest);
            return true;
          }
        } builder{*this, tris[f], parts[f], EdgeTable()};
        for (const Bary& corner : {Bary{{1, 0, 0}}, Bary{{0, 1, 0}}, Bary{{0, 0, 1}}}) builder.add(corner);  // ids 0, 1, 2
        Bisection(tris[f], w, h, target, max_depth).run(builder);
      }
    });
    std::vector<size_t> first_vertex(nf + 1, 0), first_triangle(nf + 1, 0);
    max_edge = 0;
    for (size_t f = 0; f < nf; ++f) {
      first_vertex[f + 1] = first_vertex[f] + parts[f].positions.size() / 4;
      first_triangle[f + 1] = first_triangle[f] + parts[f].triangles.size() / 3;
      max_edge = std::max(max_edge, parts[f].longest);
    }
    if (first_vertex[nf] > std::numeric_limits<uint32_t>::max()) throw InternalError("reference: too many vertices");
    positions.resize(4 * first_vertex[nf]);
    barycentrics.resize(2 * first_vertex[nf]);
    indices.resize(3 * first_triangle[nf]);
    triangle_face.resize(first_triangle[nf]);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nf), [&](const tbb::blocked_range<size_t>& range) {
      for (size_t f = range.begin(); f < range.end(); ++f) {
        Part& part = parts[f];
        std::copy(part.positions.begin(), part.positions.end(), positions.begin() + static_cast<std::ptrdiff_t>(4 * first_vertex[f]));
        std::copy(part.barycentrics.begin(), part.barycentrics.end(), barycentrics.begin() + static_cast<std::ptrdiff_t>(2 * first_vertex[f]));
        for (size_t i = 0; i < part.triangles.size(); ++i)
          indices[3 * first_triangle[f] + i] = static_cast<uint32_t>(first_vertex[f] + part.triangles[i]);
        std::fill_n(triangle_face.begin() + static_cast<std::ptrdiff_t>(first_triangle[f]), part.triangles.size() / 3, static_cast<uint32_t>(f));
        part = Part();
      }
    });
  }

  void build_scene() {
    device = rtcNewDevice(nullptr);
    if (!device) throw InternalError("Embree: cannot create a device");
    scene = rtcNewScene(device);
    // Robust mode: no cracks between triangles for rays through shared edges and vertices.
    // A few rays per triangle at most: the fast (Morton) build pays, and compact nodes halve the memory.
    rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_COMPACT);
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_LOW);
    if (!indices.empty()) {
      RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
      rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, positions.data(), 0, 4 * sizeof(float),
                                 positions.size() / 4);
      rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, indices.data(), 0, 3 * sizeof(uint32_t),
                                 indices.size() / 3);
      rtcCommitGeometry(geom);
      rtcAttachGeometry(scene, geom);
      rtcReleaseGeometry(geom);
    }
    if (!pieces.empty()) {
      RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
      rtcSetGeometryUserPrimitiveCount(geom, static_cast<unsigned>(pieces.size()));
      rtcSetGeometryUserData(geom, this);
      rtcSetGeometryBoundsFunction(geom, &Impl::piece_box, this);
      rtcSetGeometryIntersectFunction(geom, &Impl::intersect_piece);
      rtcCommitGeometry(geom);
      patch_geometry = rtcAttachGeometry(scene, geom);
      rtcReleaseGeometry(geom);
    }
    rtcCommitScene(scene);
    if (rtcGetDeviceError(device) != RTC_ERROR_NONE) throw InternalError("Embree: reference scene build failed (out of memory?)");
  }

  // The ray, in double, that the pieces' intersection reads (Embree passes the context
  // through; its rays are float), and the nearest piece hit so far.
  struct RayContext {
    RTCIntersectContext context;  // first: Embree's pointer to it is a pointer to this
    Vec3d org, dir;
    double t = std::numeric_limits<double>::infinity();
    uint32_t piece = 0;
    PatchHit hit;
  };

  static void piece_box(const RTCBoundsFunctionArguments* args) {
    *args->bounds_o = static_cast<const Impl*>(args->geometryUserPtr)->piece_bounds[args->primID];
  }

  // Embree's callback for one piece (rtcIntersect1: one ray). The nearest hit wins, in
  // double; between hits at the same t, the lower piece index, so that the result does not
  // depend on the traversal order.
  static void intersect_piece(const RTCIntersectFunctionNArguments* args) {
    if (args->N != 1 || !args->valid[0]) return;
    const Impl& impl = *static_cast<const Impl*>(args->geometryUserPtr);
    RayContext& rc = *reinterpret_cast<RayContext*>(args->context);
    RTCRayHit& rh = *reinterpret_cast<RTCRayHit*>(args->rayhit);
    const Piece& piece = impl.pieces[args->primID];
    PatchHit hit;
    const double t_max = std::min(rc.t, static_cast<double>(rh.ray.tfar));
    if (!intersect_bilinear_cell(impl.tris[piece.face].patch, piece.i, piece.j, impl.cell_heights(piece.i, piece.j), rc.org, rc.dir,
                                 static_cast<double>(rh.ray.tnear), t_max, hit))
      return;
    if (hit.t > rc.t || (hit.t == rc.t && args->primID > rc.piece)) return;
    rc.t = hit.t;
    rc.piece = args->primID;
    rc.hit = hit;
    // The next float up: a piece at the same t in double is still visited.
    rh.ray.tfar = std::nextafter(static_cast<float>(hit.t), std::numeric_limits<float>::infinity());
    rh.hit.u = static_cast<float>(hit.fx);
    rh.hit.v = static_cast<float>(hit.fy);
    const Vec3d& n = impl.tris[piece.face].patch.n;
    rh.hit.Ng_x = static_cast<float>(n[0]);
    rh.hit.Ng_y = static_cast<float>(n[1]);
    rh.hit.Ng_z = static_cast<float>(n[2]);
    rh.hit.primID = args->primID;
    rh.hit.geomID = args->geomID;
    rh.hit.instID[0] = args->context->instID[0];
  }

  // A sub-triangle hit's base point: barycentrics interpolated over the sub-triangle.
  void shade_triangle(const PreviewOptions& o, const CameraPose& pose, uint32_t prim, float bu, float bv, float* out) const {
    const uint32_t* tri = &indices[3 * static_cast<size_t>(prim)];
    const double w[3] = {1.0 - static_cast<double>(bu) - static_cast<double>(bv), static_cast<double>(bu), static_cast<double>(bv)};
    double b1 = 0, b2 = 0;
    for (size_t k = 0; k < 3; ++k) {
      b1 += w[k] * static_cast<double>(barycentrics[2 * static_cast<size_t>(tri[k])]);
      b2 += w[k] * static_cast<double>(barycentrics[2 * static_cast<size_t>(tri[k]) + 1]);
    }
    const size_t face = triangle_face[static_cast<size_t>(prim)];
    const BaseTriangle& bt = tris[face];
    const std::array<double, 3> b{1.0 - b1 - b2, b1, b2};
    shade(o, pose, face, b, bt.uv[0] * b[0] + bt.uv[1] * b[1] + bt.uv[2] * b[2], out);
  }

  // A piece hit's base point: texel coordinates (i + fx, j + fy), UV by sample_linear's
  // convention inverted, barycentrics by the frame's affine weights.
  void shade_piece(const PreviewOptions& o, const CameraPose& pose, uint32_t index, const PatchHit& hit, float* out) const {
    const Piece& piece = pieces[index];
    const FlatPatchFrame& f = tris[piece.face].patch;
    const double x = piece.i + hit.fx, y = piece.j + hit.fy;
    std::array<double, 3> b;
    for (size_t k = 0; k < 3; ++k) b[k] = f.bary[k][0] + f.bary[k][1] * x + f.bary[k][2] * y;
    const Vec2d uv((x + 0.5) / displacement.width, 1.0 - (y + 0.5) / displacement.height);
    shade(o, pose, piece.face, b, uv, out);
  }

  // The visible point over base point b (barycentrics) of face `face`, at `uv`.
  void shade(const PreviewOptions& o, const CameraPose& pose, size_t face, const std::array<double, 3>& b, const Vec2d& uv, float* out) const {
    const double a[2] = {uv[0], uv[1]};
    out[3] = 1.0f;
    if (o.shade == PreviewShade::uv) {
      out[0] = static_cast<float>(a[0]);
      out[1] = static_cast<float>(a[1]);
      return;
    }
    if (o.shade == PreviewShade::height) {
      out[0] = static_cast<float>(height(uv));
      return;
    }
    // lit: surface.frag's shading, with the base frame at the visible point's base point.
    const auto hs = face_halfedges(base, FaceHandle(static_cast<int>(face)));
    Vec3d n(0, 0, 0), t(0, 0, 0), p0, p1, p2;
    for (size_t k = 0; k < 3; ++k) {
      n += OpenMesh::vector_cast<Vec3d>(base.normal(base.to_vertex_handle(hs[k]))) * b[k];
      t += OpenMesh::vector_cast<Vec3d>(frames[static_cast<size_t>(hs[k].idx())].tangent) * b[k];
    }
    p0 = OpenMesh::vector_cast<Vec3d>(base.point(base.to_vertex_handle(hs[0])));
    p1 = OpenMesh::vector_cast<Vec3d>(base.point(base.to_vertex_handle(hs[1])));
    p2 = OpenMesh::vector_cast<Vec3d>(base.point(base.to_vertex_handle(hs[2])));
    Vec3d face_n = OpenMesh::cross(p1 - p0, p2 - p0);
    const bool front = OpenMesh::dot(face_n, pose.eye_d - p0) > 0;
    if (face_n.norm() > 0) face_n.normalize();
    if (OpenMesh::dot(n, n) < 1e-12) n = face_n;
    const Vec3d nn = n.norm() > 0 ? n / n.norm() : Vec3d(0, 0, 1);
    const Vec3d t_perp = t - nn * OpenMesh::dot(nn, t);
    if (OpenMesh::dot(t_perp, t_perp) < 1e-12) t = std::abs(nn[0]) < 0.9 ? OpenMesh::cross(nn, Vec3d(1, 0, 0)) : OpenMesh::cross(nn, Vec3d(0, 1, 0));
    const double sign = frames[static_cast<size_t>(hs[0].idx())].sign;
    const Vec3d bitangent = OpenMesh::cross(n, t) * sign;
    double m[3];
    for (int c = 0; c < 3; ++c) m[c] = sample_linear(normal_ts, std::min(c, normal_ts.channels - 1), a[0], a[1], wrap) * 2.0 - 1.0;
    Vec3d normal = t * m[0] + bitangent * m[1] + n * m[2];
    normal = OpenMesh::dot(normal, normal) > 1e-20 ? normal / normal.norm() : nn;
    if (!front) normal = -normal;
    const double diffuse = std::max(OpenMesh::dot(normal, OpenMesh::vector_cast<Vec3d>(pose.light)), 0.0);
    const double albedo[3] = {0.78, 0.74, 0.70};
    for (int c = 0; c < 3; ++c) out[c] = static_cast<float>(std::pow(albedo[c] * (0.12 + 0.88 * diffuse), 1.0 / 2.2));
  }

  Image render(const PreviewOptions& o) const {
    if (o.width < 1 || o.height < 1) throw UsageError("reference: image size must be positive");
    const CameraPose pose = frame_camera(base, o.camera, static_cast<float>(o.width) / static_cast<float>(o.height), reach);
    // Embree takes ray origins and geometry within about 1.8e18 of its origin (FLT_LARGE; it
    // asserts beyond): in the scene's units (`unit`) the mesh is within 1 of it, and a camera
    // farther out is refused rather than crashed on.
    const Box3 box = bounding_box(base);
    const double radius = 0.5 * box.diagonal();
    const double eye_reach = std::max((pose.eye_d - origin).norm(), radius);
    if (!(eye_reach * unit < 1e18)) {
      char need[32];
      std::snprintf(need, sizeof need, "%.3g", radius > 0 ? eye_reach / radius : eye_reach);
      throw UsageError("the reference ray tracer (Embree, float) reaches 1e18 of the mesh's half diagonals from its centre; this camera needs " +
                       std::string(need) + ": zoom in");
    }
    Image out(o.width, o.height, 4, 0.0f);
    tbb::parallel_for(tbb::blocked_range<int>(0, o.height), [&](const tbb::blocked_range<int>& rows) {
      for (int y = rows.begin(); y < rows.end(); ++y)
        for (int x = 0; x < o.width; ++x) {
          Vec3d org, dir;
          pixel_ray(pose, x, y, o.width, o.height, org, dir);
          org = (org - origin) * unit;
          RayContext rc;
          rtcInitIntersectContext(&rc.context);
          rc.org = org;
          rc.dir = dir;
          RTCRayHit rh{};
          rh.ray.org_x = static_cast<float>(org[0]);
          rh.ray.org_y = static_cast<float>(org[1]);
          rh.ray.org_z = static_cast<float>(org[2]);
          rh.ray.dir_x = static_cast<float>(dir[0]);
          rh.ray.dir_y = static_cast<float>(dir[1]);
          rh.ray.dir_z = static_cast<float>(dir[2]);
          rh.ray.tnear = 0.0f;
          rh.ray.tfar = std::numeric_limits<float>::infinity();
          rh.ray.mask = 0xFFFFFFFFu;
          rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
          rtcIntersect1(scene, &rc.context, &rh);
          if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
          if (rh.hit.geomID == patch_geometry)
            shade_piece(o, pose, rc.piece, rc.hit, out.texel(x, y));
          else
            shade_triangle(o, pose, rh.hit.primID, rh.hit.u, rh.hit.v, out.texel(x, y));
        }
    });
    out.metadata["method"] = std::string("reference");
    out.metadata["view_angle"] = o.camera.view_angle;
    out.metadata["azimuth"] = o.camera.azimuth;
    out.metadata["triangles"] = static_cast<int>(std::min<size_t>(triangle_face.size(), std::numeric_limits<int>::max()));
    out.metadata["patches"] = static_cast<int>(std::min<size_t>(pieces.size(), std::numeric_limits<int>::max()));
    return out;
  }
};

ReferenceRenderer::ReferenceRenderer(const Mesh& base, const PreviewMaps& maps, const ReferenceOptions& options)
    : impl_(std::make_unique<Impl>(base, maps, options)) {}

ReferenceRenderer::~ReferenceRenderer() = default;

Image ReferenceRenderer::render(const PreviewOptions& options) const { return impl_->render(options); }

size_t ReferenceRenderer::triangle_count() const { return impl_->triangle_face.size(); }

size_t ReferenceRenderer::patch_count() const { return impl_->pieces.size(); }

double ReferenceRenderer::max_edge_texels() const { return impl_->max_edge; }

double ReferenceRenderer::build_ms() const { return impl_->build_ms; }

Image render_reference(const Mesh& base, const PreviewMaps& maps, const PreviewOptions& options) {
  return ReferenceRenderer(base, maps).render(options);
}

}  // namespace meso
