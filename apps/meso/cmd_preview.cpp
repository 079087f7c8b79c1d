#include "cli.hpp"

#include "meso/core/error.hpp"
#include "meso/formats/atomic_file.hpp"
#include "meso/formats/image_io.hpp"
#include "meso/preview/preview.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <vector>

namespace meso::cli {

namespace {

struct Args {
  std::string base, maps, streams, png, size = "512x512", shade = "lit", heatmaps, shadows = "none";
  int turntable = 0;
  std::vector<float> pan;
  PreviewOptions options;
  bool headless = false, list = false, compare = false;
  int frames = 0;
  int repetitions = 5;
  double uv_tolerance = 1.0, reference_edge = 0.5;
  size_t reference_triangles = size_t(1) << 25;
};

// A rendered frame as the user's file takes it. EXR keeps the float values (UVs and heights
// exactly). PNG and TIFF are 8 bit: a height frame (R in object units) is normalised there to
// the displacement map's range, object = meso:height_bias + meso:height_scale * R, as bake's
// displacement.png (raw, every height below 1/255 unit came out black).
void write_frame(Image frame, const std::filesystem::path& temp, PreviewShade shade, const Image& displacement) {
  if (lower_extension(temp.string()) == ".exr") {
    write_image(frame, temp, PixelFormat::float32);
    return;
  }
  if (shade == PreviewShade::height && !displacement.pixels.empty()) {
    const auto [lo, hi] = std::minmax_element(displacement.pixels.begin(), displacement.pixels.end());
    const float bias = *lo, scale = *hi - *lo;
    const size_t step = static_cast<size_t>(frame.channels);
    for (size_t i = 0; i < frame.pixels.size(); i += step) {
      const bool background = step == 4 && frame.pixels[i + 3] == 0.0f;  // stays transparent black
      frame.pixels[i] = scale > 0 && !background ? std::clamp((frame.pixels[i] - bias) / scale, 0.0f, 1.0f) : 0.0f;
    }
    frame.metadata["height_bias"] = bias;
    frame.metadata["height_scale"] = scale;
    frame.metadata["height_units"] = std::string("object = bias + scale * R");
  }
  write_image(frame, temp, PixelFormat::uint8);
}

// --compare: the reference, every method against it, the heatmaps, the report (and a table on
// stdout without --json).
void compare(Context& ctx, const Args& args, const Mesh& base, const PreviewMaps& maps, const PreviewOptions& view,
             const std::vector<std::string>& methods, const nlohmann::json& base_report, nlohmann::json& report) {
  CompareOptions co;
  co.methods = methods;
  co.view = view;
  co.repetitions = args.repetitions;
  co.uv_tolerance_texels = args.uv_tolerance;
  co.reference.max_edge_texels = args.reference_edge;
  co.reference.max_triangles = args.reference_triangles;
  const Comparison c = compare_methods(base, maps, co);
  OutputSet outputs;
  std::vector<std::string> written;
  if (!args.heatmaps.empty()) {
    // One scale for every method, so the pictures compare.
    double top = 1;
    for (const auto& m : c.methods) top = std::max(top, m.max_iterations);
    for (const auto& m : c.methods) {
      const std::filesystem::path file = std::filesystem::path(args.heatmaps) / (m.name + ".png");
      Image heat = fetch_heatmap(m.fetches, top);
      heat.metadata["method"] = m.name;
      heat.metadata["iterations"] = view.iterations;
      write_image(heat, outputs.add(file), PixelFormat::uint8);
      written.push_back(file.string());
    }
  }
  if (!args.png.empty()) {
    write_frame(c.reference_view, outputs.add(args.png), view.shade, maps.displacement);
    written.push_back(args.png);
  }
  outputs.commit();
  for (const auto& f : written) info(ctx.globals, "wrote " + f);
  report = nlohmann::json::parse(comparison_json(c));
  report["command"] = "preview";
  report["mode"] = "compare";
  report["base"] = base_report;
  report["outputs"] = written;
  if (!ctx.globals.json) {
    std::printf("reference: %zu exact bilinear cells, %zu triangles (longest UV edge %.3g texels), built in %.0f ms, traced in %.0f ms\n",
                c.reference_patches, c.reference_triangles, c.reference_max_edge_texels, c.reference_build_ms, c.reference_ms);
    std::printf("%-20s %10s %9s %8s %10s %9s %10s\n", "method", "wrong hits", "rmse", "psnr", "mean fetch", "p99 fetch", "ms");
    for (const auto& m : c.methods)
      std::printf("%-20s %10.4f %9.5f %8.2f %10.1f %9.0f %10.2f\n", m.name.c_str(), m.wrong_hit_fraction, m.rmse, m.psnr,
                  m.mean_iterations, m.p99_iterations, m.ms);
    std::fflush(stdout);
  }
}

}  // namespace

void add_preview(CLI::App& app, Context& ctx) {
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand("preview", "Render the base mesh with its baked maps (window, or headless to PNG)");
  sub->add_option("base", args->base, "Base mesh with UVs");
  sub->add_option("--maps", args->maps, "Folder written by meso bake (displacement.exr, normal_ts.png)");
  sub->add_option("--streams", args->streams, "Folder of meso streams outputs (sdf.exr for sphere-tracing, cone.exr for cone, relaxed-cone.exr for relaxed-cone, pyramid.exr for pyramid, vdm.exr for vdm, dstream.bin for dstream); default: the --maps folder");
  CLI::Option* method_option = sub->add_option(
      "--method", args->options.method,
      "Displacement method (see --list-methods); with --compare a comma-separated list or 'all' (the default: every "
      "method whose stream is in --streams)");
  sub->add_flag("--list-methods", args->list, "Print the method names, one per line, and exit");
  sub->add_flag("--headless", args->headless, "Render off screen (EGL, no display needed) to --png");
  sub->add_option("--png", args->png,
                  "Output image for --headless (RGBA, 8 bit in .png/.tif, float in .exr; --shade height in 8 bit is normalised to "
                  "the map's range); with --compare, the reference image (in --shade); in the window "
                  "with --frames, its last frame")
      ->check(ImageOutput);
  sub->add_option("--frames", args->frames, "Window: close after N frames (scripted runs; the report gives the median frame time)")
      ->check(CLI::Range(1, 1000000));
  sub->add_option("--size", args->size, "Image size WxH");
  sub->add_option("--view-angle", args->options.camera.view_angle,
                  "Degrees between the view direction and the mesh's mean normal (0 to 89.9)")
      ->check(InRange(0.0, 89.9));
  sub->add_option("--azimuth", args->options.camera.azimuth, "Degrees around the mean normal")->check(InRange(-3600.0, 3600.0));
  sub->add_option("--zoom", args->options.camera.zoom, "Zoom factor (> 1 moves closer)")->check(InRange(1e-3, 1e3));
  sub->add_option("--pan", args->pan, "X,Y: move the view right and up by X and Y framing radii (half the mesh's box diagonal)")
      ->expected(2)
      ->delimiter(',')
      ->check(InRange(-1e3, 1e3));
  sub->add_option("--iterations", args->options.iterations, "Main iteration budget of the method")->check(CLI::Range(1, 4096));
  sub->add_option("--shade", args->shade, "lit, uv (visible point's UV in R,G) or height")
      ->check(CLI::IsMember({"lit", "uv", "height"}));
  sub->add_option("--shadows", args->shadows, "Self-shadowing of the lit shade: none, hard or soft (8 rays toward a disc light)")
      ->check(CLI::IsMember({"none", "hard", "soft"}));
  sub->add_option("--shadow-steps", args->options.shadow_steps, "Height samples along a shadow ray")->check(CLI::Range(1, 4096));
  sub->add_option("--light-size", args->options.light_size, "Angular radius of the soft shadows' light, degrees")
      ->check(InRange(0.0, 45.0));
  sub->add_option("--light-elevation", args->options.camera.light_elevation, "Light: degrees above the mesh's mean plane")
      ->check(InRange(-90.0, 90.0));
  sub->add_option("--light-azimuth", args->options.camera.light_azimuth, "Light: degrees around the mean normal")->check(InRange(-3600.0, 3600.0));
  sub->add_flag("--silhouettes", args->options.silhouettes,
                "Curved rays for steep/relief/pom (the base's curvature along the view, section 5.1 of the survey; rays that "
                "leave the surface are discarded) and, on maps that do not tile, discard visible points off the map");
  sub->add_option("--morph", args->options.morph,
                  "dstream: morph every vertex toward the coarser level by this much (1: the level drawn, 0: the coarser level's surface); "
                  "default: by distance (--lod-distance)")
      ->check(InRange(0.0, 1.0));
  sub->add_option("--lod-distance", args->options.lod_distance,
                  "dstream: vertices nearer than this (object units) take the level drawn (the finest within --iterations segments per "
                  "edge), farther than twice this the coarser level's surface, morphing between (0: no morph)")
      ->check(NonNegative);
  sub->add_option("--binary-steps", args->options.binary_steps, "relief: halvings of the step that crossed the surface (default 8)")
      ->check(CLI::Range(0, 64));
  sub->add_option("--bisection-steps", args->options.bisection_steps,
                  "relaxed-cone: halvings of the cone step that crossed the surface (default 24)")
      ->check(CLI::Range(0, 64));
  sub->add_option("--dig-epsilon", args->options.dig_epsilon,
                  "dig: least widening of a block's depth interval above its corners' (epsilon_1), fraction of the height range (default 0.1)")
      ->check(InRange(0.0, 1.0));
  sub->add_option("--dig-fallback", args->options.dig_fallback_texels,
                  "dig: a block whose corner rays are more than this many texels apart across the ray's path searches the "
                  "whole slab (default 8; 0: never)")
      ->check(NonNegative);
  sub->add_option("--tess-displacement", args->options.tess_displacement,
                  "tessellation: cut an edge per texel where the displacement along it departs from linear by more than this "
                  "fraction of the height range (default 0.02)")
      ->check(NonNegative);
  sub->add_option("--tess-normal-angle", args->options.tess_normal_angle,
                  "tessellation: at least one segment per this many degrees between an edge's end normals (default 5)")
      ->check(InRange(0.01, 360.0));
  sub->add_option("--tess-pixels", args->options.tess_pixels, "tessellation: no segment shorter than this on screen, pixels (default 2)")
      ->check(InRange(0.01, 1e6));
  sub->add_option("--tess-samples", args->options.tess_edge_samples,
                  "tessellation: intervals at which an edge's displacement is sampled for the departure test (default 8)")
      ->check(CLI::Range(1, 64));
  sub->add_option("--turntable", args->turntable,
                  "With --headless: N frames around the mesh (azimuth from --azimuth in steps of 360/N), written as "
                  "PNG_000.png, PNG_001.png, ... from --png PNG.png")
      ->check(CLI::Range(1, 3600));
  sub->add_flag("--compare", args->compare,
                "Measure the methods against a CPU ray-traced reference of the true displaced surface (off screen): wrong "
                "hits, RMSE/PSNR, texture fetches per pixel, draw time; --png writes the reference image");
  sub->add_option("--heatmaps", args->heatmaps, "With --compare: write DIR/<method>.png, texture fetches per pixel on a colour ramp");
  sub->add_option("--repetitions", args->repetitions, "With --compare: timed draws per method (the median is reported)")
      ->check(CLI::Range(1, 1000));
  sub->add_option("--uv-tolerance", args->uv_tolerance,
                  "With --compare: texels between a method's visible point and the reference's beyond which a pixel is a wrong hit")
      ->check(Positive);
  sub->add_option("--reference-edge", args->reference_edge,
                  "With --compare: longest UV edge of the reference's sub-triangles (over curved parts of the base; flat parts are intersected exactly), in texels")
      ->check(Positive);
  sub->add_option("--reference-triangles", args->reference_triangles,
                  "With --compare: cap on the reference's triangle and exact-cell count (coarser sub-triangles beyond it)")
      ->check(CLI::Range(size_t(1), size_t(1) << 30));
  sub->callback([&ctx, args, method_option] {
    const bool method_given = method_option->count() > 0;
    ctx.run = [&ctx, args, method_given](nlohmann::json& report, Progress&) {
      if (args->list) {
        // With --json the report alone (its "methods"), so that stdout stays one JSON value.
        if (!ctx.globals.json)
          for (const auto& m : preview_methods()) std::cout << m << '\n';
        report = {{"command", "preview"}, {"methods", preview_methods()}};
        return 0;
      }
      if (args->base.empty()) throw UsageError("preview: give the base mesh");
      if (args->maps.empty()) throw UsageError("preview: give --maps DIR (the folder meso bake wrote)");
      const auto& known = preview_methods();
      auto check_known = [&](const std::string& m) {
        if (std::find(known.begin(), known.end(), m) == known.end())
          throw UsageError("preview: unknown method '" + m + "' (see --list-methods)");
      };
      // --compare: the methods named (all = every method whose stream is there).
      std::vector<std::string> wanted;
      const bool all = args->compare && (!method_given || args->options.method == "all");
      if (args->compare && !all) {
        std::stringstream list(args->options.method);
        for (std::string m; std::getline(list, m, ',');) {
          if (m.empty()) continue;
          check_known(m);
          if (std::find(wanted.begin(), wanted.end(), m) == wanted.end()) wanted.push_back(m);
        }
        if (wanted.empty()) throw UsageError("preview: --method names no method");
      }
      if (!args->compare) {
        check_known(args->options.method);
        if (!args->heatmaps.empty()) throw UsageError("preview: --heatmaps needs --compare");
        if (args->headless && args->png.empty()) throw UsageError("preview: --headless needs --png FILE");
      }
      PreviewOptions o = args->options;
      parse_size(args->size, o.width, o.height);
      if (!args->pan.empty()) {
        o.camera.pan_x = args->pan[0];
        o.camera.pan_y = args->pan[1];
      }
      o.shade = args->shade == "uv" ? PreviewShade::uv : args->shade == "height" ? PreviewShade::height : PreviewShade::lit;
      o.shadows = args->shadows == "hard" ? PreviewShadows::hard : args->shadows == "soft" ? PreviewShadows::soft : PreviewShadows::none;
      if (args->turntable > 0 && (!args->headless || args->compare)) throw UsageError("preview: --turntable needs --headless (and no --compare)");
      if (args->frames > 0 && (args->headless || args->compare)) throw UsageError("preview: --frames is for the window (not --headless or --compare)");
      if (!args->headless && !args->compare && !args->png.empty() && args->frames == 0)
        throw UsageError("preview: --png needs --headless, --compare or (in the window) --frames N");
      nlohmann::json base_report;
      const Mesh base = load_mesh(ctx.globals, args->base, base_report);
      if (!has_uvs(base)) throw InputError(args->base, "has no texture coordinates; the maps cannot be applied");
      // Nothing to frame or draw (all vertices at one point, or on one line): the compare's
      // reference had said "need -nan" with a usage error, headless drew an empty frame.
      if (!has_surface_area(base)) throw InputError(args->base, "has no surface area (its faces are all degenerate): nothing to draw");
      const std::filesystem::path dir(args->maps);
      PreviewMaps maps;
      const std::filesystem::path streams_dir(args->streams.empty() ? args->maps : args->streams);
      {
        // The frame may not replace any file this run could read (a --png named after a
        // stream had replaced pyramid.exr with the frame).
        std::vector<std::string> inputs = {args->base, (dir / "displacement.exr").string(), (dir / "normal_ts.png").string()};
        for (const std::string& method : preview_methods())
          if (!required_stream(method).empty()) inputs.push_back((streams_dir / required_stream(method)).string());
        refuse_overwriting_input(args->png, inputs);
      }
      if (args->compare) {
        // Measured (one method, the demo's bricks): 4096² took 1.48 GB more than 1024²: about
        // 94 bytes per pixel (the reference's images and the GPU's frames).
        refuse_beyond_memory("preview --compare at --size " + args->size, 94.0 * o.width * o.height);
      }
      load_bake_maps(maps, dir);
      // Streams: those the method needs must be there; in a window, any that are there are
      // loaded so that every method can be switched to.
      for (const std::string& method : preview_methods()) {
        const std::string stream = required_stream(method);
        if (stream.empty()) continue;
        const std::filesystem::path file = streams_dir / stream;
        const std::string producer = stream.substr(0, stream.find('.'));  // "sdf", "cone", "vdm", "dstream", ...
        const bool needed = args->compare ? std::find(wanted.begin(), wanted.end(), method) != wanted.end() : o.method == method;
        // Loaded when there: in a window (every method can be switched to), and for --compare all.
        const bool optional = args->compare ? all : !args->headless;
        if (needed && !std::filesystem::exists(file)) {
          // The command that makes it: dstream samples the high mesh over this base, the
          // others read the height map.
          const std::string from = producer == "dstream" ? "--low " + args->base + " --high HIGH_MESH" : (dir / "displacement.exr").string();
          throw InputError(file.string(), "missing: method " + method + " needs it (meso streams " + producer + " " + from + " -o " +
                                              file.string() + ")");
        }
        if (!needed && (!optional || !std::filesystem::exists(file))) continue;
        try {
          load_stream(maps, base, method, file);
        } catch (const InputError& e) {
          if (needed) throw;
          warn(ctx.globals, std::string(e.what()) + " (" + method + " unavailable)");  // window or --compare all
          clear_stream(maps, method);
        }
      }
      if (!maps.vdm_weights.empty())
        if (const std::string w = vdm_relief_mismatch(maps.vdm_weights, base, (streams_dir / "vdm.exr").string()); !w.empty()) warn(ctx.globals, w);
      if (args->compare) {
        compare(ctx, *args, base, maps, o, all ? std::vector<std::string>{} : wanted, base_report, report);
        return 0;
      }
      if (!args->headless) {
        const WindowRun run = run_window(base, maps, o, args->frames);
        report = {{"command", "preview"}, {"method", o.method}, {"frames", run.frames}, {"median_frame_ms", run.median_ms}};
        if (!args->png.empty() && !run.last_frame.empty()) {
          OutputSet outputs;
          write_frame(run.last_frame, outputs.add(args->png), o.shade, maps.displacement);
          outputs.commit();
          report["png"] = args->png;
        }
        return 0;
      }
      if (args->turntable > 0) {
        // One context for every frame; all frames or none are written.
        HeadlessPreview preview(base, maps);
        const std::filesystem::path png(args->png);
        OutputSet outputs;
        std::vector<std::string> frames;
        const auto t0 = std::chrono::steady_clock::now();
        for (int k = 0; k < args->turntable; ++k) {
          PreviewOptions f = o;
          f.camera.azimuth = o.camera.azimuth + 360.0f * static_cast<float>(k) / static_cast<float>(args->turntable);
          char suffix[16];
          std::snprintf(suffix, sizeof suffix, "_%03d", k);
          const std::filesystem::path file = png.parent_path() / (png.stem().string() + suffix + png.extension().string());
          write_frame(preview.render(f), outputs.add(file), o.shade, maps.displacement);
          frames.push_back(file.string());
        }
        const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        outputs.commit();
        info(ctx.globals, "wrote " + std::to_string(frames.size()) + " frames " + frames.front() + " ... " + frames.back());
        report = {{"command", "preview"}, {"base", base_report}, {"method", o.method}, {"iterations", o.iterations},
                  {"width", o.width}, {"height", o.height}, {"frames", frames}, {"ms_total", ms}};
        return 0;
      }
      const auto t0 = std::chrono::steady_clock::now();
      Image img = render_headless(base, maps, o);
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      OutputSet outputs;
      write_frame(img, outputs.add(args->png), o.shade, maps.displacement);
      outputs.commit();
      info(ctx.globals, "wrote " + args->png);
      report = {{"command", "preview"}, {"base", base_report}, {"method", o.method}, {"iterations", o.iterations},
                {"width", o.width}, {"height", o.height}, {"png", args->png}, {"ms_total", ms}};
      return 0;
    };
  });
}

}  // namespace meso::cli
