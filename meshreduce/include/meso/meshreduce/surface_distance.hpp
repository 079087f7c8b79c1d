// The geometric error between two surfaces, as meso measures it everywhere (meshreduce's
// report, its tests and bench/meshreduce_peers): approximate two-sided Hausdorff and RMS
// distance by dense sampling.
//
// Each mesh is sampled at the vertices of its non-degenerate faces plus `samples` points spread over its faces in
// proportion to area (a fixed-seed generator: the same meshes give the same figures); each
// sample's distance to the other mesh's triangles is exact up to double rounding: the
// nearest of all non-degenerate triangles, found through an Embree BVH (rtcPointQuery, a
// conservative float search) and measured in double (closest point on a triangle, Ericson,
// Real-Time Collision Detection 5.1.5). forward = max over samples of
// `a` of their distance to `b`, backward = the reverse, hausdorff = max of both; the RMS
// values are over the same samples. Like CGAL's approximate_Hausdorff_distance, the result
// is a lower bound that converges to the true distance as samples grow.
#pragma once

#include "meso/core/mesh.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace meso {

struct SurfaceDistanceOptions {
  // Points sampled on the faces of each mesh (besides its vertices); 0: twice the larger
  // face count, at least 100,000 and at most 4,000,000.
  size_t samples = 0;
  uint64_t seed = 1;
};

struct SurfaceDistance {
  double forward = 0, backward = 0, hausdorff = 0;  // object units
  double rms_forward = 0, rms_backward = 0, rms = 0;
  size_t samples_a = 0, samples_b = 0;
  double seconds = 0;
};

// Triangles as index triples into points: for peers' outputs that need not be manifold.
struct TriangleSoup {
  std::vector<Vec3f> points;
  std::vector<std::array<uint32_t, 3>> triangles;
};
TriangleSoup triangle_soup(const Mesh& mesh);  // live faces; points = the mesh's vertices

// Distances between the surfaces of `a` and `b` (typically input and reduced output).
// Meshes without a non-degenerate face give infinite distances. Multi-threaded (TBB);
// results do not depend on the thread count.
SurfaceDistance measure_surface_distance(const Mesh& a, const Mesh& b, const SurfaceDistanceOptions& options = {});
SurfaceDistance measure_surface_distance(const TriangleSoup& a, const TriangleSoup& b, const SurfaceDistanceOptions& options = {});

// The same measure with `a` fixed, for several b (meshreduce --quality best measures two
// candidates against one input): a's triangles, AABB tree and samples are made once, in the
// constructor. measure(b) returns exactly measure_surface_distance(a, b, options) (seconds
// aside: the time of measure() alone). measure() may be called from several threads at once.
class SurfaceDistanceReference {
 public:
  explicit SurfaceDistanceReference(const TriangleSoup& a, const SurfaceDistanceOptions& options = {});
  explicit SurfaceDistanceReference(const Mesh& a, const SurfaceDistanceOptions& options = {});
  ~SurfaceDistanceReference();
  SurfaceDistanceReference(const SurfaceDistanceReference&) = delete;
  SurfaceDistanceReference& operator=(const SurfaceDistanceReference&) = delete;

  SurfaceDistance measure(const TriangleSoup& b) const;
  SurfaceDistance measure(const Mesh& b) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The same measure located on the faces of `b` (typically the reduced output), in b's face
// order: per face, the largest distance of the samples attributed to it, both ways: its own
// samples (corners, centroid, and points by area as above) measured to `a`, and the samples of
// `a` whose closest point on `b` lies on it, measured to that point. Object units; 0 for a
// degenerate face. Deterministic whatever the thread count.
std::vector<double> face_distances(const Mesh& a, const Mesh& b, const SurfaceDistanceOptions& options = {});

// Where b departs from a by more than `threshold` (object units): the faces of b whose
// face_distances exceed it, grouped into edge-connected regions, largest maximum first. A
// threshold below the float resolution of b's coordinates (FLT_EPSILON times the largest
// |coordinate|) counts as that resolution: smaller distances are rounding.
struct ErrorRegion {
  size_t faces = 0;
  double max_distance = 0;  // largest face distance in the region, object units
  double area = 0;          // object units^2
  Vec3f centroid{0, 0, 0};  // area-weighted
  int first_face = 0;       // lowest face index of the region (b's face order)
};
std::vector<ErrorRegion> error_regions(const Mesh& b, const std::vector<double>& face_distance, double threshold);

}  // namespace meso
