#include "cli.hpp"

#include "meso/core/error.hpp"
#include "meso/formats/atomic_file.hpp"
#include "meso/formats/image_io.hpp"
#include "meso/uvpack/uv_check.hpp"


namespace meso::cli {

void add_uvpack(CLI::App& app, Context& ctx) {
  CLI::App* uv = app.add_subcommand("uvpack", "Check UV mappings for uniqueness");
  uv->require_subcommand(1);
  struct Args {
    std::string input, overlay, report;
    int size = 1024;
  };
  auto args = std::make_shared<Args>();
  CLI::App* check = uv->add_subcommand("check", "Report texels used by more than one chart, at a given resolution");
  check->add_option("input", args->input, "Mesh with UVs")->required();
  check->add_option("--size", args->size, "Texture size in texels per side")->check(CLI::Range(1, 32768));
  check->add_option("-o,--overlay", args->overlay, "Overlay PNG (RGBA): red = shared texels, blue = used once");
  check->add_option("--report", args->report, "JSON report file");
  check->callback([&ctx, args] {
    ctx.run = [&ctx, args](nlohmann::json& report, Progress&) {
      nlohmann::json in_report;
      const Mesh mesh = load_mesh(ctx.globals, args->input, in_report);
      if (!has_uvs(mesh)) throw InputError(args->input, "has no texture coordinates to check");
      UvCheckOptions o;
      o.size = args->size;
      const UvCheckReport r = check_uv_mapping(mesh, o);
      report = {{"command", "uvpack check"},
                {"input", in_report},
                {"size", r.width},
                {"charts", r.charts},
                {"overlapping_faces", r.overlapping_faces},
                {"degenerate_faces", r.degenerate_faces},
                {"outside_faces", r.outside_faces},
                {"texels_touched", r.texels_touched},
                {"texels_shared", r.texels_shared},
                {"utilization", r.utilization}};
      OutputSet outputs;
      if (!args->overlay.empty()) write_image(r.overlay, outputs.add(args->overlay), PixelFormat::uint8);
      if (!args->report.empty()) {
        outputs.write_text(args->report, report.dump(2) + "\n");
      }
      outputs.commit();
      info(ctx.globals, args->input + ": " + std::to_string(r.charts) + " charts, " +
                            std::to_string(r.overlapping_faces.size()) + " overlapping faces, " +
                            std::to_string(r.texels_shared) + " shared texels at " + std::to_string(r.width) + "^2");
      return 0;
    };
  });
}

}  // namespace meso::cli
