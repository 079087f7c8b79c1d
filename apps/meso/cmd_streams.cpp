#include "cli.hpp"

#include "meso/core/error.hpp"
#include "meso/formats/atomic_file.hpp"
#include "meso/formats/image_io.hpp"
#include "meso/streams/cone_map.hpp"
#include "meso/streams/dilation_erosion.hpp"
#include "meso/streams/distance_field.hpp"
#include "meso/streams/pyramid.hpp"
#include "meso/streams/vdm.hpp"
#include "meso/bake/curvature.hpp"
#include "meso/bake/displacement_stream.hpp"

#include <algorithm>
#include <limits>
#include <chrono>
#include <functional>
#include <cstdio>
#include <filesystem>
#include <cmath>
#include <sstream>
#include <utility>

namespace meso::cli {

namespace {

// The largest --relief of streams vdm, in units of u: a height range ten times the map's
// width is no displacement map, and the table's cost grows with it (a grazing ray crosses up
// to relief * tan(theta) tiles of a tiling map): a 64² map with one spike, default angles,
// took 1.1 s at relief 1, 20 s at 100 and 168 s at 1000.
constexpr double kVdmMaxRelief = 10;

// The most directions (--theta x --phi x curvatures) streams vdm compresses.
constexpr double kVdmMaxDirections = 4096;

// What every stream subcommand takes: the height map, the output, the border rule, precision.
struct StreamArgs {
  std::string input, output;
  bool wrap = false, clamp = false, half = false;
};

CLI::App* add_stream_subcommand(CLI::App* streams, const std::string& name, const std::string& what,
                                const std::string& output_help, StreamArgs& a) {
  CLI::App* sub = streams->add_subcommand(name, what);
  sub->add_option("height", a.input, "Height map: EXR/PNG/TIFF, channel 0 (e.g. meso bake's displacement.exr)")->required();
  // Every stream is an EXR (docs/formats.md): say so before the work, not when writing.
  sub->add_option("-o,--output", a.output, output_help)->required()->check(CLI::Validator(
      [](std::string& path) -> std::string {
        return lower_extension(path) == ".exr" ? std::string() : path + ": streams are written as EXR (use a .exr name)";
      },
      "EXR"));
  auto* wrap = sub->add_flag("--wrap", a.wrap, "The map tiles: lookups wrap around the borders");
  sub->add_flag("--clamp", a.clamp, "Lookups clamp to the edge texels (the default)")->excludes(wrap);
  sub->add_flag("--half", a.half, "Store half floats instead of float32");
  return sub;
}

HeightField load_height_field(const StreamArgs& a) {
  refuse_overwriting_input(a.output, {a.input});
  const Image image = read_image(a.input);
  // A map that states its mapping to object units must state a usable one: ignored, the map's
  // raw values would be taken for heights without a word.
  const std::string problem = height_mapping_problem(image.metadata);
  if (!problem.empty()) throw InputError(a.input, problem + " (the map's mapping to object units)");
  HeightField field = make_height_field(image, a.wrap ? Border::wrap : Border::clamp);
  // Finite heights whose span is not (e.g. -3e38 and 3e38) cannot be normalised in float.
  if (!std::isfinite(field.scale)) throw InputError(a.input, "its heights span more than the float range; rescale the map");
  return field;
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
      if (args->half)
        for (Image& level : p.levels) round_min_max_to_half(level);  // still conservative in half
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

  auto de_args = std::make_shared<StreamArgs>();
  auto de_radius = std::make_shared<int>(0);
  CLI::App* de = add_stream_subcommand(
      streams, "dilate-erode", "Dilation and erosion maps (Kolb & Rezk-Salama): max and min of the bilinear height surface around each texel",
      "Output EXR (R = erosion: minimum, G = dilation: maximum over the (2 radius + 1)^2 texels around)", *de_args);
  de->add_option("--radius", *de_radius, "Half-width of the square neighbourhood, in texels (0: the texel's own footprint)")
      ->required()
      ->check(CLI::Range(0, 1 << 20));
  de->callback([&ctx, de_args, de_radius] {
    ctx.run = [&ctx, de_args, de_radius](nlohmann::json& report, Progress&) {
      const HeightField field = load_height_field(*de_args);
      Image m = dilation_erosion_map(field, *de_radius);
      m.metadata = height_field_metadata(field);
      m.metadata["quantity"] = std::string("dilation-erosion");
      m.metadata["channels"] = std::string("R = erosion (minimum), G = dilation (maximum) of the bilinear height surface over the neighbourhood");
      m.metadata["radius_texels"] = *de_radius;
      if (de_args->half) round_min_max_to_half(m);  // still conservative in half
      OutputSet outputs;
      write_image(m, outputs.add(de_args->output), de_args->half ? PixelFormat::half : PixelFormat::float32);
      outputs.commit();
      info(ctx.globals, "wrote " + de_args->output);
      report = {{"command", "streams dilate-erode"},
                {"input", de_args->input},
                {"output", de_args->output},
                {"width", m.width},
                {"height", m.height},
                {"radius", *de_radius},
                {"bytes", m.pixels.size() * (de_args->half ? 2 : 4)},
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
    auto fans = std::make_shared<std::string>("exact");
    CLI::App* cone = add_stream_subcommand(
        streams, relaxed ? "relaxed-cone" : "cone",
        relaxed ? "Relaxed cone map (Policarpo & Oliveira), exact for the bilinear surface: a ray to the cone's boundary crosses it at most once"
                : "Conservative cone map (Dummer), exact for the bilinear surface: no point of it inside any cone",
        "Output EXR (MIP-mapped: R = height, G = cone ratio, B = apex height)", *cone_args);
    cone->add_option("--tolerance", *tolerance, "Relative gap allowed below the exact ratio (the stored one is never wider)")
        ->check(InRange(1e-6, 0.5))
        ->capture_default_str();
    if (relaxed)
      cone->add_option("--fans", *fans,
                       "Where the apex sits on the footprint's side: exact (the widest cone) or bound (a safe, narrower one; faster on smooth "
                       "maps with features hundreds of texels wide)")
          ->check(CLI::IsMember({"exact", "bound"}))
          ->capture_default_str();
    cone->callback([&ctx, cone_args, tolerance, fans, kind] {
      ctx.run = [&ctx, cone_args, tolerance, fans, kind](nlohmann::json& report, Progress& progress) {
        const HeightField field = load_height_field(*cone_args);
        ConeMapOptions options;
        options.kind = kind;
        options.tolerance = *tolerance;
        options.half = cone_args->half;
        options.exact_fans = *fans == "exact";
        const std::vector<Image> levels = cone_map_levels(build_cone_map(field, options, progress));
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
        if (kind == ConeKind::relaxed) report["fans"] = *fans;
        return 0;
      };
    });
  }

  // View-dependent displacement: the table, compressed, in a two-part EXR.
  struct VdmArgs {
    std::string curvatures, mesh;
    int curvature_steps = 4, max_rank = 32;
    double max_error = 0.002;
    VdmOptions options;
    bool relief_given = false, curvatures_given = false;
  };
  auto vdm_args = std::make_shared<StreamArgs>();
  auto vdm = std::make_shared<VdmArgs>();
  CLI::App* vdm_cmd = add_stream_subcommand(streams, "vdm", "View-dependent displacement map (Wang et al.): per texel, view direction and curvature, where the view ray meets the surface; PCA-compressed",
                                            "Output EXR, two parts: per-texel PCA weights, and the mean and basis per direction", *vdm_args);
  vdm_cmd->add_option("--theta", vdm->options.theta, "View angles from the normal (sampled at the centres of [0, --theta-max])")->check(CLI::Range(1, 256))->capture_default_str();
  vdm_cmd->add_option("--theta-max", vdm->options.theta_max, "Largest view angle from the normal, degrees")->check(InRange(1.0, 90.0))->capture_default_str();
  vdm_cmd->add_option("--phi", vdm->options.phi, "Azimuths around the normal")->check(CLI::Range(1, 1024))->capture_default_str();
  vdm_cmd->add_option("--curvatures", vdm->curvatures, "Comma-separated curvatures along the view direction, per unit of u, increasing (default: 0, a flat base; with --mesh: from the mesh)");
  vdm_cmd->add_option("--mesh", vdm->mesh, "Base mesh: relief from its size (unless --relief) and curvature slices from quadric fits (unless --curvatures)");
  vdm_cmd->add_option("--curvature-steps", vdm->curvature_steps, "With --mesh: curvature samples over the mesh's range (5th percentile of k2 to 95th of k1; 1: the median mean curvature)")->check(CLI::Range(1, 64))->capture_default_str();
  vdm_cmd->add_option("--relief", vdm->options.relief, "Height range in units of u (default 0.1, or from --mesh)")->check(InRange(1e-9, kVdmMaxRelief));
  vdm_cmd->add_option("--max-error", vdm->max_error, "Largest RMS error of the compressed table, units of u (within --max-rank components: a warning when they fall short)")->check(NonNegative)->capture_default_str();
  vdm_cmd->add_option("--max-rank", vdm->max_rank, "Largest number of PCA components (meso preview takes at most 64)")->check(CLI::Range(0, 4096))->capture_default_str();
  vdm_cmd->callback([&ctx, vdm_args, vdm, vdm_cmd] {
    vdm->relief_given = vdm_cmd->count("--relief") > 0;
    vdm->curvatures_given = vdm_cmd->count("--curvatures") > 0;
    ctx.run = [&ctx, vdm_args, vdm](nlohmann::json& report, Progress& progress) {
      const auto start = std::chrono::steady_clock::now();
      VdmOptions o = vdm->options;
      // An empty list given (`--curvatures "$K"` with K unset) is a mistake, not the default.
      if (vdm->curvatures_given && vdm->curvatures.empty()) throw UsageError("--curvatures: the list is empty (leave the option out for the default)");
      if (!vdm->curvatures.empty()) {
        o.curvatures.clear();
        std::stringstream list(vdm->curvatures);
        std::string item;
        while (std::getline(list, item, ',')) {
          float v = 0;
          if (!parse_finite(item, v)) throw UsageError("--curvatures: '" + item + "' is not a number");
          o.curvatures.push_back(v);
        }
        // Strictly: two equal slices would make the lookup's interpolation divide by zero.
        if (std::adjacent_find(o.curvatures.begin(), o.curvatures.end(), std::greater_equal<float>()) != o.curvatures.end())
          throw UsageError("--curvatures: the values must increase");
      }
      const HeightField field = load_height_field(*vdm_args);  // after the options' checks: a usage error comes first
      nlohmann::json mesh_report;
      if (!vdm->mesh.empty()) {
        Mesh base = load_mesh(ctx.globals, vdm->mesh, mesh_report);
        if (!has_uvs(base)) throw InputError(vdm->mesh, "has no texture coordinates; the VDM needs the base mesh's UV scale");
        const double per_u = object_length_per_uv(base);
        if (!(per_u > 0)) throw InputError(vdm->mesh, "has no area in 3D or in UV");
        const std::vector<VertexCurvature> k = vdm->curvatures.empty() ? fit_curvature(base) : std::vector<VertexCurvature>{};
        std::vector<float> k1, k2;
        double lo = std::numeric_limits<double>::infinity(), hi = -lo;  // over the fitted vertices
        for (const VertexCurvature& v : k) {
          if (v.rings == 0) continue;  // not fitted
          k1.push_back(v.k1);
          k2.push_back(v.k2);
          lo = std::min(lo, static_cast<double>(v.k2));
          hi = std::max(hi, static_cast<double>(v.k1));
        }
        if (vdm->curvatures.empty()) o.curvatures = vdm_curvature_slices(k1, k2, per_u, vdm->curvature_steps);
        if (!vdm->relief_given) {
          if (field.scale / per_u > kVdmMaxRelief)
            throw InputError(vdm->mesh, "the map's height range is " + short_number(field.scale / per_u) +
                                            " units of u on this mesh, beyond " + short_number(kVdmMaxRelief) + " (are the map and the mesh in the same units?)");
          o.relief = static_cast<float>(vdm_relief_on_mesh(field.scale, per_u));
          // A height range below 1e-6 of the mesh's length per u is flat for any table: the
          // map and the mesh are likely of different assets or units.
          if (field.scale > 0 && field.scale / per_u < 1e-6)
            warn(ctx.globals, vdm->mesh + ": the map's height range is " + short_number(field.scale / per_u) +
                                  " units of u on this mesh, raised to 1e-6 (are the map and the mesh in the same units?)");
        }
        mesh_report["object_length_per_u"] = per_u;
        mesh_report["curvature_range"] = lo <= hi ? nlohmann::json{lo, hi} : nlohmann::json(nullptr);
        mesh_report["curvatures_per_u"] = o.curvatures;
      }
      // The raw table is held whole before it is compressed (W x H texels x theta x phi x
      // curvatures floats), and compressing it takes about as much again. Past 2 GiB it is
      // refused before any work (a 128^2 map with the in-range --theta 256 --phi 1024 had
      // reached 17 GB when it was stopped).
      const double directions = static_cast<double>(o.theta) * o.phi * static_cast<double>(std::max<size_t>(1, o.curvatures.size()));
      // The PCA solves a directions x directions covariance: cubic work whatever the map (on
      // a 1 x 1 map 2048 directions took 1.8 s, 4096 took 17 s, 16384 over two minutes).
      if (directions > kVdmMaxDirections)
        throw UsageError("streams vdm: " + short_number(directions) + " directions (--theta x --phi x curvatures); the limit is " +
                         short_number(kVdmMaxDirections) + ", as the compression's work grows with their cube");
      const double table_bytes = static_cast<double>(field.texel_count()) * directions * sizeof(float);
      if (table_bytes > 2.0 * (1ull << 30)) {
        char gib[32];
        std::snprintf(gib, sizeof gib, "%.1f", table_bytes / (1ull << 30));
        throw UsageError("streams vdm: the raw table would take " + std::string(gib) + " GiB (texels x --theta x --phi x curvatures, 4 bytes each); "
                         "the limit is 2 GiB: lower --theta, --phi or the curvature count");
      }
      const VdmTable table = build_vdm(field, o, progress);
      const CompressedVdm c = compress_vdm(table, vdm->max_error, vdm->max_rank);
      const std::vector<Image> parts = vdm_images(c, field, o);
      if (vdm_args->half) {
        // Distances are horizontal lengths in units of u: with a steep relief and grazing
        // angles they outgrow half floats, which would store them as Inf.
        float largest = 0;
        for (const Image& part : parts)
          for (float v : part.pixels) largest = std::max(largest, std::abs(v));
        if (largest > 65504.0f)
          throw UsageError("streams vdm --half: the table holds values up to " + short_number(largest) +
                           ", beyond half floats' 65504 (write float32, or lower --relief or --theta-max)");
      }
      OutputSet outputs;
      write_image_parts(parts, outputs.add(vdm_args->output), vdm_args->half ? PixelFormat::half : PixelFormat::float32);
      outputs.commit();
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      const size_t raw = table.distance.size() * sizeof(float);
      info(ctx.globals, "wrote " + vdm_args->output + " (rank " + std::to_string(c.rank) + ", RMS error " + short_number(c.rms_error) + ")");
      // Only when the rank cap stopped it: at full rank (every direction a component) what is
      // left is float rounding, which no rank removes.
      if (c.rms_error > vdm->max_error && c.rank == vdm->max_rank && c.rank < table.directions())
        warn(ctx.globals, vdm_args->output + ": RMS error " + short_number(c.rms_error) + " is above --max-error " + short_number(vdm->max_error) +
                              ": --max-rank " + std::to_string(vdm->max_rank) + " components were not enough (raise --max-rank)");
      report = {{"command", "streams vdm"},
                {"input", vdm_args->input},
                {"output", vdm_args->output},
                {"width", table.width},
                {"height", table.height},
                {"theta", table.theta},
                {"phi", table.phi},
                {"curvatures", o.curvatures},
                {"relief", o.relief},
                {"directions", table.directions()},
                {"rank", c.rank},
                {"rms_error", c.rms_error},
                {"max_error", c.max_error},
                {"raw_bytes", raw},
                {"bytes", c.bytes() / sizeof(float) * (vdm_args->half ? 2 : 4)},
                {"compression_ratio", static_cast<double>(raw) / static_cast<double>(std::max<size_t>(1, c.bytes()))},
                {"seconds", seconds}};
      if (!vdm->mesh.empty()) report["mesh"] = mesh_report;
      return 0;
    };
  });

  // Compressed-displacement vertex streams: sampled against the high mesh, no map needed.
  struct DstreamArgs {
    std::string low, high, output;
    float front = 0, back = 0;
    DisplacementStreamOptions options;
  };
  auto ds = std::make_shared<DstreamArgs>();
  CLI::App* dstream = streams->add_subcommand(
      "dstream", "Pre-sampled displacement per base triangle at levels 2^l, with morph targets, as 8-byte compressed vertices");
  dstream->add_option("--low", ds->low, "Base mesh (vertex normals are used or computed)")->required();
  dstream->add_option("--high", ds->high, "High-poly mesh")->required();
  dstream->add_option("-o,--output", ds->output, "Output file (dstream.bin, docs/formats.md)")->required();
  dstream->add_option("--levels", ds->options.levels, "Levels 0..L-1, level l with 2^l segments per edge")->check(CLI::Range(1, 7))->capture_default_str();
  dstream->add_option("--front", ds->front, "Ray reach outward, object units (0: 5% of the high mesh's diagonal)")->check(InRange(0.0, 1e30));
  dstream->add_option("--back", ds->back, "Ray reach inward, object units (0: as --front)")->check(InRange(0.0, 1e30));
  dstream->callback([&ctx, ds] {
    ctx.run = [&ctx, ds](nlohmann::json& report, Progress& progress) {
      refuse_overwriting_input(ds->output, {ds->low, ds->high});
      nlohmann::json low_report, high_report;
      const Mesh low = load_mesh(ctx.globals, ds->low, low_report);
      const Mesh high = load_mesh(ctx.globals, ds->high, high_report);
      DisplacementStreamOptions o = ds->options;
      o.front = ds->front;
      o.back = ds->back;
      const DisplacementStream stream = sample_displacement_stream(low, high, o, progress);
      const EncodedStream encoded = encode_displacement_stream(stream);
      OutputSet outputs;
      write_displacement_stream(encoded, static_cast<int>(low.n_vertices()), static_cast<int>(low.n_faces()), outputs.add(ds->output).string());
      outputs.commit();
      size_t vertices = 0;
      nlohmann::json levels = nlohmann::json::array();
      for (size_t l = 0; l < encoded.vertices.size(); ++l) {
        vertices += encoded.vertices[l].size();
        levels.push_back({{"segments", encoded.segments[l]}, {"vertices", encoded.vertices[l].size()}});
      }
      if (stream.misses) warn(ctx.globals, std::to_string(stream.misses) + " samples found no high surface within reach (stored as 0)");
      info(ctx.globals, "wrote " + ds->output + " (" + std::to_string(vertices) + " vertices, 8 bytes each)");
      report = {{"command", "streams dstream"},
                {"low", low_report},
                {"high", high_report},
                {"output", ds->output},
                {"levels", levels},
                {"vertices", vertices},
                {"bytes_per_vertex", 8},
                {"bytes", std::filesystem::file_size(ds->output)},
                {"raw_vertex_buffer_bytes", vertices * 12},
                {"ratio_to_raw", static_cast<double>(vertices * 12) / static_cast<double>(std::max<size_t>(1, vertices * 8))},
                {"displacement_min", encoded.min_value},
                {"displacement_max", encoded.max_value},
                {"max_position_error", encoded.max_error},
                {"rays", stream.rays},
                {"misses", stream.misses},
                {"front", stream.front},
                {"back", stream.back}};
      return 0;
    };
  });

  auto sdf_args = std::make_shared<StreamArgs>();
  auto sdf_options = std::make_shared<DistanceFieldOptions>();
  CLI::App* sdf = add_stream_subcommand(streams, "sdf", "3D distance field over the height field, for sphere tracing",
                                        "Output EXR: W x (H * depth), slices stacked, slice 0 lowest", *sdf_args);
  sdf->add_option("--depth", sdf_options->depth, "Slices along the height axis")->check(CLI::Range(1, 1024));
  sdf->add_option("--relief", sdf_options->relief, "Height range in units of the map's width (the box is 1 x H/W x relief)")
      ->check(InRange(1e-9, 1e9));
  sdf->callback([&ctx, sdf_args, sdf_options] {
    ctx.run = [&ctx, sdf_args, sdf_options](nlohmann::json& report, Progress& progress) {
      const HeightField field = load_height_field(*sdf_args);
      DistanceField df = build_distance_field(field, *sdf_options, progress);
      const int width = df.width, height = df.height, depth = df.depth;
      const float relief = df.relief;
      // Moved, not copied: at 4096² x 32 the field is 2.1 GB.
      Image img = distance_field_image(std::move(df), field);
      if (sdf_args->half) round_distances_to_half(img);
      OutputSet outputs;
      write_image(img, outputs.add(sdf_args->output), sdf_args->half ? PixelFormat::half : PixelFormat::float32);
      outputs.commit();
      info(ctx.globals, "wrote " + sdf_args->output + " (" + std::to_string(width) + "x" + std::to_string(height) + "x" +
                            std::to_string(depth) + " voxels)");
      report = {{"command", "streams sdf"}, {"input", sdf_args->input}, {"output", sdf_args->output},
                {"width", width}, {"height", height}, {"depth", depth}, {"relief", relief},
                {"bytes", img.pixels.size() * (sdf_args->half ? 2 : 4)}};
      return 0;
    };
  });
}

}  // namespace meso::cli
