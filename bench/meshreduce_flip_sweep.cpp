// Flipped faces of meso's reductions of the brick wall, over budgets and presets, counted as
// bench/meshreduce_peers counts them (bench::count_flipped: a face's normal against the
// input triangles nearest to samples spread over it).
//   meshreduce_flip_sweep [--amplitude A] [--roughness R] [--flat] COLUMNS ROWS FACES...
//   e.g. meshreduce_flip_sweep 64 32 100 200 400 600 1000
// The wall's relief (BrickWallOptions: amplitude in object units, roughness relative to it;
// --flat: no bend) defaults to the examples'. One line per (budget, preset); exit 1 when any
// face is flipped or degenerate.
#include "meshreduce_cgal_peer.hpp"
#include "meso/examples/brick_wall.hpp"
#include "meso/meshreduce/meshreduce.hpp"
#include "meso/meshreduce/surface_distance.hpp"

#include <cstdio>
#include <cstdlib>
#include <string>

int main(int argc, char** argv) {
  using namespace meso;
  BrickWallOptions wall;
  int i = 1;
  for (; i < argc && argv[i][0] == '-' && argv[i][1] == '-'; ++i) {
    const std::string k = argv[i];
    if (k == "--flat") {
      wall.bend_radius = 0;
    } else if ((k == "--amplitude" || k == "--roughness") && i + 1 < argc) {
      (k == "--amplitude" ? wall.amplitude : wall.roughness) = std::strtof(argv[++i], nullptr);
    } else {
      std::fprintf(stderr, "meshreduce_flip_sweep: unknown option %s\n", argv[i]);
      return 2;
    }
  }
  if (argc - i < 3) {
    std::fprintf(stderr, "usage: meshreduce_flip_sweep [--amplitude A] [--roughness R] [--flat] COLUMNS ROWS FACES...\n");
    return 2;
  }
  wall.columns = std::atoi(argv[i]);
  wall.rows = std::atoi(argv[i + 1]);
  if (wall.columns < 1 || wall.rows < 1) {
    std::fprintf(stderr, "meshreduce_flip_sweep: COLUMNS and ROWS must be positive\n");
    return 2;
  }
  const Mesh high = make_brick_wall(wall);
  const TriangleSoup input = triangle_soup(high);
  bool any = false;
  for (int a = i + 2; a < argc; ++a) {
    ReduceOptions o;
    o.target_faces = std::strtoul(argv[a], nullptr, 10);
    for (const auto& [name, quality] : {std::pair{"fast", ReduceQuality::fast}, std::pair{"balanced", ReduceQuality::balanced},
                                        std::pair{"best", ReduceQuality::best}}) {
      o.quality = quality;
      ReduceReport rep;
      const Mesh low = reduce_mesh(high, o, &rep);
      const bench::FlipCount c = bench::count_flipped(input, triangle_soup(low));
      std::printf("%d x %d wall, target %zu, %s: %zu faces, %zu flipped, %zu degenerate (%d passes, %zu reported, %.2f s)\n", wall.columns,
                  wall.rows, o.target_faces, name, static_cast<size_t>(low.n_faces()), c.flipped, c.degenerate, rep.passes, rep.flipped_faces,
                  rep.seconds);
      any = any || c.flipped > 0 || c.degenerate > 0;
    }
  }
  return any ? 1 : 0;
}
