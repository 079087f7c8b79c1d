// The view-dependent displacement trade: error against size over PCA ranks and view
// resolutions, on height maps of different character. Prints a Markdown table and writes
// an SVG plot (RMS error against compressed size, log-log).
// Run: build/release/bench/vdm_tradeoff [out.svg]   (figures: docs/benchmarks.md)
#include "meso/examples/brick_wall.hpp"
#include "meso/streams/vdm.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <string>
#include <vector>

using namespace meso;

namespace {

HeightField map_of(const std::string& kind, int n) {
  Image img(n, n, 1);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      float v = 0;
      if (kind == "rocks") v = u(rng);  // uniform heights
      if (kind == "bricks") v = brick_wall_height(BrickWallOptions{}, 2.0f * x / n, 1.0f * y / n);  // top heavy
      if (kind == "mountains") {  // bottom heavy: sparse peaks
        const double a = std::sin(6.2831853 * 3 * x / n) * std::sin(6.2831853 * 2 * y / n);
        v = static_cast<float>(std::pow(std::max(0.0, a), 3.0));
      }
      img.at(x, y) = v;
    }
  return make_height_field(img, Border::wrap);
}

struct Point {
  std::string series;
  double bytes, rms;
};

}  // namespace

int main(int argc, char** argv) {
  const std::string svg = argc > 1 ? argv[1] : "vdm_tradeoff.svg";
  const int n = 64;
  std::vector<Point> points;
  std::printf("| map | view samples (theta x phi) | rank | raw | compressed | ratio | RMS error (u) | max error (u) | build s |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|\n");
  for (const std::string& kind : {std::string("rocks"), std::string("bricks"), std::string("mountains")}) {
    const HeightField f = map_of(kind, n);
    for (const auto& [theta, phi] : {std::pair{4, 8}, std::pair{8, 16}}) {
      VdmOptions o;
      o.theta = theta;
      o.phi = phi;
      o.relief = 0.05f;
      const auto t0 = std::chrono::steady_clock::now();
      const VdmTable table = build_vdm(f, o);
      const double build = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      const double raw = static_cast<double>(table.distance.size() * sizeof(float));
      for (int rank : {1, 2, 4, 8, 16, 32}) {
        if (rank > table.directions()) continue;
        const CompressedVdm c = compress_vdm(table, 0.0, rank);
        std::printf("| %s | %dx%d | %d | %.0f KiB | %.0f KiB | %.1f | %.5f | %.4f | %.2f |\n", kind.c_str(), theta, phi, c.rank, raw / 1024,
                    static_cast<double>(c.bytes()) / 1024, raw / static_cast<double>(c.bytes()), c.rms_error, c.max_error, build);
        points.push_back({kind + " " + std::to_string(theta) + "x" + std::to_string(phi), static_cast<double>(c.bytes()), std::max(c.rms_error, 1e-7)});
      }
    }
  }
  // The plot: log10(bytes) across, log10(RMS) up.
  double bx0 = 1e300, bx1 = -1e300, ry0 = 1e300, ry1 = -1e300;
  for (const Point& p : points) {
    bx0 = std::min(bx0, std::log10(p.bytes));
    bx1 = std::max(bx1, std::log10(p.bytes));
    ry0 = std::min(ry0, std::log10(p.rms));
    ry1 = std::max(ry1, std::log10(p.rms));
  }
  const double W = 640, H = 400, m = 60;
  auto X = [&](double b) { return m + (std::log10(b) - bx0) / std::max(1e-9, bx1 - bx0) * (W - 2 * m); };
  auto Y = [&](double r) { return H - m - (std::log10(r) - ry0) / std::max(1e-9, ry1 - ry0) * (H - 2 * m); };
  std::ofstream out(svg);
  out << "<svg xmlns='http://www.w3.org/2000/svg' width='" << W << "' height='" << H << "' font-family='sans-serif' font-size='11'>\n";
  out << "<rect width='100%' height='100%' fill='white'/>\n";
  out << "<text x='" << W / 2 << "' y='20' text-anchor='middle'>VDM: RMS error (units of u) against compressed size, 64x64 maps, ranks 1-32</text>\n";
  out << "<text x='" << W / 2 << "' y='" << H - 15 << "' text-anchor='middle'>compressed bytes (log, " << std::pow(10, bx0) << " .. " << std::pow(10, bx1) << ")</text>\n";
  out << "<text x='15' y='" << H / 2 << "' transform='rotate(-90 15 " << H / 2 << ")' text-anchor='middle'>RMS error (log, " << std::pow(10, ry0) << " .. " << std::pow(10, ry1) << ")</text>\n";
  const char* colours[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b"};
  int series = 0;
  for (size_t i = 0; i < points.size();) {
    size_t j = i;
    out << "<polyline fill='none' stroke='" << colours[series % 6] << "' stroke-width='2' points='";
    for (; j < points.size() && points[j].series == points[i].series; ++j) out << X(points[j].bytes) << "," << Y(points[j].rms) << " ";
    out << "'/>\n<text x='" << W - m + 5 - 120 << "' y='" << 40 + 14 * series << "' fill='" << colours[series % 6] << "'>" << points[i].series << "</text>\n";
    ++series;
    i = j;
  }
  out << "</svg>\n";
  std::printf("\nplot: %s\n", svg.c_str());
  return 0;
}
