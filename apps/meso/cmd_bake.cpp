#include "cli.hpp"

#include "meso/bake/bake.hpp"
#include "meso/core/error.hpp"
#include "meso/formats/atomic_file.hpp"
#include "meso/formats/image_io.hpp"

#include <algorithm>
#include <filesystem>

namespace meso::cli {

void add_bake(CLI::App& app, Context& ctx) {
  struct Args {
    std::string low, high, out_dir, size = "1024";
    float front = 0, back = 0, max_miss_rate = 1;
    int dilate = -1;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand("bake", "Bake displacement and tangent-space normal maps from a high mesh onto a base mesh");
  sub->add_option("--low", args->low, "Base mesh with a unique UV mapping")->required();
  sub->add_option("--high", args->high, "High-poly mesh")->required();
  sub->add_option("-o,--output", args->out_dir, "Output folder: displacement.exr, normal_ts.png, coverage.png")->required();
  sub->add_option("--size", args->size, "Map size: N or WxH texels");
  sub->add_option("--front", args->front, "Ray reach outward from the base, object units (0: 5% of the high mesh's bounding-box diagonal)")
      ->check(CLI::NonNegativeNumber & Finite);
  sub->add_option("--back", args->back, "Ray reach inward from the base, object units (0: as for --front)")->check(CLI::NonNegativeNumber & Finite);
  sub->add_option("--max-miss-rate", args->max_miss_rate,
                  "Exit 1 (outputs still written) when more than this fraction of covered texels miss")
      ->check(CLI::Range(0.0, 1.0) & Finite);
  sub->add_option("--dilate", args->dilate, "Texels to fill around charts (-1: the whole map)")->check(CLI::Range(-1, 1 << 20));
  sub->callback([&ctx, args] {
    ctx.run = [&ctx, args](nlohmann::json& report, Progress& progress) {
      BakeOptions o;
      parse_size(args->size, o.width, o.height);
      o.front = args->front;
      o.back = args->back;
      o.dilate = args->dilate;
      nlohmann::json low_report, high_report;
      const Mesh low = load_mesh(ctx.globals, args->low, low_report);
      if (!has_uvs(low)) throw InputError(args->low, "has no texture coordinates; bake needs a UV-mapped base mesh");
      const Mesh high = load_mesh(ctx.globals, args->high, high_report);
      const BakeResult r = bake(low, high, o, progress);
      const std::filesystem::path dir(args->out_dir);
      OutputSet outputs;
      write_image(r.displacement, outputs.add(dir / "displacement.exr"), PixelFormat::float32);
      write_image(encode_normal_map(r.normal_ts), outputs.add(dir / "normal_ts.png"), PixelFormat::uint16);
      write_image(r.coverage, outputs.add(dir / "coverage.png"), PixelFormat::uint8);
      outputs.commit();
      if (r.misses) warn(ctx.globals, std::to_string(r.misses) + " of " + std::to_string(r.covered_texels) + " covered texels found no high surface within reach");
      info(ctx.globals, "wrote " + (dir / "displacement.exr").string() + " and " + (dir / "normal_ts.png").string());
      report = {{"command", "bake"},
                {"low", low_report},
                {"high", high_report},
                {"width", o.width},
                {"height", o.height},
                {"front", r.front},
                {"back", r.back},
                {"covered_texels", r.covered_texels},
                {"hits", r.hits},
                {"misses", r.misses},
                {"displacement_min", r.min_displacement},
                {"displacement_max", r.max_displacement},
                {"outputs", {(dir / "displacement.exr").string(), (dir / "normal_ts.png").string(), (dir / "coverage.png").string()}}};
      // The faces the artist should look at: those whose texels missed, worst first.
      nlohmann::json faces = nlohmann::json::array();
      std::vector<size_t> order;
      for (size_t f = 0; f < r.face_misses.size(); ++f)
        if (r.face_misses[f]) order.push_back(f);
      std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return r.face_misses[a] > r.face_misses[b]; });
      for (size_t f : order) faces.push_back({{"face", f}, {"texels", r.face_texels[f]}, {"misses", r.face_misses[f]}});
      report["miss_faces"] = faces;
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
