#include "cli.hpp"

#include "meso/bake/bake.hpp"
#include "meso/core/error.hpp"
#include "meso/formats/atomic_file.hpp"
#include "meso/formats/image_io.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>

namespace meso::cli {

namespace {

// A length in object units ("0.02") or as a percentage of a diagonal ("5%"); "" = 0.
float parse_length(const std::string& text, float diagonal, const char* option) {
  if (text.empty()) return 0.0f;
  const bool percent = text.back() == '%';
  const std::string number = percent ? text.substr(0, text.size() - 1) : text;
  float v = 0;
  if (!parse_finite(number, v) || v < 0)
    throw UsageError(std::string(option) + " '" + text + "': expected a non-negative length or a percentage such as 5%");
  return percent ? v / 100.0f * diagonal : v;
}

// The maps `--maps` can select, and where each goes.
const std::map<std::string, std::string>& map_files() {
  static const std::map<std::string, std::string> files{{"displacement", "displacement.exr"},
                                                        {"displacement_png", "displacement.png"},
                                                        {"normal_ts", "normal_ts.png"},
                                                        {"normal_ts_exr", "normal_ts.exr"},
                                                        {"normal_os", "normal_os.png"},
                                                        {"normal_os_exr", "normal_os.exr"},
                                                        {"coverage", "coverage.png"}};
  return files;
}

// --dilate: texels to fill around the charts, or the whole map ("inf", or -1 as before).
int parse_dilate(const std::string& text) {
  if (text == "inf" || text == "-1") return -1;
  int v = -1;
  size_t used = 0;
  try {
    v = std::stoi(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || v < 0 || v > (1 << 20))
    throw UsageError("--dilate '" + text + "': expected a texel count (0 to 1048576), or inf (or -1) for the whole map");
  return v;
}

}  // namespace

void add_bake(CLI::App& app, Context& ctx) {
  struct Args {
    std::string low, high, cage, out_dir, size = "1024", front, back, bunch, hit = "nearest";
    std::string maps = "displacement,normal_ts,coverage", basis = "linear", detail, dilate = "inf";
    float detail_scale = 0.01f;
    float max_miss_rate = 1;
    int samples = 1;
    int png_bits = 16;
    std::string normal_y = "up";
    bool ignore_backfaces = false, match_by_name = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand("bake", "Bake displacement and tangent-space normal maps from a high mesh onto a base mesh");
  sub->add_option("--low", args->low, "Base mesh with a unique UV mapping")->required();
  sub->add_option("--high", args->high, "High-poly mesh")->required();
  sub->add_option("--cage", args->cage,
                  "Cage mesh with the base's topology: rays go from each base point toward the cage's point and stop there");
  sub->add_option("-o,--output", args->out_dir, "Output folder (the maps chosen with --maps)")->required();
  sub->add_option("--maps", args->maps,
                  "Comma-separated maps to write: displacement (.exr, float), displacement_png (normalised; scale and bias in its "
                  "metadata and the report), normal_ts (.png), normal_ts_exr, normal_os (object space, .png), normal_os_exr, "
                  "coverage (.png); PNG bit depth: --png-bits")
      ->capture_default_str();
  sub->add_option("--size", args->size, "Map size: N or WxH texels");
  sub->add_option("--png-bits", args->png_bits,
                  "Bits per channel of the PNG maps (normal_ts, normal_os, displacement_png): 8 or 16 (coverage.png is always 8)")
      ->check(CLI::IsMember({8, 16}))
      ->capture_default_str();
  sub->add_option("--normal-y", args->normal_y,
                  "Green channel of the tangent-space normal maps (normal_ts, normal_ts_exr): up = +v (OpenGL: glTF, Blender, "
                  "Unity), down = -v (DirectX: Unreal); see docs/formats.md")
      ->check(CLI::IsMember({"up", "down"}))
      ->capture_default_str();
  sub->add_option("--front", args->front,
                  "Ray reach outward from the base: object units, or a percentage of the high mesh's bounding-box diagonal "
                  "(default 5%)");
  sub->add_option("--back", args->back, "Ray reach inward from the base, as --front (default 5%)");
  sub->add_option("--basis", args->basis,
                  "Base surface the rays leave from: linear (flat triangles, interpolated normals) or pn (curved PN triangles "
                  "from the corner normals, for renderers that tessellate into them)")
      ->check(CLI::IsMember({"linear", "pn"}))
      ->capture_default_str();
  sub->add_option("--detail", args->detail,
                  "Detail bump map on the high mesh (its UVs, tiled; mid-grey neutral): adds to the displacement and tilts the normals");
  sub->add_option("--detail-scale", args->detail_scale, "Object units per unit of the detail map's value")
      ->check(InRange(-1e6, 1e6))
      ->capture_default_str();
  sub->add_option("--hit", args->hit, "Which hit gives a texel its value: nearest, furthest, front-else-nearest, front-only")
      ->check(CLI::IsMember({"nearest", "furthest", "front-else-nearest", "front-only"}))
      ->capture_default_str();
  sub->add_option("--samples", args->samples,
                  "Samples per texel, a square n x n: 1, 4, 9, 16, ... 256 (stratified, box-filtered; samples may fall on "
                  "neighbouring triangles of the texel's chart)")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  sub->add_flag("--match-by-name", args->match_by_name,
                "Pair base and high parts by name (wheel_low with wheel_high; case, a trailing .NNN and _low/_lo/_lp, "
                "_high/_hi/_hp ignored): rays never hit a neighbouring part");
  sub->add_flag("--ignore-backfaces", args->ignore_backfaces, "Ignore high surfaces that face against the base surface");
  sub->add_option("--bunch", args->bunch,
                  "Hits closer than this form one bunch (a fold, a decal): its outermost hit is taken; object units or a "
                  "percentage of the diagonal (default 0.1%)");
  sub->add_option("--max-miss-rate", args->max_miss_rate,
                  "Exit 1 (outputs still written) when more than this fraction of covered texels miss")
      ->check(InRange(0.0, 1.0));
  sub->add_option("--dilate", args->dilate, "Texels to fill around charts: a count, or inf (or -1) for the whole map")
      ->capture_default_str();
  sub->callback([&ctx, args] {
    ctx.run = [&ctx, args](nlohmann::json& report, Progress& progress) {
      BakeOptions o;
      parse_size(args->size, o.width, o.height);
      // Measured: 4096^2 took 616 MB more than 2048^2 (49 bytes per texel: the maps, the
      // coverage, the per-texel sources of the dilation), whatever --maps writes. A 32768^2
      // bake (53 GB) had run this 24 GB machine out of memory.
      refuse_beyond_memory("bake --size " + args->size, 49.0 * o.width * o.height);
      o.dilate = parse_dilate(args->dilate);
      // Samples sit at the centres of n x n sub-texels: any other count would be rounded to
      // a square the user did not ask for (2 used to become 1), so it is refused.
      const int side = static_cast<int>(std::lround(std::sqrt(static_cast<double>(args->samples))));
      if (side * side != args->samples)
        throw UsageError("--samples " + std::to_string(args->samples) + ": expected a square number of samples per texel (1, 4, 9, 16, ...)");
      for (const HitRule rule : {HitRule::nearest, HitRule::furthest, HitRule::front_else_nearest, HitRule::front_only})
        if (args->hit == hit_rule_name(rule)) o.hit = rule;
      o.ignore_backfaces = args->ignore_backfaces;
      o.samples = args->samples;
      o.match_by_name = args->match_by_name;
      o.basis = args->basis == "pn" ? BakeBasis::pn : BakeBasis::linear;
      o.normal_y = args->normal_y == "down" ? NormalY::down : NormalY::up;
      Image detail;
      if (!args->detail.empty()) {
        detail = read_image(args->detail);
        {
          // Channel 0 is the bump; finite values whose span is not (a +-3e38 checker) would
          // make its gradient overflow, silently dropped from the normals (the streams refuse
          // such a map too).
          float lo = 0, hi = 0;
          for (size_t i = 0; i < detail.pixels.size(); i += static_cast<size_t>(detail.channels)) {
            lo = std::min(lo, detail.pixels[i]);
            hi = std::max(hi, detail.pixels[i]);
          }
          if (!std::isfinite(hi - lo)) throw InputError(args->detail, "its values span more than the float range; rescale the map");
          // The displacement it adds is value x --detail-scale, stored as float.
          const double reach = std::max(std::abs(static_cast<double>(lo)), std::abs(static_cast<double>(hi))) * args->detail_scale;
          if (!std::isfinite(static_cast<float>(reach)) || !std::isfinite(static_cast<float>((static_cast<double>(hi) - lo) * args->detail_scale)))
            throw InputError(args->detail, "its values times --detail-scale " + short_number(args->detail_scale) +
                                               " reach " + short_number(reach) + ", beyond the float range; rescale the map or the scale");
        }
        o.detail = &detail;
        o.detail_scale = args->detail_scale;
      }
      std::vector<std::string> wanted;
      {
        std::stringstream list(args->maps);
        std::string name;
        while (std::getline(list, name, ','))
          if (!name.empty()) {
            if (!map_files().count(name)) throw UsageError("--maps: unknown map '" + name + "'");
            wanted.push_back(name);
          }
        if (wanted.empty()) throw UsageError("--maps: no map chosen");
      }
      // Lengths may be percentages of the high mesh's diagonal: checked before loading.
      parse_length(args->front, 1, "--front");
      parse_length(args->back, 1, "--back");
      parse_length(args->bunch, 1, "--bunch");
      for (const std::string& name : wanted)
        refuse_overwriting_input((std::filesystem::path(args->out_dir) / map_files().at(name)).string(), {args->low, args->high, args->cage, args->detail});
      nlohmann::json low_report, high_report;
      const Mesh low = load_mesh(ctx.globals, args->low, low_report);
      if (!has_uvs(low)) throw InputError(args->low, "has no texture coordinates; bake needs a UV-mapped base mesh");
      {
        // The map covers [0, 1]^2 once: a face reaching outside (tiling UVs) is baked only
        // where it lies inside, which exit 0 with no miss had hidden.
        size_t outside = 0;
        for (auto f : low.faces())
          for (auto h : low.fh_range(f)) {
            const Vec2f uv = low.texcoord2D(h);
            if (uv[0] < -1e-6f || uv[0] > 1 + 1e-6f || uv[1] < -1e-6f || uv[1] > 1 + 1e-6f) {  // beyond rounding
              ++outside;
              break;
            }
          }
        if (outside)
          warn(ctx.globals, args->low + ": " + std::to_string(outside) + " of " + std::to_string(low.n_faces()) +
                                " faces have UVs outside [0, 1]; the maps hold only their parts inside (uvpack check lists them)");
      }
      const Mesh high = load_mesh(ctx.globals, args->high, high_report);
      Mesh cage;
      nlohmann::json cage_report;
      if (!args->cage.empty()) {
        cage = load_mesh(ctx.globals, args->cage, cage_report);
        if (!same_topology(low, cage))
          throw InputError(args->cage, "is not a cage of " + args->low + ": it needs the same vertices and faces in the same order");
        o.cage = &cage;
      }
      const float diagonal = bounding_box(high).diagonal();
      if (!args->detail.empty() && !has_uvs(high))
        throw InputError(args->high, "has no texture coordinates; --detail maps a bump onto the high mesh's UVs");
      o.front = parse_length(args->front, diagonal, "--front");
      o.back = parse_length(args->back, diagonal, "--back");
      o.bunch = parse_length(args->bunch, diagonal, "--bunch");
      const auto start = std::chrono::steady_clock::now();
      BakeResult r = bake(low, high, o, progress);
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      // Maps of nothing (every UV triangle degenerate, or off the map) are an input error, not
      // a bake with no misses (--max-miss-rate cannot see them: its rate is of covered texels).
      if (r.covered_texels == 0) throw InputError(args->low, "its UV triangles cover no texel of the map (degenerate or outside [0, 1])");
      const PixelFormat png_format = args->png_bits == 8 ? PixelFormat::uint8 : PixelFormat::uint16;
      const std::filesystem::path dir(args->out_dir);
      OutputSet outputs;
      nlohmann::json written = nlohmann::json::array();
      nlohmann::json png_range;
      for (const std::string& name : wanted) {
        const std::filesystem::path file = dir / map_files().at(name);
        written.push_back(file.string());
        if (name == "displacement") write_image(r.displacement, outputs.add(file), PixelFormat::float32);
        if (name == "displacement_png") {
          // Normalised to [0, 1]: object = bias + scale * value.
          Image png = r.displacement;
          const float bias = r.min_displacement, scale = r.max_displacement - r.min_displacement;
          for (float& v : png.pixels) v = scale > 0 ? std::clamp((v - bias) / scale, 0.0f, 1.0f) : 0.0f;
          png.metadata["height_bias"] = bias;
          png.metadata["height_scale"] = scale;
          png.metadata["height_units"] = std::string("object = bias + scale * value");
          write_image(png, outputs.add(file), png_format);
          png_range = {{"bias", bias}, {"scale", scale}};
        }
        if (name == "normal_ts") write_image(encode_normal_map(r.normal_ts), outputs.add(file), png_format);
        if (name == "normal_ts_exr") write_image(r.normal_ts, outputs.add(file), PixelFormat::float32);
        if (name == "normal_os") write_image(encode_normal_map(r.normal_os), outputs.add(file), png_format);
        if (name == "normal_os_exr") write_image(r.normal_os, outputs.add(file), PixelFormat::float32);
        if (name == "coverage") write_image(r.coverage, outputs.add(file), PixelFormat::uint8);
      }
      outputs.commit();
      if (r.misses) warn(ctx.globals, std::to_string(r.misses) + " of " + std::to_string(r.covered_texels) + " covered texels found no high surface within reach");
      if (!r.unmatched_parts.empty()) {
        // Named, the first few: the artist has to find them in the scene.
        std::string names;
        for (size_t i = 0; i < r.unmatched_parts.size() && i < 5; ++i) names += (i ? ", " : "") + r.unmatched_parts[i];
        if (r.unmatched_parts.size() > 5) names += ", ...";
        warn(ctx.globals, std::to_string(r.unmatched_parts.size()) + " base parts have no high part of the same name (" + names + "): they see the whole high mesh");
      }
      if (r.cage_vertices_on_base)
        warn(ctx.globals, args->cage + ": " + std::to_string(r.cage_vertices_on_base) + " of " + std::to_string(low.n_vertices()) +
                              " vertices lie on the base mesh's; rays there go along the normal with the default reach (" + short_number(r.front) + ")");
      if (r.ambiguous) warn(ctx.globals, std::to_string(r.ambiguous) + " texels had an ambiguous choice of hit (coverage value 0.75)");
      info(ctx.globals, "wrote " + std::to_string(wanted.size()) + " maps to " + dir.string());
      report = {{"command", "bake"},
                {"low", low_report},
                {"high", high_report},
                {"width", o.width},
                {"height", o.height},
                {"front", r.front},
                {"back", r.back},
                {"bunch", r.bunch},
                {"samples", r.samples},
                {"hit_rule", hit_rule_name(o.hit)},
                {"png_bits", args->png_bits},
                {"normal_y", args->normal_y},
                {"cage", args->cage},
                {"cage_vertices_on_base", r.cage_vertices_on_base},
                {"basis", args->basis},
                {"detail", args->detail},
                {"matched_parts", r.matched_parts},
                {"unmatched_parts", r.unmatched_parts},
                {"ignore_backfaces", o.ignore_backfaces},
                {"ambiguous", r.ambiguous},
                {"covered_texels", r.covered_texels},
                {"hits", r.hits},
                {"misses", r.misses},
                {"displacement_min", r.min_displacement},
                {"displacement_max", r.max_displacement},
                {"rays", r.rays},
                {"seconds", seconds},
                {"rays_per_second", seconds > 0 ? static_cast<double>(r.rays) / seconds : 0.0},
                {"outputs", written}};
      if (!png_range.is_null()) report["displacement_png"] = png_range;
      // The faces the artist should look at: those whose texels missed or were ambiguous,
      // worst first.
      auto worst_faces = [&](const std::vector<uint32_t>& count, const char* key) {
        nlohmann::json faces = nlohmann::json::array();
        std::vector<size_t> order;
        for (size_t f = 0; f < count.size(); ++f)
          if (count[f]) order.push_back(f);
        std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return count[a] > count[b]; });
        for (size_t f : order) faces.push_back({{"face", f}, {"texels", r.face_texels[f]}, {key, count[f]}});
        return faces;
      };
      report["miss_faces"] = worst_faces(r.face_misses, "misses");
      report["ambiguous_faces"] = worst_faces(r.face_ambiguous, "ambiguous");
      const double miss_rate = r.covered_texels ? static_cast<double>(r.misses) / static_cast<double>(r.covered_texels) : 0.0;
      report["miss_rate"] = miss_rate;
      if (miss_rate > args->max_miss_rate) {
        warn(ctx.globals, "miss rate " + std::to_string(miss_rate) + " exceeds --max-miss-rate " + std::to_string(args->max_miss_rate));
        return static_cast<int>(ExitCode::check_failed);
      }
      return 0;
    };
  });
}

}  // namespace meso::cli
