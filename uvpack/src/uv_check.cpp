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
#include <unordered_map>
#include <vector>

namespace meso {

namespace {

// The charts after the first that touch a texel (sorted, distinct), for the texels several
// charts touch (already reported as shared).
using MoreCharts = std::unordered_map<size_t, std::vector<int>>;

// The mip-safety check of uv_check.hpp on the touched texels' charts (`touch`: the first
// chart touching each texel, -1 for none; `more`: the others). Every chart touching a texel
// reads around it, and a texel several charts touch holds all of their values (the bake
// writes one of them, which one depends on the face order), so the verdict does not depend
// on the faces' order.
void check_mip_levels(const std::vector<int>& touch, const MoreCharts& more, int size, int levels, UvCheckReport& r) {
  if (levels > 14 || size % (1 << levels) != 0)
    throw std::invalid_argument("mip_safe " + std::to_string(levels) + " needs a size that is a multiple of 2^" + std::to_string(levels));
  const size_t n = static_cast<size_t>(size) * static_cast<size_t>(size);
  std::vector<uint8_t> written(n);
  for (size_t i = 0; i < n; ++i) written[i] = touch[i] >= 0;
  const std::vector<int32_t> source = dilation_sources(written, size, size, -1);
  std::vector<int> owner(n, -1);  // the (first) chart whose value each texel holds after dilation
  for (size_t i = 0; i < n; ++i)
    if (source[i] >= 0) owner[i] = touch[static_cast<size_t>(source[i])];
  // The other charts of the texel whose value texel i holds (touching texel: itself).
  auto more_of = [&](const std::vector<int>& label, size_t i) -> const std::vector<int>* {
    const size_t from = &label == &owner ? static_cast<size_t>(source[i]) : i;
    if (label[i] < 0 || more.empty()) return nullptr;
    const auto it = more.find(from);
    return it == more.end() ? nullptr : &it->second;
  };
  constexpr int kMixed = -2;
  std::map<std::tuple<int, int, int>, size_t> found;  // (level, chart, reads) -> texels
  r.mip_safe_levels = levels;
  for (int k = 0; k <= levels; ++k) {
    const int b = 1 << k, cn = size >> k;
    // Per level-k texel: the one chart whose values it holds (kMixed: several, -1: none), and
    // the one chart touching it (kMixed: several, -1: none).
    std::vector<int> holds(static_cast<size_t>(cn) * static_cast<size_t>(cn)), touched(holds.size());
    for (int cy = 0; cy < cn; ++cy)
      for (int cx = 0; cx < cn; ++cx) {
        int h = owner[static_cast<size_t>(cy * b) * static_cast<size_t>(size) + static_cast<size_t>(cx * b)], t = -1;
        for (int y = cy * b; y < (cy + 1) * b; ++y)
          for (int x = cx * b; x < (cx + 1) * b; ++x) {
            const size_t i = static_cast<size_t>(y) * static_cast<size_t>(size) + static_cast<size_t>(x);
            if (owner[i] != h || more_of(owner, i)) h = kMixed;
            if (touch[i] >= 0) t = (t == -1 || t == touch[i]) && !more_of(touch, i) ? touch[i] : kMixed;
          }
        holds[static_cast<size_t>(cy) * static_cast<size_t>(cn) + static_cast<size_t>(cx)] = h;
        touched[static_cast<size_t>(cy) * static_cast<size_t>(cn) + static_cast<size_t>(cx)] = t;
      }
    // The distinct charts (>= 0, increasing) that `label` gives the level-0 texels of level-k
    // texel (cx, cy): with owner, the charts whose values it holds; with touch, those touching it.
    auto charts_in = [&](const std::vector<int>& label, int cx, int cy) {
      std::vector<int> cs;
      for (int y = cy * b; y < (cy + 1) * b; ++y)
        for (int x = cx * b; x < (cx + 1) * b; ++x) {
          const size_t i = static_cast<size_t>(y) * static_cast<size_t>(size) + static_cast<size_t>(x);
          if (label[i] < 0) continue;
          cs.push_back(label[i]);
          if (const auto* others = more_of(label, i)) cs.insert(cs.end(), others->begin(), others->end());
        }
      std::sort(cs.begin(), cs.end());
      cs.erase(std::unique(cs.begin(), cs.end()), cs.end());
      return cs;
    };
    bool clean = true;
    // Each level-k texel a reader reaches counts once per (chart, reads), however many
    // touched texels reach it: collect (texel, chart, reads) first.
    std::vector<std::tuple<size_t, int, int>> hits;
    for (int cy = 0; cy < cn; ++cy)
      for (int cx = 0; cx < cn; ++cx) {
        const int t = touched[static_cast<size_t>(cy) * static_cast<size_t>(cn) + static_cast<size_t>(cx)];
        if (t == -1) continue;
        // Several charts touching it: each of them reads its neighbourhood.
        const std::vector<int> readers = t == kMixed ? charts_in(touch, cx, cy) : std::vector<int>{t};
        for (int ny = std::max(0, cy - 1); ny <= std::min(cn - 1, cy + 1); ++ny)
          for (int nx = std::max(0, cx - 1); nx <= std::min(cn - 1, cx + 1); ++nx) {
            const size_t ni = static_cast<size_t>(ny) * static_cast<size_t>(cn) + static_cast<size_t>(nx);
            const int h = holds[ni];
            for (int reader : readers) {
              if (h == reader) continue;
              for (int other : h == kMixed ? charts_in(owner, nx, ny) : std::vector<int>{h})
                if (other >= 0 && other != reader) hits.emplace_back(ni, reader, other);
            }
          }
      }
    std::sort(hits.begin(), hits.end());
    hits.erase(std::unique(hits.begin(), hits.end()), hits.end());
    for (const auto& [texel, chart, reads] : hits) {
      ++found[{k, chart, reads}];
      clean = false;
    }
    if (!clean && r.mip_safe_levels == levels) r.mip_safe_levels = k - 1;
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
      continue;
    }
    const int c = chart[static_cast<size_t>(f.idx())];
    for_each_touched(f, [&](size_t i) {
      if (first_chart[i] < 0) {
        first_chart[i] = c;
      } else if (first_chart[i] != c) {
        shared[i] = 1;
        if (o.mip_safe >= 0) more_charts[i].push_back(c);
      }
    });
  }
  for (auto& [texel, charts] : more_charts) {
    std::sort(charts.begin(), charts.end());
    charts.erase(std::unique(charts.begin(), charts.end()), charts.end());
  }
  for (auto f : mesh.faces()) {
    if (uv_double_area(mesh, f) == 0.0) continue;
    bool shares = false;
    for_each_touched(f, [&](size_t i) { shares |= shared[i] != 0; });
    if (shares) r.shared_texel_faces.push_back(f.idx());
  }

  // Exact overlaps and padding.
  UvOverlapReport exact = find_uv_overlaps(mesh, chart, o.size, o.padding);
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
  if (o.mip_safe >= 0) check_mip_levels(first_chart, more_charts, o.size, o.mip_safe, r);
  return r;
}

}  // namespace meso
