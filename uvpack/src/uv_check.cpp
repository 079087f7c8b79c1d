#include "meso/uvpack/uv_check.hpp"

#include "meso/core/dilation_sources.hpp"
#include "meso/core/uv_texels.hpp"

#include <algorithm>
#include <utility>
#include <cmath>
#include <map>
#include <numeric>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

namespace meso {

namespace {

// The charts touching each texel after the first (which `first_chart` holds): a second one
// per texel, and the rare third and further ones apart (sorted, distinct). A flat array, not a
// map of lists: mirrored halves stacked on one UV island make every texel of it shared.
struct MoreCharts {
  std::vector<int> second;                     // -1: none (empty until a texel is shared)
  std::map<size_t, std::vector<int>> further;  // a third chart and more
  void add(size_t n, size_t i, int c) {
    if (second.empty()) second.assign(n, -1);
    if (second[i] < 0 || second[i] == c) {
      second[i] = c;
      return;
    }
    auto& list = further[i];
    if (std::find(list.begin(), list.end(), c) == list.end()) list.insert(std::upper_bound(list.begin(), list.end(), c), c);
  }
  template <class Fn>
  void for_each(size_t i, Fn&& fn) const {
    if (second.empty() || second[i] < 0) return;
    fn(second[i]);
    const auto it = further.find(i);
    if (it != further.end())
      for (int c : it->second) fn(c);
  }
};

// A few distinct charts (a texel's neighbourhood rarely holds more than two or three).
struct ChartSet {
  std::vector<int> items;
  void insert(int c) {
    if (c >= 0 && std::find(items.begin(), items.end(), c) == items.end()) items.push_back(c);
  }
};

// The mip-safety check of uv_check.hpp on the touched texels' charts (`touch`: the first
// chart touching each texel, -1 for none; `more`: the others). Every chart touching a texel
// reads around it, and a texel several charts touch holds all of their values (the bake
// writes one of them, which one depends on the face order), so the verdict does not depend
// on the faces' order. Per level, each level-k texel is visited once: the charts that read it
// (those touching a level-0 texel within one level-k texel of it) against the charts whose
// values it holds: two reads of every level-0 texel per level, ten more for the level-k
// texels near another chart, and no list of hits.
void check_mip_levels(const std::vector<int>& touch, const MoreCharts& more, int size, int levels, bool wrap, UvCheckReport& r) {
  if (levels > 14 || size % (1 << levels) != 0)
    throw std::invalid_argument("mip_safe " + std::to_string(levels) + " needs a size that is a multiple of 2^" + std::to_string(levels));
  const size_t n = static_cast<size_t>(size) * static_cast<size_t>(size);
  std::vector<uint8_t> written(n);
  for (size_t i = 0; i < n; ++i) written[i] = touch[i] >= 0;
  const std::vector<int32_t> source = dilation_sources(written, size, size, -1);
  std::map<std::tuple<int, int, int>, size_t> found;  // (level, chart, reads) -> texels
  r.mip_safe_levels = levels;
  ChartSet readers, holders;
  std::vector<std::tuple<int, int, size_t>> counts;  // (chart, reads, texels) of this level
  for (int k = 0; k <= levels; ++k) {
    const int b = 1 << k, cn = size >> k;
    // The charts of the level-0 texels of level-k texel (cx, cy): touching them (`set` gets
    // them as readers), or whose values they hold after the dilation.
    auto touching = [&](int cx, int cy, ChartSet& set) {
      for (int y = cy * b; y < (cy + 1) * b; ++y)
        for (int x = cx * b; x < (cx + 1) * b; ++x) {
          const size_t i = static_cast<size_t>(y) * static_cast<size_t>(size) + static_cast<size_t>(x);
          set.insert(touch[i]);
          more.for_each(i, [&](int c) { set.insert(c); });
        }
    };
    auto holding = [&](int cx, int cy, ChartSet& set) {
      for (int y = cy * b; y < (cy + 1) * b; ++y)
        for (int x = cx * b; x < (cx + 1) * b; ++x) {
          const int32_t from = source[static_cast<size_t>(y) * static_cast<size_t>(size) + static_cast<size_t>(x)];
          if (from < 0) continue;
          set.insert(touch[static_cast<size_t>(from)]);
          more.for_each(static_cast<size_t>(from), [&](int c) { set.insert(c); });
        }
    };
    // First per level-k texel one chart or none (-1) or several (kMixed), for what touches it
    // and what it holds: a texel holding one chart that only it, or nothing, touches around it
    // (most texels) needs no sets.
    constexpr int kMixed = -2;
    std::vector<int> touched(static_cast<size_t>(cn) * static_cast<size_t>(cn)), held(touched.size());
    for (int cy = 0; cy < cn; ++cy)
      for (int cx = 0; cx < cn; ++cx) {
        readers.items.clear();
        holders.items.clear();
        touching(cx, cy, readers);
        holding(cx, cy, holders);
        const size_t c = static_cast<size_t>(cy) * static_cast<size_t>(cn) + static_cast<size_t>(cx);
        touched[c] = readers.items.empty() ? -1 : readers.items.size() == 1 ? readers.items[0] : kMixed;
        held[c] = holders.items.empty() ? -1 : holders.items.size() == 1 ? holders.items[0] : kMixed;
      }
    // The level-k texels within one of (cx, cy) (its bilinear neighbours), cut at the
    // borders (clamp) or wrapped around them (repeat); a tiny level may list one twice.
    auto around = [&](int cx, int cy, auto&& fn) {
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          int nx = cx + dx, ny = cy + dy;
          if (wrap) {
            nx = (nx + cn) % cn;
            ny = (ny + cn) % cn;
          } else if (nx < 0 || ny < 0 || nx >= cn || ny >= cn) {
            continue;
          }
          fn(nx, ny);
        }
    };
    counts.clear();
    for (int cy = 0; cy < cn; ++cy)
      for (int cx = 0; cx < cn; ++cx) {
        const int h = held[static_cast<size_t>(cy) * static_cast<size_t>(cn) + static_cast<size_t>(cx)];
        if (h == -1) continue;
        bool clean = h != kMixed;
        around(cx, cy, [&](int nx, int ny) {
          const int t = touched[static_cast<size_t>(ny) * static_cast<size_t>(cn) + static_cast<size_t>(nx)];
          clean &= t == -1 || t == h;
        });
        if (clean) continue;
        holders.items.clear();
        holding(cx, cy, holders);
        readers.items.clear();
        around(cx, cy, [&](int nx, int ny) { touching(nx, ny, readers); });
        for (int reader : readers.items)
          for (int other : holders.items) {
            if (other == reader) continue;
            auto it = std::find_if(counts.begin(), counts.end(), [&](const auto& c) { return std::get<0>(c) == reader && std::get<1>(c) == other; });
            if (it == counts.end()) counts.emplace_back(reader, other, 1);
            else ++std::get<2>(*it);
          }
      }
    for (const auto& [chart, reads, texels] : counts) found[{k, chart, reads}] += texels;
    if (!counts.empty() && r.mip_safe_levels == levels) r.mip_safe_levels = k - 1;
  }
  for (const auto& [key, texels] : found) r.mip_violations.push_back({std::get<0>(key), std::get<1>(key), std::get<2>(key), texels});
}

}  // namespace

UvCheckReport check_uv_mapping(const Mesh& mesh, const UvCheckOptions& o) {
  UvCheckReport r;
  r.width = r.height = o.size;
  const std::vector<int> chart = uv_charts(mesh, &r.charts);
  const size_t n = static_cast<size_t>(o.size) * static_cast<size_t>(o.size);
  std::vector<int> first_chart(n, -1);
  std::vector<uint8_t> shared(n, 0);
  MoreCharts more_charts;

  auto for_each_touched = [&](FaceHandle f, auto&& fn) {
    for_each_touched_texel(uv_triangle_in_pixels(mesh, f, o.size, o.size), o.size, o.size, [&](int x, int y) {
      fn(static_cast<size_t>(y) * static_cast<size_t>(o.size) + static_cast<size_t>(x));
    });
  };

  std::vector<uint8_t> degenerate(mesh.n_faces(), 0);
  for (auto f : mesh.faces()) {
    bool outside = false;
    for (auto h : face_halfedges(mesh, f)) {
      const Vec2f t = mesh.texcoord2D(h);
      outside |= t[0] < 0 || t[0] > 1 || t[1] < 0 || t[1] > 1;
    }
    if (outside) r.outside_faces.push_back(f.idx());
    // Degenerate: zero UV area, or too thin for the rasteriser's double arithmetic at this
    // size (a sliver 1e-20 high in v had touched no texel without being reported).
    if (uv_double_area(mesh, f) == 0.0 || degenerate_in_pixels(uv_triangle_in_pixels(mesh, f, o.size, o.size))) {
      r.degenerate_faces.push_back(f.idx());
      degenerate[static_cast<size_t>(f.idx())] = 1;
      continue;
    }
    const int c = chart[static_cast<size_t>(f.idx())];
    for_each_touched(f, [&](size_t i) {
      if (first_chart[i] < 0) {
        first_chart[i] = c;
      } else if (first_chart[i] != c) {
        shared[i] = 1;
        if (o.mip_safe >= 0) more_charts.add(n, i, c);
      }
    });
  }
  for (auto f : mesh.faces()) {
    if (degenerate[static_cast<size_t>(f.idx())]) continue;
    bool shares = false;
    for_each_touched(f, [&](size_t i) { shares |= shared[i] != 0; });
    if (shares) r.shared_texel_faces.push_back(f.idx());
  }

  // Exact overlaps and padding.
  UvOverlapReport exact = find_uv_overlaps(mesh, chart, o.size, o.padding, o.wrap);
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
    surface_area[c] += face_area(mesh, f);
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
  r.texel_coverage = n ? static_cast<double>(r.texels_touched) / static_cast<double>(n) : 0.0;
  double all_uv_area = 0;
  for (double a : uv_area) all_uv_area += a;
  r.utilization = n ? all_uv_area / static_cast<double>(n) : 0.0;
  if (o.mip_safe >= 0) check_mip_levels(first_chart, more_charts, o.size, o.mip_safe, o.wrap, r);
  return r;
}

}  // namespace meso
