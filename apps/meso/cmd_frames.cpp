#include "cli.hpp"

#include "meso/bake/curvature.hpp"
#include "meso/bake/tangent_frame.hpp"
#include "meso/core/error.hpp"
#include "meso/formats/atomic_file.hpp"
#include "meso/formats/mesh_io.hpp"

#include <algorithm>

namespace meso::cli {

void add_frames(CLI::App& app, Context& ctx) {
  struct Args {
    std::string input, output;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand("frames", "Tangent frames (MikkTSpace conventions) and principal curvatures of a base mesh");
  sub->add_option("input", args->input, "Base mesh with UVs")->required();
  sub->add_option("-o,--output", args->output, "Output mesh; .gltf/.glb carry TANGENT, _CURVATURE and _PRINCIPAL_DIRECTION")->required();
  sub->callback([&ctx, args] {
    ctx.run = [&ctx, args](nlohmann::json& report, Progress&) {
      if (!is_writable_mesh_extension(args->output)) throw UsageError(args->output + ": unknown mesh extension (use .obj, .ply, .gltf or .glb)");
      nlohmann::json in_report;
      Mesh mesh = load_mesh(ctx.globals, args->input, in_report);
      if (!has_uvs(mesh)) throw InputError(args->input, "has no texture coordinates; tangent frames need a UV mapping");
      const auto frames = compute_tangent_frames(mesh);
      store_tangents(mesh, frames);
      const auto curvature = fit_curvature(mesh);
      store_curvature(mesh, curvature);
      size_t unfit = 0, two_ring = 0;
      float k_lo = 0, k_hi = 0;
      for (const auto& c : curvature) {
        unfit += c.rings == 0;
        two_ring += c.rings == 2;
        k_lo = std::min(k_lo, c.k2);
        k_hi = std::max(k_hi, c.k1);
      }
      if (unfit) warn(ctx.globals, args->input + ": " + std::to_string(unfit) + " vertices have too few neighbours for a curvature fit (set to 0)");
      size_t mirrored = 0;
      for (auto h : mesh.halfedges())
        if (!mesh.is_boundary(h) && frames[static_cast<size_t>(h.idx())].sign < 0) ++mirrored;
      OutputSet outputs;
      write_mesh(mesh, outputs.add(args->output));
      outputs.commit();
      report = {{"command", "frames"},
                {"input", in_report},
                {"output", args->output},
                {"mirrored_corners", mirrored},
                {"curvature", {{"min", k_lo}, {"max", k_hi}, {"two_ring_vertices", two_ring}, {"unfit_vertices", unfit}}}};
      return 0;
    };
  });
}

}  // namespace meso::cli
