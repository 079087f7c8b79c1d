#include "cli.hpp"

#include "meso/core/error.hpp"
#include "meso/formats/atomic_file.hpp"
#include "meso/formats/image_io.hpp"
#include "meso/formats/mesh_io.hpp"
#include "meso/uvpack/uv_check.hpp"
#include "meso/uvpack/uv_pack.hpp"

#include <stdexcept>

#include <algorithm>
#include <map>


namespace meso::cli {

namespace {

nlohmann::json density_json(const std::vector<ChartDensity>& d) {
  std::vector<double> v;
  for (const auto& c : d) v.push_back(c.texels_per_unit);
  std::sort(v.begin(), v.end());
  nlohmann::json per_chart = nlohmann::json::array();
  for (const auto& c : d) per_chart.push_back({{"chart", c.chart}, {"texels_per_unit", c.texels_per_unit}});
  if (v.empty()) return {{"per_chart", per_chart}};
  return {{"min", v.front()}, {"median", v[v.size() / 2]}, {"max", v.back()}, {"per_chart", per_chart}};
}

}  // namespace

void add_uvpack(CLI::App& app, Context& ctx) {
  CLI::App* uv = app.add_subcommand("uvpack", "Check UV mappings for uniqueness; pack charts into an atlas");
  uv->require_subcommand(1);
  struct Args {
    std::string input, overlay, report;
    int size = 1024;
    double padding = 0;
    std::vector<std::string> fail_on;
  };
  auto args = std::make_shared<Args>();
  CLI::App* check = uv->add_subcommand("check", "Find UV overlaps (exactly), texels shared at a resolution, flips, padding");
  check->add_option("input", args->input, "Mesh with UVs")->required();
  check->add_option("--size", args->size, "Texture size in texels per side")->check(CLI::Range(1, 32768));
  check->add_option("--padding", args->padding, "Texels charts must keep between them (0: not checked)")
      ->check(CLI::NonNegativeNumber & Finite);
  check->add_option("-o,--overlay", args->overlay, "Overlay PNG (RGBA): red = shared texels, blue = used once");
  check->add_option("--report", args->report, "JSON report file");
  check->add_option("--fail-on", args->fail_on, "Exit 1 when any of these is found: overlap,shared,flipped,degenerate,outside,padding")
      ->delimiter(',')
      ->check(CLI::IsMember({"overlap", "shared", "flipped", "degenerate", "outside", "padding"}));
  check->callback([&ctx, args] {
    ctx.run = [&ctx, args](nlohmann::json& report, Progress&) {
      nlohmann::json in_report;
      const Mesh mesh = load_mesh(ctx.globals, args->input, in_report);
      if (!has_uvs(mesh)) throw InputError(args->input, "has no texture coordinates to check");
      UvCheckOptions o;
      o.size = args->size;
      o.padding = args->padding;
      o.overlay = !args->overlay.empty();
      const UvCheckReport r = check_uv_mapping(mesh, o);
      nlohmann::json gaps = nlohmann::json::array();
      for (const auto& g : r.padding_violations) gaps.push_back({{"charts", {g.chart_a, g.chart_b}}, {"distance", g.distance}});
      report = {{"command", "uvpack check"},
                {"input", in_report},
                {"size", r.width},
                {"padding", o.padding},
                {"charts", r.charts},
                {"overlapping_faces", r.overlapping_faces},
                {"overlap_pairs", r.overlap_pairs},
                {"shared_texel_faces", r.shared_texel_faces},
                {"flipped_faces", r.flipped_faces},
                {"degenerate_faces", r.degenerate_faces},
                {"outside_faces", r.outside_faces},
                {"padding_violations", gaps},
                {"texel_density", density_json(r.texel_density)},
                {"texels_touched", r.texels_touched},
                {"texels_shared", r.texels_shared},
                {"utilization", r.utilization}};
      OutputSet outputs;
      if (!args->overlay.empty()) write_image(r.overlay, outputs.add(args->overlay), PixelFormat::uint8);
      if (!args->report.empty()) outputs.write_text(args->report, report.dump(2) + "\n");
      outputs.commit();
      info(ctx.globals, args->input + ": " + std::to_string(r.charts) + " charts, " + std::to_string(r.overlap_pairs.size()) +
                            " overlapping face pairs, " + std::to_string(r.texels_shared) + " shared texels at " +
                            std::to_string(r.width) + "^2");
      const std::map<std::string, bool> found = {{"overlap", !r.overlap_pairs.empty()},
                                                 {"shared", r.texels_shared > 0},
                                                 {"flipped", !r.flipped_faces.empty()},
                                                 {"degenerate", !r.degenerate_faces.empty()},
                                                 {"outside", !r.outside_faces.empty()},
                                                 {"padding", !r.padding_violations.empty()}};
      for (const auto& what : args->fail_on) {
        if (found.at(what)) {
          warn(ctx.globals, args->input + ": --fail-on " + what + ": found");
          return static_cast<int>(ExitCode::check_failed);
        }
      }
      return 0;
    };
  });

  // pack: move the existing charts into an atlas with padding.
  struct PackArgs {
    std::string input, output;
    UvPackOptions options;
    bool no_rotate = false;
  };
  auto pack_args = std::make_shared<PackArgs>();
  CLI::App* pack = uv->add_subcommand("pack", "Pack the mesh's UV charts into a square atlas with padding (one common scale, 90-degree turns)");
  pack->add_option("input", pack_args->input, "Mesh with UVs (its charts are kept as they are)")->required();
  pack->add_option("-o,--output", pack_args->output, "Output mesh (.obj, .ply, .gltf, .glb)")->required();
  pack->add_option("--size", pack_args->options.size, "Atlas size in texels per side")->check(CLI::Range(1, 16384))->capture_default_str();
  pack->add_option("--padding", pack_args->options.padding, "Texels between charts (half of it to the border)")->check(CLI::Range(0, 256))->capture_default_str();
  pack->add_flag("--no-rotate", pack_args->no_rotate, "Keep every chart's orientation");
  pack->callback([&ctx, pack_args] {
    ctx.run = [&ctx, pack_args](nlohmann::json& report, Progress&) {
      if (!is_writable_mesh_extension(pack_args->output)) throw UsageError("--output " + pack_args->output + ": unsupported mesh extension");
      nlohmann::json in_report;
      Mesh mesh = load_mesh(ctx.globals, pack_args->input, in_report);
      if (!has_uvs(mesh))
        throw InputError(pack_args->input, "has no texture coordinates; pack moves existing charts (unwrapping is not implemented yet)");
      UvPackOptions o = pack_args->options;
      o.rotate = !pack_args->no_rotate;
      UvPackReport r;
      try {
        r = pack_uv_charts(mesh, o);
      } catch (const std::invalid_argument& e) {
        throw InputError(pack_args->input, e.what());
      }
      // The checker's verdict on the result, for the record.
      UvCheckOptions verify;
      verify.size = o.size;
      verify.padding = o.padding;
      verify.overlay = false;
      const UvCheckReport c = check_uv_mapping(mesh, verify);
      OutputSet outputs;
      write_mesh(mesh, outputs.add(pack_args->output));
      outputs.commit();
      info(ctx.globals, "packed " + std::to_string(r.charts) + " charts into " + pack_args->output + ", utilization " + std::to_string(r.utilization));
      report = {{"command", "uvpack pack"},
                {"input", in_report},
                {"output", pack_args->output},
                {"size", o.size},
                {"padding", o.padding},
                {"rotate", o.rotate},
                {"charts", r.charts},
                {"scale", r.scale},
                {"utilization", r.utilization},
                {"attempts", r.attempts},
                {"check", {{"overlapping_faces", c.overlapping_faces.size()},
                           {"shared_texel_faces", c.shared_texel_faces.size()},
                           {"padding_violations", c.padding_violations.size()},
                           {"outside_faces", c.outside_faces.size()}}}};
      return 0;
    };
  });
}

}  // namespace meso::cli
