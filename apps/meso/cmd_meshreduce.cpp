#include "cli.hpp"

#include "meso/core/error.hpp"
#include "meso/formats/atomic_file.hpp"
#include "meso/formats/mesh_io.hpp"
#include "meso/meshreduce/meshreduce.hpp"

#include <cmath>

namespace meso::cli {

void add_meshreduce(CLI::App& app, Context& ctx) {
  struct Args {
    std::string input, output;
    size_t faces = 0;
    double ratio = 0;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand("meshreduce", "Reduce a high-poly mesh to a base mesh (quadric edge collapse)");
  sub->add_option("input", args->input, "Input mesh (OBJ, FBX, glTF, PLY, OFF, DAE, ...)")->required();
  sub->add_option("-o,--output", args->output, "Output mesh (.obj, .ply, .gltf, .glb)")->required();
  auto* faces = sub->add_option("--faces", args->faces, "Target face count")->check(CLI::PositiveNumber);
  auto* ratio = sub->add_option("--ratio", args->ratio, "Target as a fraction of the input's faces")
                    ->check(CLI::Range(0.0, 1.0) & Finite);
  faces->excludes(ratio);
  sub->callback([&ctx, args, faces, ratio] {
    if (faces->count() + ratio->count() != 1) throw CLI::ValidationError("meshreduce", "give exactly one target: --faces N or --ratio R");
    ctx.run = [&ctx, args](nlohmann::json& report, Progress& progress) {
      if (!is_writable_mesh_extension(args->output)) throw UsageError(args->output + ": unknown mesh extension (use .obj, .ply, .gltf or .glb)");
      nlohmann::json in_report;
      const Mesh input = load_mesh(ctx.globals, args->input, in_report);
      ReduceOptions o;
      o.target_faces = args->faces ? args->faces
                                   : static_cast<size_t>(std::llround(args->ratio * static_cast<double>(input.n_faces())));
      if (o.target_faces >= input.n_faces())
        warn(ctx.globals, "target " + std::to_string(o.target_faces) + " faces is not below the input's " +
                              std::to_string(input.n_faces()) + ": the mesh is written unchanged");
      ReduceReport r;
      const Mesh out = reduce_mesh(input, o, &r, progress);
      if (!r.target_reached)
        warn(ctx.globals, "stopped at " + std::to_string(r.output_faces) + " faces: no further collapse keeps the UV charts, boundaries and orientation intact");
      OutputSet outputs;
      write_mesh(out, outputs.add(args->output));
      outputs.commit();
      info(ctx.globals, "wrote " + args->output + " (" + std::to_string(r.output_faces) + " faces)");
      report = {{"command", "meshreduce"},
                {"input", in_report},
                {"output", {{"path", args->output}, {"vertices", r.output_vertices}, {"faces", r.output_faces}}},
                {"target_faces", o.target_faces},
                {"target_reached", r.target_reached},
                {"collapses", r.collapses},
                {"seconds", r.seconds}};
      return 0;
    };
  });
}

}  // namespace meso::cli
