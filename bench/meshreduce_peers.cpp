// meshreduce against its peers, on the same inputs and face counts, in one run, with one
// error measure (meso::measure_surface_distance: two-sided Hausdorff and RMS by dense
// sampling, CGAL AABB tree).
//
//   build/release/bench/meshreduce_peers                       # bricks + smooth torus, 10 %, 1 %, 0.1 %
//   build/release/bench/meshreduce_peers --ratios 0.1,0.01 --mesh high.obj --only-files
//   build/release/bench/meshreduce_peers --presets fast,balanced --no-cgal --no-blender --no-meshlab
//
// meso runs once per --quality preset (--presets, default fast,balanced,best), each row
// naming it in the preset column.
// Inputs: the bundled brick wall (262,144 triangles, one UV chart), a smooth analytic
// torus (262,144 triangles, UV seams along both wrap lines), and any --mesh files. meso runs
// twice: on the mesh with its UVs (seams kept, as the pipeline uses it) and, "no UVs", on the
// positions the peers get. Peers, each on positions only (welded; none is given the UVs):
//  - meshoptimizer's meshopt_simplify, when built with libmeshoptimizer-dev;
//  - CGAL's edge_collapse with the Garland–Heckbert plane policies and the bounded normal
//    change filter (bench/meshreduce_cgal_peer.cpp);
//  - Blender's Decimate modifier, Collapse, ratio = target / input faces, when `blender` is
//    on the PATH (bench/meshreduce_blender.py, run as a separate process);
//  - MeshLab's Quadric Edge Collapse Decimation through `xvfb-run -a meshlabserver`, when
//    both are on the PATH: once at its default parameters, once "careful" (PreserveNormal,
//    PreserveTopology and PlanarQuadric on, the options a user reaches for against flips).
// Times are wall-clock, best of --repeat runs, single thread, of the reduction alone: the
// library call for meso, meshoptimizer and CGAL, the modifier's application inside Blender.
// meshlabserver does not report a filter's time, so MeshLab's is the run with the filter
// minus a run that only loads the same input (both best of at least 3), which also counts
// writing the small output.
//
// Every output is measured as a triangle soup welded by position (the way meso's reader
// welds), against the input as a soup, and its triangles are counted: flipped (normal
// against that of the input triangle nearest its centroid), degenerate (zero area) and
// non-manifold (on an edge of more than two triangles or of two triangles that traverse it
// the same way, at a vertex whose triangles form more than one fan, or repeating a vertex).
#include "meshreduce_cgal_peer.hpp"
#include "meso/examples/brick_wall.hpp"
#include "meso/examples/parametric.hpp"
#include "meso/formats/mesh_io.hpp"
#include "meso/meshreduce/meshreduce.hpp"
#include "meso/meshreduce/surface_distance.hpp"

#ifdef MESO_HAVE_MESHOPTIMIZER
#include <meshoptimizer.h>
#endif

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <numeric>
#include <optional>
#include <sstream>
#include <string>
#include <unordered_map>
#include <vector>

namespace {

using namespace meso;
namespace fs = std::filesystem;


double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

struct Row {
  std::string method;
  std::string preset = "–";  // meso's --quality
  size_t faces = 0;
  double seconds = 0;
  SurfaceDistance d;
  size_t flipped = 0, degenerate = 0, non_manifold = 0;
  bool ok = false;
  std::string note;  // why a peer gave no result
};

// Merges bitwise-equal positions and drops unreferenced points, so that every method's
// output is counted and measured on the same terms: meso's reader (Blender's and MeshLab's
// outputs) puts non-manifold faces on vertices of their own, and meshoptimizer's output
// indexes the whole input vertex array.
TriangleSoup weld(const TriangleSoup& in) {
  struct Key {
    float x, y, z;
    bool operator<(const Key& o) const { return std::memcmp(this, &o, sizeof(Key)) < 0; }
  };
  std::map<Key, uint32_t> index;
  TriangleSoup out;
  out.triangles.reserve(in.triangles.size());
  for (const auto& t : in.triangles) {
    std::array<uint32_t, 3> w{};
    for (int k = 0; k < 3; ++k) {
      const Vec3f& p = in.points[t[k]];
      const auto [it, added] = index.try_emplace(Key{p[0], p[1], p[2]}, static_cast<uint32_t>(out.points.size()));
      if (added) out.points.push_back(p);
      w[k] = it->second;
    }
    out.triangles.push_back(w);
  }
  return out;
}

// Triangles of a welded soup that are not part of a consistently oriented 2-manifold (see the
// file comment for the cases).
size_t count_non_manifold(const TriangleSoup& s) {
  const size_t n = s.triangles.size();
  std::vector<char> bad(n, 0), repeated(n, 0);
  // Corners (3 per triangle) around each vertex are joined through the edges their triangles
  // share; a vertex with more than one group of corners is a bow-tie.
  std::vector<uint32_t> parent(3 * n);
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](uint32_t c) {
    while (parent[c] != c) c = parent[c] = parent[parent[c]];
    return c;
  };
  auto join = [&](uint32_t a, uint32_t b) { parent[find(a)] = find(b); };
  struct Use {
    uint32_t face;
    int from;  // corner index of the edge's first vertex in the face's order
  };
  std::unordered_map<uint64_t, std::vector<Use>> edges;
  edges.reserve(2 * n);
  for (uint32_t f = 0; f < n; ++f) {
    const auto& t = s.triangles[f];
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) {
      bad[f] = repeated[f] = 1;
      continue;
    }
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = t[k], b = t[(k + 1) % 3];
      edges[(uint64_t{std::min(a, b)} << 32) | std::max(a, b)].push_back({f, k});
    }
  }
  for (const auto& [key, uses] : edges) {
    const bool wrong = uses.size() > 2 || (uses.size() == 2 && s.triangles[uses[0].face][uses[0].from] ==
                                                                   s.triangles[uses[1].face][uses[1].from]);
    if (wrong)
      for (const Use& u : uses) bad[u.face] = 1;
    if (uses.size() != 2) continue;
    // Join the corners at each of the edge's two vertices across the two triangles.
    for (const uint32_t v : {static_cast<uint32_t>(key >> 32), static_cast<uint32_t>(key & 0xffffffffu)}) {
      uint32_t c[2];
      for (int i = 0; i < 2; ++i) {
        const auto& t = s.triangles[uses[i].face];
        const int k = t[0] == v ? 0 : t[1] == v ? 1 : 2;
        c[i] = 3 * uses[i].face + static_cast<uint32_t>(k);
      }
      join(c[0], c[1]);
    }
  }
  std::vector<uint32_t> group(s.points.size(), UINT32_MAX);
  std::vector<char> bowtie(s.points.size(), 0);
  for (uint32_t c = 0; c < 3 * n; ++c) {
    if (repeated[c / 3]) continue;  // joined to nothing: it would make every vertex it touches a bow-tie
    const uint32_t v = s.triangles[c / 3][c % 3], root = find(c);
    if (group[v] == UINT32_MAX) group[v] = root;
    else if (group[v] != root) bowtie[v] = 1;
  }
  size_t count = 0;
  for (uint32_t f = 0; f < n; ++f) {
    const auto& t = s.triangles[f];
    count += bad[f] || bowtie[t[0]] || bowtie[t[1]] || bowtie[t[2]];
  }
  return count;
}

// Measures and counts an output against the input (both as soups).
void finish(Row& r, const TriangleSoup& input, const TriangleSoup& output) {
  const TriangleSoup out = weld(output);
  r.faces = out.triangles.size();
  r.d = measure_surface_distance(input, out);
  const bench::FlipCount flips = bench::count_flipped(input, out);
  r.flipped = flips.flipped;
  r.degenerate = flips.degenerate;
  r.non_manifold = count_non_manifold(out);
  r.ok = true;
}

Row run_meso(const std::string& method, const Mesh& in, const TriangleSoup& input, size_t target, int repeat,
             const ReduceOptions& base, const std::string& preset) {
  Row r;
  r.method = method;
  r.preset = preset;
  r.seconds = 1e30;
  Mesh out;
  for (int i = 0; i < repeat; ++i) {
    ReduceOptions o = base;
    o.target_faces = target;
    o.quality = preset == "fast" ? ReduceQuality::fast : preset == "best" ? ReduceQuality::best : ReduceQuality::balanced;
    const double t0 = now();
    out = reduce_mesh(in, o);
    r.seconds = std::min(r.seconds, now() - t0);
  }
  finish(r, input, triangle_soup(out));
  return r;
}

// The peers' input as a meso Mesh: positions only, so no UV seams to keep (the bricks have a
// boundary still), for the row that compares meso with the peers on their own terms.
Mesh mesh_from_soup(const TriangleSoup& s) {
  Mesh m;
  std::vector<VertexHandle> v;
  v.reserve(s.points.size());
  for (const auto& p : s.points) v.push_back(m.add_vertex(p));
  for (const auto& t : s.triangles) m.add_face(v[t[0]], v[t[1]], v[t[2]]);
  return m;
}

Row run_meshopt(const TriangleSoup& input, size_t target, int repeat) {
  Row r;
  r.method = "meshoptimizer";
#ifdef MESO_HAVE_MESHOPTIMIZER
  std::vector<unsigned> indices;
  indices.reserve(input.triangles.size() * 3);
  for (const auto& t : input.triangles) indices.insert(indices.end(), t.begin(), t.end());
  std::vector<unsigned> out(indices.size());
  size_t n = 0;
  r.seconds = 1e30;
  for (int i = 0; i < repeat; ++i) {
    const double t0 = now();
    n = meshopt_simplify(out.data(), indices.data(), indices.size(), &input.points[0][0], input.points.size(), sizeof(Vec3f),
                         target * 3, 1.0f, 0, nullptr);
    r.seconds = std::min(r.seconds, now() - t0);
  }
  TriangleSoup soup;
  soup.points = input.points;
  for (size_t i = 0; i + 2 < n; i += 3) soup.triangles.push_back({out[i], out[i + 1], out[i + 2]});
  finish(r, input, soup);
#else
  (void)input, (void)target, (void)repeat;
  r.note = "not built (apt-get install libmeshoptimizer-dev, then reconfigure)";
#endif
  return r;
}

Row run_cgal(const TriangleSoup& input, size_t target, int repeat) {
  Row r;
  r.method = "CGAL GH";
  const bench::CgalResult c = bench::run_cgal_garland_heckbert(input, target, repeat);
  r.seconds = c.seconds;
  finish(r, input, c.out);
  return r;
}

bool on_path(const std::string& program) { return std::system(("command -v " + program + " >/dev/null 2>&1").c_str()) == 0; }

// Runs a shell command; its stdout and stderr, and whether it exited with 0.
bool run_command(const std::string& command, std::string& output) {
  output.clear();
  FILE* p = popen((command + " 2>&1").c_str(), "r");
  if (!p) return false;
  char buffer[4096];
  size_t got;
  while ((got = std::fread(buffer, 1, sizeof buffer, p)) > 0) output.append(buffer, got);
  return pclose(p) == 0;
}

std::string last_lines(const std::string& text, int lines) {
  size_t at = text.size();
  for (int i = 0; i <= lines && at > 0; ++i) at = text.rfind('\n', at - 1);
  return at == std::string::npos ? text : text.substr(at + 1);
}

// An external peer's output read back with meso's reader.
bool read_back(Row& r, const fs::path& file, const TriangleSoup& input) {
  try {
    finish(r, input, triangle_soup(read_mesh(file)));
    return true;
  } catch (const std::exception& e) {
    r.note = std::string("unreadable output: ") + e.what();
    return false;
  }
}

Row run_blender(const std::string& blender, const std::string& script, const fs::path& obj, const fs::path& work,
                const TriangleSoup& input, size_t target, int repeat) {
  Row r;
  r.method = "Blender";
  const double ratio = static_cast<double>(target) / static_cast<double>(input.triangles.size());
  const fs::path out = work / "blender_out.obj";
  char ratio_text[32];
  std::snprintf(ratio_text, sizeof ratio_text, "%.17g", ratio);
  const std::string command = "'" + blender + "' -b --factory-startup -t 1 --python '" + script + "' -- '" + obj.string() + "' '" +
                              out.string() + "' " + ratio_text;
  r.seconds = 1e30;
  for (int i = 0; i < repeat; ++i) {
    std::string output;
    const bool ran = run_command(command, output);
    const size_t at = output.find("meshreduce_blender: seconds ");
    if (!ran || at == std::string::npos) {
      r.note = "blender failed: " + last_lines(output, 3);
      return r;
    }
    r.seconds = std::min(r.seconds, std::strtod(output.c_str() + at + std::strlen("meshreduce_blender: seconds "), nullptr));
  }
  read_back(r, out, input);
  return r;
}

// The filter's parameters: MeshLab's defaults but for the target, or with `careful` its
// options against flips and topology changes and its planar quadrics on (meshlabserver
// requires every parameter of the filter in the script).
std::string meshlab_script(size_t target, bool careful) {
  const char* on = careful ? "true" : "false";
  std::ostringstream s;
  s << "<!DOCTYPE FilterScript>\n<FilterScript>\n"
    << " <filter name=\"Simplification: Quadric Edge Collapse Decimation\">\n"
    << "  <Param type=\"RichInt\" name=\"TargetFaceNum\" value=\"" << target << "\"/>\n"
    << "  <Param type=\"RichFloat\" name=\"TargetPerc\" value=\"0\"/>\n"
    << "  <Param type=\"RichFloat\" name=\"QualityThr\" value=\"0.3\"/>\n"
    << "  <Param type=\"RichBool\" name=\"PreserveBoundary\" value=\"false\"/>\n"
    << "  <Param type=\"RichFloat\" name=\"BoundaryWeight\" value=\"1\"/>\n"
    << "  <Param type=\"RichBool\" name=\"PreserveNormal\" value=\"" << on << "\"/>\n"
    << "  <Param type=\"RichBool\" name=\"PreserveTopology\" value=\"" << on << "\"/>\n"
    << "  <Param type=\"RichBool\" name=\"OptimalPlacement\" value=\"true\"/>\n"
    << "  <Param type=\"RichBool\" name=\"PlanarQuadric\" value=\"" << on << "\"/>\n"
    << "  <Param type=\"RichFloat\" name=\"PlanarWeight\" value=\"0.001\"/>\n"
    << "  <Param type=\"RichBool\" name=\"QualityWeight\" value=\"false\"/>\n"
    << "  <Param type=\"RichBool\" name=\"AutoClean\" value=\"true\"/>\n"
    << "  <Param type=\"RichBool\" name=\"Selected\" value=\"false\"/>\n"
    << " </filter>\n</FilterScript>\n";
  return s.str();
}

// Best wall time of `runs` runs of a command; nullopt (and the output in `failure`) if one fails.
std::optional<double> time_command(const std::string& command, int runs, std::string& failure) {
  double best = 1e30;
  for (int i = 0; i < runs; ++i) {
    std::string output;
    const double t0 = now();
    if (!run_command(command, output)) {
      failure = last_lines(output, 3);
      return std::nullopt;
    }
    best = std::min(best, now() - t0);
  }
  return best;
}

Row run_meshlab(const fs::path& off, const fs::path& work, const TriangleSoup& input, size_t target, int repeat, bool careful,
                std::optional<double>& load_seconds) {
  Row r;
  r.method = careful ? "MeshLab careful" : "MeshLab";
  const int runs = std::max(repeat, 3);
  // The 2020.09 OBJ importer of Debian 12's meshlab asserts on plain v/f files; OFF loads.
  const std::string base = "xvfb-run -a meshlabserver -i '" + off.string() + "'";
  std::string failure;
  if (!load_seconds) load_seconds = time_command(base, runs, failure);
  if (!load_seconds) {
    r.note = "meshlabserver failed to load the input: " + failure;
    return r;
  }
  const fs::path script = work / "meshlab.mlx", out = work / "meshlab_out.obj";
  if (FILE* f = std::fopen(script.c_str(), "w")) {
    std::fputs(meshlab_script(target, careful).c_str(), f);
    std::fclose(f);
  }
  const auto total = time_command(base + " -o '" + out.string() + "' -s '" + script.string() + "'", runs, failure);
  if (!total) {
    r.note = "meshlabserver failed: " + failure;
    return r;
  }
  r.seconds = std::max(0.0, *total - *load_seconds);
  read_back(r, out, input);
  return r;
}

// Positions-only input files for the external peers (OBJ for Blender, OFF for MeshLab), with
// enough digits that every float reads back exactly.
void write_plain(const TriangleSoup& s, const fs::path& obj, const fs::path& off) {
  FILE* a = std::fopen(obj.c_str(), "w");
  FILE* b = std::fopen(off.c_str(), "w");
  if (!a || !b) {
    std::fprintf(stderr, "meshreduce_peers: cannot write %s\n", obj.parent_path().c_str());
    std::exit(4);
  }
  std::fprintf(b, "OFF\n%zu %zu 0\n", s.points.size(), s.triangles.size());
  for (const auto& p : s.points) {
    std::fprintf(a, "v %.9g %.9g %.9g\n", p[0], p[1], p[2]);
    std::fprintf(b, "%.9g %.9g %.9g\n", p[0], p[1], p[2]);
  }
  for (const auto& t : s.triangles) {
    std::fprintf(a, "f %u %u %u\n", t[0] + 1, t[1] + 1, t[2] + 1);
    std::fprintf(b, "3 %u %u %u\n", t[0], t[1], t[2]);
  }
  std::fclose(a);
  std::fclose(b);
}

std::vector<double> parse_list(const std::string& s) {
  std::vector<double> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(std::strtod(item.c_str(), nullptr));
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<double> ratios = {0.1, 0.01, 0.001};
  std::vector<std::string> files;
  int repeat = 1;
  bool builtin = true, use_blender = true, use_meshlab = true, use_cgal = true;
  std::vector<std::string> presets = {"fast", "balanced", "best"};
  std::string blender = "blender", blender_script = MESO_BENCH_DIR "/meshreduce_blender.py";
  ReduceOptions base;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--ratios") {
      ratios = parse_list(value());
    } else if (a == "--mesh") {
      files.push_back(value());
    } else if (a == "--only-files") {
      builtin = false;
    } else if (a == "--repeat") {
      repeat = std::max(1, std::atoi(value().c_str()));
    } else if (a == "--max-normal-deviation") {
      base.max_normal_deviation = std::strtof(value().c_str(), nullptr);
    } else if (a == "--max-aspect-ratio") {
      base.max_aspect_ratio = std::strtof(value().c_str(), nullptr);
    } else if (a == "--blender") {
      blender = value();
    } else if (a == "--blender-script") {
      blender_script = value();
    } else if (a == "--no-blender") {
      use_blender = false;
    } else if (a == "--no-meshlab") {
      use_meshlab = false;
    } else if (a == "--no-cgal") {
      use_cgal = false;
    } else if (a == "--presets") {
      presets.clear();
      std::stringstream list(value());
      for (std::string p; std::getline(list, p, ',');) {
        if (p != "fast" && p != "balanced" && p != "best") {
          std::fprintf(stderr, "--presets: %s is not fast, balanced or best\n", p.c_str());
          return 2;
        }
        presets.push_back(p);
      }
    } else {
      std::fprintf(stderr,
                   "usage: meshreduce_peers [--ratios 0.1,0.01,0.001] [--mesh FILE]... [--only-files] [--repeat N]\n"
                   "                        [--max-normal-deviation DEG] [--max-aspect-ratio R]\n"
                   "                        [--blender BIN] [--blender-script PY] [--no-blender] [--no-meshlab] [--no-cgal]\n"
                   "                        [--presets fast,balanced,best]\n");
      return 2;
    }
  }
  // Missing external peers are skipped with one line each, not an error: the bench must run
  // wherever meso builds.
  if (use_blender && !on_path(blender)) {
    std::fprintf(stderr, "meshreduce_peers: %s not found, Blender skipped (apt-get install -y blender)\n", blender.c_str());
    use_blender = false;
  }
  if (use_meshlab && !(on_path("meshlabserver") && on_path("xvfb-run"))) {
    std::fprintf(stderr, "meshreduce_peers: meshlabserver or xvfb-run not found, MeshLab skipped (apt-get install -y meshlab xvfb)\n");
    use_meshlab = false;
  }
#ifndef MESO_HAVE_MESHOPTIMIZER
  std::fprintf(stderr, "meshreduce_peers: built without meshoptimizer (apt-get install -y libmeshoptimizer-dev, reconfigure)\n");
#endif
  const fs::path work = fs::temp_directory_path() / ("meshreduce_peers." + std::to_string(getpid()));
  fs::create_directories(work);

  std::vector<std::pair<std::string, Mesh>> meshes;
  if (builtin) {
    meshes.emplace_back("bricks", make_brick_wall(BrickWallOptions{}));
    meshes.emplace_back("torus", make_smooth_torus(512, 256));
  }
  for (const auto& f : files) meshes.emplace_back(f, read_mesh(f));

  std::printf("| mesh | input faces | target | method | preset | faces | seconds | Hausdorff %% diag | RMS %% diag | time ÷ meshopt | "
              "Hausdorff ÷ best peer | flipped | degenerate | non-manifold |\n");
  std::printf("|---|---:|---:|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  std::fflush(stdout);
  for (const auto& [name, mesh] : meshes) {
    const double diag = bounding_box(mesh).diagonal();
    const TriangleSoup input = weld(triangle_soup(mesh));
    const Mesh plain = mesh_from_soup(input);
    const size_t input_non_manifold = count_non_manifold(input);
    if (input_non_manifold > 0) std::fprintf(stderr, "meshreduce_peers: %s has %zu non-manifold triangles\n", name.c_str(), input_non_manifold);
    const fs::path obj = work / "input.obj", off = work / "input.off";
    if (use_blender || use_meshlab) write_plain(input, obj, off);
    std::optional<double> meshlab_load;
    for (const double ratio : ratios) {
      const size_t target = static_cast<size_t>(std::llround(ratio * static_cast<double>(mesh.n_faces())));
      std::vector<Row> rows;
      for (const auto& preset : presets) {
        rows.push_back(run_meso("meso", mesh, input, target, repeat, base, preset));
        rows.push_back(run_meso("meso, no UVs", plain, input, target, repeat, base, preset));
      }
      rows.push_back(run_meshopt(input, target, repeat));
      if (use_cgal) rows.push_back(run_cgal(input, target, repeat));
      if (use_blender) rows.push_back(run_blender(blender, blender_script, obj, work, input, target, repeat));
      if (use_meshlab)
        for (const bool careful : {false, true}) rows.push_back(run_meshlab(off, work, input, target, repeat, careful, meshlab_load));
      double best_peer = INFINITY, meshopt = NAN;
      for (const Row& r : rows) {
        if (!r.ok) continue;
        if (r.method.rfind("meso", 0) != 0) best_peer = std::min(best_peer, r.d.hausdorff);
        if (r.method == "meshoptimizer") meshopt = r.seconds;
      }
      for (const Row& r : rows) {
        if (!r.ok) {
          std::printf("| %s | %zu | %zu (%.3g %%) | %s | %s | – | – | – | – | – | – | – | – | – |\n", name.c_str(), mesh.n_faces(), target,
                      100 * ratio, r.method.c_str(), r.preset.c_str());
          std::fprintf(stderr, "meshreduce_peers: %s at %zu faces: %s\n", r.method.c_str(), target, r.note.c_str());
          continue;
        }
        std::printf("| %s | %zu | %zu (%.3g %%) | %s | %s | %zu | %.3f | %.4f | %.5f | %.2f | %.2f | %zu | %zu | %zu |\n", name.c_str(),
                    mesh.n_faces(), target, 100 * ratio, r.method.c_str(), r.preset.c_str(), r.faces, r.seconds, 100 * r.d.hausdorff / diag,
                    100 * r.d.rms / diag, r.seconds / meshopt, r.d.hausdorff / best_peer, r.flipped, r.degenerate, r.non_manifold);
      }
      std::fflush(stdout);
    }
  }
  fs::remove_all(work);
  return 0;
}
