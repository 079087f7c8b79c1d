#include "cli.hpp"

#include "meso/core/error.hpp"
#include "meso/formats/atomic_file.hpp"
#include "meso/formats/image_io.hpp"
#include "meso/preview/preview.hpp"

#include <chrono>
#include <filesystem>
#include <iostream>

namespace meso::cli {

void add_preview(CLI::App& app, Context& ctx) {
  struct Args {
    std::string base, maps, streams, png, size = "512x512", shade = "lit";
    PreviewOptions options;
    bool headless = false, list = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand("preview", "Render the base mesh with its baked maps (window, or headless to PNG)");
  sub->add_option("base", args->base, "Base mesh with UVs");
  sub->add_option("--maps", args->maps, "Folder written by meso bake (displacement.exr, normal_ts.png)");
  sub->add_option("--streams", args->streams, "Folder of meso streams outputs (sdf.exr for sphere-tracing, cone.exr for cone, relaxed-cone.exr for relaxed-cone); default: the --maps folder");
  sub->add_option("--method", args->options.method, "Displacement method (see --list-methods)")
      ->check(CLI::IsMember(preview_methods()));
  sub->add_flag("--list-methods", args->list, "Print the method names, one per line, and exit");
  sub->add_flag("--headless", args->headless, "Render off screen (EGL, no display needed) to --png");
  sub->add_option("--png", args->png, "Output image for --headless (RGBA PNG, 8 bit)");
  sub->add_option("--size", args->size, "Image size WxH");
  sub->add_option("--view-angle", args->options.camera.view_angle,
                  "Degrees between the view direction and the mesh's mean normal (0 to 89.9)")
      ->check(CLI::Range(0.0, 89.9) & Finite);
  sub->add_option("--azimuth", args->options.camera.azimuth, "Degrees around the mean normal")->check(Finite);
  sub->add_option("--zoom", args->options.camera.zoom, "Zoom factor (> 1 moves closer)")->check(CLI::PositiveNumber & Finite);
  sub->add_option("--iterations", args->options.iterations, "Main iteration budget of the method")->check(CLI::Range(1, 4096));
  sub->add_option("--shade", args->shade, "lit, uv (visible point's UV in R,G) or height")
      ->check(CLI::IsMember({"lit", "uv", "height"}));
  sub->callback([&ctx, args] {
    ctx.run = [&ctx, args](nlohmann::json& report, Progress&) {
      if (args->list) {
        for (const auto& m : preview_methods()) std::cout << m << '\n';
        report = {{"command", "preview"}, {"methods", preview_methods()}};
        return 0;
      }
      if (args->base.empty()) throw UsageError("preview: give the base mesh");
      if (args->maps.empty()) throw UsageError("preview: give --maps DIR (the folder meso bake wrote)");
      if (args->headless && args->png.empty()) throw UsageError("preview: --headless needs --png FILE");
      PreviewOptions o = args->options;
      parse_size(args->size, o.width, o.height);
      o.shade = args->shade == "uv" ? PreviewShade::uv : args->shade == "height" ? PreviewShade::height : PreviewShade::lit;
      nlohmann::json base_report;
      const Mesh base = load_mesh(ctx.globals, args->base, base_report);
      if (!has_uvs(base)) throw InputError(args->base, "has no texture coordinates; the maps cannot be applied");
      const std::filesystem::path dir(args->maps);
      PreviewMaps maps;
      maps.displacement = read_image(dir / "displacement.exr");
      maps.normal_ts = read_image(dir / "normal_ts.png");
      if (maps.normal_ts.channels < 3) throw InputError((dir / "normal_ts.png").string(), "needs 3 channels (a tangent-space normal map)");
      // Streams: those the method needs must be there; in a window, any that are there are
      // loaded so that every method can be switched to.
      const std::filesystem::path streams_dir(args->streams.empty() ? args->maps : args->streams);
      for (const std::string& method : preview_methods()) {
        const std::string stream = required_stream(method);
        if (stream.empty()) continue;
        const std::filesystem::path file = streams_dir / stream;
        const std::string producer = stream.substr(0, stream.size() - 4);  // "sdf", "cone", "relaxed-cone"
        const bool needed = o.method == method;
        if (needed && !std::filesystem::exists(file))
          throw InputError(file.string(), "missing: method " + o.method + " needs it (meso streams " + producer + " " +
                                              (dir / "displacement.exr").string() + " -o " + file.string() + ")");
        if (!needed && (args->headless || !std::filesystem::exists(file))) continue;
        Image& slot = *stream_for(maps, method);
        try {
          slot = read_image(file);
          check_stream_matches(method, slot, maps.displacement, file.string());
        } catch (const InputError& e) {
          if (needed) throw;
          warn(ctx.globals, std::string(e.what()) + " (" + method + " unavailable)");  // window only
          slot = Image();
        }
      }
      if (!args->headless) {
        run_window(base, maps, o);
        report = {{"command", "preview"}, {"method", o.method}};
        return 0;
      }
      const auto t0 = std::chrono::steady_clock::now();
      Image img = render_headless(base, maps, o);
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      OutputSet outputs;
      write_image(img, outputs.add(args->png), PixelFormat::uint8);
      outputs.commit();
      info(ctx.globals, "wrote " + args->png);
      report = {{"command", "preview"}, {"base", base_report}, {"method", o.method}, {"iterations", o.iterations},
                {"width", o.width}, {"height", o.height}, {"png", args->png}, {"ms_total", ms}};
      return 0;
    };
  });
}

}  // namespace meso::cli
