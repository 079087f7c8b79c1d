#include "meso/meshreduce/meshreduce.hpp"

#include "mod_chart_guard.hpp"

#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModNormalFlippingT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>
#include <OpenMesh/Tools/Decimater/Observer.hh>

#include <chrono>

namespace meso {

namespace {

class ProgressObserver : public OpenMesh::Decimater::Observer {
 public:
  ProgressObserver(Progress& p, size_t interval) : Observer(interval), progress_(p), interval_(interval) {}
  void notify(size_t) override { progress_.advance(interval_); }

 private:
  Progress& progress_;
  size_t interval_;
};

}  // namespace

Mesh reduce_mesh(const Mesh& input, const ReduceOptions& options, ReduceReport* report, Progress& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  Mesh mesh = input;
  mesh.garbage_collection();  // counts and face indices refer to live elements only
  ReduceReport rep;
  rep.input_vertices = mesh.n_vertices();
  rep.input_faces = mesh.n_faces();

  if (options.target_faces < mesh.n_faces()) {
    mesh.request_face_normals();
    mesh.update_face_normals();

    using Decimater = OpenMesh::Decimater::DecimaterT<Mesh>;
    Decimater dec(mesh);
    OpenMesh::Decimater::ModQuadricT<Mesh>::Handle quadric;
    OpenMesh::Decimater::ModNormalFlippingT<Mesh>::Handle no_flip;
    ModChartGuardT<Mesh>::Handle guard;
    dec.add(quadric);
    dec.add(no_flip);
    dec.add(guard);
    dec.module(quadric).unset_max_err();
    dec.module(guard).set_tolerances(options.boundary_tolerance * bounding_box(mesh).diagonal(), options.uv_tolerance);
    if (!dec.initialize()) throw std::logic_error("meshreduce: decimater modules failed to initialise");

    const size_t wanted = mesh.n_faces() - options.target_faces;
    // Each collapse removes two faces (one on a boundary).
    const size_t interval = std::max<size_t>(1, wanted / 200);
    ProgressObserver observer(progress, interval);
    dec.set_observer(&observer);
    progress.begin("meshreduce", wanted / 2 + 1);
    rep.collapses = dec.decimate_to_faces(0, options.target_faces);
    progress.end();
    dec.set_observer(nullptr);
    mesh.garbage_collection();
    mesh.release_face_normals();
  }
  compute_angle_weighted_normals(mesh);

  rep.output_vertices = mesh.n_vertices();
  rep.output_faces = mesh.n_faces();
  // A target at or above the input is met by the input itself.
  rep.target_reached = options.target_faces >= rep.input_faces || mesh.n_faces() <= options.target_faces;
  rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (report) *report = rep;
  return mesh;
}

}  // namespace meso
