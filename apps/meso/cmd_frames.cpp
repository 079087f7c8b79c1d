#include "cli.hpp"

#include "meso/bake/curvature.hpp"
#include "meso/bake/curvature_map.hpp"
#include "meso/bake/tangent_frame.hpp"
#include "meso/core/error.hpp"
#include "meso/formats/atomic_file.hpp"
#include "meso/formats/image_io.hpp"
#include "meso/formats/mesh_io.hpp"

#include <algorithm>
#include <limits>
#include <cctype>
#include <filesystem>

namespace meso::cli {

void add_frames(CLI::App& app, Context& ctx) {
  struct Args {
    std::string input, output, curvature_map, size = "1024";
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand("frames", "Tangent frames (MikkTSpace conventions) and principal curvatures of a base mesh");
  sub->add_option("input", args->input, "Base mesh with UVs")->required();
  sub->add_option("-o,--output", args->output, "Output mesh, .gltf or .glb (TANGENT, _CURVATURE, _PRINCIPAL_DIRECTION; .obj and .ply, which cannot hold them, are refused)")->required();
  CLI::Option* map = sub->add_option("--curvature-map", args->curvature_map,
                                     "Also write the second fundamental form per texel of the UV layout (float32 EXR: R = k_tt, G = k_tb, "
                                     "B = k_bb in 1/object units in the texel's tangent frame, A = 1 computed / 0 dilated; see docs/formats.md)");
  sub->add_option("--size", args->size, "Curvature map size: N or WxH texels (default 1024)")->needs(map);
  sub->callback([&ctx, args] {
    ctx.run = [&ctx, args](nlohmann::json& report, Progress&) {
      if (!is_writable_mesh_extension(args->output)) throw UsageError(args->output + ": unknown mesh extension (use .gltf or .glb)");
      {
        // OBJ and PLY have no place for per-corner tangents or per-vertex curvatures: writing
        // one would drop everything this command computes and still succeed, so it is refused
        // as a bad value (exit 2) before any work.
        const std::string ext = lower_extension(args->output);
        if (ext != ".gltf" && ext != ".glb")
          throw UsageError(args->output + ": " + ext.substr(1) + " cannot hold tangent frames or curvatures; write .gltf or .glb");
      }
      CurvatureMapOptions map_options;
      const bool want_map = !args->curvature_map.empty();
      if (want_map) {
        parse_size(args->size, map_options.width, map_options.height);
        // Measured: 4096^2 took 204 MB more than 2048^2 (16 bytes per texel).
        refuse_beyond_memory("frames --curvature-map at --size " + args->size, 16.0 * map_options.width * map_options.height);
        if (lower_extension(args->curvature_map) != ".exr") throw UsageError(args->curvature_map + ": the curvature map is a float EXR (use .exr)");
      }
      refuse_overwriting_input(args->output, {args->input});
      refuse_overwriting_input(args->curvature_map, {args->input});
      nlohmann::json in_report;
      Mesh mesh = load_mesh(ctx.globals, args->input, in_report);
      if (!has_uvs(mesh)) throw InputError(args->input, "has no texture coordinates; tangent frames need a UV mapping");
      const auto frames = compute_tangent_frames(mesh);
      store_tangents(mesh, frames);
      const auto curvature = fit_curvature(mesh);
      store_curvature(mesh, curvature);
      size_t unfit = 0, two_ring = 0, three_ring = 0;
      // Over the fitted vertices only: the unfit ones hold a 0 that is no measurement (a
      // sphere's range had read [0, 1/r]).
      float k_lo = std::numeric_limits<float>::infinity(), k_hi = -k_lo;
      for (const auto& c : curvature) {
        unfit += c.rings == 0;
        two_ring += c.rings == 2;
        three_ring += c.rings == 3;
        if (c.rings == 0) continue;
        k_lo = std::min(k_lo, c.k2);
        k_hi = std::max(k_hi, c.k1);
      }
      const nlohmann::json k_min = k_lo <= k_hi ? nlohmann::json(k_lo) : nlohmann::json(nullptr);
      const nlohmann::json k_max = k_lo <= k_hi ? nlohmann::json(k_hi) : nlohmann::json(nullptr);
      if (unfit) warn(ctx.globals, args->input + ": " + std::to_string(unfit) + " vertices have no curvature fit (set to 0): their neighbourhoods up to the 3-ring do not determine one (too few neighbours, or all on a line or in two rows)");
      size_t mirrored = 0;
      for (auto h : mesh.halfedges())
        if (!mesh.is_boundary(h) && frames[static_cast<size_t>(h.idx())].sign < 0) ++mirrored;
      OutputSet outputs;
      write_mesh(mesh, outputs.add(args->output));
      CurvatureMap cmap;
      if (want_map) {
        cmap = bake_curvature_map(mesh, frames, curvature, map_options);
        if (cmap.texels == 0)
          throw InputError(args->input, "its UV triangles cover no texel of the curvature map (degenerate or outside [0, 1])");
        write_image(cmap.image, outputs.add(args->curvature_map), PixelFormat::float32);
        if (cmap.undefined)
          warn(ctx.globals, args->curvature_map + ": " + std::to_string(cmap.undefined) + " texels have no tangent frame (filled from neighbours)");
      }
      outputs.commit();
      report = {{"command", "frames"},
                {"input", in_report},
                {"output", args->output},
                {"mirrored_corners", mirrored},
                {"curvature", {{"min", k_min}, {"max", k_max}, {"two_ring_vertices", two_ring}, {"three_ring_vertices", three_ring}, {"unfit_vertices", unfit}}}};
      if (want_map)
        report["curvature_map"] = {{"output", args->curvature_map},
                                   {"width", map_options.width},
                                   {"height", map_options.height},
                                   {"channels", nlohmann::json::array({"R", "G", "B", "A"})},
                                   {"texels", cmap.texels},
                                   {"undefined_texels", cmap.undefined},
                                   {"min", cmap.min},
                                   {"max", cmap.max}};
      return 0;
    };
  });
}

}  // namespace meso::cli
