// End-to-end tests of the `meso` command: exit codes, error lines, no partial output, and
// the walking skeleton on a small generated asset whose answer is known.
#include "meso/core/memory.hpp"
#include "meso/examples/brick_wall.hpp"
#include "meso/formats/image_io.hpp"
#include "meso/formats/mesh_io.hpp"
#include "bumpy_torus.hpp"
#include "test_support.hpp"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <utility>
#include <variant>

namespace meso {
namespace {

namespace fs = std::filesystem;

struct Result {
  int code = -1;
  std::string out, err;
};

// Runs meso with `args`; `env` ("NAME=value ", may be empty) goes before the command.
Result run_env(const std::string& env, const std::string& args) {
  test::TempDir tmp;
  const std::string cmd = env + std::string(MESO_EXE) + " " + args + " 2>" + (tmp / "stderr").string();
  Result r;
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) return r;
  char buf[4096];
  size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) r.out.append(buf, n);
  const int status = ::pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.err = test::read_text(tmp / "stderr");
  return r;
}

Result run(const std::string& args) { return run_env("", args); }

void example(const std::string& args) {
  const std::string cmd = std::string(MESO_EXAMPLE_EXE) + " " + args;
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
}

size_t lines(const std::string& s) { return static_cast<size_t>(std::count(s.begin(), s.end(), '\n')); }

// Without an EGL that offers a surfaceless display, headless preview says what is missing
// (exit 4); libepoxy had aborted the process. --list-methods --json prints one JSON value.
TEST(CliPreview, NoEglIsAnEnvironmentErrorAndTheMethodListIsJson) {
  test::TempDir dir;
  write_mesh(test::make_grid(2, 2), dir / "grid.obj");
  const std::string grid = (dir / "grid.obj").string();
  ASSERT_EQ(run("bake --low " + grid + " --high " + grid + " -o " + (dir / "maps").string() + " --size 16").code, 0);
  const Result r = run_env("__EGL_VENDOR_LIBRARY_FILENAMES=" + (dir / "none.json").string() + " ",
                           "preview " + grid + " --maps " + (dir / "maps").string() + " --method pom --headless --size 8x8 --png " +
                               (dir / "o.png").string());
  EXPECT_EQ(r.code, 4) << r.err;
  EXPECT_NE(r.err.find("EGL: no surfaceless platform"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "o.png"));
  const Result list = run("preview --list-methods --json");
  ASSERT_EQ(list.code, 0);
  EXPECT_EQ(nlohmann::json::parse(list.out)["methods"].size(), 17u) << list.out;
}

// vdm on a flat map sees the plane (through the table, all its pixels had been wrong here),
// and a table whose relief is not the maps' on this mesh (made without --mesh) is warned
// about.
TEST(CliPreview, VdmSeesAFlatMapAndWarnsOfAnotherRelief) {
  test::TempDir dir;
  write_mesh(test::make_grid(2, 2), dir / "grid.obj");
  write_mesh(test::make_plane(0.3f, 0.0f, 0.05f), dir / "tilt.obj");
  const std::string grid = (dir / "grid.obj").string(), maps = (dir / "maps").string(), tilted = (dir / "tilted").string();
  // 128 texels (at 16 the table's error stayed within the hit tolerance).
  ASSERT_EQ(run("bake --low " + grid + " --high " + grid + " -o " + maps + " --size 128").code, 0);
  // Without --mesh (relief 0.1).
  ASSERT_EQ(run("streams vdm " + maps + "/displacement.exr --theta 4 --phi 8 -o " + maps + "/vdm.exr").code, 0);
  const Result flat = run("preview " + grid + " --maps " + maps + " --compare --json --method vdm --size 24x24 --view-angle 60");
  ASSERT_EQ(flat.code, 0) << flat.err;
  const auto report = nlohmann::json::parse(flat.out);
  EXPECT_GT(report["methods"][0]["pixels"].get<double>(), 0) << flat.out;
  EXPECT_EQ(report["methods"][0]["wrong_hit_fraction"].get<double>(), 0.0) << flat.out;
  EXPECT_EQ(flat.err.find("made for a relief"), std::string::npos) << "no relief to mismatch on a flat map";
  ASSERT_EQ(run("bake --low " + grid + " --high " + (dir / "tilt.obj").string() + " -o " + tilted + " --size 16").code, 0);
  ASSERT_EQ(run("streams vdm " + tilted + "/displacement.exr --theta 4 --phi 8 -o " + tilted + "/vdm.exr").code, 0);  // relief 0.1
  const Result other = run("preview " + grid + " --maps " + tilted + " --compare --method vdm --size 8x8");
  EXPECT_EQ(other.code, 0) << other.err;
  EXPECT_NE(other.err.find("vdm.exr: made for a relief of 0.1 units of u, but its height range on this mesh is "), std::string::npos) << other.err;
  ASSERT_EQ(run("streams vdm " + tilted + "/displacement.exr --mesh " + grid + " --theta 4 --phi 8 -o " + tilted + "/vdm.exr").code, 0);
  EXPECT_EQ(run("preview " + grid + " --maps " + tilted + " --compare --method vdm --size 8x8").err.find("made for a relief"), std::string::npos);
}

TEST(Cli, HelpVersionAndMethodList) {
  const Result help = run("--help");
  EXPECT_EQ(help.code, 0);
  for (const char* sub : {"meshreduce", "uvpack", "bake", "frames", "streams", "preview"}) EXPECT_NE(help.out.find(sub), std::string::npos) << sub;
  const Result version = run("--version");
  EXPECT_EQ(version.code, 0);
  EXPECT_NE(version.out.find("meso "), std::string::npos);
  const Result methods = run("preview --list-methods");
  EXPECT_EQ(methods.code, 0);
  EXPECT_EQ(methods.out,
            "mesh\ntessellation\nbump\nparallax\noffset-limited\nslope\niterative-parallax\nsteep\nrelief\npom\ncone\nrelaxed-"
            "cone\npyramid\nsphere-tracing\ndig\nvdm\ndstream\n");
}

// uvpack pack: the seamed cube's six charts packed with padding; the checker agrees.
TEST(Cli, UvpackPackMakesAUniqueMappingWithPadding) {
  test::TempDir dir;
  write_mesh(test::make_seamed_cube(), dir / "cube.obj");
  const Result r = run("uvpack pack " + (dir / "cube.obj").string() + " -o " + (dir / "packed.obj").string() + " --size 128 --padding 3 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto report = nlohmann::json::parse(r.out);
  EXPECT_EQ(report["charts"], 6);
  EXPECT_GT(report["utilization"].get<double>(), 0.3);
  EXPECT_EQ(report["min_area_orientation"], true);
  const Result check = run("uvpack check " + (dir / "packed.obj").string() + " --size 128 --padding 3 --fail-on overlap,shared,padding,outside");
  EXPECT_EQ(check.code, 0) << check.err;
  // --quarter-turns: only quarter turns of the input's orientation, as the report says.
  const Result quarter = run("uvpack pack " + (dir / "cube.obj").string() + " -o " + (dir / "quarter.obj").string() + " --size 128 --padding 3 --quarter-turns --json");
  ASSERT_EQ(quarter.code, 0) << quarter.err;
  EXPECT_EQ(nlohmann::json::parse(quarter.out)["min_area_orientation"], false);
  // Addressing: --wrap (the default) keeps ceil(3 / 2) = 2 texels to the border, --clamp none.
  EXPECT_EQ(report["addressing"], "wrap");
  EXPECT_EQ(report["border_margin"], 2);
  const Result clamp = run("uvpack pack " + (dir / "cube.obj").string() + " -o " + (dir / "clamp.obj").string() + " --size 128 --padding 3 --clamp --json");
  ASSERT_EQ(clamp.code, 0) << clamp.err;
  EXPECT_EQ(nlohmann::json::parse(clamp.out)["addressing"], "clamp");
  EXPECT_EQ(nlohmann::json::parse(clamp.out)["border_margin"], 0);
  EXPECT_EQ(run("uvpack pack " + (dir / "cube.obj").string() + " -o " + (dir / "x.obj").string() + " --wrap --clamp").code, 2);
  EXPECT_FALSE(fs::exists(dir / "x.obj"));
  // The checker measures across the border with --wrap: the default packing keeps the padding there.
  const Result across = run("uvpack check " + (dir / "packed.obj").string() + " --size 128 --padding 3 --wrap --fail-on padding --report " +
                            (dir / "wrap.json").string());
  EXPECT_EQ(across.code, 0) << across.err;
  std::ifstream wrap_report(dir / "wrap.json");
  EXPECT_EQ(nlohmann::json::parse(wrap_report)["addressing"], "wrap");
  EXPECT_EQ(run("uvpack check " + (dir / "packed.obj").string() + " --size 128 --wrap --clamp").code, 2);
  // (A mesh without UVs is unwrapped first: Cli.UvpackPackUnwrapsAMeshWithoutUvs.)
}

// --mip-safe K on pack and check; --density moves texels to the chart whose map has detail.
TEST(Cli, UvpackMipSafeAndDensity) {
  test::TempDir dir;
  write_mesh(test::make_seamed_cube(), dir / "cube.obj");
  const std::string cube = (dir / "cube.obj").string();
  const Result safe = run("uvpack pack " + cube + " -o " + (dir / "safe.obj").string() + " --size 256 --padding 2 --mip-safe 3 --clamp --json");
  ASSERT_EQ(safe.code, 0) << safe.err;
  const auto report = nlohmann::json::parse(safe.out);
  EXPECT_EQ(report["mip_safe"], 3);
  EXPECT_EQ(report["check"]["mip_violations"], 0);
  // For repeat addressing (the default) charts keep 2^3 texels from the border, so that no
  // lookup of levels 0..3 wraps around: its report's check, measured with that addressing,
  // and the checker's --wrap find nothing.
  const Result wrapped = run("uvpack pack " + cube + " -o " + (dir / "wrapped.obj").string() + " --size 256 --padding 2 --mip-safe 3 --json");
  ASSERT_EQ(wrapped.code, 0) << wrapped.err;
  const auto wrapped_report = nlohmann::json::parse(wrapped.out);
  EXPECT_EQ(wrapped_report["border_margin"], 8);
  EXPECT_EQ(wrapped_report["check"]["mip_violations"], 0);
  EXPECT_EQ(run("uvpack check " + (dir / "wrapped.obj").string() + " --size 256 --padding 2 --mip-safe 3 --wrap --fail-on mip,padding").code, 0);
  // Where that margin leaves no room, the error names --mip-safe, not the padding.
  const Result no_room = run("uvpack pack " + cube + " -o " + (dir / "x.obj").string() + " --size 16 --padding 2 --mip-safe 3");
  EXPECT_EQ(no_room.code, 2);
  EXPECT_NE(no_room.err.find("--mip-safe 3 (8 texels from each side under --wrap; --clamp keeps none) leaves no texel inside a 16-texel atlas"),
            std::string::npos)
      << no_room.err;
  EXPECT_GT(report["utilization"].get<double>(), 0.05);
  EXPECT_GT(report["texel_coverage"].get<double>(), report["utilization"].get<double>());
  const Result check = run("uvpack check " + (dir / "safe.obj").string() + " --size 256 --mip-safe 3 --fail-on mip,shared --report " +
                           (dir / "r.json").string());
  EXPECT_EQ(check.code, 0) << check.err;
  std::ifstream in(dir / "r.json");
  const auto r = nlohmann::json::parse(in);
  EXPECT_EQ(r["mip_safe_levels"], 3);
  EXPECT_TRUE(r["mip_violations"].empty());
  // The plain packing at padding 2 is not mip-safe to level 3: --fail-on mip exits 1.
  ASSERT_EQ(run("uvpack pack " + cube + " -o " + (dir / "plain.obj").string() + " --size 256 --padding 2").code, 0);
  EXPECT_EQ(run("uvpack check " + (dir / "plain.obj").string() + " --size 256 --mip-safe 3 --fail-on mip").code, 1);
  EXPECT_EQ(run("uvpack check " + cube + " --size 100 --mip-safe 3").code, 2) << "100 is not a multiple of 8";
  EXPECT_EQ(run("uvpack pack " + cube + " -o " + (dir / "x.obj").string() + " --size 100 --mip-safe 3").code, 2);
  EXPECT_EQ(run("uvpack check " + cube + " --size 64 --fail-on mip").code, 2) << "--fail-on mip needs --mip-safe";
  EXPECT_EQ(run("uvpack pack " + cube + " -o " + (dir / "x.obj").string() + " --size 64 --padding 64").code, 2) << "no room inside the margin";
  const Result crowded = run("uvpack pack " + cube + " -o " + (dir / "x.obj").string() + " --size 8 --padding 4");
  EXPECT_EQ(crowded.code, 3) << "6 charts 5 texels apart cannot fit 8^2";
  EXPECT_NE(crowded.err.find("cannot fit"), std::string::npos) << crowded.err;
  EXPECT_FALSE(fs::exists(dir / "x.obj"));

  // --density: a map with detail on the packed layout's first chart only (its UV box; the
  // other charts lie 2 texels away or more, on a constant).
  ASSERT_EQ(run("uvpack pack " + cube + " -o " + (dir / "layout.obj").string() + " --size 64 --padding 2").code, 0);
  const Mesh layout = read_mesh(dir / "layout.obj");
  size_t charts = 0;
  const std::vector<int> chart = uv_charts(layout, &charts);
  ASSERT_EQ(charts, 6u);
  float u0 = 1, u1 = 0, v0 = 1, v1 = 0;
  for (auto f : layout.faces())
    if (chart[static_cast<size_t>(f.idx())] == chart[0])
      for (auto h : face_halfedges(layout, f)) {
        const Vec2f t = layout.texcoord2D(h);
        u0 = std::min(u0, t[0]), u1 = std::max(u1, t[0]), v0 = std::min(v0, t[1]), v1 = std::max(v1, t[1]);
      }
  Image map(64, 64, 1, 0.5f);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      const float u = (x + 0.5f) / 64, v = 1 - (y + 0.5f) / 64;
      if (u >= u0 && u <= u1 && v >= v0 && v <= v1) map.at(x, y) = static_cast<float>((x * 7 + y * 13) % 5) / 5.0f;
    }
  write_image(map, dir / "detail.exr", PixelFormat::float32);
  const Result dense = run("uvpack pack " + (dir / "layout.obj").string() + " -o " + (dir / "dense.obj").string() +
                           " --size 64 --padding 2 --density " + (dir / "detail.exr").string() + " --json");
  ASSERT_EQ(dense.code, 0) << dense.err;
  const auto dr = nlohmann::json::parse(dense.out);
  const auto& per_chart = dr["density"]["per_chart"];
  ASSERT_EQ(per_chart.size(), 6u);
  double detailed_gain = 0, other_gain = 0;
  for (const auto& c : per_chart) {
    const double gain = c["texels_after"].get<double>() / c["texels_before"].get<double>();
    if (c["chart"] == chart[0]) {
      EXPECT_EQ(c["scale"], 2.0) << "clamped growth";
      detailed_gain = gain;
    } else {
      EXPECT_EQ(c["scale"], 0.5) << "clamped shrink";
      other_gain = std::max(other_gain, gain);
    }
  }
  EXPECT_NEAR(detailed_gain / other_gain, 16.0, 0.05) << "(2 / 0.5)^2 times the texels, relative to the flat charts";
  EXPECT_EQ(run("uvpack check " + (dir / "dense.obj").string() + " --size 64 --padding 2 --fail-on overlap,shared,padding,outside").code, 0);
  EXPECT_EQ(run("uvpack pack " + cube + " -o " + (dir / "x.obj").string() + " --density " + (dir / "missing.exr").string()).code, 3)
      << "a missing input file, as everywhere";
}

TEST(Cli, BadUsageExitsTwo) {
  EXPECT_EQ(run("").code, 2);
  EXPECT_EQ(run("no-such-command").code, 2);
  EXPECT_EQ(run("meshreduce in.obj").code, 2) << "missing -o";
  EXPECT_EQ(run("meshreduce in.obj -o out.obj --faces 10 --ratio 0.5").code, 2);
  EXPECT_EQ(run("bake --low a.obj --high b.obj -o d --size 12x").code, 2);
  EXPECT_EQ(run("preview --headless base.obj --maps d").code, 2) << "--headless without --png";
  EXPECT_EQ(run("streams pyramid h.exr -o p.exr --wrap --clamp").code, 2);
  EXPECT_EQ(run("streams sdf h.exr -o s.exr --depth 0").code, 2);
  EXPECT_EQ(run("streams cone h.exr -o c.exr --tolerance 0").code, 2);
  EXPECT_EQ(run("preview base.obj --maps d --headless --png p.png --zoom nan").code, 2);
  EXPECT_EQ(run("preview base.obj --maps d --headless --png p.png --pan 0.5").code, 2) << "--pan takes X,Y";
  EXPECT_EQ(run("preview base.obj --maps d --headless --png p.png --pan 0.5,inf").code, 2);
  EXPECT_EQ(run("meshreduce in.obj -o out.obj --ratio nan").code, 2);
  EXPECT_EQ(run("streams sdf h.exr -o s.exr --relief inf").code, 2);
  // Finite as doubles but not as floats: they became inf in metadata, null in JSON, or NaN maps.
  EXPECT_EQ(run("streams sdf h.exr -o s.exr --relief 1e39").code, 2);
  EXPECT_EQ(run("streams vdm h.exr -o v.exr --relief 1e39").code, 2);
  EXPECT_EQ(run("streams vdm h.exr -o v.exr --relief 11").code, 2) << "beyond 10: a tiling map's rays walked for minutes";
  EXPECT_EQ(run("streams vdm h.exr -o v.exr --curvatures 0,0").code, 2) << "curvatures must increase strictly";
  EXPECT_EQ(run("streams vdm h.exr -o v.exr --curvatures \"\"").code, 2) << "an empty list given is not the default";
  EXPECT_EQ(run("streams dstream --low a.obj --high b.obj -o d.bin --front 1e39").code, 2);
  EXPECT_EQ(run("streams cone h.exr -o c.exr --tolerance nan").code, 2);
  EXPECT_EQ(run("streams cone h.exr -o c.png").code, 2) << "streams are EXR: refused before any work";
  // An option's own check speaks in one line of meso's form, naming the option and the value
  // (CLI11's PositiveNumber printed DBL_MAX's 309 digits, then a second line).
  for (const std::string& args : {std::string("meshreduce in.obj -o out.obj --faces -5"), std::string("--threads -1 meshreduce in.obj -o o.obj --faces 5"),
                                  std::string("preview base.obj --maps d --headless --png p.png --zoom 0")}) {
    const Result r = run(args);
    EXPECT_EQ(r.code, 2) << args;
    EXPECT_EQ(lines(r.err), 1u) << r.err;
    EXPECT_EQ(r.err.rfind("meso: error: --", 0), 0u) << r.err;
    EXPECT_LT(r.err.size(), 120u) << r.err;
  }
}

// Output names that cannot work are refused before any work, naming the user's path (they
// failed after the work with exit 4, naming the temporary file, or silently lost an output).
TEST(Cli, OutputsThatCannotBeWrittenAreUsageErrors) {
  test::TempDir dir;
  write_mesh(test::make_grid(2, 2), dir / "grid.obj");
  const std::string grid = (dir / "grid.obj").string();
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"uvpack check " + grid + " --size 16 -o " + (dir / "ov.xyz").string(), "unknown image extension"},
      {"uvpack check " + grid + " --size 16 -o " + (dir / "same.png").string() + " --report " + (dir / "same.png").string(),
       "same.png: named for two outputs of this run"},
      {"uvpack check " + grid + " --size 16 --report " + (dir / "nodir").string() + "/", "nodir/: names a folder"},
      {"meshreduce " + grid + " -o /proc/meso-test.obj --faces 4", "/proc/meso-test.obj: cannot write there: "},
  };
  for (const auto& [args, message] : cases) {
    const Result r = run(args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
    EXPECT_EQ(lines(r.err), 1u) << r.err;
    EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find(".meso-tmp"), std::string::npos) << r.err;
  }
  EXPECT_FALSE(fs::exists(dir / "same.png"));
  EXPECT_FALSE(fs::exists(dir / "nodir"));
}

// An output naming an input (also spelled another way) is refused before any work and the
// input is left as it was (streams cone IN -o IN had replaced the height map by its cones).
TEST(Cli, AnOutputOverItsOwnInputIsRefused) {
  test::TempDir dir;
  write_mesh(test::make_grid(2, 2), dir / "grid.obj");
  Image h(4, 4, 1, 0.25f);
  write_image(h, dir / "h.exr", PixelFormat::float32);
  const std::string grid = (dir / "grid.obj").string(), other_spelling = (dir / "." / "grid.obj").string();
  const std::string height = (dir / "h.exr").string();
  const auto grid_before = test::read_text(dir / "grid.obj");
  const std::vector<std::string> cases = {
      "meshreduce " + grid + " -o " + other_spelling + " --faces 4",
      "meshreduce " + grid + " -o " + (dir / "r.obj").string() + " --faces 4 --progressive " + grid,
      "uvpack pack " + grid + " -o " + grid + " --size 16",
      "streams cone " + height + " -o " + height,
      "streams sdf " + height + " -o " + (dir / "." / "h.exr").string(),
  };
  for (const std::string& args : cases) {
    const Result r = run(args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
    EXPECT_EQ(lines(r.err), 1u) << r.err;
    EXPECT_NE(r.err.find("is also the input"), std::string::npos) << r.err;
  }
  EXPECT_EQ(test::read_text(dir / "grid.obj"), grid_before);
  EXPECT_EQ(read_image(dir / "h.exr").pixels, h.pixels);
  EXPECT_FALSE(fs::exists(dir / "r.obj"));
  // preview's frame over a stream it could read (it had replaced pyramid.exr with the frame).
  ASSERT_EQ(run("bake --low " + grid + " --high " + grid + " -o " + (dir / "maps").string() + " --size 16").code, 0);
  const std::string displacement = (dir / "maps" / "displacement.exr").string(), pyramid = (dir / "maps" / "pyramid.exr").string();
  ASSERT_EQ(run("streams pyramid " + displacement + " -o " + pyramid).code, 0);
  const auto pyramid_before = test::read_text(dir / "maps" / "pyramid.exr");
  for (const std::string& extra : {std::string(" --headless --method pyramid"), std::string(" --compare --method pyramid")}) {
    const Result r = run("preview " + grid + " --maps " + (dir / "maps").string() + extra + " --size 8x8 --png " + pyramid);
    EXPECT_EQ(r.code, 2) << extra << "\n" << r.err;
    EXPECT_NE(r.err.find("is also the input"), std::string::npos) << r.err;
  }
  EXPECT_EQ(test::read_text(dir / "maps" / "pyramid.exr"), pyramid_before);
}

// Numbers beyond int are out of range, said as such (CLI11 had said "Could not convert", and
// --size "is not N or WxH").
TEST(Cli, HugeCountsAreOutOfRange) {
  const Result threads = run("--threads 99999999999 streams cone h.exr -o c.exr");
  EXPECT_EQ(threads.code, 2);
  EXPECT_EQ(lines(threads.err), 1u) << threads.err;
  EXPECT_EQ(threads.err.find("Could not convert"), std::string::npos) << threads.err;
  EXPECT_NE(threads.err.find("--threads"), std::string::npos) << threads.err;
  const Result size = run("bake --low a.obj --high b.obj -o d --size 99999999999");
  EXPECT_EQ(size.code, 2);
  EXPECT_NE(size.err.find("out of range"), std::string::npos) << size.err;
}

// Bounded floating-point options refuse NaN (CLI::Range let it through: `streams vdm
// --theta-max nan` wrote an all-zero map with exit 0) and say their range as written.
TEST(Cli, BoundedNumbersRefuseNanAndSayTheirRange) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"streams vdm h.exr -o v.exr --theta-max nan", "--theta-max: 'nan' is not a number in [1, 90]"},
      {"preview b.obj --maps m --view-angle 95", "--view-angle: '95' is not a number in [0, 89.9]"},
      {"meshreduce a.obj -o b.obj --ratio 0", "--ratio: '0' is not a number in (0, 1]"},
      {"meshreduce a.obj -o b.obj --ratio inf", "--ratio: 'inf' is not a number in (0, 1]"},
      {"preview b.obj --maps m --zoom 1e9", "--zoom: '1e9' is not a number in [0.001, 1000]"},
  };
  for (const auto& [args, message] : cases) {
    const Result r = run(args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
    EXPECT_EQ(lines(r.err), 1u) << r.err;
    EXPECT_NE(r.err.find(message), std::string::npos) << args << "\n" << r.err;
  }
}

// A bake whose maps cannot fit in this machine's memory is refused before any work (32768^2,
// about 53 GB, had run a 24 GB machine out of memory).
TEST(Cli, BakeBeyondTheMachinesMemoryIsRefused) {
  if (physical_memory_bytes() > 50e9) GTEST_SKIP() << "this machine could hold a 32768^2 bake";
  const Result r = run("bake --low a.obj --high b.obj -o d --size 32768");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find("bake --size 32768 needs about 52.6 GB of memory"), std::string::npos) << r.err;
}

TEST(Cli, BadInputExitsThreeWithOneLineNamingTheFileAndNoOutput) {
  test::TempDir dir;
  test::write_text(dir / "garbage.obj", "\x7f\x45\x4c\x46 definitely not a mesh \x01\x02");
  test::write_text(dir / "nan.obj", "v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n");
  test::write_text(dir / "nouv.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n");
  // Non-manifold (import warns) and without UVs (bake fails): still exactly one line.
  test::write_text(dir / "fan.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 1 0 1\nf 1 2 3\nf 2 4 3\nf 2 3 5\n");
  test::write_text(dir / "nan.exr", "");
  test::write_text(dir / "nanuv.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvt nan 0\nvt 1 1\nf 1/1 2/2 3/3\n");
  test::write_text(dir / "flatuv.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0.5 0.5\nf 1/1 2/1 3/1\n");
  // A 0.01-unit triangle 1e6 units out, where floats step by 0.0625: its shape is gone.
  test::write_text(dir / "far.obj", "v 1000000 0 0\nv 1000000.01 0 0\nv 1000000 0.01 0\nf 1 2 3\n");
  // Finite heights whose span overflows float: they cannot be normalised (were NaN, exit 4).
  Image wide(4, 4, 1, 0.0f);
  wide.at(0, 0) = -3e38f;
  wide.at(3, 3) = 3e38f;
  write_image(wide, dir / "wide.exr", PixelFormat::float32);
  // Cut short: a float TIFF (libtiff reports the short strip, yet OIIO's read succeeded with
  // zeros), a PNG's pixels and a PNG's header (libpng printed its own lines besides meso's).
  // A PNG damaged inside its data, not under ASan (OIIO 2.4 leaks on libpng's error path).
  Image waves(64, 64, 1);
  for (size_t i = 0; i < waves.pixels.size(); ++i) waves.pixels[i] = 0.5f + 0.5f * std::sin(0.37f * float(i % 64) + 0.11f * float(i / 64));
  write_image(waves, dir / "cut.tif", PixelFormat::float32);
  write_image(waves, dir / "cut.png", PixelFormat::uint16);
  fs::copy_file(dir / "cut.png", dir / "head.png");
  std::string damaged = test::read_text(dir / "cut.png");
  damaged[damaged.find("IDAT") + 200] ^= 0x55;
  test::write_text(dir / "damaged.png", damaged);
  fs::resize_file(dir / "cut.tif", fs::file_size(dir / "cut.tif") / 2);
  fs::resize_file(dir / "cut.png", fs::file_size(dir / "cut.png") / 2);
  fs::resize_file(dir / "head.png", 30);
  struct Case {
    std::string args, file;
  };
  const std::string out = (dir / "out.obj").string();
  const std::vector<Case> cases = {
      {"meshreduce " + (dir / "missing.obj").string() + " -o " + out + " --faces 10", "missing.obj"},
      {"meshreduce " + (dir / "garbage.obj").string() + " -o " + out + " --faces 10", "garbage.obj"},
      {"meshreduce " + (dir / "nan.obj").string() + " -o " + out + " --faces 10", "nan.obj"},
      {"meshreduce " + (dir / "far.obj").string() + " -o " + out + " --faces 10", "far.obj: its coordinates reach 1e+06"},
      {"bake --low " + (dir / "nouv.obj").string() + " --high " + (dir / "nouv.obj").string() + " -o " +
           (dir / "maps").string() + " --size 16",
       "nouv.obj"},
      {"uvpack check " + (dir / "nouv.obj").string() + " --size 16 -o " + (dir / "o.png").string(), "nouv.obj"},
      {"bake --low " + (dir / "fan.obj").string() + " --high " + (dir / "nouv.obj").string() + " -o " +
           (dir / "maps").string() + " --size 16",
       "fan.obj"},
      {"streams pyramid " + (dir / "nan.exr").string() + " -o " + (dir / "o.exr").string(), "nan.exr"},
      {"streams relaxed-cone " + (dir / "nan.exr").string() + " -o " + (dir / "o.exr").string(), "nan.exr"},
      {"streams dilate-erode " + (dir / "nan.exr").string() + " -o " + (dir / "o.exr").string() + " --radius 1", "nan.exr"},
      {"bake --low " + (dir / "flatuv.obj").string() + " --high " + (dir / "nouv.obj").string() + " -o " + (dir / "maps").string() + " --size 16",
       "flatuv.obj"},
      {"streams cone " + (dir / "wide.exr").string() + " -o " + (dir / "o.exr").string(), "wide.exr"},
      {"streams sdf " + (dir / "wide.exr").string() + " -o " + (dir / "o.exr").string(), "wide.exr"},
      {"uvpack check " + (dir / "nanuv.obj").string() + " --size 16 -o " + (dir / "o.png").string(), "nanuv.obj: line 5"},
      {"streams cone " + (dir / "cut.tif").string() + " -o " + (dir / "o.exr").string(), "cut.tif: cannot read image data"},
      {"streams cone " + (dir / "cut.png").string() + " -o " + (dir / "o.exr").string(), "cut.png: cut short: its IDAT chunk"},
      {"streams cone " + (dir / "head.png").string() + " -o " + (dir / "o.exr").string(), "head.png: cut short: its IHDR chunk"},
#if !defined(__SANITIZE_ADDRESS__)
      {"streams cone " + (dir / "damaged.png").string() + " -o " + (dir / "o.exr").string(), "damaged.png: cannot read image data"},
#endif
      {"meshreduce --from-progressive " + dir.path().string() + " --faces 10 -o " + out, "is a folder"},
      {"uvpack pack " + (dir / "flatuv.obj").string() + " -o " + out + " --density " + (dir / "nope.exr").string(), "nope.exr: no such file"},
      {"uvpack pack " + (dir / "flatuv.obj").string() + " -o " + out, "flatuv.obj: its UVs have no area"},
      {"frames " + (dir / "flatuv.obj").string() + " -o " + (dir / "o.glb").string() + " --curvature-map " + (dir / "o.exr").string() + " --size 16",
       "flatuv.obj: its UV triangles cover no texel"},
  };
  for (const auto& c : cases) {
    const Result r = run(c.args);
    EXPECT_EQ(r.code, 3) << c.args << "\n" << r.err;
    EXPECT_EQ(lines(r.err), 1u) << r.err;
    EXPECT_NE(r.err.find(c.file), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
    EXPECT_FALSE(fs::exists(dir / "o.png"));
    EXPECT_FALSE(fs::exists(dir / "o.exr"));
    EXPECT_TRUE(!fs::exists(dir / "maps") || fs::is_empty(dir / "maps")) << "no partial bake output";
  }
  // Nearer (1e4: steps of 1/1024, 1.4 % of its edges) it is read, with a warning saying why
  // its detail is coarse.
  test::write_text(dir / "near.obj", "v 10000 0 0\nv 10000.05 0 0\nv 10000 0.05 0\nf 1 2 3\n");
  const Result near = run("meshreduce " + (dir / "near.obj").string() + " -o " + out + " --faces 10");
  EXPECT_EQ(near.code, 0) << near.err;
  EXPECT_NE(near.err.find("near.obj: coordinates reach 1e+04, where 32-bit floats step by 0.000977"), std::string::npos) << near.err;
}

// streams vdm holds its raw table in memory: options that would make it larger than 2 GiB
// are refused up front (exit 2, one line) instead of exhausting the machine.
TEST(Cli, StreamsVdmRefusesATableBeyondItsMemoryLimit) {
  test::TempDir dir;
  write_image(Image(512, 512, 1, 0.5f), dir / "h.exr", PixelFormat::float32);
  const Result r = run("streams vdm " + (dir / "h.exr").string() + " -o " + (dir / "v.exr").string() + " --theta 64 --phi 64");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find("4.0 GiB"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "v.exr"));
  // More directions than the compression can solve for in reasonable time, even on one texel
  // (its covariance is directions x directions: 16384 had run for minutes).
  write_image(Image(1, 1, 1, 0.5f), dir / "one.exr", PixelFormat::float32);
  const Result many = run("streams vdm " + (dir / "one.exr").string() + " -o " + (dir / "v.exr").string() + " --theta 256 --phi 64");
  EXPECT_EQ(many.code, 2) << many.err;
  EXPECT_NE(many.err.find("16384 directions"), std::string::npos) << many.err;
  EXPECT_FALSE(fs::exists(dir / "v.exr"));
}

// --max-error is met within --max-rank components; when they fall short the command still
// writes the table (its error is in the report) but says so, naming the knob to raise.
TEST(Cli, StreamsVdmWarnsWhenTheRankCapMissesTheError) {
  test::TempDir dir;
  Image h(16, 16, 1);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) h.at(x, y) = static_cast<float>((x * 7 + y * 13) % 11) / 10.0f;
  write_image(h, dir / "h.exr", PixelFormat::float32);
  const std::string base = "streams vdm " + (dir / "h.exr").string() + " -o " + (dir / "v.exr").string() + " --theta 4 --phi 4 --relief 0.5";
  const Result capped = run(base + " --max-rank 1 --max-error 1e-6");
  ASSERT_EQ(capped.code, 0) << capped.err;
  EXPECT_NE(capped.err.find("--max-rank 1 components were not enough"), std::string::npos) << capped.err;
  const Result met = run(base + " --max-rank 64 --max-error 1");
  ASSERT_EQ(met.code, 0) << met.err;
  EXPECT_EQ(met.err.find("were not enough"), std::string::npos) << met.err;
  // At full rank (16 directions, 16 components) the error left is float rounding: no rank
  // would lower it, so no warning even for --max-error 0.
  const Result full = run(base + " --max-rank 4096 --max-error 0");
  ASSERT_EQ(full.code, 0) << full.err;
  EXPECT_EQ(full.err.find("were not enough"), std::string::npos) << full.err;
}

// A one-channel float EXR written with OpenEXR itself: meso's writer refuses non-finite
// samples, and the inputs here must have them.
void write_exr_as_is(const Image& image, const fs::path& path) {
  Imf::Header header(image.width, image.height);
  header.channels().insert("Y", Imf::Channel(Imf::FLOAT));
  Imf::FrameBuffer frame;
  frame.insert("Y", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(const_cast<float*>(image.pixels.data())), sizeof(float),
                               sizeof(float) * static_cast<size_t>(image.width)));
  Imf::OutputFile file(path.c_str(), header);
  file.setFrameBuffer(frame);
  file.writePixels(image.height);
}

// A height map that states a broken mapping to object units (meso:height_scale 'nan') is
// refused naming it; it had been dropped without a word, the raw values taken for heights.
TEST(Cli, StreamsRefuseABrokenHeightMapping) {
  test::TempDir dir;
  Image img(4, 4, 1, 0.5f);
  img.at(1, 1) = 0.75f;
  img.metadata["height_bias"] = 0.0f;
  for (const std::string scale : {"nan", "-1", "abc"}) {
    img.metadata["height_scale"] = scale;
    write_image(img, dir / "m.png", PixelFormat::uint16);
    const Result r = run("streams cone " + (dir / "m.png").string() + " -o " + (dir / "c.exr").string());
    EXPECT_EQ(r.code, 3) << scale << ": " << r.err;
    EXPECT_NE(r.err.find("m.png: its meso:height_scale is not a finite number"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "c.exr"));
  }
  // A range float cannot hold: the scale lost in the bias (every height had come out the
  // same), or bias + scale beyond the float range.
  for (const auto& [bias, scale, message] : {std::tuple<std::string, std::string, std::string>{"3e38", "1", "is below a float step"},
                                             {"3e38", "1e38", "overflows a float"}}) {
    img.metadata["height_bias"] = bias;
    img.metadata["height_scale"] = scale;
    write_image(img, dir / "m.png", PixelFormat::uint16);
    const Result r = run("streams cone " + (dir / "m.png").string() + " -o " + (dir / "c.exr").string());
    EXPECT_EQ(r.code, 3) << bias << " " << scale << ": " << r.err;
    EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "c.exr"));
  }
  img.metadata["height_bias"] = 0.0f;
  img.metadata["height_scale"] = 2.0f;
  write_image(img, dir / "m.png", PixelFormat::uint16);
  EXPECT_EQ(run("streams cone " + (dir / "m.png").string() + " -o " + (dir / "c.exr").string()).code, 0);
}

// A height map with non-finite texels: every stream exits 3 with one line naming the file and
// the first bad texel in row order, and writes nothing.
TEST(Cli, StreamsNameTheFirstNonFiniteTexel) {
  test::TempDir dir;
  Image bad(8, 6, 1, 0.5f);
  bad.at(5, 4) = -std::numeric_limits<float>::infinity();
  bad.at(2, 3) = std::numeric_limits<float>::infinity();  // first in row order: row 3 before row 4
  write_exr_as_is(bad, dir / "inf.exr");
  for (const std::string stream : {"pyramid", "cone", "relaxed-cone", "sdf", "dilate-erode --radius 1"}) {
    const Result r = run("streams " + stream.substr(0, stream.find(' ')) + " " + (dir / "inf.exr").string() + " -o " +
                         (dir / "o.exr").string() + (stream.find(' ') == std::string::npos ? "" : stream.substr(stream.find(' '))));
    EXPECT_EQ(r.code, 3) << stream << "\n" << r.err;
    EXPECT_EQ(lines(r.err), 1u) << r.err;
    EXPECT_NE(r.err.find("inf.exr"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("infinite sample at texel (2, 3)"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "o.exr"));
  }
}

// OpenImageIO lives in a module opened on the first image read or write
// (formats/src/image_io_backend.hpp): a command that touches no image never opens it, and
// one that does but cannot open it fails with exit 4 and one line naming the module.
TEST(Cli, ImageModuleIsOpenedOnlyWhenAnImageIsRead) {
  test::TempDir dir;
  example("--columns 8 --rows 4 -o " + (dir / "wall.obj").string());
  const std::string no_module = "MESO_IMAGE_MODULE=" + (dir / "missing.so").string() + " ";
  const Result reduce = run_env(no_module, "meshreduce " + (dir / "wall.obj").string() + " -o " + (dir / "low.obj").string() + " --faces 20");
  EXPECT_EQ(reduce.code, 0) << reduce.err;
  EXPECT_TRUE(fs::exists(dir / "low.obj"));
  test::write_text(dir / "h.exr", "");
  const Result cone = run_env(no_module, "streams cone " + (dir / "h.exr").string() + " -o " + (dir / "cone.exr").string());
  EXPECT_EQ(cone.code, 4) << cone.err;
  EXPECT_EQ(lines(cone.err), 1u) << cone.err;
  EXPECT_NE(cone.err.find("missing.so"), std::string::npos) << cone.err;
  EXPECT_FALSE(fs::exists(dir / "cone.exr"));
}

TEST(Cli, UvCheckFailsOnRequestOnly) {
  test::TempDir dir;
  // Two separate triangles in 3D mapped onto the same UV triangle.
  test::write_text(dir / "twice.obj",
                   "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 0 0\nv 6 0 0\nv 5 1 0\n"
                   "vt 0.1 0.1\nvt 0.9 0.1\nvt 0.1 0.9\n"
                   "f 1/1 2/2 3/3\nf 4/1 5/2 6/3\n");
  const std::string report = (dir / "r.json").string();
  const Result plain = run("uvpack check " + (dir / "twice.obj").string() + " --size 64 --report " + report);
  EXPECT_EQ(plain.code, 0) << plain.err;
  const auto j = nlohmann::json::parse(test::read_text(report));
  EXPECT_EQ(j["overlapping_faces"], nlohmann::json({0, 1}));
  EXPECT_EQ(j["overlap_pairs"], nlohmann::json({{0, 1}}));
  EXPECT_EQ(j["charts"], 2);
  const Result strict = run("uvpack check " + (dir / "twice.obj").string() + " --size 64 --fail-on flipped,overlap");
  EXPECT_EQ(strict.code, 1);
  EXPECT_EQ(run("uvpack check " + (dir / "twice.obj").string() + " --size 64 --fail-on flipped").code, 0);
  EXPECT_EQ(run("uvpack check " + (dir / "twice.obj").string() + " --fail-on nonsense").code, 2);
}

class Skeleton : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir();
    // A flat wall: the base is the z = 0 plane, so the bake's answer is brick_wall_height.
    example("--bend-radius 0 --columns 300 --rows 150 -o " + (*dir_ / "high.obj").string());
    example("--bend-radius 0 --base --columns 4 --rows 2 -o " + (*dir_ / "base.obj").string());
  }
  static void TearDownTestSuite() { delete dir_; }
  static test::TempDir* dir_;
};
test::TempDir* Skeleton::dir_ = nullptr;

// A progress bar on a terminal (here a pseudo-terminal from util-linux's `script`), and none
// when stderr is a file or with --quiet.
TEST_F(Skeleton, BakeShowsAProgressBarOnATerminalOnly) {
  const auto& d = *dir_;
  const std::string bake = std::string(MESO_EXE) + " bake --low " + (d / "base.obj").string() + " --high " + (d / "high.obj").string() +
                           " --size 64x32 -o ";
  auto on_terminal = [&](const std::string& args) {
    const std::string cmd = "script -qec '" + args + "' /dev/null";
    std::string out;
    FILE* p = ::popen(cmd.c_str(), "r");
    if (!p) return out;
    char buf[4096];
    for (size_t n; (n = std::fread(buf, 1, sizeof buf, p)) > 0;) out.append(buf, n);
    EXPECT_EQ(::pclose(p), 0) << cmd;
    return out;
  };
  const std::string tty = on_terminal(bake + (d / "tty").string());
  EXPECT_NE(tty.find("\rbake"), std::string::npos) << tty;
  EXPECT_NE(tty.find("[" + std::string(30, '#') + "] 100.0%"), std::string::npos) << tty;
  EXPECT_EQ(on_terminal(bake + (d / "tty_quiet").string() + " --quiet").find('\r'), std::string::npos);
  const Result file = run("bake --low " + (d / "base.obj").string() + " --high " + (d / "high.obj").string() + " --size 64x32 -o " +
                          (d / "not_tty").string());
  ASSERT_EQ(file.code, 0) << file.err;
  EXPECT_EQ(file.err.find('\r'), std::string::npos) << file.err;
}

TEST_F(Skeleton, BakeReproducesTheHeightFieldAndIsDeterministic) {
  const auto& d = *dir_;
  const Result r = run("bake --low " + (d / "base.obj").string() + " --high " + (d / "high.obj").string() + " -o " +
                    (d / "maps1").string() + " --size 128x64 --threads 1 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto report = nlohmann::json::parse(r.out);
  EXPECT_EQ(report["misses"], 0);
  EXPECT_EQ(report["covered_texels"], 128 * 64);
  const Image disp = read_image(d / "maps1" / "displacement.exr");
  ASSERT_EQ(disp.width, 128);
  ASSERT_EQ(disp.height, 64);
  BrickWallOptions w;
  std::vector<float> err;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 128; ++x)
      err.push_back(std::abs(disp.at(x, y) - brick_wall_height(w, texel_center_u(x, 128) * w.width, texel_center_v(y, 64) * w.height)));
  std::sort(err.begin(), err.end());
  EXPECT_LT(err[err.size() / 2], 0.02f * w.amplitude);
  EXPECT_LT(err[err.size() * 9 / 10], 0.2f * w.amplitude);  // bevel kinks between grid vertices
  // The metadata says what the values are: object units, and their range (every texel holds
  // a hit's value after the dilation, so the range is the image's).
  ASSERT_EQ(disp.metadata.count("units"), 1u);
  EXPECT_EQ(std::get<std::string>(disp.metadata.at("units")), "object");
  ASSERT_EQ(disp.metadata.count("min"), 1u);
  ASSERT_EQ(disp.metadata.count("max"), 1u);
  EXPECT_EQ(std::get<float>(disp.metadata.at("min")), *std::min_element(disp.pixels.begin(), disp.pixels.end()));
  EXPECT_EQ(std::get<float>(disp.metadata.at("max")), *std::max_element(disp.pixels.begin(), disp.pixels.end()));
  const Image normals = read_image(d / "maps1" / "normal_ts.png");
  EXPECT_EQ(normals.channels, 3);

  const Result r2 = run("bake --low " + (d / "base.obj").string() + " --high " + (d / "high.obj").string() + " -o " +
                     (d / "maps2").string() + " --size 128x64 --threads 2 --quiet");
  ASSERT_EQ(r2.code, 0) << r2.err;
  EXPECT_EQ(r2.err, "") << "--quiet";
  EXPECT_EQ(read_image(d / "maps1" / "coverage.png").channels, 1);
  // Rays that cannot reach the high surface: every covered texel misses, the check fails
  // (exit 1) yet the maps are written, and the report names the faces.
  const Result short_rays = run("bake --low " + (d / "base.obj").string() + " --high " + (d / "high.obj").string() + " -o " +
                                (d / "maps3").string() + " --size 32x16 --front 1e-7 --back 1e-7 --max-miss-rate 0.5 --json");
  EXPECT_EQ(short_rays.code, 1) << short_rays.err;
  EXPECT_TRUE(std::filesystem::exists(d / "maps3" / "displacement.exr"));
  const auto miss_report = nlohmann::json::parse(short_rays.out);
  EXPECT_GT(miss_report["miss_rate"].get<double>(), 0.5);
  EXPECT_FALSE(miss_report["miss_faces"].empty());
  for (const char* f : {"displacement.exr", "normal_ts.png", "coverage.png"})
    EXPECT_EQ(test::read_text(d / "maps1" / f), test::read_text(d / "maps2" / f)) << f << " differs with the thread count";
}

TEST_F(Skeleton, WholePipeline) {
  const auto& d = *dir_;
  const Result reduce = run("meshreduce " + (d / "high.obj").string() + " -o " + (d / "reduced.obj").string() + " --faces 400 --json");
  ASSERT_EQ(reduce.code, 0) << reduce.err;
  const Mesh reduced = read_mesh(d / "reduced.obj");
  EXPECT_LE(reduced.n_faces(), 400u);
  EXPECT_TRUE(has_uvs(reduced));
  EXPECT_EQ(nlohmann::json::parse(reduce.out)["output"]["faces"], reduced.n_faces());

  const Result check = run("uvpack check " + (d / "reduced.obj").string() + " --size 256 -o " + (d / "overlay.png").string() +
                        " --report " + (d / "uv.json").string());
  ASSERT_EQ(check.code, 0) << check.err;
  const auto uv = nlohmann::json::parse(test::read_text(d / "uv.json"));
  EXPECT_EQ(uv["charts"], 1);
  EXPECT_TRUE(uv["overlapping_faces"].empty());
  EXPECT_EQ(read_image(d / "overlay.png").channels, 4);

  const Result frames = run("frames " + (d / "reduced.obj").string() + " -o " + (d / "framed.glb").string());
  ASSERT_EQ(frames.code, 0) << frames.err;
  EXPECT_EQ(read_mesh(d / "framed.glb").n_faces(), reduced.n_faces());
  // The flat base surface: frames along +x, curvature zero.
  const Result flat = run("frames " + (d / "base.obj").string() + " -o " + (d / "base.gltf").string() + " --json");
  ASSERT_EQ(flat.code, 0) << flat.err;
  const auto flat_report = nlohmann::json::parse(flat.out);
  EXPECT_NEAR(flat_report["curvature"]["min"].get<double>(), 0.0, 1e-4);
  EXPECT_NEAR(flat_report["curvature"]["max"].get<double>(), 0.0, 1e-4);
  const auto gltf = nlohmann::json::parse(test::read_text(d / "base.gltf"));
  const auto& attributes = gltf["meshes"][0]["primitives"][0]["attributes"];
  for (const char* a : {"POSITION", "NORMAL", "TEXCOORD_0", "TANGENT", "_CURVATURE", "_PRINCIPAL_DIRECTION"})
    EXPECT_TRUE(attributes.contains(a)) << a;

  const Result bake = run("bake --low " + (d / "reduced.obj").string() + " --high " + (d / "high.obj").string() + " -o " +
                       (d / "maps").string() + " --size 128x64");
  ASSERT_EQ(bake.code, 0) << bake.err;
  // Chosen maps only, reach as a percentage, the 16-bit displacement with its range.
  const Result chosen = run("bake --low " + (d / "reduced.obj").string() + " --high " + (d / "high.obj").string() + " -o " +
                            (d / "chosen").string() + " --size 64 --maps displacement_png,normal_os --front 4% --back 4% " +
                            "--hit front-else-nearest --ignore-backfaces --json");
  ASSERT_EQ(chosen.code, 0) << chosen.err;
  EXPECT_TRUE(fs::exists(d / "chosen" / "displacement.png"));
  EXPECT_TRUE(fs::exists(d / "chosen" / "normal_os.png"));
  EXPECT_FALSE(fs::exists(d / "chosen" / "displacement.exr"));
  const auto chosen_report = nlohmann::json::parse(chosen.out);
  EXPECT_EQ(chosen_report["hit_rule"], "front-else-nearest");
  EXPECT_NEAR(chosen_report["front"].get<double>(), chosen_report["back"].get<double>(), 1e-9);
  const Image disp_png = read_image(d / "chosen" / "displacement.png");
  // PNG keeps text: the scale is written round-trippably.
  EXPECT_FLOAT_EQ(std::stof(std::get<std::string>(disp_png.metadata.at("height_scale"))),
                  chosen_report["displacement_png"]["scale"].get<float>());
  EXPECT_EQ(run("bake --low " + (d / "reduced.obj").string() + " --high " + (d / "high.obj").string() + " -o " +
                (d / "bad").string() + " --maps displacement,nonsense")
                .code,
            2);
  EXPECT_EQ(run("bake --low " + (d / "reduced.obj").string() + " --high " + (d / "high.obj").string() + " -o " +
                (d / "bad").string() + " --front 5%%")
                .code,
            2);

  const Result pyramid = run("streams pyramid " + (d / "maps" / "displacement.exr").string() + " -o " +
                             (d / "pyramid.exr").string() + " --json");
  ASSERT_EQ(pyramid.code, 0) << pyramid.err;
  const auto levels = read_image_levels(d / "pyramid.exr");
  ASSERT_EQ(levels.size(), 8u) << "128x64 -> ... -> 1x1";
  EXPECT_EQ(levels.back().at(0, 0, 0), 0.0f) << "normalised minimum";
  EXPECT_EQ(levels.back().at(0, 0, 1), 1.0f) << "normalised maximum";
  EXPECT_EQ(nlohmann::json::parse(pyramid.out)["levels"], 8);

  // Dilation and erosion maps: radius 0 is the pyramid's level 0; radius 2 bounds every
  // level-0 footprint of its 5 x 5 window (the border: clamp, the default).
  for (const int radius : {0, 2}) {
    const fs::path de = d / ("de" + std::to_string(radius) + ".exr");
    const Result r = run("streams dilate-erode " + (d / "maps" / "displacement.exr").string() + " -o " + de.string() +
                         " --radius " + std::to_string(radius) + " --json");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(nlohmann::json::parse(r.out)["radius"], radius);
    const Image m = read_image(de);
    ASSERT_EQ(m.channels, 2);
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 128; ++x) {
        if (radius == 0) {
          ASSERT_EQ(m.at(x, y, 0), levels[0].at(x, y, 0));
          ASSERT_EQ(m.at(x, y, 1), levels[0].at(x, y, 1));
          continue;
        }
        float lo = 2, hi = -1;
        for (int j = std::max(0, y - 2); j <= std::min(63, y + 2); ++j)
          for (int i = std::max(0, x - 2); i <= std::min(127, x + 2); ++i) {
            lo = std::min(lo, levels[0].at(i, j, 0));
            hi = std::max(hi, levels[0].at(i, j, 1));
          }
        ASSERT_EQ(m.at(x, y, 0), lo) << x << "," << y;
        ASSERT_EQ(m.at(x, y, 1), hi) << x << "," << y;
      }
  }
  EXPECT_EQ(run("streams dilate-erode " + (d / "maps" / "displacement.exr").string() + " -o " + (d / "x.exr").string()).code, 2)
      << "--radius is required";

  // Cone maps of the baked displacement: the MIP chain of the pyramid's sizes, apexes equal
  // to the pyramid's footprint maxima, ratios finite, relaxed never narrower, coarse levels
  // minimum-filtered.
  const Result cone = run("streams cone " + (d / "maps" / "displacement.exr").string() + " -o " + (d / "cone.exr").string() + " --json");
  ASSERT_EQ(cone.code, 0) << cone.err;
  const Result relaxed = run("streams relaxed-cone " + (d / "maps" / "displacement.exr").string() + " -o " +
                             (d / "relaxed-cone.exr").string());
  ASSERT_EQ(relaxed.code, 0) << relaxed.err;
  const auto cones = read_image_levels(d / "cone.exr"), relaxed_cones = read_image_levels(d / "relaxed-cone.exr");
  ASSERT_EQ(cones.size(), 8u);
  const auto cone_report = nlohmann::json::parse(cone.out);
  EXPECT_EQ(cone_report["levels"], 8);
  EXPECT_GT(cone_report["bytes"].get<size_t>(), 128u * 64u * 12u);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 128; ++x) {
      ASSERT_EQ(cones[0].at(x, y, 2), levels[0].at(x, y, 1)) << x << "," << y;
      ASSERT_TRUE(std::isfinite(cones[0].at(x, y, 1)));
      ASSERT_GE(relaxed_cones[0].at(x, y, 1), cones[0].at(x, y, 1) * (1 - 2e-4f));
    }
  EXPECT_EQ(cones[1].at(3, 5, 1), std::min({cones[0].at(6, 10, 1), cones[0].at(7, 10, 1), cones[0].at(6, 11, 1), cones[0].at(7, 11, 1)}));
  EXPECT_EQ(std::get<std::string>(relaxed_cones[0].metadata.at("cone_kind")), "relaxed");

  // The view-dependent displacement of the baked map on the reduced base: curvature range
  // and relief from the mesh; two parts whose shapes the report states.
  const Result vdm = run("streams vdm " + (d / "maps" / "displacement.exr").string() + " -o " + (d / "vdm.exr").string() +
                         " --theta 3 --phi 4 --mesh " + (d / "reduced.obj").string() + " --curvature-steps 2 --max-rank 6 --json");
  ASSERT_EQ(vdm.code, 0) << vdm.err;
  const auto vdm_report = nlohmann::json::parse(vdm.out);
  const auto vdm_parts = read_image_parts(d / "vdm.exr");
  ASSERT_EQ(vdm_parts.size(), 2u);
  EXPECT_EQ(vdm_parts[0].width, 128);
  EXPECT_EQ(vdm_parts[0].channels, std::max(1, vdm_report["rank"].get<int>()));
  EXPECT_EQ(vdm_parts[1].height, vdm_report["directions"].get<int>());
  EXPECT_EQ(vdm_report["directions"], 3 * 4 * vdm_report["curvatures"].size());
  EXPECT_LT(vdm_report["bytes"].get<double>(), vdm_report["raw_bytes"].get<double>());
  EXPECT_EQ(run("streams vdm " + (d / "maps" / "displacement.exr").string() + " -o " + (d / "v.exr").string() + " --curvatures 0,x").code, 2);
  EXPECT_EQ(run("streams vdm " + (d / "maps" / "displacement.exr").string() + " -o " + (d / "v.exr").string() + " --curvatures 1,0").code, 2)
      << "curvatures must increase";
  // --mesh gives the relief; --curvatures, when given, the slices.
  const Result given = run("streams vdm " + (d / "maps" / "displacement.exr").string() + " -o " + (d / "v.exr").string() +
                           " --theta 2 --phi 2 --curvatures 0 --json --mesh " + (d / "reduced.obj").string());
  ASSERT_EQ(given.code, 0) << given.err;
  const auto given_report = nlohmann::json::parse(given.out);
  EXPECT_EQ(given_report["curvatures"], nlohmann::json::array({0.0}));
  EXPECT_EQ(given_report["relief"], vdm_report["relief"]);
  EXPECT_EQ(given.err.find("raised to 1e-6"), std::string::npos) << given.err;
  // The same mesh at 10^12 times its size: curvature slices and length per u scale with it
  // (they were -inf and null from float areas), and the map's relief, now below 1e-6 of a
  // unit of u, is raised with a warning (it was silent).
  Mesh huge = read_mesh(d / "reduced.obj");
  for (auto v : huge.vertices()) huge.set_point(v, huge.point(v) * 1e12f);
  write_mesh(huge, d / "huge.obj");
  const Result scaled = run("streams vdm " + (d / "maps" / "displacement.exr").string() + " -o " + (d / "vh.exr").string() +
                            " --theta 3 --phi 4 --mesh " + (d / "huge.obj").string() + " --curvature-steps 2 --max-rank 6 --json");
  ASSERT_EQ(scaled.code, 0) << scaled.err;
  const auto scaled_report = nlohmann::json::parse(scaled.out);
  ASSERT_EQ(scaled_report["curvatures"].size(), vdm_report["curvatures"].size());
  for (size_t i = 0; i < scaled_report["curvatures"].size(); ++i)
    EXPECT_NEAR(scaled_report["curvatures"][i].get<double>(), vdm_report["curvatures"][i].get<double>(), 1e-3) << i;
  EXPECT_NEAR(scaled_report["mesh"]["object_length_per_u"].get<double>() / vdm_report["mesh"]["object_length_per_u"].get<double>(), 1e12, 1e6);
  EXPECT_NE(scaled.err.find("raised to 1e-6"), std::string::npos) << scaled.err;

  // Compressed displacement vertex streams: the file's size is the documented layout.
  const Result dstream = run("streams dstream --low " + (d / "reduced.obj").string() + " --high " + (d / "high.obj").string() + " -o " +
                             (d / "dstream.bin").string() + " --levels 3 --json");
  ASSERT_EQ(dstream.code, 0) << dstream.err;
  const auto ds_report = nlohmann::json::parse(dstream.out);
  const size_t ds_vertices = ds_report["vertices"].get<size_t>();
  EXPECT_EQ(fs::file_size(d / "dstream.bin"), 8 + 16 + 8 + 3 * 8 + 8 * ds_vertices);
  EXPECT_EQ(ds_vertices, reduced.n_faces() * (3 + 6 + 15));
  EXPECT_LE(ds_report["max_position_error"].get<double>(),
            (ds_report["displacement_max"].get<double>() - ds_report["displacement_min"].get<double>()) / 32766 * 1.001);

  const Result sdf = run("streams sdf " + (d / "maps" / "displacement.exr").string() + " -o " + (d / "sdf.exr").string() +
                         " --depth 8 --relief 0.05");
  ASSERT_EQ(sdf.code, 0) << sdf.err;
  const Image field = read_image(d / "sdf.exr");
  EXPECT_EQ(field.width, 128);
  EXPECT_EQ(field.height, 64 * 8);
  EXPECT_EQ(std::get<int>(field.metadata.at("depth")), 8);
  // In the top slice (normalised height 15/16) a voxel is inside the solid exactly where the
  // pyramid says the filtered surface reaches that high over its texel.
  size_t inside = 0;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 128; ++x) {
      const bool solid = levels[0].at(x, y, 1) >= 15.0f / 16.0f;
      inside += solid;
      ASSERT_EQ(field.at(x, 7 * 64 + y) == 0.0f, solid) << x << "," << y;
    }
  EXPECT_LT(inside, 128u * 64u / 2);

  const Result preview = run("preview " + (d / "reduced.obj").string() + " --maps " + (d / "maps").string() +
                          " --method pom --headless --png " + (d / "pom.png").string() + " --size 96x64 --view-angle 45");
  ASSERT_EQ(preview.code, 0) << preview.err;
  const Image png = read_image(d / "pom.png");
  EXPECT_EQ(png.width, 96);
  EXPECT_EQ(png.height, 64);
  size_t covered = 0;
  for (size_t i = 0; i < png.texel_count(); ++i) covered += png.pixels[4 * i + 3] > 0.5f;
  EXPECT_GT(covered, png.texel_count() / 10) << "the wall is in the frame";

  // vdm and dstream draw the streams made above (vdm.exr, dstream.bin); a stream made for
  // another base mesh is refused naming the file.
  for (const char* method : {"vdm", "dstream"}) {
    const std::string frame = (d / (std::string(method) + ".png")).string();
    const Result r = run("preview " + (d / "reduced.obj").string() + " --maps " + (d / "maps").string() + " --streams " + d.path().string() +
                         " --method " + method + " --headless --png " + frame + " --size 48x32 --iterations 4 --lod-distance 2");
    ASSERT_EQ(r.code, 0) << method << ": " << r.err;
    const Image img = read_image(frame);
    size_t on = 0;
    for (size_t i = 0; i < img.texel_count(); ++i) on += img.pixels[4 * i + 3] > 0.5f;
    EXPECT_GT(on, img.texel_count() / 10) << method;
  }
  std::filesystem::create_directories(d / "other");
  ASSERT_EQ(run("streams dstream --low " + (d / "base.obj").string() + " --high " + (d / "high.obj").string() + " -o " +
                (d / "other" / "dstream.bin").string() + " --levels 1")
                .code,
            0);
  const Result foreign = run("preview " + (d / "reduced.obj").string() + " --maps " + (d / "maps").string() + " --streams " +
                             (d / "other").string() + " --method dstream --headless --png " + (d / "f.png").string());
  EXPECT_EQ(foreign.code, 3);
  EXPECT_NE(foreign.err.find("dstream.bin"), std::string::npos) << foreign.err;
  EXPECT_FALSE(fs::exists(d / "f.png"));
  // Missing, it names the command that makes it: dstream from the meshes, not the height map.
  std::filesystem::create_directories(d / "none");
  const Result missing = run("preview " + (d / "reduced.obj").string() + " --maps " + (d / "maps").string() + " --streams " +
                             (d / "none").string() + " --method dstream --headless --png " + (d / "f.png").string());
  EXPECT_EQ(missing.code, 3);
  EXPECT_NE(missing.err.find("(meso streams dstream --low " + (d / "reduced.obj").string() + " --high HIGH_MESH -o "), std::string::npos) << missing.err;

  // A turntable: N frames around the mesh, numbered from the --png name, all written or none.
  const Result turntable = run("preview " + (d / "reduced.obj").string() + " --maps " + (d / "maps").string() +
                               " --method relief --shadows soft --headless --png " + (d / "turn.png").string() +
                               " --size 32x24 --turntable 3 --json");
  ASSERT_EQ(turntable.code, 0) << turntable.err;
  EXPECT_EQ(nlohmann::json::parse(turntable.out)["frames"].size(), 3u);
  std::vector<float> alphas;
  for (const char* f : {"turn_000.png", "turn_001.png", "turn_002.png"}) {
    ASSERT_TRUE(fs::exists(d / f)) << f;
    const Image frame = read_image(d / f);
    EXPECT_EQ(frame.width, 32);
    double sum = 0.0;
    for (float v : frame.pixels) sum += v;
    alphas.push_back(static_cast<float>(sum));
  }
  EXPECT_NE(alphas[0], alphas[1]) << "the frames are seen from different azimuths";
  EXPECT_FALSE(fs::exists(d / "turn_003.png"));
  EXPECT_EQ(run("preview " + (d / "reduced.obj").string() + " --maps " + (d / "maps").string() + " --png " +
                (d / "w.png").string() + " --turntable 3")
                .code,
            2)
      << "--turntable without --headless";
  EXPECT_FALSE(fs::exists(d / "w_000.png"));

  const Result traced = run("preview " + (d / "reduced.obj").string() + " --maps " + (d / "maps").string() + " --streams " +
                            d.path().string() + " --method sphere-tracing --headless --png " + (d / "traced.png").string() +
                            " --size 48x32");
  ASSERT_EQ(traced.code, 0) << traced.err;
  // A distance field made from another height map is refused, naming the file.
  Image ramp(128, 64, 1);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 128; ++x) ramp.at(x, y) = 0.001f * static_cast<float>(x);
  std::filesystem::create_directories(d / "stale");
  write_image(ramp, d / "stale" / "ramp.exr", PixelFormat::float32);
  const Result other = run("streams sdf " + (d / "stale" / "ramp.exr").string() + " -o " + (d / "stale" / "sdf.exr").string());
  ASSERT_EQ(other.code, 0) << other.err;
  const Result stale = run("preview " + (d / "reduced.obj").string() + " --maps " + (d / "maps").string() + " --streams " +
                           (d / "stale").string() + " --method sphere-tracing --headless --png " + (d / "x.png").string());
  EXPECT_EQ(stale.code, 3) << stale.err;
  EXPECT_NE(stale.err.find((d / "stale" / "sdf.exr").string()), std::string::npos) << stale.err;

  // A stream whose header numbers were damaged (NaN height_scale) is refused, naming it; it
  // rendered with 96 % wrong hits.
  {
    std::vector<Image> bad_levels = read_image_levels(d / "pyramid.exr");
    bad_levels[0].metadata["height_scale"] = std::nanf("");
    std::filesystem::create_directories(d / "badmeta");
    write_image_levels(bad_levels, d / "badmeta" / "pyramid.exr", PixelFormat::float32);
    const Result bad = run("preview " + (d / "reduced.obj").string() + " --maps " + (d / "maps").string() + " --streams " +
                           (d / "badmeta").string() + " --method pyramid --headless --png " + (d / "x.png").string() + " --size 16x16");
    EXPECT_EQ(bad.code, 3) << bad.err;
    EXPECT_NE(bad.err.find("pyramid.exr: meso:height_scale is nan"), std::string::npos) << bad.err;
  }

  const Result no_stream = run("preview " + (d / "reduced.obj").string() + " --maps " + (d / "maps").string() +
                               " --method sphere-tracing --headless --png " + (d / "x.png").string());
  EXPECT_EQ(no_stream.code, 3);
  EXPECT_NE(no_stream.err.find("sdf.exr"), std::string::npos) << no_stream.err;

  const Result missing_maps = run("preview " + (d / "reduced.obj").string() + " --maps " + (d / "nowhere").string() +
                               " --headless --png " + (d / "x.png").string());
  EXPECT_EQ(missing_maps.code, 3);
  EXPECT_NE(missing_maps.err.find("displacement.exr"), std::string::npos);
  EXPECT_FALSE(fs::exists(d / "x.png"));

  // The measuring instrument: methods against the ray-traced reference, as JSON.
  const std::string base_maps = "preview " + (d / "reduced.obj").string() + " --maps " + (d / "maps").string() + " --streams " + d.path().string();
  const Result compare = run(base_maps + " --compare --method pom,cone,pyramid,sphere-tracing,dig,tessellation --size 64x48 --view-angle 35 --json --heatmaps " +
                             (d / "heat").string() + " --reference-edge 1");
  ASSERT_EQ(compare.code, 0) << compare.err;
  const auto cmp = nlohmann::json::parse(compare.out);
  ASSERT_EQ(cmp["methods"].size(), 6u);
  EXPECT_GT(cmp["reference"]["triangles"].get<size_t>(), reduced.n_faces());
  for (const auto& m : cmp["methods"]) {
    for (const char* key : {"name", "wrong_hit_fraction", "rmse", "psnr", "mean_iterations", "p99_iterations", "ms"})
      EXPECT_TRUE(m.contains(key)) << key;
    EXPECT_GE(m["wrong_hit_fraction"].get<double>(), 0.0);
    EXPECT_LE(m["wrong_hit_fraction"].get<double>(), 0.25) << m["name"] << ": an accurate method on a mildly curved base";
    EXPECT_TRUE(fs::exists(d / "heat" / (m["name"].get<std::string>() + ".png")));
  }
  EXPECT_EQ(run(base_maps + " --compare --method pom,nope --size 32x32").code, 2);
  EXPECT_EQ(run(base_maps + " --heatmaps " + (d / "h2").string() + " --method pom --headless --png " + (d / "y.png").string()).code, 2);
  EXPECT_EQ(run("preview " + (d / "reduced.obj").string() + " --maps " + (d / "maps").string() + " --compare --method sphere-tracing --size 32x32")
                .code,
            3)
      << "no sdf.exr in the maps folder";
}

}  // namespace
}  // namespace meso

// ---- meshreduce: progressive meshes and locks (issue 3) ----

namespace meso {
namespace {

// A 12 x 12 grid in the z = 0 plane with UV = (x, y), written as two OBJ objects (face
// groups after import): "hand", the 3 x 3 quads at columns and rows 4-6, and "body".
std::string two_part_grid_obj() {
  const int n = 12;
  std::string s;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const std::string x = std::to_string(double(i) / n), y = std::to_string(double(j) / n);
      s += "v " + x + " " + y + " 0\nvt " + x + " " + y + "\n";
    }
  for (const bool hand : {false, true}) {
    s += hand ? "o hand\n" : "o body\n";
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        if ((i >= 4 && i < 7 && j >= 4 && j < 7) != hand) continue;
        auto c = [&](int di, int dj) {
          const std::string k = std::to_string((j + dj) * (n + 1) + i + di + 1);
          return " " + k + "/" + k;
        };
        s += "f" + c(0, 0) + c(1, 0) + c(1, 1) + "\nf" + c(0, 0) + c(1, 1) + c(0, 1) + "\n";
      }
  }
  return s;
}

TEST(CliMeshreduce, ProgressiveLevelsEqualDirectReduction) {
  test::TempDir d;
  const std::string in = (d / "grid.obj").string();
  test::write_text(d / "grid.obj", two_part_grid_obj());
  const Result r = run("meshreduce " + in + " -o " + (d / "a.obj").string() + " --faces 60 --progressive " + (d / "a.pm").string() +
                       " --no-measure --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto report = nlohmann::json::parse(r.out);
  EXPECT_EQ(report["progressive"]["bytes"].get<size_t>(), fs::file_size(d / "a.pm"));
  EXPECT_GT(report["progressive"]["collapses"].get<size_t>(), 100u);
  // The last level is the output; others are what reducing directly gives; same bytes again.
  ASSERT_EQ(run("meshreduce --from-progressive " + (d / "a.pm").string() + " --faces 60 -o " + (d / "b.obj").string()).code, 0);
  EXPECT_EQ(test::read_text(d / "a.obj"), test::read_text(d / "b.obj"));
  for (const std::string target : {"--faces 200", "--ratio 0.5"}) {
    const Result level = run("meshreduce --from-progressive " + (d / "a.pm").string() + " " + target + " -o " + (d / "c.obj").string() +
                             " --json");
    ASSERT_EQ(level.code, 0) << level.err;
    EXPECT_TRUE(nlohmann::json::parse(level.out).contains("error")) << "measured against the record's input";
    ASSERT_EQ(run("meshreduce " + in + " " + target + " -o " + (d / "d.obj").string() + " --no-measure").code, 0);
    EXPECT_EQ(test::read_text(d / "c.obj"), test::read_text(d / "d.obj")) << target;
  }
}

TEST(CliMeshreduce, ProgressiveErrors) {
  test::TempDir d;
  const std::string in = (d / "grid.obj").string(), pm = (d / "a.pm").string(), out = (d / "out.obj").string();
  test::write_text(d / "grid.obj", two_part_grid_obj());
  ASSERT_EQ(run("meshreduce " + in + " -o " + (d / "a.obj").string() + " --faces 60 --progressive " + pm + " --no-measure").code, 0);
  const std::string bytes = test::read_text(d / "a.pm");
  test::write_text(d / "cut.pm", bytes.substr(0, bytes.size() - 100));
  const Result cut = run("meshreduce --from-progressive " + (d / "cut.pm").string() + " --faces 100 -o " + out);
  EXPECT_EQ(cut.code, 3);
  EXPECT_NE(cut.err.find((d / "cut.pm").string() + ": truncated"), std::string::npos) << cut.err;
  EXPECT_EQ(lines(cut.err), 1u) << cut.err;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(run("meshreduce --from-progressive " + in + " --faces 100 -o " + out).code, 3) << "not a .pm";
  EXPECT_EQ(run("meshreduce --from-progressive " + pm + " --error 1% -o " + out).code, 2);
  EXPECT_EQ(run("meshreduce " + in + " --from-progressive " + pm + " --faces 100 -o " + out).code, 2);
  EXPECT_EQ(run("meshreduce --faces 100 -o " + out).code, 2) << "no input";
  // All or nothing: a .pm that cannot be written leaves no mesh either.
  fs::create_directory(d / "folder.pm");
  EXPECT_EQ(run("meshreduce " + in + " --faces 100 -o " + out + " --progressive " + (d / "folder.pm").string()).code, 2);
  EXPECT_FALSE(fs::exists(out));
}

// --report-regions: the faces of the output farther from the input than E, grouped; the
// worst region's distance is the measured Hausdorff distance (one measure everywhere).
TEST(CliMeshreduce, RegionsBeyondTheThreshold) {
  test::TempDir d;
  Mesh high = test::make_grid(16, 16);
  for (auto v : high.vertices()) {
    const Vec3f p = high.point(v);
    if (std::abs(p[0] - 0.25f) < 1e-6f && std::abs(p[1] - 0.75f) < 1e-6f) high.set_point(v, Vec3f(p[0], p[1], 0.3f));
  }
  write_mesh(high, d / "spike.obj");
  const std::string in = (d / "spike.obj").string(), out = (d / "out.obj").string();
  const Result r = run("meshreduce " + in + " -o " + out + " --faces 8 --max-normal-deviation 180 --report-regions 0.05 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto report = nlohmann::json::parse(r.out);
  const auto& regions = report["regions"];
  EXPECT_EQ(regions["threshold"], 0.05);
  ASSERT_GE(regions["count"].get<size_t>(), 1u);
  EXPECT_NEAR(regions["largest"][0]["max_distance"].get<double>(), report["error"]["hausdorff"].get<double>(), 1e-9);
  EXPECT_NE(r.err.find("regions"), std::string::npos) << "one warning line says so";
  const Result none = run("meshreduce " + in + " -o " + out + " --faces 8 --max-normal-deviation 180 --report-regions 100% --json");
  ASSERT_EQ(none.code, 0) << none.err;
  EXPECT_EQ(nlohmann::json::parse(none.out)["regions"]["count"], 0);
  EXPECT_EQ(run("meshreduce " + in + " -o " + out + " --faces 8 --report-regions -1").code, 2);
}

TEST(CliMeshreduce, LocksAndTheTargetOutOfReach) {
  test::TempDir d;
  const std::string in = (d / "grid.obj").string(), out = (d / "out.obj").string();
  test::write_text(d / "grid.obj", two_part_grid_obj());
  const Result hand = run("meshreduce " + in + " -o " + out + " --faces 10 --lock-group hand --no-measure --json");
  ASSERT_EQ(hand.code, 0) << hand.err;
  const auto report = nlohmann::json::parse(hand.out);
  EXPECT_EQ(report["locked_vertices"], 16);
  EXPECT_EQ(report["passes"], 1) << "a flat grid leaves no face facing away: one pass";
  EXPECT_EQ(report["flipped_faces"], 0);
  EXPECT_FALSE(report["target_reached"].get<bool>());
  EXPECT_GE(report["output"]["faces"].get<size_t>(), 18u) << "the hand's 18 faces stay";
  EXPECT_EQ(lines(hand.err), 2u) << hand.err;  // the warning, then "wrote"
  EXPECT_NE(hand.err.find("warning: stopped at"), std::string::npos) << hand.err;
  EXPECT_NE(hand.err.find("locks"), std::string::npos) << hand.err;

  const Result boundary = run("meshreduce " + in + " -o " + out + " --faces 10 --lock-boundary --lock-group hand --no-measure --json");
  ASSERT_EQ(boundary.code, 0) << boundary.err;
  EXPECT_EQ(nlohmann::json::parse(boundary.out)["locked_vertices"], 48 + 16);
  const Mesh reduced = read_mesh(out);
  size_t outline = 0;
  for (auto v : reduced.vertices()) outline += reduced.is_boundary(v);
  EXPECT_EQ(outline, 48u);

  const Result unknown = run("meshreduce " + in + " -o " + out + " --faces 10 --lock-group foot");
  EXPECT_EQ(unknown.code, 2);
  EXPECT_NE(unknown.err.find("'foot'"), std::string::npos) << unknown.err;
  EXPECT_NE(unknown.err.find("'hand'"), std::string::npos) << unknown.err;
}

}  // namespace
}  // namespace meso

namespace meso {
namespace {

// uvpack pack on a mesh without UVs unwraps it (normal-cone charts, LSCM or ARAP) and packs
// the charts; the checker finds a unique mapping with the padding. --unwrap replaces UVs a
// mesh has; bad unwrap options are usage errors.
TEST(Cli, UvpackPackUnwrapsAMeshWithoutUvs) {
  test::TempDir dir;
  Mesh flat = test::make_seamed_cube();
  flat.release_halfedge_texcoords2D();
  write_mesh(flat, dir / "nouv.ply");
  for (const std::string method : {"lscm", "arap"}) {
    const std::string out = (dir / ("unwrapped_" + method + ".obj")).string();
    const Result r = run("--json uvpack pack " + (dir / "nouv.ply").string() + " -o " + out + " --size 128 --padding 2 --unwrap-method " + method);
    ASSERT_EQ(r.code, 0) << r.err;
    const auto report = nlohmann::json::parse(r.out);
    EXPECT_EQ(report["charts"], 6);
    EXPECT_EQ(report["unwrap"]["method"], method);
    EXPECT_EQ(report["unwrap"]["charts"], 6);
    EXPECT_NEAR(report["unwrap"]["stretch_l2"].get<double>(), 1.0, 1e-6);
    for (const char* k : {"overlapping_faces", "shared_texel_faces", "padding_violations", "outside_faces", "flipped_faces"})
      EXPECT_EQ(report["check"][k], 0) << k;
    const Result check = run("uvpack check " + out + " --size 128 --padding 2 --fail-on overlap,shared,padding,outside,flipped");
    EXPECT_EQ(check.code, 0) << check.err;
  }
  // A mesh with UVs keeps its charts unless --unwrap: the seamed cube's sides are its charts
  // either way, but only --unwrap reports an unwrap.
  write_mesh(test::make_seamed_cube(), dir / "cube.obj");
  const Result kept = run("--json uvpack pack " + (dir / "cube.obj").string() + " -o " + (dir / "kept.obj").string() + " --size 64");
  ASSERT_EQ(kept.code, 0) << kept.err;
  EXPECT_FALSE(nlohmann::json::parse(kept.out).contains("unwrap"));
  const Result rewrapped =
      run("--json uvpack pack " + (dir / "cube.obj").string() + " -o " + (dir / "re.obj").string() + " --size 64 --unwrap --max-stretch 1.05 --chart-angle 30");
  ASSERT_EQ(rewrapped.code, 0) << rewrapped.err;
  EXPECT_EQ(nlohmann::json::parse(rewrapped.out)["unwrap"]["charts"], 6);
  // A mesh without area has nothing to unwrap, which is what the error says (it had said
  // "--unwrap makes new ones" to a user who gave --unwrap).
  Mesh point = test::make_grid(2, 2);
  for (auto v : point.vertices()) point.set_point(v, Vec3f(1, 1, 1));
  write_mesh(point, dir / "point.obj");
  const Result none = run("uvpack pack " + (dir / "point.obj").string() + " -o " + (dir / "x.obj").string() + " --size 64 --unwrap");
  EXPECT_EQ(none.code, 3) << none.err;
  EXPECT_NE(none.err.find("point.obj: has no surface area"), std::string::npos) << none.err;
  EXPECT_EQ(run("uvpack pack " + (dir / "cube.obj").string() + " -o " + (dir / "x.obj").string() + " --unwrap-method tutte").code, 2);
  EXPECT_EQ(run("uvpack pack " + (dir / "cube.obj").string() + " -o " + (dir / "x.obj").string() + " --max-stretch 0.5").code, 2);
  EXPECT_FALSE(fs::exists(dir / "x.obj"));
}

}  // namespace
}  // namespace meso

namespace meso {
namespace {

// frames --curvature-map: the per-texel second fundamental form of a sphere (radius 2,
// outward normals, UVs around and pole to pole) as a float EXR with R, G, B, A, in
// 1/object units; bad sizes and extensions are usage errors and leave no file.
TEST(Cli, FramesWritesACurvatureMap) {
  test::TempDir d;
  const double r = 2.0, pi = 3.14159265358979323846;
  const Mesh sphere = test::make_parametric(48, 24, [&](double s, double t) {
    const double th = pi * (0.05 + 0.9 * t), ph = 2 * pi * s;
    return Vec3f(float(r * std::sin(th) * std::cos(ph)), float(r * std::sin(th) * std::sin(ph)), float(-r * std::cos(th)));
  }, true, false);
  write_mesh(sphere, d / "sphere.obj");
  const std::string in = (d / "sphere.obj").string(), out = (d / "framed.glb").string(), map = (d / "maps" / "curvature.exr").string();
  const Result ok = run("--json frames " + in + " -o " + out + " --curvature-map " + map + " --size 64x32");
  ASSERT_EQ(ok.code, 0) << ok.err;
  ASSERT_TRUE(fs::exists(map));
  EXPECT_TRUE(fs::exists(out));
  const Image k = read_image(map);
  EXPECT_EQ(k.width, 64);
  EXPECT_EQ(k.height, 32);
  EXPECT_EQ(k.channels, 4);
  EXPECT_EQ(std::get<std::string>(k.metadata.at("quantity")), "curvature");
  EXPECT_EQ(std::get<std::string>(k.metadata.at("units")), "1/object");
  for (float v : k.pixels) ASSERT_TRUE(std::isfinite(v));
  // A texel on the equator, away from the seam: K = I / r.
  EXPECT_NEAR(k.at(32, 16, 0), 1 / r, 0.05 / r);
  EXPECT_NEAR(k.at(32, 16, 1), 0.0, 0.05 / r);
  EXPECT_NEAR(k.at(32, 16, 2), 1 / r, 0.05 / r);
  EXPECT_EQ(k.at(32, 16, 3), 1.0f);
  const auto report = nlohmann::json::parse(ok.out);
  ASSERT_TRUE(report.contains("curvature_map")) << ok.out;
  EXPECT_EQ(report["curvature_map"]["output"], map);
  EXPECT_EQ(report["curvature_map"]["width"], 64);
  EXPECT_EQ(report["curvature_map"]["height"], 32);
  EXPECT_EQ(report["curvature_map"]["texels"], 64 * 32) << "the UVs cover the whole map";
  EXPECT_NEAR(report["curvature_map"]["max"].get<double>(), 1 / r, 0.05 / r);
  // The vertices' range: a sphere bends one way, so both ends are near 1/r (the minimum had
  // started at 0 and stayed there).
  EXPECT_GT(report["curvature"]["min"].get<double>(), 0.5 / r);
  EXPECT_LT(report["curvature"]["max"].get<double>(), 2 / r);

  for (const std::string bad : {"--size 0", "--size 64y32", "--size x", "--size 40000"}) {
    const Result r2 = run("frames " + in + " -o " + (d / "bad.glb").string() + " --curvature-map " + (d / "bad.exr").string() + " " + bad);
    EXPECT_EQ(r2.code, 2) << bad << ": " << r2.err;
    EXPECT_EQ(lines(r2.err), 1u) << r2.err;
  }
  EXPECT_EQ(run("frames " + in + " -o " + (d / "bad.glb").string() + " --size 64").code, 2) << "--size needs --curvature-map";
  EXPECT_EQ(run("frames " + in + " -o " + (d / "bad.glb").string() + " --curvature-map " + (d / "bad.png").string()).code, 2);
  EXPECT_FALSE(fs::exists(d / "bad.glb"));
  EXPECT_FALSE(fs::exists(d / "bad.exr"));
  EXPECT_FALSE(fs::exists(d / "bad.png"));
}

}  // namespace
}  // namespace meso

// ---- meshreduce: --quality presets ----

namespace meso {
namespace {

// A mesh without surface area (collinear faces) has no distance to measure: the report has
// no `error` and a warning says why (every distance field had been null).
TEST(CliMeshreduce, NoDistanceForAMeshWithoutArea) {
  test::TempDir dir;
  test::write_text(dir / "line.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nf 1 2 3\nf 2 3 4\n");
  const Result r = run("meshreduce " + (dir / "line.obj").string() + " -o " + (dir / "out.obj").string() + " --ratio 0.5 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.out.find("null"), std::string::npos) << r.out;
  EXPECT_FALSE(nlohmann::json::parse(r.out).contains("error"));
  EXPECT_NE(r.err.find("no distance measured: the input has no surface area"), std::string::npos) << r.err;
}

TEST(CliMeshreduce, QualityPresets) {
  test::TempDir d;
  const std::string in = (d / "grid.obj").string();
  test::write_text(d / "grid.obj", two_part_grid_obj());
  for (const std::string q : {"fast", "balanced", "best"}) {
    const Result r = run("meshreduce " + in + " -o " + (d / (q + ".obj")).string() + " --faces 60 --quality " + q + " --no-measure --json");
    ASSERT_EQ(r.code, 0) << r.err;
    const auto report = nlohmann::json::parse(r.out);
    EXPECT_EQ(report["quality"], q);
    EXPECT_LE(report["output"]["faces"].get<size_t>(), 60u);
    // best reports its two candidates, their fits and which it kept; it is balanced's output
    // when the unfitted area-weighted one is kept.
    EXPECT_EQ(report.contains("best"), q == "best");
    if (q == "best") {
      const auto& b = report["best"];
      ASSERT_TRUE(b.contains("hausdorff_area_fitted") && b.contains("hausdorff_uniform_fitted"));
      const double area = b["hausdorff_area"], uniform = b["hausdorff_uniform"];
      const double fitted = std::min(b["hausdorff_area_fitted"].get<double>(), b["hausdorff_uniform_fitted"].get<double>());
      EXPECT_EQ(b["fitted"], fitted < std::min(area, uniform));
      const bool balanced = !b["fitted"].get<bool>() && area <= uniform;
      if (!b["fitted"].get<bool>()) {
        EXPECT_EQ(b["planes"], area <= uniform ? "area" : "uniform");
      }
      EXPECT_EQ(test::read_text(d / "best.obj") == test::read_text(d / "balanced.obj"), balanced);
    }
  }
  // The default is balanced.
  ASSERT_EQ(run("meshreduce " + in + " -o " + (d / "default.obj").string() + " --faces 60 --no-measure").code, 0);
  EXPECT_EQ(test::read_text(d / "default.obj"), test::read_text(d / "balanced.obj"));
  EXPECT_EQ(run("meshreduce " + in + " -o " + (d / "x.obj").string() + " --faces 60 --quality fastest").code, 2);
  EXPECT_EQ(run("meshreduce --from-progressive a.pm --faces 10 -o " + (d / "x.obj").string() + " --quality fast").code, 2);
}

}  // namespace
}  // namespace meso

// ---- bake: the report, --dilate, --samples, ambiguity, the 16-bit displacement (issue 5) ----

namespace meso {
namespace {

// The meso command line of a bake of `low` onto `high` (files in `dir`) into dir/out.
std::string bake_args(const test::TempDir& dir, const std::string& low, const std::string& high, const std::string& out, const std::string& extra) {
  return "bake --low " + (dir / low).string() + " --high " + (dir / high).string() + " -o " + (dir / out).string() + " " + extra;
}

// --json reports the rays cast, the bake's time and their ratio; --dilate inf (and -1) is the
// default, unlimited fill; --dilate 2 fills only texels within 2 of a hit texel (Euclidean,
// as dilation_sources), the others keep the fill value (displacement 0).
TEST(CliBake, ReportsRaysPerSecondAndDilatesByTheRadiusGiven) {
  test::TempDir dir;
  // One quad over UV [1/4, 1/2]^2 (in 3D the same square at z = 0) under a plane at 0.01.
  write_mesh(test::make_uv_quads({{0.25f, 0.25f, 0.5f, 0.5f}}), dir / "low.obj");
  write_mesh(test::make_plane(0, 0, 0.01f), dir / "high.obj");
  const std::string size = "--size 32 --front 0.05 --back 0.05 --maps displacement,coverage";
  const Result plain = run(bake_args(dir, "low.obj", "high.obj", "default", size + " --json"));
  ASSERT_EQ(plain.code, 0) << plain.err;
  const auto report = nlohmann::json::parse(plain.out);
  ASSERT_TRUE(report.contains("seconds"));
  ASSERT_TRUE(report.contains("rays_per_second"));
  EXPECT_GT(report["seconds"].get<double>(), 0.0);
  EXPECT_GT(report["rays_per_second"].get<double>(), 0.0);
  EXPECT_GE(report["rays"].get<double>(), 2.0 * report["covered_texels"].get<double>()) << "at least one ray each way per texel";
  EXPECT_NEAR(report["rays_per_second"].get<double>() * report["seconds"].get<double>(), report["rays"].get<double>(),
              1e-6 * report["rays"].get<double>());

  for (const char* unlimited : {"inf", "-1"}) {
    const Result r = run(bake_args(dir, "low.obj", "high.obj", std::string("inf") + unlimited, size + " --dilate " + unlimited));
    ASSERT_EQ(r.code, 0) << unlimited << ": " << r.err;
    EXPECT_EQ(test::read_text(dir / (std::string("inf") + unlimited) / "displacement.exr"), test::read_text(dir / "default" / "displacement.exr"))
        << "--dilate " << unlimited;
  }
  const Image filled = read_image(dir / "default" / "displacement.exr");
  for (float v : filled.pixels) EXPECT_NEAR(v, 0.01f, 1e-6f);

  const Result two = run(bake_args(dir, "low.obj", "high.obj", "two", size + " --dilate 2"));
  ASSERT_EQ(two.code, 0) << two.err;
  const Image disp = read_image(dir / "two" / "displacement.exr"), coverage = read_image(dir / "two" / "coverage.png");
  size_t kept = 0, reached = 0;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) {
      int nearest = 1 << 30;  // squared distance to the nearest texel that hit
      for (int yy = 0; yy < 32; ++yy)
        for (int xx = 0; xx < 32; ++xx)
          if (coverage.at(xx, yy) == 1.0f) nearest = std::min(nearest, (x - xx) * (x - xx) + (y - yy) * (y - yy));
      if (nearest > 4) {
        EXPECT_EQ(disp.at(x, y), 0.0f) << x << "," << y << " is farther than 2 from the chart";
        ++kept;
      } else {
        EXPECT_NEAR(disp.at(x, y), 0.01f, 1e-6f) << x << "," << y;
        reached += nearest > 0;
      }
    }
  EXPECT_GT(kept, 0u);
  EXPECT_GT(reached, 0u);
  for (const char* bad : {"--dilate infinity", "--dilate -2", "--dilate 2.5", "--dilate ''"}) {
    const Result r = run(bake_args(dir, "low.obj", "high.obj", "bad", size + " " + bad));
    EXPECT_EQ(r.code, 2) << bad;
    EXPECT_EQ(lines(r.err), 1u) << r.err;
  }
}

// --samples takes squares only (the samples sit at the centres of n x n sub-texels): 4 and 9
// run and are reported, 2 and 5 are refused with one line naming the option, before loading.
TEST(CliBake, SamplesMustBeASquare) {
  test::TempDir dir;
  write_mesh(test::make_grid(2, 2), dir / "low.obj");
  write_mesh(test::make_plane(0, 0, 0.01f), dir / "high.obj");
  for (const int k : {4, 9}) {
    const Result r = run(bake_args(dir, "low.obj", "high.obj", "s" + std::to_string(k), "--size 8 --json --samples " + std::to_string(k)));
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(nlohmann::json::parse(r.out)["samples"], k);
  }
  for (const int k : {2, 5}) {
    const Result r = run(bake_args(dir, "low.obj", "high.obj", "bad", "--size 8 --samples " + std::to_string(k)));
    EXPECT_EQ(r.code, 2) << k;
    EXPECT_EQ(lines(r.err), 1u) << r.err;
    EXPECT_NE(r.err.find("--samples"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("square"), std::string::npos) << r.err;
  }
}

// Two layers 0.0100 out and 0.0102 in, within the bunch distance (0.001) of each other: every
// texel's choice is ambiguous, and the report lists each base face with all its texels.
TEST(CliBake, AmbiguousTexelsAreReportedPerFace) {
  test::TempDir dir;
  write_mesh(test::make_grid(2, 2), dir / "low.obj");
  write_mesh(test::make_layers({{0.010f, true}, {-0.0102f, true}}), dir / "high.obj");
  const Result r = run(bake_args(dir, "low.obj", "high.obj", "maps", "--size 8 --front 0.05 --back 0.05 --bunch 0.001 --json"));
  ASSERT_EQ(r.code, 0) << r.err;
  const auto report = nlohmann::json::parse(r.out);
  EXPECT_EQ(report["ambiguous"], 64);
  const auto& faces = report["ambiguous_faces"];
  ASSERT_EQ(faces.size(), 8u) << "every face of the 2 x 2 grid";
  size_t sum = 0;
  std::vector<int> seen;
  for (const auto& f : faces) {
    EXPECT_EQ(f["ambiguous"], f["texels"]) << f.dump();
    sum += f["ambiguous"].get<size_t>();
    seen.push_back(f["face"].get<int>());
  }
  EXPECT_EQ(sum, 64u);
  std::sort(seen.begin(), seen.end());
  EXPECT_EQ(seen, std::vector<int>({0, 1, 2, 3, 4, 5, 6, 7}));
  const Image coverage = read_image(dir / "maps" / "coverage.png");
  for (float c : coverage.pixels) EXPECT_NEAR(c, 191.0f / 255.0f, 1e-6f) << "0.75 in 8 bits";
}

// A high plane with a hole over UV [1/4, 3/4]^2: a quarter of the texels miss, the report
// names the faces, and --max-miss-rate turns that into exit 1 (maps written) only above it.
TEST(CliBake, AHoleFailsTheMissRateCheck) {
  test::TempDir dir;
  write_mesh(test::make_grid(2, 2), dir / "low.obj");
  write_mesh(test::without_faces(test::make_plane(0, 0, 0.02f),
                                 [](const Mesh& m, FaceHandle f) {
                                   Vec3f c(0, 0, 0);
                                   for (auto v : m.fv_range(f)) c += m.point(v) / 3.0f;
                                   return c[0] > 0.25f && c[0] < 0.75f && c[1] > 0.25f && c[1] < 0.75f;
                                 }),
             dir / "high.obj");
  const std::string common = "--size 16 --front 0.05 --back 0.05 --json --max-miss-rate ";
  const Result strict = run(bake_args(dir, "low.obj", "high.obj", "strict", common + "0.2"));
  EXPECT_EQ(strict.code, 1) << strict.err;
  EXPECT_TRUE(fs::exists(dir / "strict" / "displacement.exr"));
  const auto report = nlohmann::json::parse(strict.out);
  EXPECT_EQ(report["misses"], 64);
  EXPECT_DOUBLE_EQ(report["miss_rate"].get<double>(), 0.25);
  size_t sum = 0;
  for (const auto& f : report["miss_faces"]) sum += f["misses"].get<size_t>();
  EXPECT_EQ(sum, 64u);
  EXPECT_EQ(run(bake_args(dir, "low.obj", "high.obj", "loose", common + "0.3")).code, 0);
}

// A PNG file's bit depth and colour type (0 grey, 2 RGB), from its IHDR chunk; (-1, -1) when
// the file is not a PNG.
std::pair<int, int> png_header(const fs::path& path) {
  const std::string png = test::read_text(path);
  if (png.size() < 26 || png.substr(12, 4) != "IHDR") return {-1, -1};
  return {static_cast<unsigned char>(png[24]), static_cast<unsigned char>(png[25])};
}

// displacement.png: 16-bit grey, its bias and scale in the metadata equal to the report's,
// and bias + scale * value reproduces displacement.exr within one step of 16 bits.
TEST_F(Skeleton, DisplacementPngIs16BitAndDecodesToTheExr) {
  const auto& d = *dir_;
  const Result r = run("bake --low " + (d / "base.obj").string() + " --high " + (d / "high.obj").string() + " -o " +
                       (d / "png16").string() + " --size 64x32 --maps displacement,displacement_png --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto report = nlohmann::json::parse(r.out);
  EXPECT_EQ(png_header(d / "png16" / "displacement.png"), std::make_pair(16, 0)) << "16 bits, colour type grey";
  const Image img = read_image(d / "png16" / "displacement.png"), exr = read_image(d / "png16" / "displacement.exr");
  const float bias = std::stof(std::get<std::string>(img.metadata.at("height_bias")));
  const float scale = std::stof(std::get<std::string>(img.metadata.at("height_scale")));
  EXPECT_EQ(bias, report["displacement_png"]["bias"].get<float>());
  EXPECT_EQ(scale, report["displacement_png"]["scale"].get<float>());
  EXPECT_EQ(bias, report["displacement_min"].get<float>());
  ASSERT_GT(scale, 0.0f);
  ASSERT_EQ(img.pixels.size(), exr.pixels.size());
  double worst = 0;
  for (size_t i = 0; i < img.pixels.size(); ++i)
    worst = std::max(worst, std::abs(double(bias) + double(scale) * img.pixels[i] - exr.pixels[i]));
  std::printf("[ displacement.png ] worst |bias + scale v - exr| = %.3g = %.3f of scale/65535\n", worst, worst / (scale / 65535.0));
  EXPECT_LE(worst, scale / 65535.0);
}

}  // namespace
}  // namespace meso

namespace meso {
namespace {

// ---- bake: PNG bit depth, green convention; frames: formats that cannot hold frames; glTF
// TANGENT values (issue 5, the auditor's gaps) ----

// The identity bake of issue 5 through the command line: high = low, a curved mesh with UV
// seams and a mirrored half (the library's BakeAccuracy test mesh), normal_ts.png in 8 and in
// 16 bits: every covered texel decodes to (0, 0, 1) within half an LSB. displacement.png
// follows --png-bits too; coverage.png stays 8-bit.
TEST(CliBake, IdentityBakeDecodesToUpWithinHalfAnLsbIn8And16Bits) {
  test::TempDir dir;
  Mesh torus = test::BumpyTorus{}.mesh(48, 24);
  test::mirror_half(torus);
  write_mesh(torus, dir / "torus.obj");
  // The premise, as the command sees the file: half the faces' corners mirrored.
  const Result frames = run("frames " + (dir / "torus.obj").string() + " -o " + (dir / "torus.glb").string() + " --json");
  ASSERT_EQ(frames.code, 0) << frames.err;
  EXPECT_EQ(nlohmann::json::parse(frames.out)["mirrored_corners"], 3 * torus.n_faces() / 2);
  for (const int bits : {8, 16}) {
    const std::string out = "b" + std::to_string(bits);
    const Result r = run(bake_args(dir, "torus.obj", "torus.obj", out, "--size 256 --maps normal_ts,displacement_png,coverage --json --png-bits " + std::to_string(bits)));
    ASSERT_EQ(r.code, 0) << r.err;
    const auto report = nlohmann::json::parse(r.out);
    EXPECT_EQ(report["png_bits"], bits);
    EXPECT_EQ(report["misses"], 0);
    EXPECT_EQ(png_header(dir / out / "normal_ts.png"), std::make_pair(bits, 2)) << "RGB at the requested depth";
    EXPECT_EQ(png_header(dir / out / "displacement.png"), std::make_pair(bits, 0)) << "grey at the requested depth";
    EXPECT_EQ(png_header(dir / out / "coverage.png"), std::make_pair(8, 0)) << "coverage stays 8-bit grey";
    const double max_code = bits == 8 ? 255.0 : 65535.0;
    const Image normals = read_image(dir / out / "normal_ts.png"), coverage = read_image(dir / out / "coverage.png");
    const test::UpCodesCheck check = test::check_codes_decode_to_up(test::image_codes(normals, max_code), coverage, max_code, out);
    EXPECT_EQ(check.checked, report["covered_texels"].get<size_t>());
    EXPECT_GT(check.checked, 256u * 256u / 2);
    EXPECT_EQ(check.bad, 0u);
    std::printf("[ identity cli ] %2d-bit: %zu covered texels, largest code offsets x %.2f y %.2f z %.2f LSB\n", bits, check.checked,
                check.worst[0], check.worst[1], check.worst[2]);
  }
  for (const char* bad : {"--png-bits 12", "--png-bits 0", "--normal-y sideways"}) {
    const Result r = run(bake_args(dir, "torus.obj", "torus.obj", "bad", std::string("--size 8 ") + bad));
    EXPECT_EQ(r.code, 2) << bad;
    EXPECT_NE(r.err.find(std::string(bad).substr(0, std::string(bad).find(' '))), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "bad")) << bad;
  }
}

// --normal-y down (Unreal, DirectX: green = -v) writes the default map (up: glTF, Blender,
// Unity) with y negated, texel for texel, and says so in the maps' metadata and the report.
// A tilted high plane, so that both x and y of the normals are far from 0.
TEST(CliBake, NormalYDownNegatesGreenTexelForTexel) {
  test::TempDir dir;
  write_mesh(test::make_grid(2, 2), dir / "low.obj");
  write_mesh(test::make_plane(0.3f, -0.2f, 0.01f), dir / "high.obj");
  const std::string common = "--size 16 --front 0.5 --back 0.5 --maps normal_ts,normal_ts_exr,normal_os_exr --json";
  const Result up = run(bake_args(dir, "low.obj", "high.obj", "up", common));
  const Result down = run(bake_args(dir, "low.obj", "high.obj", "down", common + " --normal-y down"));
  ASSERT_EQ(up.code, 0) << up.err;
  ASSERT_EQ(down.code, 0) << down.err;
  EXPECT_EQ(nlohmann::json::parse(up.out)["normal_y"], "up") << "the default";
  EXPECT_EQ(nlohmann::json::parse(down.out)["normal_y"], "down");
  const Image up_exr = read_image(dir / "up" / "normal_ts.exr"), down_exr = read_image(dir / "down" / "normal_ts.exr");
  const Image up_png = read_image(dir / "up" / "normal_ts.png"), down_png = read_image(dir / "down" / "normal_ts.png");
  ASSERT_EQ(up_exr.pixels.size(), 16u * 16u * 3u);
  ASSERT_EQ(down_exr.pixels.size(), up_exr.pixels.size());
  ASSERT_EQ(down_png.pixels.size(), up_png.pixels.size());
  const std::vector<long> up_codes = test::image_codes(up_png, 65535), down_codes = test::image_codes(down_png, 65535);
  // The plane's normal in the grid's tangent space (t = +x, b = +y, n = +z): y = 0.2 / |.|.
  const float expected_y = 0.2f / std::sqrt(0.3f * 0.3f + 0.2f * 0.2f + 1.0f);
  for (size_t i = 0; i < 16 * 16; ++i) {
    ASSERT_NEAR(up_exr.pixels[3 * i + 1], expected_y, 1e-5f) << i;
    ASSERT_EQ(down_exr.pixels[3 * i + 0], up_exr.pixels[3 * i + 0]) << i;
    ASSERT_EQ(down_exr.pixels[3 * i + 1], -up_exr.pixels[3 * i + 1]) << i;
    ASSERT_EQ(down_exr.pixels[3 * i + 2], up_exr.pixels[3 * i + 2]) << i;
    // Encoded: (y + 1) / 2 and (1 - y) / 2 sum to one, so the codes to 65535 (within the
    // rounding of a code that falls on a half).
    ASSERT_EQ(down_codes[3 * i + 0], up_codes[3 * i + 0]) << i;
    ASSERT_NEAR(down_codes[3 * i + 1] + up_codes[3 * i + 1], 65535, 1) << i;
    ASSERT_EQ(down_codes[3 * i + 2], up_codes[3 * i + 2]) << i;
  }
  for (const Image* m : {&up_exr, &up_png})
    EXPECT_EQ(std::get<std::string>(m->metadata.at("normal_y")), "up");
  for (const Image* m : {&down_exr, &down_png}) {
    EXPECT_EQ(std::get<std::string>(m->metadata.at("normal_y")), "down");
    EXPECT_NE(std::get<std::string>(m->metadata.at("space")).find("-v"), std::string::npos);
  }
  // normal_os.exr: the plane's own normal, and the same bytes whatever the convention.
  const Image os = read_image(dir / "up" / "normal_os.exr");
  const float len = std::sqrt(0.3f * 0.3f + 0.2f * 0.2f + 1.0f);
  const float plane_normal[3] = {-0.3f / len, 0.2f / len, 1.0f / len};
  ASSERT_EQ(os.pixels.size(), 16u * 16u * 3u);
  for (size_t i = 0; i < os.pixels.size(); ++i) ASSERT_NEAR(os.pixels[i], plane_normal[i % 3], 1e-5f) << i;
  EXPECT_EQ(test::read_text(dir / "up" / "normal_os.exr"), test::read_text(dir / "down" / "normal_os.exr"));
}

// frames writes tangents and curvatures, which only glTF holds: an .obj or .ply output would
// silently drop them, so it is refused as a bad value (exit 2, one line naming the file),
// before any work, and nothing is written.
TEST(CliFrames, RefusesOutputsThatCannotHoldFrames) {
  test::TempDir dir;
  write_mesh(test::make_grid(2, 2), dir / "grid.obj");
  for (const char* out : {"x.obj", "x.ply", "X.OBJ"}) {
    const Result r = run("frames " + (dir / "grid.obj").string() + " -o " + (dir / out).string());
    EXPECT_EQ(r.code, 2) << out;
    EXPECT_EQ(lines(r.err), 1u) << r.err;
    EXPECT_NE(r.err.find(out), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(".gltf or .glb"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / out));
  }
  EXPECT_EQ(run("frames " + (dir / "grid.obj").string() + " -o " + (dir / "x.gltf").string()).code, 0);
}

// One glTF attribute of the first primitive as floats (the buffer embedded as base64, as
// meso writes it), `components` per vertex.
std::vector<float> gltf_floats(const nlohmann::json& gltf, const std::string& attribute, int components) {
  const std::string uri = gltf["buffers"][0]["uri"].get<std::string>();
  const std::string prefix = "data:application/octet-stream;base64,";
  EXPECT_EQ(uri.compare(0, prefix.size(), prefix), 0);
  std::vector<uint8_t> bytes;
  uint32_t acc = 0;
  int bits = 0;
  for (size_t i = prefix.size(); i < uri.size() && uri[i] != '='; ++i) {
    const char c = uri[i];
    const int v = c >= 'A' && c <= 'Z' ? c - 'A' : c >= 'a' && c <= 'z' ? c - 'a' + 26 : c >= '0' && c <= '9' ? c - '0' + 52 : c == '+' ? 62 : 63;
    acc = (acc << 6) | static_cast<uint32_t>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      bytes.push_back(static_cast<uint8_t>(acc >> bits));
    }
  }
  const auto& accessor = gltf["accessors"][gltf["meshes"][0]["primitives"][0]["attributes"][attribute].get<size_t>()];
  EXPECT_EQ(accessor["componentType"], 5126) << "float";
  const auto& view = gltf["bufferViews"][accessor["bufferView"].get<size_t>()];
  const size_t offset = view["byteOffset"].get<size_t>() + accessor.value("byteOffset", size_t(0));
  const size_t count = accessor["count"].get<size_t>() * static_cast<size_t>(components);
  std::vector<float> out(count);
  EXPECT_LE(offset + 4 * count, bytes.size());
  if (offset + 4 * count <= bytes.size()) std::memcpy(out.data(), bytes.data() + offset, 4 * count);
  return out;
}

// glTF TANGENT values through `meso frames -o x.gltf`, read back from the file: a flat grid
// (UV = xy) has (1, 0, 0, +1) everywhere; the same grid with the right half's u mirrored
// (u = 1 - x there: the tangent turns to -x, the handedness to -1) keeps (1, 0, 0, +1) on the
// left and has (-1, 0, 0, -1) on the right, and the vertices on the mirror line, whose UVs
// are the same on both sides, are split because their tangents differ.
TEST(CliFrames, GltfTangentsOfAFlatGridAndAMirroredHalf) {
  test::TempDir dir;
  const int n = 4;
  Mesh grid = test::make_grid(n, n);
  write_mesh(grid, dir / "grid.obj");
  Mesh mirrored = grid;
  for (auto f : mirrored.faces()) {
    float cx = 0;
    for (auto v : mirrored.fv_range(f)) cx += mirrored.point(v)[0] / 3.0f;
    if (cx > 0.5f)
      for (auto h : face_halfedges(mirrored, f)) {
        const Vec2f uv = mirrored.texcoord2D(h);
        mirrored.set_texcoord2D(h, Vec2f(1.0f - uv[0], uv[1]));
      }
  }
  write_mesh(mirrored, dir / "mirrored.obj");
  for (const char* name : {"grid", "mirrored"}) {
    SCOPED_TRACE(name);
    const Result r = run("frames " + (dir / (std::string(name) + ".obj")).string() + " -o " + (dir / (std::string(name) + ".gltf")).string());
    ASSERT_EQ(r.code, 0) << r.err;
    const auto gltf = nlohmann::json::parse(test::read_text(dir / (std::string(name) + ".gltf")));
    const std::vector<float> tangent = gltf_floats(gltf, "TANGENT", 4), position = gltf_floats(gltf, "POSITION", 3);
    const size_t vertices = position.size() / 3;
    ASSERT_EQ(tangent.size(), 4 * vertices);
    const bool mirror = std::string(name) == "mirrored";
    // (n + 1)^2 grid vertices; the mirrored grid adds a copy of the n + 1 on the line x = 1/2.
    EXPECT_EQ(vertices, static_cast<size_t>((n + 1) * (n + 1) + (mirror ? n + 1 : 0)));
    size_t plain = 0, flipped = 0;
    for (size_t i = 0; i < vertices; ++i) {
      const float x = position[3 * i];
      const float* t = &tangent[4 * i];
      const bool right = mirror && (x > 0.5f || (x == 0.5f && t[3] < 0));
      const float want[4] = {right ? -1.0f : 1.0f, 0.0f, 0.0f, right ? -1.0f : 1.0f};
      for (int c = 0; c < 4; ++c) EXPECT_NEAR(t[c], want[c], 1e-6f) << "vertex " << i << " at x = " << x << ", component " << c;
      (t[3] < 0 ? flipped : plain) += 1;
    }
    EXPECT_EQ(plain, static_cast<size_t>(mirror ? (n + 1) * (n / 2 + 1) : (n + 1) * (n + 1)));
    EXPECT_EQ(flipped, static_cast<size_t>(mirror ? (n + 1) * (n / 2 + 1) : 0));
  }
}

}  // namespace
}  // namespace meso

namespace meso {
namespace {

// ---- bake: the options tested only in the library until now, through the command line ----

// A cage leaning (0.02, 0, 0.05) away from a flat base: rays run toward it (a layer 0.01 up is
// 0.01 * slant away along the leaning ray, and bakes to its height, 0.01) and stop at it (a layer at 0.06, past
// the cage's 0.05, is out of reach: every texel misses, although --front 0.2 would reach it
// along the normal: Bake.CageSetsTheRaysDirectionAndOutwardReach).
TEST(CliBake, CageLeansTheRaysAndBoundsTheirReach) {
  test::TempDir dir;
  const Mesh base = test::make_grid(2, 2);
  Mesh cage_mesh = base;
  for (auto v : cage_mesh.vertices()) cage_mesh.set_point(v, cage_mesh.point(v) + Vec3f(0.02f, 0.0f, 0.05f));
  write_mesh(base, dir / "low.obj");
  write_mesh(cage_mesh, dir / "cage.obj");
  write_mesh(test::make_layers({{0.01f, true}}), dir / "near.obj");
  write_mesh(test::make_layers({{0.06f, true}}), dir / "far.obj");
  write_mesh(test::make_grid(3, 2), dir / "other.obj");
  const std::string common = "--size 8 --front 0.2 --back 0.2 --maps displacement --json";
  const std::string cage = " --cage " + (dir / "cage.obj").string();
  const double slant = std::sqrt(0.02 * 0.02 + 0.05 * 0.05) / 0.05;  // ray length per unit height
  const Result near = run(bake_args(dir, "low.obj", "near.obj", "near", common + cage));
  ASSERT_EQ(near.code, 0) << near.err;
  const auto near_report = nlohmann::json::parse(near.out);
  EXPECT_EQ(near_report["misses"], 0);
  EXPECT_EQ(near_report["cage"], (dir / "cage.obj").string());
  EXPECT_NEAR(near_report["displacement_min"].get<double>(), 0.01, 1e-6) << "along the ray it is " << 0.01 * slant;
  EXPECT_NEAR(near_report["displacement_max"].get<double>(), 0.01, 1e-6);
  const Result far = run(bake_args(dir, "low.obj", "far.obj", "far", common + cage));
  ASSERT_EQ(far.code, 0) << far.err;
  const auto far_report = nlohmann::json::parse(far.out);
  EXPECT_EQ(far_report["hits"], 0) << "the layer past the cage is out of reach";
  EXPECT_EQ(far_report["misses"], far_report["covered_texels"]);
  // A cage must have the base's topology: a bad input naming the cage, nothing written.
  const Result bad = run(bake_args(dir, "low.obj", "near.obj", "bad", common + " --cage " + (dir / "other.obj").string()));
  EXPECT_EQ(bad.code, 3);
  EXPECT_EQ(lines(bad.err), 1u) << bad.err;
  EXPECT_NE(bad.err.find("other.obj"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(dir / "bad"));
  EXPECT_EQ(near_report["cage_vertices_on_base"], 0);
  EXPECT_EQ(near.err.find("lie on the base"), std::string::npos) << near.err;
  // A cage equal to the base gives no direction: the rays go along the normal with --front,
  // as without a cage, and the run says so (it was silent).
  const Result flat = run(bake_args(dir, "low.obj", "near.obj", "flat", common + " --cage " + (dir / "low.obj").string()));
  ASSERT_EQ(flat.code, 0) << flat.err;
  const auto flat_report = nlohmann::json::parse(flat.out);
  EXPECT_EQ(flat_report["cage_vertices_on_base"], base.n_vertices());
  EXPECT_NE(flat.err.find("9 of 9 vertices lie on the base mesh's"), std::string::npos) << flat.err;
  EXPECT_NEAR(flat_report["displacement_max"].get<double>(), 0.01, 1e-5) << "along the normal";
}

// Inputs a degenerate-input sweep found accepted silently: a base whose UVs tile 0..2 is
// baked only inside [0, 1] (now a warning naming the count); a detail map whose values span
// more than a float had its gradient overflow (now refused as the streams refuse it).
TEST(CliBake, TiledUvsWarnAndADetailBeyondTheFloatSpanIsRefused) {
  test::TempDir dir;
  Mesh tiled = test::make_grid(2, 2);
  for (auto h : tiled.halfedges())
    if (!tiled.is_boundary(h)) tiled.set_texcoord2D(h, tiled.texcoord2D(h) * 2.0f);
  write_mesh(tiled, dir / "tiled.obj");
  write_mesh(test::make_grid(2, 2), dir / "low.obj");
  write_mesh(test::make_layers({{0.01f, true}}), dir / "high.obj");
  const Result t = run(bake_args(dir, "tiled.obj", "high.obj", "t", "--size 8 --front 0.1 --back 0.1"));
  EXPECT_EQ(t.code, 0) << t.err;
  EXPECT_NE(t.err.find("tiled.obj: 6 of 8 faces have UVs outside [0, 1]"), std::string::npos) << t.err;
  const Result plain = run(bake_args(dir, "low.obj", "high.obj", "p", "--size 8 --front 0.1 --back 0.1"));
  EXPECT_EQ(plain.code, 0) << plain.err;
  EXPECT_EQ(plain.err.find("outside [0, 1]"), std::string::npos) << plain.err;
  Image checker(4, 4, 1);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) checker.at(x, y) = (x + y) % 2 ? 3e38f : -3e38f;
  write_image(checker, dir / "checker.exr", PixelFormat::float32);
  const Result detail = run(bake_args(dir, "low.obj", "high.obj", "d", "--size 8 --detail " + (dir / "checker.exr").string()));
  EXPECT_EQ(detail.code, 3) << detail.err;
  EXPECT_NE(detail.err.find("checker.exr: its values span more than the float range"), std::string::npos) << detail.err;
  EXPECT_FALSE(fs::exists(dir / "d"));
  // Finite values that overflow once scaled: refused naming the map (they had reached the
  // writer as Inf, exit 4).
  write_image(Image(4, 4, 1, 1e34f), dir / "strong.exr", PixelFormat::float32);
  const Result strong = run(bake_args(dir, "low.obj", "high.obj", "s", "--size 8 --detail " + (dir / "strong.exr").string() + " --detail-scale 1e6"));
  EXPECT_EQ(strong.code, 3) << strong.err;
  EXPECT_NE(strong.err.find("strong.exr: its values times --detail-scale"), std::string::npos) << strong.err;
  EXPECT_FALSE(fs::exists(dir / "s"));
}

// --basis pn: a coarse sphere band (12 sides, radial normals in the file) over a fine one. The
// flat triangles sit well inside the sphere; the PN patches built from the normals follow it
// far more closely (the report's displacement range over hits, --dilate 0).
TEST(CliBake, PnBasisFollowsTheCurvedSurface) {
  test::TempDir dir;
  write_mesh(test::make_sphere_band(12, 4), dir / "low.obj");
  write_mesh(test::make_sphere_band(128, 48), dir / "high.obj");
  auto worst = [&](const std::string& basis) {
    const Result r = run(bake_args(dir, "low.obj", "high.obj", basis, "--size 64 --dilate 0 --maps displacement --json --basis " + basis));
    EXPECT_EQ(r.code, 0) << r.err;
    if (r.code != 0) return -1.0;
    const auto report = nlohmann::json::parse(r.out);
    EXPECT_EQ(report["basis"], basis);
    EXPECT_EQ(report["misses"], 0);
    return std::max(std::abs(report["displacement_min"].get<double>()), std::abs(report["displacement_max"].get<double>()));
  };
  const double linear = worst("linear"), pn = worst("pn");
  EXPECT_GT(linear, 0.02) << "the flat triangles of a 12-sided band are far inside";
  EXPECT_LT(pn, 0.2 * linear) << "linear " << linear << ", pn " << pn;
  EXPECT_EQ(run(bake_args(dir, "low.obj", "high.obj", "bad", "--size 8 --basis cubic")).code, 2);
}

// --detail BUMP --detail-scale S: a sine across the high plane's u (u = (x + 0.5) / 2) adds
// S (b - 1/2) to the displacement and tilts the normals by its slope, in displacement.exr,
// normal_ts.exr and normal_os.exr, at S = 0.02 (twice the default: a scale ignored would show).
// A high mesh without UVs cannot carry the bump (bad input).
TEST(CliBake, DetailBumpAddsItsScaledHeightAndTiltsTheNormals) {
  test::TempDir dir;
  write_mesh(test::make_grid(2, 2), dir / "low.obj");
  write_mesh(test::make_plane(0, 0, 0), dir / "high.obj");
  Image bump(64, 1, 1);
  for (int x = 0; x < 64; ++x) bump.at(x, 0) = static_cast<float>(0.5 + 0.5 * std::sin(2 * M_PI * (x + 0.5) / 64));
  write_image(bump, dir / "bump.exr", PixelFormat::float32);
  const std::string common = "--size 16 --front 0.05 --back 0.05 --maps displacement,normal_ts_exr,normal_os_exr --detail " + (dir / "bump.exr").string();
  const double scale = 0.02;
  const Result r = run(bake_args(dir, "low.obj", "high.obj", "scaled", common + " --detail-scale 0.02"));
  ASSERT_EQ(r.code, 0) << r.err;
  const Image disp = read_image(dir / "scaled" / "displacement.exr"), ts = read_image(dir / "scaled" / "normal_ts.exr"),
              os = read_image(dir / "scaled" / "normal_os.exr");
  for (int x = 2; x < 14; ++x) {
    const double u_high = ((x + 0.5) / 16 + 0.5) / 2;
    const double height = scale * 0.5 * std::sin(2 * M_PI * u_high);
    const double slope = scale * 0.5 * 2 * M_PI * std::cos(2 * M_PI * u_high) / 2;  // per unit x
    const double nx = -slope / std::sqrt(1 + slope * slope);
    EXPECT_NEAR(disp.at(x, 8), height, 4e-4) << x;
    EXPECT_NEAR(os.at(x, 8, 0), nx, 2e-3) << x;
    EXPECT_NEAR(ts.at(x, 8, 0), nx, 2e-3) << x << ": the grid's tangent is +x";
  }
  test::write_text(dir / "nouv.obj", "v -1 -1 0.01\nv 2 -1 0.01\nv 2 2 0.01\nv -1 2 0.01\nf 1 2 3\nf 1 3 4\n");
  const Result no_uvs = run(bake_args(dir, "low.obj", "nouv.obj", "bad", common));
  EXPECT_EQ(no_uvs.code, 3) << no_uvs.err;
  EXPECT_NE(no_uvs.err.find("nouv.obj"), std::string::npos) << no_uvs.err;
  EXPECT_FALSE(fs::exists(dir / "bad"));
}

// An OBJ object `name`: the rectangle [x0, x1] x [y0, y1] at height z (two triangles, facing
// +z), with UV = (x, y) when `uv`; `first` is the 1-based index of its first vertex.
std::string rect_obj(const std::string& name, float x0, float x1, float y0, float y1, float z, int first, bool uv) {
  std::string s = "o " + name + "\n";
  const float xs[4] = {x0, x1, x1, x0}, ys[4] = {y0, y0, y1, y1};
  for (int k = 0; k < 4; ++k) {
    s += "v " + std::to_string(xs[k]) + " " + std::to_string(ys[k]) + " " + std::to_string(z) + "\n";
    if (uv) s += "vt " + std::to_string(xs[k]) + " " + std::to_string(ys[k]) + "\n";
  }
  auto corner = [&](int k) {
    const std::string i = std::to_string(first + k);
    return uv ? i + "/" + i : i;
  };
  return s + "f " + corner(0) + " " + corner(1) + " " + corner(2) + "\nf " + corner(0) + " " + corner(2) + " " + corner(3) + "\n";
}

// --match-by-name: the base's "Box_low" (left half) and "Plate_LP.001" (right half) each see
// only their high part: box_high 0.01 above everything, plate_high 0.02 below everything.
// Paired, the plate's texels take their own plate, not the nearer box surface that the
// nearest rule picks unpaired (Bake.MatchByNamePairsParts).
TEST(CliBake, MatchByNameKeepsRaysOffTheNeighbouringPart) {
  test::TempDir dir;
  test::write_text(dir / "low.obj", rect_obj("Box_low", 0, 0.5f, 0, 1, 0, 1, true) + rect_obj("Plate_LP.001", 0.5f, 1, 0, 1, 0, 5, true));
  test::write_text(dir / "high.obj", rect_obj("box_high", -1, 2, -1, 2, 0.01f, 1, false) + rect_obj("plate_high", -1, 2, -1, 2, -0.02f, 5, false));
  const std::string common = "--size 8 --front 0.05 --back 0.05 --maps displacement --json";
  const Result paired = run(bake_args(dir, "low.obj", "high.obj", "paired", common + " --match-by-name"));
  ASSERT_EQ(paired.code, 0) << paired.err;
  const auto report = nlohmann::json::parse(paired.out);
  EXPECT_EQ(report["matched_parts"], nlohmann::json::array({"Box_low", "Plate_LP.001"}));
  EXPECT_TRUE(report["unmatched_parts"].empty());
  const Image disp = read_image(dir / "paired" / "displacement.exr");
  for (int y = 0; y < 8; ++y) {
    EXPECT_NEAR(disp.at(1, y), 0.01f, 1e-6f) << "box texel";
    EXPECT_NEAR(disp.at(6, y), -0.02f, 1e-6f) << "plate texel: the nearer box surface is not its part";
  }
  // A base part without a high partner sees the whole high mesh, with a warning and in the report.
  test::write_text(dir / "other.obj", rect_obj("box_high", -1, 2, -1, 2, 0.01f, 1, false) + rect_obj("other_high", -1, 2, -1, 2, -0.02f, 5, false));
  const Result partial = run(bake_args(dir, "low.obj", "other.obj", "partial", common + " --match-by-name"));
  ASSERT_EQ(partial.code, 0) << partial.err;
  EXPECT_EQ(nlohmann::json::parse(partial.out)["unmatched_parts"], nlohmann::json::array({"Plate_LP.001"}));
  EXPECT_NE(partial.err.find("no high part of the same name (Plate_LP.001)"), std::string::npos) << partial.err;
  EXPECT_NEAR(read_image(dir / "partial" / "displacement.exr").at(6, 4), 0.01f, 1e-6f);
}

// --front/--back as percentages resolve against the high mesh's bounding-box diagonal, and
// the default reach is 5 % of it, both ways (the report's front and back, object units).
TEST(CliBake, PercentReachResolvesAgainstTheHighDiagonal) {
  test::TempDir dir;
  write_mesh(test::make_grid(2, 2), dir / "low.obj");
  write_mesh(test::make_plane(0.3f, -0.2f, 0.01f), dir / "high.obj");
  const float diagonal = bounding_box(read_mesh(dir / "high.obj")).diagonal();
  ASSERT_GT(diagonal, 2.8f) << "[-0.5, 1.5]^2, tilted";
  const std::string common = "--size 4 --maps displacement --json";
  const auto percent = nlohmann::json::parse(run(bake_args(dir, "low.obj", "high.obj", "p", common + " --front 4% --back 2.5%")).out);
  EXPECT_NEAR(percent["front"].get<double>(), 0.04 * diagonal, 1e-6 * diagonal);
  EXPECT_NEAR(percent["back"].get<double>(), 0.025 * diagonal, 1e-6 * diagonal);
  const auto defaults = nlohmann::json::parse(run(bake_args(dir, "low.obj", "high.obj", "d", common)).out);
  EXPECT_NEAR(defaults["front"].get<double>(), 0.05 * diagonal, 1e-6 * diagonal);
  EXPECT_NEAR(defaults["back"].get<double>(), 0.05 * diagonal, 1e-6 * diagonal);
}

}  // namespace
// The window draws what headless draws ("same shaders, same results"): under a virtual X
// server (Debian's xvfb, which setup-deps installs; GLX on the same Mesa llvmpipe), the
// window closes itself after 2 frames and writes its last one; it must match the headless
// render of the same view in every pixel below the on-screen line (the top 16 rows), to the
// 8-bit framebuffer's rounding.
// Embree asserts (exit 134) on rays and geometry beyond about 1.8e18 units, and misses
// triangles under an absolute floor: the reference traces in units of the mesh's half
// diagonal, so a mesh 1.2e21 across compares as one of 1 (it was refused, exit 2), and the
// camera options are bounded.
TEST(CliPreview, CompareTracesAMeshBeyondEmbreesRangeAndBoundsTheCamera) {
  test::TempDir dir;
  Mesh huge = test::make_grid(2, 2);
  for (auto v : huge.vertices()) huge.set_point(v, huge.point(v) * std::ldexp(1.0f, 70));  // ~1.2e21 across
  write_mesh(huge, dir / "huge.obj");
  const std::string obj = (dir / "huge.obj").string();
  ASSERT_EQ(run("bake --low " + obj + " --high " + obj + " -o " + (dir / "maps").string() + " --size 16").code, 0);
  const Result r = run("preview " + obj + " --maps " + (dir / "maps").string() + " --compare --json --method pom --size 8x8");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto report = nlohmann::json::parse(r.out);
  ASSERT_EQ(report["methods"].size(), 1u);
  EXPECT_GT(report["methods"][0]["pixels"].get<double>(), 0) << r.out;
  EXPECT_EQ(report["methods"][0]["wrong_hit_fraction"].get<double>(), 0.0) << "a flat identity bake: the method and the reference agree";
  // Beyond the driver's size (llvmpipe: 16384): a usage error saying so (it was exit 4,
  // "float framebuffer is not supported").
  const Result wide = run("preview " + obj + " --maps " + (dir / "maps").string() + " --method pom --headless --png " +
                          (dir / "w.png").string() + " --size 32768x1");
  EXPECT_EQ(wide.code, 2) << wide.err;
  EXPECT_NE(wide.err.find("pixels per side"), std::string::npos) << wide.err;
  // --compare says so before its reference (it had taken 46 s at 16385 x 16), a size beyond
  // the machine's memory is refused up front (32768² had asked for 32 GB), and a window
  // beyond 16384 is refused before any window is made (32768² aborted inside libxcb).
  for (const char* size : {"16385x16", "32768x32768"}) {
    const Result c = run("preview " + obj + " --maps " + (dir / "maps").string() + " --compare --method pom --size " + size);
    EXPECT_EQ(c.code, 2) << size << "\n" << c.err;
    EXPECT_EQ(lines(c.err), 1u) << c.err;
  }
  const Result window = run("preview " + obj + " --maps " + (dir / "maps").string() + " --method pom --size 20000x20000");
  EXPECT_EQ(window.code, 2) << window.err;
  EXPECT_NE(window.err.find("a preview window is at most 16384 pixels per side"), std::string::npos) << window.err;
  for (const char* option : {"--pan 1e20,0", "--zoom 1e39", "--azimuth 1e39", "--light-azimuth 1e39"})
    EXPECT_EQ(run("preview " + obj + " --maps " + (dir / "maps").string() + " --compare --method pom --size 8x8 " + option).code, 2) << option;
}

// Off a clamped map (UVs beyond [0, 1]) the surface goes on, clamp-to-edge, as the reference
// and the linear searches read it; cone, relaxed-cone and pyramid now follow it as sphere
// tracing does (they had stopped at the map's border: every pixel of a quad mapped to UVs
// 1..2 was wrong). The map: a tilted plane baked onto a unit quad. (Its relief, up to 0.4 on
// a quad 1 across, puts much of the image where the reference's surface, which ends at the
// quad, and the per-pixel methods' clamped one differ: every method, sphere tracing too,
// has the same wrong hits there.)
TEST(CliPreview, SafeMethodsFollowAClampedMapBeyondItsBorder) {
  test::TempDir d;
  const std::string quad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n";
  test::write_text(d / "q0.obj", "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n" + quad);
  test::write_text(d / "q.obj", "vt 1 1\nvt 2 1\nvt 2 2\nvt 1 2\n" + quad);
  test::write_text(d / "tilt.obj", "v -0.5 -0.5 0.55\nv 1.5 -0.5 -0.05\nv 1.5 1.5 -0.05\nv -0.5 1.5 0.55\nf 1 2 3\nf 1 3 4\n");
  const std::string maps = (d / "maps").string(), displacement = (d / "maps" / "displacement.exr").string();
  ASSERT_EQ(run("bake --low " + (d / "q0.obj").string() + " --high " + (d / "tilt.obj").string() + " -o " + maps + " --size 64 --front 1 --back 1").code, 0);
  for (const char* stream : {"cone", "relaxed-cone", "pyramid", "sdf"})
    ASSERT_EQ(run(std::string("streams ") + stream + " " + displacement + " -o " + maps + "/" + stream + ".exr").code, 0) << stream;
  const Result r = run("preview " + (d / "q.obj").string() + " --maps " + maps +
                       " --compare --json --method sphere-tracing,cone,relaxed-cone,pyramid --size 48x36 --view-angle 60");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto report = nlohmann::json::parse(r.out);
  ASSERT_EQ(report["methods"].size(), 4u);
  const double traced = report["methods"][0]["wrong_hit_fraction"].get<double>();
  EXPECT_LT(traced, 0.5) << r.out;
  for (const auto& m : report["methods"]) {
    EXPECT_GT(m["pixels"].get<double>(), 100) << r.out;
    EXPECT_LE(m["wrong_hit_fraction"].get<double>(), traced + 0.01) << m["name"] << "\n" << r.out;
  }
}

// A displacement map whose finite heights span more than a float (-3e38 to 3e38) cannot be
// normalised: the streams refused it and so does the previewer, before any rendering.
TEST(CliPreview, DisplacementBeyondTheFloatSpanIsRefused) {
  test::TempDir d;
  write_mesh(test::make_grid(2, 2), d / "base.obj");
  fs::create_directories(d / "maps");
  Image height(4, 4, 1, 0.0f), normals(4, 4, 3, 0.5f);
  height.at(0, 0) = -3e38f;
  height.at(3, 3) = 3e38f;
  write_image(height, d / "maps" / "displacement.exr", PixelFormat::float32);
  write_image(normals, d / "maps" / "normal_ts.png", PixelFormat::uint8);
  const Result r = run("preview " + (d / "base.obj").string() + " --maps " + (d / "maps").string() + " --method pom --headless --png " +
                       (d / "p.png").string() + " --size 8x8");
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find("displacement.exr: its heights span more than the float range"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(d / "p.png"));
  // --png naming one of the maps it reads is refused before any work.
  const Result over = run("preview " + (d / "base.obj").string() + " --maps " + (d / "maps").string() + " --method pom --headless --png " +
                          (d / "maps" / "normal_ts.png").string() + " --size 8x8");
  EXPECT_EQ(over.code, 2) << over.err;
  EXPECT_NE(over.err.find("is also the input"), std::string::npos) << over.err;
}

// Maps the previewer must draw, or refuse, as the other stages do (a degenerate-input sweep):
// a displacement.exr with more channels draws channel 0 (a G of 1e20 had emptied the frame);
// a surface displaced 2 units below a unit base is drawn (the depth range had clipped it);
// a base without area is bad input (compare had said "need -nan" with exit 2).
TEST(CliPreview, DrawsChannelZeroAndFarDisplacementsAndRefusesAFlatBase) {
  test::TempDir d;
  write_mesh(test::make_grid(2, 2), d / "base.obj");
  Image one(8, 8, 1), three(8, 8, 3), normals(8, 8, 3, 0.5f), far(8, 8, 1);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) {
      one.at(x, y) = three.at(x, y, 0) = 0.01f * static_cast<float>((x + y) % 3);
      three.at(x, y, 1) = 1e20f;
      three.at(x, y, 2) = -3.0f;
      far.at(x, y) = -2.0f + 0.01f * static_cast<float>(x);
    }
  for (const auto& [name, image] : {std::pair<std::string, const Image*>{"one", &one}, {"three", &three}, {"far", &far}}) {
    fs::create_directories(d / name);
    write_image(*image, d / name / "displacement.exr", PixelFormat::float32);
    write_image(normals, d / name / "normal_ts.png", PixelFormat::uint8);
  }
  auto render = [&](const std::string& maps, const std::string& method) {
    const fs::path png = d / (maps + "_" + method + ".png");
    const Result r = run("preview " + (d / "base.obj").string() + " --maps " + (d / maps).string() + " --method " + method +
                         " --headless --size 32x32 --view-angle 30 --png " + png.string());
    EXPECT_EQ(r.code, 0) << r.err;
    return r.code == 0 ? read_image(png) : Image();
  };
  auto covered = [](const Image& img) {
    size_t n = 0;
    for (size_t i = 3; i < img.pixels.size(); i += 4) n += img.pixels[i] > 0;
    return n;
  };
  for (const char* method : {"relief", "mesh"}) {
    const Image a = render("one", method), b = render("three", method);
    EXPECT_GT(covered(a), 100u) << method;
    EXPECT_EQ(a.pixels, b.pixels) << method << ": channels 1 and 2 must not matter";
    EXPECT_GT(covered(render("far", method)), 100u) << method << ": the surface 2 units below is drawn";
  }
  Mesh flat = test::make_grid(2, 2);
  for (auto v : flat.vertices()) flat.set_point(v, Vec3f(0.5f, 0.5f, 0.0f));
  write_mesh(flat, d / "point.obj");
  for (const std::string& mode : {" --headless --png " + (d / "p.png").string(), std::string(" --compare")}) {
    const Result r = run("preview " + (d / "point.obj").string() + " --maps " + (d / "one").string() + " --method pom --size 16x16" + mode);
    EXPECT_EQ(r.code, 3) << mode << "\n" << r.err;
    EXPECT_NE(r.err.find("point.obj: has no surface area"), std::string::npos) << r.err;
  }
}

// The maps are read as their metadata says: a displacement.exr that records its mapping to
// object units (bake's displacement.png converted to EXR) through that mapping, as `meso
// streams` reads it (it had been drawn 1/scale times too high, and its streams refused as
// "made from another height map"); a normal map baked with --normal-y down with its green
// turned back (it had been drawn with green inverted). Another quantity under either name is
// refused.
TEST(CliPreview, MapsAreReadAsTheirMetadataSays) {
  test::TempDir d;
  write_mesh(test::make_grid(2, 2), d / "base.obj");
  // Heights and greens that the mappings carry exactly (multiples of 1/64, codes k / 255).
  Image height(8, 8, 1), normalised(8, 8, 1), up(8, 8, 3, 0.0f), down(8, 8, 3, 0.0f);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) {
      const int k = (x + 2 * y) % 3;
      height.at(x, y) = 0.25f + static_cast<float>(k) / 64.0f;
      normalised.at(x, y) = static_cast<float>(k) / 2.0f;
      const float g = static_cast<float>(100 + 20 * ((x + y) % 4)) / 255.0f;
      up.at(x, y, 0) = down.at(x, y, 0) = 140.0f / 255.0f;
      up.at(x, y, 1) = g;
      down.at(x, y, 1) = 1.0f - g;
      up.at(x, y, 2) = down.at(x, y, 2) = 230.0f / 255.0f;
    }
  normalised.metadata = {{"height_scale", 2.0f / 64.0f}, {"height_bias", 0.25f}};
  down.metadata = {{"quantity", std::string("normal")}, {"normal_y", std::string("down")}};
  auto write_maps = [&](const std::string& maps, const Image& displacement, const Image& normals) {
    fs::create_directories(d / maps);
    write_image(displacement, d / maps / "displacement.exr", PixelFormat::float32);
    write_image(normals, d / maps / "normal_ts.png", PixelFormat::uint8);
  };
  write_maps("plain", height, up);
  write_maps("tagged", normalised, down);
  auto render = [&](const std::string& maps) {
    const fs::path png = d / (maps + ".png");
    const Result r = run("preview " + (d / "base.obj").string() + " --maps " + (d / maps).string() +
                         " --method relief --headless --size 32x32 --view-angle 40 --png " + png.string());
    EXPECT_EQ(r.code, 0) << r.err;
    return r.code == 0 ? read_image(png) : Image();
  };
  const Image plain = render("plain"), tagged = render("tagged");
  ASSERT_FALSE(plain.pixels.empty());
  EXPECT_EQ(plain.pixels, tagged.pixels);
  // Another meso map under either name.
  Image cone = height, object_space = up;
  cone.metadata = {{"quantity", std::string("cone map")}};
  object_space.metadata = {{"quantity", std::string("normal")}, {"space", std::string("object")}};
  write_maps("wrong_height", cone, up);
  write_maps("wrong_normals", height, object_space);
  for (const auto& [maps, message] : {std::pair<std::string, std::string>{"wrong_height", "displacement.exr: holds a cone map"},
                                      {"wrong_normals", "normal_ts.png: is an object-space normal map"}}) {
    const Result r = run("preview " + (d / "base.obj").string() + " --maps " + (d / maps).string() +
                         " --method relief --headless --size 8x8 --png " + (d / "no.png").string());
    EXPECT_EQ(r.code, 3) << maps << "\n" << r.err;
    EXPECT_EQ(lines(r.err), 1u) << r.err;
    EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(d / "no.png"));
  }
}

// --shade height: object units in an EXR; in an 8-bit PNG normalised to the map's range with
// the mapping in its metadata (the raw heights, all below 1/255 unit, had come out black).
TEST(CliPreview, HeightShadeIsReadableInEveryFormat) {
  test::TempDir d;
  write_mesh(test::make_grid(2, 2), d / "base.obj");
  fs::create_directories(d / "maps");
  Image height(8, 8, 1), normals(8, 8, 3, 0.5f);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) height.at(x, y) = 0.004f * static_cast<float>(x);  // 0 to 0.028
  write_image(height, d / "maps" / "displacement.exr", PixelFormat::float32);
  write_image(normals, d / "maps" / "normal_ts.png", PixelFormat::uint8);
  const std::string scene = "preview " + (d / "base.obj").string() + " --maps " + (d / "maps").string() +
                            " --method pom --headless --size 32x32 --view-angle 0 --shade height --png ";
  ASSERT_EQ(run(scene + (d / "h.exr").string()).code, 0);
  ASSERT_EQ(run(scene + (d / "h.png").string()).code, 0);
  const Image exr = read_image(d / "h.exr"), png = read_image(d / "h.png");
  float exr_max = 0, png_max = 0;
  for (size_t i = 0; i < exr.pixels.size(); i += 4) {
    if (exr.pixels[i + 3] == 0) continue;
    EXPECT_GE(exr.pixels[i], -1e-6f);
    EXPECT_LE(exr.pixels[i], 0.028f + 1e-6f);
    exr_max = std::max(exr_max, exr.pixels[i]);
  }
  for (size_t i = 0; i < png.pixels.size(); i += 4) png_max = std::max(png_max, png.pixels[i]);
  EXPECT_GT(exr_max, 0.02f) << "object units";
  EXPECT_GT(png_max, 0.7f) << "normalised to the map's range";
  EXPECT_NEAR(std::stod(std::get<std::string>(png.metadata.at("height_scale"))), 0.028, 1e-6);
  EXPECT_NEAR(std::stod(std::get<std::string>(png.metadata.at("height_bias"))), 0.0, 1e-9);
}

TEST(CliPreview, WindowDrawsWhatHeadlessDraws) {
  if (std::system("command -v xvfb-run >/dev/null 2>&1") != 0) {
    if (const char* required = std::getenv("MESO_REQUIRE_PEERS"); required && std::string(required) == "1")
      FAIL() << "xvfb-run is missing (scripts/setup-deps installs xvfb): the window is untested";
    GTEST_SKIP() << "xvfb-run not found";
  }
  test::TempDir d;
  write_mesh(test::make_grid(4, 4), d / "base.obj");
  fs::create_directories(d / "maps");
  Image height(64, 64, 1), normals(64, 64, 3);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      height.at(x, y) = 0.03f * std::abs(std::sin(0.3f * static_cast<float>(x)) * std::cos(0.2f * static_cast<float>(y)));
      const float nx = 0.3f * std::sin(0.2f * static_cast<float>(x)), ny = 0.2f * std::cos(0.3f * static_cast<float>(y));
      normals.at(x, y, 0) = 0.5f * nx + 0.5f;
      normals.at(x, y, 1) = 0.5f * ny + 0.5f;
      normals.at(x, y, 2) = 0.5f * std::sqrt(1 - nx * nx - ny * ny) + 0.5f;
    }
  write_image(height, d / "maps" / "displacement.exr", PixelFormat::float32);
  write_image(normals, d / "maps" / "normal_ts.png", PixelFormat::uint16);
  const std::string scene = "preview " + (d / "base.obj").string() + " --maps " + (d / "maps").string() +
                            " --method relief --size 96x64 --view-angle 50 --azimuth 20";
  const Result window = run_env("xvfb-run -a -s '-screen 0 320x240x24' ", scene + " --frames 2 --png " + (d / "window.png").string() + " --json");
  ASSERT_EQ(window.code, 0) << window.err;
  const auto report = nlohmann::json::parse(window.out);
  EXPECT_EQ(report["frames"].get<int>(), 2);
  EXPECT_GT(report["median_frame_ms"].get<double>(), 0.0);
  ASSERT_EQ(run(scene + " --headless --png " + (d / "headless.png").string()).code, 0);
  const Image win = read_image(d / "window.png"), off = read_image(d / "headless.png");
  ASSERT_EQ(win.width, off.width);
  ASSERT_EQ(win.height, off.height);
  size_t on_mesh = 0;
  double worst = 0;
  for (int y = 16; y < win.height; ++y)
    for (int x = 0; x < win.width; ++x) {
      on_mesh += off.at(x, y, 3) > 0.5f;
      for (int c = 0; c < 3; ++c) worst = std::max(worst, static_cast<double>(std::abs(win.at(x, y, c) - off.at(x, y, c))));
    }
  std::printf("window against headless: largest difference %.4f (%zu pixels on the mesh)\n", worst, on_mesh);
  EXPECT_GT(on_mesh, 96u * 48u / 10);
  EXPECT_LE(worst, 1.5 / 255.0);
  EXPECT_EQ(run(scene + " --headless --png " + (d / "x.png").string() + " --frames 2").code, 2) << "--frames is for the window";
  EXPECT_EQ(run(scene + " --png " + (d / "y.png").string()).code, 2) << "--png in the window needs --frames";
}

}  // namespace meso
