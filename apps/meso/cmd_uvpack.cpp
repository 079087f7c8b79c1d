#include "cli.hpp"

#include "meso/core/error.hpp"
#include "meso/formats/atomic_file.hpp"
#include "meso/formats/image_io.hpp"
#include "meso/uvpack/uv_check.hpp"

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
  CLI::App* uv = app.add_subcommand("uvpack", "Check UV mappings for uniqueness");
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
}

}  // namespace meso::cli
