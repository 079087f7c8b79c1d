#include "cli.hpp"

#include "meso/core/error.hpp"
#include "meso/formats/atomic_file.hpp"
#include "meso/formats/image_io.hpp"
#include "meso/streams/pyramid.hpp"

namespace meso::cli {

void add_streams(CLI::App& app, Context& ctx) {
  CLI::App* streams = app.add_subcommand("streams", "Precompute data for per-pixel displacement from a height map");
  streams->require_subcommand(1);
  struct Args {
    std::string input, output;
    bool wrap = false, clamp = false, half = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* pyramid = streams->add_subcommand("pyramid", "Min-max MIP pyramid of the bilinearly filtered height surface");
  pyramid->add_option("height", args->input, "Height map: EXR/PNG/TIFF, channel 0 (e.g. meso bake's displacement.exr)")->required();
  pyramid->add_option("-o,--output", args->output, "Output EXR (MIP-mapped: R = minimum, G = maximum)")->required();
  auto* wrap = pyramid->add_flag("--wrap", args->wrap, "The map tiles: lookups wrap around the borders");
  pyramid->add_flag("--clamp", args->clamp, "Lookups clamp to the edge texels (the default)")->excludes(wrap);
  pyramid->add_flag("--half", args->half, "Store half floats instead of float32");
  pyramid->callback([&ctx, args] {
    ctx.run = [&ctx, args](nlohmann::json& report, Progress&) {
      const Image height = read_image(args->input);
      const HeightField field = make_height_field(height, args->wrap ? Border::wrap : Border::clamp);
      MinMaxPyramid p = build_min_max_pyramid(field);
      p.levels[0].metadata = {{"quantity", std::string("min-max pyramid")},
                              {"channels", std::string("R = minimum, G = maximum of the bilinear height surface over each texel")},
                              {"height_scale", field.scale},
                              {"height_bias", field.bias},
                              {"height_units", std::string("normalised: object = bias + scale * value")},
                              {"border", std::string(border_name(field.border))}};
      OutputSet outputs;
      write_image_levels(p.levels, outputs.add(args->output), args->half ? PixelFormat::half : PixelFormat::float32);
      outputs.commit();
      info(ctx.globals, "wrote " + args->output + " (" + std::to_string(p.levels.size()) + " levels)");
      report = {{"command", "streams pyramid"},
                {"input", args->input},
                {"output", args->output},
                {"width", height.width},
                {"height", height.height},
                {"levels", p.levels.size()},
                {"scale", field.scale},
                {"bias", field.bias},
                {"border", border_name(field.border)}};
      return 0;
    };
  });
}

}  // namespace meso::cli
