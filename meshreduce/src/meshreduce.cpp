#include "meso/meshreduce/meshreduce.hpp"
#include "meso/meshreduce/progressive.hpp"
#include "meso/meshreduce/surface_distance.hpp"

#include "collapse_loop.hpp"
#include "halfedge_collapse.hpp"
#include "modules.hpp"
#include "surface_fit.hpp"

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

namespace meso {

namespace {

// The error module checks distances at samples (input vertices, edge midpoints and three
// points per face one way; new vertices, edge midpoints and face centroids the other way).
// The distance between two triangulated surfaces can peak between samples (up to ~1.3 times
// the sampled value where an output face steps over the input's relief), so the samples
// are held to this fraction of the target.
constexpr double kErrorMargin = 0.7;

// The largest output best's surface fit runs on (see reduce_mesh).
constexpr size_t kMaxFitFaces = 200000;

// The input as a progressive record stores it: live vertices in order, faces in order with
// their corner order (corner 0 = to-vertex of the face's halfedge), corner UVs, groups.
void capture_input(const Mesh& mesh, ProgressiveMesh& pm) {
  pm = ProgressiveMesh();
  std::vector<uint32_t> index(mesh.n_vertices(), 0);
  for (auto v : mesh.vertices()) {
    index[static_cast<size_t>(v.idx())] = static_cast<uint32_t>(pm.positions.size());
    pm.positions.push_back(mesh.point(v));
  }
  pm.has_uvs = has_uvs(mesh);
  pm.group_names = group_names(mesh);
  for (auto f : mesh.faces()) {
    for (auto h : face_halfedges(mesh, f)) {
      pm.corners.push_back(index[static_cast<size_t>(mesh.to_vertex_handle(h).idx())]);
      if (pm.has_uvs) pm.corner_uvs.push_back(mesh.texcoord2D(h));
    }
    pm.face_groups.push_back(static_cast<uint32_t>(std::max(0, face_group(mesh, f))));
  }
  pm.final_faces = pm.input_faces();
}

bool has_garbage(const Mesh& mesh) {
  bool garbage = false;
  for (auto v : mesh.all_vertices()) garbage |= mesh.status(v).deleted();
  for (auto e : mesh.all_edges()) garbage |= mesh.status(e).deleted();
  for (auto f : mesh.all_faces()) garbage |= mesh.status(f).deleted();
  return garbage;
}

// Per vertex: whether a lock holds it.
std::vector<uint8_t> boundary_vertices(const Mesh& mesh) {
  std::vector<uint8_t> locked(mesh.n_vertices(), 0);
  for (auto v : mesh.vertices()) locked[static_cast<size_t>(v.idx())] = mesh.is_boundary(v);
  return locked;
}

std::vector<uint8_t> group_vertices(const Mesh& mesh, const std::vector<std::string>& groups) {
  const auto& names = group_names(mesh);
  std::vector<uint8_t> match(names.size(), 0);
  for (size_t g = 0; g < names.size(); ++g) match[g] = std::find(groups.begin(), groups.end(), names[g]) != groups.end();
  std::vector<uint8_t> locked(mesh.n_vertices(), 0);
  for (auto f : mesh.faces()) {
    const int g = face_group(mesh, f);
    if (g < 0 || static_cast<size_t>(g) >= match.size() || !match[static_cast<size_t>(g)]) continue;
    for (auto v : mesh.fv_range(f)) locked[static_cast<size_t>(v.idx())] = 1;
  }
  return locked;
}

// The output vertices the surface fit must leave where they are: those on a boundary (the
// outline itself, which the fit's one-sided input samples would pull inward) and the locked
// ones. Vertices on UV seams move: a seam vertex is one position shared by the faces on both
// sides, each corner keeping its own UV, so a move neither tears nor folds a chart; the seam
// moves with the surface as interior vertices do, tethered to within seam_tolerance of where
// the reduction left it, on the input's seam (uv_seam_vertices; untethered, a 100-face torus's
// seam vertices moved 4.6 % of the diagonal off it). Held fixed they kept the seamed torus at
// 1.21x and 1.33x the best peer's Hausdorff distance at 1 % and 0.1 % (free: 0.94x and
// 1.08x; docs/benchmarks.md).
std::vector<uint8_t> fit_fixed_vertices(const Mesh& mesh, const ReduceOptions& options) {
  std::vector<uint8_t> fixed = boundary_vertices(mesh);
  if (!options.lock_groups.empty()) {
    const auto locked = group_vertices(mesh, options.lock_groups);
    for (size_t i = 0; i < fixed.size(); ++i) fixed[i] |= locked[i];
  }
  return fixed;
}

// One reduction with the given face-plane weighting (LoopOptions::uniform_planes): every
// new face within the `strict` balls is tested against the input (NoFlip), and `flipped`
// receives the output faces that the bench would count as flipped.
Mesh reduce_once(const Mesh& input, const ReduceOptions& options, bool uniform_planes, int pass, ReduceReport* report, Progress& progress,
                 ProgressiveMesh* progressive, reduce::InputSurface* surface, const std::vector<reduce::FlipBall>& strict,
                 std::vector<reduce::FlipBall>& flipped) {
  using namespace reduce;
  const auto t0 = std::chrono::steady_clock::now();
  flipped.clear();
  Mesh mesh;
  if (progressive) {
    // The collapses refer to halfedges: reduce the mesh the replay will rebuild. Compaction
    // reorders (OpenMesh swaps the last live element into each hole): capture after it.
    if (has_garbage(input)) {
      Mesh live = input;
      reduce::compact(live);
      capture_input(live, *progressive);
    } else {
      capture_input(input, *progressive);
    }
    mesh = progressive_base_input(*progressive);
  } else {
    mesh = input;
  }
  // Counts and face indices refer to live elements only. OpenMesh's garbage_collection maps
  // every handle even when nothing is deleted (and is a tenth of the reduction in Debian's
  // assertion-enabled build): only call it when there is garbage. Without deleted elements
  // its maps are the identity, so skipping it changes nothing.
  if (has_garbage(mesh)) compact(mesh);
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
    lo.seam_weight = options.seam_weight;
    lo.lazy = options.quality == ReduceQuality::fast;
    lo.uniform_planes = uniform_planes;
    if (pass > 1) lo.label = "meshreduce, pass " + std::to_string(pass);
    CollapseLoop loop(mesh, lo);
    if (progressive) loop.record(progressive);
    // Locks first: the cheapest test, and the one that explains a target out of reach.
    std::vector<uint8_t> pinned(mesh.n_vertices(), 0);
    auto lock = [&](const char* name, std::vector<uint8_t> locked) {
      for (size_t i = 0; i < locked.size(); ++i) pinned[i] |= locked[i];
      loop.add(std::make_unique<VertexLock>(name, std::move(locked)));
    };
    if (options.lock_boundary) lock("lock_boundary", boundary_vertices(mesh));
    if (!options.lock_groups.empty()) lock("lock_group", group_vertices(mesh, options.lock_groups));
    rep.locked_vertices = static_cast<size_t>(std::count(pinned.begin(), pinned.end(), uint8_t{1}));
    const double diagonal = bounding_box(mesh).diagonal() * loop.scale();
    loop.add(std::make_unique<ChartGuard>(loop, options.boundary_tolerance * diagonal, options.seam_tolerance * diagonal,
                                          options.uv_tolerance));
    if (lo.has_uvs) loop.add(std::make_unique<UvFoldGuard>());
    auto no_flip = std::make_unique<NoFlip>(surface, strict);
    NoFlip& flips = *no_flip;
    loop.add(std::move(no_flip));
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
    flipped = flips.flipped_faces(loop);
    loop.write_back();
    compact(mesh);
  }
  if (progressive) progressive->final_faces = mesh.n_faces();
  clear_boundary_uvs(mesh);
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

// Passes of a reduction at most: the first, then one more per pass that left flipped faces.
constexpr int kMaxPasses = 6;

// reduce_once, again while it leaves flipped faces, each pass testing every new face around
// the flipped faces of all passes before it (NoFlip's strict balls). The report's time
// covers all passes.
Mesh reduce_without_flips(const Mesh& input, const ReduceOptions& options, bool uniform_planes, ReduceReport* report, Progress& progress,
                          ProgressiveMesh* progressive, reduce::InputSurface& surface) {
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<reduce::FlipBall> strict, flipped;
  ReduceReport rep;
  Mesh out;
  for (int pass = 1;; ++pass) {
    out = reduce_once(input, options, uniform_planes, pass, &rep, progress, progressive, &surface, strict, flipped);
    rep.passes = pass;
    rep.flipped_faces = flipped.size();
    if (flipped.empty() || pass == kMaxPasses) break;
    strict.insert(strict.end(), flipped.begin(), flipped.end());
  }
  rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (report) *report = rep;
  return out;
}

}  // namespace

Mesh reduce_mesh(const Mesh& input, const ReduceOptions& options, ReduceReport* report, Progress& progress,
                 ProgressiveMesh* progressive) {
  if (options.quality != ReduceQuality::best) {
    reduce::InputSurface surface;
    return reduce_without_flips(input, options, false, report, progress, progressive, surface);
  }
  // best: both weightings, then the output nearer the input by the measure meso reports.
  const auto t0 = std::chrono::steady_clock::now();
  ReduceReport reports[2];
  ProgressiveMesh records[2];
  Mesh outputs[2];
  // The two reductions are independent (each deterministic, the input only read), and so
  // are the input's side of the measure (its triangles, BVH and samples) and of the surface
  // fit: the four run as parallel tasks, and the measure's set-up is shared. The bar follows
  // the first reduction; the second reports to no one.
  const bool fit = !progressive && options.max_normal_deviation >= 180.0f;
  std::unique_ptr<SurfaceDistanceReference> reference;
  std::unique_ptr<reduce::SurfaceFitTarget> target;
  reduce::InputSurface surface;  // the flip guard's, shared by the two reductions
  tbb::parallel_invoke(
      [&] { outputs[0] = reduce_without_flips(input, options, false, &reports[0], progress, progressive ? &records[0] : nullptr, surface); },
      [&] { outputs[1] = reduce_without_flips(input, options, true, &reports[1], null_progress(), progressive ? &records[1] : nullptr, surface); },
      [&] { reference = std::make_unique<SurfaceDistanceReference>(input); },
      [&] {
        if (fit) target = std::make_unique<reduce::SurfaceFitTarget>(input);
      });
  // Each candidate measured and, unless the record forbids it, fitted (surface_fit.hpp) and
  // measured again. The fit lowers the RMS distance nearly always, the
  // Hausdorff distance usually but not always, and not always most on the candidate that
  // was nearer before it (docs/benchmarks.md): the nearest of the four is kept (ties: the
  // unfitted one, then area).
  SurfaceDistance distance[2], fit_distance[2];
  Mesh fitted[2];
  reduce::SurfaceFitReport fit_reports[2];
  auto candidate = [&](int k) {
    distance[k] = reference->measure(outputs[k]);
    // Nothing reduced (a target at or above the input): nothing to fit. Above
    // kMaxFitFaces output faces the fit's time and memory outgrow its gain, which is at
    // coarse levels (a 2M-face wall halved: +73 s and +1.2 GB, for a distance of 0.0007 % of
    // the diagonal; at 105k faces: +11 s, +0.4 GB; docs/benchmarks.md).
    if (!fit || reports[k].collapses == 0 || outputs[k].n_faces() > kMaxFitFaces) {
      fit_distance[k].hausdorff = std::numeric_limits<double>::infinity();
      return;
    }
    fitted[k] = outputs[k];
    reduce::SurfaceFitOptions fo;
    fo.max_aspect_ratio = options.max_aspect_ratio;
    fo.tethered = uv_seam_vertices(fitted[k]);
    fo.tether = static_cast<double>(options.seam_tolerance) * bounding_box(input).diagonal();
    fit_reports[k] = reduce::fit_to_surface(fitted[k], *target, fit_fixed_vertices(fitted[k], options), fo);
    fit_distance[k] = reference->measure(fitted[k]);
  };
  // One after the other: each measure and fit is parallel inside, and two fits at once
  // would double the fit's working memory (about 1.2 GB per million output faces).
  candidate(0);
  candidate(1);
  int pick = distance[1].hausdorff < distance[0].hausdorff ? 1 : 0;
  bool use_fit = false;
  for (int k = 0; k < 2 && fit; ++k)
    if (fit_distance[k].hausdorff < (use_fit ? fit_distance[pick] : distance[pick]).hausdorff) pick = k, use_fit = true;
  ReduceReport rep = reports[pick];
  rep.planes = pick == 1 ? "uniform" : "area";
  rep.candidate_hausdorff = {distance[0].hausdorff, distance[1].hausdorff};
  if (fit && std::isfinite(fit_distance[0].hausdorff) && std::isfinite(fit_distance[1].hausdorff))
    rep.fitted_hausdorff = {fit_distance[0].hausdorff, fit_distance[1].hausdorff};
  rep.fitted = use_fit;
  rep.distance = use_fit ? fit_distance[pick] : distance[pick];
  if (use_fit) {
    outputs[pick] = std::move(fitted[pick]);
    rep.tracked_error = -1;
    rep.flipped_faces = fit_reports[pick].facing_away;
  }
  rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (report) *report = rep;
  if (progressive) *progressive = std::move(records[pick]);
  return std::move(outputs[pick]);
}

}  // namespace meso
