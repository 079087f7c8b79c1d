#include "meso/meshreduce/meshreduce.hpp"

#include "collapse_loop.hpp"
#include "modules.hpp"

#include <chrono>
#include <stdexcept>

namespace meso {

namespace {

// The error module checks distances at samples (input vertices, edge midpoints and three
// points per face one way; new vertices, edge midpoints and face centroids the other way).
// The distance between two triangulated surfaces can peak between samples (up to ~1.3 times
// the sampled value where an output face steps over the input's relief), so the samples
// are held to this fraction of the target.
constexpr double kErrorMargin = 0.7;

}  // namespace

Mesh reduce_mesh(const Mesh& input, const ReduceOptions& options, ReduceReport* report, Progress& progress) {
  using namespace reduce;
  const auto t0 = std::chrono::steady_clock::now();
  Mesh mesh = input;
  mesh.garbage_collection();  // counts and face indices refer to live elements only
  ReduceReport rep;
  rep.input_vertices = mesh.n_vertices();
  rep.input_faces = mesh.n_faces();
  const bool by_error = options.max_error >= 0;
  if (!(options.max_error < 0 || std::isfinite(options.max_error)))
    throw std::invalid_argument("reduce_mesh: max_error must be finite");

  if ((options.target_faces < mesh.n_faces() || by_error) && mesh.n_faces() > 0) {
    LoopOptions lo;
    lo.target_faces = options.target_faces;
    lo.has_uvs = has_uvs(mesh);
    lo.boundary_weight = options.boundary_weight;
    CollapseLoop loop(mesh, lo);
    const double diagonal = static_cast<double>(bounding_box(mesh).diagonal()) * loop.scale();
    loop.add(std::make_unique<ChartGuard>(loop, options.boundary_tolerance * diagonal, options.uv_tolerance));
    if (lo.has_uvs) loop.add(std::make_unique<UvFoldGuard>());
    loop.add(std::make_unique<NoFlip>());
    if (options.max_normal_deviation < 180.0f) loop.add(std::make_unique<NormalDeviation>(options.max_normal_deviation));
    if (options.max_aspect_ratio > 0.0f) loop.add(std::make_unique<AspectRatioGuard>(loop, options.max_aspect_ratio));
    ErrorBound* bound = nullptr;
    if (by_error) {
      auto b = std::make_unique<ErrorBound>(kErrorMargin * options.max_error * loop.scale());
      bound = b.get();
      loop.add(std::move(b));  // last: the most expensive test, and its commit follows its allow
    }
    rep.collapses = loop.run(progress);
    if (bound) rep.tracked_error = bound->tracked(loop) / loop.scale();
    rep.max_quadric_cost = loop.max_cost();
    for (const auto& m : loop.modules()) rep.rejected[m->name()] = m->rejected;
    loop.write_back();
    mesh.garbage_collection();
  }
  compute_angle_weighted_normals(mesh);

  rep.output_vertices = mesh.n_vertices();
  rep.output_faces = mesh.n_faces();
  // A face target at or above the input is met by the input itself; an error target alone
  // is met by construction.
  rep.target_reached = options.target_faces >= rep.input_faces || mesh.n_faces() <= options.target_faces ||
                       (by_error && options.target_faces == 0);
  rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (report) *report = rep;
  return mesh;
}

}  // namespace meso
