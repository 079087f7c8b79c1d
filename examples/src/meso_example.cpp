// meso-example: writes the bundled example asset (a brick wall) so that nothing large is
// committed. Deterministic: the same options give byte-identical files.
#include "meso/core/error.hpp"
#include "meso/examples/brick_wall.hpp"
#include "meso/formats/atomic_file.hpp"
#include "meso/formats/mesh_io.hpp"

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace {
// CLI11's Range lets NaN through (it fails neither comparison).
const CLI::Validator kFinite(
    [](std::string& text) -> std::string {
      char* end = nullptr;
      const double v = std::strtod(text.c_str(), &end);
      return end != text.c_str() && *end == '\0' && std::isfinite(v) ? std::string() : "'" + text + "' is not a finite number";
    },
    "FINITE");
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Writes meso's example asset: a UV-mapped high-poly brick wall"};
  meso::BrickWallOptions o;
  std::string out;
  app.add_option("-o,--output", out, "Output mesh (.obj, .ply, .gltf, .glb)")->required();
  app.add_option("--columns", o.columns, "Grid quads along the wall")->check(CLI::Range(2, 8192));
  app.add_option("--rows", o.rows, "Grid quads up the wall")->check(CLI::Range(2, 8192));
  app.add_option("--bend-radius", o.bend_radius, "Radius of the cylinder the wall bends around; 0 = flat")
      ->check(CLI::Range(0.0f, 1e6f) & kFinite);
  app.add_option("--amplitude", o.amplitude, "Brick height above the mortar, object units")->check(CLI::Range(1e-6f, 1e3f) & kFinite);
  bool base = false;
  app.add_flag("--base", base, "Write the smooth base surface instead of the bricks");
  // Bad usage: exit 2, one line, as meso's own.
  app.failure_message([](const CLI::App*, const CLI::Error& e) { return std::string("meso-example: ") + e.what() + "\n"; });
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  try {
    const meso::Mesh mesh = base ? meso::make_brick_wall_base(o, o.columns, o.rows) : meso::make_brick_wall(o);
    meso::OutputSet outputs;
    meso::write_mesh(mesh, outputs.add(out));
    outputs.commit();
  } catch (const meso::Error& e) {
    std::fprintf(stderr, "meso-example: %s\n", e.what());
    return static_cast<int>(e.code());
  }
  return 0;
}
