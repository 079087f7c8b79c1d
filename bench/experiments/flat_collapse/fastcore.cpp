// EXPERIMENT: see fastcore.hpp. Quadric math and small geometric helpers are meso's own
// (meshreduce/src/quadric.hpp, geometry.hpp, included read-only from /work/main).
#include "fastcore.hpp"

#include "closest_triangles.hpp"  // meso's flip test against the input (Embree BVH), as NoFlip uses it
#include "geometry.hpp"  // meso's 2D UV helpers (uv_cross, lerp_uv, point_segment_distance on Vec2f)

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>

#include <tbb/parallel_for.h>

#define NOINLINE __attribute__((noinline))

namespace fastcore {

namespace {

using meso::reduce::lerp_uv;
using meso::reduce::uv_cross;

// Plain 3-vector (OpenMesh's VectorT loops over DIM and is not unrolled at -O2: a third of the
// prototype's instructions went to its operators).
struct Vec3d {
  double x = 0, y = 0, z = 0;
  Vec3d() = default;
  Vec3d(double a, double b, double c) : x(a), y(b), z(c) {}
  explicit Vec3d(double a) : x(a), y(a), z(a) {}
  double operator[](int i) const { return i == 0 ? x : i == 1 ? y : z; }
  Vec3d operator+(const Vec3d& o) const { return {x + o.x, y + o.y, z + o.z}; }
  Vec3d operator-(const Vec3d& o) const { return {x - o.x, y - o.y, z - o.z}; }
  Vec3d operator*(double s) const { return {x * s, y * s, z * s}; }
  Vec3d operator/(double s) const { return {x / s, y / s, z / s}; }
  Vec3d& operator+=(const Vec3d& o) { x += o.x, y += o.y, z += o.z; return *this; }
  Vec3d& operator/=(double s) { x /= s, y /= s, z /= s; return *this; }
  bool operator==(const Vec3d& o) const { return x == o.x && y == o.y && z == o.z; }
  double sqrnorm() const { return x * x + y * y + z * z; }
  double norm() const { return std::sqrt(sqrnorm()); }
  double max() const { return std::max({x, y, z}); }
  void minimize(const Vec3d& o) { x = std::min(x, o.x), y = std::min(y, o.y), z = std::min(z, o.z); }
  void maximize(const Vec3d& o) { x = std::max(x, o.x), y = std::max(y, o.y), z = std::max(z, o.z); }
};
struct Vec3d;
inline OpenMesh::Vec3d om(const Vec3d& v);
inline double dot(const Vec3d& a, const Vec3d& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3d cross(const Vec3d& a, const Vec3d& b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }

inline OpenMesh::Vec3d om(const Vec3d& v) { return OpenMesh::Vec3d(v.x, v.y, v.z); }

// meso's helpers (meshreduce/src/geometry.hpp, quadric.hpp) on this vector type.
inline double point_segment_distance(const Vec3d& p, const Vec3d& a, const Vec3d& b) {
  const Vec3d ab = b - a;
  const double l2 = ab.sqrnorm();
  const double t = l2 > 0 ? std::clamp(dot(p - a, ab) / l2, 0.0, 1.0) : 0.0;
  return (p - (a + ab * t)).norm();
}
using meso::reduce::point_segment_distance;
inline double aspect_ratio(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const double l = std::max({(b - a).sqrnorm(), (c - b).sqrnorm(), (a - c).sqrnorm()});
  const double area2 = cross(b - a, c - a).norm();
  if (!(area2 > 0)) return std::numeric_limits<double>::infinity();
  return l * std::sqrt(3.0) / (2.0 * area2);
}
inline double closest_point_sqr(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c, double w[3]) {
  const Vec3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  auto done = [&](double wa, double wb, double wc) {
    w[0] = wa, w[1] = wb, w[2] = wc;
    return (a * wa + b * wb + c * wc - p).sqrnorm();
  };
  if (d1 <= 0 && d2 <= 0) return done(1, 0, 0);
  const Vec3d bp = p - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return done(0, 1, 0);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return done(1 - v, v, 0);
  }
  const Vec3d cp = p - c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return done(0, 0, 1);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double v = d2 / (d2 - d6);
    return done(1 - v, 0, v);
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double v = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return done(0, 1 - v, v);
  }
  const double denom = va + vb + vc;
  if (!(std::abs(denom) > 0)) {
    const double da = (p - a).sqrnorm(), db = (p - b).sqrnorm(), dc = (p - c).sqrnorm();
    if (da <= db && da <= dc) return done(1, 0, 0);
    return db <= dc ? done(0, 1, 0) : done(0, 0, 1);
  }
  const double v = vb / denom, ww = vc / denom;
  return done(1 - v - ww, v, ww);
}

constexpr double kLengthBias = 1e-12;  // as meso: ties go to the shortest edge
constexpr uint32_t kNone = UINT32_MAX;

inline bool same(const Vec2f& a, const Vec2f& b) { return a[0] == b[0] && a[1] == b[1]; }
inline uint32_t next3(uint32_t k) { return k == 2 ? 0 : k + 1; }
inline uint32_t prev3(uint32_t k) { return k == 0 ? 2 : k - 1; }


// Lean versions of meso's placement (same maths: regularised minimiser around the midpoint,
// refined once, kept when within 2 edge lengths of the midpoint; else the best of p0, p1,
// mid), in plain doubles.
struct Q10 {
  double a00 = 0, a01 = 0, a02 = 0, a11 = 0, a12 = 0, a22 = 0, b0 = 0, b1 = 0, b2 = 0, c = 0;
  static Q10 plane(const Vec3d& n, double d, double w) {
    Q10 q;
    q.a00 = w * n.x * n.x, q.a01 = w * n.x * n.y, q.a02 = w * n.x * n.z;
    q.a11 = w * n.y * n.y, q.a12 = w * n.y * n.z, q.a22 = w * n.z * n.z;
    q.b0 = w * d * n.x, q.b1 = w * d * n.y, q.b2 = w * d * n.z;
    q.c = w * d * d;
    return q;
  }
  Q10& operator+=(const Q10& o) {
    a00 += o.a00, a01 += o.a01, a02 += o.a02, a11 += o.a11, a12 += o.a12, a22 += o.a22;
    b0 += o.b0, b1 += o.b1, b2 += o.b2, c += o.c;
    return *this;
  }
  Q10 operator+(const Q10& o) const { Q10 r = *this; r += o; return r; }
  double operator()(const Vec3d& p) const;
};
inline double qeval(const Q10& q, double x, double y, double z) {
  const double ax = q.a00 * x + q.a01 * y + q.a02 * z, ay = q.a01 * x + q.a11 * y + q.a12 * z, az = q.a02 * x + q.a12 * y + q.a22 * z;
  const double v = x * ax + y * ay + z * az + 2.0 * (q.b0 * x + q.b1 * y + q.b2 * z) + q.c;
  return v > 0 ? v : 0;
}
// (A + eps I) s = -(A x + b): the step from x.
inline double Q10::operator()(const Vec3d& p) const { return qeval(*this, p.x, p.y, p.z); }
// meso's segment_placement: the minimiser on p0 + t (p1 - p0), t in [0, 1].
inline double segment_placement(const Q10& q, const Vec3d& p0, const Vec3d& p1, double& t) {
  const Vec3d d = p1 - p0;
  auto A = [&](const Vec3d& x) {
    return Vec3d(q.a00 * x.x + q.a01 * x.y + q.a02 * x.z, q.a01 * x.x + q.a11 * x.y + q.a12 * x.z, q.a02 * x.x + q.a12 * x.y + q.a22 * x.z);
  };
  const double dad = dot(d, A(d));
  const double slope = dot(d, A(p0) + Vec3d(q.b0, q.b1, q.b2));
  const double scale = (q.a00 + q.a11 + q.a22) * dot(d, d);
  if (dad > 1e-9 * scale && std::isfinite(dad)) {
    t = std::clamp(-slope / dad, 0.0, 1.0);
  } else {
    t = 0.5;
  }
  return q(p0 + d * t);
}
inline bool qstep(const Q10& q, double eps, double x, double y, double z, double s[3]) {
  const double r0 = -(q.a00 * x + q.a01 * y + q.a02 * z + q.b0), r1 = -(q.a01 * x + q.a11 * y + q.a12 * z + q.b1),
               r2 = -(q.a02 * x + q.a12 * y + q.a22 * z + q.b2);
  const double a = q.a00 + eps, b = q.a01, c = q.a02, d = q.a11 + eps, e = q.a12, f = q.a22 + eps;
  const double c00 = d * f - e * e, c01 = c * e - b * f, c02 = b * e - c * d;
  const double det = a * c00 + b * c01 + c * c02;
  if (!(std::abs(det) > 0)) return false;
  const double c11 = a * f - c * c, c12 = b * c - a * e, c22 = a * d - b * b;
  const double inv = 1.0 / det;
  s[0] = (c00 * r0 + c01 * r1 + c02 * r2) * inv;
  s[1] = (c01 * r0 + c11 * r1 + c12 * r2) * inv;
  s[2] = (c02 * r0 + c12 * r1 + c22 * r2) * inv;
  return std::isfinite(s[0] + s[1] + s[2]);
}
inline double lean_optimal(const Q10& q, const Vec3d& p0, const Vec3d& p1, Vec3d& out, bool refine) {
  const double mx = 0.5 * (p0[0] + p1[0]), my = 0.5 * (p0[1] + p1[1]), mz = 0.5 * (p0[2] + p1[2]);
  const double trace = q.a00 + q.a11 + q.a22;
  if (trace > 0 && std::isfinite(trace)) {
    const double eps = 1e-3 * trace;
    double s[3], s2[3];
    if (qstep(q, eps, mx, my, mz, s)) {
      const double x = mx + s[0], y = my + s[1], z = mz + s[2];
      if (!refine) s2[0] = s2[1] = s2[2] = 0;
      if (!refine || qstep(q, eps, x, y, z, s2)) {
        const double ox = x + s2[0], oy = y + s2[1], oz = z + s2[2];
        const double dx = ox - mx, dy = oy - my, dz = oz - mz;
        const double ex = p1[0] - p0[0], ey = p1[1] - p0[1], ez = p1[2] - p0[2];
        if (dx * dx + dy * dy + dz * dz <= 4.0 * (ex * ex + ey * ey + ez * ez)) {
          const double co = qeval(q, ox, oy, oz);
          // The minimiser is at most the midpoint's cost but for rounding; check the ends only
          // when it is not clearly the best (as meso's fallback).
          const double cm = qeval(q, mx, my, mz);
          if (co <= cm) {
            out = Vec3d(ox, oy, oz);
            return co;
          }
        }
      }
    }
  }
  const double c0 = qeval(q, p0[0], p0[1], p0[2]), c1 = qeval(q, p1[0], p1[1], p1[2]), cm = qeval(q, mx, my, mz);
  double best = cm;
  out = Vec3d(mx, my, mz);
  if (c0 < best) best = c0, out = p0;
  if (c1 < best) best = c1, out = p1;
  return best;
}

// A growable array without per-push checks (the caller reserves).
template <class T>
struct Buf {
  std::unique_ptr<T[]> p;
  size_t n = 0, cap = 0;
  void reserve(size_t c) {
    if (c <= cap) return;
    std::unique_ptr<T[]> q(new T[c]);
    if (n) std::memcpy(static_cast<void*>(q.get()), p.get(), n * sizeof(T));
    p = std::move(q);
    cap = c;
  }
  void clear() { n = 0; }
  void push_back(const T& v) { p[n++] = v; }
  size_t size() const { return n; }
  T* data() { return p.get(); }
  T& operator[](size_t i) { return p[i]; }
  const T& operator[](size_t i) const { return p[i]; }
  T* begin() { return p.get(); }
  T* end() { return p.get() + n; }
  const T* begin() const { return p.get(); }
  const T* end() const { return p.get() + n; }
};

enum Kind : uint8_t { kOptimal, kOnto, kSlide };

struct Edge {
  uint32_t a, b;  // half-edge a->b in face f
  uint32_t f, g;  // g: the twin face (b->a), kNone on a boundary
  uint8_t feat, boundary, k;  // k: a's corner in f
};

struct Cand {
  uint32_t v0, v1;  // v0 goes, v1 is kept and moves to q
  Kind kind;
  double t;  // slide: q = p0 + t (p1 - p0)
  Vec3d p0, p1, q;
  double cost;
  bool boundary;
};

struct FanFace {
  uint32_t f;
  uint32_t k;  // corner index of the moving vertex
  bool from_v0;
  bool adj_l, adj_r;
  Vec3d old_p, b, c;
  Vec2f old_uv, uv_b, uv_c, new_uv;
};

class Reducer {
 public:
  Reducer(const Vec3f* points, size_t nv, const std::array<uint32_t, 3>* tris, size_t nt, const std::array<Vec2f, 3>* uvs,
          const Options& o)
      : o_(o), in_points_(points), nv_(nv), has_uv_(uvs != nullptr) {
    // Normalise to the unit box, power-of-two scale (as meso).
    Vec3d lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
    for (size_t i = 0; i < nv; ++i) {
      const Vec3d p(points[i][0], points[i][1], points[i][2]);
      lo.minimize(p), hi.maximize(p);
    }
    if (nv == 0) lo = hi = Vec3d(0, 0, 0);
    center_ = (lo + hi) * 0.5;
    const double extent = (hi - lo).max();
    scale_ = 1.0;
    if (extent > 0 && std::isfinite(extent)) {
      int e = 0;
      std::frexp(extent, &e);
      scale_ = std::ldexp(1.0, -e);
    }
    diag_ = (hi - lo).norm() * scale_;
    pos_.resize(nv);
    src_.resize(nv);
    for (size_t i = 0; i < nv; ++i) {
      pos_[i] = (Vec3d(points[i][0], points[i][1], points[i][2]) - center_) * scale_;
      src_[i] = static_cast<int32_t>(i);
    }
    tri_.assign(tris, tris + nt);
    if (has_uv_) uv_.assign(uvs, uvs + nt);
    alive_.assign(nt, 1);
    faces_ = nt;
    nsum_.resize(nt);
    ckey_.assign(nt, {0.f, 0.f, 0.f});
    quadric_.assign(nv, Q10());
    dirty_.assign(nv, 0);
    stamp_.assign(nv, 0);
    deg_.resize(nv);
    off_.resize(nv + 1);
  }

  Output run(Stats* stats) {
    Stats s;
    if (o_.steep_test || o_.post_check) {
      in_tris_.reserve(tri_.size());
      for (const auto& t : tri_) in_tris_.push_back(meso::reduce::Triangle{om(pos_[t[0]]), om(pos_[t[1]]), om(pos_[t[2]])});
      if (!o_.lazy_bvh) ensure_bvh();
    }
    build_adjacency();
    enumerate_edges();
    init_quadrics();
    for (;;) {
      if (faces_ <= o_.target_faces) break;
      if (s.passes > 0) {
        compact();
        build_adjacency();
        enumerate_edges();
      }
      ++pass_;
      ++s.passes;
      const size_t made = run_pass(s);
      if (made == 0) break;
    }
    if (o_.post_check) s.post_flipped = post_check();
    if (stats) *stats = s;
    return output();
  }

 private:
  // The input's BVH, built the first time a test needs it (lazy_bvh) or up front.
  void ensure_bvh() const {
    if (nearest_) return;
    nearest_ = std::make_unique<meso::reduce::ClosestTriangles>(in_tris_);
    mean_edge_ = meso::reduce::mean_edge(in_tris_);
  }

  // meso's final check (NoFlip::flipped_faces): every output face against the input under it,
  // as the bench counts a flip, with a 3-degree margin; in parallel (TBB), as meso does.
  NOINLINE size_t post_check() const {
    std::vector<uint32_t> live;
    for (uint32_t f = 0; f < tri_.size(); ++f) {
      if (!alive_[f]) continue;
      if (o_.post_check_steep_only) {
        // Only faces over 60 degrees from the summed normals of the input faces they stand
        // for (the in-loop steep test's trigger).
        const auto& t = tri_[f];
        const Vec3d n = cross(pos_[t[1]] - pos_[t[0]], pos_[t[2]] - pos_[t[0]]);
        if (dot(n, nsum_[f]) >= 0.5 * n.norm() * nsum_[f].norm()) continue;
      }
      live.push_back(f);
    }
    if (live.empty()) return 0;
    ensure_bvh();
    std::vector<uint8_t> flipped(live.size(), 0);
    tbb::parallel_for(size_t{0}, live.size(), [&](size_t i) {
      const auto& t = tri_[live[i]];
      const Vec3d &a = pos_[t[0]], &b = pos_[t[1]], &c = pos_[t[2]];
      const Vec3d n = cross(b - a, c - a);
      flipped[i] = n.sqrnorm() > 0 && meso::reduce::faces_away_screened(*nearest_, om(a), om(b), om(c), om(n), mean_edge_,
                                                                         meso::reduce::kFlippedCos, meso::reduce::kFlippedScreenCos);
    });
    return static_cast<size_t>(std::count(flipped.begin(), flipped.end(), uint8_t{1}));
  }

  // ---- setup per pass ----
  NOINLINE void compact() {
    size_t w = 0;
    for (size_t f = 0; f < tri_.size(); ++f) {
      if (!alive_[f]) continue;
      tri_[w] = tri_[f];
      nsum_[w] = nsum_[f];
      ckey_[w] = ckey_[f];
      if (has_uv_) uv_[w] = uv_[f];
      ++w;
    }
    tri_.resize(w);
    nsum_.resize(w);
    ckey_.resize(w);
    if (has_uv_) uv_.resize(w);
    alive_.assign(w, 1);
  }

  NOINLINE void build_adjacency() {
    std::fill(off_.begin(), off_.end(), 0u);
    for (const auto& t : tri_)
      for (uint32_t v : t) ++off_[v + 1];
    for (size_t i = 0; i < nv_; ++i) off_[i + 1] += off_[i];
    adj_.resize(off_[nv_]);
    cursor_.assign(off_.begin(), off_.end() - 1);
    for (uint32_t f = 0; f < tri_.size(); ++f)
      for (uint32_t v : tri_[f]) adj_[cursor_[v]++] = f;
  }

  // The face (other than f) around b holding the half-edge b->a, and b's corner in it.
  uint32_t twin(uint32_t f, uint32_t a, uint32_t b, uint32_t& jb) const {
    for (uint32_t i = off_[b]; i < off_[b + 1]; ++i) {
      const uint32_t h = adj_[i];
      if (h == f || !alive_[h]) continue;
      const auto& t = tri_[h];
      for (uint32_t j = 0; j < 3; ++j)
        if (t[j] == b && t[next3(j)] == a) {
          jb = j;
          return h;
        }
    }
    return kNone;
  }

  NOINLINE void enumerate_edges() {
    edges_.clear();
    prevdeg_.swap(deg_);
    deg_.assign(nv_, 0);
    // Per vertex a, its outgoing half-edges a->n (one per face around a); the twin n->a is
    // the face around a where a's previous corner is n. Each edge once: a < n, or no twin.
    struct Local {
      uint32_t f, k, n, p;
    };
    edges_.reserve(tri_.size() * 3 + 64);
    std::vector<Local> big;
    Local small[64];
    for (uint32_t a = 0; a < nv_; ++a) {
      const uint32_t b0 = off_[a], b1 = off_[a + 1];
      if (b0 == b1) continue;
      const uint32_t m = b1 - b0;
      Local* local = small;
      if (m > 64) {
        big.resize(m);
        local = big.data();
      }
      for (uint32_t i = 0; i < m; ++i) {
        const uint32_t f = adj_[b0 + i];
        const auto& t = tri_[f];
        const uint32_t k = t[0] == a ? 0 : t[1] == a ? 1 : 2;
        local[i] = {f, k, t[next3(k)], t[prev3(k)]};
      }
      for (uint32_t hi = 0; hi < m; ++hi) {
        const Local& h = local[hi];
        const Local* tw = nullptr;
        for (uint32_t gi = 0; gi < m; ++gi)
          if (local[gi].p == h.n) {
            tw = &local[gi];
            break;
          }
        if (tw && a > h.n) continue;
        Edge e{a, h.n, h.f, tw ? tw->f : kNone, 0, 0, static_cast<uint8_t>(h.k)};
        if (!tw) {
          e.feat = e.boundary = 1;
        } else if (has_uv_) {
          e.feat = !same(uv_[h.f][h.k], uv_[tw->f][tw->k]) || !same(uv_[h.f][next3(h.k)], uv_[tw->f][prev3(tw->k)]);
        }
        if (e.feat) ++deg_[a], ++deg_[h.n];
        edges_.push_back(e);
      }
    }
  }

  NOINLINE void init_quadrics() {
    for (uint32_t f = 0; f < tri_.size(); ++f) {
      const auto& t = tri_[f];
      const Vec3d &a = pos_[t[0]], &b = pos_[t[1]], &c = pos_[t[2]];
      Vec3d n = cross(b - a, c - a);
      nsum_[f] = n;
      const double len = n.norm();
      if (!(len > 0)) continue;
      n /= len;
      const Q10 q = Q10::plane(n, -dot(n, a), 0.5 * len);
      for (uint32_t v : t) quadric_[v] += q;
    }
    // Feature planes: through each feature edge, perpendicular to each of its faces.
    auto add_plane = [&](uint32_t f, uint32_t from, uint32_t to, double weight) {
      const auto& t = tri_[f];
      const Vec3d &a = pos_[t[0]], &b = pos_[t[1]], &c = pos_[t[2]];
      Vec3d n = cross(b - a, c - a);
      const double len = n.norm();
      if (!(len > 0)) return;
      n /= len;
      const Vec3d& p = pos_[from];
      const Vec3d d = pos_[to] - p;
      Vec3d cn = cross(d, n);
      const double cl = cn.norm();
      if (!(cl > 0)) return;
      cn /= cl;
      const Q10 cq = Q10::plane(cn, -dot(cn, p), weight * d.sqrnorm());
      quadric_[from] += cq;
      quadric_[to] += cq;
    };
    for (const Edge& e : edges_) {
      if (!e.feat) continue;
      const double w = e.boundary ? o_.boundary_weight : o_.seam_weight;
      add_plane(e.f, e.a, e.b, w);
      if (e.g != kNone) add_plane(e.g, e.b, e.a, w);
    }
  }

  // ---- evaluation (meso's placement rules) ----
  NOINLINE bool evaluate(const Edge& e, Cand& c, bool cheap = false) const {
    const uint8_t da = deg_[e.a], db = deg_[e.b];
    bool fixed = false;
    if (e.feat) {
      c.kind = kSlide;
      if (da == 2) {
        c.v0 = e.a, c.v1 = e.b, fixed = db != 2;
      } else if (db == 2) {
        c.v0 = e.b, c.v1 = e.a, fixed = true;
      } else {
        return false;  // both ends are corners of the feature network
      }
    } else if (da == 0 && db == 0) {
      c.kind = kOptimal, c.v0 = e.a, c.v1 = e.b;
    } else if (da == 0) {
      c.kind = kOnto, c.v0 = e.a, c.v1 = e.b;
    } else if (db == 0) {
      c.kind = kOnto, c.v0 = e.b, c.v1 = e.a;
    } else {
      return false;  // would pinch a chart or the outline
    }
    c.boundary = e.boundary;
    const Q10 q = quadric_[c.v0] + quadric_[c.v1];
    c.p0 = pos_[c.v0];
    c.p1 = pos_[c.v1];
    switch (c.kind) {
      case kOptimal:
        if (o_.optimal_placement) {
          c.t = -1;
          if (cheap) {
            // Ranking only: the best of the ends and the midpoint (an upper bound of the
            // optimal cost); the collapse itself re-evaluates with the optimal placement.
            const Vec3d m = (c.p0 + c.p1) * 0.5;
            c.cost = std::min({q(c.p0), q(c.p1), q(m)});
            c.q = m;
            break;
          }
          c.cost = lean_optimal(q, c.p0, c.p1, c.q, o_.refine);
        } else {
          const double c0 = q(c.p0), c1 = q(c.p1);
          if (c0 < c1) std::swap(c.v0, c.v1), std::swap(c.p0, c.p1);
          c.t = 1, c.q = c.p1, c.cost = std::min(c0, c1);
        }
        break;
      case kOnto:
        c.t = 1, c.q = c.p1, c.cost = q(c.p1);
        break;
      case kSlide:
        if (fixed) {
          c.t = 1;
        } else if (o_.optimal_placement) {
          segment_placement(q, c.p0, c.p1, c.t);
        } else {
          const double c0 = q(c.p0), c1 = q(c.p1);
          c.t = 1;
          if (c0 < c1) std::swap(c.v0, c.v1), std::swap(c.p0, c.p1);
        }
        c.q = c.t == 1 ? c.p1 : c.t == 0 ? c.p0 : c.p0 + (c.p1 - c.p0) * c.t;
        c.cost = q(c.q);
        break;
    }
    return std::isfinite(c.cost);
  }

  // The ranking key of an edge for endpoint placement (what evaluate() + key_of() give,
  // without filling a candidate): kinds and ends as in evaluate().
  bool endpoint_key(const Edge& e, float& key) const {
    const uint8_t da = deg_[e.a], db = deg_[e.b];
    uint32_t v0, v1;
    bool both = false;  // either end may be kept
    if (e.feat) {
      if (da == 2) v0 = e.a, v1 = e.b, both = db == 2;
      else if (db == 2) v0 = e.b, v1 = e.a;
      else return false;
    } else if (da == 0 && db == 0) {
      v0 = e.a, v1 = e.b, both = true;
    } else if (da == 0) {
      v0 = e.a, v1 = e.b;
    } else if (db == 0) {
      v0 = e.b, v1 = e.a;
    } else {
      return false;
    }
    const Q10& q0 = quadric_[v0];
    const Q10& q1 = quadric_[v1];
    const Vec3d& p0 = pos_[v0];
    const Vec3d& p1 = pos_[v1];
    double cost = qeval(q0, p1.x, p1.y, p1.z) + qeval(q1, p1.x, p1.y, p1.z);
    if (both) cost = std::min(cost, qeval(q0, p0.x, p0.y, p0.z) + qeval(q1, p0.x, p0.y, p0.z));
    if (!std::isfinite(cost)) return false;
    key = static_cast<float>(cost + kLengthBias * (p1 - p0).sqrnorm());
    return true;
  }

  static float key_of(const Cand& c) { return static_cast<float>(c.cost + kLengthBias * (c.p1 - c.p0).sqrnorm()); }

  NOINLINE void sort_keys(size_t scan) {
    if (!o_.radix) {
      std::sort(keys_.begin(), keys_.end());
      return;
    }
    // Only the first `scan` keys are needed: keep those whose top 12 bits are at most the
    // bucket where the cumulative count reaches `scan` (order kept), then sort those.
    if (scan < keys_.size()) {
      static uint32_t hist[4096];
      std::memset(hist, 0, sizeof hist);
      const size_t n = keys_.size();
      for (size_t i = 0; i < n; ++i) ++hist[keys_[i] >> 52];
      uint32_t thr = 0;
      for (size_t acc = 0; thr < 4096; ++thr) {
        acc += hist[thr];
        if (acc >= scan) break;
      }
      size_t w = 0;
      for (size_t i = 0; i < n; ++i)
        if ((keys_[i] >> 52) <= thr) keys_[w++] = keys_[i];
      keys_.n = w;
    }
    // LSD radix on the high 32 bits (the float key), 11+11+10 bits; stable, so equal keys
    // stay in edge order (the low 32 bits), as a full sort would give.
    tmp_.reserve(keys_.size());
    const int shifts[3] = {32, 43, 54};
    const int widths[3] = {11, 11, 10};
    uint64_t* src = keys_.data();
    uint64_t* dst = tmp_.data();
    const size_t n = keys_.size();
    for (int p = 0; p < 3; ++p) {
      const uint32_t buckets = 1u << widths[p], mask = buckets - 1;
      uint32_t count[2048 + 1] = {0};
      for (size_t i = 0; i < n; ++i) ++count[((src[i] >> shifts[p]) & mask) + 1];
      for (uint32_t b = 0; b < buckets; ++b) count[b + 1] += count[b];
      for (size_t i = 0; i < n; ++i) dst[count[(src[i] >> shifts[p]) & mask]++] = src[i];
      std::swap(src, dst);
    }
    if (src != keys_.data()) std::memcpy(keys_.data(), src, n * sizeof(uint64_t));
  }

  NOINLINE size_t run_pass(Stats& s) {
    keys_.clear();
    keys_.reserve(edges_.size() + 1);
    Cand c;
    const uint32_t last = pass_ - 1;  // keys of edges whose ends did not change in the last pass still hold
    for (uint32_t i = 0; i < edges_.size(); ++i) {
      const Edge& e = edges_[i];
      float& cached = ckey_[e.f][e.k];
      float k;
      if (last > 0 && o_.cache && dirty_[e.a] != last && dirty_[e.b] != last && deg_[e.a] == prevdeg_[e.a] && deg_[e.b] == prevdeg_[e.b]) {
        k = cached;
        if (std::isnan(k)) continue;
      } else {
        ++s.evaluated;
        if (!o_.optimal_placement && o_.fast_key) {
          if (!endpoint_key(e, k)) {
            cached = std::numeric_limits<float>::quiet_NaN();
            continue;
          }
          cached = k;
        } else {
          if (!evaluate(e, c, o_.rank_cheap)) {
            cached = std::numeric_limits<float>::quiet_NaN();
            continue;
          }
          k = cached = key_of(c);
        }
      }
      uint32_t bits;
      std::memcpy(&bits, &k, 4);
      keys_.push_back((uint64_t{bits} << 32) | i);
    }
    const size_t excess = faces_ - o_.target_faces;
    const size_t goal = std::max<size_t>(1, static_cast<size_t>(std::ceil(static_cast<double>(excess) * o_.pass_goal)));
    const size_t scan = std::max<size_t>(1, static_cast<size_t>(std::ceil(static_cast<double>(keys_.size()) * o_.pass_scan)));
    sort_keys(scan);
    size_t removed = 0, made = 0;
    for (size_t i = 0; i < keys_.size() && i < scan; ++i) {
      if (faces_ <= o_.target_faces || removed >= goal) break;
      const Edge& e = edges_[keys_[i] & 0xffffffffu];
      if (dirty_[e.a] == pass_ || dirty_[e.b] == pass_) {
        ++s.skipped_dirty;
        continue;
      }
      ++s.attempted;
      evaluate(e, c);
      const size_t before = faces_;
      if (try_collapse(c, s)) {
        ++made;
        removed += before - faces_;
      }
    }
    s.collapses += made;
    if (std::getenv("FASTCORE_VERBOSE"))
      std::fprintf(stderr, "pass %u: edges %zu cands %zu made %zu faces %zu\n", pass_, edges_.size(), keys_.size(), made, faces_);
    return made;
  }

  // ---- the collapse ----
  int side_of(const Vec2f& u, const Vec2f* uvs, const bool* valid) const {
    if (valid[0] && same(u, uvs[0])) return 0;
    if (valid[1] && same(u, uvs[1])) return 1;
    return -1;
  }

  // The other feature neighbour of v (feature degree 2) than `exclude`, and its UV on each
  // side (sides by v's UV: uvv[s]).
  NOINLINE uint32_t other_feature(uint32_t v, uint32_t exclude, const Vec2f* uvv, const bool* valid, Vec2f* uv_other) const {
    uint32_t other = kNone;
    for (uint32_t i = off_[v]; i < off_[v + 1]; ++i) {
      const uint32_t f = adj_[i];
      if (!alive_[f]) continue;
      const auto& t = tri_[f];
      const uint32_t k = t[0] == v ? 0 : t[1] == v ? 1 : 2;
      // Half-edge v -> n in f.
      const uint32_t n = t[next3(k)];
      uint32_t jb = 0;
      const uint32_t g = twin(f, v, n, jb);
      bool feat = g == kNone;
      if (!feat && has_uv_) feat = !same(uv_[f][k], uv_[g][next3(jb)]) || !same(uv_[f][next3(k)], uv_[g][jb]);
      if (feat && n != exclude) {
        other = n;
        if (has_uv_) {
          const int s = side_of(uv_[f][k], uvv, valid);
          if (s >= 0) uv_other[s] = uv_[f][next3(k)];
          if (g != kNone) {
            const int s2 = side_of(uv_[g][next3(jb)], uvv, valid);
            if (s2 >= 0) uv_other[s2] = uv_[g][jb];
          }
        }
      }
      // Half-edge p -> v in f, on a boundary (no v -> p anywhere).
      const uint32_t p = t[prev3(k)];
      uint32_t jp = 0;
      if (p != exclude && twin(f, p, v, jp) == kNone) {
        other = p;
        if (has_uv_) {
          const int s = side_of(uv_[f][k], uvv, valid);
          if (s >= 0) uv_other[s] = uv_[f][prev3(k)];
        }
      }
    }
    return other;
  }

  bool folds(const Vec2f& uv) const {
    for (const auto& ff : fan_) {
      const double before = uv_cross(ff.old_uv, ff.uv_b, ff.uv_c);
      if (before != 0 && uv_cross(uv, ff.uv_b, ff.uv_c) * before <= 0) return true;
    }
    return false;
  }

  NOINLINE bool try_collapse(Cand& c, Stats& s) {
    const uint32_t v0 = c.v0, v1 = c.v1;
    // Faces at the edge: fl holds v0->v1, fr holds v1->v0.
    uint32_t fl = kNone, fr = kNone, vl = kNone, vr = kNone, nshared = 0;
    for (uint32_t i = off_[v0]; i < off_[v0 + 1]; ++i) {
      const uint32_t f = adj_[i];
      if (!alive_[f]) continue;
      const auto& t = tri_[f];
      const uint32_t k = t[0] == v0 ? 0 : t[1] == v0 ? 1 : 2;
      if (t[next3(k)] == v1) {
        fl = f, vl = t[prev3(k)], ++nshared;
      } else if (t[prev3(k)] == v1) {
        fr = f, vr = t[next3(k)], ++nshared;
      }
    }
    if (nshared == 0 || nshared > 2 || (vl != kNone && vl == vr)) {
      ++s.rej_link;
      return false;
    }
    // Link condition: the one-rings of v0 and v1 meet only in vl and vr.
    if (++stamp_id_ == 0) {
      std::fill(stamp_.begin(), stamp_.end(), 0u);
      stamp_id_ = 1;
    }
    for (uint32_t i = off_[v1]; i < off_[v1 + 1]; ++i)
      if (alive_[adj_[i]])
        for (uint32_t x : tri_[adj_[i]]) stamp_[x] = stamp_id_;
    for (uint32_t i = off_[v0]; i < off_[v0 + 1]; ++i)
      if (alive_[adj_[i]])
      for (uint32_t x : tri_[adj_[i]])
        if (x != v0 && x != v1 && x != vl && x != vr && stamp_[x] == stamp_id_) {
          ++s.rej_link;
          return false;
        }
    // The fan: faces around v0 or v1 that survive.
    fan_.clear();
    for (int side = 0; side < 2; ++side) {
      const uint32_t v = side == 0 ? v0 : v1;
      for (uint32_t i = off_[v]; i < off_[v + 1]; ++i) {
        const uint32_t f = adj_[i];
        if (f == fl || f == fr || !alive_[f]) continue;
        const auto& t = tri_[f];
        FanFace ff;
        ff.f = f;
        ff.k = t[0] == v ? 0 : t[1] == v ? 1 : 2;
        ff.from_v0 = side == 0;
        const uint32_t b = t[next3(ff.k)], cc = t[prev3(ff.k)];
        ff.adj_l = vl != kNone && (b == vl || cc == vl);
        ff.adj_r = vr != kNone && (b == vr || cc == vr);
        ff.old_p = pos_[v];
        ff.b = pos_[b];
        ff.c = pos_[cc];
        if (has_uv_) {
          ff.old_uv = uv_[f][ff.k];
          ff.uv_b = uv_[f][next3(ff.k)];
          ff.uv_c = uv_[f][prev3(ff.k)];
          ff.new_uv = ff.old_uv;
        }
        fan_.push_back(ff);
      }
    }
    // UVs at the edge, per side (0: fl, 1: fr).
    bool side_valid[2] = {fl != kNone, fr != kNone};
    Vec2f uv0[2], uv1[2];
    if (has_uv_) {
      if (fl != kNone) {
        const auto& t = tri_[fl];
        const uint32_t k = t[0] == v0 ? 0 : t[1] == v0 ? 1 : 2;
        uv0[0] = uv_[fl][k], uv1[0] = uv_[fl][next3(k)];
      }
      if (fr != kNone) {
        const auto& t = tri_[fr];
        const uint32_t k = t[0] == v0 ? 0 : t[1] == v0 ? 1 : 2;
        uv0[1] = uv_[fr][k], uv1[1] = uv_[fr][prev3(k)];
      }
    }
    // Chart guard: slides only along straight stretches, no sliver wedges.
    if (c.kind == kSlide) {
      if (has_uv_ && side_valid[0] && side_valid[1] && (uv0[0] == uv0[1] || (c.t < 1 && uv1[0] == uv1[1]))) {
        ++s.rej_chart;  // sides cannot be told apart by UV
        return false;
      }
      Vec2f uvo0[2], uvo1[2];
      const uint32_t other0 = other_feature(v0, v1, uv0, side_valid, uvo0);
      const uint32_t other1 = deg_[v1] == 2 ? other_feature(v1, v0, uv1, side_valid, uvo1) : kNone;
      const bool v1_moves = c.t < 1 && other1 != kNone;
      const double tol = (c.boundary ? o_.boundary_tolerance : o_.seam_tolerance) * diag_;
      bool ok = other0 != kNone && other0 != vl && other0 != vr && other0 != v1;
      if (ok && other1 != kNone) ok = other1 != vl && other1 != vr && other1 != other0 && other1 != v0;
      if (ok) ok = point_segment_distance(c.p0, pos_[other0], c.q) <= tol;
      if (ok && v1_moves) ok = point_segment_distance(c.p1, c.q, pos_[other1]) <= tol;
      if (ok && has_uv_) {
        for (int sd = 0; sd < 2 && ok; ++sd) {
          if (!side_valid[sd]) continue;
          const Vec2f nu = lerp_uv(uv0[sd], uv1[sd], c.t);
          if (point_segment_distance(uv0[sd], uvo0[sd], nu) > o_.uv_tolerance) ok = false;
          if (ok && v1_moves && point_segment_distance(uv1[sd], nu, uvo1[sd]) > o_.uv_tolerance) ok = false;
        }
      }
      if (!ok) {
        ++s.rej_chart;
        return false;
      }
    }
    // Normals: against the face's own before, and against the input faces it stands for.
    int shares_l = 0, shares_r = 0;
    for (const auto& ff : fan_) shares_l += ff.adj_l, shares_r += ff.adj_r;
    const Vec3d removed_l = fl != kNone && shares_l > 0 ? nsum_[fl] / shares_l : Vec3d(0, 0, 0);
    const Vec3d removed_r = fr != kNone && shares_r > 0 ? nsum_[fr] / shares_r : Vec3d(0, 0, 0);
    merged_.clear();
    for (const auto& ff : fan_) {
      Vec3d input = nsum_[ff.f];
      if (ff.adj_l) input += removed_l;
      if (ff.adj_r) input += removed_r;
      merged_.push_back(input);
      const Vec3d n1 = cross(ff.b - c.q, ff.c - c.q);
      if (o_.input_normal_test && dot(n1, input) < 0) {
        ++s.rej_flip;
        return false;
      }
      // meso's steep test: a face over 60 degrees from its input sum, against the input
      // triangles nearest to samples over it, refused past 84 degrees.
      if (o_.steep_test && dot(n1, input) < 0.5 * n1.norm() * input.norm() && (ensure_bvh(), true) &&
          meso::reduce::faces_away(*nearest_, om(c.q), om(ff.b), om(ff.c), om(n1), mean_edge_, meso::reduce::AwayTest{0.1, 2, 16, false})) {
        ++s.rej_steep;
        return false;
      }
      const Vec3d n0 = cross(ff.b - ff.old_p, ff.c - ff.old_p);
      if (!(n0.sqrnorm() > 0)) continue;
      const double sc = (ff.b - c.q).sqrnorm() * (ff.c - c.q).sqrnorm();
      if (!(n1.sqrnorm() > 1e-18 * sc) || dot(n0, n1) <= 0) {
        ++s.rej_flip;
        return false;
      }
    }
    // Needles.
    if (o_.max_aspect_ratio > 0) {
      double worst_new = 0;
      bool need_exact = true;
      if (o_.lean) {
        // Squared aspect ratio without roots: 3 l^2 / (4 |n|^2) with 2 area = |n|.
        const double max2 = o_.max_aspect_ratio * o_.max_aspect_ratio;
        bool over = false;
        for (const auto& ff : fan_) {
          const Vec3d e0 = ff.b - c.q, e1 = ff.c - c.q, e2 = ff.c - ff.b;
          const double l = std::max({e0.sqrnorm(), e1.sqrnorm(), e2.sqrnorm()});
          const double n2 = cross(e0, e1).sqrnorm();
          if (!(3.0 * l * l <= max2 * 4.0 * n2)) {
            over = true;
            break;
          }
        }
        need_exact = over;
      }
      if (need_exact)
        for (const auto& ff : fan_) worst_new = std::max(worst_new, aspect_ratio(c.q, ff.b, ff.c));
      if (worst_new > o_.max_aspect_ratio) {
        double worst_old = 0;
        for (const auto& ff : fan_) worst_old = std::max(worst_old, aspect_ratio(ff.old_p, ff.b, ff.c));
        for (uint32_t f : {fl, fr})
          if (f != kNone) worst_old = std::max(worst_old, aspect_ratio(pos_[tri_[f][0]], pos_[tri_[f][1]], pos_[tri_[f][2]]));
        if (worst_new > worst_old) {
          ++s.rej_needle;
          return false;
        }
      }
    }
    // UVs of the moving corners.
    if (has_uv_) {
      bool uv_checked = false;
      const int main_side = side_valid[0] ? 0 : 1;
      if (c.kind == kOptimal && c.t < 0) {
        const Vec3d d = c.p1 - c.p0;
        const double l2 = d.sqrnorm();
        const double sp = l2 > 0 ? std::clamp(dot(c.q - c.p0, d) / l2, 0.0, 1.0) : 0.5;
        const Vec2f options[4] = {reproject_uv(c, fl, fr, uv1[main_side]), lerp_uv(uv0[main_side], uv1[main_side], sp), uv1[main_side],
                                  uv0[main_side]};
        int pick = -1;
        for (int i = 0; i < 4; ++i)
          if (!folds(options[i])) {
            pick = i;
            break;
          }
        if (pick < 0) {
          ++s.rej_uv;
          return false;
        }
        for (auto& ff : fan_) ff.new_uv = options[pick];
        uv_checked = true;
      } else if (c.kind != kSlide) {
        // onto (or endpoint placement): v0's corners take v1's UV in the chart of fl/fr.
        for (auto& ff : fan_)
          if (ff.from_v0) ff.new_uv = uv1[main_side];
      } else {
        for (auto& ff : fan_) {
          if (!ff.from_v0 && c.t == 1) continue;
          const int sd = side_of(ff.old_uv, ff.from_v0 ? uv0 : uv1, side_valid);
          if (sd < 0) {
            ++s.rej_uv;
            return false;
          }
          ff.new_uv = lerp_uv(uv0[sd], uv1[sd], c.t);
        }
      }
      for (const auto& ff : fan_) {
        if (uv_checked && !std::getenv("NOSKIP")) break;
        const double before = uv_cross(ff.old_uv, ff.uv_b, ff.uv_c);
        if (before == 0) continue;
        if (uv_cross(ff.new_uv, ff.uv_b, ff.uv_c) * before <= 0) {
          ++s.rej_uv;
          return false;
        }
      }
    }
    // Apply.
    quadric_[v1] += quadric_[v0];
    if (c.q == c.p1) {
    } else if (c.q == c.p0) {
      src_[v1] = src_[v0];
    } else {
      src_[v1] = -1;
    }
    pos_[v1] = c.q;
    for (size_t i = 0; i < fan_.size(); ++i) {
      const auto& ff = fan_[i];
      tri_[ff.f][ff.k] = v1;
      if (has_uv_) uv_[ff.f][ff.k] = ff.new_uv;
      nsum_[ff.f] = merged_[i];
    }
    for (uint32_t f : {fl, fr})
      if (f != kNone) alive_[f] = 0, --faces_;
    if (o_.ring_lock) {
      for (uint32_t v : {v0, v1})
        for (uint32_t i = off_[v]; i < off_[v + 1]; ++i)
          for (uint32_t x : tri_[adj_[i]]) dirty_[x] = pass_;
    }
    dirty_[v0] = dirty_[v1] = pass_;
    return true;
  }

  mutable bool inside_ = false;
  NOINLINE Vec2f reproject_uv(const Cand& c, uint32_t fl, uint32_t fr, Vec2f fallback) const {
    inside_ = false;
    double best = std::numeric_limits<double>::max();
    Vec2f uv = fallback;
    auto consider = [&](const Vec3d& a, const Vec3d& b, const Vec3d& cc, const Vec2f& ua, const Vec2f& ub, const Vec2f& uc) {
      double w[3];
      const double d2 = closest_point_sqr(c.q, a, b, cc, w);
      if (d2 < best) {
        best = d2;
        inside_ = w[0] > 0 && w[1] > 0 && w[2] > 0;
        uv = Vec2f(static_cast<float>(w[0] * ua[0] + w[1] * ub[0] + w[2] * uc[0]), static_cast<float>(w[0] * ua[1] + w[1] * ub[1] + w[2] * uc[1]));
      }
    };
    for (uint32_t f : {fl, fr}) {
      if (f == kNone) continue;
      const auto& t = tri_[f];
      consider(pos_[t[0]], pos_[t[1]], pos_[t[2]], uv_[f][0], uv_[f][1], uv_[f][2]);
    }
    // q over the inside of fl or fr (its closest point strictly inside): no fan face can be
    // nearer than... not guaranteed in general, but the fan faces lie beyond fl/fr's
    // other edges; meso scans all of them. o_.lean: stop here when the closest point is
    // inside.
    if (o_.lean && inside_) return uv;
    for (const auto& ff : fan_) consider(ff.old_p, ff.b, ff.c, ff.old_uv, ff.uv_b, ff.uv_c);
    return uv;
  }

  NOINLINE Output output() const {
    Output out;
    out.points.resize(nv_);
    for (size_t i = 0; i < nv_; ++i) {
      if (src_[i] >= 0) {
        out.points[i] = in_points_[src_[i]];
      } else {
        const Vec3d p = pos_[i] / scale_ + center_;
        out.points[i] = Vec3f(static_cast<float>(p[0]), static_cast<float>(p[1]), static_cast<float>(p[2]));
      }
    }
    out.triangles.reserve(faces_);
    for (size_t f = 0; f < tri_.size(); ++f) {
      if (!alive_[f]) continue;
      out.triangles.push_back(tri_[f]);
      if (has_uv_) out.uvs.push_back(uv_[f]);
    }
    return out;
  }

  Options o_;
  const Vec3f* in_points_;
  size_t nv_;
  bool has_uv_;
  Vec3d center_{0, 0, 0};
  double scale_ = 1, diag_ = 1;
  std::vector<Vec3d> pos_;
  std::vector<int32_t> src_;
  std::vector<Q10> quadric_;
  std::vector<std::array<uint32_t, 3>> tri_;
  std::vector<std::array<Vec2f, 3>> uv_;
  std::vector<Vec3d> nsum_;
  // The input surface for meso's steep-face test and final flip check (normalised units).
  std::vector<meso::reduce::Triangle> in_tris_;
  mutable std::unique_ptr<meso::reduce::ClosestTriangles> nearest_;
  mutable double mean_edge_ = 1;
  std::vector<std::array<float, 3>> ckey_;  // per corner: the key of the edge it starts (cache; NaN: not a candidate)
  std::vector<uint8_t> alive_;
  size_t faces_ = 0;
  std::vector<uint32_t> off_, adj_, cursor_;
  std::vector<uint8_t> deg_, prevdeg_;
  std::vector<uint32_t> dirty_, stamp_;
  uint32_t pass_ = 0, stamp_id_ = 0;
  Buf<Edge> edges_;
  Buf<uint64_t> keys_, tmp_;
  std::vector<FanFace> fan_;
  std::vector<Vec3d> merged_;
};

}  // namespace

Output reduce(const Vec3f* points, size_t n_points, const std::array<uint32_t, 3>* triangles, size_t n_triangles,
              const std::array<Vec2f, 3>* uvs, const Options& options, Stats* stats) {
  Reducer r(points, n_points, triangles, n_triangles, uvs, options);
  return r.run(stats);
}

}  // namespace fastcore
