#include "cli.hpp"

#include "meso/core/error.hpp"
#include "meso/formats/atomic_file.hpp"
#include "meso/formats/image_io.hpp"
#include "meso/formats/mesh_io.hpp"
#include "meso/uvpack/uv_check.hpp"
#include "meso/uvpack/uv_density.hpp"
#include "meso/uvpack/uv_pack.hpp"
#include "meso/uvpack/uv_unwrap.hpp"

#include <algorithm>
#include <numeric>
#include <chrono>
#include <cmath>
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

// UV area per chart (uv_charts() order), in units of the unit square.
std::vector<double> chart_uv_areas(const Mesh& mesh) {
  size_t count = 0;
  const std::vector<int> chart = uv_charts(mesh, &count);
  std::vector<double> area(count, 0.0);
  for (auto f : mesh.faces()) area[static_cast<size_t>(chart[static_cast<size_t>(f.idx())])] += 0.5 * std::abs(static_cast<double>(uv_double_area(mesh, f)));
  return area;
}

}  // namespace

void add_uvpack(CLI::App& app, Context& ctx) {
  CLI::App* uv = app.add_subcommand("uvpack", "Check UV mappings for uniqueness; pack charts into an atlas");
  uv->require_subcommand(1);
  struct Args {
    std::string input, overlay, report;
    int size = 1024;
    double padding = 0;
    int mip_safe = -1;
    bool wrap = false, clamp = false;
    std::vector<std::string> fail_on;
  };
  auto args = std::make_shared<Args>();
  CLI::App* check = uv->add_subcommand("check", "Find UV overlaps (exactly), texels shared at a resolution, flips, padding");
  check->add_option("input", args->input, "Mesh with UVs")->required();
  check->add_option("--size", args->size, "Texture size in texels per side")->check(CLI::Range(1, 32768));
  check->add_option("--padding", args->padding, "Texels charts must keep between them (0: not checked)")
      ->check(NonNegative);
  check->add_option("--mip-safe", args->mip_safe,
                    "Also check that no texel of MIP levels 0..K that a chart's bilinear lookups read holds another chart's values "
                    "(after the bake's dilation; box-filtered levels; --size a multiple of 2^K)")
      ->check(CLI::Range(0, 14));
  auto* check_wrap = check->add_flag("--wrap", args->wrap,
                                     "The texture is sampled with repeat addressing: padding and MIP reads are also checked across its borders");
  check->add_flag("--clamp", args->clamp, "The texture is sampled with clamp-to-edge addressing (the default)")->excludes(check_wrap);
  check->add_option("-o,--overlay", args->overlay, "Overlay PNG (RGBA): red = shared texels, blue = used once")->check(ImageOutput);
  check->add_option("--report", args->report, "JSON report file");
  check->add_option("--fail-on", args->fail_on, "Exit 1 when any of these is found: overlap,shared,flipped,degenerate,outside,padding,mip")
      ->delimiter(',')
      ->check(CLI::IsMember({"overlap", "shared", "flipped", "degenerate", "outside", "padding", "mip"}));
  check->callback([&ctx, args] {
    ctx.run = [&ctx, args](nlohmann::json& report, Progress&) {
      refuse_overwriting_input(args->overlay, {args->input});
      refuse_overwriting_input(args->report, {args->input});
      nlohmann::json in_report;
      const Mesh mesh = load_mesh(ctx.globals, args->input, in_report);
      if (!has_uvs(mesh)) throw InputError(args->input, "has no texture coordinates to check");
      UvCheckOptions o;
      o.size = args->size;
      o.padding = args->padding;
      o.overlay = !args->overlay.empty();
      o.mip_safe = args->mip_safe;
      o.wrap = args->wrap;
      if (o.mip_safe >= 0 && o.size % (1 << o.mip_safe) != 0)
        throw UsageError("--mip-safe " + std::to_string(o.mip_safe) + " needs --size to be a multiple of " + std::to_string(1 << o.mip_safe));
      if (o.mip_safe < 0 && std::find(args->fail_on.begin(), args->fail_on.end(), "mip") != args->fail_on.end())
        throw UsageError("--fail-on mip needs --mip-safe K");
      const UvCheckReport r = check_uv_mapping(mesh, o);
      nlohmann::json gaps = nlohmann::json::array();
      for (const auto& g : r.padding_violations) gaps.push_back({{"charts", {g.chart_a, g.chart_b}}, {"distance", g.distance}});
      report = {{"command", "uvpack check"},
                {"input", in_report},
                {"size", r.width},
                {"padding", o.padding},
                {"addressing", o.wrap ? "wrap" : "clamp"},
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
                {"utilization", r.utilization},
                {"texel_coverage", r.texel_coverage}};
      if (o.mip_safe >= 0) {
        nlohmann::json mips = nlohmann::json::array();
        for (const auto& m : r.mip_violations) mips.push_back({{"level", m.level}, {"chart", m.chart}, {"reads", m.reads}, {"texels", m.texels}});
        report["mip_safe"] = o.mip_safe;
        report["mip_safe_levels"] = r.mip_safe_levels;
        report["mip_violations"] = mips;
      }
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
                                                 {"padding", !r.padding_violations.empty()},
                                                 {"mip", !r.mip_violations.empty()}};
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
    bool quarter_turns = false;
    bool clamp = false;
    bool unwrap = false;
    std::string unwrap_method = "lscm";
    UvUnwrapOptions unwrap_options;
    std::string density;
    double density_clamp = 2.0;
    std::string quality = "balanced";
  };
  auto pack_args = std::make_shared<PackArgs>();
  CLI::App* pack = uv->add_subcommand("pack", "Pack the mesh's UV charts into a square atlas with padding (one common scale; charts turned by quarter turns of their own or their minimum-area orientation)");
  pack->add_option("input", pack_args->input, "Mesh (its UV charts are kept as they are, unless --unwrap or it has no UVs)")->required();
  pack->add_option("-o,--output", pack_args->output, "Output mesh (.obj, .ply, .gltf, .glb)")->required();
  pack->add_option("--size", pack_args->options.size, "Atlas size in texels per side")->check(CLI::Range(1, 16384))->capture_default_str();
  pack->add_option("--padding", pack_args->options.padding, "Texels between charts (and half of it, rounded up, to the border unless --clamp)")->check(CLI::Range(0, 256))->capture_default_str();
  auto* pack_wrap = pack->add_flag("--wrap", "The atlas is sampled with repeat addressing: charts keep half the padding (rounded up) "
                                               "to its border, so that they are the padding apart across the wrap (the default)");
  pack->add_flag("--clamp", pack_args->clamp, "The atlas is sampled with clamp-to-edge addressing: charts may touch its border")
      ->excludes(pack_wrap);
  pack->add_flag("--no-rotate", pack_args->no_rotate, "Keep every chart's orientation");
  pack->add_flag("--quarter-turns", pack_args->quarter_turns,
                 "Turn charts by multiples of 90 degrees of their input orientation only (by default each chart's minimum-area "
                 "orientation is tried too)");
  pack->add_option("--quality", pack_args->quality,
                   "Search effort: fast (2 orientations, scale within 4 %), balanced (4 orientations, 1 %), best (also 3 chart orders, 0.25 %)")
      ->check(CLI::IsMember({"fast", "balanced", "best"}))
      ->capture_default_str();
  pack->add_option("--mip-safe", pack_args->options.mip_safe,
                   "Keep charts apart so that no texel of MIP levels 0..K their bilinear lookups read holds another chart's values "
                   "(box-filtered levels of a map dilated as meso bake does; about 4 * 2^K texels between charts; --size a multiple of 2^K)")
      ->check(CLI::Range(0, 14));
  pack->add_option("--density", pack_args->density,
                   "A map in the mesh's current UV layout (e.g. a first bake's displacement or normal map): charts are scaled by the "
                   "detail it holds (RMS gradient), within --density-clamp, so detailed charts get more texels");  // a missing file: exit 3 on reading, as every input
  pack->add_option("--density-clamp", pack_args->density_clamp, "Largest growth or shrink of a chart's linear scale by --density")
      ->check(InRange(1.0, 16.0))
      ->capture_default_str();
  pack->add_flag("--unwrap", pack_args->unwrap, "Make new charts (normal-cone charts flattened by LSCM or ARAP) instead of the mesh's UVs; implied when it has none");
  pack->add_option("--unwrap-method", pack_args->unwrap_method, "Flattening: lscm (conformal, fast) or arap (as-rigid-as-possible)")
      ->check(CLI::IsMember({"lscm", "arap"}))
      ->capture_default_str();
  pack->add_option("--max-stretch", pack_args->unwrap_options.max_stretch, "Largest L2 stretch of a chart (1 = isometric); charts above it are split")
      ->check(InRange(1.0, 1e6))
      ->capture_default_str();
  pack->add_option("--chart-angle", pack_args->unwrap_options.max_chart_angle, "Degrees a face normal may deviate from its chart's mean normal")
      ->check(InRange(1.0, 179.0))
      ->capture_default_str();
  pack->add_option("--max-chart-faces", pack_args->unwrap_options.max_chart_faces, "Faces per chart at most (0: no cap)")
      ->check(NonNegative)
      ->capture_default_str();
  pack->callback([&ctx, pack_args] {
    ctx.run = [&ctx, pack_args](nlohmann::json& report, Progress&) {
      if (!is_writable_mesh_extension(pack_args->output)) throw UsageError("--output " + pack_args->output + ": unsupported mesh extension");
      refuse_overwriting_input(pack_args->output, {pack_args->input});
      nlohmann::json in_report;
      Mesh mesh = load_mesh(ctx.globals, pack_args->input, in_report);
      nlohmann::json unwrap_report;
      if (pack_args->unwrap || !has_uvs(mesh)) {
        if (mesh.n_faces() == 0) throw InputError(pack_args->input, "has no faces to unwrap");
        // Nothing to flatten: the unwrap would leave UVs without area, and the message below
        // would then suggest --unwrap to a user who gave it.
        if (!has_surface_area(mesh)) throw InputError(pack_args->input, "has no surface area (its faces are all degenerate): nothing to unwrap");
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
      o.min_area_orientation = !pack_args->quarter_turns;
      o.quality = pack_args->quality == "fast" ? PackQuality::fast : pack_args->quality == "best" ? PackQuality::best : PackQuality::balanced;
      std::vector<ChartDetail> detail;
      std::vector<double> area_before;
      if (!pack_args->density.empty()) {
        if (!unwrap_report.is_null()) throw UsageError("--density measures the mesh's own UV layout; it cannot be used with --unwrap or a mesh without UVs");
        const Image map = read_image(pack_args->density);
        if (map.empty()) throw InputError(pack_args->density, "is an empty image");
        detail = measure_chart_detail(mesh, map, pack_args->density_clamp);
        for (const auto& d : detail) o.chart_scale.push_back(d.scale);
        area_before = chart_uv_areas(mesh);
      }
      if (o.mip_safe >= 0 && o.size % (1 << o.mip_safe) != 0)
        throw UsageError("--mip-safe " + std::to_string(o.mip_safe) + " needs --size to be a multiple of " + std::to_string(1 << o.mip_safe));
      o.wrap = !pack_args->clamp;
      if (2 * atlas_border_margin(o) >= o.size) {
        // Name what set the margin: the padding, or --mip-safe's wider one.
        UvPackOptions padding_only = o;
        padding_only.mip_safe = -1;
        const std::string by = atlas_border_margin(o) > atlas_border_margin(padding_only)
                                   ? "--mip-safe " + std::to_string(o.mip_safe) + " (" + std::to_string(1 << o.mip_safe) +
                                         " texels from each side under --wrap; --clamp keeps none)"
                                   : "--padding " + std::to_string(o.padding);
        throw UsageError(by + " leaves no texel inside a " + std::to_string(o.size) + "-texel atlas");
      }
      {
        const std::vector<double> areas = chart_uv_areas(mesh);
        if (!(std::accumulate(areas.begin(), areas.end(), 0.0) > 0))
          throw InputError(pack_args->input, "its UVs have no area (all at one point or on a line): nothing to pack; --unwrap makes new ones");
      }
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
      verify.mip_safe = o.mip_safe;
      verify.wrap = o.wrap;  // measured as the atlas will be sampled
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
                {"addressing", o.wrap ? "wrap" : "clamp"},
                {"border_margin", atlas_border_margin(o)},
                {"rotate", o.rotate},
                {"min_area_orientation", o.rotate && o.min_area_orientation},
                {"quality", pack_args->quality},
                {"charts", r.charts},
                {"scale", r.scale},
                {"utilization", r.utilization},
                {"texel_coverage", c.texel_coverage},  // the checker's, as formats.md says (the packer's includes its rounding margin)
                {"attempts", r.attempts},
                {"seconds", pack_seconds},
                {"check", {{"overlapping_faces", c.overlapping_faces.size()},
                           {"shared_texel_faces", c.shared_texel_faces.size()},
                           {"padding_violations", c.padding_violations.size()},
                           {"outside_faces", c.outside_faces.size()},
                           {"flipped_faces", c.flipped_faces.size()}}}};
      if (o.mip_safe >= 0) {
        report["mip_safe"] = o.mip_safe;
        report["check"]["mip_violations"] = c.mip_violations.size();
      }
      if (!unwrap_report.is_null()) report["unwrap"] = unwrap_report;
      if (!detail.empty()) {
        const std::vector<double> area_after = chart_uv_areas(mesh);
        const double texels = static_cast<double>(o.size) * o.size;
        nlohmann::json per_chart = nlohmann::json::array();
        for (size_t k = 0; k < detail.size(); ++k)
          per_chart.push_back({{"chart", detail[k].chart},
                               {"detail", detail[k].detail},
                               {"scale", detail[k].scale},
                               {"texels_before", area_before[k] * texels},
                               {"texels_after", area_after[k] * texels}});
        report["density"] = {{"map", pack_args->density}, {"clamp", pack_args->density_clamp}, {"per_chart", per_chart}};
      }
      return 0;
    };
  });
}

}  // namespace meso::cli
