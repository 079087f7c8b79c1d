// Embree 3 scene over one mesh, shared by the bake and the displacement streams (internal).
#pragma once

#include "meso/core/error.hpp"
#include "meso/core/mesh.hpp"
#include "meso/core/mesh_arrays.hpp"

#include <Eigen/Dense>
#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace meso {

// RAII for an Embree scene over one mesh (positions copied once, with Embree's padding).
// Positions are stored relative to `origin` (computed in double): far from the object-space
// origin, float coordinates are coarse (2^-7 at 65536), and ray origins and hit distances
// computed there would be too; relative to a nearby origin they keep full precision.
class RayScene {
 public:
  RayScene(const Mesh& mesh, const Eigen::Vector3d& origin) {
    // flatten(mesh), in parallel, with the positions moved to the origin on the way. (A
    // mesh with deleted faces, which flatten() skips: flatten() itself.)
    bool deleted = false;
    if (mesh.has_face_status())
      for (auto f : mesh.all_faces()) deleted |= mesh.status(f).deleted();
    if (deleted) arrays_ = flatten(mesh);
    const size_t nv = mesh.n_vertices(), nf = deleted ? 0 : mesh.n_faces();
    arrays_.positions.resize(nv * 3 + 1, 0.0f);
    if (!deleted) arrays_.triangles.resize(nf * 3);
    const Vec3f* points = mesh.points();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nv, 4096), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i < r.end(); ++i)
        for (int k = 0; k < 3; ++k)
          arrays_.positions[3 * i + static_cast<size_t>(k)] = static_cast<float>(static_cast<double>(points[i][k]) - origin[k]);
    });
    if (!deleted) tbb::parallel_for(tbb::blocked_range<size_t>(0, nf, 4096), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t f = r.begin(); f < r.end(); ++f) {
        const auto hs = face_halfedges(mesh, FaceHandle(static_cast<int>(f)));
        for (size_t k = 0; k < 3; ++k) arrays_.triangles[3 * f + k] = static_cast<uint32_t>(mesh.to_vertex_handle(hs[k]).idx());
      }
    });
    device_ = rtcNewDevice(nullptr);
    if (!device_) throw InternalError("Embree: cannot create a device");
    scene_ = rtcNewScene(device_);
    // Robust mode: no cracks between triangles for rays through shared edges and vertices.
    // Context filters (collect()) where Embree was built with filter functions; a query
    // without one (intersect(), occluded()) runs exactly as in a scene without the flag.
    filters_ = rtcGetDeviceProperty(device_, RTC_DEVICE_PROPERTY_FILTER_FUNCTION_SUPPORTED) != 0;
    rtcSetSceneFlags(scene_, filters_ ? RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION : RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
    RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, arrays_.positions.data(), 0,
                               3 * sizeof(float), arrays_.vertex_count());
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, arrays_.triangles.data(), 0,
                               3 * sizeof(uint32_t), arrays_.triangle_count());
    rtcCommitGeometry(geom);
    rtcAttachGeometry(scene_, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(scene_);
    if (rtcGetDeviceError(device_) != RTC_ERROR_NONE) throw InternalError("Embree: scene build failed");
  }
  ~RayScene() {
    rtcReleaseScene(scene_);
    rtcReleaseDevice(device_);
  }
  RayScene(const RayScene&) = delete;
  RayScene& operator=(const RayScene&) = delete;

  struct Hit {
    float t = std::numeric_limits<float>::infinity();
    uint32_t prim = 0;
    float u = 0, v = 0;
    bool valid() const { return std::isfinite(t); }
  };
  // A ray from org along dir over [tnear, tfar], with no hit yet.
  static RTCRayHit ray_hit(const Vec3f& org, const Vec3f& dir, float tnear, float tfar) {
    RTCRayHit rh{};
    rh.ray.org_x = org[0];
    rh.ray.org_y = org[1];
    rh.ray.org_z = org[2];
    rh.ray.dir_x = dir[0];
    rh.ray.dir_y = dir[1];
    rh.ray.dir_z = dir[2];
    rh.ray.tnear = tnear;
    rh.ray.tfar = tfar;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    return rh;
  }
  Hit intersect(const Vec3f& org, const Vec3f& dir, float tnear, float tfar) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh = ray_hit(org, dir, tnear, tfar);
    rtcIntersect1(scene_, &ctx, &rh);
    Hit h;
    if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
      h.t = rh.ray.tfar;
      h.prim = rh.hit.primID;
      h.u = rh.hit.u;
      h.v = rh.hit.v;
    }
    return h;
  }
  // Whether anything lies along the ray within [tnear, tfar] (an any-hit query: cheaper).
  bool occluded(const Vec3f& org, const Vec3f& dir, float tnear, float tfar) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay ray = ray_hit(org, dir, tnear, tfar).ray;
    rtcOccluded1(scene_, &ctx, &ray);
    return ray.tfar < 0;  // Embree marks an occluded ray with tfar = -inf
  }
  // Every candidate hit along a ray in [tnear, tfar] and a little beyond the nearest: one
  // traversal that reports each triangle the ray crosses at t in [tnear, min(tfar, t_min +
  // window)], t_min the nearest such t (a triangle may appear twice: spatial splits). The
  // values (t, prim, u, v) are those intersect() reports for the same triangle. False when
  // Embree has no filter functions or more than kMaxCandidates were found: use intersect().
  static constexpr int kMaxCandidates = 16;
  struct Candidate {  // as Hit; no initialisers: only the first n are ever written or read
    float t;
    uint32_t prim;
    float u, v;
  };
  struct Candidates {
    int n = 0;
    bool overflow = false;
    Candidate hit[kMaxCandidates];
  };
  bool collect(const Vec3f& org, const Vec3f& dir, float tnear, float tfar, float window, Candidates& out) const {
    if (!filters_) return false;
    CollectContext cc;
    rtcInitIntersectContext(&cc.ctx);
    cc.ctx.filter = &CollectContext::filter;
    cc.out = &out;
    cc.window = window;
    cc.cap = tfar;
    out.n = 0;
    out.overflow = false;
    RTCRayHit rh = ray_hit(org, dir, tnear, tfar);
    rtcIntersect1(scene_, &cc.ctx, &rh);
    return !out.overflow;
  }
  // Whether collect() can run (else it returns false at once, casting nothing).
  bool filters() const { return filters_; }
  const MeshArrays& arrays() const { return arrays_; }
  // A vertex's position relative to the scene's origin.
  Eigen::Vector3d position(uint32_t vertex) const {
    const float* c = &arrays_.positions[3 * static_cast<size_t>(vertex)];
    return Eigen::Vector3d(c[0], c[1], c[2]);
  }
  // The triangle's geometric normal, right-handed with its vertex order (unnormalised).
  Eigen::Vector3d face_normal(uint32_t prim) const {
    const uint32_t* t = &arrays_.triangles[3 * static_cast<size_t>(prim)];
    auto p = [&](int k) {
      const float* c = &arrays_.positions[3 * static_cast<size_t>(t[k])];
      return Eigen::Vector3d(c[0], c[1], c[2]);
    };
    return (p(1) - p(0)).cross(p(2) - p(0));
  }

 private:
  // The context of collect(): Embree hands the filter the intersect context it was given.
  // The filter records the candidate and accepts it, then widens the ray's far end from the
  // candidate's t (where Embree put it) to the nearest candidate's t + window: the traversal
  // goes on over that span and no further. (Embree's intersectors re-read tfar after an
  // accepting filter: "intersection filters may modify tfar value".)
  struct CollectContext {
    RTCIntersectContext ctx;  // first: Embree passes &ctx
    Candidates* out = nullptr;
    float window = 0, cap = 0;
    static void filter(const RTCFilterFunctionNArguments* args) {
      auto* self = reinterpret_cast<CollectContext*>(args->context);
      for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] == 0) continue;
        const float t = RTCRayN_tfar(args->ray, args->N, i);
        Candidates& c = *self->out;
        if (c.n < kMaxCandidates) {
          Candidate& h = c.hit[c.n++];
          h.t = t;
          h.prim = RTCHitN_primID(args->hit, args->N, i);
          h.u = RTCHitN_u(args->hit, args->N, i);
          h.v = RTCHitN_v(args->hit, args->N, i);
        } else {
          c.overflow = true;
        }
        self->cap = std::min(self->cap, t + self->window);
        RTCRayN_tfar(args->ray, args->N, i) = std::max(self->cap, t);
      }
    }
  };

  MeshArrays arrays_;
  bool filters_ = false;
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
};

}  // namespace meso
