#include "cli.hpp"

#include "meso/bake/tangent_frame.hpp"
#include "meso/core/error.hpp"
#include "meso/formats/atomic_file.hpp"
#include "meso/formats/mesh_io.hpp"

namespace meso::cli {

void add_frames(CLI::App& app, Context& ctx) {
  struct Args {
    std::string input, output;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand("frames", "Compute per-corner tangent frames (MikkTSpace conventions) and write them with the mesh");
  sub->add_option("input", args->input, "Base mesh with UVs")->required();
  sub->add_option("-o,--output", args->output, "Output mesh; .gltf/.glb carry the frames as TANGENT")->required();
  sub->callback([&ctx, args] {
    ctx.run = [&ctx, args](nlohmann::json& report, Progress&) {
      if (!is_writable_mesh_extension(args->output)) throw UsageError(args->output + ": unknown mesh extension (use .obj, .ply, .gltf or .glb)");
      nlohmann::json in_report;
      Mesh mesh = load_mesh(ctx.globals, args->input, in_report);
      if (!has_uvs(mesh)) throw InputError(args->input, "has no texture coordinates; tangent frames need a UV mapping");
      const auto frames = compute_tangent_frames(mesh);
      store_tangents(mesh, frames);
      size_t mirrored = 0;
      for (auto h : mesh.halfedges())
        if (!mesh.is_boundary(h) && frames[static_cast<size_t>(h.idx())].sign < 0) ++mirrored;
      OutputSet outputs;
      write_mesh(mesh, outputs.add(args->output));
      outputs.commit();
      report = {{"command", "frames"}, {"input", in_report}, {"output", args->output}, {"mirrored_corners", mirrored}};
      return 0;
    };
  });
}

}  // namespace meso::cli
