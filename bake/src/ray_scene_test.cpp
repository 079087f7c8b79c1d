// RayScene pairs the mesh's triangles into Embree quads; its hits must still be the
// triangles' hits: the same triangle, distance and barycentrics (over the triangle's stored
// corners) as a brute-force intersection of every triangle, in double precision.
#include "ray_scene.hpp"
#include "meso/core/float_rounding.hpp"

#include "meso/examples/brick_wall.hpp"
#include "meso/examples/parametric.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <limits>
#include <random>

namespace meso {
namespace {

struct Exact {
  double t = std::numeric_limits<double>::infinity();
  uint32_t prim = 0;
  double u = 0, v = 0, edge = 0;  // edge: the smallest barycentric (distance to an edge)
  double second = std::numeric_limits<double>::infinity();  // the next triangle's t
};

// Moeller-Trumbore against every triangle, in double: the nearest hit in [0, tfar].
Exact brute_force(const RayScene& scene, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tfar) {
  Exact best;
  const auto& tris = scene.arrays().triangles;
  for (uint32_t f = 0; f < scene.arrays().triangle_count(); ++f) {
    const Eigen::Vector3d p0 = scene.position(tris[3 * f]), p1 = scene.position(tris[3 * f + 1]), p2 = scene.position(tris[3 * f + 2]);
    const Eigen::Vector3d e1 = p1 - p0, e2 = p2 - p0, pv = d.cross(e2);
    const double det = e1.dot(pv);
    if (std::abs(det) < 1e-300) continue;
    const Eigen::Vector3d tv = o - p0, qv = tv.cross(e1);
    const double u = tv.dot(pv) / det, v = d.dot(qv) / det, t = e2.dot(qv) / det;
    if (u < 0 || v < 0 || u + v > 1 || t < 0 || t > tfar) continue;
    if (t < best.t) {
      best.second = best.t;
      best = Exact{t, f, u, v, std::min({u, v, 1 - u - v}), best.second};
    } else {
      best.second = std::min(best.second, t);
    }
  }
  return best;
}

void expect_triangle_hits(const Mesh& mesh, unsigned seed, bool paired = true) {
  const Vec3f c = bounding_box(mesh).center();
  const RayScene scene(mesh, Eigen::Vector3d(c[0], c[1], c[2]));
  if (paired) {
    ASSERT_LT(scene.quad_count(), mesh.n_faces()) << "no triangles were paired";
  }
  const auto box = bounding_box(mesh);
  const double diag = box.diagonal();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(-0.6, 0.6), sphere(-1.0, 1.0);
  int hits = 0, checked = 0;
  for (int i = 0; i < 3000; ++i) {
    // Every other ray aims near a vertex (most hit), the rest go anywhere (many miss).
    Eigen::Vector3d o(unit(rng) * diag, unit(rng) * diag, unit(rng) * diag), d;
    if (i % 2 == 0) {
      const VertexHandle v(static_cast<int>(rng() % mesh.n_vertices()));
      const Vec3f p = mesh.point(v) - c;
      d = Eigen::Vector3d(p[0] + 0.01 * diag * unit(rng), p[1] + 0.01 * diag * unit(rng), p[2] + 0.01 * diag * unit(rng)) - o;
    } else {
      do d = Eigen::Vector3d(sphere(rng), sphere(rng), sphere(rng));
      while (d.squaredNorm() > 1 || d.squaredNorm() < 1e-4);
    }
    d.normalize();
    const Vec3f of(round_to_float(o.x()), round_to_float(o.y()), round_to_float(o.z()));  // (float_rounding.hpp)
    const Vec3f df(round_to_float(d.x()), round_to_float(d.y()), round_to_float(d.z()));
    // The brute force sees the ray as Embree does: float origin and direction.
    const Eigen::Vector3d od(of[0], of[1], of[2]), dd(df[0], df[1], df[2]);
    const float tfar = static_cast<float>(2 * diag);
    const Exact e = brute_force(scene, od, dd, tfar);
    const RayScene::Hit h = scene.intersect(of, df, 0.0f, tfar);
    const double tol = 1e-5 * diag;
    // Skip rays whose answer float rounding may change: through an edge, or two surfaces
    // within the tolerance of each other.
    if (std::isfinite(e.t) && (e.edge < 1e-4 || e.second - e.t < 10 * tol)) continue;
    ++checked;
    ASSERT_EQ(h.valid(), std::isfinite(e.t)) << "ray " << i;
    if (!h.valid()) continue;
    ++hits;
    EXPECT_EQ(h.prim, e.prim) << "ray " << i;
    EXPECT_NEAR(h.t, e.t, tol) << "ray " << i;
    EXPECT_NEAR(h.u, e.u, 1e-4) << "ray " << i;
    EXPECT_NEAR(h.v, e.v, 1e-4) << "ray " << i;
    // collect() reports the same triangle at the same place.
    RayScene::Candidates cs;
    if (scene.collect(of, df, 0.0f, tfar, 0.0f, cs)) {
      ASSERT_GE(cs.n, 1);
      int first = 0;
      for (int j = 1; j < cs.n; ++j)
        if (cs.hit[j].t < cs.hit[first].t) first = j;
      EXPECT_EQ(cs.hit[first].prim, h.prim);
      EXPECT_EQ(cs.hit[first].t, h.t);
      EXPECT_EQ(cs.hit[first].u, h.u);
      EXPECT_EQ(cs.hit[first].v, h.v);
    }
  }
  EXPECT_GT(checked, 2500);
  EXPECT_GT(hits, 1000);
}

TEST(RayScene, QuadsHitAsTheirTrianglesOnAClosedSurface) { expect_triangle_hits(make_smooth_torus(40, 20), 1u); }

TEST(RayScene, QuadsHitAsTheirTrianglesOnABrickWall) {
  BrickWallOptions o;
  o.columns = 48;
  o.rows = 24;
  expect_triangle_hits(make_brick_wall(o), 2u);
}

// Holes and a lone triangle leave faces without a partner: single quads.
TEST(RayScene, QuadsHitAsTheirTrianglesWhereFacesStaySingle) {
  const Mesh torus = make_smooth_torus(30, 14);
  const Mesh holed = test::without_faces(torus, [](const Mesh&, FaceHandle f) { return f.idx() % 7 == 3 || f.idx() % 11 == 5; });
  expect_triangle_hits(holed, 3u);
}

// Two triangles make one quad, whatever corner each face's stored order starts at (the
// pairing rotates both to the quad's corners): every rotation of both faces gives each hit
// to its triangle with its barycentrics over the triangle's own stored corners.
TEST(RayScene, QuadsReportTheirTrianglesInEveryCornerRotation) {
  const std::array<Vec3f, 4> p = {Vec3f(0, 0, 0), Vec3f(1, 0, 0.1f), Vec3f(1, 1, 0), Vec3f(0, 1, 0.2f)};
  const std::array<std::array<int, 3>, 2> tris = {{{0, 1, 2}, {0, 2, 3}}};
  for (int ra = 0; ra < 3; ++ra)
    for (int rb = 0; rb < 3; ++rb) {
      Mesh m;
      std::array<VertexHandle, 4> v;
      for (int i = 0; i < 4; ++i) v[static_cast<size_t>(i)] = m.add_vertex(p[static_cast<size_t>(i)]);
      for (int t = 0; t < 2; ++t) {
        const int r = t == 0 ? ra : rb;
        const auto& c = tris[static_cast<size_t>(t)];
        m.add_face(v[static_cast<size_t>(c[static_cast<size_t>(r % 3)])], v[static_cast<size_t>(c[static_cast<size_t>((r + 1) % 3)])],
                   v[static_cast<size_t>(c[static_cast<size_t>((r + 2) % 3)])]);
      }
      const RayScene scene(m, Eigen::Vector3d(0, 0, 0));
      ASSERT_EQ(scene.quad_count(), 1u);
      for (uint32_t f = 0; f < 2; ++f) {
        const uint32_t* t = &scene.arrays().triangles[3 * f];
        const Eigen::Vector3d c0 = scene.position(t[0]), c1 = scene.position(t[1]), c2 = scene.position(t[2]);
        const Eigen::Vector3d n = scene.face_normal(f).normalized();
        for (const auto& w : {std::array<double, 3>{0.2, 0.3, 0.5}, {0.6, 0.1, 0.3}, {0.15, 0.7, 0.15}}) {
          const Eigen::Vector3d at = w[0] * c0 + w[1] * c1 + w[2] * c2, o = at + 0.5 * n;
          const RayScene::Hit h = scene.intersect(Vec3f(float(o.x()), float(o.y()), float(o.z())), Vec3f(float(-n.x()), float(-n.y()), float(-n.z())), 0.0f, 1.0f);
          ASSERT_TRUE(h.valid()) << ra << rb << " face " << f;
          EXPECT_EQ(h.prim, f) << ra << rb;
          EXPECT_NEAR(h.t, 0.5, 1e-5) << ra << rb;
          EXPECT_NEAR(h.u, w[1], 1e-5) << ra << rb << " face " << f;
          EXPECT_NEAR(h.v, w[2], 1e-5) << ra << rb << " face " << f;
        }
      }
    }
}

// Robust mode: rays through shared edges (the diagonals inside quads, and the edges between
// quads or single triangles) and shared vertices find one of the faces there: no cracks.
TEST(RayScene, RaysThroughEdgesAndVerticesFindAFace) {
  const Mesh torus = make_smooth_torus(36, 18);
  const Vec3f c = bounding_box(torus).center();
  const RayScene scene(torus, Eigen::Vector3d(c[0], c[1], c[2]));
  ASSERT_LT(scene.quad_count(), torus.n_faces());
  int rays = 0;
  auto cast_at = [&](const Vec3f& at, const Vec3f& n, std::initializer_list<int> faces) {
    const float h = 0.01f;
    const Vec3f org = at - c + h * n;
    const RayScene::Hit hit = scene.intersect(org, -n, 0.0f, 2 * h);
    ++rays;
    ASSERT_TRUE(hit.valid()) << "a crack at (" << at[0] << ", " << at[1] << ", " << at[2] << ")";
    EXPECT_NEAR(hit.t, h, 1e-5f);
    EXPECT_TRUE(std::find(faces.begin(), faces.end(), static_cast<int>(hit.prim)) != faces.end());
  };
  for (auto e : torus.edges()) {
    const auto h0 = torus.halfedge_handle(e, 0), h1 = torus.halfedge_handle(e, 1);
    const FaceHandle f0 = torus.face_handle(h0), f1 = torus.face_handle(h1);
    const Vec3f a = torus.point(torus.from_vertex_handle(h0)), b = torus.point(torus.to_vertex_handle(h0));
    const Vec3f n = (torus.calc_face_normal(f0) + torus.calc_face_normal(f1)).normalized();
    for (float s : {0.5f, 1.0f / 3.0f}) cast_at(a + s * (b - a), n, {f0.idx(), f1.idx()});
  }
  for (auto v : torus.vertices()) {
    std::vector<int> faces;
    for (auto f : torus.vf_range(v)) faces.push_back(f.idx());
    const Vec3f n = torus.normal(v);
    const float h = 0.01f;
    const RayScene::Hit hit = scene.intersect(torus.point(v) - c + h * n, -n, 0.0f, 2 * h);
    ASSERT_TRUE(hit.valid()) << "a hole at vertex " << v.idx();
    EXPECT_TRUE(std::find(faces.begin(), faces.end(), static_cast<int>(hit.prim)) != faces.end());
  }
  EXPECT_GT(rays, 3000);
}

// A mesh with deleted faces (not garbage-collected) is flattened without them and its
// triangles stay single: the hits are still the remaining triangles'.
TEST(RayScene, DeletedFacesAreLeftOutAndTheRestHitAsTriangles) {
  Mesh torus = make_smooth_torus(24, 12);
  torus.request_face_status();
  torus.request_edge_status();
  torus.request_vertex_status();
  for (auto f : torus.faces())
    if (f.idx() % 5 == 0) torus.delete_face(f, false);
  expect_triangle_hits(torus, 4u, false);
}

}  // namespace
// The ray streams answer as the single rays do: through 20 stacked layers (a window wide
// enough for all of them overflows the 16 candidates; narrower ones hold a few), 64 rays of
// a stream get the same candidates within their windows (triangles, and t, u, v to the
// packet kernels' rounding) as collect() gives each on its own, and occluded_coherent() the
// same answers as occluded(), for rays going up and down.
TEST(RayScene, StreamsAnswerAsSingleRays) {
  std::vector<std::pair<float, bool>> layers;
  for (int k = 0; k < 20; ++k) layers.emplace_back(0.05f * static_cast<float>(k), k % 2 == 0);
  const Mesh mesh = test::make_layers(layers);
  const RayScene scene(mesh, Eigen::Vector3d::Zero());
  if (!scene.streams() || !scene.filters()) GTEST_SKIP() << "this Embree has no ray streams or filter functions";
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  int compared = 0, overflowed = 0;
  for (int round = 0; round < 8; ++round) {
    constexpr unsigned m = RayScene::kMaxStream;
    std::vector<RTCRayHit> rays(m);
    std::vector<RTCRay> probes(m);
    std::array<float, m> windows{};
    std::vector<RayScene::Candidates> streamed(m);
    for (unsigned j = 0; j < m; ++j) {
      // From below or above the stack, steep enough to stay over the layers.
      const bool up = (j + static_cast<unsigned>(round)) % 2 == 0;
      const Vec3f org(0.2f + 0.6f * unit(rng), 0.2f + 0.6f * unit(rng), up ? -0.1f : 1.1f);
      const Vec3f dir = Vec3f(0.2f * (unit(rng) - 0.5f), 0.2f * (unit(rng) - 0.5f), up ? 1.0f : -1.0f).normalized();
      rays[j] = RayScene::ray_hit(org, dir, 0.0f, 0.9f + 0.5f * unit(rng));
      rays[j].ray.id = j;
      windows[j] = std::array<float, 4>{0.0f, 0.07f, 0.3f, 2.0f}[j % 4];
      probes[j] = RayScene::ray_hit(org, dir, 0.0f, 0.03f + 0.2f * unit(rng)).ray;
      probes[j].id = j;
    }
    const std::vector<RTCRayHit> sent = rays;
    scene.collect_coherent(rays.data(), m, windows.data(), streamed.data());
    std::array<bool, m> hit{};
    std::vector<RTCRay> probes_sent = probes;
    scene.occluded_coherent(probes.data(), m, hit.data());
    for (unsigned j = 0; j < m; ++j) {
      const RTCRay& r = sent[j].ray;
      const Vec3f org(r.org_x, r.org_y, r.org_z), dir(r.dir_x, r.dir_y, r.dir_z);
      RayScene::Candidates single;
      const bool ok = scene.collect(org, dir, r.tnear, r.tfar, windows[j], single);
      // What collect() promises: every triangle within the window past the nearest hit.
      // Beyond it, which candidates get recorded (and so whether 16 overflow) depends on the
      // traversal order, which differs between packets and single rays.
      if (ok && !streamed[j].overflow) {
        auto within = [&](const RayScene::Candidates& c) {
          float nearest = std::numeric_limits<float>::infinity();
          for (int k = 0; k < c.n; ++k) nearest = std::min(nearest, c.hit[k].t);
          std::vector<RayScene::Candidate> in;
          for (int k = 0; k < c.n; ++k)
            if (c.hit[k].t <= nearest + windows[j] * (1 - 1e-4f) - 1e-6f) in.push_back(c.hit[k]);
          std::sort(in.begin(), in.end(), [](const RayScene::Candidate& a, const RayScene::Candidate& b) { return a.prim < b.prim; });
          return in;
        };
        const auto a = within(streamed[j]), b = within(single);
        ASSERT_EQ(a.size(), b.size()) << "ray " << j;
        for (size_t k = 0; k < a.size(); ++k) {
          EXPECT_EQ(a[k].prim, b[k].prim) << "ray " << j;
          EXPECT_NEAR(a[k].t, b[k].t, 1e-6f) << "ray " << j;
          EXPECT_NEAR(a[k].u, b[k].u, 1e-5f) << "ray " << j;
          EXPECT_NEAR(a[k].v, b[k].v, 1e-5f) << "ray " << j;
        }
        ++compared;
      } else {
        overflowed += !ok && streamed[j].overflow;
      }
      const RTCRay& p = probes_sent[j];
      EXPECT_EQ(hit[j], scene.occluded(Vec3f(p.org_x, p.org_y, p.org_z), Vec3f(p.dir_x, p.dir_y, p.dir_z), p.tnear, p.tfar)) << "probe " << j;
    }
  }
  // Both kinds of rays occurred: compared candidate sets, and the widest windows overflowing
  // in both.
  EXPECT_GT(compared, 8 * 64 / 2);
  EXPECT_GT(overflowed, 0);
}

}  // namespace meso
