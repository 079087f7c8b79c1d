#include "meso/uvpack/uv_pack.hpp"

#include "meso/core/uv_texels.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace meso {

namespace {

// A chart in "q" coordinates, q = (u, 1 - v): x right and y down like texel rows, so that
// q * size is a pixel position (image.hpp).
struct Chart {
  std::vector<int> faces;
  std::vector<std::array<double, 6>> tris;  // q of the three corners, face_halfedges() order
  double x0 = 0, y0 = 0, w = 0, h = 0;      // bounding box
  double area = 0;
};

// Corner q rotated by r quarter turns inside the chart's box, measured from its new corner.
std::array<double, 2> turn(const Chart& c, double qx, double qy, int r) {
  const double dx = qx - c.x0, dy = qy - c.y0;
  switch (r & 3) {
    case 1: return {c.h - dy, dx};
    case 2: return {c.w - dx, c.h - dy};
    case 3: return {dy, c.w - dx};
    default: return {dx, dy};
  }
}

// Charts sit 1/64 texel inside their first texel: a corner exactly on a texel edge could
// otherwise touch the neighbouring texel once the new UVs are rounded to float.
constexpr double kInset = 1.0 / 64;

// The texels a chart touches at scale s and orientation r, relative to its box's corner
// placed at kInset past texel (0, 0)'s corner: conservative, as uv_check rasterises.
std::vector<std::array<int, 2>> footprint(const Chart& c, double s, int r, int& bw, int& bh) {
  const double w = (r & 1) ? c.h : c.w, h = (r & 1) ? c.w : c.h;
  bw = static_cast<int>(std::floor(w * s + kInset)) + 1;
  bh = static_cast<int>(std::floor(h * s + kInset)) + 1;
  std::vector<uint8_t> mark(static_cast<size_t>(bw) * static_cast<size_t>(bh), 0);
  for (const auto& t : c.tris) {
    UvTriangle tri{};
    for (int k = 0; k < 3; ++k) {
      const auto p = turn(c, t[static_cast<size_t>(2 * k)], t[static_cast<size_t>(2 * k + 1)], r);
      tri.px[k] = p[0] * s + kInset;
      tri.py[k] = p[1] * s + kInset;
    }
    const double area = (tri.px[1] - tri.px[0]) * (tri.py[2] - tri.py[0]) - (tri.py[1] - tri.py[0]) * (tri.px[2] - tri.px[0]);
    if (area == 0) continue;
    for_each_touched_texel(tri, bw, bh, [&](int x, int y) { mark[static_cast<size_t>(y) * static_cast<size_t>(bw) + static_cast<size_t>(x)] = 1; });
  }
  std::vector<std::array<int, 2>> out;
  for (int y = 0; y < bh; ++y)
    for (int x = 0; x < bw; ++x)
      if (mark[static_cast<size_t>(y) * static_cast<size_t>(bw) + static_cast<size_t>(x)]) out.push_back({x, y});
  if (out.empty()) out.push_back({0, 0});  // a chart without UV area keeps one texel
  return out;
}

struct Placement {
  int orientation = 0, x = 0, y = 0;
};

// Greedy placement at scale s; false when some chart finds no room.
bool place_all(const std::vector<Chart>& charts, const std::vector<size_t>& order, double s, const UvPackOptions& o,
               std::vector<Placement>& where, size_t& touched) {
  const int n = o.size, pad = std::max(0, o.padding), margin = (pad + 1) / 2;
  // Texels within `pad` of a placed chart's texel (Chebyshev): a new chart's texels must
  // avoid them. next_free[row * n + col]: the first unblocked column >= col in the row (n
  // if none), so a scan jumps over blocked runs instead of stepping through them.
  std::vector<uint8_t> blocked(static_cast<size_t>(n) * static_cast<size_t>(n), 0);
  std::vector<int> next_free(static_cast<size_t>(n) * static_cast<size_t>(n));
  // next_blocked[row * n + col]: the first blocked column >= col (n if none), so a run of a
  // footprint row is tested at once: [c0, c1] is free when next_blocked[c0] > c1.
  std::vector<int> next_blocked(static_cast<size_t>(n) * static_cast<size_t>(n));
  auto refresh_row = [&](int row) {
    int free_col = n, blocked_col = n;
    for (int col = n - 1; col >= 0; --col) {
      const size_t k = static_cast<size_t>(row) * static_cast<size_t>(n) + static_cast<size_t>(col);
      if (blocked[k]) blocked_col = col;
      else free_col = col;
      next_free[k] = free_col;
      next_blocked[k] = blocked_col;
    }
  };
  for (int row = 0; row < n; ++row) refresh_row(row);
  where.assign(charts.size(), Placement{});
  touched = 0;
  for (size_t c : order) {
    bool found = false;
    Placement best;
    std::vector<std::array<int, 2>> best_texels;
    for (int r = 0; r < (o.rotate ? 4 : 1); ++r) {
      int bw = 0, bh = 0;
      const auto texels = footprint(charts[c], s, r, bw, bh);
      // The footprint as runs of consecutive texels per row (row, first, last): texels come
      // row by row, left to right.
      std::vector<std::array<int, 3>> runs;
      for (const auto& t : texels) {
        if (!runs.empty() && runs.back()[0] == t[1] && runs.back()[2] + 1 == t[0]) runs.back()[2] = t[0];
        else runs.push_back({t[1], t[0], t[0]});
      }
      // This orientation's first fit in scan order (lowest row, then leftmost), searched no
      // lower than the best so far.
      bool here = false;
      for (int y = margin; y + bh <= n - margin && !here && !(found && y > best.y); ++y) {
        int x = margin;
        while (x + bw <= n - margin) {
          int jump = -1;
          for (const auto& run : runs) {
            const size_t row = static_cast<size_t>(y + run[0]) * static_cast<size_t>(n);
            const int hit = next_blocked[row + static_cast<size_t>(x + run[1])];
            if (hit <= x + run[2]) {
              // The run must start past the blocked stretch that begins at `hit`.
              jump = next_free[row + static_cast<size_t>(hit)] - run[1];
              break;
            }
          }
          if (jump < 0) {
            here = true;
            if (!found || y < best.y || (y == best.y && x < best.x)) {
              best = {r, x, y};
              best_texels = texels;
              found = true;
            }
            break;
          }
          x = std::max(x + 1, jump);
        }
      }
    }
    if (!found) return false;
    where[c] = best;
    touched += best_texels.size();
    int row0 = n, row1 = -1;
    for (const auto& t : best_texels) {
      const int tx = best.x + t[0], ty = best.y + t[1];
      for (int y = std::max(0, ty - pad); y <= std::min(n - 1, ty + pad); ++y) {
        for (int x = std::max(0, tx - pad); x <= std::min(n - 1, tx + pad); ++x) blocked[static_cast<size_t>(y) * static_cast<size_t>(n) + static_cast<size_t>(x)] = 1;
        row0 = std::min(row0, y);
        row1 = std::max(row1, y);
      }
    }
    for (int row = row0; row <= row1; ++row) refresh_row(row);
  }
  return true;
}

}  // namespace

UvPackReport pack_uv_charts(Mesh& mesh, const UvPackOptions& o) {
  UvPackReport report;
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
      t[2 * k + 1] = 1.0 - static_cast<double>(uv[1]);
    }
    c.tris.push_back(t);
  }
  double total_area = 0;
  for (Chart& c : charts) {
    double x0 = std::numeric_limits<double>::infinity(), y0 = x0, x1 = -x0, y1 = -x0;
    for (const auto& t : c.tris)
      for (int k = 0; k < 3; ++k) {
        x0 = std::min(x0, t[static_cast<size_t>(2 * k)]);
        x1 = std::max(x1, t[static_cast<size_t>(2 * k)]);
        y0 = std::min(y0, t[static_cast<size_t>(2 * k + 1)]);
        y1 = std::max(y1, t[static_cast<size_t>(2 * k + 1)]);
      }
    c.x0 = x0;
    c.y0 = y0;
    c.w = x1 - x0;
    c.h = y1 - y0;
    for (const auto& t : c.tris) c.area += 0.5 * std::abs((t[2] - t[0]) * (t[5] - t[1]) - (t[3] - t[1]) * (t[4] - t[0]));
    total_area += c.area;
  }
  report.charts = count;
  // Largest first (by box area, then index: deterministic).
  std::vector<size_t> order(count);
  for (size_t i = 0; i < count; ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return charts[a].w * charts[a].h > charts[b].w * charts[b].h; });

  // The scale: start where the charts' area would fill the atlas, halve until a packing
  // succeeds, then bisect between the last failure and success to within 1 %.
  const double n = o.size;
  double hi = total_area > 0 ? std::sqrt(n * n / total_area) : n;
  double lo = 0;
  std::vector<Placement> where, best;
  size_t touched = 0, best_touched = 0;
  for (int k = 0; k < 40; ++k) {
    ++report.attempts;
    if (place_all(charts, order, hi, o, where, touched)) {
      lo = hi;
      best = where;
      best_touched = touched;
      break;
    }
    hi *= 0.5;
  }
  if (best.empty() && count > 0) throw std::invalid_argument("the charts do not fit the atlas at any scale tried");
  double fail = lo * 2;
  // Bisect in [lo, fail): lo packs, fail did not (or was not tried beyond the start).
  while (fail > 0 && fail / lo > 1.01 && report.attempts < 60) {
    const double mid = std::sqrt(lo * fail);
    ++report.attempts;
    if (place_all(charts, order, mid, o, where, touched)) {
      lo = mid;
      best = where;
      best_touched = touched;
    } else {
      fail = mid;
    }
  }
  report.scale = lo;
  report.utilization = static_cast<double>(best_touched) / (n * n);
  // Move the UVs: q' = (turn(q) * s + offset) / size, v = 1 - q'y.
  for (size_t ci = 0; ci < count; ++ci) {
    const Chart& c = charts[ci];
    const Placement& p = best[ci];
    for (int f : c.faces)
      for (auto h : face_halfedges(mesh, FaceHandle(f))) {
        const Vec2f uv = mesh.texcoord2D(h);
        const auto q = turn(c, uv[0], 1.0 - static_cast<double>(uv[1]), p.orientation);
        const double x = (q[0] * lo + kInset + p.x) / n, y = (q[1] * lo + kInset + p.y) / n;
        mesh.set_texcoord2D(h, Vec2f(static_cast<float>(x), static_cast<float>(1.0 - y)));
      }
  }
  return report;
}

}  // namespace meso
