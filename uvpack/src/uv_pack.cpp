#include "meso/uvpack/uv_pack.hpp"

#include "meso/core/uv_texels.hpp"
#include "free_rows.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace meso {

namespace {

// A chart's frame: its q coordinates turned by an angle (cos, sin) about the origin, and the
// bounding box there. Frame 0 is the input's orientation; frame 1, when the chart has one, the
// orientation of its minimum-area bounding rectangle.
struct Frame {
  double cos = 1, sin = 0;
  double x0 = 0, y0 = 0, w = 0, h = 0;
};

// A chart in "q" coordinates, q = (u, -v): x right and y down like texel rows. Charts are
// moved to their boxes, so only differences matter; -v rather than image.hpp's 1 - v keeps
// UVs near 0 apart (1 - 1e-17 is 1: a chart 1e-17 across had packed to a point, exit 0).
struct Chart {
  std::vector<int> faces;
  std::vector<std::array<double, 6>> tris;  // q of the three corners, face_halfedges() order
  std::array<Frame, 2> frames;
  int frame_count = 1;
  double area = 0;
  double factor = 1;                        // options.chart_scale
};

// Orientation o of a chart: frame o / 4 turned by o % 4 quarter turns.
constexpr int kMaxOrientations = 8;

// Corner q in orientation o, measured from the corner of the turned box.
std::array<double, 2> turn(const Chart& c, double qx, double qy, int o) {
  const Frame& f = c.frames[static_cast<size_t>(o >> 2)];
  const double dx = f.cos * qx - f.sin * qy - f.x0, dy = f.sin * qx + f.cos * qy - f.y0;
  switch (o & 3) {
    case 1: return {f.h - dy, dx};
    case 2: return {f.w - dx, f.h - dy};
    case 3: return {dy, f.w - dx};
    default: return {dx, dy};
  }
}

// The box of a chart's corners turned by (cos, sin).
Frame frame_of(const Chart& c, double cos, double sin) {
  Frame f;
  f.cos = cos;
  f.sin = sin;
  double x0 = std::numeric_limits<double>::infinity(), y0 = x0, x1 = -x0, y1 = -x0;
  for (const auto& t : c.tris)
    for (size_t k = 0; k < 3; ++k) {
      const double x = cos * t[2 * k] - sin * t[2 * k + 1], y = sin * t[2 * k] + cos * t[2 * k + 1];
      x0 = std::min(x0, x);
      x1 = std::max(x1, x);
      y0 = std::min(y0, y);
      y1 = std::max(y1, y);
    }
  f.x0 = x0;
  f.y0 = y0;
  f.w = x1 - x0;
  f.h = y1 - y0;
  return f;
}

// The turn that makes the chart's bounding box smallest: one of the convex hull's edges lies on
// the minimum-area rectangle (Freeman and Shapira), so each edge's direction is tried. Returns
// the frame whose x axis runs along the best edge.
Frame min_area_frame(const Chart& c) {
  std::vector<std::array<double, 2>> p;
  p.reserve(3 * c.tris.size());
  for (const auto& t : c.tris)
    for (size_t k = 0; k < 3; ++k) {
      if (!std::isfinite(t[2 * k]) || !std::isfinite(t[2 * k + 1])) return c.frames[0];  // no order to sort by
      p.push_back({t[2 * k], t[2 * k + 1]});
    }
  std::sort(p.begin(), p.end());
  p.erase(std::unique(p.begin(), p.end()), p.end());
  if (p.size() < 3) return c.frames[0];
  // Andrew's monotone chain.
  auto cross = [](const std::array<double, 2>& o, const std::array<double, 2>& a, const std::array<double, 2>& b) {
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
  };
  std::vector<std::array<double, 2>> hull(2 * p.size());
  size_t k = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], p[i]) <= 0) --k;
    hull[k++] = p[i];
  }
  for (size_t i = p.size() - 1, lower = k + 1; i > 0; --i) {
    while (k >= lower && cross(hull[k - 2], hull[k - 1], p[i - 1]) <= 0) --k;
    hull[k++] = p[i - 1];
  }
  hull.resize(k - 1);
  Frame best = c.frames[0];
  double best_area = best.w * best.h;
  for (size_t i = 0; i < hull.size(); ++i) {
    const auto& a = hull[i];
    const auto& b = hull[(i + 1) % hull.size()];
    const double dx = b[0] - a[0], dy = b[1] - a[1], len = std::hypot(dx, dy);
    if (!(len > 0)) continue;
    // Turn the edge onto the x axis: by -atan2(dy, dx).
    double x0 = std::numeric_limits<double>::infinity(), y0 = x0, x1 = -x0, y1 = -x0;
    const double cs = dx / len, sn = -dy / len;
    for (const auto& q : hull) {
      const double x = cs * q[0] - sn * q[1], y = sn * q[0] + cs * q[1];
      x0 = std::min(x0, x);
      x1 = std::max(x1, x);
      y0 = std::min(y0, y);
      y1 = std::max(y1, y);
    }
    if ((x1 - x0) * (y1 - y0) < best_area) {
      best_area = (x1 - x0) * (y1 - y0);
      best = frame_of(c, cs, sn);
    }
  }
  return best;
}

// Charts sit 1/64 texel inside their first texel: a corner exactly on a texel edge could
// otherwise touch the neighbouring texel once the new UVs are rounded to float.
constexpr double kInset = 1.0 / 64;

// How far, in texels, rounding a written UV to float can move a corner in an atlas of n
// texels: half a float ulp of a value below 1 is at most 2^-25, n 2^-25 texels; twice that
// for margin. Footprints are rasterised with texels grown by it (triangle_overlaps_texel), so
// the texels the written, rounded triangles touch are within them: a chart edge a hair short
// of a texel line, pushed across it by the rounding, had shared that texel with the next
// chart at --padding 0. Below kInset for every atlas size allowed (16384: 2^-10 texels).
double rounding_margin(double n) { return n * 0x1p-24; }

// Free texels kept between two charts' touched texels: the padding, at least 2 with mip_safe
// (level 0's share of the per-level gaps, see pack_uv_charts in the header).
int chart_gap(const UvPackOptions& o) { return o.mip_safe >= 0 ? std::max(2, o.padding) : std::max(0, o.padding); }

struct Placement {
  int orientation = 0, x = 0, y = 0;
};

// A chart's footprint in one orientation: its texels as runs of consecutive texels per row
// (row, first, last) relative to its box corner, the box size and the texel count.
struct Footprint {
  std::vector<std::array<int, 3>> runs;
  int bw = 0, bh = 0;
  size_t texels = 0;
};

// The texels a chart touches at scale s and orientation r, relative to its box's corner
// placed at kInset past texel (0, 0)'s corner: conservative, as uv_check rasterises. A
// triangle's touched texels in a row are consecutive, so they are gathered as spans (one per
// triangle and row, split where a texel is skipped), then merged row by row: the work is per
// span, not per texel of the box.
Footprint footprint(const Chart& c, double s, int r, double grow) {
  Footprint out;
  if (c.area == 0) {
    // No UV area (every face degenerate: a point or a line in UV): no texel to keep, so one
    // texel whatever its extent, and its UVs collapse to that texel's centre. Its extent
    // scaled as the others' had bounded the common scale: a degenerate line 1 long in UV beside
    // a chart 0.2 across had left that chart 1/5 of the atlas it could have.
    out.bw = out.bh = 1;
    out.runs.push_back({0, 0, 0});
    out.texels = 1;
    return out;
  }
  s *= c.factor;
  const Frame& f = c.frames[static_cast<size_t>(r >> 2)];
  const double w = (r & 1) ? f.h : f.w, h = (r & 1) ? f.w : f.h;
  out.bw = static_cast<int>(std::floor(w * s + kInset + grow)) + 1;
  out.bh = static_cast<int>(std::floor(h * s + kInset + grow)) + 1;
  std::vector<std::array<int, 3>> spans;
  for (const auto& t : c.tris) {
    UvTriangle tri{};
    for (int k = 0; k < 3; ++k) {
      const auto p = turn(c, t[static_cast<size_t>(2 * k)], t[static_cast<size_t>(2 * k + 1)], r);
      tri.px[k] = p[0] * s + kInset;
      tri.py[k] = p[1] * s + kInset;
    }
    const double area = (tri.px[1] - tri.px[0]) * (tri.py[2] - tri.py[0]) - (tri.py[1] - tri.py[0]) * (tri.px[2] - tri.px[0]);
    if (area == 0) continue;
    std::array<int, 3> span{-1, 0, -1};
    const auto gather = [&](int x, int y) {
      if (y == span[0] && x == span[2] + 1) {
        span[2] = x;
        return;
      }
      if (span[0] >= 0) spans.push_back(span);
      span = {y, x, x};
    };
    for_each_touched_texel(tri, out.bw, out.bh, gather, 0, 1 << 30, grow);
    if (span[0] >= 0) spans.push_back(span);
  }
  std::sort(spans.begin(), spans.end());
  for (const auto& sp : spans) {
    if (!out.runs.empty() && out.runs.back()[0] == sp[0] && sp[1] <= out.runs.back()[2] + 1) {
      out.runs.back()[2] = std::max(out.runs.back()[2], sp[2]);
      continue;
    }
    out.runs.push_back(sp);
  }
  for (const auto& run : out.runs) out.texels += static_cast<size_t>(run[2] - run[1] + 1);
  if (out.runs.empty()) {  // a chart without UV area keeps one texel
    out.runs.push_back({0, 0, 0});
    out.texels = 1;
  }
  return out;
}

// The orientations a chart is tried in: the first `turns` quarter turns of each of its frames.
int orientation_count(const Chart& c, int turns) { return turns * c.frame_count; }
int orientation_at(int i, int turns) { return (i / turns) * 4 + i % turns; }

using Footprints = std::vector<std::array<Footprint, kMaxOrientations>>;

// Every chart's footprints at scale s, computed in parallel (each chart on its own: the
// result does not depend on the split).
Footprints footprints_at(const std::vector<Chart>& charts, double s, int turns, double grow) {
  Footprints out(charts.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, charts.size()), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t c = range.begin(); c < range.end(); ++c)
      for (int i = 0; i < orientation_count(charts[c], turns); ++i) {
        const int r = orientation_at(i, turns);
        out[c][static_cast<size_t>(r)] = footprint(charts[c], s, r, grow);
      }
  });
  return out;
}

// In a max tree over `size` leaves (a power of two; node i has children 2i and 2i + 1, the
// leaves are size..2 size - 1, unused ones 0), the first leaf >= from whose value is at least
// need (> 0), or -1. Bottom-up: from the leaf, climb until a subtree to the right holds such a
// value, then descend to its leftmost one; the answer is usually near `from`, so this visits
// fewer nodes than a descent from the root.
int first_leaf_at_least(const int* t, int size, int from, int need) {
  if (from >= size) return -1;
  size_t i = static_cast<size_t>(from) + static_cast<size_t>(size);
  while (t[i] < need) {
    while (i & 1) i >>= 1;  // a right child: its parent's range ends where its own does
    if (i == 0) return -1;  // climbed past the root: nothing to the right
    ++i;                    // the subtree just right of the ranges seen so far
  }
  while (i < static_cast<size_t>(size)) {
    i *= 2;
    if (t[i] < need) ++i;
  }
  return static_cast<int>(i) - size;
}

// Maximum over rows with "the first row at or after `from` whose value is at least `need`" in
// O(log n): the row scan skips full rows without visiting them.
class RowMax {
 public:
  explicit RowMax(int rows) : size_(1) {
    while (size_ < rows) size_ *= 2;
    tree_.assign(2 * static_cast<size_t>(size_), 0);
  }
  void set(int row, int value) {
    size_t i = static_cast<size_t>(row) + static_cast<size_t>(size_);
    tree_[i] = value;
    for (i /= 2; i >= 1; i /= 2) tree_[i] = std::max(tree_[2 * i], tree_[2 * i + 1]);
  }
  int value(int row) const { return tree_[static_cast<size_t>(row) + static_cast<size_t>(size_)]; }
  // The first row >= from with value >= need (> 0), or -1.
  int first_at_least(int from, int need) const { return first_leaf_at_least(tree_.data(), size_, from, need); }

 private:
  int size_;
  std::vector<int> tree_;
};

// One greedy packing at a scale: whether every chart found room, where, and how far it got,
// which aims the scale search's next attempt.
struct Attempt {
  bool ok = false;
  std::vector<Placement> where;
  size_t touched = 0;  // texels the placed charts touch
  // Succeeded: the rows the charts reach / the rows inside the border margin. Failed: the texels
  // the atlas was seen to hold (the placed charts', plus the still free ones when fewer were
  // left than the remaining charts need) / the texels of all charts.
  double fill = 0;
};

// Greedy placement of the charts' footprints at one scale, the charts in `order`, each where its first fit in scan order
// (lowest row, then leftmost) among its orientations is highest: by its top row, or by_bottom by
// the row below it (which favours the orientation that adds least height).
Attempt place_all(const std::vector<Chart>& charts, const Footprints& prints, const std::vector<size_t>& order, bool by_bottom, const UvPackOptions& o,
                  int turns) {
  Attempt result;
  std::vector<Placement>& where = result.where;
  size_t& touched = result.touched;
  const int n = o.size, pad = chart_gap(o), margin = atlas_border_margin(o);
  // A packing cannot succeed when the charts' texels (each in its smallest orientation)
  // exceed the texels inside the margin: fail before placing anything.
  std::vector<size_t> least(charts.size());
  size_t need = 0;
  for (size_t c = 0; c < charts.size(); ++c) {
    least[c] = prints[c][0].texels;
    for (int i = 1; i < orientation_count(charts[c], turns); ++i)
      least[c] = std::min(least[c], prints[c][static_cast<size_t>(orientation_at(i, turns))].texels);
    need += least[c];
  }
  const size_t inside = static_cast<size_t>(std::max(0, n - 2 * margin)) * static_cast<size_t>(std::max(0, n - 2 * margin));
  if (need > inside) {
    result.fill = static_cast<double>(inside) / static_cast<double>(need);
    return result;
  }
  // The same bound while placing: the charts still to place need at least `remaining` texels
  // that no placed chart blocks, so once fewer are free the packing has failed; stopping there
  // changes the work, not the outcome.
  size_t remaining = need, free_inside = inside;
  // Texels within `pad` of a placed chart's texel (Chebyshev) are blocked: a new chart's
  // texels must avoid them.
  FreeRows free_rows(n);
  // longest_free: per row the longest free run, so whole rows without room for a footprint's
  // widest run are skipped at once.
  RowMax longest_free(n);
  // Blocks columns [a, b] of a row, taking the free ones inside the margin off free_inside;
  // the row's longest free run is refreshed once the chart is placed.
  auto block_range = [&](int row, int a, int b) {
    if (row >= margin && row < n - margin && std::max(a, margin) <= std::min(b, n - margin - 1)) {
      free_inside -= free_rows.take(row, std::max(a, margin), std::min(b, n - margin - 1));
    }
    free_rows.take(row, a, b);
  };
  for (int row = 0; row < n; ++row) longest_free.set(row, free_rows.longest(row));
  where.assign(charts.size(), Placement{});
  int bottom = margin;  // the first row below every placed chart
  for (size_t c : order) {
    // Each orientation's first fit in scan order (lowest row, then leftmost), the
    // orientations searched in parallel; the chosen one is the least (key, x, orientation),
    // whatever the timing, where the key is the fit's top row (or, by_bottom, the row below its
    // box). lowest_key lets a scan stop below a fit another one already found (it could not
    // win), which changes work, not the result.
    std::array<Placement, kMaxOrientations> fit;
    std::array<bool, kMaxOrientations> fits{};
    std::atomic<int> lowest_key{2 * n};
    auto key_offset = [&](int r) { return by_bottom ? prints[c][static_cast<size_t>(r)].bh : 0; };
    auto scan = [&](int r) {
      const Footprint& fp = prints[c][static_cast<size_t>(r)];
      const int bw = fp.bw, bh = fp.bh, off = key_offset(r);
      // Runs tested widest first: they are the likeliest to be blocked; a run that rules out a
      // word of candidates moves halfway to the front, as the next words tend to meet the same
      // obstacle. A fit needs every run free, so the order changes the work, not the fit found.
      std::vector<std::array<int, 3>> runs = fp.runs;
      std::stable_sort(runs.begin(), runs.end(), [](const auto& p, const auto& q) { return p[2] - p[1] > q[2] - q[1]; });
      // The footprint's widest run (row offset, length): rows without a free run that long
      // are skipped through the row maximum.
      int wide_row = 0, wide = 0;
      for (const auto& run : runs)
        if (run[2] - run[1] + 1 > wide) wide = run[2] - run[1] + 1, wide_row = run[0];
      for (int y = margin; y + bh <= n - margin && y + off <= lowest_key.load(std::memory_order_relaxed); ++y) {
        const int next = longest_free.first_at_least(y + wide_row, wide);
        if (next < 0) return;
        if (next - wide_row > y) {
          y = next - wide_row - 1;  // the loop's ++y lands on it
          continue;
        }
        // Each run's row needs a free run at least as long; at the first that has none the scan
        // moves on to the next row where that run would find one.
        int skip = -1;
        for (size_t i = 0; i < runs.size(); ++i) {
          const auto run = runs[i];
          const int length = run[2] - run[1] + 1;
          if (longest_free.value(y + run[0]) < length) {  // the rows' maxima, contiguous in memory
            skip = longest_free.first_at_least(y + run[0] + 1, length);
            if (skip < 0) return;
            skip -= run[0];
            break;
          }
        }
        if (skip >= 0) {
          y = skip - 1;  // the loop's ++y lands on it
          continue;
        }
        // The row's candidate columns x in [margin, n - margin - bw], 64 at a time from x0: a
        // mask that each run narrows to the starts where its row is free; the lowest bit left
        // is the leftmost fit.
        const int x_last = n - margin - bw;
        for (int x0 = margin; x0 <= x_last;) {
          uint64_t fit_mask = x_last - x0 < 63 ? ~uint64_t{0} >> (63 - (x_last - x0)) : ~uint64_t{0};
          size_t ruled_out = 0;  // the run that emptied the mask
          for (size_t i = 0; i < runs.size() && fit_mask != 0; ++i) {
            const auto run = runs[i];
            const int row = y + run[0];
            for (int at = run[1]; at <= run[2] && fit_mask != 0; at += 64)
              fit_mask &= free_rows.starts(row, x0 + at, std::min(64, run[2] - at + 1));
            if (fit_mask == 0) ruled_out = i;
          }
          if (fit_mask == 0) {
            // No start in [x0, x0 + 63] fits: the next 64 begin where the run that ruled these
            // out is next free in its row (nowhere: no fit in this row); the holes too short
            // for it are passed without testing their starts.
            const auto run = runs[ruled_out];
            std::swap(runs[ruled_out], runs[ruled_out / 2]);
            const int free_at = free_rows.next_fit(y + run[0], x0 + 64 + run[1], run[2] - run[1] + 1);
            if (free_at < 0) break;
            x0 = free_at - run[1];
            continue;
          }
          fit[static_cast<size_t>(r)] = {r, x0 + __builtin_ctzll(fit_mask), y};
          fits[static_cast<size_t>(r)] = true;
          int seen = lowest_key.load(std::memory_order_relaxed);
          while (y + off < seen && !lowest_key.compare_exchange_weak(seen, y + off, std::memory_order_relaxed)) {
          }
          return;
        }
      }
    };
    // An orientation whose footprint is a lower one's (a rectangle's half turn) would find the
    // same fit and lose the tie: it is not searched.
    const int count = orientation_count(charts[c], turns);
    std::array<int, kMaxOrientations> tried{};
    int distinct = 0;
    for (int i = 0; i < count; ++i) {
      const int r = orientation_at(i, turns);
      const Footprint& f = prints[c][static_cast<size_t>(r)];
      bool same = false;
      for (int j = 0; j < distinct && !same; ++j) {
        const Footprint& g = prints[c][static_cast<size_t>(tried[static_cast<size_t>(j)])];
        same = f.bw == g.bw && f.bh == g.bh && f.runs == g.runs;
      }
      if (!same) tried[static_cast<size_t>(distinct++)] = r;
    }
    if (distinct == 1) scan(tried[0]);
    else tbb::parallel_for(0, distinct, [&](int j) { scan(tried[static_cast<size_t>(j)]); });
    bool found = false;
    Placement best;
    for (int j = 0; j < distinct; ++j) {
      const int r = tried[static_cast<size_t>(j)];
      if (!fits[static_cast<size_t>(r)]) continue;
      const Placement& f = fit[static_cast<size_t>(r)];
      const int key = f.y + key_offset(r), best_key = found ? best.y + key_offset(best.orientation) : 0;
      if (!found || key < best_key || (key == best_key && f.x < best.x)) {
        best = f;
        found = true;
      }
    }
    if (!found) {
      result.fill = static_cast<double>(need - remaining) / static_cast<double>(need);
      return result;
    }
    where[c] = best;
    const Footprint& placed = prints[c][static_cast<size_t>(best.orientation)];
    touched += placed.texels;
    remaining -= least[c];
    bottom = std::max(bottom, best.y + placed.bh);
    // The placed texels, as (x, y) in the atlas.
    std::vector<std::array<int, 2>> best_texels;
    best_texels.reserve(placed.texels);
    for (const auto& run : placed.runs)
      for (int x = run[1]; x <= run[2]; ++x) best_texels.push_back({best.x + x, best.y + run[0]});
    int row0 = n, row1 = -1;  // the rows blocked in
    for (const auto& run : placed.runs) {
      // A run dilated by the padding: a box of rows and columns.
      const int ty = best.y + run[0], x0 = std::max(0, best.x + run[1] - pad), x1 = std::min(n - 1, best.x + run[2] + pad);
      for (int y = std::max(0, ty - pad); y <= std::min(n - 1, ty + pad); ++y) block_range(y, x0, x1);
      row0 = std::min(row0, std::max(0, ty - pad));
      row1 = std::max(row1, std::min(n - 1, ty + pad));
    }
    // Mip-safe levels (uv_pack.hpp): the chart's level-k texels dilated by m_k - 1 block
    // every level-0 texel inside them.
    for (int k = 1; k <= o.mip_safe; ++k) {
      const int b = 1 << k, reach = k == 1 ? 3 : 4, cn = n >> k;
      int cx0 = cn, cy0 = cn, cx1 = -1, cy1 = -1;
      for (const auto& t : best_texels) {
        const int cx = t[0] >> k, cy = t[1] >> k;
        cx0 = std::min(cx0, cx);
        cy0 = std::min(cy0, cy);
        cx1 = std::max(cx1, cx);
        cy1 = std::max(cy1, cy);
      }
      const int cw = cx1 - cx0 + 1;
      std::vector<uint8_t> coarse(static_cast<size_t>(cw) * static_cast<size_t>(cy1 - cy0 + 1), 0);
      for (const auto& t : best_texels)
        coarse[static_cast<size_t>((t[1] >> k) - cy0) * static_cast<size_t>(cw) + static_cast<size_t>((t[0] >> k) - cx0)] = 1;
      // Rows of the dilated coarse set, as column ranges per coarse row (a box dilation),
      // over the chart's dilated box only: its columns [dx0, dx1].
      const int dx0 = std::max(0, cx0 - reach), dx1 = std::min(cn - 1, cx1 + reach);
      std::vector<uint8_t> row(static_cast<size_t>(dx1 - dx0 + 1));
      for (int cy = std::max(0, cy0 - reach); cy <= std::min(cn - 1, cy1 + reach); ++cy) {
        std::fill(row.begin(), row.end(), uint8_t{0});
        bool any = false;
        for (int sy = std::max(cy0, cy - reach); sy <= std::min(cy1, cy + reach); ++sy)
          for (int sx = cx0; sx <= cx1; ++sx)
            if (coarse[static_cast<size_t>(sy - cy0) * static_cast<size_t>(cw) + static_cast<size_t>(sx - cx0)]) {
              for (int x = std::max(dx0, sx - reach); x <= std::min(dx1, sx + reach); ++x) row[static_cast<size_t>(x - dx0)] = 1;
              any = true;
            }
        if (!any) continue;
        for (int y = cy * b; y < (cy + 1) * b; ++y) {
          for (int cx = dx0; cx <= dx1; ++cx) {
            if (!row[static_cast<size_t>(cx - dx0)]) continue;
            int end = cx;  // a stretch of marked coarse columns, blocked in one range
            while (end < dx1 && row[static_cast<size_t>(end + 1 - dx0)]) ++end;
            block_range(y, cx * b, end * b + b - 1);
            cx = end;
          }
          row0 = std::min(row0, y);
          row1 = std::max(row1, y);
        }
      }
    }
    for (int row = row0; row <= row1; ++row) longest_free.set(row, free_rows.longest(row));
    if (remaining > free_inside) {
      result.fill = static_cast<double>(need - remaining + free_inside) / static_cast<double>(need);
      return result;
    }
  }
  result.ok = true;
  result.fill = static_cast<double>(bottom - margin) / static_cast<double>(n - 2 * margin);
  return result;
}

}  // namespace

UvPackReport pack_uv_charts(Mesh& mesh, const UvPackOptions& o) {
  UvPackReport report;
  if (o.mip_safe > 14 || (o.mip_safe >= 0 && o.size % (1 << o.mip_safe) != 0))
    throw std::invalid_argument("--mip-safe " + std::to_string(o.mip_safe) + " needs an atlas size that is a multiple of 2^" + std::to_string(o.mip_safe));
  {
    // Each chart keeps at least one texel and `pad` free texels to the next, inside a border
    // margin: more charts than fit that way cannot be packed at any scale.
    const int pad = chart_gap(o), margin = atlas_border_margin(o);
    const long long side = o.size - 2LL * margin;
    if (side <= 0)
      throw std::invalid_argument("padding " + std::to_string(o.padding) + " leaves no texel inside a " + std::to_string(o.size) + "-texel atlas");
    const long long per_row = (side + pad) / (pad + 1);
    size_t charts = 0;
    uv_charts(mesh, &charts);
    if (static_cast<long long>(charts) > per_row * per_row)
      throw std::invalid_argument(std::to_string(charts) + " charts with padding " + std::to_string(pad) + " cannot fit a " + std::to_string(o.size) +
                                  "^2 atlas at any scale (at most " + std::to_string(per_row * per_row) + ")");
  }
  for (double f : o.chart_scale)
    if (!(f > 0) || !std::isfinite(f)) throw std::invalid_argument("chart scales must be positive and finite");
  size_t count = 0;
  const std::vector<int> chart_of = uv_charts(mesh, &count);
  std::vector<Chart> charts(count);
  for (auto f : mesh.faces()) {
    Chart& c = charts[static_cast<size_t>(chart_of[static_cast<size_t>(f.idx())])];
    c.faces.push_back(f.idx());
    std::array<double, 6> t{};
    const auto hs = face_halfedges(mesh, f);
    for (size_t k = 0; k < 3; ++k) {
      const Vec2f uv = mesh.texcoord2D(hs[k]);
      t[2 * k] = uv[0];
      t[2 * k + 1] = -static_cast<double>(uv[1]);
    }
    c.tris.push_back(t);
  }
  double total_area = 0;
  // A chart's minimum-area orientation replaces the input's when its box is at least 10 % smaller
  // (the input's then rarely wins: on 782 unwrapped charts keeping both cost 1.7x the CPU time for
  // 60.0 % utilisation against 61.2 %), and is a second frame when it is 1-10 % smaller; an
  // axis-aligned rectangle keeps its one frame.
  tbb::parallel_for(size_t{0}, count, [&](size_t ci) {
    Chart& c = charts[ci];
    c.frames[0] = frame_of(c, 1, 0);
    if (!o.rotate || !o.min_area_orientation) return;
    const Frame m = min_area_frame(c);
    if (m.w * m.h < 0.9 * c.frames[0].w * c.frames[0].h) {
      c.frames[0] = m;
    } else if (m.w * m.h < 0.99 * c.frames[0].w * c.frames[0].h) {
      c.frames[1] = m;
      c.frame_count = 2;
    }
  });
  for (Chart& c : charts) {
    for (const auto& t : c.tris) c.area += 0.5 * std::abs((t[2] - t[0]) * (t[5] - t[1]) - (t[3] - t[1]) * (t[4] - t[0]));
    const size_t ci = static_cast<size_t>(&c - charts.data());
    if (ci < o.chart_scale.size()) c.factor = o.chart_scale[ci];
    total_area += c.area * c.factor * c.factor;
  }
  report.charts = count;
  const int turns = !o.rotate ? 1 : o.quality == PackQuality::fast ? 2 : 4;
  const double tolerance = o.quality == PackQuality::fast ? 1.04 : o.quality == PackQuality::best ? 1.0025 : 1.01;
  // Chart orders, each largest first (stable: ties keep the index order, deterministic): by box
  // area (the first search's), longest side, UV area, box perimeter.
  auto sorted_by = [&](auto key) {
    std::vector<size_t> order(count);
    for (size_t i = 0; i < count; ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return key(charts[a]) > key(charts[b]); });
    return order;
  };
  // A chart's box: that of its last (smallest) frame.
  auto box = [](const Chart& c) { return c.frames[static_cast<size_t>(c.frame_count - 1)]; };
  std::vector<std::vector<size_t>> orders;
  orders.push_back(sorted_by([&](const Chart& c) { return box(c).w * box(c).h * c.factor * c.factor; }));
  if (o.quality != PackQuality::fast) {
    orders.push_back(sorted_by([&](const Chart& c) { return std::max(box(c).w, box(c).h) * c.factor; }));
    orders.push_back(sorted_by([&](const Chart& c) { return c.area * c.factor * c.factor; }));
  }
  if (o.quality == PackQuality::best) orders.push_back(sorted_by([&](const Chart& c) { return (box(c).w + box(c).h) * c.factor; }));
  for (size_t i = orders.size(); i-- > 1;)  // an order that repeats an earlier one adds nothing (one chart: all do)
    if (std::find(orders.begin(), orders.begin() + static_cast<std::ptrdiff_t>(i), orders[i]) != orders.begin() + static_cast<std::ptrdiff_t>(i))
      orders.erase(orders.begin() + static_cast<std::ptrdiff_t>(i));

  // The scale, first with the first order placed by top row. The charts' UV area would fill
  // the atlas at s_area. Successes aim well and failures do not (below), so the search starts
  // where most inputs pack: at 0.7 s_area the charts cover 49 % of the atlas (measured
  // utilisations: 41-99 %; on seven benchmark inputs 0.7 took 34 packings in all, 0.5, 0.6 and
  // 0.8 35-36). A success whose charts reach a share u of the rows aims the next attempt at
  // 1 / sqrt(u) times its scale (as if the packing kept its density: close when u is well below
  // 1). A failure says little about how far off it was (the last, smallest chart fails as often
  // as a large one), so before a success the scale steps down 5 % (or to sqrt(f) times, at most
  // a halving, when the charts placed held only a share f < 0.9 of the texels), a success before
  // any failure steps up by at least the tolerance and at most a doubling, and once a success
  // and a failure bracket the answer it is bisected. A success inside the bracket aims at its
  // own estimate but kept in the middle half of the bracket (log scale), which so shrinks by at
  // least a quarter; the search stops when the bracket is within the tolerance.
  const double n = o.size;
  double ok = 0, fail = 0;
  double fit_bound = 0;  // one chart: the largest scale its box fits at (no larger one packs)
  Attempt best;
  {
    double s = 0.7 * (total_area > 0 ? std::sqrt(n * n / total_area) : n);
    if (count == 1 && total_area > 0) {
      // One chart: the largest scale at which its box fits inside the border margin (the
      // square atlas makes it the box's longer side, in any quarter turn), with kInset free
      // at both ends: the chart spans [margin + kInset, n - margin - kInset], so the float
      // rounding of the written UVs (~1e-7 n texels) cannot carry it into a margin texel.
      // The search below would stop up to its tolerance short of it; from here it succeeds
      // at once.
      double side = std::numeric_limits<double>::infinity();
      for (int f = 0; f < charts[0].frame_count; ++f)
        side = std::min(side, std::max(charts[0].frames[static_cast<size_t>(f)].w, charts[0].frames[static_cast<size_t>(f)].h));
      const double room = n - 2.0 * atlas_border_margin(o) - 2.0 * kInset;
      if (side > 0 && room > 0) s = room * (1 - 1e-9) / (side * charts[0].factor), fit_bound = s;
    }
    for (int k = 0; k < 60; ++k) {
      ++report.attempts;
      Attempt a = place_all(charts, footprints_at(charts, s, turns, rounding_margin(n)), orders[0], false, o, turns);
      const double aim = a.ok ? s / std::sqrt(std::max(a.fill, 1e-9)) : s * std::clamp(std::sqrt(a.fill), 0.5, 0.95);
      if (a.ok) {
        ok = s;
        best = std::move(a);
        if (total_area == 0) break;  // no chart has UV area: any scale packs
        if (s == fit_bound) break;   // one chart at the largest scale its box allows: done
      } else {
        fail = s;
      }
      if (ok > 0 && fail > 0) {
        if (fail / ok <= tolerance) break;
        const double quarter = std::pow(fail / ok, 0.25);
        s = ok == s ? std::clamp(aim, ok * quarter, fail / quarter) : std::sqrt(ok * fail);
      } else {
        s = ok > 0 ? std::clamp(aim, s * tolerance, s * 2) : aim;
      }
    }
  }
  if (!best.ok && count > 0) throw std::invalid_argument("the charts do not fit the atlas at any scale tried");

  // Then above it: the greedy packing is not monotone in the scale, and another order or
  // placement rule often packs where the first failed. Every variant (order x top row or
  // bottom row) is tried at a scale above the best success, the one that last succeeded
  // first; a success raises the best scale and the next target by the same step, a round in
  // which all fail halves the step (log scale) down to a quarter of the tolerance. The
  // packings this may take are bounded by the preset and the chart count (a packing costs
  // about its charts), so that many charts cost no more than before.
  const size_t variants = 2 * orders.size();
  const size_t per_chart = o.quality == PackQuality::best ? 24000 : o.quality == PackQuality::balanced ? 2400 : 0;
  size_t budget = std::min(o.quality == PackQuality::best ? size_t{64} : size_t{18}, per_chart / std::max<size_t>(count, 1));
  if (fail > 0 && ok > 0 && variants > 1 && budget >= variants) {
    double step = fail / ok;
    const double finest = std::pow(tolerance, 0.25);
    size_t first = 0;
    while (budget > 0) {
      const double target = ok * step;
      const Footprints prints = footprints_at(charts, target, turns, rounding_margin(n));
      bool rose = false;
      for (size_t j = 0; j < variants && budget > 0; ++j) {
        const size_t v = (first + j) % variants;
        --budget;
        ++report.attempts;
        Attempt a = place_all(charts, prints, orders[v / 2], v % 2 == 1, o, turns);
        if (a.ok) {
          ok = target;
          best = std::move(a);
          first = v;
          rose = true;
          break;
        }
      }
      if (!rose) {
        if (step <= finest) break;
        step = std::sqrt(step);
      }
    }
  }
  const double lo = ok;
  report.scale = lo;
  report.texel_coverage = static_cast<double>(best.touched) / (n * n);
  report.utilization = total_area * lo * lo / (n * n);
  // Move the UVs: q' = (turn(q) * s + offset) / size, v = 1 - q'y; a chart without UV area to
  // the centre of its one texel (footprint()).
  for (size_t ci = 0; ci < count; ++ci) {
    const Chart& c = charts[ci];
    const Placement& p = best.where[ci];
    for (int f : c.faces)
      for (auto h : face_halfedges(mesh, FaceHandle(f))) {
        const Vec2f uv = mesh.texcoord2D(h);
        const auto q = turn(c, uv[0], -static_cast<double>(uv[1]), p.orientation);
        const double scale = c.area == 0 ? 0 : lo * c.factor, inset = c.area == 0 ? 0.5 : kInset;
        const double x = (q[0] * scale + inset + p.x) / n, y = (q[1] * scale + inset + p.y) / n;
        mesh.set_texcoord2D(h, Vec2f(static_cast<float>(x), static_cast<float>(1.0 - y)));
      }
  }
  return report;
}

}  // namespace meso
