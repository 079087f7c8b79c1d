// The measuring instrument: every method against the reference renderer, with its texture
// fetches and its draw time.
#include "meso/preview/preview.hpp"

#include "meso/core/error.hpp"
#include "sampling.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

namespace meso {

namespace {

bool covered(const Image& img, int x, int y) { return img.at(x, y, 3) > 0.5f; }

// Signed UV difference in texels of an n-texel axis; on a tiling map the shorter way round.
double texel_difference(double a, double b, int n, bool wrap) {
  double d = a - b;
  if (wrap) d -= std::round(d);
  return d * n;
}

void measure(const Image& ref_uv, const Image& ref_lit, const Image& uv, const Image& lit, const Image& fetches,
             int map_w, int map_h, bool wrap, double tolerance, MethodComparison& r) {
  double squared = 0;
  for (int y = 0; y < uv.height; ++y)
    for (int x = 0; x < uv.width; ++x) {
      const bool a = covered(ref_uv, x, y), b = covered(uv, x, y);
      if (!a && !b) continue;
      ++r.pixels;
      bool wrong = a != b;
      if (!wrong) {
        const double du = texel_difference(uv.at(x, y, 0), ref_uv.at(x, y, 0), map_w, wrap);
        const double dv = texel_difference(uv.at(x, y, 1), ref_uv.at(x, y, 1), map_h, wrap);
        const double d = std::hypot(du, dv);
        wrong = !(d <= tolerance);  // NaN is wrong too
      }
      r.wrong_hits += wrong;
      const bool la = covered(ref_lit, x, y), lb = covered(lit, x, y);
      for (int c = 0; c < 3; ++c) {
        const double va = la ? ref_lit.at(x, y, c) : 0.0, vb = lb ? lit.at(x, y, c) : 0.0;
        squared += (va - vb) * (va - vb);
      }
    }
  // Nothing on the mesh in either image (the view misses it): nothing was measured, which is
  // NaN (null in the JSON) rather than a perfect 0.
  const double none = std::numeric_limits<double>::quiet_NaN();
  r.wrong_hit_fraction = r.pixels ? static_cast<double>(r.wrong_hits) / static_cast<double>(r.pixels) : none;
  r.rmse = r.pixels ? std::sqrt(squared / (3.0 * static_cast<double>(r.pixels))) : none;
  r.psnr = !(r.rmse >= 0) ? none : r.rmse > 0 ? 20.0 * std::log10(1.0 / r.rmse) : std::numeric_limits<double>::infinity();
  fetch_statistics(fetches, r);
}

std::string number(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

}  // namespace

void fetch_statistics(const Image& fetches, MethodComparison& r) {
  r.mean_iterations = r.p99_iterations = r.max_iterations = std::numeric_limits<double>::quiet_NaN();
  std::vector<float> counts;
  for (size_t i = 0; i < fetches.texel_count(); ++i)
    if (fetches.pixels[2 * i + 1] > 0.5f) counts.push_back(fetches.pixels[2 * i]);
  if (counts.empty()) return;
  std::sort(counts.begin(), counts.end());
  double sum = 0;
  for (float c : counts) sum += c;
  r.mean_iterations = sum / static_cast<double>(counts.size());
  const size_t rank = static_cast<size_t>(std::ceil(0.99 * static_cast<double>(counts.size())));
  r.p99_iterations = counts[std::max<size_t>(rank, 1) - 1];
  r.max_iterations = counts.back();
}

Comparison compare_methods(const Mesh& base, const PreviewMaps& maps, const CompareOptions& o) {
  std::vector<std::string> methods = o.methods;
  const auto& known = preview_methods();
  if (methods.empty()) {
    for (const auto& m : known) {
      if (has_stream(maps, m)) methods.push_back(m);
    }
  }
  // Usage errors before any work.
  for (const auto& m : methods) {
    if (std::find(known.begin(), known.end(), m) == known.end())
      throw UsageError("unknown preview method '" + m + "' (see --list-methods)");
    if (!has_stream(maps, m)) throw UsageError("method " + m + " needs the stream " + required_stream(m) + " (meso streams)");
  }
  // The GPU first: a size it cannot render is said before the reference's work (46 s at
  // 16385 x 16).
  HeadlessPreview gpu(base, maps);
  gpu.check_size(o.view.width, o.view.height);
  Comparison c;
  c.view = o.view;
  c.uv_tolerance_texels = o.uv_tolerance_texels;
  const ReferenceRenderer reference(base, maps, o.reference);
  c.reference_triangles = reference.triangle_count();
  c.reference_patches = reference.patch_count();
  c.reference_max_edge_texels = reference.max_edge_texels();
  c.reference_build_ms = reference.build_ms();
  PreviewOptions v = o.view;
  v.shade = PreviewShade::uv;
  const auto t0 = std::chrono::steady_clock::now();
  c.reference_uv = reference.render(v);
  c.reference_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  v.shade = PreviewShade::lit;
  c.reference_lit = reference.render(v);
  c.reference_view = o.view.shade == PreviewShade::uv    ? c.reference_uv
                     : o.view.shade == PreviewShade::lit ? c.reference_lit
                                                         : reference.render(o.view);

  // Each method's maps tile or clamp as its own stream says (method_tiles). The reference above
  // follows the methods without a stream, which tile when any stream does; a method whose
  // stream clamps among streams that tile is measured against a clamping reference, rendered
  // once from the maps without their streams.
  const bool wrap = maps_tile(maps);
  Image clamped_uv, clamped_lit;
  for (const auto& m : methods) {
    MethodComparison r;
    r.name = m;
    PreviewOptions mo = o.view;
    mo.shadows = PreviewShadows::none;  // the reference casts no shadow rays
    mo.method = m;
    mo.shade = PreviewShade::uv;
    const Image uv = gpu.render(mo, &r.fetches);
    mo.shade = PreviewShade::lit;
    const Image lit = gpu.render(mo);
    r.ms = gpu.time_draw(mo, o.repetitions);
    const bool tiles = method_tiles(maps, m);
    if (tiles != wrap && clamped_uv.empty()) {
      PreviewMaps plain;
      plain.displacement = maps.displacement;
      plain.normal_ts = maps.normal_ts;
      const ReferenceRenderer clamped(base, plain, o.reference);
      PreviewOptions rv = o.view;
      rv.shade = PreviewShade::uv;
      clamped_uv = clamped.render(rv);
      rv.shade = PreviewShade::lit;
      clamped_lit = clamped.render(rv);
    }
    measure(tiles == wrap ? c.reference_uv : clamped_uv, tiles == wrap ? c.reference_lit : clamped_lit, uv, lit, r.fetches,
            maps.displacement.width, maps.displacement.height, tiles, o.uv_tolerance_texels, r);
    c.methods.push_back(std::move(r));
  }
  return c;
}

std::string comparison_json(const Comparison& c) {
  std::string s = "{\"reference\": {\"triangles\": " + std::to_string(c.reference_triangles) +
                  ", \"patches\": " + std::to_string(c.reference_patches) +
                  ", \"max_edge_texels\": " + number(c.reference_max_edge_texels) + ", \"build_ms\": " + number(c.reference_build_ms) +
                  ", \"ms\": " + number(c.reference_ms) + "}";
  s += ", \"width\": " + std::to_string(c.view.width) + ", \"height\": " + std::to_string(c.view.height);
  s += ", \"view_angle\": " + number(c.view.camera.view_angle) + ", \"azimuth\": " + number(c.view.camera.azimuth);
  s += ", \"zoom\": " + number(c.view.camera.zoom) + ", \"iterations\": " + std::to_string(c.view.iterations);
  s += ", \"uv_tolerance_texels\": " + number(c.uv_tolerance_texels) + ", \"methods\": [";
  for (size_t i = 0; i < c.methods.size(); ++i) {
    const MethodComparison& m = c.methods[i];
    if (i) s += ", ";
    // Method names are preview_methods() entries: plain ASCII, nothing to escape.
    s += "{\"name\": \"" + m.name + "\", \"pixels\": " + std::to_string(m.pixels) +
         ", \"wrong_hit_fraction\": " + number(m.wrong_hit_fraction) + ", \"rmse\": " + number(m.rmse) +
         ", \"psnr\": " + number(m.psnr) + ", \"mean_iterations\": " + number(m.mean_iterations) +
         ", \"p99_iterations\": " + number(m.p99_iterations) + ", \"max_iterations\": " + number(m.max_iterations) +
         ", \"ms\": " + number(m.ms) + "}";
  }
  s += "]}";
  return s;
}

Image fetch_heatmap(const Image& fetches, double max_fetches) {
  // viridis at 0, 1/4, 1/2, 3/4, 1.
  static const std::array<std::array<double, 3>, 5> ramp{{{68, 1, 84}, {59, 82, 139}, {33, 145, 140}, {94, 201, 98}, {253, 231, 37}}};
  Image out(fetches.width, fetches.height, 4, 0.0f);
  const double top = std::log2(1.0 + std::max(max_fetches, 1.0));
  for (size_t i = 0; i < fetches.texel_count(); ++i) {
    if (fetches.channels > 1 && !(fetches.pixels[i * static_cast<size_t>(fetches.channels) + 1] > 0.5f)) continue;
    const double n = std::max(0.0, static_cast<double>(fetches.pixels[i * static_cast<size_t>(fetches.channels)]));
    const double t = std::clamp(std::log2(1.0 + n) / top, 0.0, 1.0) * 4.0;
    const size_t k = std::min<size_t>(static_cast<size_t>(t), 3);
    const double f = t - static_cast<double>(k);
    for (size_t ch = 0; ch < 3; ++ch) out.pixels[4 * i + ch] = static_cast<float>((ramp[k][ch] * (1 - f) + ramp[k + 1][ch] * f) / 255.0);
    out.pixels[4 * i + 3] = 1.0f;
  }
  out.metadata["fetches_max"] = static_cast<float>(max_fetches);
  out.metadata["fetches_scale"] = std::string("viridis over log2(1 + fetches) / log2(1 + fetches_max)");
  return out;
}

}  // namespace meso
