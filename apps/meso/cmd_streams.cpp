#include "cli.hpp"

#include "meso/core/error.hpp"
#include "meso/formats/atomic_file.hpp"
#include "meso/formats/image_io.hpp"
#include "meso/streams/cone_map.hpp"
#include "meso/streams/distance_field.hpp"
#include "meso/streams/pyramid.hpp"

namespace meso::cli {

namespace {

// What every stream subcommand takes: the height map, the output, the border rule, precision.
struct StreamArgs {
  std::string input, output;
  bool wrap = false, clamp = false, half = false;
};

CLI::App* add_stream_subcommand(CLI::App* streams, const std::string& name, const std::string& what,
                                const std::string& output_help, StreamArgs& a) {
  CLI::App* sub = streams->add_subcommand(name, what);
  sub->add_option("height", a.input, "Height map: EXR/PNG/TIFF, channel 0 (e.g. meso bake's displacement.exr)")->required();
  sub->add_option("-o,--output", a.output, output_help)->required();
  auto* wrap = sub->add_flag("--wrap", a.wrap, "The map tiles: lookups wrap around the borders");
  sub->add_flag("--clamp", a.clamp, "Lookups clamp to the edge texels (the default)")->excludes(wrap);
  sub->add_flag("--half", a.half, "Store half floats instead of float32");
  return sub;
}

HeightField load_height_field(const StreamArgs& a) {
  return make_height_field(read_image(a.input), a.wrap ? Border::wrap : Border::clamp);
}


}  // namespace

void add_streams(CLI::App& app, Context& ctx) {
  CLI::App* streams = app.add_subcommand("streams", "Precompute data for per-pixel displacement from a height map");
  streams->require_subcommand(1);
  auto args = std::make_shared<StreamArgs>();
  CLI::App* pyramid = add_stream_subcommand(streams, "pyramid", "Min-max MIP pyramid of the bilinearly filtered height surface",
                                            "Output EXR (MIP-mapped: R = minimum, G = maximum)", *args);
  pyramid->callback([&ctx, args] {
    ctx.run = [&ctx, args](nlohmann::json& report, Progress&) {
      const HeightField field = load_height_field(*args);
      const Image& height = field.height;
      MinMaxPyramid p = build_min_max_pyramid(field);
      p.levels[0].metadata = height_field_metadata(field);
      p.levels[0].metadata["quantity"] = std::string("min-max pyramid");
      p.levels[0].metadata["channels"] = std::string("R = minimum, G = maximum of the bilinear height surface over each texel");
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
                {"bytes", [&p, args] {
                   size_t n = 0;
                   for (const Image& l : p.levels) n += l.pixels.size();
                   return n * (args->half ? 2 : 4);
                 }()},
                {"scale", field.scale},
                {"bias", field.bias},
                {"border", border_name(field.border)}};
      return 0;
    };
  });

  for (const ConeKind kind : {ConeKind::conservative, ConeKind::relaxed}) {
    const bool relaxed = kind == ConeKind::relaxed;
    auto cone_args = std::make_shared<StreamArgs>();
    auto tolerance = std::make_shared<double>(1e-4);
    CLI::App* cone = add_stream_subcommand(
        streams, relaxed ? "relaxed-cone" : "cone",
        relaxed ? "Relaxed cone map (Policarpo & Oliveira), exact for the bilinear surface: a ray to the cone's boundary crosses it at most once"
                : "Conservative cone map (Dummer), exact for the bilinear surface: no point of it inside any cone",
        "Output EXR (MIP-mapped: R = height, G = cone ratio, B = apex height)", *cone_args);
    cone->add_option("--tolerance", *tolerance, "Relative gap allowed below the exact ratio (the stored one is never wider)")
        ->check(CLI::Range(1e-6, 0.5))
        ->capture_default_str();
    cone->callback([&ctx, cone_args, tolerance, kind] {
      ctx.run = [&ctx, cone_args, tolerance, kind](nlohmann::json& report, Progress&) {
        const HeightField field = load_height_field(*cone_args);
        ConeMapOptions options;
        options.kind = kind;
        options.tolerance = *tolerance;
        options.half = cone_args->half;
        const std::vector<Image> levels = cone_map_levels(build_cone_map(field, options));
        OutputSet outputs;
        write_image_levels(levels, outputs.add(cone_args->output), cone_args->half ? PixelFormat::half : PixelFormat::float32);
        outputs.commit();
        info(ctx.globals, "wrote " + cone_args->output + " (" + std::to_string(levels.size()) + " levels)");
        const Image& l0 = levels[0];
        size_t capped = 0;
        float lo = kConeRatioCap;
        for (size_t i = 0; i < l0.texel_count(); ++i) {
          const float r = l0.pixels[i * 3 + 1];
          capped += r >= kConeRatioCap;
          lo = std::min(lo, r);
        }
        size_t texels = 0;
        for (const Image& l : levels) texels += l.texel_count();
        report = {{"command", std::string("streams ") + (kind == ConeKind::relaxed ? "relaxed-cone" : "cone")},
                  {"input", cone_args->input},
                  {"output", cone_args->output},
                  {"width", l0.width},
                  {"height", l0.height},
                  {"levels", levels.size()},
                  {"scale", field.scale},
                  {"bias", field.bias},
                  {"border", border_name(field.border)},
                  {"tolerance", *tolerance},
                  {"min_ratio", lo},
                  {"unbounded_texels", capped},
                  {"bytes", texels * 3 * (cone_args->half ? 2 : 4)}};
        return 0;
      };
    });
  }

  auto sdf_args = std::make_shared<StreamArgs>();
  auto sdf_options = std::make_shared<DistanceFieldOptions>();
  CLI::App* sdf = add_stream_subcommand(streams, "sdf", "3D distance field over the height field, for sphere tracing",
                                        "Output EXR: W x (H * depth), slices stacked, slice 0 lowest", *sdf_args);
  sdf->add_option("--depth", sdf_options->depth, "Slices along the height axis")->check(CLI::Range(1, 1024));
  sdf->add_option("--relief", sdf_options->relief, "Height range in units of the map's width (the box is 1 x H/W x relief)")
      ->check(CLI::PositiveNumber & Finite);
  sdf->callback([&ctx, sdf_args, sdf_options] {
    ctx.run = [&ctx, sdf_args, sdf_options](nlohmann::json& report, Progress&) {
      const HeightField field = load_height_field(*sdf_args);
      const DistanceField df = build_distance_field(field, *sdf_options);
      const Image img = distance_field_image(df, field);
      OutputSet outputs;
      write_image(img, outputs.add(sdf_args->output), sdf_args->half ? PixelFormat::half : PixelFormat::float32);
      outputs.commit();
      info(ctx.globals, "wrote " + sdf_args->output + " (" + std::to_string(df.width) + "x" + std::to_string(df.height) + "x" +
                            std::to_string(df.depth) + " voxels)");
      report = {{"command", "streams sdf"}, {"input", sdf_args->input}, {"output", sdf_args->output},
                {"width", df.width}, {"height", df.height}, {"depth", df.depth}, {"relief", df.relief},
                {"bytes", img.pixels.size() * (sdf_args->half ? 2 : 4)}};
      return 0;
    };
  });
}

}  // namespace meso::cli
