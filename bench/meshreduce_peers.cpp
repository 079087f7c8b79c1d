// meshreduce against its peers, on the same inputs and face counts, in one run, with one
// error measure (meso::measure_surface_distance: two-sided Hausdorff and RMS by dense
// sampling, CGAL AABB tree).
//
//   build/release/bench/meshreduce_peers                       # bricks + smooth torus, 10 % and 1 %
//   build/release/bench/meshreduce_peers --ratios 0.1,0.01,0.001 --mesh high.obj --markdown
//
// Inputs: the bundled brick wall (262,144 triangles, one UV chart), a smooth analytic
// torus (262,144 triangles, UV seams along both wrap lines), and any --mesh files. Peers:
// meshoptimizer's meshopt_simplify (positions only, welded; no attributes), when built
// with libmeshoptimizer-dev. Times are wall-clock, best of --repeat runs, single thread.
#include "meso/examples/brick_wall.hpp"
#include "meso/examples/parametric.hpp"
#include "meso/formats/mesh_io.hpp"
#include "meso/meshreduce/meshreduce.hpp"
#include "meso/meshreduce/surface_distance.hpp"

#include <meshoptimizer.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

namespace {

using namespace meso;

// A torus (major radius 1, minor 0.35) with a gentle smooth wave on the tube: smooth
// everywhere, curvature varying; UV = (s, t) with seams where s and t wrap.
Mesh make_smooth_torus(int columns, int rows) {
  return make_parametric_surface(
      columns, rows,
      [](double s, double t) {
        const double u = 2 * M_PI * s, v = 2 * M_PI * t;
        const double r = 0.35 + 0.04 * std::sin(3 * u) * std::cos(2 * v);
        const double R = 1.0 + r * std::cos(v);
        return Vec3f(static_cast<float>(R * std::cos(u)), static_cast<float>(R * std::sin(u)), static_cast<float>(r * std::sin(v)));
      },
      true, true, "torus");
}

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

struct Row {
  std::string mesh, method;
  size_t input_faces = 0, target = 0, faces = 0;
  double seconds = 0;
  SurfaceDistance d;
  double diagonal = 0;
};

Row run_meso(const std::string& name, const Mesh& in, size_t target, int repeat, const ReduceOptions& base) {
  Row r;
  r.mesh = name;
  r.method = "meso";
  r.input_faces = in.n_faces();
  r.target = target;
  r.seconds = 1e30;
  Mesh out;
  for (int i = 0; i < repeat; ++i) {
    ReduceOptions o = base;
    o.target_faces = target;
    const double t0 = now();
    out = reduce_mesh(in, o);
    r.seconds = std::min(r.seconds, now() - t0);
  }
  r.faces = out.n_faces();
  r.d = measure_surface_distance(in, out);
  return r;
}

Row run_meshopt(const std::string& name, const Mesh& in, size_t target, int repeat) {
  Row r;
  r.mesh = name;
  r.method = "meshoptimizer";
  r.input_faces = in.n_faces();
  r.target = target;
  std::vector<float> positions;
  positions.reserve(in.n_vertices() * 3);
  for (auto v : in.vertices())
    for (int k = 0; k < 3; ++k) positions.push_back(in.point(v)[k]);
  std::vector<unsigned> indices;
  indices.reserve(in.n_faces() * 3);
  for (auto f : in.faces())
    for (auto h : face_halfedges(in, f)) indices.push_back(static_cast<unsigned>(in.to_vertex_handle(h).idx()));
  std::vector<unsigned> out(indices.size());
  size_t n = 0;
  r.seconds = 1e30;
  for (int i = 0; i < repeat; ++i) {
    const double t0 = now();
    n = meshopt_simplify(out.data(), indices.data(), indices.size(), positions.data(), in.n_vertices(), sizeof(float) * 3,
                         target * 3, 1.0f, 0, nullptr);
    r.seconds = std::min(r.seconds, now() - t0);
  }
  // meshoptimizer's output need not be manifold: measure it as a triangle soup.
  TriangleSoup soup;
  soup.points.assign(in.points(), in.points() + in.n_vertices());
  for (size_t i = 0; i + 2 < n; i += 3) soup.triangles.push_back({out[i], out[i + 1], out[i + 2]});
  r.faces = soup.triangles.size();
  r.d = measure_surface_distance(triangle_soup(in), soup);
  return r;
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
  std::vector<double> ratios = {0.1, 0.01};
  std::vector<std::string> files;
  int repeat = 1;
  bool builtin = true;
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
    } else {
      std::fprintf(stderr,
                   "usage: meshreduce_peers [--ratios 0.1,0.01] [--mesh FILE]... [--only-files] [--repeat N]\n"
                   "                        [--max-normal-deviation DEG] [--max-aspect-ratio R]\n");
      return 2;
    }
  }
  std::vector<std::pair<std::string, Mesh>> meshes;
  if (builtin) {
    meshes.emplace_back("bricks", make_brick_wall(BrickWallOptions{}));
    meshes.emplace_back("torus", make_smooth_torus(512, 256));
  }
  for (const auto& f : files) meshes.emplace_back(f, read_mesh(f));

  std::printf("| mesh | input faces | target | method | faces | seconds | Hausdorff %% diag | RMS %% diag | time vs meshopt | Hausdorff vs meshopt |\n");
  std::printf("|---|---:|---:|---|---:|---:|---:|---:|---:|---:|\n");
  for (const auto& [name, mesh] : meshes) {
    const double diag = bounding_box(mesh).diagonal();
    for (const double ratio : ratios) {
      const size_t target = static_cast<size_t>(std::llround(ratio * static_cast<double>(mesh.n_faces())));
      const Row mo = run_meshopt(name, mesh, target, repeat);
      const Row me = run_meso(name, mesh, target, repeat, base);
      for (const Row* r : {&me, &mo}) {
        std::printf("| %s | %zu | %zu (%.3g %%) | %s | %zu | %.3f | %.4f | %.5f | %.2f | %.2f |\n", r->mesh.c_str(), r->input_faces,
                    r->target, 100 * ratio, r->method.c_str(), r->faces, r->seconds, 100 * r->d.hausdorff / diag,
                    100 * r->d.rms / diag, r->seconds / mo.seconds, r->d.hausdorff / mo.d.hausdorff);
        std::fflush(stdout);
      }
    }
  }
  return 0;
}
