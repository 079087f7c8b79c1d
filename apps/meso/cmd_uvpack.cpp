#include "cli.hpp"

#include "meso/core/error.hpp"
#include "meso/formats/atomic_file.hpp"
#include "meso/formats/image_io.hpp"
#include "meso/formats/mesh_io.hpp"
#include "meso/uvpack/uv_check.hpp"
#include "meso/uvpack/uv_pack.hpp"
#include "meso/uvpack/uv_unwrap.hpp"

#include <algorithm>
#include <chrono>
#include <map>
#include <stdexcept>


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

nlohmann::json unwrap_json(const UvUnwrapReport& r, const std::string& method, double seconds) {
  std::vector<double> l2;
  for (const auto& c : r.per_chart) l2.push_back(c.stretch_l2);
  std::sort(l2.begin(), l2.end());
  nlohmann::json chart_l2 = nlohmann::json::object();
  if (!l2.empty()) chart_l2 = {{"min", l2.front()}, {"median", l2[l2.size() / 2]}, {"max", l2.back()}};
  return {{"method", method},
          {"charts", r.charts},
          {"grown_charts", r.grown_charts},
          {"splits", {{"topology", r.topology_splits}, {"stretch", r.stretch_splits}, {"overlap", r.overlap_splits}, {"failure", r.failure_splits}}},
          {"stretch_l2", r.stretch_l2},
          {"stretch_linf", r.stretch_linf},
          {"chart_stretch_l2", chart_l2},
          {"angle_distortion", {{"mean", r.angle_distortion_mean}, {"max", r.angle_distortion_max}}},
          {"area_distortion_mean", r.area_distortion_mean},
          {"degenerate_faces", r.degenerate_faces},
          {"seconds", seconds}};
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
    bool unwrap = false;
    std::string unwrap_method = "lscm";
    UvUnwrapOptions unwrap_options;
  };
  auto pack_args = std::make_shared<PackArgs>();
  CLI::App* pack = uv->add_subcommand("pack", "Pack the mesh's UV charts into a square atlas with padding (one common scale, 90-degree turns)");
  pack->add_option("input", pack_args->input, "Mesh (its UV charts are kept as they are, unless --unwrap or it has no UVs)")->required();
  pack->add_option("-o,--output", pack_args->output, "Output mesh (.obj, .ply, .gltf, .glb)")->required();
  pack->add_option("--size", pack_args->options.size, "Atlas size in texels per side")->check(CLI::Range(1, 16384))->capture_default_str();
  pack->add_option("--padding", pack_args->options.padding, "Texels between charts (half of it to the border)")->check(CLI::Range(0, 256))->capture_default_str();
  pack->add_flag("--no-rotate", pack_args->no_rotate, "Keep every chart's orientation");
  pack->add_flag("--unwrap", pack_args->unwrap, "Make new charts (normal-cone charts flattened by LSCM or ARAP) instead of the mesh's UVs; implied when it has none");
  pack->add_option("--unwrap-method", pack_args->unwrap_method, "Flattening: lscm (conformal, fast) or arap (as-rigid-as-possible)")
      ->check(CLI::IsMember({"lscm", "arap"}))
      ->capture_default_str();
  pack->add_option("--max-stretch", pack_args->unwrap_options.max_stretch, "Largest L2 stretch of a chart (1 = isometric); charts above it are split")
      ->check(CLI::Range(1.0, 1e6) & Finite)
      ->capture_default_str();
  pack->add_option("--chart-angle", pack_args->unwrap_options.max_chart_angle, "Degrees a face normal may deviate from its chart's mean normal")
      ->check(CLI::Range(1.0, 179.0) & Finite)
      ->capture_default_str();
  pack->add_option("--max-chart-faces", pack_args->unwrap_options.max_chart_faces, "Faces per chart at most (0: no cap)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  pack->callback([&ctx, pack_args] {
    ctx.run = [&ctx, pack_args](nlohmann::json& report, Progress&) {
      if (!is_writable_mesh_extension(pack_args->output)) throw UsageError("--output " + pack_args->output + ": unsupported mesh extension");
      nlohmann::json in_report;
      Mesh mesh = load_mesh(ctx.globals, pack_args->input, in_report);
      nlohmann::json unwrap_report;
      if (pack_args->unwrap || !has_uvs(mesh)) {
        if (mesh.n_faces() == 0) throw InputError(pack_args->input, "has no faces to unwrap");
        if (!has_uvs(mesh)) info(ctx.globals, pack_args->input + ": no texture coordinates, unwrapping");
        UvUnwrapOptions u = pack_args->unwrap_options;
        u.method = pack_args->unwrap_method == "arap" ? UnwrapMethod::arap : UnwrapMethod::lscm;
        const auto start = std::chrono::steady_clock::now();
        const UvUnwrapReport ur = unwrap_uv_charts(mesh, u);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        unwrap_report = unwrap_json(ur, pack_args->unwrap_method, seconds);
        info(ctx.globals, "unwrapped into " + std::to_string(ur.charts) + " charts (" + pack_args->unwrap_method + "), L2 stretch " +
                              std::to_string(ur.stretch_l2) + ", worst chart " + std::to_string(ur.max_chart_stretch_l2));
      }
      UvPackOptions o = pack_args->options;
      o.rotate = !pack_args->no_rotate;
      UvPackReport r;
      const auto pack_start = std::chrono::steady_clock::now();
      try {
        r = pack_uv_charts(mesh, o);
      } catch (const std::invalid_argument& e) {
        throw InputError(pack_args->input, e.what());
      }
      const double pack_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - pack_start).count();
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
                {"seconds", pack_seconds},
                {"check", {{"overlapping_faces", c.overlapping_faces.size()},
                           {"shared_texel_faces", c.shared_texel_faces.size()},
                           {"padding_violations", c.padding_violations.size()},
                           {"outside_faces", c.outside_faces.size()},
                           {"flipped_faces", c.flipped_faces.size()}}}};
      if (!unwrap_report.is_null()) report["unwrap"] = unwrap_report;
      return 0;
    };
  });
}

}  // namespace meso::cli
