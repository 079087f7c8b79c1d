#include "meso/streams/cone_map.hpp"
#include "meso/streams/half_rounding.hpp"

#include <Imath/half.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_for_each.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace meso {

const char* cone_kind_name(ConeKind k) { return k == ConeKind::relaxed ? "relaxed" : "conservative"; }

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Depth of the branch and bound on one quarter-texel piece: pieces of 2^-10 of their size.
// Reached only where the bound converges slowly; the bound is then kept (safe).
constexpr int kMaxDepth = 10;
// Relaxed cones stop sooner: along the edge of the region seen descending the bound closes
// only linearly, and a whole curve of rectangles would reach the depth (measured on the
// tests' maps: 4 leaves the median and 90th-percentile gaps where 10 had them, 4x faster).
constexpr int kMaxDepthRelaxed = 4;
// Depth of the one-dimensional branch and bound along an arc of the edge of the set seen
// descending (relaxed cones): arcs of 2^-24 of a piece's size.
constexpr int kArcDepth = 24;


// S sampled on the half-texel grid: value (a, b) at pixel (a / 2, b / 2), a in [0, 2W],
// b in [0, 2H]. A quarter-texel piece [a/2, (a+1)/2] x [b/2, (b+1)/2] lies inside one cell
// between texel centres, where S is one bilinear polynomial, so S on the piece is exactly
// the bilinear interpolation of the piece's four grid values.
// A quarter of the points (a and b odd) are texel centres, where S is the texel itself: they
// are read from the height field, not stored (the map's size less working memory, at +0.7 %
// instructions at most). The others are stored row by row: rows with b even whole (2W + 1
// values), rows with b odd at even a only (W + 1 values).
struct HalfGrid {
  int gw = 0, gh = 0, w = 0;
  const float* texels = nullptr;  // the height field's, row by row (it outlives the grid)
  std::vector<size_t> row;        // where row b starts in v
  std::vector<float> v;
  // The 3 x 3 grid values of texel (i, j), point (2i + c, 2j + r) at 3 r + c: three rows, no
  // parity tests (what the searches read: a texel's pieces, plane, gradient box, maximum).
  std::array<float, 9> texel(int i, int j) const {
    const float* r0 = &v[row[static_cast<size_t>(2 * j)] + static_cast<size_t>(2 * i)];
    const float* r1 = &v[row[static_cast<size_t>(2 * j + 1)] + static_cast<size_t>(i)];
    const float* r2 = &v[row[static_cast<size_t>(2 * j + 2)] + static_cast<size_t>(2 * i)];
    return {r0[0], r0[1], r0[2], r1[0], centre(i, j), r1[1], r2[0], r2[1], r2[2]};
  }
  // bilinear_blend() at fractions (0, 0) of heights >= 0: the texel plus 0 (+0 for -0), bit
  // for bit what the grid held there.
  float centre(int i, int j) const { return texels[static_cast<size_t>(j) * static_cast<size_t>(w) + static_cast<size_t>(i)] + 0.0f; }
};

// Grid point a along an axis is S at pixel a / 2: between texels (a - 1) div 2 and the next,
// at fraction 0 (a odd, a texel centre) or 1/2 (a even, an edge), exactly as bilinear()
// finds them from floor(a / 2 - 1/2).
inline int grid_texel(int a) { return (a + 1) / 2 - 1; }  // a >= 0
inline float grid_fraction(int a) { return (a & 1) != 0 ? 0.0f : 0.5f; }

HalfGrid half_grid(const HeightField& f) {
  const int w = f.height.width, h = f.height.height;
  // The texels with a border of one, as the border rule reads them: S(a / 2, b / 2) is
  // f.bilinear(a / 2, b / 2) bit for bit, without its floor and four addressed lookups
  // per grid point (3 % of the build at 256²).
  const int pw = w + 2;
  std::vector<float> padded(static_cast<size_t>(pw) * static_cast<size_t>(h + 2));
  for (int y = -1; y <= h; ++y)
    for (int x = -1; x <= w; ++x) padded[static_cast<size_t>(y + 1) * static_cast<size_t>(pw) + static_cast<size_t>(x + 1)] = f.texel(x, y);
  auto at = [&](int x, int y) { return padded[static_cast<size_t>(y + 1) * static_cast<size_t>(pw) + static_cast<size_t>(x + 1)]; };
  HalfGrid g;
  g.gw = 2 * w + 1;
  g.gh = 2 * h + 1;
  g.w = w;
  g.texels = f.height.pixels.data();
  g.row.resize(static_cast<size_t>(g.gh));
  size_t n = 0;
  for (int b = 0; b < g.gh; ++b) {
    g.row[static_cast<size_t>(b)] = n;
    n += static_cast<size_t>((b & 1) != 0 ? w + 1 : g.gw);
  }
  g.v.resize(n);
  tbb::parallel_for(tbb::blocked_range<int>(0, g.gh), [&](const tbb::blocked_range<int>& rows) {
    for (int b = rows.begin(); b < rows.end(); ++b) {
      const int y = grid_texel(b);
      const float ty = grid_fraction(b);
      const int step = (b & 1) != 0 ? 2 : 1;
      for (int a = 0; a < g.gw; a += step) {
        const int x = grid_texel(a);
        g.v[g.row[static_cast<size_t>(b)] + static_cast<size_t>(step == 2 ? a >> 1 : a)] =
            bilinear_blend(at(x, y), at(x + 1, y), at(x, y + 1), at(x + 1, y + 1), grid_fraction(a), ty);
      }
    }
  });
  return g;
}

// Two doubles in one SSE2 register on x86-64 (a GCC/Clang vector extension: plain scalar
// code elsewhere): a piece's corners two at a time, a block's texels k and k + 1.
typedef double Pair __attribute__((vector_size(16)));
inline Pair load_pair(const double* p) {
  Pair v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
// max(a, b) per lane. Where a and b differ only in the sign of a zero, either may come back
// (as with pair_min): each use here squares the result, compares it with 0, or adds it to a
// nonzero value, none of which sees that sign.
inline Pair pair_max(Pair a, Pair b) {
#if defined(__SSE2__)
  return _mm_max_pd(a, b);
#else
  return a > b ? a : b;
#endif
}
inline Pair positive_part(Pair a) { return pair_max(a, Pair{0.0, 0.0}); }
inline Pair pair_min(Pair a, Pair b) {
#if defined(__SSE2__)
  return _mm_min_pd(a, b);
#else
  return a < b ? a : b;
#endif
}
inline Pair pair_sqrt(Pair a) {
#if defined(__SSE2__)
  return _mm_sqrt_pd(a);
#else
  return Pair{std::sqrt(a[0]), std::sqrt(a[1])};
#endif
}
// Whether a or b has a lane < 0 (false for NaNs, as the scalar compares).
inline bool any_negative(Pair a, Pair b) {
#if defined(__SSE2__)
  return _mm_movemask_pd(_mm_or_pd(_mm_cmplt_pd(a, Pair{0.0, 0.0}), _mm_cmplt_pd(b, Pair{0.0, 0.0}))) != 0;
#else
  return a[0] < 0 || a[1] < 0 || b[0] < 0 || b[1] < 0;
#endif
}

// Whether a < b in either lane (false for NaNs, as the scalar compares).
inline bool any_less(Pair a, Pair b) {
#if defined(__SSE2__)
  return _mm_movemask_pd(_mm_cmplt_pd(a, b)) != 0;
#else
  return a[0] < b[0] || a[1] < b[1];
#endif
}

// One quarter-texel piece at pixel (x0, y0), 0.5 wide: S = c + a s + b t + e s t with local
// coordinates s = 2 (x - x0), t = 2 (y - y0) in [0, 1].
struct Piece {
  double x0 = 0, y0 = 0, c = 0, a = 0, b = 0, e = 0;
  double top = 0;  // the largest corner value: S's maximum on the piece (a bilinear's is at a corner)
  // value() at the corners (0, 0), (1, 0), (0, 1), (1, 1), as refine() reads them: computed
  // once per piece here, not by each texel that searches it (2 % of the instructions).
  std::array<double, 4> corner{};
  Piece() = default;
  Piece(double px, double py, double v00, double v10, double v01, double v11)
      : x0(px), y0(py), c(v00), a(v10 - v00), b(v01 - v00), e(v00 - v10 - v01 + v11), top(std::max(std::max(v00, v10), std::max(v01, v11))) {
    corner = {value(0, 0), value(1, 0), value(0, 1), value(1, 1)};
  }
  double value(double s, double t) const { return c + a * s + b * t + e * s * t; }
  double gx(double t) const { return 2.0 * (a + e * t); }  // dS/dx, per pixel
  double gy(double s) const { return 2.0 * (b + e * s); }
  double x(double s) const { return x0 + 0.5 * s; }
  double y(double t) const { return y0 + 0.5 * t; }
};

// |(x, y)| without std::hypot's overflow guards (slow, and the values here are bounded by
// the map's size).
inline double length(double x, double y) { return std::sqrt(x * x + y * y); }
// The gap between [lo, hi] and the point or interval beyond it: max(lo - b, 0, a - hi).
inline double gap(double lo, double hi, double a, double b) { return std::max(std::max(lo - b, a - hi), 0.0); }

struct Rect {
  double x0, y0, x1, y1;
};

double rect_distance(const Rect& r, const Rect& f) {
  const double dx = gap(f.x0, f.x1, r.x0, r.x1);
  const double dy = gap(f.y0, f.y1, r.y0, r.y1);
  return length(dx, dy);
}

// The supremum of psi(y) = (S(y) - T) / dist(y, F) over the pieces it is shown, for one
// footprint F with apex T: the reciprocal of the cone ratio in texels per unit height.
// `psi` is attained at a point of the surface; `bound` is the largest upper bound of a piece
// dismissed within the tolerance. The answer lies in [psi, max(psi, bound)].
//
// What is returned is level() = max(psi, bound), so a region whose upper bound is at most
// level() cannot change it (what it holds is attained below the bound, or bounded by it):
// every test prunes against level(), not psi. This matters where a bound had to be kept
// (relaxed cones near the edge of the region seen descending): regions no steeper than the
// bound already conceded are then left alone instead of refined to the depth cap.
class ConeSearch {
 public:
  ConeSearch(const Rect& footprint, double top, bool relaxed, double tolerance, bool exact_fans)
      : f_(footprint), top_(top), relaxed_(relaxed), tol_(tolerance), max_depth_(relaxed ? kMaxDepthRelaxed : kMaxDepth), fans_(exact_fans) {}

  double psi = 0;
  double bound = 0;
  double level() const { return std::max(psi, bound); }

  void piece(const Piece& p) {
    if (p.top <= top_) return;  // no point above the apex (most pieces offered)
    const double px1 = p.x0 + 0.5, py1 = p.y0 + 0.5;
    // The zone in locals first: tested through the members, the two int stores were read
    // back as one 64-bit load, which store forwarding cannot serve (a stall of ~40 % of this
    // function's time at 4096², perf).
    const int zx = p.x0 >= f_.x1 ? 1 : (px1 <= f_.x0 ? -1 : 0);
    const int zy = p.y0 >= f_.y1 ? 1 : (py1 <= f_.y0 ? -1 : 0);
    if (zx == 0 && zy == 0) return;  // inside F, where S <= T
    zx_ = zx;
    zy_ = zy;
    // Relaxed cones: most pieces offered rise away from F (the texel's gradient box could not
    // show it; the piece's own corners can), so that test first (smooth bumps at 512²: 10.9 M
    // of 15.1 M pieces).
    if (relaxed_ && never_descends(p, 0, 0, 1, 1)) return;
    const std::array<double, 4>& v = p.corner;
    // refine()'s first tests, which end most pieces, here without its call, which then
    // starts after them (settle()).
    double upper = 0;
    if (zx_ == 0 || zy_ == 0) {
      // The exact supremum over a side piece (<= 0 when no corner is above T).
      upper = side_upper(p, 0, 0, 1, 1, v);
      if (upper <= level()) return;
    } else {
      // Corner zone: the nearest point of F is its corner c.
      cx_ = zx_ > 0 ? f_.x1 : f_.x0;
      cy_ = zy_ > 0 ? f_.y1 : f_.y0;
      // Before the corner's setup too (a piece that touches c, at distance 0, goes on unless
      // no corner is above T: it may hold the limit at c).
      const double vmax = std::max(std::max(v[0], v[1]), std::max(v[2], v[3]));
      if (vmax <= top_) return;
      const double near = nearest(p, 0, 0, 1, 1);
      if (near > 0 && vmax - top_ <= level() * near) return;
      // The piece touches c when one of its corners is c (local coordinates sc, tc).
      touches_ = (cx_ == p.x0 || cx_ == px1) && (cy_ == p.y0 || cy_ == py1);
      sc_ = 2 * (cx_ - p.x0);
      tc_ = 2 * (cy_ - p.y0);
      // Along a ray y = c + r u out of c (u a unit vector into the zone's quadrant), the
      // piece's polynomial is quadratic in r: S = S(c) + r grad S(c) . u + r^2 4 e zx zy ux uy
      // (S(c) and grad S(c) of the polynomial extended to c), and dist(y, F) = r, so
      //     psi = (S(c) - T) / r + grad S(c) . u + r 4 e zx zy ux uy.
      // Unless S(c) < T and e zx zy < 0 (then psi is concave in r and may peak inside), psi
      // is monotone or convex along every ray, so its supremum over a rectangle of the piece
      // lies on the rectangle's boundary, where exact one-dimensional maxima settle it.
      // (sc_, tc_ are integers and the grid values floats: S(c) is a sum of float differences
      // with small integer weights, exact in double unless heights span 2^29 in magnitude.)
      boundary_max_ = !(p.value(sc_, tc_) < top_ && p.e * zx_ * zy_ < 0);
    }
    if (zx_ != 0 && zy_ != 0 && touches_ && p.value(sc_, tc_) >= top_) attain_corner_limit(p);
    settle(p, 0, 0, 1, 1, v, 0xf, 0, upper);
  }

 private:
  double distance(double x, double y) const {
    const double dx = gap(f_.x0, f_.x1, x, x);
    const double dy = gap(f_.y0, f_.y1, y, y);
    return length(dx, dy);
  }
  // The same for a point of the current piece, whose zone fixes the form: the gap along one
  // axis beside F (no square root), the distance to the corner c off it. The same values,
  // bit for bit (a correctly rounded square root of a rounded square is the number).
  double piece_distance(double x, double y) const {
    if (zy_ == 0) return std::max(zx_ > 0 ? x - f_.x1 : f_.x0 - x, 0.0);
    if (zx_ == 0) return std::max(zy_ > 0 ? y - f_.y1 : f_.y0 - y, 0.0);
    return length(x - cx_, y - cy_);
  }
  // Some point of F sees the surface at (s, t) fall away: grad S . (y - x) < 0. Linear in x,
  // so F's corners decide; the sum is smallest at the corner where each of its two terms is,
  // and rounding is monotone, so the smaller term along each axis gives the verdict of the
  // four corners' sums, bit for bit.
  bool descends(const Piece& p, double s, double t) const { return falls(p.gx(t), p.gy(s), p.x(s), p.y(t)); }
  bool falls(double gx, double gy, double x, double y) const {
    return std::min(gx * (x - f_.x0), gx * (x - f_.x1)) + std::min(gy * (y - f_.y0), gy * (y - f_.y1)) < 0;
  }
  // No point of the rectangle descends: grad S(y) . (y - x) is bilinear in y on a piece (the
  // gradient is affine and has no x^2 or y^2 term), so its minimum is at a corner.
  // falls() at the four corners, two at a time: lane j of a pair is the corner at y_j, whose
  // dS/dx is gx_j (dS/dx depends on t only, dS/dy on s only). The same IEEE operations per
  // corner, so the same verdicts (a minimum of two equal products may take the other's zero
  // sign, which no sum's sign depends on); at 1024² relaxed bumps this test was 10 % of the
  // time as four scalar calls with early exits.
  bool never_descends(const Piece& p, double s0, double t0, double s1, double t1) const {
    const Pair gx = {p.gx(t0), p.gx(t1)}, y = {p.y(t0), p.y(t1)};
    auto along_x = [&](double x) { return pair_min(gx * (x - f_.x0), gx * (x - f_.x1)); };
    auto along_y = [&](double gy) { return pair_min(gy * (y - f_.y0), gy * (y - f_.y1)); };
    return !any_negative(along_x(p.x(s0)) + along_y(p.gy(s0)), along_x(p.x(s1)) + along_y(p.gy(s1)));
  }
  // Some single corner of F sees the whole rectangle descend: grad S(y) . (y - x) is
  // bilinear in y (see never_descends), so negative at the rectangle's corners means
  // negative throughout.
  bool descends_throughout(const Piece& p, double s0, double t0, double s1, double t1) const {
    // The rectangle's corners' gradients and positions, once for F's four corners.
    const double gx[2] = {p.gx(t0), p.gx(t1)}, gy[2] = {p.gy(s0), p.gy(s1)};
    const double x[2] = {p.x(s0), p.x(s1)}, y[2] = {p.y(t0), p.y(t1)};
    for (double fx : {f_.x0, f_.x1})
      for (double fy : {f_.y0, f_.y1}) {
        bool all = true;
        for (int i = 0; i < 2; ++i)
          for (int j = 0; j < 2; ++j) all = all && gx[j] * (x[i] - fx) + gy[i] * (y[j] - fy) < 0;
        if (all) return true;
      }
    return false;
  }
  // The interior maximum of psi along an edge of a corner-zone rectangle: `fixed` is t (an
  // edge along x, `along_x`) or s, the edge runs over [lo, hi] of the other coordinate. With
  // q the offset from c along the edge and k the fixed offset across it, S is linear,
  // S - T = A + B q, and psi(q) = (A + B q) / sqrt(k^2 + q^2) has its one stationary point
  // where B (k^2 + q^2) = (A + B q) q, at q = B k^2 / A. Its ends are the rectangle's corners.
  void edge_maximum(const Piece& p, double fixed, double lo, double hi, bool along_x) {
    const double z = along_x ? zx_ : zy_;
    const double c_local = along_x ? sc_ : tc_;  // c's position along the edge, local
    const double k = along_x ? (p.y(fixed) - cy_) * zy_ : (p.x(fixed) - cx_) * zx_;
    const double a = (along_x ? p.value(c_local, fixed) : p.value(fixed, c_local)) - top_;
    const double b = 2 * z * (along_x ? p.a + p.e * fixed : p.b + p.e * fixed);  // dS/dq
    if (a == 0) return;  // psi monotone in q: the ends decide
    const double local = c_local + 2 * z * (b * k * k / a);
    if (!(local > lo && local < hi)) return;
    if (along_x) {
      attain(p, local, fixed, p.value(local, fixed));
    } else {
      attain(p, fixed, local, p.value(fixed, local));
    }
  }
  void attain(const Piece& p, double s, double t, double v) {
    if (v <= top_) return;  // most points offered; the distance is not needed for them
    const double d = piece_distance(p.x(s), p.y(t));
    if (d <= 0) return;
    const double ratio = (v - top_) / d;
    if (ratio > psi && (!relaxed_ || descends(p, s, t))) {  // the cheaper test first
      psi = ratio;
      best = {p.x(s), p.y(t), v, p.gx(t), p.gy(s), true};
    }
  }

 public:
  // The point that gave psi, to seed the search of a neighbouring texel: its steepest point
  // is usually close by, and a good slope from the start lets the search skip more.
  struct Point {
    double x = 0, y = 0, v = 0, gx = 0, gy = 0;
    bool valid = false;
  } best;
  // Texel (x, y) of the grid's map shifted by (ox, oy) pixels, in F's row or column but not
  // F: the supremum of psi over every point of it, without its pieces. The gap to F is along
  // one axis, so as in side_upper: along a column of the texel the gap is constant and S
  // linear on each piece, along a row (S - T) / gap is monotone on each piece, and where the
  // row leaves F's edge (gap 0, S <= T) it is at most its value half a texel on. So the
  // largest (S - T) / gap over the 3 x 3 grid points at a positive gap is the supremum.
  // Conservative cones attain it (the gradient of a seed is read by relaxed cones only): the
  // texel is settled. For relaxed ones it bounds the supremum over the points seen
  // descending: settled (dismissed) when no steeper than the level, else its pieces decide.
  bool side_texel_settles(const HalfGrid& g, int x, int y, double ox, double oy) {
    const double px = ox + x, py = oy + y;
    const bool in_row = py == f_.y0;  // else in F's column: the gap is along y
    double upper = relaxed_ ? 0.0 : psi;  // conservative cones raise psi itself
    const std::array<float, 9> grid = g.texel(x, y);
    for (int r = 0; r <= 2; ++r)
      for (int c = 0; c <= 2; ++c) {
        const double v = grid[static_cast<size_t>(3 * r + c)];
        if (v <= top_) continue;
        const double qx = px + 0.5 * c, qy = py + 0.5 * r;
        const double d = in_row ? std::max(qx - f_.x1, f_.x0 - qx) : std::max(qy - f_.y1, f_.y0 - qy);
        if (!(d > 0) || !((v - top_) / d > upper)) continue;
        upper = (v - top_) / d;
        if (!relaxed_) {
          psi = upper;
          best = {qx, qy, v, 0, 0, true};
        }
      }
    return !relaxed_ || upper <= level();
  }

  // Texel (x, y) of the grid's map shifted by (ox, oy) pixels, off F's rows and columns and
  // not touching F (in a corner zone, whose nearest point of F is its corner c): whether no
  // point of it can be steeper than `slope`, from its 3 x 3 grid values `v` alone (no
  // pieces). As settle()'s first bound for one piece, over the whole texel: dist(y, F) =
  // |y - c| >= u . (y - c) for a unit u, and where u . (y - c) > 0 over the texel,
  // (S - T) / (u . (y - c)) is on each of its four pieces a bilinear over a positive linear
  // function, monotone along each axis, so its supremum over the texel is at one of the 9
  // grid points. u: the direction from c to the texel's centre, then to its four corners
  // (corner_upper's directions); each one that keeps every grid point at most `slope`
  // settles the texel. (On the smooth bumps at 256², after the plane test's one-root bound,
  // the centre settles 46 % of the texels it is tried on, the corners 24 % more.)
  // `slope`: level(), or the level widened by the tolerance (a concession the caller records).
  bool corner_texel_settles(const std::array<double, 9>& v, double px, double py, double slope) const {
    const int zx = px >= f_.x1 ? 1 : (px + 1 <= f_.x0 ? -1 : 0);
    const int zy = py >= f_.y1 ? 1 : (py + 1 <= f_.y0 ? -1 : 0);
    if (zx == 0 || zy == 0) return false;
    const double cx = zx > 0 ? f_.x1 : f_.x0, cy = zy > 0 ? f_.y1 : f_.y0;
    // Offsets from c away from F (>= 0) of the grid's columns and rows, and the indices of
    // the near and far ones.
    const std::array<double, 3> qx = {(px - cx) * zx, (px + 0.5 - cx) * zx, (px + 1 - cx) * zx};
    const std::array<double, 3> qy = {(py - cy) * zy, (py + 0.5 - cy) * zy, (py + 1 - cy) * zy};
    const size_t lx = zx > 0 ? 0 : 2, hx = 2 - lx, ly = zy > 0 ? 0 : 2, hy = 2 - ly;
    if (qx[lx] <= 0 && qy[ly] <= 0) return false;  // touches c
    // The level less a relative margin of 1e-9, far above the rounding of the products and
    // sums below (every term of u . q >= 0: offsets and directions along the zone; T n
    // against S n, both from floats), so that a texel is settled only where the exact
    // comparison would settle it; a borderline one is left to its pieces.
    const double lvl = slope * (1 - 1e-9);
    // S - T at the grid points (differences of floats: exact), columns 0 and 1 of each row
    // as a pair, column 2 apart.
    const Pair e0 = load_pair(&v[0]) - top_, e1 = load_pair(&v[3]) - top_, e2 = load_pair(&v[6]) - top_;
    const double f0 = v[2] - top_, f1 = v[5] - top_, f2 = v[8] - top_;
    // Settled by direction (ux, uy) (>= 0, not both 0): (S - T) n <= lvl (u . q) at every
    // grid point (a point above T at u . q = 0 fails it).
    auto along = [&](double ux, double uy) {
      const double n = length(ux, uy), ax = lvl * ux, ay = lvl * uy;
      const Pair cols = Pair{ax * qx[0], ax * qx[1]};
      const double col2 = ax * qx[2], r0 = ay * qy[0], r1 = ay * qy[1], r2 = ay * qy[2];
      if (any_less(cols + r0, e0 * n) || any_less(cols + r1, e1 * n) || any_less(cols + r2, e2 * n)) return false;
      return !(f0 * n > col2 + r0) && !(f1 * n > col2 + r1) && !(f2 * n > col2 + r2);
    };
    if (along(qx[1], qy[1])) return true;
    for (size_t b : {ly, hy})
      for (size_t a : {lx, hx})
        if ((qx[a] > 0 || qy[b] > 0) && along(qx[a], qy[b])) return true;
    return false;
  }

  void seed(const Point& q) {
    if (!q.valid || q.v <= top_) return;
    // Most seeds are no steeper than psi: (v - T)^2 well below psi^2 d^2 says so without the
    // square root and the division (the margin, far above their rounding, leaves every
    // borderline seed to the exact test below; up to 32 seeds a texel since the wavefront).
    const double gx = gap(f_.x0, f_.x1, q.x, q.x), gy = gap(f_.y0, f_.y1, q.y, q.y);
    const double rise = q.v - top_;
    if (rise * rise < psi * psi * (gx * gx + gy * gy) * (1 - 1e-9)) return;
    // Relaxed cones: a seed not seen descending goes before its square root is taken (on the
    // bricks at 1024² that root's latency was 5 % of run()).
    if (relaxed_ && !falls(q.gx, q.gy, q.x, q.y)) return;
    const double d = length(gx, gy);
    if (d <= 0) return;
    if ((q.v - top_) / d > psi) {
      psi = (q.v - top_) / d;
      best = q;
    }
  }

 private:

  // Where the surface reaches T at F's corner c (S(c) = T), psi tends to grad S(c) . u
  // along the direction u from c: no point attains the supremum over the quadrant, its
  // limit does (the infimum of the ratio is not attained either). A subdivision keeps the
  // same few directions at c and would never close the gap, so the limit is taken here:
  // the support function of the quarter circle at grad S(c). Relaxed cones take it only
  // where some corner of F sees c's neighbourhood descend (f_k(c) < 0 for an x_k != c).
  void attain_corner_limit(const Piece& p) {
    const double gx = p.gx(tc_) * zx_, gy = p.gy(sc_) * zy_;
    if (relaxed_) {
      bool falls = false;
      for (double fx : {f_.x0, f_.x1})
        for (double fy : {f_.y0, f_.y1})
          falls |= (fx != cx_ || fy != cy_) && p.gx(tc_) * (cx_ - fx) + p.gy(sc_) * (cy_ - fy) < 0;
      if (!falls) return;
    }
    psi = std::max(psi, gx >= 0 && gy >= 0 ? length(gx, gy) : std::max(gx, gy));
  }

  // v: S at the corners (s0, t0), (s1, t0), (s0, t1), (s1, t1), from the caller, which has
  // evaluated them already (the same calls, so the same values). fresh: the corners not yet
  // offered to attain(); a point offered again cannot raise psi, which only grows.
  void refine(const Piece& p, double s0, double t0, double s1, double t1, const std::array<double, 4>& v, unsigned fresh, int depth) {
    double vmax = -kInf;
    for (int k = 0; k < 4; ++k) vmax = std::max(vmax, v[k]);  // a bilinear function's maximum is at a corner
    if (vmax <= top_) return;
    // First the cheapest bound, which ends most rectangles: beside F the exact supremum, off
    // its corner the plain bound (max S - T) / (nearest distance).
    double upper = 0;
    if (zx_ == 0 || zy_ == 0) {
      upper = side_upper(p, s0, t0, s1, t1, v);
      if (upper <= level()) return;
    } else {
      if (vmax - top_ <= level() * nearest(p, s0, t0, s1, t1)) return;
    }
    settle(p, s0, t0, s1, t1, v, fresh, depth, upper);
  }

  // refine() after its first bound has not dismissed the rectangle (`upper`: that bound
  // beside F, unused off its corner). piece() enters here for a whole piece, having made the
  // same tests.
  void settle(const Piece& p, double s0, double t0, double s1, double t1, const std::array<double, 4>& v, unsigned fresh, int depth,
              double upper) {
    const std::array<double, 4> ss = {s0, s1, s0, s1}, ts = {t0, t0, t1, t1};
    // Relaxed cones: psi has no local maximum inside the set D seen descending, in either
    // zone. At a stationary point y of psi = (S - T) / dist with S(y) > T, grad S = psi n, n
    // the unit direction from y's nearest point q of F (grad dist); F is convex and lies
    // behind the line through q normal to n, so n . (y - x) >= dist(y, F) > 0 for every x in
    // F, and grad S(y) . (y - x) > 0: no corner of F sees y descend. So over a rectangle R
    // the supremum over R n D lies on R's edges or on the curves bounding D, which crossed()
    // searches exactly, whatever the curvature of S along the rays (boundary_max_).
    bool exact_crossing = false;
    // (The descent tests after the cheapest bound, which ends more rectangles for less.)
    if (zx_ == 0 || zy_ == 0) {
      if (relaxed_ && never_descends(p, s0, t0, s1, t1)) return;
      exact_crossing = relaxed_ && !descends_throughout(p, s0, t0, s1, t1);
    } else {
      // Then one bound over every point (the direction to the rectangle's centre, see
      // corner_upper, which starts with it), cheaper than the descent tests and the eight
      // evaluations below when it settles the rectangle.
      if (!touches_) {
        const double ux = p.x(s0) + p.x(s1) - 2 * cx_, uy = p.y(t0) + p.y(t1) - 2 * cy_;
        const double n = length(ux, uy);
        // Settled when at every corner u . (y - c) = dot / n > 0 and (v - T) / (dot / n) <=
        // level. Those two divisions, in a chain, held a third of this function's samples
        // (perf, conservative bricks at 1024²); where
        // (v - T) n and level dot differ by more than a relative 1e-9 (far above the rounding
        // of either form) their comparison gives the same verdict without them.
        const double lvl = level();
        bool settled = true;
        for (int k = 0; k < 4 && settled; ++k) {
          const double dot = ux * (p.x(ss[k]) - cx_) + uy * (p.y(ts[k]) - cy_), rise = v[k] - top_;
          if (!(dot > 1e-290)) {  // not positive, or small enough for the quotient to underflow
            const double l = dot / n;
            settled = l > 0 && (rise / l <= lvl);
            continue;
          }
          const double lhs = rise * n, rhs = lvl * dot;
          if (lhs <= rhs * (1 - 1e-9)) continue;
          if (lhs > rhs * (1 + 1e-9)) {
            settled = false;
            continue;
          }
          settled = rise / (dot / n) <= lvl;
        }
        if (settled) return;
      }
      if (relaxed_ && never_descends(p, s0, t0, s1, t1)) return;
      if (boundary_max_ || relaxed_) {
        // The supremum is on the boundary (of the rectangle, or for relaxed cones of its part
        // seen descending, see above), where it is computed exactly.
        if (!relaxed_ || descends_throughout(p, s0, t0, s1, t1)) {
          for (int k = 0; k < 4; ++k)
            if (fresh & (1u << k)) attain(p, ss[k], ts[k], v[k]);
          for (double t : {t0, t1}) edge_maximum(p, t, s0, s1, true);
          for (double s : {s0, s1}) edge_maximum(p, s, t0, t1, false);
          return;
        }
        exact_crossing = true;
      }
      upper = corner_upper(p, s0, t0, s1, t1, v);
    }
    if (upper <= level()) return;
    for (int k = 0; k < 4; ++k)
      if (fresh & (1u << k)) attain(p, ss[k], ts[k], v[k]);
    const double sm = 0.5 * (s0 + s1), tm = 0.5 * (t0 + t1);
    const double vm = p.value(sm, tm);
    attain(p, sm, tm, vm);
    if (upper > std::max(psi * (1 + tol_), bound) && exact_crossing && crossed(p, s0, t0, s1, t1)) return;
    if (upper <= std::max(psi * (1 + tol_), bound) || depth >= max_depth_) {
      bound = std::max(bound, upper);
      return;
    }
    // The children's corners: this rectangle's corners and centre (offered above) and the
    // midpoints of its edges.
    const double top_mid = p.value(sm, t0), left_mid = p.value(s0, tm), right_mid = p.value(s1, tm), bottom_mid = p.value(sm, t1);
    refine(p, s0, t0, sm, tm, {v[0], top_mid, left_mid, vm}, 0x6, depth + 1);
    refine(p, sm, t0, s1, tm, {top_mid, v[1], vm, right_mid}, 0x9, depth + 1);
    refine(p, s0, tm, sm, t1, {left_mid, vm, v[2], bottom_mid}, 0x9, depth + 1);
    refine(p, sm, tm, s1, t1, {vm, right_mid, bottom_mid, v[3]}, 0x6, depth + 1);
  }

  // The nearest distance from a corner-zone rectangle to F (to its corner c).
  double nearest(const Piece& p, double s0, double t0, double s1, double t1) const {
    const double ax = (p.x(s0) - cx_) * zx_, bx = (p.x(s1) - cx_) * zx_, ay = (p.y(t0) - cy_) * zy_, by = (p.y(t1) - cy_) * zy_;
    return length(std::min(ax, bx), std::min(ay, by));
  }

  // Side zone: dist is the gap along one axis. Along a row S is linear, and (S - T) / gap
  // is then monotone, so the supremum over the rectangle (and over any part of it cut along
  // rows) is at a corner; at gap 0 the row's value tends to at most that of its far end
  // (S <= T on F's edge). The supremum of psi over the rectangle, exactly.
  double side_upper(const Piece& p, double s0, double t0, double s1, double t1, const std::array<double, 4>& v) const {
    const std::array<double, 4> ss = {s0, s1, s0, s1}, ts = {t0, t0, t1, t1};
    double upper = 0;
    for (int k = 0; k < 4; ++k) {
      const double d = piece_distance(p.x(ss[k]), p.y(ts[k]));
      if (d > 0) upper = std::max(upper, (v[k] - top_) / d);
    }
    return upper;
  }

  // Corner zone: an upper bound of psi over the rectangle (every point, seen descending or not).
  double corner_upper(const Piece& p, double s0, double t0, double s1, double t1, const std::array<double, 4>& v) const {
    const std::array<double, 4> ss = {s0, s1, s0, s1}, ts = {t0, t0, t1, t1};
    // dist = |y - c| >= u . (y - c) for any unit u (Cauchy-Schwarz), with offsets measured
    // away from F (both >= 0 here). (S - T) / (u . (y - c)) is a bilinear over a linear
    // function, monotone along each axis, so over the rectangle it peaks at a corner. Each u
    // gives a bound; the directions to the corners and to the centre make it tight to second
    // order in the rectangle's angular size (exact when the supremum sits at a corner, as on
    // a plane).
    std::array<double, 4> ox{}, oy{};
    for (int k = 0; k < 4; ++k) {
      ox[k] = (p.x(ss[k]) - cx_) * zx_;
      oy[k] = (p.y(ts[k]) - cy_) * zy_;
    }
    double upper = kInf;
    auto along = [&](double ux, double uy) {
      const double n = length(ux, uy);
      if (n <= 0) return;
      double b = 0;
      for (int k = 0; k < 4; ++k) {
        const double l = (ux * ox[k] + uy * oy[k]) / n;
        if (l <= 0) return;  // u . (y - c) must stay positive on the rectangle
        b = std::max(b, (v[k] - top_) / l);
      }
      upper = std::min(upper, b);
    };
    // The centre first, then the corners, until one settles it.
    along(ox[0] + ox[3], oy[0] + oy[3]);
    for (int k = 0; k < 4 && upper > level(); ++k) along(ox[k], oy[k]);
    if (touches_) {
      // Mean value bound from c: S(y) - T <= S(c) - T + (grad S(xi) . u) |y - c|, u the
      // unit direction from c into the zone's quadrant and xi on the segment, inside the
      // box spanned by c and the rectangle. max over u of g . u is the support function of
      // the quarter circle (|g| when g points into the quadrant, else its larger component
      // along the zone), convex in g; the gradient is affine on the piece, so the box's
      // corners decide.
      const double bs0 = std::min(s0, sc_), bs1 = std::max(s1, sc_), bt0 = std::min(t0, tc_), bt1 = std::max(t1, tc_);
      double g = 0;
      for (double s : {bs0, bs1})
        for (double t : {bt0, bt1}) {
          const double gx = p.gx(t) * zx_, gy = p.gy(s) * zy_;
          g = std::max(g, gx >= 0 && gy >= 0 ? length(gx, gy) : std::max(gx, gy));
        }
      double far = 0;
      for (int k = 0; k < 4; ++k) far = std::max(far, length(p.x(ss[k]) - cx_, p.y(ts[k]) - cy_));
      if (far > 0) upper = std::min(upper, g + (p.value(sc_, tc_) - top_) / far);
    }
    return upper;
  }

  // A point of the closure of the set seen descending (on the edge of that set, or on a
  // rectangle's edge next to it): the supremum over the set is the maximum over its closure,
  // psi being continuous, so such points are offered without the descent test. (Counting a
  // limit point can only make the cone narrower, never wider.)
  void attain_closure(const Piece& p, double s, double t) {
    const double v = p.value(s, t);
    if (v <= top_) return;
    const double d = piece_distance(p.x(s), p.y(t));
    if (d <= 0) return;
    const double ratio = (v - top_) / d;
    if (ratio > psi) {
      psi = ratio;
      best = {p.x(s), p.y(t), v, p.gx(t), p.gy(s), true};
    }
  }

  // f_k(s, t) = grad S(y) . (y - x_k) for a corner x_k of F, on a piece: bilinear in the
  // local coordinates (grad S is affine, dS/dx in t only and dS/dy in s only), so
  // f_k = A + B s + C t + E s t; the relaxed cone counts the points where some f_k < 0.
  struct Bilinear {
    double a, b, c, e;
    double at(double s, double t) const { return a + b * s + c * t + e * s * t; }
  };

  // The exact supremum of psi over the part of a rectangle seen descending, where psi has no
  // interior maximum (side zone; corner zone with boundary_max_), for a rectangle that the
  // edge of the descending set D = union of {f_k < 0} crosses. Over R and D_k = {f_k < 0} the
  // maximum of psi lies on the boundary of R n D_k: the parts of R's edges where f_k <= 0
  // (f_k is linear along an edge: one interval) and the arcs of the curve f_k = 0 inside R
  // (a hyperbola's branches, each monotone), searched in one dimension by branch and bound.
  // Returns false (nothing done) on a degenerate curve, where the caller refines instead.
  // Where a component of grad S keeps its sign over R, one side of F gives the smaller term
  // along that axis at every point of R (gx (x - fx) is least at fx = F's right edge where
  // gx >= 0, at its left edge where gx <= 0; falls() takes the same minimum): the other
  // side's D_k lie inside that side's over R and cannot hold a larger supremum, so only the
  // one side is searched (on the bricks the signs are constant on 3 rectangles out of 4).
  // Kept out of line: inlined, it made refine()'s frame larger for the conservative cones too
  // (+4 % of refine's own instructions on the bricks), which never call it.
  [[gnu::noinline]] bool crossed(const Piece& p, double s0, double t0, double s1, double t1) {
    // Filled for k < n only (not value-initialised: zeroing them was 12 % of this function's
    // samples, perf, relaxed bumps at 4096²).
    std::array<Bilinear, 4> fk;
    std::array<std::array<double, 4>, 4> fv;
    std::array<Arcs, 4> ends;
    int n = 0;
    // dS/dx is affine in t and dS/dy in s: the ends decide their signs over R.
    const double gx0 = p.gx(t0), gx1 = p.gx(t1), gy0 = p.gy(s0), gy1 = p.gy(s1);
    const bool x_rises = gx0 >= 0 && gx1 >= 0, x_falls = gx0 <= 0 && gx1 <= 0;
    const bool y_rises = gy0 >= 0 && gy1 >= 0, y_falls = gy0 <= 0 && gy1 <= 0;
    for (double fx : {f_.x0, f_.x1})
      for (double fy : {f_.y0, f_.y1}) {
        if ((fx == f_.x0 && x_rises) || (fx == f_.x1 && x_falls && !x_rises)) continue;
        if ((fy == f_.y0 && y_rises) || (fy == f_.y1 && y_falls && !y_rises)) continue;
        const double dx = p.x0 - fx, dy = p.y0 - fy;
        // 2 (a + e t)(dx + s / 2) + 2 (b + e s)(dy + t / 2)
        const Bilinear q{2 * (p.a * dx + p.b * dy), p.a + 2 * p.e * dy, p.b + 2 * p.e * dx, 2 * p.e};
        const std::array<double, 4> f = {q.at(s0, t0), q.at(s1, t0), q.at(s0, t1), q.at(s1, t1)};
        if (!(std::min({f[0], f[1], f[2], f[3]}) < 0)) continue;  // D_k misses R (f_k bilinear: corners decide)
        // The arcs first: a degenerate curve leaves the rectangle to the caller untouched.
        if (!arcs(q, f, s0, t0, s1, t1, ends[static_cast<size_t>(n)])) return false;
        fk[static_cast<size_t>(n)] = q;
        fv[static_cast<size_t>(n++)] = f;
      }
    for (int k = 0; k < n; ++k) {
      const Bilinear& q = fk[static_cast<size_t>(k)];
      const std::array<double, 4>& f = fv[static_cast<size_t>(k)];
      edge_part(p, t0, s0, s1, f[0], f[1], true);
      edge_part(p, t1, s0, s1, f[2], f[3], true);
      edge_part(p, s0, t0, t1, f[0], f[2], false);
      edge_part(p, s1, t0, t1, f[1], f[3], false);
      const Arcs& a = ends[static_cast<size_t>(k)];
      for (int i = 0; i < a.count; ++i) search_arc(p, q, a.ends[static_cast<size_t>(i)]);
    }
    return true;
  }

  // The part of an edge where f <= 0 (f linear along it, flo and fhi at its ends): its ends,
  // and in the corner zone the edge's interior maximum (edge_maximum) when inside.
  void edge_part(const Piece& p, double fixed, double lo, double hi, double flo, double fhi, bool along_x) {
    if (flo > 0 && fhi > 0) return;
    double a = lo, b = hi;
    if (flo > 0) a = lo + (hi - lo) * (flo / (flo - fhi));
    if (fhi > 0) b = lo + (hi - lo) * (flo / (flo - fhi));
    a = std::clamp(a, lo, hi);
    b = std::clamp(b, lo, hi);
    for (double q : {a, b}) {
      if (along_x) {
        attain_closure(p, q, fixed);
      } else {
        attain_closure(p, fixed, q);
      }
    }
    if (zx_ != 0 && zy_ != 0 && b > a) edge_maximum(p, fixed, a, b, along_x);
  }

  // The arcs of f = 0 inside [s0, s1] x [t0, t1] (f's corner values in fc), each by its ends
  // (s, t, s, t), one per branch of the curve.
  struct Arcs {
    int count = 0;
    std::array<std::array<double, 4>, 2> ends;
  };
  // Returns false where they are not well formed (a branch that does not cross the
  // boundary exactly twice).
  bool arcs(const Bilinear& f, const std::array<double, 4>& fc, double s0, double t0, double s1, double t1, Arcs& out) const {
    out.count = 0;
    // Where f = 0 on the boundary: sign changes along the edges, and corners where f = 0.
    std::array<std::array<double, 2>, 8> at{};
    int count = 0;
    auto add = [&](double s, double t) {
      for (int k = 0; k < count; ++k)
        if (at[static_cast<size_t>(k)][0] == s && at[static_cast<size_t>(k)][1] == t) return;
      if (count < 8) at[static_cast<size_t>(count)] = {s, t};
      ++count;
    };
    const std::array<double, 4> ss = {s0, s1, s0, s1}, ts = {t0, t0, t1, t1};
    for (int k = 0; k < 4; ++k)
      if (fc[static_cast<size_t>(k)] == 0) add(ss[static_cast<size_t>(k)], ts[static_cast<size_t>(k)]);
    auto edge = [&](int i, int j) {  // corners i and j, one edge
      const double fi = fc[static_cast<size_t>(i)], fj = fc[static_cast<size_t>(j)];
      if (!((fi < 0 && fj > 0) || (fi > 0 && fj < 0))) return;
      const double r = fi / (fi - fj);
      add(ss[static_cast<size_t>(i)] + r * (ss[static_cast<size_t>(j)] - ss[static_cast<size_t>(i)]),
          ts[static_cast<size_t>(i)] + r * (ts[static_cast<size_t>(j)] - ts[static_cast<size_t>(i)]));
    };
    edge(0, 1);
    edge(2, 3);
    edge(0, 2);
    edge(1, 3);
    if (count == 0) return true;
    // Branches: f = e (s - s*)(t - t*) + const with s* = -c / e; a branch keeps the sign of
    // s - s* (a line when e = 0: one branch). Each must meet the boundary exactly twice.
    std::array<int, 8> side{};
    int minus = 0, plus = 0;
    for (int k = 0; k < count && k < 8; ++k) {
      int sgn = 1;
      if (f.e != 0) {
        const double d = at[static_cast<size_t>(k)][0] + f.c / f.e;
        if (d == 0) return false;
        sgn = d > 0 ? 1 : -1;
      }
      side[static_cast<size_t>(k)] = sgn;
      (sgn > 0 ? plus : minus) += 1;
    }
    if (count > 4 || (minus != 0 && minus != 2) || (plus != 0 && plus != 2)) return false;
    for (int sgn : {-1, 1}) {
      std::array<double, 4> arc{};
      int got = 0;
      for (int k = 0; k < count; ++k)
        if (side[static_cast<size_t>(k)] == sgn) {
          arc[static_cast<size_t>(2 * got)] = at[static_cast<size_t>(k)][0];
          arc[static_cast<size_t>(2 * got + 1)] = at[static_cast<size_t>(k)][1];
          ++got;
        }
      if (got == 2) out.ends[static_cast<size_t>(out.count++)] = arc;
    }
    return true;
  }

  // An arc of f = 0 between its ends e (s, t, s, t), parametrised by u, the local coordinate
  // along which it extends further (s or t); the other coordinate is w(u) = -(P + Q u) /
  // (R + E u), R + E u keeping its sign on a branch (see arcs()). On it
  // S - T = N(u) / (R + E u), N quadratic: S = c + g u + (h + e u) w gives
  // (S - T)(R + E u) = (c - T + g u)(R + E u) - (h + e u)(P + Q u).
  struct ArcForm {
    bool along_s;
    double u0, u1, wlo, whi;  // the ends' u, and the range of w
    double fp, fq, fr, fe;    // f = P + Q u + R w + E u w
    std::array<double, 3> n;  // N's coefficients, constant first
    double w(double u) const { return std::clamp(-(fp + fq * u) / (fr + fe * u), wlo, whi); }
  };
  ArcForm arc_form(const Piece& p, const Bilinear& f, const std::array<double, 4>& e) const {
    ArcForm a;
    a.along_s = std::abs(e[2] - e[0]) >= std::abs(e[3] - e[1]);
    a.u0 = a.along_s ? e[0] : e[1];
    a.u1 = a.along_s ? e[2] : e[3];
    a.wlo = std::min(a.along_s ? e[1] : e[0], a.along_s ? e[3] : e[2]);
    a.whi = std::max(a.along_s ? e[1] : e[0], a.along_s ? e[3] : e[2]);
    const double g = a.along_s ? p.a : p.b, h = a.along_s ? p.b : p.a;
    a.fp = f.a;
    a.fq = a.along_s ? f.b : f.c;
    a.fr = a.along_s ? f.c : f.b;
    a.fe = f.e;
    const double c0 = p.c - top_;
    a.n = {c0 * a.fr - h * a.fp, c0 * a.fe + g * a.fr - h * a.fq - p.e * a.fp, g * a.fe - p.e * a.fq};
    return a;
  }
  void attain_on(const Piece& p, const ArcForm& a, double u) {
    if (a.along_s) {
      attain_closure(p, u, a.w(u));
    } else {
      attain_closure(p, a.w(u), u);
    }
  }

  // The maximum over [u0, u1] of N(u) / D(u), N and D quadratics (constant coefficient
  // first) and D without a zero there, and where it is: at an end or where
  // N' D - N D' = k2 u^2 + 2 k1 u + k0 = 0 (the cubic terms cancel).
  static double rational_max(const std::array<double, 3>& n, const std::array<double, 3>& d, double u0, double u1, double& arg) {
    auto ratio = [&](double u) { return (n[0] + u * (n[1] + u * n[2])) / (d[0] + u * (d[1] + u * d[2])); };
    double best = ratio(u0);
    arg = u0;
    auto offer = [&](double u) {
      const double v = ratio(u);
      if (v > best) {
        best = v;
        arg = u;
      }
    };
    offer(u1);
    const double k2 = n[2] * d[1] - n[1] * d[2], k1 = n[2] * d[0] - n[0] * d[2], k0 = n[1] * d[0] - n[0] * d[1];
    const double lo = std::min(u0, u1), hi = std::max(u0, u1);
    auto root = [&](double u) {
      if (u > lo && u < hi) offer(u);
    };
    if (k2 == 0) {
      if (k1 != 0) root(-k0 / (2 * k1));
    } else {
      const double disc = k1 * k1 - k2 * k0;
      if (disc >= 0) {
        // The stable pair of formulas (no cancellation between -k1 and the square root).
        const double r = -(k1 + std::copysign(std::sqrt(disc), k1));
        root(r / k2);
        if (r != 0) root(k0 / r);
      }
    }
    return best;
  }

  // Side zone: the maximum of psi along one monotone arc (its ends attained by the caller) in
  // closed form, as edge_maximum's along a segment. The gap to F is affine in u or in w, so
  // psi = N / D with D = (R + E u)(alpha + beta u) or alpha (R + E u) - beta (P + Q u) for
  // gap = alpha + beta v, v = u or w. Where the gap is positive at both ends (it is monotone
  // along the arc) psi is smooth on the arc and rational_max gives its supremum, attained,
  // instead of a search whose boxes close only linearly. An arc that reaches F's edge at a
  // point where S = T (the fan out of the apex) is taken too, by its limit there (below).
  // Returns false, leaving the arc to the search, where the gap vanishes at both ends, where
  // it vanishes at an end with S < T there, or where the arc is a point.
  bool side_arc(const Piece& p, const Bilinear& f, const std::array<double, 4>& e) {
    const bool on_f0 = !(piece_distance(p.x(e[0]), p.y(e[1])) > 0), on_f1 = !(piece_distance(p.x(e[2]), p.y(e[3])) > 0);
    if ((on_f0 && on_f1) || ((on_f0 || on_f1) && !fans_)) return false;  // ConeMapOptions::exact_fans
    // An end on F's edge is taken only where S = T there (the fan): elsewhere S < T near it,
    // psi tends to -inf, and the boxes close.
    if ((on_f0 && p.value(e[0], e[1]) != top_) || (on_f1 && p.value(e[2], e[3]) != top_)) return false;
    const ArcForm a = arc_form(p, f, e);
    if (a.u0 == a.u1) return false;
    // The gap z (v / 2 + origin - edge) = alpha + beta v, v the local coordinate across F's
    // edge (s beside F's left or right side, t above or below it).
    const bool beside_x = zy_ == 0;
    const double z = beside_x ? zx_ : zy_;
    const double edge = beside_x ? (zx_ > 0 ? f_.x1 : f_.x0) : (zy_ > 0 ? f_.y1 : f_.y0);
    const double alpha = z * ((beside_x ? p.x0 : p.y0) - edge), beta = 0.5 * z;
    const std::array<double, 3> d = beside_x == a.along_s
                                        ? std::array<double, 3>{a.fr * alpha, a.fr * beta + a.fe * alpha, a.fe * beta}
                                        : std::array<double, 3>{alpha * a.fr - beta * a.fp, alpha * a.fe - beta * a.fq, 0.0};
    double arg;
    if (!on_f0 && !on_f1) {
      rational_max(a.n, d, a.u0, a.u1, arg);
      attain_on(p, a, arg);
      return true;
    }
    // The fan: at the end u_e on F's edge both the gap and S - T vanish, so N and D share the
    // root u_e and psi = N1 / D1 on the arc, N = (u - u_e) N1, D = (u - u_e) D1: the value of
    // N1 / D1 at u_e is psi's limit there, which no point attains and which boxes around
    // u_e, bounded the same at every size (psi is homogeneous of degree 0 about it), never
    // close on. The remainders of the divisions, N(u_e) and D(u_e), are 0 but for rounding:
    // (S(u_e) - T) (R + E u_e) <= 0 against D's sign, so dropping N's can only raise psi.
    // D1 is affine: a sign kept at both ends is kept between (an arc tangent to F's edge at
    // u_e, where D1 vanishes too, is left to the boxes).
    const double ue = on_f0 ? a.u0 : a.u1;
    const std::array<double, 3> n1 = {a.n[1] + ue * a.n[2], a.n[2], 0.0}, d1 = {d[1] + ue * d[2], d[2], 0.0};
    const double dl = d1[0] + d1[1] * a.u0, dh = d1[0] + d1[1] * a.u1;
    if (!((dl > 0 && dh > 0) || (dl < 0 && dh < 0))) return false;
    const double limit = rational_max(n1, d1, a.u0, a.u1, arg);
    if (arg == ue) {
      psi = std::max(psi, limit);
    } else {
      attain_on(p, a, arg);
    }
    return true;
  }

  // corner_upper over the box of the arc's points at u0 and u1, which holds the arc between
  // them (it is monotone). Out of line: corner_arc's fallback, almost never taken.
  [[gnu::noinline]] double arc_box_upper(const Piece& p, const ArcForm& a, double u0, double u1) const {
    const double w0 = a.w(u0), w1 = a.w(u1);
    const double s0 = a.along_s ? u0 : w0, s1 = a.along_s ? u1 : w1, t0 = a.along_s ? w0 : u0, t1 = a.along_s ? w1 : u1;
    const double bs0 = std::min(s0, s1), bs1 = std::max(s0, s1), bt0 = std::min(t0, t1), bt1 = std::max(t0, t1);
    return corner_upper(p, bs0, bt0, bs1, bt1, {p.value(bs0, bt0), p.value(bs1, bt0), p.value(bs0, bt1), p.value(bs1, bt1)});
  }

  // Corner zone: a branch and bound along one monotone arc over intervals of u, whose bound
  // closes quadratically. For a unit vector v into the zone's quadrant, dist(y, F) = |y - c|
  // >= v . (y - c) > 0 (Cauchy-Schwarz; both in the quadrant, y != c), so where S >= T
  // psi <= (S - T) / (v . (y - c)) = N / D, with D = (R + E u) v . (y - c) a quadratic in u
  // (the offset along u is affine in u, the one along w times R + E u too), whose maximum
  // over the interval rational_max gives; where S < T, psi < 0 <= level. With v the
  // direction to the arc's point in the middle of the interval the bound exceeds the
  // supremum by a factor 1 / cos(angle), second order in the interval's angular size, where
  // a box's bound is first order: most arcs settle in a few intervals. The maximiser of the
  // bound is offered as a point of the arc. Returns false, leaving the arc to the box search,
  // where an end is at c (a piece touching c, where psi may tend to a limit) or the arc is a
  // point.
  bool corner_arc(const Piece& p, const Bilinear& f, const std::array<double, 4>& e) {
    if (!(piece_distance(p.x(e[0]), p.y(e[1])) > 0) || !(piece_distance(p.x(e[2]), p.y(e[3])) > 0)) return false;
    const ArcForm a = arc_form(p, f, e);
    if (a.u0 == a.u1) return false;
    // The offsets from c into the quadrant: along u, a0 + a1 u; along w, (b0 + b1 u) / (R + E u).
    const double zu = a.along_s ? zx_ : zy_, zw = a.along_s ? zy_ : zx_;
    const double a0 = zu * (a.along_s ? p.x0 - cx_ : p.y0 - cy_), a1 = 0.5 * zu;
    const double ow = zw * (a.along_s ? p.y0 - cy_ : p.x0 - cx_);
    const double b0 = ow * a.fr - 0.5 * zw * a.fp, b1 = ow * a.fe - 0.5 * zw * a.fq;
    const double m_sign = a.fr + a.fe * 0.5 * (a.u0 + a.u1) > 0 ? 1.0 : -1.0;  // R + E u's sign on the branch
    struct Span {
      double u0, u1;
      int depth;
    };
    // Depth first, the half holding the bound's maximiser first: one pending half per level.
    std::array<Span, kArcDepth + 2> stack;
    int top = 0;
    stack[static_cast<size_t>(top++)] = {a.u0, a.u1, 0};
    while (top > 0) {
      const Span sp = stack[static_cast<size_t>(--top)];
      const double um = 0.5 * (sp.u0 + sp.u1);
      const double ou = std::max(a0 + a1 * um, 0.0), ov = std::max((b0 + b1 * um) / (a.fr + a.fe * um), 0.0);
      const double len = length(ou, ov);
      const double vu = ou / len, vw = ov / len;
      const std::array<double, 3> d = {vu * a0 * a.fr + vw * b0, vu * (a0 * a.fe + a1 * a.fr) + vw * b1, vu * a1 * a.fe};
      // D must keep R + E u's sign (v . (y - c) > 0) over the interval: its ends and vertex.
      auto positive = [&](double u) { return m_sign * (d[0] + u * (d[1] + u * d[2])) > 0; };
      bool valid = len > 0 && positive(sp.u0) && positive(sp.u1);
      if (valid && d[2] != 0) {
        const double vertex = -d[1] / (2 * d[2]);
        if (vertex > std::min(sp.u0, sp.u1) && vertex < std::max(sp.u0, sp.u1)) valid = positive(vertex);
      }
      double upper, arg = um;
      if (valid) {
        upper = std::max(rational_max(a.n, d, sp.u0, sp.u1, arg), 0.0);
      } else {
        upper = arc_box_upper(p, a, sp.u0, sp.u1);  // rounding near an axis through c
      }
      attain_on(p, a, arg);
      if (upper <= level()) continue;
      if (upper <= std::max(psi * (1 + tol_), bound) || sp.depth >= kArcDepth) {
        bound = std::max(bound, upper);
        continue;
      }
      const Span lower{sp.u0, um, sp.depth + 1}, upper_half{um, sp.u1, sp.depth + 1};
      const bool arg_in_lower = (arg - um) * (sp.u0 - um) > 0;
      stack[static_cast<size_t>(top++)] = arg_in_lower ? upper_half : lower;
      stack[static_cast<size_t>(top++)] = arg_in_lower ? lower : upper_half;
    }
    return true;
  }

  // Along one monotone arc of f = 0 between (arc[0], arc[1]) and (arc[2], arc[3]): in closed
  // form beside F (side_arc), by intervals of the arc's parameter off its corner (corner_arc),
  // and where those decline (an end on F's boundary) by boxes: the arc lies in the box of
  // its ends, whose bound (side_upper / corner_upper) holds for it; boxes are halved along
  // the arc until the bound is within the tolerance of a value attained on the arc.
  void search_arc(const Piece& p, const Bilinear& f, const std::array<double, 4>& whole) {
    attain_closure(p, whole[0], whole[1]);
    attain_closure(p, whole[2], whole[3]);
    if (zx_ == 0 || zy_ == 0 ? side_arc(p, f, whole) : corner_arc(p, f, whole)) return;
    struct Arc {
      std::array<double, 4> e;
      int depth;
    };
    // Not value-initialised: entries are written before they are read, and zeroing the 50
    // entries (2 kB per arc) cost 1.2 % of the instructions of relaxed bricks at 256².
    std::array<Arc, 2 * kArcDepth + 2> stack;
    int top = 0;
    stack[static_cast<size_t>(top++)] = {whole, 0};
    while (top > 0) {
      const Arc a = stack[static_cast<size_t>(--top)];
      const double bs0 = std::min(a.e[0], a.e[2]), bs1 = std::max(a.e[0], a.e[2]);
      const double bt0 = std::min(a.e[1], a.e[3]), bt1 = std::max(a.e[1], a.e[3]);
      const std::array<double, 4> v = {p.value(bs0, bt0), p.value(bs1, bt0), p.value(bs0, bt1), p.value(bs1, bt1)};
      if (std::max({v[0], v[1], v[2], v[3]}) <= top_) continue;
      double upper, near;
      if (zx_ == 0 || zy_ == 0) {
        upper = side_upper(p, bs0, bt0, bs1, bt1, v);
        near = std::min(piece_distance(p.x(bs0), p.y(bt0)), piece_distance(p.x(bs1), p.y(bt1)));  // dist is monotone across the box
      } else {
        const double vmax = std::max({v[0], v[1], v[2], v[3]});
        near = nearest(p, bs0, bt0, bs1, bt1);
        if (vmax - top_ <= level() * near) continue;
        upper = corner_upper(p, bs0, bt0, bs1, bt1, v);
      }
      if (upper <= level()) continue;
      // The arc's point halfway along its longer extent.
      double sm, tm;
      if (bs1 - bs0 >= bt1 - bt0) {
        sm = 0.5 * (bs0 + bs1);
        tm = std::clamp(-(f.a + f.b * sm) / (f.c + f.e * sm), bt0, bt1);
      } else {
        tm = 0.5 * (bt0 + bt1);
        sm = std::clamp(-(f.a + f.c * tm) / (f.b + f.e * tm), bs0, bs1);
      }
      if (!std::isfinite(sm) || !std::isfinite(tm)) {
        bound = std::max(bound, upper);
        continue;
      }
      attain_closure(p, sm, tm);
      // A box touching F's boundary (where the arc may end at a point with S = T) is left
      // with its bound soon: there psi is homogeneous of degree 0 in the offset, so the
      // bound of a box does not shrink with the box, and halving would go on to the cap.
      if (upper <= std::max(psi * (1 + tol_), bound) || a.depth >= (near > 0 ? kArcDepth : max_depth_)) {
        bound = std::max(bound, upper);
        continue;
      }
      // The half nearer F last, so searched first: bounds grow toward F, and once the
      // largest is kept the rest of the arc is dismissed against it.
      const Arc first{{a.e[0], a.e[1], sm, tm}, a.depth + 1}, second{{sm, tm, a.e[2], a.e[3]}, a.depth + 1};
      const bool first_nearer = piece_distance(p.x(a.e[0]), p.y(a.e[1])) < piece_distance(p.x(a.e[2]), p.y(a.e[3]));
      stack[static_cast<size_t>(top++)] = first_nearer ? second : first;
      stack[static_cast<size_t>(top++)] = first_nearer ? first : second;
    }
  }

  Rect f_;
  double top_;
  bool relaxed_;
  double tol_;
  int max_depth_;
  bool fans_;  // relaxed: a fan's limit taken exactly (ConeMapOptions::exact_fans)
  int zx_ = 0, zy_ = 0;
  double cx_ = 0, cy_ = 0, sc_ = 0, tc_ = 0;
  bool touches_ = false, boundary_max_ = false;
};

// Bounds of S over power-of-two blocks of texels: level L, node (nx, ny) covers texels
// [nx 2^L, (nx+1) 2^L) x [ny 2^L, (ny+1) 2^L) clipped to the map. Per node: the maximum of
// the apex heights, and (levels >= 1) a plane above S over the node,
// S(y) <= a + g . (y - c), c the node's centre, g roughly S's mean gradient there. The max
// bounds a node by its nearest distance, a first-order bound that a smooth surface hugging
// the cone never meets; the plane bounds S - psi dist(y, F) to second order (exact on a
// plane), which is what prunes the wide regions near a cone's tangency.
struct MaxTree {
  std::vector<int> w, h;
  std::vector<std::vector<float>> level;
  std::vector<std::vector<float>> plane;  // per node a, gx, gy (level 0 unused)
  // Per node (levels >= 1) the box of S's gradients over it, gx in [0], [1], gy in [2], [3]:
  // relaxed cones skip a node where the surface rises away from the whole footprint. Empty
  // for conservative cones, which never read it (4 floats a node, and the texels' boxes).
  std::vector<std::vector<float>> gradient;
  size_t index(int l, int x, int y) const {
    return static_cast<size_t>(y) * static_cast<size_t>(w[static_cast<size_t>(l)]) + static_cast<size_t>(x);
  }
  float at(int l, int x, int y) const { return level[static_cast<size_t>(l)][index(l, x, y)]; }
};

// The float next to a finite v, above it (up) or below: std::nextafter's value, without its
// library call (1 % of the instructions of relaxed builds at 256²).
float float_step(float v, bool up) {
  if (v == 0) return up ? std::numeric_limits<float>::denorm_min() : -std::numeric_limits<float>::denorm_min();
  uint32_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  bits = (v > 0) == up ? bits + 1 : bits - 1;  // the magnitude grows when the step leads away from 0
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

// The box of S's gradients over texel (i, j): on each of its four pieces dS/dx is affine in
// y and dS/dy in x, so the pieces' corners give the extremes. Rounded outward.
void texel_gradients(const HalfGrid& grid, int i, int j, float* q) {
  double lo_x = kInf, hi_x = -kInf, lo_y = kInf, hi_y = -kInf;
  const std::array<float, 9> g = grid.texel(i, j);
  for (size_t b = 0; b <= 1; ++b)
    for (size_t a = 0; a <= 1; ++a) {
      const double v00 = g[3 * b + a], v10 = g[3 * b + a + 1], v01 = g[3 * b + a + 3], v11 = g[3 * b + a + 4];
      for (double gx : {2 * (v10 - v00), 2 * (v11 - v01)}) {
        lo_x = std::min(lo_x, gx);
        hi_x = std::max(hi_x, gx);
      }
      for (double gy : {2 * (v01 - v00), 2 * (v11 - v10)}) {
        lo_y = std::min(lo_y, gy);
        hi_y = std::max(hi_y, gy);
      }
    }
  q[0] = float_step(static_cast<float>(lo_x), false);
  q[1] = float_step(static_cast<float>(hi_x), true);
  q[2] = float_step(static_cast<float>(lo_y), false);
  q[3] = float_step(static_cast<float>(hi_y), true);
}

// Gradient boxes (gx in [0], [1], gy in [2], [3]) of unions of texels: start empty, take in
// each part's box (min and max: exact, so a union of outward-rounded boxes stays outward).
std::array<float, 4> empty_box() {
  constexpr float inf = std::numeric_limits<float>::infinity();
  return {inf, -inf, inf, -inf};
}
void widen_box(float* box, const float* part) {
  box[0] = std::min(box[0], part[0]);
  box[1] = std::max(box[1], part[1]);
  box[2] = std::min(box[2], part[2]);
  box[3] = std::max(box[3], part[3]);
}

// A float not below v.
float up(double v) {
  float f = static_cast<float>(v);
  if (static_cast<double>(f) < v) f = float_step(f, true);
  return f;
}

// The plane of texel (i, j): g from its 3 x 3 grid values (mean of the differences across
// it), a exact (S minus an affine function is bilinear on each piece, so the 9 grid points
// hold its maximum).
void texel_plane(const HalfGrid& grid, int i, int j, float* q) {
  const std::array<float, 9> g = grid.texel(i, j);
  double gx = 0, gy = 0;
  for (size_t k = 0; k <= 2; ++k) {
    gx += (g[3 * k + 2] - g[3 * k]) / 3.0;
    gy += (g[6 + k] - g[k]) / 3.0;
  }
  const float fx = static_cast<float>(gx), fy = static_cast<float>(gy);
  double a = -kInf;
  for (size_t b = 0; b <= 2; ++b)
    for (size_t c = 0; c <= 2; ++c) a = std::max(a, g[3 * b + c] - fx * (0.5 * static_cast<double>(c) - 0.5) - fy * (0.5 * static_cast<double>(b) - 0.5));
  q[0] = up(a);
  q[1] = fx;
  q[2] = fy;
}

MaxTree max_tree(std::vector<float> top, const HalfGrid& grid, int width, int height, bool boxes) {
  MaxTree t;
  t.w.push_back(width);
  t.h.push_back(height);
  t.level.push_back(std::move(top));
  // Level 0 keeps no planes or gradient boxes (7 floats a texel, the largest arrays of the
  // build): level 1 computes its children's from the grid, and so does the search.
  t.plane.emplace_back();
  t.gradient.emplace_back();
  while (t.w.back() > 1 || t.h.back() > 1) {
    const int l = static_cast<int>(t.w.size()) - 1;  // the finer level
    const int fw = t.w.back(), fh = t.h.back(), cw = (fw + 1) / 2, ch = (fh + 1) / 2;
    const double fs = std::ldexp(1.0, l), cs = 2 * fs;  // node sizes in texels
    std::vector<float> c(static_cast<size_t>(cw) * static_cast<size_t>(ch));
    std::vector<float> cp(c.size() * 3);
    std::vector<float> cg(boxes ? c.size() * 4 : 0);
    const std::vector<float>& fine = t.level.back();
    const std::vector<float>& fine_plane = t.plane.back();
    const std::vector<float>& fine_gradient = t.gradient.back();
    auto rect_of = [&](double size, int x, int y, double& x0, double& y0, double& x1, double& y1) {
      x0 = x * size;
      y0 = y * size;
      x1 = std::min((x + 1) * size, static_cast<double>(width));
      y1 = std::min((y + 1) * size, static_cast<double>(height));
    };
    tbb::parallel_for(tbb::blocked_range<int>(0, ch), [&](const tbb::blocked_range<int>& rows) {
      for (int y = rows.begin(); y < rows.end(); ++y)
        for (int x = 0; x < cw; ++x) {
          // The node's children (up to 4): maximum, plane, gradient box.
          struct Child {
            float m, plane[3], box[4];
            double x0, y0, x1, y1;
          };
          std::array<Child, 4> kids{};
          int count = 0;
          for (int yy = 2 * y; yy <= std::min(2 * y + 1, fh - 1); ++yy)
            for (int xx = 2 * x; xx <= std::min(2 * x + 1, fw - 1); ++xx) {
              Child& k = kids[static_cast<size_t>(count++)];
              const size_t n = static_cast<size_t>(yy) * static_cast<size_t>(fw) + static_cast<size_t>(xx);
              k.m = fine[n];
              if (l == 0) {
                texel_plane(grid, xx, yy, k.plane);
                if (boxes) texel_gradients(grid, xx, yy, k.box);
              } else {
                std::copy_n(&fine_plane[n * 3], 3, k.plane);
                if (boxes) std::copy_n(&fine_gradient[n * 4], 4, k.box);
              }
              rect_of(fs, xx, yy, k.x0, k.y0, k.x1, k.y1);
            }
          float m = -1.0f;
          double gx = 0, gy = 0, weight = 0;
          for (int i = 0; i < count; ++i) {
            const Child& k = kids[static_cast<size_t>(i)];
            m = std::max(m, k.m);
            const double area = (k.x1 - k.x0) * (k.y1 - k.y0);
            gx += area * k.plane[1];
            gy += area * k.plane[2];
            weight += area;
          }
          gx /= weight;
          gy /= weight;
          const float fx = static_cast<float>(gx), fy = static_cast<float>(gy);
          double nx0, ny0, nx1, ny1;
          rect_of(cs, x, y, nx0, ny0, nx1, ny1);
          const double ncx = 0.5 * (nx0 + nx1), ncy = 0.5 * (ny0 + ny1);
          // On a child, S - g_N . (y - c_N) <= a_C + g_C . (y - c_C) - g_N . (y - c_N): affine,
          // so the child's corners bound it.
          double a = -kInf;
          for (int i = 0; i < count; ++i) {
            const Child& k = kids[static_cast<size_t>(i)];
            const double ca = k.plane[0], cgx = k.plane[1], cgy = k.plane[2];
            const double ccx = 0.5 * (k.x0 + k.x1), ccy = 0.5 * (k.y0 + k.y1);
            for (double px : {k.x0, k.x1})
              for (double py : {k.y0, k.y1})
                a = std::max(a, ca + cgx * (px - ccx) + cgy * (py - ccy) - fx * (px - ncx) - fy * (py - ncy));
          }
          const size_t n = static_cast<size_t>(y) * static_cast<size_t>(cw) + static_cast<size_t>(x);
          c[n] = m;
          // Never above the node's maximum where that is lower (a flat top): keep both.
          cp[n * 3] = up(a);
          cp[n * 3 + 1] = fx;
          cp[n * 3 + 2] = fy;
          if (!boxes) continue;
          float* box = &cg[n * 4];
          const std::array<float, 4> none = empty_box();
          std::copy(none.begin(), none.end(), box);
          for (int i = 0; i < count; ++i) widen_box(box, kids[static_cast<size_t>(i)].box);
        }
    });
    t.w.push_back(cw);
    t.h.push_back(ch);
    t.level.push_back(std::move(c));
    t.plane.push_back(std::move(cp));
    t.gradient.push_back(std::move(cg));
  }
  // Level 1's gradient boxes (4 floats per 2 x 2 texels: the map's size) were needed only to
  // build level 2's: the walk unions the four texels' boxes instead (LeafCache), the same
  // values (an outward-rounded box's union is exact).
  if (boxes && t.gradient.size() > 1) std::vector<float>().swap(t.gradient[1]);
  return t;
}

// No point of the rectangle r is seen descending from F: grad S(y) . (y - x) >= 0 for every
// corner x of F, with the gradient anywhere in its box (interval products, so safe). Per
// corner of F the two terms' minima are added; the smallest sum over F's corners is the sum
// of the smaller term along each axis (rounding is monotone: the same verdict).
// The lowest term along one axis: the smallest g (y - x) for g in [g0, g1], y in [r0, r1],
// x in [f0, f1], bilinear in g and in the offset y - x, whose extremes are r0 - f1 and
// r1 - f0, so the four products at the extremes bound the others (rounding monotone again).
// Both axes' terms in one SSE2 pair (x in lane 0, y in lane 1; a minimum of equal products
// may keep the other's zero sign, which no sum's sign depends on).
bool rises_away(const float* box, const Rect& r, const Rect& f) {
  const Pair g0 = {box[0], box[2]}, g1 = {box[1], box[3]};
  const Pair d0 = Pair{r.x0, r.y0} - Pair{f.x1, f.y1}, d1 = Pair{r.x1, r.y1} - Pair{f.x0, f.y0};
  const Pair low = pair_min(pair_min(g0 * d0, g0 * d1), pair_min(g1 * d0, g1 * d1));
  return !(low[0] + low[1] < 0);
}

// Upper bound of S(y) - psi dist(y, F) - T over the rectangle r (disjoint from F's
// interior), from the node's plane: the exact maximum of h(y) = plane(y) - psi dist(y, F)
// when it is positive; when it is not, some value <= 0 that bounds it.
// h is concave (affine minus a convex distance), so its maximum over r lies on r's boundary
// (an interior stationary point needs |g| = psi, where h is constant along a ray that
// reaches the boundary anyway). Along an edge, dist is |x - e| beside F or
// sqrt((x - e)^2 + k^2) off its corner: the maximum of gx x - psi sqrt((x - e)^2 + k^2) is at
// x - e = k r / sqrt(1 - r^2), r = gx / psi, when |r| < 1; else at an end.
double plane_excess(const float* plane, const Rect& r, const Rect& f, double top, double psi) {
  const double a = plane[0] - top, gx = plane[1], gy = plane[2];
  const double ncx = 0.5 * (r.x0 + r.x1), ncy = 0.5 * (r.y0 + r.y1);
  // Inlined (up to 16 copies): left to GCC, the choice flips with the size of unrelated code
  // in this file, and the call cost 13 % more instructions in the plane tests.
  auto h = [&](double x, double y) __attribute__((always_inline)) {
    return a + gx * (x - ncx) + gy * (y - ncy) - psi * length(gap(f.x0, f.x1, x, x), gap(f.y0, f.y1, y, y));
  };
  // Corners first, a positive one settles it (the caller asks whether the answer is <= 0, and
  // any value of h in r is good for under()'s shortcut): the four at once, two per SSE2 pair,
  // each the same IEEE operations as h() (so the same values; a gap's zero may change sign,
  // which its square does not see), their square roots side by side rather than one after
  // the other (conservative bumps at 512², one thread: -5 % time in alternated runs).
  const Pair xs = {r.x0, r.x1};
  const Pair across_x = xs - ncx, gap_x = pair_max(pair_max(f.x0 - xs, xs - f.x1), Pair{0.0, 0.0});
  const Pair gap_x2 = gap_x * gap_x, lin_x = a + gx * across_x;
  auto corners = [&](double y) {
    const double gap_y = gap(f.y0, f.y1, y, y);
    return lin_x + gy * (y - ncy) - psi * pair_sqrt(gap_x2 + gap_y * gap_y);
  };
  const Pair c = pair_max(corners(r.y0), corners(r.y1));
  double best = std::max(c[0], c[1]);
  if (best > 0) return best;
  // Then, along each edge, where F's lines cross it (dist changes form there) and the
  // stationary point off F's side or corner.
  auto edge = [&](double s0, double s1, double e0, double e1, double k, double slope, auto&& point) {
    for (double e : {e0, e1})
      if (e > s0 && e < s1) best = std::max(best, point(e));
    if (!(psi > 0) || k <= 0) return;  // piecewise linear along the edge: ends and F's lines
    const double ratio = slope / psi;
    if (std::abs(ratio) >= 1) return;
    const double offset = k * ratio / std::sqrt(1 - ratio * ratio);
    if (offset <= 0 && e0 + offset > s0) best = std::max(best, point(std::min(e0 + offset, s1)));
    if (offset >= 0 && e1 + offset < s1) best = std::max(best, point(std::max(e1 + offset, s0)));
  };
  for (double y : {r.y0, r.y1}) {
    edge(r.x0, r.x1, f.x0, f.x1, gap(f.y0, f.y1, y, y), gx, [&](double x) { return h(x, y); });
    if (best > 0) return best;
  }
  for (double x : {r.x0, r.x1}) {
    edge(r.y0, r.y1, f.y0, f.y1, gap(f.x0, f.x1, x, x), gy, [&](double y) { return h(x, y); });
    if (best > 0) return best;
  }
  return best;
}

// Stored ratios round toward zero (a narrower cone is still safe); ratios are >= 0 and
// below kConeRatioCap, so half's finite range holds them.
float round_down(double v, bool half) {
  float f = static_cast<float>(v);
  if (static_cast<double>(f) > v) f = std::nextafter(f, 0.0f);
  return half ? half_below(f) : f;
}

// The planes and gradient boxes of leaf texels, which the tree does not store (7 floats a
// texel), computed when first needed and kept in a small direct-mapped cache per task: the
// searches of neighbouring blocks open mostly the same leaves. The same functions of the
// same grid values, so what is cached is what would be computed again.
class LeafCache {
 public:
  explicit LeafCache(const HalfGrid& grid) : grid_(grid), entries_(kSide * kSide) {}
  const float* plane(int x, int y) {
    Entry& e = at(x, y);
    if (!e.has_plane) texel_plane(grid_, x, y, e.plane.data());
    e.has_plane = true;
    return e.plane.data();
  }
  const float* box(int x, int y) {
    Entry& e = at(x, y);
    if (!e.has_box) texel_gradients(grid_, x, y, e.box.data());
    e.has_box = true;
    return e.box.data();
  }

 private:
  static constexpr int kSide = 64;
  struct Entry {
    int x = -1, y = -1;
    bool has_plane = false, has_box = false;
    std::array<float, 3> plane{};
    std::array<float, 4> box{};
  };
  Entry& at(int x, int y) {
    Entry& e = entries_[static_cast<size_t>((y % kSide) * kSide + x % kSide)];
    if (e.x != x || e.y != y) e = Entry{x, y};
    return e;
  }
  const HalfGrid& grid_;
  std::vector<Entry> entries_;
};

// Texels are searched kBlock x kBlock at a time: one walk of the quadtree serves the block,
// each node carrying the set of the block's texels (a bit mask) for which it may still hold
// a steeper point. What a per-texel search re-did for every texel (the descent from the
// root, popping, sorting and pushing nodes, the children's rectangles and gaps) is done once
// per block; the tests that decide (a node's maximum over its distance, its plane, its
// gradient box, the pieces) stay per texel, so each texel's answer is still the exact
// supremum of its own cone within the tolerance. The result depends on the blocks (the
// order in which each texel meets the nodes, within the tolerance) but not on the threads.
// Measured (callgrind, the 256² maps of bench/cone_time): 2 x 2 texels cost 6-11 % more
// (less is shared), 8 x 8 20-60 % more (each texel meets far nodes before its near ones).
constexpr int kBlockLog = 2;
constexpr int kBlock = 1 << kBlockLog;  // texel k of a block: column k % kBlock, row k / kBlock
using Mask = uint32_t;
static_assert(kBlock * kBlock <= 32, "one bit per texel of a block");
static_assert(kBlock % 2 == 0, "pairs of texels within a row");

struct Block {
  int i0 = 0, j0 = 0, bw = 0, bh = 0;  // texels [i0, i0 + bw) x [j0, j0 + bh)
  Rect f{};                            // the union of their footprints
};

inline int low_bit(Mask m) { return __builtin_ctz(m); }
// The bits of a block's column 0 and row 0.
constexpr Mask kColumn = [] {
  Mask m = 0;
  for (int r = 0; r < kBlock; ++r) m |= Mask{1} << (r * kBlock);
  return m;
}();
constexpr Mask kRow = (Mask{1} << kBlock) - 1;
// Per column (or row) of a block, a squared gap.
using Gaps = std::array<double, kBlock>;

// The squared gaps from the block's columns (rows) [t0 + c, t0 + c + 1] to [a0, a1]:
// gap() = max(t0 + c - a1, a0 - t0 - c - 1, 0), the same values (all are whole numbers,
// exact in double) from two differences, two columns at a time (the scalar loop was 3 % of
// the instructions: every child of every node walked needs two of these).
inline Gaps squared_gaps(int t0, double a0, double a1) {
  const double after = t0 - a1, before = a0 - t0 - 1.0;
  Gaps g;
  for (size_t c = 0; c < kBlock; c += 2) {
    const Pair k = {static_cast<double>(c), static_cast<double>(c + 1)};
    const Pair gp = positive_part(pair_max(after + k, before - k));
    const Pair sq = gp * gp;
    std::memcpy(&g[c], &sq, sizeof sq);
  }
  return g;
}
// a < b per texel: bit 0 the pair's first texel, bit 1 its second.
inline Mask less_bits(Pair a, Pair b) {
#if defined(__SSE2__)
  return static_cast<Mask>(_mm_movemask_pd(_mm_cmplt_pd(a, b)));
#else
  return static_cast<Mask>((a[0] < b[0] ? 1 : 0) | (a[1] < b[1] ? 2 : 0));
#endif
}

// a <= b per texel (false for a NaN, as the scalar compare), bits as less_bits().
inline Mask at_most_bits(Pair a, Pair b) {
#if defined(__SSE2__)
  return static_cast<Mask>(_mm_movemask_pd(_mm_cmple_pd(a, b)));
#else
  return static_cast<Mask>((a[0] <= b[0] ? 1 : 0) | (a[1] <= b[1] ? 2 : 0));
#endif
}
inline Pair pair_abs(Pair a) { return Pair{std::abs(a[0]), std::abs(a[1])}; }

// A first plane test with one square root, for the texels of `texels` of the block whose first
// texel is (i0, j0): those it settles (h <= 0 over r, so plane_excess would answer <= 0).
// dist(y, F) >= n . (y - p) for p the point of F nearest r's centre and n the unit direction
// from p to that centre (F is convex and n lies in its normal cone at p), so h(y) <= a +
// g . (y - centre) - psi n . (y - p), an affine function whose maximum over r is its value at
// the centre plus the half-extents times the absolute slopes. Tight to first order in r's
// angular size seen from F, the regime in which planes are tested: on the smooth bumps at
// 512² it settles 87 % of the tests that end <= 0 (256²: -25 % instructions, bricks -3 %,
// noise +2 %, against none). The texels of a node share its centre, extents and plane, and
// their gaps to it along x per column, along y per row: so they are tested together, the
// square roots and divisions in pairs (-6.6 % instructions on the bumps against one texel
// at a time, the same verdicts).
Mask one_root_settles(const float* plane, const Rect& r, int i0, int j0, const std::array<double, kBlock * kBlock>& top,
                      const std::array<double, kBlock * kBlock>& psi, Mask texels) {
  const double gx = plane[1], gy = plane[2];
  const double ncx = 0.5 * (r.x0 + r.x1), ncy = 0.5 * (r.y0 + r.y1);
  // Offsets from the block's columns (in pairs, built in registers: stored one double at a
  // time and loaded two at a time, they stalled store forwarding) and rows to r's centre.
  std::array<Pair, kBlock / 2> dx;
  std::array<double, kBlock> dy;
  for (size_t c = 0; c < kBlock; ++c) {
    const double fy = j0 + static_cast<double>(c);
    dy[c] = ncy - std::clamp(ncy, fy, fy + 1);
  }
  for (size_t c = 0; c < kBlock; c += 2) {
    const Pair fx = {i0 + static_cast<double>(c), i0 + static_cast<double>(c + 1)};
    dx[c / 2] = ncx - pair_min(pair_max(Pair{ncx, ncx}, fx), fx + 1.0);  // std::clamp's values
  }
  const double wx = r.x1 - r.x0, wy = r.y1 - r.y0;
  Mask out = 0;
  for (Mask pairs = (texels | texels >> 1) & 0x55555555u; pairs != 0; pairs &= pairs - 1) {
    const size_t k = static_cast<size_t>(low_bit(pairs));
    const Pair x = dx[(k & (kBlock - 1)) / 2];
    const double y = dy[k >> kBlockLog];
    const Pair d = pair_sqrt(x * x + y * y);
    const Pair p = load_pair(&psi[k]);
    const Pair a = static_cast<double>(plane[0]) - load_pair(&top[k]);
    const Pair nx = x / d, ny = y / d;
    const Pair bound = a - p * d + pair_abs(gx - p * nx) * 0.5 * wx + pair_abs(gy - p * ny) * 0.5 * wy;
    out |= (less_bits(Pair{0.0, 0.0}, d) & at_most_bits(bound, Pair{0.0, 0.0})) << k;
  }
  return out & texels;
}

// The texels of `keep` for which a node of maximum m at squared gaps gx2 (per column of the
// block) and gy2 (per row) may hold a steeper point: m > T and not (m - T)^2 <= level^2 d^2,
// the test of one texel at a time (the same IEEE operations, so the same verdicts) for two
// at once, the masks from the compares. It is level2 d^2 < max(m - T, 0)^2: d^2 is 0 or at
// least 1 (gaps are whole texels), level2 is finite (the caller clamps it below overflow),
// and a positive m - T is a difference of floats, whose square does not underflow. Pairs without a texel of `keep` are skipped: a
// child is tested for ~7 of the 16 texels on the bricks. With_apart: `apart` receives those
// of the texels kept with d^2 >= size2.
template <bool with_apart>
Mask steeper(double m, const Gaps& gx2, const Gaps& gy2, const std::array<double, kBlock * kBlock>& top,
             const std::array<double, kBlock * kBlock>& level2, Mask keep, double size2, Mask& apart) {
  Mask out = 0;
  for (Mask pairs = (keep | keep >> 1) & 0x55555555u; pairs != 0; pairs &= pairs - 1) {
    const size_t k = static_cast<size_t>(low_bit(pairs));
    const Pair e = positive_part(m - load_pair(&top[k]));
    const Pair d2 = load_pair(&gx2[k & (kBlock - 1)]) + gy2[k >> kBlockLog];
    const Mask kept = less_bits(load_pair(&level2[k]) * d2, e * e);
    out |= kept << k;
    if constexpr (with_apart) apart |= (kept & ~less_bits(d2, Pair{size2, size2})) << k;
  }
  if constexpr (with_apart) apart &= keep;
  return out & keep;
}

// steeper() for the four children of a node at once: child u = 2 uy + ux has maximum km[u]
// and squared gaps gx2[ux] (per column of the block) and gy2[uy] (per row). Pair by pair of
// texels, whose apexes, levels and gaps are loaded once for the four (one child after the
// other cost 2.5 % more instructions on the bricks, a loop over the four 1 % more); the same
// IEEE operations per texel, so the same verdicts.
inline std::array<Mask, 4> children_steeper(const std::array<double, 4>& km, const std::array<Gaps, 2>& gx2, const std::array<Gaps, 2>& gy2,
                                            const std::array<double, kBlock * kBlock>& top,
                                            const std::array<double, kBlock * kBlock>& level2, Mask keep) {
  Mask m0 = 0, m1 = 0, m2 = 0, m3 = 0;
  for (Mask pairs = (keep | keep >> 1) & 0x55555555u; pairs != 0; pairs &= pairs - 1) {
    const size_t k = static_cast<size_t>(low_bit(pairs));
    const Pair t = load_pair(&top[k]), l2 = load_pair(&level2[k]);
    const size_t c = k & (kBlock - 1), r = k >> kBlockLog;
    const Pair x0 = load_pair(&gx2[0][c]), x1 = load_pair(&gx2[1][c]);
    const double y0 = gy2[0][r], y1 = gy2[1][r];
    auto test = [&](double m, Pair gx, double gy) {
      const Pair e = positive_part(m - t);
      return less_bits(l2 * (gx + gy), e * e) << k;
    };
    m0 |= test(km[0], x0, y0);
    m1 |= test(km[1], x1, y0);
    m2 |= test(km[2], x0, y1);
    m3 |= test(km[3], x1, y1);
  }
  return {m0 & keep, m1 & keep, m2 & keep, m3 & keep};
}

// steeper()'s `apart` for texels all kept: those of `keep` with d^2 >= size2.
inline Mask apart_bits(const Gaps& gx2, const Gaps& gy2, Mask keep, double size2) {
  Mask out = 0;
  for (Mask pairs = (keep | keep >> 1) & 0x55555555u; pairs != 0; pairs &= pairs - 1) {
    const size_t k = static_cast<size_t>(low_bit(pairs));
    const Pair d2 = load_pair(&gx2[k & (kBlock - 1)]) + gy2[k >> kBlockLog];
    out |= (3u & ~less_bits(d2, Pair{size2, size2})) << k;
  }
  return out & keep;
}

// A texel's 8 neighbours, the sides first.
constexpr std::array<std::pair<int, int>, 8> kNeighbours = {{{-1, 0}, {1, 0}, {0, -1}, {0, 1}, {-1, -1}, {1, -1}, {-1, 1}, {1, 1}}};

class BlockSearch {
 public:
  using PerTexel = std::array<double, kBlock * kBlock>;

  BlockSearch(const MaxTree& tree, const HalfGrid& grid, int w, int h, bool wrap, double tolerance, bool exact_fans)
      : tree_(tree), grid_(grid), w_(w), h_(h), wrap_(wrap), tol_(tolerance), fans_(exact_fans), root_(static_cast<int>(tree.level.size()) - 1),
        global_max_(tree.at(root_, 0, 0)), leaves_(grid) {}

  // Searches the texels of `todo` in block b (apex heights `top`), of one kind, each seeded
  // with every point of `seeds`; texel k stops once its psi reaches cap[k] (the caller needs
  // only min(cap, supremum)). The searches are left in s (indexed by k).
  void run(const Block& b, const PerTexel& top, bool relaxed, Mask todo, const PerTexel& cap, const std::vector<ConeSearch::Point>& seeds,
           std::vector<ConeSearch>& s) {
    s.clear();
    for (int k = 0; k < kBlock * kBlock; ++k) {
      const int i = b.i0 + (k & (kBlock - 1)), j = b.j0 + (k >> kBlockLog);
      footprint_[static_cast<size_t>(k)] = Rect{static_cast<double>(i), static_cast<double>(j), i + 1.0, j + 1.0};
      s.emplace_back(footprint_[static_cast<size_t>(k)], top[static_cast<size_t>(k)], relaxed, tol_, fans_);
    }
    relaxed_ = relaxed;
    live_ = 0;
    for (Mask q = todo; q != 0; q &= q - 1) {
      const size_t k = static_cast<size_t>(low_bit(q));
      for (const ConeSearch::Point& p : seeds) s[k].seed(p);
      if (s[k].psi < cap[k]) live_ |= Mask{1} << k;
    }
    // First each texel's own neighbourhood (the 8 texels around it): they touch F, so no
    // bound dismisses them and they are searched whatever the order; searched first, they
    // give each texel a slope close to its answer before the walk (its steepest point is
    // most often next to it), so that the walk's tests dismiss more. The walk then skips them.
    near_ = true;
    around_built_ = 0;
    for (Mask q = live_; q != 0; q &= q - 1) {
      const int k = low_bit(q);
      const size_t uk = static_cast<size_t>(k);
      const int i = b.i0 + (k & (kBlock - 1)), j = b.j0 + (k >> kBlockLog);
      for (const auto& [dx, dy] : kNeighbours) {
        const int x = i + dx, y = j + dy;
        if (x < 0 || y < 0 || x >= w_ || y >= h_ || !(tree_.at(0, x, y) > top[uk]) || !(s[uk].psi < cap[uk])) continue;
        if (relaxed && rises_away(leaves_.box(x, y), Rect{static_cast<double>(x), static_cast<double>(y), x + 1.0, y + 1.0}, footprint_[uk])) continue;
        if ((dx == 0 || dy == 0) && s[uk].side_texel_settles(grid_, x, y, 0, 0)) continue;  // a side neighbour whole
        for (const Piece& p : around_pieces(b, x, y)) s[uk].piece(p);
      }
      if (!(s[uk].psi < cap[uk])) live_ &= ~(Mask{1} << k);
    }
    visit(b, top, cap, s, 0, 0, live_);
    near_ = false;
    if (wrap_) {
      // Copies of the tile: none farther than (global max - T) / level can hold a steeper
      // point. A texel with nothing higher in the tile has nothing higher in any copy.
      Mask seen = 0;
      double reach = 0;
      for (Mask q = live_; q != 0; q &= q - 1) {
        const size_t k = static_cast<size_t>(low_bit(q));
        const double level = s[k].level();
        if (level <= 0) continue;
        seen |= Mask{1} << k;
        reach = std::max(reach, (global_max_ - top[k]) / level);
      }
      if (seen != 0) {
        const int ax = static_cast<int>(std::ceil(reach / w_)) + 1, ay = static_cast<int>(std::ceil(reach / h_)) + 1;
        for (int bb = -ay; bb <= ay; ++bb)
          for (int a = -ax; a <= ax; ++a)
            if (a != 0 || bb != 0) visit(b, top, cap, s, static_cast<double>(a) * w_, static_cast<double>(bb) * h_, seen);
      }
    }
  }

 private:
  struct Node {
    int level, x, y;
    float m;    // the node's maximum
    Mask mask;  // the block's texels for which it may hold a steeper point
    double d2;  // squared distance to the block's footprint (orders nodes; no square root)
    // The squared gaps from the block's columns and rows to the node, computed once by the
    // parent (which needs them to test it) for the test when it is popped.
    Gaps gx2, gy2;
    // Relaxed cones: the node's priority (the largest (m - T) / d over the block, squared).
    double key = 0;
  };

  // Under the cone of the slope found: nothing to gain. Under the cone of that slope
  // widened by the tolerance: the node is dismissed and the widened slope kept as the
  // bound (the stored cone may be that much narrower, never wider).
  bool under(ConeSearch& s, const float* plane, const Rect& r, const Rect& f, double t) {
    const double level = s.level(), excess = plane_excess(plane, r, f, t, level);
    if (excess <= 0) return true;
    const double widened = s.psi * (1 + tol_);
    if (!(widened > s.bound)) return false;
    // plane_excess returned a value of h at some point y of r, and the widened cone lowers h
    // there by (widened - level) dist(y, F), dist at most the sum of r's largest gaps along
    // x and y: above that, the widened test cannot dismiss the node either. (It was tried
    // on 328,209 nodes of the bricks at 256² and dismissed 119, at ~70 instructions each.)
    const double far = std::max(gap(f.x0, f.x1, r.x0, r.x0), gap(f.x0, f.x1, r.x1, r.x1)) +
                       std::max(gap(f.y0, f.y1, r.y0, r.y0), gap(f.y0, f.y1, r.y1, r.y1));
    if (excess > (widened - level) * far) return false;
    if (plane_excess(plane, r, f, t, widened) <= 0) {
      s.bound = std::max(s.bound, widened);
      conceded_ = true;
      return true;
    }
    return false;
  }

  // The plane test of a node (or leaf) for the texels of `keep`; those apart from it
  // (`apart`, d > 0; plane_excess needs r outside the footprint) may be dropped. Returns the
  // texels left. (A first test for the whole block, with its union footprint, lowest apex and
  // lowest slope, dismissed 4 % of the nodes it was tried on and cost more than it saved.)
  // `then(k)` is the second test of a texel k that the one-root bound leaves (true: settled):
  // the exact plane test at nodes, the texel's grid values at leaves.
  template <class Then>
  Mask planes(const float* plane, const Rect& r, const Block& b, const PerTexel& top, std::vector<ConeSearch>& s, Mask keep, Mask apart, Then then) {
    const Mask tested = keep & apart;
    if (tested == 0) return keep;
    PerTexel level{};
    store_levels(s, tested, level, false);
    const Mask settled = one_root_settles(plane, r, b.i0, b.j0, top, level, tested);
    keep &= ~settled;
    for (Mask q = tested & ~settled; q != 0; q &= q - 1) {
      const size_t k = static_cast<size_t>(low_bit(q));
      if (then(k)) keep &= ~(Mask{1} << k);
    }
    return keep;
  }
  Mask planes(const float* plane, const Rect& r, const Block& b, const PerTexel& top, std::vector<ConeSearch>& s, Mask keep, Mask apart) {
    return planes(plane, r, b, top, s, keep, apart, [&](size_t k) { return under(s[k], plane, r, footprint_[k], top[k]); });
  }

  // The levels of the texels of `texels` (squared: below overflow, see steeper(); an infinite
  // square is tested the same), into `out` a pair of texels at a time: the paired tests load
  // them two at a time, which a store of one double each leaves waiting on store forwarding
  // (perf: the hottest spots of steeper() and one_root_settles()). A pair's other texel gets
  // its level too, which no test of it reads.
  static void store_levels(const std::vector<ConeSearch>& s, Mask texels, PerTexel& out, bool squared) {
    for (Mask pairs = (texels | texels >> 1) & 0x55555555u; pairs != 0; pairs &= pairs - 1) {
      const size_t k = static_cast<size_t>(low_bit(pairs));
      Pair v = {s[k].level(), s[k + 1].level()};
      if (squared) v = pair_min(v * v, Pair{std::numeric_limits<double>::max(), std::numeric_limits<double>::max()});
      std::memcpy(&out[k], &v, sizeof v);
    }
  }

  // Relaxed cones: drop the texels that see no point of r descend. Once for the block first
  // (no point descends as seen from F_B: then from no F_p inside it either).
  // Per texel the term along x depends on its column only, the one along y on its row: each
  // is computed once, two columns (rows) at a time, and the texels' sums two at a time
  // (rises_away's verdict, bit for bit: where a minimum picks the other of two equal
  // products, they differ at most in the sign of a zero, which no sum's sign depends on).
  Mask rising(const float* box, const Rect& r, const Block& b, Mask keep) const {
    if ((keep & (keep - 1)) != 0 && rises_away(box, r, b.f)) return 0;
    const std::array<double, kBlock> along_x = lowest_terms(box[0], box[1], r.x0, r.x1, b.i0),
                                     along_y = lowest_terms(box[2], box[3], r.y0, r.y1, b.j0);
    Mask out = 0;
    for (Mask pairs = (keep | keep >> 1) & 0x55555555u; pairs != 0; pairs &= pairs - 1) {
      const size_t k = static_cast<size_t>(low_bit(pairs));
      out |= less_bits(load_pair(&along_x[k & (kBlock - 1)]) + along_y[k >> kBlockLog], Pair{0.0, 0.0}) << k;
    }
    return out & keep;
  }
  // rises_away()'s lowest term along one axis for the block's columns (rows)
  // [t0 + c, t0 + c + 1], c = 0 .. kBlock - 1.
  static std::array<double, kBlock> lowest_terms(double g0, double g1, double r0, double r1, int t0) {
    std::array<double, kBlock> out;
    for (size_t c = 0; c < kBlock; c += 2) {
      const Pair f0 = {static_cast<double>(t0 + static_cast<int>(c)), static_cast<double>(t0 + static_cast<int>(c) + 1)};
      const Pair d0 = r0 - (f0 + 1.0), d1 = r1 - f0;
      const Pair low = pair_min(pair_min(g0 * d0, g0 * d1), pair_min(g1 * d0, g1 * d1));
      std::memcpy(&out[c], &low, sizeof low);
    }
    return out;
  }

  // Over one copy of the map shifted by (ox, oy) pixels. Conservative cones go depth-first,
  // the nearest child (to the block) first. Relaxed cones go best-first: the node of largest
  // first-order bound (m - T) / d next (`key`), with the best child of the node just split
  // searched next without the heap, the rest queued. Why: a relaxed cone's steepest point
  // seen descending is often a far crest, and searched nearest first the levels rose leaf by
  // leaf along the crests on the way, each leaf too little to dismiss the next (1024² bumps:
  // 7.7 s; started at their final levels, 2.3 s; best-first 3.5-3.9 s). Conservative cones
  // mostly find theirs next to the texel, where depth-first is cheaper (best-first, 256², with
  // the wavefront: bumps +5 % instructions, bricks +7 %, noise +8 %). The order changes how
  // much is split before the levels are reached, not the answer: it is the same within the
  // tolerance.
  void visit(const Block& b, const PerTexel& top, const PerTexel& cap, std::vector<ConeSearch>& s, double ox, double oy, Mask mask0) {
    stack_.clear();
    queue_.clear();
    const double root_d = rect_distance(Rect{ox, oy, ox + w_, oy + h_}, b.f);
    stack_.push_back({root_, 0, 0, static_cast<float>(global_max_), mask0, root_d * root_d,
                      squared_gaps(b.i0, ox, ox + w_), squared_gaps(b.j0, oy, oy + h_)});
    if (relaxed_) queue_.emplace_back(0.0, 0u);  // stack_ holds the nodes, queue_ their order
    PerTexel level2{};
    // The nearest child of a node is searched next without going through the stack, and when
    // no level has changed since it was tested (nothing between but the parent's plane test,
    // which rarely concedes a bound) the test is not made again: its verdicts are the mask
    // it carries (44 % of the nodes on the bricks; the same verdicts, so the same search).
    Node n{};
    bool held = false, tested = false;  // n is the child to search next; its mask is current
    while (live_ != 0) {
      if (!held) {
        if (relaxed_) {
          if (queue_.empty()) break;
          std::pop_heap(queue_.begin(), queue_.end());
          n = stack_[queue_.back().second];
          queue_.pop_back();
        } else {
          if (stack_.empty()) break;
          n = stack_.back();
          stack_.pop_back();
        }
      }
      held = false;
      const double m = n.m;
      const int size = 1 << n.level;
      const Rect r = node_rect(n, ox, oy);
      const double size2 = static_cast<double>(size) * size;
      // A node no higher than the apex, or whose maximum over its nearest distance is no
      // steeper than the slope already found (the value returned, level()), cannot change
      // that texel's answer: (m - T) <= level d, squared (both sides >= 0).
      // The plane test (`apart`) only for nodes no larger than their distance: closer, the
      // cone's distance term bends across the node and the test almost never dismisses it
      // (measured on the bricks at 256²: 3 % of the tests at 8 texels, none above; a test
      // costs ~300 instructions). Only a prune is skipped, never a point counted.
      Mask apart = 0, keep;
      if (tested) {
        keep = n.mask;  // within live_, which only leaves change
        apart = apart_bits(n.gx2, n.gy2, keep, size2);
      } else {
        const Mask live = n.mask & live_;
        store_levels(s, live, level2, true);
        keep = steeper<true>(m, n.gx2, n.gy2, top, level2, live, size2, apart);
      }
      tested = false;
      if (keep == 0) continue;
      conceded_ = false;
      if (n.level > 0) {
        const size_t index = tree_.index(n.level, n.x, n.y);
        // Relaxed cones test the gradient box and no plane: their slopes are lower, so 77 % of
        // their plane tests failed (bricks, 256²), and the ones that did not spared less than
        // they all cost (without them, 256²: bricks -3.9 % instructions, noise -0.8 %, the
        // smooth bumps -15 %). (The tree keeps its planes: the conservative search that
        // relaxed cones fall back to where a bound stayed loose tests them.)
        if (relaxed_) {
          // Every node but the root had its rising test when it was made (below).
          if (n.level == root_) keep = rising(gradient_box(n.level, n.x, n.y).data(), r, b, keep);
        } else {
          keep = planes(&tree_.plane[static_cast<size_t>(n.level)][index * 3], r, b, top, s, keep, apart);
        }
        if (keep == 0) continue;
      } else {
        if (near_) {
          // The texels whose neighbourhood holds this leaf have searched it already.
          const int c = n.x - b.i0, rr = n.y - b.j0;
          Mask cols = 0, rows = 0;
          for (int u = std::max(c - 1, 0); u <= std::min(c + 1, kBlock - 1); ++u) cols |= kColumn << u;
          for (int u = std::max(rr - 1, 0); u <= std::min(rr + 1, kBlock - 1); ++u) rows |= kRow << (u * kBlock);
          keep &= ~(cols & rows);
          apart &= keep;
          if (keep == 0) continue;
        }
        Mask gridded = 0;  // texels whose corner_texel_settles() has failed
        std::array<double, 9> leaf_grid{};  // conservative cones: its grid values, for corner_texel_settles()
        if (!relaxed_) {
          const std::array<float, 9> g = grid_.texel(n.x, n.y);
          std::copy(g.begin(), g.end(), leaf_grid.begin());
        }
        // A leaf in a texel's row or column is taken whole first (side_texel_settles):
        // conservative cones then need no plane test, which costs more.
        Mask whole = 0;
        for (Mask q = keep; q != 0; q &= q - 1) {
          const size_t k = static_cast<size_t>(low_bit(q));
          if (r.x0 == footprint_[k].x0 || r.y0 == footprint_[k].y0) whole |= Mask{1} << k;
        }
        // Relaxed cones test no plane at a leaf: after the gradient box, their pieces' own
        // first bounds cost less than the plane tests they would spare (without them, 256²:
        // bricks -2.9 % instructions, noise -1.4 %, bumps -2.2 %). Conservative cones keep
        // them: without them the bricks took 2.4 % fewer instructions but the smooth bumps 13 %
        // more (there the surface hugs the cone and the pieces' bounds close late). At a leaf
        // that is only the plane's one-root bound: a texel it leaves is tested on its own grid
        // values (corner_texel_settles), which settle 60-70 % of them on the smooth bumps where
        // the plane's curvature had failed, and then goes to its pieces; the exact plane test
        // (under) settled fewer after that than it cost (256² instructions, against the plane
        // test alone: bumps -10 %, bricks -6 %, noise -1.6 %; with under() between them: bumps
        // -7 %).
        if (relaxed_) {
          if (n.level == root_) keep = rising(leaves_.box(n.x, n.y), r, b, keep);
        } else {
          apart &= ~whole;
          // The plane test's one-root bound, then the texel's grid values.
          keep = planes(leaves_.plane(n.x, n.y), r, b, top, s, keep, apart, [&](size_t k) {
            if (s[k].corner_texel_settles(leaf_grid, ox + n.x, oy + n.y, s[k].level())) return true;
            // Then at the slope widened by the tolerance, conceding it as under() does: the
            // leaf holds nothing steeper than psi (1 + tolerance), which becomes the bound
            // (the stored cone at most that much narrower, never wider). Near the far
            // tangencies of smooth maps most leaves are within the tolerance of the level and
            // went to their pieces (bumps, instructions: 256² +0.4 %, 512² -1.5 %, 1024² -3.8 %).
            const double widened = s[k].psi * (1 + tol_);
            if (widened > s[k].bound && s[k].corner_texel_settles(leaf_grid, ox + n.x, oy + n.y, widened)) {
              s[k].bound = widened;
              return true;
            }
            gridded |= Mask{1} << k;
            return false;
          });
        }
        if (keep == 0) continue;
        const std::array<Piece, 4> pieces = texel_pieces(ox, oy, n.x, n.y);
        for (Mask q = keep; q != 0; q &= q - 1) {
          const size_t k = static_cast<size_t>(low_bit(q));
          if ((whole >> k) & 1 ? !s[k].side_texel_settles(grid_, n.x, n.y, ox, oy) : relaxed_ || ((gridded >> k) & 1) || !s[k].corner_texel_settles(leaf_grid, ox + n.x, oy + n.y, s[k].level()))
            for (const Piece& p : pieces) s[k].piece(p);
          if (!(s[k].psi < cap[k])) live_ &= ~(Mask{1} << k);
        }
        continue;
      }
      // The children, each with the texels for which the test above would not skip it when
      // popped (the level only grows until then, and the test is repeated there).
      std::array<Node, 4> kids;
      int count = 0;
      const int l = n.level - 1;
      const int cs = 1 << l, kw = tree_.w[static_cast<size_t>(l)], kh = tree_.h[static_cast<size_t>(l)];
      const float* kid_max = tree_.level[static_cast<size_t>(l)].data();
      const int cx0 = 2 * n.x, cx1 = std::min(2 * n.x + 1, kw - 1), cy0 = 2 * n.y, cy1 = std::min(2 * n.y + 1, kh - 1);
      std::array<Gaps, 2> kgx2{}, kgy2{};
      std::array<double, 2> bgx{}, bgy{};  // gaps to the block's footprint
      // Along one axis: the squared gaps from each of the block's texel columns (rows) to
      // the children's cells k0..k1 (origin o, cells cs wide, clipped at `extent`), and the
      // gap from the block's footprint [f0, f1].
      auto axis_gaps = [&](int k0, int k1, double o, double extent, int t0, double f0, double f1, std::array<Gaps, 2>& g2,
                           std::array<double, 2>& bg) {
        for (int k = k0; k <= k1; ++k) {
          const double a0 = o + static_cast<double>(k) * cs, a1 = o + std::min(static_cast<double>(k + 1) * cs, extent);
          const size_t u = static_cast<size_t>(k - k0);
          g2[u] = squared_gaps(t0, a0, a1);
          bg[u] = gap(f0, f1, a0, a1);
        }
      };
      axis_gaps(cx0, cx1, ox, static_cast<double>(w_), b.i0, b.f.x0, b.f.x1, kgx2, bgx);
      axis_gaps(cy0, cy1, oy, static_cast<double>(h_), b.j0, b.f.y0, b.f.y1, kgy2, bgy);
      // Child u = 2 uy + ux; one beyond the map's edge gets the maximum -inf, which no texel keeps.
      std::array<double, 4> km;
      for (size_t u = 0; u < 4; ++u) {
        const int cx = cx0 + static_cast<int>(u & 1), cy = cy0 + static_cast<int>(u >> 1);
        km[u] = cx <= cx1 && cy <= cy1 ? kid_max[static_cast<size_t>(cy) * static_cast<size_t>(kw) + static_cast<size_t>(cx)] : -kInf;
      }
      const std::array<Mask, 4> kid = children_steeper(km, kgx2, kgy2, top, level2, keep);
      for (size_t u = 0; u < 4; ++u)
        if (kid[u] != 0) {
          const size_t ux = u & 1, uy = u >> 1;
          kids[static_cast<size_t>(count++)] = Node{l, cx0 + static_cast<int>(ux), cy0 + static_cast<int>(uy), static_cast<float>(km[u]), kid[u],
                                                    bgx[ux] * bgx[ux] + bgy[uy] * bgy[uy], kgx2[ux], kgy2[uy]};
        }
      if (count == 0) continue;
      if (relaxed_) {
        // The rising test when a node is made, not when it is popped: a node that rises away
        // from the block never enters the queue and its bound never competes for the order
        // (bumps at 512²: -9 % instructions; noise at 256²: +6 %, as it pops fewer of them).
        std::array<size_t, 4> made{};  // the children kept, in order
        size_t count_made = 0, best = 0;
        for (size_t a = 0; a < static_cast<size_t>(count); ++a) {
          Node& child = kids[a];
          const Rect cr = node_rect(child, ox, oy);
          child.mask = rising(child.level == 0 ? leaves_.box(child.x, child.y) : gradient_box(child.level, child.x, child.y).data(), cr, b, child.mask);
          if (child.mask == 0) continue;
          double lowest = kInf;  // the lowest apex of the texels it is kept for
          for (Mask q = child.mask; q != 0; q &= q - 1) lowest = std::min(lowest, top[static_cast<size_t>(low_bit(q))]);
          const double rise = child.m - lowest;  // > 0: steeper() kept the texels
          child.key = child.d2 > 0 ? rise * rise / child.d2 : kInf;  // the bound, squared
          if (count_made == 0 || child.key > kids[best].key) best = a;
          made[count_made++] = a;
        }
        if (count_made == 0) continue;
        for (size_t u = 0; u < count_made; ++u) {
          const size_t a = made[u];
          if (a == best) continue;
          queue_.emplace_back(kids[a].key, static_cast<uint32_t>(stack_.size()));
          stack_.push_back(kids[a]);
          std::push_heap(queue_.begin(), queue_.end());
        }
        n = kids[best];
        held = true;
        tested = !conceded_;
        continue;
      }
      // Farthest pushed first, the nearest searched next (insertion sort of <= 4, of
      // indices: a node is 96 bytes).
      std::array<size_t, 4> order = {0, 1, 2, 3};
      for (size_t a = 1; a < static_cast<size_t>(count); ++a)
        for (size_t c = a; c > 0 && kids[order[c - 1]].d2 < kids[order[c]].d2; --c) std::swap(order[c - 1], order[c]);
      for (size_t k = 0; k + 1 < static_cast<size_t>(count); ++k) stack_.push_back(kids[order[k]]);
      n = kids[order[static_cast<size_t>(count - 1)]];
      held = true;
      tested = !conceded_;
    }
  }

  // The four pieces of texel (x, y), next to block b (within one texel of it), built once
  // per block: most are a neighbour of two of the block's texels or more (bricks at 256²:
  // -0.5 % instructions conservative, -0.8 % relaxed).
  const std::array<Piece, 4>& around_pieces(const Block& b, int x, int y) {
    const int slot = (y - b.j0 + 1) * (kBlock + 2) + (x - b.i0 + 1);
    std::array<Piece, 4>& ps = around_[static_cast<size_t>(slot)];
    if (((around_built_ >> slot) & 1) == 0) {
      ps = texel_pieces(0, 0, x, y);
      around_built_ |= uint64_t{1} << slot;
    }
    return ps;
  }

  // The pixels node n covers in the copy of the map shifted by (ox, oy), clipped to the map.
  Rect node_rect(const Node& n, double ox, double oy) const {
    const int size = 1 << n.level;
    return {ox + static_cast<double>(n.x) * size, oy + static_cast<double>(n.y) * size, ox + std::min(static_cast<double>(n.x + 1) * size, static_cast<double>(w_)),
            oy + std::min(static_cast<double>(n.y + 1) * size, static_cast<double>(h_))};
  }

  // The gradient box of node (x, y) of level >= 1: the tree's, or at level 1 level1_box().
  std::array<float, 4> gradient_box(int level, int x, int y) {
    if (level == 1) return level1_box(x, y);
    const float* box = &tree_.gradient[static_cast<size_t>(level)][tree_.index(level, x, y) * 4];
    return {box[0], box[1], box[2], box[3]};
  }

  // The gradient box of level-1 node (x, y): the union of its texels' (max_tree releases
  // that level's boxes; the texels' come from the leaf cache).
  std::array<float, 4> level1_box(int x, int y) {
    std::array<float, 4> box = empty_box();
    for (int yy = 2 * y; yy <= std::min(2 * y + 1, h_ - 1); ++yy)
      for (int xx = 2 * x; xx <= std::min(2 * x + 1, w_ - 1); ++xx) widen_box(box.data(), leaves_.box(xx, yy));
    return box;
  }

  // The four pieces of texel (x, y) of the map shifted by (ox, oy) pixels.
  std::array<Piece, 4> texel_pieces(double ox, double oy, int x, int y) const {
    const std::array<float, 9> g = grid_.texel(x, y);
    const double px = ox + x, py = oy + y;
    return {Piece(px, py, g[0], g[1], g[3], g[4]), Piece(px + 0.5, py, g[1], g[2], g[4], g[5]), Piece(px, py + 0.5, g[3], g[4], g[6], g[7]),
            Piece(px + 0.5, py + 0.5, g[4], g[5], g[7], g[8])};
  }

  const MaxTree& tree_;
  const HalfGrid& grid_;
  int w_, h_;
  bool wrap_;
  double tol_;
  bool fans_;
  int root_;
  double global_max_;
  LeafCache leaves_;
  bool relaxed_ = false;
  bool near_ = false;  // visiting the map itself (not a copy): the neighbourhoods are searched
  Mask live_ = 0;  // texels still searching (psi below their cap)
  // around_pieces()'s pieces of the (kBlock + 2)^2 texels around the block, and which are built.
  std::array<std::array<Piece, 4>, (kBlock + 2) * (kBlock + 2)> around_{};
  uint64_t around_built_ = 0;
  static_assert((kBlock + 2) * (kBlock + 2) <= 64, "one bit per texel around a block");
  bool conceded_ = false;  // a plane test of the node being searched has raised a bound
  std::array<Rect, kBlock * kBlock> footprint_{};
  std::vector<Node> stack_;  // conservative: the nodes to search, the next last; relaxed: every node queued
  std::vector<std::pair<double, uint32_t>> queue_;  // relaxed: a max-heap of (key, index in stack_)
};

}  // namespace

// A seed for the next block, once: neighbouring texels often share their steepest point.
void add_seed(std::vector<ConeSearch::Point>& seeds, const ConeSearch::Point& p) {
  if (!p.valid) return;
  for (const ConeSearch::Point& q : seeds)
    if (q.x == p.x && q.y == p.y) return;
  seeds.push_back(p);
}

Image build_cone_map(const HeightField& input, const ConeMapOptions& o, Progress& progress) {
  // With half output the cones are those of the heights as stored (rounded to half); a copy
  // only then (the map's size again in working memory otherwise).
  HeightField rounded;
  if (o.half) {
    rounded = input;
    for (float& v : rounded.height.pixels) v = static_cast<float>(Imath::half(v));
  }
  const HeightField& field = o.half ? rounded : input;
  const int w = field.height.width, h = field.height.height;
  const HalfGrid g = half_grid(field);
  std::vector<float> texel_top(static_cast<size_t>(w) * static_cast<size_t>(h));
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      float m = -1.0f;
      for (float v : g.texel(i, j)) m = std::max(m, v);
      texel_top[static_cast<size_t>(j) * static_cast<size_t>(w) + static_cast<size_t>(i)] = m;
    }
  const bool relaxed = o.kind == ConeKind::relaxed;
  const MaxTree tree = max_tree(std::move(texel_top), g, w, h, relaxed);
  const std::vector<float>& apex = tree.level[0];

  Image out(w, h, 3);
  const int blocks_x = (w + kBlock - 1) / kBlock, blocks_y = (h + kBlock - 1) / kBlock;
  // Blocks in a wavefront: block (bi, bj) starts once the block on its left and the one
  // above it are done, and is seeded with both's steepest points (a texel's steepest point
  // is often its neighbours'; seeds from above as well as from the left: 1024² bumps, one
  // thread, relaxed -22 %, conservative -12 %). What a block passes on depends on its two
  // predecessors only, so results never depend on the threads or the order they run in.
  struct Seeds {
    std::vector<ConeSearch::Point> conservative, relaxed;
  };
  std::vector<Seeds> from_left(static_cast<size_t>(blocks_y)), from_above(static_cast<size_t>(blocks_x));
  struct Worker {
    BlockSearch walk;
    std::vector<ConeSearch> searches, fallback;
    Seeds in;
    std::vector<ConeSearch::Point> seeds;
  };
  tbb::enumerable_thread_specific<Worker> workers(
      [&] { return Worker{BlockSearch(tree, g, w, h, field.border == Border::wrap, o.tolerance, o.exact_fans), {}, {}, {}, {}}; });
  auto search_block = [&](int bi, int bj) {
    Worker& wk = workers.local();
    Block b;
    b.i0 = bi * kBlock;
    b.j0 = bj * kBlock;
    b.bw = std::min(kBlock, w - b.i0);
    b.bh = std::min(kBlock, h - b.j0);
    b.f = Rect{static_cast<double>(b.i0), static_cast<double>(b.j0), static_cast<double>(b.i0 + b.bw), static_cast<double>(b.j0 + b.bh)};
    BlockSearch::PerTexel top{}, cap{}, psi{};
    Mask all = 0;
    for (int y = 0; y < b.bh; ++y)
      for (int x = 0; x < b.bw; ++x) {
        const size_t k = static_cast<size_t>(y * kBlock + x);
        top[k] = apex[static_cast<size_t>(b.j0 + y) * static_cast<size_t>(w) + static_cast<size_t>(b.i0 + x)];
        cap[k] = kInf;
        all |= Mask{1} << k;
      }
    Seeds& left = from_left[static_cast<size_t>(bj)];
    Seeds& above = from_above[static_cast<size_t>(bi)];
    wk.in.conservative.clear();
    wk.in.relaxed.clear();
    for (const Seeds* from : {&left, &above}) {
      for (const ConeSearch::Point& p : from->conservative) add_seed(wk.in.conservative, p);
      for (const ConeSearch::Point& p : from->relaxed) add_seed(wk.in.relaxed, p);
    }
    Seeds out_seeds;
    // One search per texel: the supremum of the slope (relaxed: over points seen
    // descending).
    wk.walk.run(b, top, relaxed, all, cap, relaxed ? wk.in.relaxed : wk.in.conservative, wk.searches);
    std::vector<ConeSearch::Point>& next = relaxed ? out_seeds.relaxed : out_seeds.conservative;
    Mask loose = 0;
    for (Mask q = all; q != 0; q &= q - 1) {
      const size_t k = static_cast<size_t>(low_bit(q));
      psi[k] = wk.searches[k].level();
      add_seed(next, wk.searches[k].best);
      // A relaxed cone is never narrower than the conservative one (which satisfies the
      // relaxed condition too); where the relaxed search kept a loose bound (near a fan)
      // the conservative search decides, up to the relaxed bound.
      if (relaxed && wk.searches[k].bound > wk.searches[k].psi * (1 + o.tolerance)) {
        loose |= Mask{1} << k;
        cap[k] = psi[k];
      }
    }
    if (loose != 0) {
      wk.seeds = wk.in.conservative;
      wk.seeds.insert(wk.seeds.end(), out_seeds.relaxed.begin(), out_seeds.relaxed.end());  // points above T either way
      wk.walk.run(b, top, false, loose, cap, wk.seeds, wk.fallback);
      for (Mask q = loose; q != 0; q &= q - 1) {
        const size_t k = static_cast<size_t>(low_bit(q));
        psi[k] = std::min(psi[k], wk.fallback[k].level());
        add_seed(out_seeds.conservative, wk.fallback[k].best);
      }
    }
    for (Mask q = all; q != 0; q &= q - 1) {
      const int k = low_bit(q);
      const int i = b.i0 + (k & (kBlock - 1)), j = b.j0 + (k >> kBlockLog);
      const double p = psi[static_cast<size_t>(k)];
      const double ratio = p > 0 ? 1.0 / (p * w) : kInf;  // texels -> units of u
      out.at(i, j, 0) = field.height.at(i, j);
      out.at(i, j, 1) = round_down(std::min(ratio, static_cast<double>(kConeRatioCap)), o.half);
      const double t = top[static_cast<size_t>(k)];
      out.at(i, j, 2) = o.half ? half_above(static_cast<float>(t)) : static_cast<float>(t);
    }
    // The block on the right reads from_left[bj] and the one below from_above[bi], each only
    // after this block is done, and this block was the last to need what they held.
    above = out_seeds;
    left = std::move(out_seeds);
    progress.advance(1);
  };
  // Each block counts its predecessors not yet done; the last to finish feeds it.
  std::vector<std::atomic<uint8_t>> waiting(static_cast<size_t>(blocks_x) * static_cast<size_t>(blocks_y));
  for (int bj = 0; bj < blocks_y; ++bj)
    for (int bi = 0; bi < blocks_x; ++bi)
      waiting[static_cast<size_t>(bj) * static_cast<size_t>(blocks_x) + static_cast<size_t>(bi)].store(static_cast<uint8_t>((bi > 0) + (bj > 0)));
  progress.begin(relaxed ? "relaxed cone map" : "cone map", static_cast<uint64_t>(blocks_x) * static_cast<uint64_t>(blocks_y));
  const std::array<std::pair<int, int>, 1> first = {{{0, 0}}};
  tbb::parallel_for_each(first.begin(), first.end(), [&](const std::pair<int, int>& block, tbb::feeder<std::pair<int, int>>& feeder) {
    const auto [bi, bj] = block;
    search_block(bi, bj);
    auto done = [&](int x, int y) {
      if (x < blocks_x && y < blocks_y && --waiting[static_cast<size_t>(y) * static_cast<size_t>(blocks_x) + static_cast<size_t>(x)] == 0) feeder.add({x, y});
    };
    done(bi, bj + 1);
    done(bi + 1, bj);
  });
  progress.end();

  out.metadata = height_field_metadata(field);
  out.metadata["quantity"] = std::string(relaxed ? "relaxed cone map" : "cone map");
  out.metadata["cone_kind"] = std::string(cone_kind_name(o.kind));
  out.metadata["channels"] = std::string("R = texel height, G = cone ratio, B = apex height (max of the filtered surface over the texel)");
  out.metadata["ratio_units"] = std::string("units of u per unit of normalised height (texels square; multiply by texels_per_u for texels)");
  out.metadata["texels_per_u"] = w;
  out.metadata["ratio_cap"] = kConeRatioCap;
  out.metadata["tolerance"] = static_cast<float>(o.tolerance);
  if (relaxed) out.metadata["fans"] = std::string(o.exact_fans ? "exact" : "bound");
  return out;
}

std::vector<Image> cone_map_levels(Image level0) {
  std::vector<Image> levels;
  levels.push_back(std::move(level0));
  while (levels.back().width > 1 || levels.back().height > 1) {
    const Image& fine = levels.back();
    const int fw = fine.width, fh = fine.height, cw = std::max(1, fw / 2), ch = std::max(1, fh / 2);
    Image coarse(cw, ch, 3);
    for (int y = 0; y < ch; ++y) {
      // Finer texels overlapping this one's footprint (as build_min_max_pyramid).
      const int y0 = static_cast<int>(static_cast<long>(y) * fh / ch);
      const int y1 = static_cast<int>((static_cast<long>(y + 1) * fh + ch - 1) / ch) - 1;
      for (int x = 0; x < cw; ++x) {
        const int x0 = static_cast<int>(static_cast<long>(x) * fw / cw);
        const int x1 = static_cast<int>((static_cast<long>(x + 1) * fw + cw - 1) / cw) - 1;
        float hmax = -kConeRatioCap, ratio = kConeRatioCap, apex = -kConeRatioCap;
        for (int yy = y0; yy <= y1; ++yy)
          for (int xx = x0; xx <= x1; ++xx) {
            hmax = std::max(hmax, fine.at(xx, yy, 0));
            ratio = std::min(ratio, fine.at(xx, yy, 1));
            apex = std::max(apex, fine.at(xx, yy, 2));
          }
        coarse.at(x, y, 0) = hmax;
        coarse.at(x, y, 1) = ratio;
        coarse.at(x, y, 2) = apex;
      }
    }
    levels.push_back(std::move(coarse));
  }
  return levels;
}

// ---- the reference tracer ----

HeightHit trace_cone_map(const HeightField& field, const Image& cone, ConeKind kind, const HeightRay& r, int max_steps) {
  HeightHit out;
  const int w = field.height.width, h = field.height.height;
  if (!(r.dz < 0)) return out;
  const double horizontal = length(r.dx, r.dy);
  const double t_floor = r.z / -r.dz;  // where the ray reaches height 0, below every surface
  double t = r.z > 1 ? (r.z - 1) / -r.dz : 0.0;
  auto wrap = [](int k, int n) { return ((k % n) + n) % n; };
  while (out.steps < max_steps) {
    ++out.steps;
    const double x = r.x + t * r.dx, y = r.y + t * r.dy, z = r.z + t * r.dz;
    if (field.border == Border::clamp && (x < 0 || y < 0 || x > w || y > h)) return out;
    if (t >= t_floor) {
      // At height 0 over the map (or starting below it), at or below S: it met S here, its
      // footprint test having missed the floor by a rounding hair (z(t_floor) ~ +1e-16 over a
      // flat map).
      out.hit = true;
      out.t = t;
      return out;
    }
    // The texel the ray is in or entering: judged a hair ahead along the ray, so that a point
    // on an edge belongs to the texel ahead even when rounding put it a hair short of the edge
    // (the exit time was then t itself, and the march stalled until max_steps: a miss).
    const double ahead = t + 1e-12 * (1 + t);
    int i = static_cast<int>(std::floor(r.x + ahead * r.dx)), j = static_cast<int>(std::floor(r.y + ahead * r.dy));
    if (field.border == Border::clamp) {
      i = std::clamp(i, 0, w - 1);
      j = std::clamp(j, 0, h - 1);
    }
    const int ci = wrap(i, w), cj = wrap(j, h);
    const double ratio = static_cast<double>(cone.at(ci, cj, 1)) * w, apex = cone.at(ci, cj, 2);
    double t_exit = t_floor;
    if (r.dx > 0) t_exit = std::min(t_exit, (i + 1 - r.x) / r.dx);
    if (r.dx < 0) t_exit = std::min(t_exit, (i - r.x) / r.dx);
    if (r.dy > 0) t_exit = std::min(t_exit, (j + 1 - r.y) / r.dy);
    if (r.dy < 0) t_exit = std::min(t_exit, (j - r.y) / r.dy);
    t_exit = std::max(t_exit, t);
    const double step = z >= apex ? ratio * (z - apex) / (horizontal + ratio * -r.dz) : 0.0;
    if (t + step < t_exit) {
      double th = 0;
      if (intersect_footprint(field, i, j, r, t, t_exit, th)) {
        out.hit = true;
        out.t = th;
        return out;
      }
      t = t_exit;
      continue;
    }
    const double tq = std::min(t + step, t_floor);
    if (kind == ConeKind::relaxed &&
        field.bilinear(r.x + tq * r.dx, r.y + tq * r.dy) >= r.z + tq * r.dz) {
      // One crossing in [t, tq] (the relaxed cone's guarantee): bisect it.
      double lo = t, hi = tq;
      for (int it = 0; it < 64; ++it) {
        const double mid = 0.5 * (lo + hi);
        if (mid <= lo || mid >= hi) break;
        (field.bilinear(r.x + mid * r.dx, r.y + mid * r.dy) >= r.z + mid * r.dz ? hi : lo) = mid;
      }
      out.hit = true;
      out.t = hi;
      return out;
    }
    t = tq;
  }
  return out;
}

}  // namespace meso
