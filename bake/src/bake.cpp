#include "meso/bake/bake.hpp"

#include "meso/bake/dilate.hpp"
#include "meso/bake/tangent_frame.hpp"
#include "meso/bake/uv_raster.hpp"
#include "pn_triangle.hpp"
#include "ray_scene.hpp"
#include "meso/core/error.hpp"
#include "meso/core/mesh_arrays.hpp"

#include <Eigen/Dense>
#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <limits>
#include <memory>

namespace meso {

namespace {

// A hit along a texel's ray: signed distance from the base surface (positive outward),
// whether the high surface faces the way the base does, and where on the high mesh.
struct RayHit {
  float d = 0;
  bool front = true;
  uint32_t prim = 0;
  float u = 0, v = 0;
};

// tbn.inverse() * h for a 3 x 3 matrix, with the same operations in the same order as
// Eigen 3.4 evaluates that expression (so the same bits, checked on 3e7 random matrices and
// by the bake's output hash): the inverse from the cofactors and 1 / det, det from the first
// column's cofactors; product rows 0 and 1 summed (x0 + x1) + x2 (Eigen's packet path),
// row 2 x0 + (x1 + x2) (its scalar tail). Without the temporaries of the expression template,
// which cost more than the arithmetic. (Checked with the project's flags: x86-64 baseline, no
// FMA contraction; a build that contracts either side may round differently, as Eigen itself
// would across such builds.)
Eigen::Vector3d inverse_times(const Eigen::Matrix3d& m, const Eigen::Vector3d& h) {
  auto cofactor = [&m](int i, int j) {
    const int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
    return m(i1, j1) * m(i2, j2) - m(i1, j2) * m(i2, j1);
  };
  const double c00 = cofactor(0, 0), c10 = cofactor(1, 0), c20 = cofactor(2, 0);
  const double invdet = 1.0 / ((c00 * m(0, 0) + c10 * m(1, 0)) + c20 * m(2, 0));
  const double r0[3] = {c00 * invdet, c10 * invdet, c20 * invdet};
  const double r1[3] = {cofactor(0, 1) * invdet, cofactor(1, 1) * invdet, cofactor(2, 1) * invdet};
  const double r2[3] = {cofactor(0, 2) * invdet, cofactor(1, 2) * invdet, cofactor(2, 2) * invdet};
  return Eigen::Vector3d((r0[0] * h[0] + r0[1] * h[1]) + r0[2] * h[2], (r1[0] * h[0] + r1[1] * h[1]) + r1[2] * h[2],
                         r2[0] * h[0] + (r2[1] * h[1] + r2[2] * h[2]));
}

// The choice among a texel's hits (hits sorted by d). Returns the index of the hit that
// gives the value, or -1 for a miss; sets `ambiguous`.
int choose_hit(const std::vector<RayHit>& hits, HitRule rule, float bunch, bool& ambiguous) {
  ambiguous = false;
  const int n = static_cast<int>(hits.size());
  if (n == 0) return -1;
  bool any_front = false;
  for (const RayHit& h : hits) any_front |= h.front;
  if (rule == HitRule::front_only && !any_front) return -1;
  const bool fronts_only = (rule == HitRule::front_only || rule == HitRule::front_else_nearest) && any_front;
  // Bunches: maximal runs of hits closer than `bunch` to the previous one.
  // (At most 16 hits per direction: on the stack, left uninitialised: filled below.)
  std::array<int, 64> small;
  std::vector<int> large;
  int* bunch_of_data = small.data();
  if (n > static_cast<int>(small.size())) {
    large.assign(static_cast<size_t>(n), 0);
    bunch_of_data = large.data();
  }
  int* bunch_of = bunch_of_data;
  bunch_of[0] = 0;
  for (int i = 1; i < n; ++i)
    bunch_of[static_cast<size_t>(i)] = bunch_of[static_cast<size_t>(i - 1)] + (hits[static_cast<size_t>(i)].d - hits[static_cast<size_t>(i - 1)].d > bunch);
  // Score (lower is better): |d| for the nearest rules, -|d| for the furthest; outward wins
  // a tie. (The tie is its own comparison: an epsilon taken off the score, as before, vanished
  // in any |d| above 1e-14, and the inward hit, first in d order, won.)
  auto score = [&](const RayHit& h) { return (rule == HitRule::furthest ? -1.0 : 1.0) * std::abs(h.d); };
  auto better = [&](int i, int j) {
    const RayHit &a = hits[static_cast<size_t>(i)], &b = hits[static_cast<size_t>(j)];
    const double sa = score(a), sb = score(b);
    return sa < sb || (sa == sb && a.d >= 0 && b.d < 0);
  };
  int best = -1, second = -1;
  for (int i = 0; i < n; ++i) {
    if (fronts_only && !hits[static_cast<size_t>(i)].front) continue;
    if (best < 0 || better(i, best)) best = i;
  }
  for (int i = 0; i < n; ++i) {
    if ((fronts_only && !hits[static_cast<size_t>(i)].front) || bunch_of[static_cast<size_t>(i)] == bunch_of[static_cast<size_t>(best)]) continue;
    if (second < 0 || better(i, second)) second = i;
  }
  ambiguous = second >= 0 && score(hits[static_cast<size_t>(second)]) - score(hits[static_cast<size_t>(best)]) < bunch;
  // The value: the hit of the chosen bunch furthest from the base surface.
  int pick = best;
  for (int i = 0; i < n; ++i)
    if (bunch_of[static_cast<size_t>(i)] == bunch_of[static_cast<size_t>(best)] &&
        std::abs(hits[static_cast<size_t>(i)].d) > std::abs(hits[static_cast<size_t>(pick)].d))
      pick = i;
  return pick;
}

}  // namespace

bool same_topology(const Mesh& base, const Mesh& cage) {
  if (base.n_vertices() != cage.n_vertices() || base.n_faces() != cage.n_faces()) return false;
  for (auto f : base.faces()) {
    const auto a = face_halfedges(base, f), b = face_halfedges(cage, FaceHandle(f.idx()));
    for (size_t k = 0; k < 3; ++k)
      if (base.to_vertex_handle(a[k]).idx() != cage.to_vertex_handle(b[k]).idx()) return false;
  }
  return true;
}

const char* normal_y_name(NormalY y) { return y == NormalY::down ? "down" : "up"; }

const char* hit_rule_name(HitRule r) {
  switch (r) {
    case HitRule::nearest: return "nearest";
    case HitRule::furthest: return "furthest";
    case HitRule::front_else_nearest: return "front-else-nearest";
    case HitRule::front_only: return "front-only";
  }
  return "nearest";
}

namespace {
BakeResult bake_at_scale(const Mesh& low, const Mesh& high, const BakeOptions& o, Progress& progress);
}  // namespace

// Meshes far from unit size (a high mesh near 1e15 units missed every texel, one near 1e-19
// too) are baked in the unit box: unit_scale_exponent() in ray_scene.hpp.
BakeResult bake(const Mesh& low, const Mesh& high, const BakeOptions& o, Progress& progress) {
  const int e = unit_scale_exponent({&low, &high, o.cage});
  if (e == 0) return bake_at_scale(low, high, o, progress);
  const float to_unit = std::ldexp(1.0f, -e), from_unit = std::ldexp(1.0f, e);
  const Mesh l = scaled_mesh(low, to_unit), h = scaled_mesh(high, to_unit);
  const Mesh c = o.cage ? scaled_mesh(*o.cage, to_unit) : Mesh();
  BakeOptions so = o;
  so.front *= to_unit;
  so.back *= to_unit;
  so.bunch *= to_unit;
  so.detail_scale *= to_unit;
  if (o.cage) so.cage = &c;
  BakeResult r = bake_at_scale(l, h, so, progress);
  for (float& v : r.displacement.pixels) v *= from_unit;
  for (float* x : {&r.front, &r.back, &r.bunch, &r.min_displacement, &r.max_displacement}) *x *= from_unit;
  r.displacement.metadata["min"] = r.min_displacement;
  r.displacement.metadata["max"] = r.max_displacement;
  return r;
}

namespace {
BakeResult bake_at_scale(const Mesh& low, const Mesh& high, const BakeOptions& o, Progress& progress) {
  if (!has_uvs(low)) throw std::logic_error("bake: base mesh without UVs");
  BakeResult r;
  const auto high_box = bounding_box(high);  // one pass over the high mesh's vertices
  const float reach = 0.05f * high_box.diagonal();
  r.front = o.front > 0 ? o.front : reach;
  r.back = o.back > 0 ? o.back : reach;
  r.bunch = o.bunch > 0 ? o.bunch : 0.001f * high_box.diagonal();

  // Ray start offset: far below the scale of any detail, far above float rounding of
  // coordinates relative to the base's centre.
  const float eps = 1e-5f * std::max(high_box.diagonal(), bounding_box(low).diagonal());
  if (o.cage)
    for (auto v : low.vertices())
      if (!((o.cage->point(VertexHandle(v.idx())) - low.point(v)).norm() > eps)) ++r.cage_vertices_on_base;
  // Work relative to the base's centre (see RayScene).
  const Vec3f center = bounding_box(low).center();
  const Eigen::Vector3d origin(center[0], center[1], center[2]);
  // The high surfaces rays may hit: the whole high mesh, or with match_by_name one part per
  // base part. Each has its scene and its vertex normals indexed like the scene's vertices.
  struct Part {
    std::unique_ptr<RayScene> scene;
    std::vector<Vec3f> normals;
    std::vector<std::array<Vec2f, 3>> uvs;  // per scene triangle, its corners' high-mesh UVs (detail maps)
  };
  const bool want_uvs = o.detail && !o.detail->empty() && has_uvs(high);
  std::vector<Part> parts;
  std::vector<int> face_part(low.n_faces(), 0);
  auto add_part = [&](const std::vector<bool>* keep) {
    Mesh sub;
    std::vector<Vec3f> normals;
    std::vector<std::array<Vec2f, 3>> uvs;
    // The corners' UVs of high face f, in the order of the scene triangle's vertices (which
    // follow face_halfedges of the face added to the scene).
    auto corner_uvs = [&](FaceHandle f, const std::array<int, 3>& high_vertex_of_corner) {
      std::array<Vec2f, 3> out{};
      for (auto h : face_halfedges(high, f))
        for (size_t k = 0; k < 3; ++k)
          if (high.to_vertex_handle(h).idx() == high_vertex_of_corner[k]) out[k] = high.texcoord2D(h);
      return out;
    };
    if (!keep) {
      // The whole high mesh: the scene reads it directly (no copy).
      for (auto v : high.vertices()) normals.push_back(high.normal(v));
      if (want_uvs)
        for (auto f : high.faces()) {
          const auto hs = face_halfedges(high, f);
          uvs.push_back({high.texcoord2D(hs[0]), high.texcoord2D(hs[1]), high.texcoord2D(hs[2])});
        }
    } else {
      std::vector<int> map(high.n_vertices(), -1);
      std::vector<int> back;  // sub vertex -> high vertex
      for (auto f : high.faces()) {
        if (!(*keep)[static_cast<size_t>(f.idx())]) continue;
        std::vector<VertexHandle> vs;
        for (auto v : high.fv_range(f)) {
          int& m = map[static_cast<size_t>(v.idx())];
          if (m < 0) {
            m = sub.add_vertex(high.point(v)).idx();
            normals.push_back(high.normal(v));
            back.push_back(v.idx());
          }
          vs.push_back(VertexHandle(m));
        }
        FaceHandle added = sub.add_face(vs);
        if (!added.is_valid()) {  // non-manifold within the part: on its own vertices
          for (auto& h : vs) {
            const Vec3f q = sub.point(h);
            normals.push_back(normals[static_cast<size_t>(h.idx())]);
            back.push_back(back[static_cast<size_t>(h.idx())]);
            h = sub.add_vertex(q);
          }
          added = sub.add_face(vs);
        }
        if (want_uvs) {
          std::array<int, 3> corner{};
          const auto hs = face_halfedges(sub, added);
          for (size_t k = 0; k < 3; ++k) corner[k] = back[static_cast<size_t>(sub.to_vertex_handle(hs[k]).idx())];
          uvs.push_back(corner_uvs(f, corner));
        }
      }
    }
    Part part;
    part.scene = std::make_unique<RayScene>(keep ? sub : high, origin);
    part.normals = std::move(normals);
    part.uvs = std::move(uvs);
    parts.push_back(std::move(part));
    return static_cast<int>(parts.size()) - 1;
  };
  // The scenes build (Embree, in parallel itself) while this thread rasterises the UV layout
  // and prepares the maps; nothing below reads `parts` or `face_part` before the wait.
  tbb::task_group building;
  building.run([&] {
    if (!o.match_by_name) {
      add_part(nullptr);
    } else {
      auto key = [](std::string name, bool is_high) {
        std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
        const size_t dot = name.rfind('.');
        if (dot != std::string::npos && dot + 1 < name.size() &&
            std::all_of(name.begin() + static_cast<long>(dot) + 1, name.end(), [](unsigned char c) { return std::isdigit(c) != 0; }))
          name.erase(dot);
        static const std::array<const char*, 3> high_suffixes{"_high", "_hi", "_hp"}, low_suffixes{"_low", "_lo", "_lp"};
        for (const char* suffix : is_high ? high_suffixes : low_suffixes) {
          const std::string sfx(suffix);
          if (name.size() > sfx.size() && name.compare(name.size() - sfx.size(), sfx.size(), sfx) == 0) return name.substr(0, name.size() - sfx.size());
        }
        return name;
      };
      const auto& low_names = group_names(low);
      const auto& high_names = group_names(high);
      std::vector<int> low_part(low_names.size(), -1);
      int whole = -1;
      for (size_t g = 0; g < low_names.size(); ++g) {
        const std::string k = key(low_names[g], false);
        std::vector<bool> keep(high.n_faces(), false);
        bool any = false;
        for (auto f : high.faces()) {
          const int hg = face_group(high, f);
          if (hg >= 0 && static_cast<size_t>(hg) < high_names.size() && key(high_names[static_cast<size_t>(hg)], true) == k) {
            keep[static_cast<size_t>(f.idx())] = true;
            any = true;
          }
        }
        if (any) {
          low_part[g] = add_part(&keep);
          r.matched_parts.push_back(low_names[g]);
        } else {
          if (whole < 0) whole = add_part(nullptr);
          low_part[g] = whole;
          r.unmatched_parts.push_back(low_names[g]);
        }
      }
      for (auto f : low.faces()) {
        const int g = face_group(low, f);
        if (g >= 0 && static_cast<size_t>(g) < low_part.size()) {
          face_part[static_cast<size_t>(f.idx())] = low_part[static_cast<size_t>(g)];
        } else {
          if (whole < 0) whole = add_part(nullptr);
          face_part[static_cast<size_t>(f.idx())] = whole;
        }
      }
    }
  });

  const auto frames = compute_tangent_frames(low);
  const auto samples = rasterize_uv(low, o.width, o.height);
  r.displacement = Image(o.width, o.height, 1, 0.0f);
  r.normal_ts = Image(o.width, o.height, 3, 0.0f);
  r.normal_os = Image(o.width, o.height, 3, 0.0f);
  std::vector<uint8_t> written(r.displacement.texel_count(), 0);
  std::vector<uint8_t> ambiguous(r.displacement.texel_count(), 0);
  std::vector<uint8_t> covered(r.displacement.texel_count(), 0);

  progress.begin("bake", static_cast<uint64_t>(o.height));
  // One sample: the base point of `face` at barycentrics `bary` (face_halfedges order);
  // false when its rays find nothing the hit rule accepts.
  struct SampleValue {
    double disp = 0;
    Eigen::Vector3d ts, os;
    bool ambiguous = false;
  };
  // Per base face, what its texels interpolate, read from the mesh once: corner positions
  // relative to the origin (and the cage's), vertex normals, tangents, the handedness.
  struct FaceCorners {
    Eigen::Vector3d p[3], n[3], t[3], c[3];
    double sign = 1;
  };
  std::vector<FaceCorners> corners(low.n_faces());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, low.n_faces(), 256), [&](const tbb::blocked_range<size_t>& fr) {
    for (size_t fi = fr.begin(); fi < fr.end(); ++fi) {
      FaceCorners& fc = corners[fi];
      const auto hs = face_halfedges(low, FaceHandle(static_cast<int>(fi)));
      for (size_t k = 0; k < 3; ++k) {
        const auto v = low.to_vertex_handle(hs[k]);
        const Vec3f& pv = low.point(v);
        const Vec3f& nv = low.normal(v);
        const Vec3f& tv = frames[static_cast<size_t>(hs[k].idx())].tangent;
        fc.p[k] = Eigen::Vector3d(pv[0], pv[1], pv[2]) - origin;
        fc.n[k] = Eigen::Vector3d(nv[0], nv[1], nv[2]);
        fc.t[k] = Eigen::Vector3d(tv[0], tv[1], tv[2]);
      }
      fc.sign = frames[static_cast<size_t>(hs[0].idx())].sign;
      if (o.cage) {
        const auto cs = face_halfedges(*o.cage, FaceHandle(static_cast<int>(fi)));
        for (size_t k = 0; k < 3; ++k) {
          const Vec3f& cv = o.cage->point(o.cage->to_vertex_handle(cs[k]));
          fc.c[k] = Eigen::Vector3d(cv[0], cv[1], cv[2]) - origin;
        }
      }
    }
  });
  // `rays` counts the Embree queries cast (each intersect, occluded and collect is one ray),
  // for the report's rays per second.
  //
  // A sample's rays in three steps: setup() (the base point, its frame and the ray's
  // direction), gather() each way (the queries), shade() (the choice among the hits and the
  // values). trace() runs them in turn for one sample; the row loop's coherent path runs
  // each step over a run of texels, casting their first queries together as ray streams
  // (Embree's packets), and hands gather() those answers through `Answers`.
  struct SampleRay {
    const Part* part = nullptr;
    Eigen::Vector3d p, n, t, base_normal, dir;
    double sign = 1;  // the frame's handedness
    Vec3f d;
    float front_reach = 0;
  };
  // Queries already cast for a gather(): the outward collect() (with probe = inf, the
  // first query of gather(+1)) or the inward any-hit probe (the first of gather(-1) when
  // probe < tfar). Null: gather() casts its own.
  struct Answers {
    const RayScene::Candidates* collected = nullptr;  // with collect()'s return value:
    bool collect_ok = false;
    bool has_occluded = false, occluded = false;
  };
  auto setup = [&](int face, const std::array<float, 3>& bary, SampleRay& sr) -> bool {
    sr.part = &parts[static_cast<size_t>(face_part[static_cast<size_t>(face)])];
    const FaceCorners& fc = corners[static_cast<size_t>(face)];
    // Interpolated position, normal and MikkTSpace frame (unnormalised, as the shader).
    Eigen::Vector3d p = Eigen::Vector3d::Zero(), n = Eigen::Vector3d::Zero(), t = Eigen::Vector3d::Zero();
    for (size_t k = 0; k < 3; ++k) {
      const double w = bary[k];
      p += w * fc.p[k];
      n += w * fc.n[k];
      t += w * fc.t[k];
    }
    if (o.basis == BakeBasis::pn) {
      // The curved PN patch instead of the flat triangle: position and normal.
      const std::array<Eigen::Vector3d, 3> cp{fc.p[0], fc.p[1], fc.p[2]}, cn{fc.n[0], fc.n[1], fc.n[2]};
      pn_triangle(cp, cn, {bary[0], bary[1], bary[2]}, p, n);
    }
    if (!(n.norm() > 1e-12)) return false;  // opposite normals cancel: no direction to cast along
    sr.p = p;
    sr.sign = fc.sign;
    sr.n = n;
    sr.t = t;
    sr.base_normal = n.normalized();  // what "front-facing" is measured against
    sr.dir = sr.base_normal;
    sr.front_reach = r.front;
    if (o.cage) {
      // Toward the cage's point, and no further.
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (size_t k = 0; k < 3; ++k) c += bary[k] * fc.c[k];
      const Eigen::Vector3d to_cage = c - p;
      if (to_cage.norm() > eps) {
        sr.dir = to_cage.normalized();
        sr.front_reach = static_cast<float>(to_cage.norm());
      }
    }
    sr.d = Vec3f(static_cast<float>(sr.dir.x()), static_cast<float>(sr.dir.y()), static_cast<float>(sr.dir.z()));
    return true;
  };
  // Both ways from the base surface; the hit nearer to it wins (outward on a tie).
  // Each ray starts `eps` behind the base point so that a high surface lying exactly
  // on the base (high = low) is found by both, at distance 0.
  auto start_at = [&](const SampleRay& sr, double offset) {
    const Eigen::Vector3d q = sr.p + offset * sr.dir;
    return Vec3f(static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z()));
  };
  // The hits along one direction (sign +1 outward, -1 inward). Only what the rule can
  // use is traced: the nearest rules stop after the first hit's bunch (continuations
  // reach only `bunch` further, cheap rays); the others go on through the reach.
  const bool all_hits = o.hit == HitRule::furthest;
  // A hit at ray distance t of a ray that started eps behind the base point, going `way`.
  auto make_hit = [&](const SampleRay& sr, int way, float distance, uint32_t prim, float u, float v) {
    RayHit rh;
    rh.d = static_cast<float>(way) * (distance - eps);
    rh.front = sr.part->scene->face_normal(prim).dot(sr.base_normal) > 0;
    rh.prim = prim;
    rh.u = u;
    rh.v = v;
    return rh;
  };
  // The window past the nearest candidate that collect() reports (see collect_first).
  auto collect_window = [&](float tfar) { return 2.0f * r.bunch + 1e-6f * (tfar + eps); };
  // The common case in one traversal: the loop below casts for the nearest hit, then asks
  // whether anything lies within `bunch` behind it (usually nothing). collect() reports
  // every triangle the ray crosses up to a little past the nearest one's bunch, with the
  // values intersect() would give; when the nearest is unique and the rule stops at it
  // and nothing lies behind it (with a margin), the loop's answer is known: that one hit.
  // Anything else (a tie, more hits to follow, no filter support) runs the loop.
  //
  // `probe` < tfar: hits beyond `probe` cannot change the texel's value (see below), so
  // a ray to `probe` that finds nothing settles it (with or without filter support); if it
  // finds something, the whole ray.
  auto collect_first = [&](const SampleRay& sr, const Vec3f& org, const Vec3f& dir_s, int way, float tfar, float probe,
                           std::vector<RayHit>& hits, uint64_t& rays, const Answers* given) -> bool {
    if (all_hits || o.ignore_backfaces) return false;
    const RayScene& scene = *sr.part->scene;
    // Nothing within `probe` (the usual answer): an any-hit query settles it for less than
    // a closest-hit one, which must order its descent by distance.
    if (probe < tfar) {
      ++rays;
      if (!(given && given->has_occluded ? given->occluded : scene.occluded(org, dir_s, 0.0f, probe))) return true;
    }
    RayScene::Candidates own;
    const RayScene::Candidates* cands = &own;
    rays += scene.filters();
    if (given && given->collected) {
      if (!given->collect_ok) return false;
      cands = given->collected;
    } else if (!scene.collect(org, dir_s, 0.0f, tfar, collect_window(tfar), own)) {
      return false;
    }
    const RayScene::Candidates& c = *cands;
    if (c.n == 0) return true;  // intersect() misses
    int first = 0;
    for (int j = 1; j < c.n; ++j)
      if (c.hit[j].t < c.hit[first].t) first = j;
    const RayScene::Candidate& h = c.hit[first];
    for (int j = 0; j < c.n; ++j)
      if (c.hit[j].t == h.t && c.hit[j].prim != h.prim) return false;  // a tie: Embree's pick
    if (given && given->collected) {
      // A ray stream's packet kernels may round t a few units in the last place differently
      // from a single ray's: another triangle that close is a tie the single ray may order the
      // other way, so the single ray's own loop decides (the same answer as trace()).
      const float near_tie = h.t + 1e-5f * (h.t + eps);
      for (int j = 0; j < c.n; ++j)
        if (c.hit[j].prim != h.prim && c.hit[j].t <= near_tie) return false;
    }
    const RayHit rh = make_hit(sr, way, h.t, h.prim, h.u, h.v);
    if (!(o.hit == HitRule::nearest || rh.front)) return false;  // the loop goes on
    const float tnear = std::nextafter(h.t, tfar) + 1e-7f * (h.t + eps);
    const float tstop = std::min(tfar, h.t + r.bunch);
    if (tnear < tstop) {
      // The loop's any-hit query over [tnear, tstop]: must find nothing, with a margin.
      const float lo = h.t + 0.5f * (tnear - h.t), hi = tstop + 1e-6f * (tstop + eps) + 0.5f * r.bunch;
      for (int j = 0; j < c.n; ++j)
        if (c.hit[j].prim != h.prim && c.hit[j].t >= lo && c.hit[j].t <= hi) return false;
    }
    hits.push_back(rh);
    return true;
  };
  auto gather = [&](const SampleRay& sr, int way, float limit, float probe, std::vector<RayHit>& hits, uint64_t& rays,
                    const Answers* given) {
    const RayScene& scene = *sr.part->scene;
    const Vec3f org = start_at(sr, -way * eps);
    const Vec3f dir_s = way > 0 ? sr.d : -sr.d;
    if (collect_first(sr, org, dir_s, way, limit + eps, probe, hits, rays, given)) return;
    const float end = limit + eps;
    float tnear = 0.0f, tfar = end;
    bool found_front = false;
    for (int k = 0; k < 16; ++k) {
      const auto h = scene.intersect(org, dir_s, tnear, tfar);
      ++rays;
      if (!h.valid()) break;
      const RayHit rh = make_hit(sr, way, h.t, h.prim, h.u, h.v);
      // Past the hit (by a relative step that float coordinates resolve).
      tnear = std::nextafter(h.t, tfar) + 1e-7f * (h.t + eps);
      if (!(o.ignore_backfaces && !rh.front)) {
        hits.push_back(rh);
        found_front |= rh.front;
        const bool done = !all_hits && (o.hit == HitRule::nearest || found_front);
        // Only the bunch remains of interest: hits within `bunch` of the previous one, a
        // chain (choose_hit), so each hit in it moves the end on.
        if (done) tfar = std::min(end, h.t + r.bunch);
        // Usually nothing is that close behind: an any-hit query says so for less.
        rays += done && tnear < tfar;  // the occluded() query below
        if (done && (tnear >= tfar || !scene.occluded(org, dir_s, tnear, tfar))) break;
      }
      if (tnear >= tfar) break;
    }
  };
  const float no_probe = std::numeric_limits<float>::infinity();
  // When the outward ray found exactly one hit, at |d| = A, and the rule stops at it (a
  // nearest rule; front-facing unless the rule is nearest), an inward hit further than
  // A + bunch from the base can be neither the choice (it is further), nor an ambiguous
  // second (its score is more than `bunch` worse), nor in the choice's bunch (the gap to
  // it exceeds `bunch`): the inward ray need only reach A + bunch, with a margin, unless
  // it finds something there (then it goes the whole way, as before).
  auto inward_probe = [&](const std::vector<RayHit>& hits) {
    float probe = no_probe;
    if (hits.size() == 1 && !all_hits && !o.ignore_backfaces && (o.hit == HitRule::nearest || hits[0].front))
      probe = std::abs(hits[0].d) + eps + 2.0f * r.bunch + 1e-6f * (r.back + eps);
    return probe;
  };
  // The value from a sample's hits (both ways); false when the rule accepts none.
  auto shade = [&](const SampleRay& sr, std::vector<RayHit>& hits, SampleValue& value) -> bool {
    const Part& part = *sr.part;
    const RayScene& scene = *part.scene;
    const std::vector<Vec3f>& high_normals = part.normals;
    const Eigen::Vector3d& n = sr.n;
    const Eigen::Vector3d& t = sr.t;
    const Eigen::Vector3d b = sr.sign * n.cross(t);
    const Eigen::Vector3d& dir = sr.dir;
    // By d. One or two hits are the rule: std::sort's insertion sort on two swaps them when
    // the second is less, exactly as here.
    if (hits.size() == 2) {
      if (hits[1].d < hits[0].d) std::swap(hits[0], hits[1]);
    } else if (hits.size() > 2) {
      std::sort(hits.begin(), hits.end(), [](const RayHit& p1, const RayHit& p2) { return p1.d < p2.d; });
    }
    bool unsure = false;
    const int chosen = choose_hit(hits, o.hit, r.bunch, unsure);
    if (chosen < 0) return false;
    const RayHit& hit = hits[static_cast<size_t>(chosen)];
    // With a cage the ray leans toward the cage point: the value is the hit's height along the
    // base normal (a layer parallel to the base bakes to its height whatever the cage), not
    // its distance along the ray. Without one the ray is the normal: d as it is.
    const float disp = o.cage && dir != sr.base_normal ? static_cast<float>(hit.d * dir.dot(sr.base_normal)) : hit.d;
    // High normal at the hit, Embree barycentrics: (1-u-v) v0 + u v1 + v v2.
    const uint32_t* tri = &scene.arrays().triangles[3 * static_cast<size_t>(hit.prim)];
    // Component by component in float, as OpenMesh's vector operators compute it.
    const float w0 = 1.0f - hit.u - hit.v;
    const Vec3f& n0 = high_normals[tri[0]];
    const Vec3f& n1 = high_normals[tri[1]];
    const Vec3f& n2 = high_normals[tri[2]];
    const Vec3f hn((n0[0] * w0 + n1[0] * hit.u) + n2[0] * hit.v, (n0[1] * w0 + n1[1] * hit.u) + n2[1] * hit.v,
                   (n0[2] * w0 + n1[2] * hit.u) + n2[2] * hit.v);
    Eigen::Matrix3d tbn;
    tbn.col(0) = t;
    tbn.col(1) = b;
    tbn.col(2) = n;
    Eigen::Vector3d m(0, 0, 1);
    const Eigen::Vector3d hnd(hn[0], hn[1], hn[2]);
    const double det = tbn.determinant();
    if (std::abs(det) > 1e-12 && hnd.squaredNorm() > 0) {
      m = inverse_times(tbn, hnd);  // exact inverse of the decoder's matrix
      if (m.squaredNorm() > 0) m.normalize();
      else m = Eigen::Vector3d(0, 0, 1);
    }
    Eigen::Vector3d high_normal = hnd.squaredNorm() > 0 ? Eigen::Vector3d(hnd.normalized()) : dir;
    double detail_height = 0;
    if (!part.uvs.empty()) {
      // The detail bump on the high surface (course notes, "Ray-caster"): its height adds to
      // the distance, its gradient tilts the high normal. UV of the hit on the high mesh, the
      // bump tiled and bilinear, mid-grey neutral; gradient by central differences of one
      // texel, carried to 3D with the gradients of u and v over the hit triangle.
      const auto& cuv = part.uvs[static_cast<size_t>(hit.prim)];
      const double hu = (1.0 - hit.u - hit.v) * cuv[0][0] + hit.u * cuv[1][0] + hit.v * cuv[2][0];
      const double hv = (1.0 - hit.u - hit.v) * cuv[0][1] + hit.u * cuv[1][1] + hit.v * cuv[2][1];
      const Image& bump = *o.detail;
      auto sample = [&](double u, double v) {
        const double px = u * bump.width - 0.5, py = (1.0 - v) * bump.height - 0.5;
        const double x0 = std::floor(px), y0 = std::floor(py), fx = px - x0, fy = py - y0;
        auto at = [&](double x, double y) {
          const int ix = static_cast<int>(((static_cast<long long>(x) % bump.width) + bump.width) % bump.width);
          const int iy = static_cast<int>(((static_cast<long long>(y) % bump.height) + bump.height) % bump.height);
          return static_cast<double>(bump.at(ix, iy, 0));
        };
        return (at(x0, y0) * (1 - fx) + at(x0 + 1, y0) * fx) * (1 - fy) + (at(x0, y0 + 1) * (1 - fx) + at(x0 + 1, y0 + 1) * fx) * fy;
      };
      const double du = 1.0 / bump.width, dv = 1.0 / bump.height;
      detail_height = o.detail_scale * (sample(hu, hv) - 0.5);
      const double bu = o.detail_scale * (sample(hu + du, hv) - sample(hu - du, hv)) / (2 * du);
      const double bv = o.detail_scale * (sample(hu, hv + dv) - sample(hu, hv - dv)) / (2 * dv);
      const Eigen::Vector3d e1 = scene.position(tri[1]) - scene.position(tri[0]), e2 = scene.position(tri[2]) - scene.position(tri[0]);
      const Eigen::Vector3d fn = e1.cross(e2);
      if (fn.norm() > 0) {
        const Eigen::Vector3d un = fn.normalized();
        const double a1 = e1.dot(e2.cross(un)), a2 = e2.dot(un.cross(e1));
        if (std::abs(a1) > 0 && std::abs(a2) > 0) {
          const Eigen::Vector3d g1 = e2.cross(un) / a1, g2 = un.cross(e1) / a2;  // gradients of the barycentrics
          const Eigen::Vector3d grad_u = (cuv[1][0] - cuv[0][0]) * g1 + (cuv[2][0] - cuv[0][0]) * g2;
          const Eigen::Vector3d grad_v = (cuv[1][1] - cuv[0][1]) * g1 + (cuv[2][1] - cuv[0][1]) * g2;
          Eigen::Vector3d tilted = high_normal - (bu * grad_u + bv * grad_v);
          if (tilted.norm() > 0) high_normal = tilted.normalized();
        }
      }
      if (std::abs(det) > 1e-12) {
        m = inverse_times(tbn, high_normal);
        m = m.squaredNorm() > 0 ? Eigen::Vector3d(m.normalized()) : Eigen::Vector3d(0, 0, 1);
      }
    }
    value.disp = disp + detail_height;
    value.ts = m;
    value.os = high_normal;
    value.ambiguous = unsure;
    return true;
  };
  auto trace = [&](int face, const std::array<float, 3>& bary, std::vector<RayHit>& hits, SampleValue& value, uint64_t& rays) -> bool {
    SampleRay sr;
    if (!setup(face, bary, sr)) return false;
    hits.clear();
    gather(sr, +1, sr.front_reach, no_probe, hits, rays, nullptr);
    gather(sr, -1, r.back, inward_probe(hits), hits, rays, nullptr);
    return shade(sr, hits, value);
  };

  // Supersampling: n x n stratified samples per texel at the centres of its n x n sub-texels,
  // located by rasterising the UV layout at n times the resolution (a band of rows at a
  // time). A sample counts when its point lies inside a face of the texel's own chart (it
  // may be a neighbouring triangle's); a texel with none (a border texel) keeps its single
  // sample at the chart's point nearest to its centre.
  const int sub = std::max(1, static_cast<int>(std::lround(std::sqrt(static_cast<double>(std::max(1, o.samples))))));
  r.samples = sub * sub;
  std::unique_ptr<UvRasterizer> fine;
  std::vector<int> chart;
  if (sub > 1) {
    fine = std::make_unique<UvRasterizer>(low, o.width * sub, o.height * sub);
    chart = uv_charts(low);
  }

  building.wait();
  std::vector<uint64_t> row_rays(static_cast<size_t>(o.height), 0);  // summed in row order below
  std::vector<uint64_t> row_stream_rays(static_cast<size_t>(o.height), 0);
  // The coherent path (one sample per texel, one scene, a rule whose first queries are known
  // in advance): the texels of a run of up to kMaxStream in a row (fixed positions: the
  // same runs whatever the thread count) are set up, their outward collect() queries cast as
  // one ray stream, each texel's outward answer settled (with single rays where the stream's
  // answer does not settle it), their inward probes cast as one stream, then each texel
  // finished on its own (single rays where a probe finds something) and shaded. The same
  // queries as trace() casts, in another order.
  const bool coherent = o.coherent && !fine && parts.size() == 1 && parts[0].scene->filters() && parts[0].scene->streams() && !all_hits && !o.ignore_backfaces;
  constexpr unsigned kRun = RayScene::kMaxStream;
  // Texel (x, y) = i gets the mean of `count` samples.
  auto write_texel = [&](int x, int y, size_t i, const SampleValue& sum, int count, bool unsure) {
    // The box filter: mean displacement, mean normal renormalised.
    const Eigen::Vector3d ts = sum.ts.squaredNorm() > 0 ? Eigen::Vector3d(sum.ts.normalized()) : Eigen::Vector3d(0, 0, 1);
    const Eigen::Vector3d os = sum.os.squaredNorm() > 0 ? Eigen::Vector3d(sum.os.normalized()) : Eigen::Vector3d(0, 0, 1);
    r.displacement.at(x, y) = static_cast<float>(sum.disp / count);
    for (int c = 0; c < 3; ++c) {
      r.normal_ts.at(x, y, c) = static_cast<float>(ts[c]);
      r.normal_os.at(x, y, c) = static_cast<float>(os[c]);
    }
    ambiguous[i] = unsure;
    written[i] = 1;
  };
  tbb::parallel_for(tbb::blocked_range<int>(0, o.height), [&](const tbb::blocked_range<int>& rows) {
    std::vector<RayHit> hits;
    // The coherent path's run: per texel its rays, hits, answers and index.
    struct Lane {
      int x = 0;
      SampleRay sr;
      std::vector<RayHit> hits;
      Answers given;
      float probe = 0;
    };
    std::vector<Lane> lanes(coherent ? kRun : 0);
    std::vector<RayScene::Candidates> candidates(coherent ? kRun : 0);
    std::vector<RTCRayHit> outward(coherent ? kRun : 0);
    std::vector<RTCRay> inward(coherent ? kRun : 0);
    std::array<float, kRun> windows{};
    std::array<bool, kRun> occluded{};
    std::array<unsigned, kRun> inward_lane{};
    for (int y = rows.begin(); y < rows.end(); ++y) {
      uint64_t rays = 0;  // local: rows of other threads share the vector's cache lines
      uint64_t stream_rays = 0;
      if (coherent) {
        const RayScene& scene = *parts[0].scene;
        for (int x0 = 0; x0 < o.width; x0 += static_cast<int>(kRun)) {
          const int x1 = std::min(o.width, x0 + static_cast<int>(kRun));
          unsigned m = 0;
          for (int x = x0; x < x1; ++x) {
            const size_t i = static_cast<size_t>(y) * static_cast<size_t>(o.width) + static_cast<size_t>(x);
            const TexelSample& s = samples[i];
            if (s.face < 0) continue;
            covered[i] = 1;
            Lane& lane = lanes[m];
            lane.x = x;
            if (!setup(s.face, s.bary, lane.sr)) continue;
            // gather(+1)'s first query: collect() from eps behind the base point.
            const float tfar = lane.sr.front_reach + eps;
            const Vec3f from = start_at(lane.sr, -eps);
            // (A non-finite origin would spoil the culling of its whole packet; setup() lets
            // none through today. Such a ray finds nothing on its own either: a miss.)
            if (!(std::isfinite(from[0]) && std::isfinite(from[1]) && std::isfinite(from[2]))) continue;
            outward[m] = RayScene::ray_hit(from, lane.sr.d, 0.0f, tfar);
            outward[m].ray.id = m;
            windows[m] = collect_window(tfar);
            ++m;
          }
          if (m == 0) continue;
          scene.collect_coherent(outward.data(), m, windows.data(), candidates.data());
          unsigned k = 0;
          for (unsigned j = 0; j < m; ++j) {
            Lane& lane = lanes[j];
            lane.hits.clear();
            Answers given;
            given.collected = &candidates[j];
            given.collect_ok = !candidates[j].overflow;
            gather(lane.sr, +1, lane.sr.front_reach, no_probe, lane.hits, rays, &given);
            lane.probe = inward_probe(lane.hits);
            lane.given = Answers{};
            if (lane.probe < r.back + eps) {
              // gather(-1)'s first query: the any-hit probe from eps in front of the base point.
              inward[k] = RayScene::ray_hit(start_at(lane.sr, eps), -lane.sr.d, 0.0f, lane.probe).ray;
              inward[k].id = j;
              inward_lane[k++] = j;
            }
          }
          if (k > 0) scene.occluded_coherent(inward.data(), k, occluded.data());
          stream_rays += m + k;
          for (unsigned q = 0; q < k; ++q) {
            Answers& given = lanes[inward_lane[q]].given;
            given.has_occluded = true;
            given.occluded = occluded[q];
          }
          for (unsigned j = 0; j < m; ++j) {
            Lane& lane = lanes[j];
            gather(lane.sr, -1, r.back, lane.probe, lane.hits, rays, &lane.given);
            SampleValue one;
            if (!shade(lane.sr, lane.hits, one)) continue;
            write_texel(lane.x, y, static_cast<size_t>(y) * static_cast<size_t>(o.width) + static_cast<size_t>(lane.x), one, 1, one.ambiguous);
          }
        }
        row_rays[static_cast<size_t>(y)] = rays;
        row_stream_rays[static_cast<size_t>(y)] = stream_rays;
        progress.advance(1);
        continue;
      }
      std::vector<TexelSample> band;
      if (fine) band = fine->rows(y * sub, (y + 1) * sub);
      for (int x = 0; x < o.width; ++x) {
        const size_t i = static_cast<size_t>(y) * static_cast<size_t>(o.width) + static_cast<size_t>(x);
        const TexelSample& s = samples[i];
        if (s.face < 0) continue;
        covered[i] = 1;
        SampleValue sum, one;
        sum.ts = sum.os = Eigen::Vector3d::Zero();
        int count = 0;
        bool unsure = false;
        for (int b = 0; b < sub && fine; ++b)
          for (int a = 0; a < sub; ++a) {
            const TexelSample& f = band[static_cast<size_t>(b) * static_cast<size_t>(o.width * sub) + static_cast<size_t>(x * sub + a)];
            if (f.face < 0 || !f.centre_inside || chart[static_cast<size_t>(f.face)] != chart[static_cast<size_t>(s.face)]) continue;
            if (!trace(f.face, f.bary, hits, one, rays)) continue;
            sum.disp += one.disp;
            sum.ts += one.ts;
            sum.os += one.os;
            unsure |= one.ambiguous;
            ++count;
          }
        if (count == 0) {
          if (!trace(s.face, s.bary, hits, one, rays)) continue;
          sum = one;
          unsure = one.ambiguous;
          count = 1;
        }
        write_texel(x, y, i, sum, count, unsure);
      }
      row_rays[static_cast<size_t>(y)] = rays;
      progress.advance(1);
    }
  });
  progress.end();
  for (const uint64_t n : row_rays) r.rays += n;
  for (const uint64_t n : row_stream_rays) r.stream_rays += n;

  r.coverage = Image(o.width, o.height, 1, 0.0f);
  r.face_texels.assign(low.n_faces(), 0);
  r.face_misses.assign(low.n_faces(), 0);
  r.face_ambiguous.assign(low.n_faces(), 0);
  // The report, over blocks of texels in parallel, then summed block by block in order
  // (counts add up in any order; the range keeps the first of equal extremes, as one pass
  // in texel order would).
  struct Tally {
    std::vector<uint32_t> texels, misses, ambiguous;  // per face
    size_t covered = 0, hits = 0, misses_total = 0, ambiguous_total = 0;
    bool any = false, nan = false;
    float lo = 0, hi = 0;
  };
  const size_t texel_total = written.size();
  // Blocks only where texels far outnumber faces (each block counts per face).
  const size_t blocks = std::max<size_t>(1, std::min({size_t(16), texel_total / 65536, texel_total / (4 * low.n_faces() + 1)}));
  std::vector<Tally> tallies(blocks);
  tbb::parallel_for(size_t(0), blocks, [&](size_t b) {
    Tally& t = tallies[b];
    t.texels.assign(low.n_faces(), 0);
    t.misses.assign(low.n_faces(), 0);
    t.ambiguous.assign(low.n_faces(), 0);
    const size_t i0 = texel_total * b / blocks, i1 = texel_total * (b + 1) / blocks;
    for (size_t i = i0; i < i1; ++i) {
      if (!written[i]) {
        // Texels nobody wrote keep the flat answer until dilation reaches them; unwritten
        // object-space normals: the base normal would need the face; up (z) until the
        // dilation reaches them.
        r.normal_ts.pixels[3 * i + 2] = 1.0f;
        r.normal_os.pixels[3 * i + 2] = 1.0f;
      }
      t.covered += covered[i];
      if (!covered[i]) continue;
      const size_t face = static_cast<size_t>(samples[i].face);
      ++t.texels[face];
      r.coverage.pixels[i] = written[i] ? (ambiguous[i] ? 0.75f : 1.0f) : 0.5f;
      t.misses[face] += !written[i];
      t.ambiguous[face] += written[i] && ambiguous[i];
      t.ambiguous_total += written[i] && ambiguous[i];
      if (written[i]) {
        ++t.hits;
        const float d = r.displacement.pixels[i];
        t.nan |= std::isnan(d);
        if (!t.any) t.lo = t.hi = d;
        t.lo = std::min(t.lo, d);
        t.hi = std::max(t.hi, d);
        t.any = true;
      } else {
        ++t.misses_total;
      }
    }
  });
  bool first = true, nan = false;
  for (const Tally& t : tallies) {
    r.covered_texels += t.covered;
    r.hits += t.hits;
    r.misses += t.misses_total;
    r.ambiguous += t.ambiguous_total;
    for (size_t f = 0; f < t.texels.size(); ++f) {
      r.face_texels[f] += t.texels[f];
      r.face_misses[f] += t.misses[f];
      r.face_ambiguous[f] += t.ambiguous[f];
    }
    nan |= t.nan;
    if (!t.any) continue;
    if (first) r.min_displacement = r.max_displacement = t.lo;
    r.min_displacement = std::min(r.min_displacement, t.lo);
    r.max_displacement = std::max(r.max_displacement, t.hi);
    first = false;
  }
  if (nan) {
    // A NaN sticks or is skipped depending on where it comes: the one pass, exactly.
    first = true;
    for (size_t i = 0; i < texel_total; ++i) {
      if (!covered[i] || !written[i]) continue;
      const float d = r.displacement.pixels[i];
      if (first) r.min_displacement = r.max_displacement = d;
      r.min_displacement = std::min(r.min_displacement, d);
      r.max_displacement = std::max(r.max_displacement, d);
      first = false;
    }
  }
  // Every texel written (a layout that covers the map, and no misses): nothing to fill.
  if (r.hits != written.size()) {
    const auto sources = dilation_sources(written, o.width, o.height, o.dilate);
    apply_dilation(r.displacement, sources);
    apply_dilation(r.normal_ts, sources);
    apply_dilation(r.normal_os, sources);
  }

  r.displacement.metadata = {{"quantity", std::string("displacement")},
                             {"units", std::string("object")},
                             {"convention", std::string("signed distance along the base normal, positive outward")},
                             {"min", r.min_displacement},
                             {"max", r.max_displacement}};
  r.coverage.metadata = {{"quantity", std::string("coverage")},
                         {"values", std::string("1 = hit, 0.75 = ambiguous hit, 0.5 = miss (covered, nothing within reach), 0 = outside the charts")}};
  // Green down (DirectX): y negated, nothing else; the frame is MikkTSpace's either way, so
  // the flip is exact.
  const bool y_down = o.normal_y == NormalY::down;
  if (y_down)
    for (size_t i = 0; i < r.normal_ts.texel_count(); ++i) r.normal_ts.pixels[3 * i + 1] = -r.normal_ts.pixels[3 * i + 1];
  r.normal_ts.metadata = {{"quantity", std::string("normal")},
                          {"space", std::string(y_down ? "tangent (MikkTSpace frame, +y = -v: green down, DirectX)"
                                                       : "tangent (MikkTSpace frame, +y = +v: green up, OpenGL)")},
                          {"normal_y", std::string(normal_y_name(o.normal_y))}};
  r.normal_os.metadata = {{"quantity", std::string("normal")}, {"space", std::string("object")}};
  return r;
}
}  // namespace

Image encode_normal_map(const Image& normal_ts) {
  Image out = normal_ts;
  for (float& v : out.pixels) v = v * 0.5f + 0.5f;
  out.metadata["encoding"] = std::string("n * 0.5 + 0.5");
  return out;
}

}  // namespace meso
