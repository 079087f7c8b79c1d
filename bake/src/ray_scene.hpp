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
#include <array>
#include <cmath>
#include <initializer_list>
#include <limits>

namespace meso {

// Meshes far from unit size are baked scaled by a power of two into the unit box, which
// every float operation carries exactly, and object-unit results are scaled back: the
// bake's tests hold a few absolute floors (a determinant above 1e-12), and Embree takes
// coordinates within 1.8e18. The exponent e brings the meshes' largest finite coordinate
// into [0.5, 1); 0 when it lies within [2^-20, 2^20] already (the meshes are used as given).
inline int unit_scale_exponent(std::initializer_list<const Mesh*> meshes) {
  float largest = 0;
  for (const Mesh* m : meshes)
    if (m)
      for (auto v : m->vertices())
        for (int k = 0; k < 3; ++k)
          if (std::isfinite(m->point(v)[k])) largest = std::max(largest, std::abs(m->point(v)[k]));
  if (!(largest > 0) || (largest >= std::ldexp(1.0f, -20) && largest <= std::ldexp(1.0f, 20))) return 0;
  return std::ilogb(largest) + 1;
}

inline Mesh scaled_mesh(const Mesh& m, float s) {
  Mesh out = m;
  for (auto v : out.vertices()) out.set_point(v, out.point(v) * s);
  return out;
}

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
    if (!deleted) pair_triangles(mesh);
    else single_quads();
    device_ = rtcNewDevice(nullptr);
    if (!device_) throw InternalError("Embree: cannot create a device");
    scene_ = rtcNewScene(device_);
    // Robust mode: no cracks between triangles for rays through shared edges and vertices.
    // Context filters (collect()) where Embree was built with filter functions; a query
    // without one (intersect(), occluded()) runs exactly as in a scene without the flag.
    filters_ = rtcGetDeviceProperty(device_, RTC_DEVICE_PROPERTY_FILTER_FUNCTION_SUPPORTED) != 0;
    streams_ = rtcGetDeviceProperty(device_, RTC_DEVICE_PROPERTY_RAY_STREAM_SUPPORTED) != 0;
    rtcSetSceneFlags(scene_, filters_ ? RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION : RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
    RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_QUAD);
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, arrays_.positions.data(), 0,
                               3 * sizeof(float), arrays_.vertex_count());
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT4, quads_.data(), 0,
                               4 * sizeof(uint32_t), quads_.size() / 4);
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
      to_triangle(rh.hit.primID, rh.hit.u, rh.hit.v, h.prim, h.u, h.v);
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
  // window)], t_min the nearest such t (a triangle may appear twice: both halves of a quad
  // hit at its diagonal can be reported as the same triangle, see to_triangle). The values
  // (t, prim, u, v) are those intersect() reports for the same triangle. False when
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
    cc.scene = this;
    cc.out = &out;
    cc.window = window;
    cc.cap = tfar;
    out.n = 0;
    out.overflow = false;
    RTCRayHit rh = ray_hit(org, dir, tnear, tfar);
    rtcIntersect1(scene_, &cc.ctx, &rh);
    return !out.overflow;
  }
  // Ray streams: m rays of neighbouring texels at once, which Embree traces as packets
  // (RTC_INTERSECT_CONTEXT_FLAG_COHERENT: its packet kernels, 16 rays wide with AVX-512).
  // rays[j].ray.id must be j. collect_coherent() is collect() for each: out[j] gets ray j's
  // candidates over its [tnear, tfar] and windows[j], and its return value (false on
  // overflow) is !out[j].overflow; occluded_coherent() sets hit[j] to occluded() of ray j.
  // The traversal order differs from the single-ray queries', which changes nothing (collect
  // reports every candidate within its window whatever the order), but Embree's packet
  // kernels may round a hit's t, u, v differently in the last bits from its single-ray ones.
  // Call them only where streams() holds, collect_coherent() only where filters() does too.
  static constexpr unsigned kMaxStream = 64;
  void collect_coherent(RTCRayHit* rays, unsigned m, const float* windows, Candidates* out) const {
    StreamContext sc;
    rtcInitIntersectContext(&sc.ctx);
    sc.ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    sc.ctx.filter = &StreamContext::filter;
    sc.scene = this;
    sc.out = out;
    sc.windows = windows;
    for (unsigned j = 0; j < m; ++j) {
      out[j].n = 0;
      out[j].overflow = false;
      sc.caps[j] = rays[j].ray.tfar;
    }
    rtcIntersect1M(scene_, &sc.ctx, rays, m, sizeof(RTCRayHit));
  }
  void occluded_coherent(RTCRay* rays, unsigned m, bool* hit) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    rtcOccluded1M(scene_, &ctx, rays, m, sizeof(RTCRay));
    for (unsigned j = 0; j < m; ++j) hit[j] = rays[j].tfar < 0;
  }
  // Embree primitives: the mesh's triangles paired into quads (see Pair).
  size_t quad_count() const { return pairs_.size(); }
  // Whether collect() can run (else it returns false at once, casting nothing).
  bool filters() const { return filters_; }
  // Whether Embree was built with ray streams (rtcIntersect1M), for the *_coherent queries.
  bool streams() const { return streams_; }
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
  // Both filters' work for lane i of a hit: the candidate recorded (or the overflow noted),
  // the ray's cap lowered to the nearest candidate's t + window, and the ray's far end set
  // to it (never below this hit's t, where Embree put it).
  void record(const RTCFilterFunctionNArguments* args, unsigned i, Candidates& c, float& cap, float window) const {
    const float t = RTCRayN_tfar(args->ray, args->N, i);
    if (c.n < kMaxCandidates) {
      Candidate& h = c.hit[c.n++];
      h.t = t;
      to_triangle(RTCHitN_primID(args->hit, args->N, i), RTCHitN_u(args->hit, args->N, i), RTCHitN_v(args->hit, args->N, i), h.prim,
                  h.u, h.v);
    } else {
      c.overflow = true;
    }
    cap = std::min(cap, t + window);
    RTCRayN_tfar(args->ray, args->N, i) = std::max(cap, t);
  }

  // The context of collect(): Embree hands the filter the intersect context it was given.
  // The filter records the candidate and accepts it, then widens the ray's far end from the
  // candidate's t (where Embree put it) to the nearest candidate's t + window: the traversal
  // goes on over that span and no further. (Embree's intersectors re-read tfar after an
  // accepting filter: "intersection filters may modify tfar value".)
  struct CollectContext {
    RTCIntersectContext ctx;  // first: Embree passes &ctx
    const RayScene* scene = nullptr;
    Candidates* out = nullptr;
    float window = 0, cap = 0;
    static void filter(const RTCFilterFunctionNArguments* args) {
      auto* self = reinterpret_cast<CollectContext*>(args->context);
      for (unsigned i = 0; i < args->N; ++i)
        if (args->valid[i] != 0) self->scene->record(args, i, *self->out, self->cap, self->window);
    }
  };

  // collect_coherent()'s context: CollectContext's filter per ray of the stream, told apart
  // by their ids (Embree hands the filter its own packets of the stream's rays, N lanes).
  struct StreamContext {
    RTCIntersectContext ctx;  // first: Embree passes &ctx
    const RayScene* scene = nullptr;
    Candidates* out = nullptr;
    const float* windows = nullptr;
    float caps[kMaxStream];
    static void filter(const RTCFilterFunctionNArguments* args) {
      auto* self = reinterpret_cast<StreamContext*>(args->context);
      for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] == 0) continue;
        const unsigned j = RTCRayN_id(args->ray, args->N, i);
        self->scene->record(args, i, self->out[j], self->caps[j], self->windows[j]);
      }
    }
  };

  // Triangles paired into quads (Embree's quad leaves hold twice the triangles of its
  // triangle leaves, and the BVH over half the primitives is shallower and builds faster).
  // Quad q = (v0, v1, v2, v3) is Embree's pair of triangles (v0, v1, v3) and (v2, v3, v1),
  // the mesh's triangles pairs_[q].tri[0] and tri[1] (tri[1] = tri[0] for a triangle left
  // single, stored as (v0, v1, v2, v2): its second triangle is degenerate, never hit).
  // rot[k]: the position, in the triangle's stored corner order, of the quad corner its
  // weights start from (v0 for the first triangle, v2 for the second).
  struct Pair {
    uint32_t tri[2];
    uint8_t rot[2];
  };
  // Embree's hit on quad q at (u, v) as the triangle's hit: its index and its barycentrics
  // (1 - u - v) t0 + u t1 + v t2 over its stored corners. Embree's quad coordinates span
  // the quad: (0,0) = v0, (1,0) = v1, (1,1) = v2, (0,1) = v3; on the first triangle
  // p = v0 + u (v1 - v0) + v (v3 - v0), u + v <= 1, and on the second
  // p = v2 + (1 - u)(v3 - v2) + (1 - v)(v1 - v2), u + v >= 1 (Embree 3.13's quad
  // intersectors, Pluecker in robust mode). Embree does not say which half it hit, and its
  // u, v are rounded (an approximate reciprocal, edge tests with a tolerance): a hit within
  // ~1e-7 of the diagonal may be given to the other half, with weights within ~1e-7 of
  // [0, 1] and the same point, as Embree itself picks either triangle at a shared edge.
  void to_triangle(uint32_t q, float u, float v, uint32_t& prim, float& tu, float& tv) const {
    const Pair& p = pairs_[q];
    float w[3];  // weights of the triangle's corners, from its quad start corner on
    int k;
    if (u + v <= 1.0f || p.tri[1] == p.tri[0]) {
      k = 0;
      w[0] = 1.0f - u - v;
      w[1] = u;
      w[2] = v;
    } else {
      k = 1;
      w[0] = u + v - 1.0f;
      w[1] = 1.0f - u;
      w[2] = 1.0f - v;
    }
    prim = p.tri[k];
    const int r = p.rot[k];
    // Stored corner c has weight w[(c - r) mod 3].
    tu = w[(4 - r) % 3];
    tv = w[(5 - r) % 3];
  }
  void single_quads() {
    const size_t nt = arrays_.triangle_count();
    quads_.resize(4 * nt);
    pairs_.resize(nt);
    for (size_t f = 0; f < nt; ++f) {
      const uint32_t* t = &arrays_.triangles[3 * f];
      uint32_t* q = &quads_[4 * f];
      q[0] = t[0], q[1] = t[1], q[2] = t[2], q[3] = t[2];
      // (v0, v1, v3) = (t0, t1, t2): starts at stored corner 0.
      pairs_[f] = Pair{{static_cast<uint32_t>(f), static_cast<uint32_t>(f)}, {0, 0}};
    }
  }
  // Each face's preferred partner: its neighbour across its longest edge (a grid's
  // diagonal: compact quads); faces that prefer each other pair (in parallel), then the
  // rest greedily in face order with any unpaired neighbour. Deterministic: no step depends
  // on the thread count. (OpenMesh's faces are consistently oriented and have three distinct
  // vertices, so a neighbour holds the shared edge the other way round.)
  void pair_triangles(const Mesh& mesh) {
    const size_t nt = arrays_.triangle_count();
    constexpr uint32_t kNone = ~0u;
    // partner[f]: the face f pairs with; edge[f]: the corner k of f whose halfedge (from
    // corner k-1 to corner k) it shares with its partner.
    std::vector<uint32_t> partner(nt, kNone), pref(nt, kNone);
    std::vector<uint8_t> edge(nt, 0), pref_edge(nt, 0);
    auto neighbour = [&](HalfedgeHandle h) {
      const FaceHandle g = mesh.opposite_face_handle(h);
      return g.is_valid() ? static_cast<uint32_t>(g.idx()) : kNone;
    };
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nt, 4096), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t f = r.begin(); f < r.end(); ++f) {
        const auto hs = face_halfedges(mesh, FaceHandle(static_cast<int>(f)));
        const uint32_t* t = &arrays_.triangles[3 * f];
        const float* p[3] = {&arrays_.positions[3 * size_t{t[0]}], &arrays_.positions[3 * size_t{t[1]}], &arrays_.positions[3 * size_t{t[2]}]};
        float best_len = -1;
        for (size_t k = 0, prev = 2; k < 3; prev = k++) {
          const uint32_t g = neighbour(hs[k]);
          const float dx = p[k][0] - p[prev][0], dy = p[k][1] - p[prev][1], dz = p[k][2] - p[prev][2];
          const float len = dx * dx + dy * dy + dz * dz;
          if (g != kNone && g != f && len > best_len) pref[f] = g, pref_edge[f] = static_cast<uint8_t>(k), best_len = len;
        }
      }
    });
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nt, 4096), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t f = r.begin(); f < r.end(); ++f)
        if (pref[f] != kNone && pref[pref[f]] == f) partner[f] = pref[f], edge[f] = pref_edge[f];
    });
    for (size_t f = 0; f < nt; ++f) {
      if (partner[f] != kNone || pref[f] == kNone) continue;
      const auto hs = face_halfedges(mesh, FaceHandle(static_cast<int>(f)));
      for (size_t k = 0; k < 3; ++k) {
        const uint32_t g = neighbour(hs[k]);
        if (g == kNone || g == f || partner[g] != kNone) continue;
        partner[f] = g, edge[f] = static_cast<uint8_t>(k);
        partner[g] = static_cast<uint32_t>(f);  // its edge is not needed: f comes first
        break;
      }
    }
    size_t nq = 0;
    for (size_t f = 0; f < nt; ++f) nq += partner[f] == kNone || partner[f] > f;
    quads_.resize(4 * nq);
    pairs_.resize(nq);
    for (size_t f = 0, q = 0; f < nt; ++f) {
      const uint32_t* t = &arrays_.triangles[3 * f];
      const uint32_t g = partner[f];
      uint32_t* out = &quads_[4 * q];
      if (g == kNone) {
        out[0] = t[0], out[1] = t[1], out[2] = t[2], out[3] = t[2];
        pairs_[q++] = Pair{{static_cast<uint32_t>(f), static_cast<uint32_t>(f)}, {0, 0}};
        continue;
      }
      if (g < f) continue;  // emitted with its partner
      // f = (a, b, c) from corner k+1 on, the shared edge b -> c; the partner holds c -> b
      // and its third corner d: quad (a, b, d, c), triangles (a, b, c) and (d, c, b).
      const int k = edge[f], ka = k == 2 ? 0 : k + 1, kb = k == 0 ? 2 : k - 1;
      const uint32_t b = t[kb], c = t[k];
      const uint32_t* s = &arrays_.triangles[3 * size_t{g}];
      const uint8_t kd = s[0] != b && s[0] != c ? 0 : s[1] != b && s[1] != c ? 1 : 2;
      out[0] = t[ka], out[1] = b, out[2] = s[kd], out[3] = c;
      pairs_[q++] = Pair{{static_cast<uint32_t>(f), g}, {static_cast<uint8_t>(ka), kd}};
    }
  }

  MeshArrays arrays_;
  std::vector<uint32_t> quads_;
  std::vector<Pair> pairs_;
  bool filters_ = false;
  bool streams_ = false;
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
};

}  // namespace meso
