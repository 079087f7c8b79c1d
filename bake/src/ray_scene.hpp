// Embree 3 scene over one mesh, shared by the bake and the displacement streams (internal).
#pragma once

#include "meso/core/error.hpp"
#include "meso/core/mesh.hpp"
#include "meso/core/mesh_arrays.hpp"

#include <Eigen/Dense>
#include <embree3/rtcore.h>

#include <cmath>
#include <limits>

namespace meso {

// RAII for an Embree scene over one mesh (positions copied once, with Embree's padding).
// Positions are stored relative to `origin` (computed in double): far from the object-space
// origin, float coordinates are coarse (2^-7 at 65536), and ray origins and hit distances
// computed there would be too; relative to a nearby origin they keep full precision.
class RayScene {
 public:
  RayScene(const Mesh& mesh, const Eigen::Vector3d& origin) : arrays_(flatten(mesh)) {
    for (size_t i = 0; i < arrays_.vertex_count(); ++i)
      for (int k = 0; k < 3; ++k) {
        float& c = arrays_.positions[3 * i + static_cast<size_t>(k)];
        c = static_cast<float>(static_cast<double>(c) - origin[k]);
      }
    device_ = rtcNewDevice(nullptr);
    if (!device_) throw InternalError("Embree: cannot create a device");
    scene_ = rtcNewScene(device_);
    // Robust mode: no cracks between triangles for rays through shared edges and vertices.
    rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
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
  Hit intersect(const Vec3f& org, const Vec3f& dir, float tnear, float tfar) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
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
    RTCRay ray{};
    ray.org_x = org[0];
    ray.org_y = org[1];
    ray.org_z = org[2];
    ray.dir_x = dir[0];
    ray.dir_y = dir[1];
    ray.dir_z = dir[2];
    ray.tnear = tnear;
    ray.tfar = tfar;
    ray.mask = 0xFFFFFFFFu;
    rtcOccluded1(scene_, &ctx, &ray);
    return ray.tfar < 0;  // Embree marks an occluded ray with tfar = -inf
  }
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
  MeshArrays arrays_;
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
};

}  // namespace meso
