#include "cli.hpp"

#include "meso/core/error.hpp"
#include "meso/formats/atomic_file.hpp"
#include "meso/formats/mesh_io.hpp"
#include "meso/meshreduce/meshreduce.hpp"
#include "meso/meshreduce/progressive.hpp"
#include "meso/meshreduce/surface_distance.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>

namespace meso::cli {

namespace {

// "0.01" (object units) or "0.5%" (of the bounding-box diagonal).
struct ErrorTarget {
  double value = 0;
  bool percent = false;
};

ErrorTarget parse_error(const std::string& text, const char* option = "--error") {
  ErrorTarget t;
  std::string number = text;
  if (!number.empty() && number.back() == '%') {
    t.percent = true;
    number.pop_back();
  }
  char* end = nullptr;
  t.value = std::strtod(number.c_str(), &end);
  if (number.empty() || end != number.c_str() + number.size() || !std::isfinite(t.value) || t.value < 0)
    throw CLI::ValidationError(option, text + ": expected a non-negative number, optionally followed by % (of the bounding-box diagonal)");
  return t;
}

// `measured`: the distance reduce_mesh already measured (--quality best), else measured here.
void add_distance(nlohmann::json& report, Globals& g, const Mesh& input, const Mesh& out, double diagonal,
                  const std::optional<SurfaceDistance>& measured) {
  // The measure samples and queries surfaces: without area there is none (the fields had
  // come out null, with a warning that read like a failure). The report then has no `error`,
  // as with --no-measure.
  for (const Mesh* m : {&input, &out})
    if (!has_surface_area(*m)) {
      warn(g, std::string("no distance measured: the ") + (m == &input ? "input" : "output") + " has no surface area (its faces are all degenerate)");
      return;
    }
  const SurfaceDistance d = measured ? *measured : measure_surface_distance(input, out);
  const double pct = diagonal > 0 ? 100.0 / diagonal : 0.0;
  report["error"] = {{"hausdorff", d.hausdorff},
                     {"hausdorff_percent", d.hausdorff * pct},
                     {"rms", d.rms},
                     {"rms_percent", d.rms * pct},
                     {"input_to_output", d.forward},
                     {"output_to_input", d.backward},
                     {"samples", d.samples_a + d.samples_b},
                     {"seconds", d.seconds}};
  if (std::isfinite(d.hausdorff) && std::isfinite(d.hausdorff * pct))
    info(g, "Hausdorff distance " + short_number(d.hausdorff) + " (" + short_number(d.hausdorff * pct) + " % of the diagonal)");
  else
    warn(g, "the Hausdorff distance could not be measured (it came out non-finite)");
}

// The regions of the output farther than `threshold` from the input (object units).
void add_regions(nlohmann::json& report, Globals& g, const Mesh& input, const Mesh& out, double threshold, double diagonal) {
  const std::vector<double> d = face_distances(input, out);
  const std::vector<ErrorRegion> regions = error_regions(out, d, threshold);
  const double pct = diagonal > 0 ? 100.0 / diagonal : 0.0;
  size_t over = 0;
  for (const ErrorRegion& r : regions) over += r.faces;
  nlohmann::json list = nlohmann::json::array();
  for (size_t i = 0; i < regions.size() && i < 100; ++i) {
    const ErrorRegion& r = regions[i];
    list.push_back({{"faces", r.faces},
                    {"max_distance", r.max_distance},
                    {"max_percent", r.max_distance * pct},
                    {"area", r.area},
                    {"centroid", {r.centroid[0], r.centroid[1], r.centroid[2]}},
                    {"first_face", r.first_face}});
  }
  report["regions"] = {{"threshold", threshold}, {"count", regions.size()}, {"faces", over}, {"largest", list}};
  if (!regions.empty())
    warn(g, std::to_string(regions.size()) + " regions (" + std::to_string(over) + " faces) are farther than " + short_number(threshold) +
                " from the input; the worst, " + short_number(regions[0].max_distance) + ", around face " +
                std::to_string(regions[0].first_face) + " (see --json's regions)");
}

// Each name once, in order of first appearance (a file may name several groups alike).
std::string joined(const std::vector<std::string>& names) {
  std::string s;
  for (size_t i = 0; i < names.size(); ++i)
    if (std::find(names.begin(), names.begin() + static_cast<std::ptrdiff_t>(i), names[i]) == names.begin() + static_cast<std::ptrdiff_t>(i))
      s += (s.empty() ? "" : ", ") + ("'" + names[i] + "'");
  return s;
}

}  // namespace

void add_meshreduce(CLI::App& app, Context& ctx) {
  struct Args {
    std::string input, output, error, progressive, from_progressive, regions;
    size_t faces = 0;
    double ratio = 0;
    float max_normal_deviation = ReduceOptions{}.max_normal_deviation;
    float max_aspect_ratio = ReduceOptions{}.max_aspect_ratio;
    bool no_measure = false, lock_boundary = false;
    std::vector<std::string> lock_groups;
    std::string quality = "balanced";
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand("meshreduce", "Reduce a high-poly mesh to a base mesh (quadric edge collapse with optimal placement)");
  auto* input_opt = sub->add_option("input", args->input, "Input mesh (OBJ, FBX, glTF, PLY, OFF, DAE, ...); not with --from-progressive");
  sub->add_option("-o,--output", args->output, "Output mesh (.obj, .ply, .gltf, .glb)")->required();
  auto* faces = sub->add_option("--faces", args->faces, "Target face count")->check(Positive);
  auto* ratio = sub->add_option("--ratio", args->ratio, "Target as a fraction of the input's faces")
                    ->check(InRange(0.0, 1.0, true));
  auto* error = sub->add_option("--error", args->error,
                                "Target: the largest geometric error (two-sided, sampled), in object units, or in % of the "
                                "bounding-box diagonal with a % sign (0.5%); reduces as far as the error stays within it");
  faces->excludes(ratio);
  faces->excludes(error);
  ratio->excludes(error);
  sub->add_option("--max-normal-deviation", args->max_normal_deviation,
                  "Largest angle in degrees between an output face's normal and the input faces it replaced (180: off)")
      ->check(InRange(0.0, 180.0))
      ->capture_default_str();
  sub->add_option("--max-aspect-ratio", args->max_aspect_ratio,
                  "Refuse collapses that create a triangle with a larger aspect ratio (longest edge^2 * sqrt(3) / (4 area): "
                  "1 = equilateral) unless the faces replaced had one; 0: off")
      ->check(NonNegative)
      ->capture_default_str();
  auto* lock_boundary =
      sub->add_flag("--lock-boundary", args->lock_boundary, "Boundary vertices never move and are never removed (boundary edges never collapse)");
  auto* lock_group = sub->add_option("--lock-group", args->lock_groups,
                                     "Faces of this group (input mesh/node name) are not simplified: their vertices never move "
                                     "and are never removed; repeatable")
                         ->expected(1)
                         ->allow_extra_args(false)  // one name per --lock-group: the input mesh stays positional
                         ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  auto* progressive = sub->add_option("--progressive", args->progressive,
                                      "Also write the progressive mesh (.pm): the input and every collapse, from which "
                                      "--from-progressive rebuilds any level of detail between input and output");
  auto* from = sub->add_option("--from-progressive", args->from_progressive,
                               "Instead of reducing an input mesh, rebuild the level of detail with --faces N or --ratio R "
                               "from a .pm file written by --progressive");
  from->excludes(input_opt);
  from->excludes(error);
  from->excludes(progressive);
  from->excludes(lock_boundary);
  from->excludes(lock_group);
  auto* quality = sub->add_option("--quality", args->quality,
                                  "Speed against error: fast (lazy heap keys: queued edges are re-evaluated only when "
                                  "popped; fewer evaluations, not strictly cheapest-first: errors about those of balanced), balanced (every edge around a collapse "
                                  "re-evaluated at once), best (balanced with area-weighted and with uniform face quadrics, each also with its free vertices "
                                  "fitted to the input, keeping the nearest of the four by measured Hausdorff distance: two reductions, two fits and four "
                                  "measurements); every preset keeps every guarantee")
                      ->check(CLI::IsMember({"fast", "balanced", "best"}))
                      ->capture_default_str();
  from->excludes(quality);
  sub->add_flag("--no-measure", args->no_measure, "Skip measuring the Hausdorff and RMS distance between input and output");
  auto* regions = sub->add_option("--report-regions", args->regions,
                                  "Report the regions of the output farther from the input than E (object units, or % of the "
                                  "diagonal), both ways, as connected groups of faces (default with --error: its target)");
  regions->excludes(from);
  sub->callback([&ctx, args, faces, ratio, error, from] {
    if (faces->count() + ratio->count() + error->count() != 1)
      throw CLI::ValidationError("meshreduce", "give exactly one target: --faces N, --ratio R or --error E");
    if (args->input.empty() && !from->count())
      throw CLI::ValidationError("meshreduce", "give an input mesh (or --from-progressive FILE)");
    ErrorTarget error_target, regions_target;
    if (error->count()) error_target = parse_error(args->error);
    if (!args->regions.empty()) regions_target = parse_error(args->regions, "--report-regions");
    if (from->count()) {
      ctx.run = [&ctx, args](nlohmann::json& report, Progress&) {
        if (!is_writable_mesh_extension(args->output))
          throw UsageError(args->output + ": unknown mesh extension (use .obj, .ply, .gltf or .glb)");
        refuse_overwriting_input(args->output, {args->from_progressive});
        const auto t0 = std::chrono::steady_clock::now();
        const ProgressiveMesh pm = read_progressive(args->from_progressive);
        const size_t n = pm.input_faces();
        const size_t target =
            args->faces ? args->faces : static_cast<size_t>(std::llround(args->ratio * static_cast<double>(n)));
        if (target < pm.final_faces)
          warn(ctx.globals, "target " + std::to_string(target) + " faces is below the progressive mesh's last level (" +
                                std::to_string(pm.final_faces) + " faces): wrote that level");
        size_t replayed = 0;
        const Mesh out = progressive_level(pm, target, &replayed);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        OutputSet outputs;
        write_mesh(out, outputs.add(args->output));
        outputs.commit();
        info(ctx.globals, "wrote " + args->output + " (" + std::to_string(out.n_faces()) + " faces, " + std::to_string(replayed) +
                              " of " + std::to_string(pm.collapses.size()) + " collapses)");
        report = {{"command", "meshreduce"},
                  {"progressive", {{"path", args->from_progressive},
                                   {"input_vertices", pm.positions.size()},
                                   {"input_faces", n},
                                   {"final_faces", pm.final_faces},
                                   {"collapses", pm.collapses.size()}}},
                  {"output", {{"path", args->output}, {"vertices", out.n_vertices()}, {"faces", out.n_faces()}}},
                  {"target_faces", target},
                  {"target_reached", out.n_faces() <= target},
                  {"collapses", replayed},
                  {"seconds", seconds}};
        if (!args->no_measure) {
          const Mesh input = progressive_base_input(pm);
          const double diagonal = bounding_box(input).diagonal();
          report["bounding_box_diagonal"] = diagonal;
          add_distance(report, ctx.globals, input, out, diagonal, std::nullopt);
        }
        return 0;
      };
      return;
    }
    ctx.run = [&ctx, args, error_target, regions_target](nlohmann::json& report, Progress& progress) {
      if (!is_writable_mesh_extension(args->output)) throw UsageError(args->output + ": unknown mesh extension (use .obj, .ply, .gltf or .glb)");
      if (!args->progressive.empty() && std::filesystem::path(args->progressive) == std::filesystem::path(args->output))
        throw UsageError(args->progressive + ": --progressive and -o name the same file");
      refuse_overwriting_input(args->output, {args->input});
      refuse_overwriting_input(args->progressive, {args->input});
      nlohmann::json in_report;
      const Mesh input = load_mesh(ctx.globals, args->input, in_report);
      const auto& names = group_names(input);
      for (const auto& g : args->lock_groups)
        if (std::find(names.begin(), names.end(), g) == names.end())
          throw UsageError("--lock-group '" + g + "': " + args->input + " has no face group of that name (groups: " + joined(names) + ")");
      const double diagonal = bounding_box(input).diagonal();
      ReduceOptions o;
      o.max_normal_deviation = args->max_normal_deviation;
      o.max_aspect_ratio = args->max_aspect_ratio;
      o.lock_boundary = args->lock_boundary;
      o.lock_groups = args->lock_groups;
      o.quality = args->quality == "fast" ? ReduceQuality::fast : args->quality == "best" ? ReduceQuality::best : ReduceQuality::balanced;
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
      ProgressiveMesh pm;
      const bool record = !args->progressive.empty();
      if (record && o.quality == ReduceQuality::best)
        warn(ctx.globals, "--progressive: --quality best skips its surface fit, so that the record's last level is the output");
      else if (o.quality == ReduceQuality::best && o.max_normal_deviation < 180.0f)
        warn(ctx.globals, "--max-normal-deviation: --quality best skips its surface fit, which does not check that bound");
      const Mesh out = reduce_mesh(input, o, &r, progress, record ? &pm : nullptr);
      const bool locked = o.lock_boundary || !o.lock_groups.empty();
      if (!r.target_reached)
        warn(ctx.globals, "stopped at " + std::to_string(r.output_faces) + " faces, not " + std::to_string(o.target_faces) +
                              (locked ? ": the locks (" + std::to_string(r.locked_vertices) +
                                            " vertices) and the constraints allow no further collapse"
                                      : ": no further collapse keeps the UV charts, boundaries and orientation intact"));
      if (r.flipped_faces > 0)
        warn(ctx.globals, std::to_string(r.flipped_faces) + " output faces face away from the input under them after " +
                              std::to_string(r.passes) + " passes of the reduction");
      OutputSet outputs;
      write_mesh(out, outputs.add(args->output));
      if (record) write_progressive(pm, outputs.add(args->progressive));
      outputs.commit();
      info(ctx.globals, "wrote " + args->output + " (" + std::to_string(r.output_faces) + " faces)");
      report = {{"command", "meshreduce"},
                {"input", in_report},
                {"output", {{"path", args->output}, {"vertices", r.output_vertices}, {"faces", r.output_faces}}},
                {"target_faces", o.target_faces},
                {"target_reached", r.target_reached},
                {"collapses", r.collapses},
                {"passes", r.passes},
                {"flipped_faces", r.flipped_faces},
                {"seconds", r.seconds},
                {"quality", args->quality},
                {"bounding_box_diagonal", diagonal},
                {"rejected", r.rejected}};
      if (locked) report["locked_vertices"] = r.locked_vertices;
      if (o.quality == ReduceQuality::best)
        report["best"] = {{"planes", r.planes},
                          {"hausdorff_area", r.candidate_hausdorff.at(0)},
                          {"hausdorff_uniform", r.candidate_hausdorff.at(1)},
                          {"fitted", r.fitted}};
      if (o.quality == ReduceQuality::best && r.fitted_hausdorff.size() == 2) {
        report["best"]["hausdorff_area_fitted"] = r.fitted_hausdorff[0];
        report["best"]["hausdorff_uniform_fitted"] = r.fitted_hausdorff[1];
      }
      if (record)
        report["progressive"] = {{"path", args->progressive},
                                 {"collapses", pm.collapses.size()},
                                 {"bytes", std::filesystem::file_size(args->progressive)}};
      if (by_error) {
        report["target_error"] = o.max_error;
        report["tracked_error"] = r.tracked_error;
      }
      if (!args->no_measure) add_distance(report, ctx.globals, input, out, diagonal, r.distance);
      if (!args->regions.empty())
        add_regions(report, ctx.globals, input, out, regions_target.percent ? regions_target.value * 0.01 * diagonal : regions_target.value, diagonal);
      else if (by_error)
        add_regions(report, ctx.globals, input, out, o.max_error, diagonal);
      return 0;
    };
  });
}

}  // namespace meso::cli
