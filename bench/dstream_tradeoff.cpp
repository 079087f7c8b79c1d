// The compressed-displacement trade (issue 8): per level of `streams dstream`, the stream's
// size against the geometric error of the decoded mesh, on the bundled brick wall.
//
// For each base resolution and each level l (2^l segments per base edge) it reports the
// vertices, the stream's bytes (8 per vertex) against a raw float3 position buffer (12 per
// vertex) and an indexed mesh of the same tessellation (float3 positions + 32-bit indices),
// the quantisation bound of the 14-bit displacements and the largest decoding error met (object
// units), and the two-sided Hausdorff and RMS
// distance from the decoded level to the high mesh (meso::measure_surface_distance, the one
// measure meso uses everywhere), in % of the high mesh's bounding-box diagonal.
//
// Run: build/release/bench/dstream_tradeoff        (figures: docs/benchmarks.md)
#include "meso/bake/displacement_stream.hpp"
#include "meso/examples/brick_wall.hpp"
#include "meso/meshreduce/surface_distance.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

using namespace meso;

namespace {

// The decoded level as a triangle soup: the regular tessellation of every base triangle,
// triangles (i, j), (i + 1, j), (i, j + 1) and, inside, (i + 1, j), (i + 1, j + 1), (i, j + 1),
// in the stream's vertex order (i = 0..s, j = 0..s - i per triangle).
TriangleSoup decoded_soup(const Mesh& base, const EncodedStream& stream, int level) {
  TriangleSoup soup;
  soup.points = decode_displacement_level(base, stream, level);
  const int s = stream.segments[static_cast<size_t>(level)];
  const uint32_t per_triangle = static_cast<uint32_t>((s + 1) * (s + 2) / 2);
  // Index of (i, j) inside a triangle: rows i hold s - i + 1 vertices each.
  std::vector<uint32_t> row_start(static_cast<size_t>(s) + 2, 0);
  for (int i = 0; i <= s; ++i) row_start[static_cast<size_t>(i) + 1] = row_start[static_cast<size_t>(i)] + static_cast<uint32_t>(s - i + 1);
  auto at = [&](uint32_t t, int i, int j) { return t * per_triangle + row_start[static_cast<size_t>(i)] + static_cast<uint32_t>(j); };
  const uint32_t triangles = static_cast<uint32_t>(soup.points.size() / per_triangle);
  for (uint32_t t = 0; t < triangles; ++t)
    for (int i = 0; i < s; ++i)
      for (int j = 0; i + j < s; ++j) {
        soup.triangles.push_back({at(t, i, j), at(t, i + 1, j), at(t, i, j + 1)});
        if (i + j + 1 < s) soup.triangles.push_back({at(t, i + 1, j), at(t, i + 1, j + 1), at(t, i, j + 1)});
      }
  return soup;
}

}  // namespace

int main() {
  const BrickWallOptions wall;  // 262,144 triangles, bent around a cylinder of radius 3
  const Mesh high = make_brick_wall(wall);
  const TriangleSoup high_soup = triangle_soup(high);
  const double diagonal = bounding_box(high).diagonal();
  std::printf("| base triangles | level | segments | vertices | stream | raw float3 | indexed mesh | quantisation bound | decoded max error | Hausdorff %% | RMS %% | sample s |\n");
  std::printf("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const auto& [columns, rows] : {std::pair{32, 16}, std::pair{64, 32}}) {
    const Mesh base = make_brick_wall_base(wall, columns, rows);
    DisplacementStreamOptions o;
    o.levels = 7;
    const auto t0 = std::chrono::steady_clock::now();
    const DisplacementStream stream = sample_displacement_stream(base, high, o);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const EncodedStream encoded = encode_displacement_stream(stream);
    for (int l = 0; l < static_cast<int>(encoded.segments.size()); ++l) {
      const TriangleSoup soup = decoded_soup(base, encoded, l);
      const SurfaceDistance d = measure_surface_distance(soup, high_soup);
      const double vertices = static_cast<double>(soup.points.size());
      // An indexed mesh of the same surface shares the vertices the stream repeats along
      // edges: about one vertex per two triangles, each 12 bytes, plus 12 bytes of indices per triangle.
      const double triangles = static_cast<double>(soup.triangles.size());
      const double indexed = (triangles / 2 + static_cast<double>(base.n_vertices())) * 12 + triangles * 12;
      std::printf("| %zu | %d | %d | %.0f | %.1f KiB | %.1f KiB | %.1f KiB | %.2e | %.2e | %.4f | %.5f | %.2f |\n", base.n_faces(), l,
                  encoded.segments[static_cast<size_t>(l)], vertices, vertices * 8 / 1024, vertices * 12 / 1024, indexed / 1024,
                  (encoded.max_value - encoded.min_value) / 32766.0, encoded.max_error, 100.0 * d.hausdorff / diagonal,
                  100.0 * d.rms / diagonal, seconds);
    }
  }
  return 0;
}
