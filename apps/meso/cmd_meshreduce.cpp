#include "cli.hpp"

#include "meso/core/error.hpp"
#include "meso/formats/atomic_file.hpp"
#include "meso/formats/mesh_io.hpp"
#include "meso/meshreduce/meshreduce.hpp"
#include "meso/meshreduce/surface_distance.hpp"

#include <cmath>
#include <cstdlib>

namespace meso::cli {

namespace {

// "0.01" (object units) or "0.5%" (of the bounding-box diagonal).
struct ErrorTarget {
  double value = 0;
  bool percent = false;
};

ErrorTarget parse_error(const std::string& text) {
  ErrorTarget t;
  std::string number = text;
  if (!number.empty() && number.back() == '%') {
    t.percent = true;
    number.pop_back();
  }
  char* end = nullptr;
  t.value = std::strtod(number.c_str(), &end);
  if (number.empty() || end != number.c_str() + number.size() || !std::isfinite(t.value) || t.value < 0)
    throw CLI::ValidationError("--error", text + ": expected a non-negative number, optionally followed by % (of the bounding-box diagonal)");
  return t;
}

}  // namespace

void add_meshreduce(CLI::App& app, Context& ctx) {
  struct Args {
    std::string input, output, error;
    size_t faces = 0;
    double ratio = 0;
    float max_normal_deviation = ReduceOptions{}.max_normal_deviation;
    float max_aspect_ratio = ReduceOptions{}.max_aspect_ratio;
    bool no_measure = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand("meshreduce", "Reduce a high-poly mesh to a base mesh (quadric edge collapse with optimal placement)");
  sub->add_option("input", args->input, "Input mesh (OBJ, FBX, glTF, PLY, OFF, DAE, ...)")->required();
  sub->add_option("-o,--output", args->output, "Output mesh (.obj, .ply, .gltf, .glb)")->required();
  auto* faces = sub->add_option("--faces", args->faces, "Target face count")->check(CLI::PositiveNumber);
  auto* ratio = sub->add_option("--ratio", args->ratio, "Target as a fraction of the input's faces")
                    ->check(CLI::Range(0.0, 1.0) & Finite);
  auto* error = sub->add_option("--error", args->error,
                                "Target: the largest geometric error (two-sided, sampled), in object units, or in % of the "
                                "bounding-box diagonal with a % sign (0.5%); reduces as far as the error stays within it");
  faces->excludes(ratio);
  faces->excludes(error);
  ratio->excludes(error);
  sub->add_option("--max-normal-deviation", args->max_normal_deviation,
                  "Largest angle in degrees between an output face's normal and the input faces it replaced (180: off)")
      ->check(CLI::Range(0.0f, 180.0f) & Finite)
      ->capture_default_str();
  sub->add_option("--max-aspect-ratio", args->max_aspect_ratio,
                  "Refuse collapses that create a triangle with a larger aspect ratio (longest edge^2 * sqrt(3) / (4 area): "
                  "1 = equilateral) unless the faces replaced had one; 0: off")
      ->check(CLI::NonNegativeNumber & Finite)
      ->capture_default_str();
  sub->add_flag("--no-measure", args->no_measure, "Skip measuring the Hausdorff and RMS distance between input and output");
  sub->callback([&ctx, args, faces, ratio, error] {
    if (faces->count() + ratio->count() + error->count() != 1)
      throw CLI::ValidationError("meshreduce", "give exactly one target: --faces N, --ratio R or --error E");
    ErrorTarget error_target;
    if (error->count()) error_target = parse_error(args->error);
    ctx.run = [&ctx, args, error_target](nlohmann::json& report, Progress& progress) {
      if (!is_writable_mesh_extension(args->output)) throw UsageError(args->output + ": unknown mesh extension (use .obj, .ply, .gltf or .glb)");
      nlohmann::json in_report;
      const Mesh input = load_mesh(ctx.globals, args->input, in_report);
      const double diagonal = bounding_box(input).diagonal();
      ReduceOptions o;
      o.max_normal_deviation = args->max_normal_deviation;
      o.max_aspect_ratio = args->max_aspect_ratio;
      const bool by_error = !args->error.empty();
      if (by_error) {
        o.max_error = error_target.percent ? error_target.value * 0.01 * diagonal : error_target.value;
      } else {
        o.target_faces = args->faces ? args->faces
                                     : static_cast<size_t>(std::llround(args->ratio * static_cast<double>(input.n_faces())));
        if (o.target_faces >= input.n_faces())
          warn(ctx.globals, "target " + std::to_string(o.target_faces) + " faces is not below the input's " +
                                std::to_string(input.n_faces()) + ": the mesh is written unchanged");
      }
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
                {"seconds", r.seconds},
                {"bounding_box_diagonal", diagonal},
                {"rejected", r.rejected}};
      if (by_error) {
        report["target_error"] = o.max_error;
        report["tracked_error"] = r.tracked_error;
      }
      if (!args->no_measure) {
        const SurfaceDistance d = measure_surface_distance(input, out);
        const double pct = diagonal > 0 ? 100.0 / diagonal : 0.0;
        report["error"] = {{"hausdorff", d.hausdorff},
                           {"hausdorff_percent", d.hausdorff * pct},
                           {"rms", d.rms},
                           {"rms_percent", d.rms * pct},
                           {"input_to_output", d.forward},
                           {"output_to_input", d.backward},
                           {"samples", d.samples_a + d.samples_b},
                           {"seconds", d.seconds}};
        info(ctx.globals, "Hausdorff distance " + std::to_string(d.hausdorff) + " (" +
                              std::to_string(diagonal > 0 ? 100.0 * d.hausdorff / diagonal : 0.0) + " % of the diagonal)");
      }
      return 0;
    };
  });
}

}  // namespace meso::cli
