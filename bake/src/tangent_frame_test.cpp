#include "meso/bake/tangent_frame.hpp"

#include "test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numeric>
#include <random>
#include <vector>

namespace meso {
namespace {

TEST(TangentFrame, GridWithAxisAlignedUvs) {
  const Mesh m = test::make_grid(4, 3, 2.0f, 1.0f);
  const auto frames = compute_tangent_frames(m);
  for (auto h : m.halfedges()) {
    if (m.is_boundary(h)) continue;
    const auto& f = frames[static_cast<size_t>(h.idx())];
    EXPECT_NEAR(f.tangent[0], 1.0f, 1e-6);
    EXPECT_NEAR(f.tangent[1], 0.0f, 1e-6);
    EXPECT_NEAR(f.tangent[2], 0.0f, 1e-6);
    EXPECT_EQ(f.sign, 1.0f);
    EXPECT_NEAR(f.du_length, 2.0f, 1e-5) << "object units per UV unit along u";
    EXPECT_NEAR(f.dv_length, 1.0f, 1e-5);
  }
}

TEST(TangentFrame, MirroredUvsFlipTheSign) {
  Mesh m = test::make_grid(3, 3);
  for (auto h : m.halfedges()) {
    if (m.is_boundary(h)) continue;
    Vec2f uv = m.texcoord2D(h);
    m.set_texcoord2D(h, Vec2f(1.0f - uv[0], uv[1]));
  }
  const auto frames = compute_tangent_frames(m);
  for (auto h : m.halfedges()) {
    if (m.is_boundary(h)) continue;
    const auto& f = frames[static_cast<size_t>(h.idx())];
    EXPECT_NEAR(f.tangent[0], -1.0f, 1e-6);
    EXPECT_EQ(f.sign, -1.0f);
  }
}

TEST(TangentFrame, DegenerateUvsGiveFiniteOrthonormalFrames) {
  Mesh m = test::make_grid(2, 2);
  for (auto h : m.halfedges())
    if (!m.is_boundary(h)) m.set_texcoord2D(h, Vec2f(0.5f, 0.5f));
  const auto frames = compute_tangent_frames(m);
  for (auto h : m.halfedges()) {
    if (m.is_boundary(h)) continue;
    const auto& f = frames[static_cast<size_t>(h.idx())];
    ASSERT_TRUE(std::isfinite(f.tangent.sqrnorm()));
    EXPECT_NEAR(f.tangent.norm(), 1.0f, 1e-6);
    EXPECT_NEAR(OpenMesh::dot(f.tangent, m.normal(m.to_vertex_handle(h))), 0.0f, 1e-6);
    EXPECT_TRUE(std::isfinite(f.du_length) && std::isfinite(f.dv_length));
  }
}

TEST(TangentFrame, SplitsAtSeamsAndStaysInTheTangentPlane) {
  const Mesh m = test::make_seamed_cube();
  const auto frames = compute_tangent_frames(m);
  for (auto h : m.halfedges()) {
    if (m.is_boundary(h)) continue;
    const auto& f = frames[static_cast<size_t>(h.idx())];
    EXPECT_NEAR(f.tangent.norm(), 1.0f, 1e-6);
    EXPECT_NEAR(OpenMesh::dot(f.tangent, m.normal(m.to_vertex_handle(h))), 0.0f, 1e-6);
  }
  // Corners of one vertex on different sides (different UVs) have different tangents.
  const VertexHandle v0(0);
  std::vector<Vec3f> seen;
  for (auto h : m.vih_range(v0)) {
    if (m.is_boundary(h)) continue;
    seen.push_back(frames[static_cast<size_t>(h.idx())].tangent);
  }
  bool differ = false;
  for (const auto& t : seen) differ |= (t - seen.front()).norm() > 0.1f;
  EXPECT_TRUE(differ);
}

// ---- invariance under reordering and re-indexing ----------------------------------------------

struct Soup {
  std::vector<Vec3f> points;
  std::vector<std::array<int, 3>> tris;
  std::vector<std::array<Vec2f, 3>> uvs;
};

Mesh build(const Soup& s, const std::vector<Vec3f>* normals = nullptr) {
  Mesh m;
  m.request_halfedge_texcoords2D();
  for (const auto& p : s.points) m.add_vertex(p);
  for (size_t t = 0; t < s.tris.size(); ++t) {
    const auto& tri = s.tris[t];
    const auto f = m.add_face(VertexHandle(tri[0]), VertexHandle(tri[1]), VertexHandle(tri[2]));
    for (auto h : face_halfedges(m, f))
      for (size_t k = 0; k < 3; ++k)
        if (m.to_vertex_handle(h).idx() == tri[k]) m.set_texcoord2D(h, s.uvs[t][k]);
  }
  set_face_groups(m, {"soup"}, {});
  compute_angle_weighted_normals(m);
  if (normals)
    for (auto v : m.vertices()) m.set_normal(v, (*normals)[static_cast<size_t>(v.idx())]);
  return m;
}

// A curved sheet whose UVs have everything at once: a chart, a column collapsed in UV
// (zero-area triangles) right on a mirror line (mirrored chart beyond, so the collapsed
// triangles sit between a preserving and a mirrored group), a separate chart touching the
// first one at a single UV point, and a triangle whose UVs collapse to one point.
Soup everything_sheet() {
  const int n = 16;
  Soup s;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const double x = double(i) / n, y = double(j) / n;
      // Irregular enough that summation order would show in the last bits.
      const double jx = 0.2 / n * std::sin(37.0 * i + 11.0 * j), jy = 0.2 / n * std::cos(23.0 * i - 7.0 * j);
      s.points.push_back(Vec3f(float(x + jx), float(y + jy + 0.05 * std::sin(4 * x)), float(0.3 * std::sin(3 * x) * std::cos(2 * y))));
    }
  auto uv = [&](int i, int j, int qi, int qj) {
    const float v = float(j) / n;
    if (qi == 2 && qj == 1) return Vec2f(0.3f, 0.3f);  // all three corners at one UV
    // columns 0..7 preserving, column 8 collapsed onto column 7, 9.. mirrored
    const int iu = i <= 7 ? i : 7 - (i - 8);
    const Vec2f base(float(iu) / n + 0.01f * float(j * j) / n, v + 0.02f * float(iu));
    if (qj < 12) return base;
    // The top rows: a separate chart, touching the rest at vertex (4, 12) only.
    const float d = float(i - 4) / n;
    return base + Vec2f(0.2f * d * d, 0.1f * d * d + 0.05f * d);
  };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int q[4][2] = {{i, j}, {i + 1, j}, {i + 1, j + 1}, {i, j + 1}};
      for (const auto& t : {std::array<int, 3>{0, 1, 2}, std::array<int, 3>{0, 2, 3}}) {
        std::array<int, 3> tri{};
        std::array<Vec2f, 3> tuv{};
        for (size_t k = 0; k < 3; ++k) {
          const auto& c = q[t[k]];
          tri[k] = c[1] * (n + 1) + c[0];
          tuv[k] = uv(c[0], c[1], i, j);
        }
        s.tris.push_back(tri);
        s.uvs.push_back(tuv);
      }
    }
  return s;
}

// The same surface with vertices and faces shuffled and each face's corners rotated.
Soup reindexed(const Soup& s, unsigned seed, std::vector<int>* vertex_of_new = nullptr) {
  std::mt19937 rng(seed);
  std::vector<int> vperm(s.points.size()), fperm(s.tris.size());
  std::iota(vperm.begin(), vperm.end(), 0);
  std::iota(fperm.begin(), fperm.end(), 0);
  std::shuffle(vperm.begin(), vperm.end(), rng);  // new vertex i is old vertex vperm[i]
  std::shuffle(fperm.begin(), fperm.end(), rng);
  std::vector<int> new_of_old(s.points.size());
  for (size_t i = 0; i < vperm.size(); ++i) new_of_old[static_cast<size_t>(vperm[i])] = static_cast<int>(i);
  Soup r;
  for (int old : vperm) r.points.push_back(s.points[static_cast<size_t>(old)]);
  for (int f : fperm) {
    const size_t rot = rng() % 3;
    std::array<int, 3> tri{};
    std::array<Vec2f, 3> tuv{};
    for (size_t k = 0; k < 3; ++k) {
      tri[k] = new_of_old[static_cast<size_t>(s.tris[static_cast<size_t>(f)][(k + rot) % 3])];
      tuv[k] = s.uvs[static_cast<size_t>(f)][(k + rot) % 3];
    }
    r.tris.push_back(tri);
    r.uvs.push_back(tuv);
  }
  if (vertex_of_new) *vertex_of_new = vperm;
  return r;
}

// A corner named by what it is, not by indices: its face's corner positions (sorted) and its own.
using CornerKey = std::array<float, 12>;
CornerKey corner_key(const Mesh& m, HalfedgeHandle h) {
  std::array<std::array<float, 3>, 3> ps{};
  size_t i = 0;
  for (auto g : face_halfedges(m, m.face_handle(h))) {
    const Vec3f p = m.point(m.to_vertex_handle(g));
    ps[i++] = {p[0], p[1], p[2]};
  }
  std::sort(ps.begin(), ps.end());
  const Vec3f p = m.point(m.to_vertex_handle(h));
  return {ps[0][0], ps[0][1], ps[0][2], ps[1][0], ps[1][1], ps[1][2], ps[2][0], ps[2][1], ps[2][2], p[0], p[1], p[2]};
}

std::map<CornerKey, TangentFrame> frames_by_corner(const Mesh& m) {
  const auto frames = compute_tangent_frames(m);
  std::map<CornerKey, TangentFrame> out;
  for (auto f : m.faces())
    for (auto h : face_halfedges(m, f)) out[corner_key(m, h)] = frames[static_cast<size_t>(h.idx())];
  return out;
}

TEST(TangentFrame, IdenticalWhenFacesReorderedAndMeshReindexed) {
  const Soup s = everything_sheet();
  const Mesh m = build(s);
  const auto ref = frames_by_corner(m);
  ASSERT_EQ(ref.size(), 3 * m.n_faces());
  for (unsigned seed = 1; seed <= 10; ++seed) {
    std::vector<int> old_of_new;
    const Soup r = reindexed(s, seed, &old_of_new);
    // Vertex normals carried over by vertex, so that only the frames' own computation is tested.
    std::vector<Vec3f> normals;
    for (int old : old_of_new) normals.push_back(m.normal(VertexHandle(old)));
    const auto got = frames_by_corner(build(r, &normals));
    ASSERT_EQ(got.size(), ref.size());
    for (const auto& [key, fr] : ref) {
      const auto it = got.find(key);
      ASSERT_NE(it, got.end());
      // Bit for bit: contributions are summed in a canonical order.
      EXPECT_EQ(it->second.tangent, fr.tangent) << "seed " << seed;
      EXPECT_EQ(it->second.sign, fr.sign) << "seed " << seed;
      EXPECT_EQ(it->second.du_length, fr.du_length) << "seed " << seed;
      EXPECT_EQ(it->second.dv_length, fr.dv_length) << "seed " << seed;
    }
    // With normals recomputed from the reordered faces, only their rounding differs.
    const auto got2 = frames_by_corner(build(r));
    for (const auto& [key, fr] : ref) {
      const auto& g = got2.at(key);
      EXPECT_LT((g.tangent - fr.tangent).norm(), 1e-6f) << "seed " << seed;
      EXPECT_EQ(g.sign, fr.sign) << "seed " << seed;
    }
  }
}

TEST(TangentFrame, OneSignPerTriangleAndFiniteEverywhere) {
  // Zero-area UV triangles between a preserving and a mirrored group take one orientation
  // for all three corners (preserving), so a renderer may take the sign from any corner.
  const Mesh m = build(everything_sheet());
  const auto frames = compute_tangent_frames(m);
  size_t mirrored = 0;
  for (auto f : m.faces()) {
    const auto hs = face_halfedges(m, f);
    for (auto h : hs) {
      const auto& fr = frames[static_cast<size_t>(h.idx())];
      EXPECT_EQ(fr.sign, frames[static_cast<size_t>(hs[0].idx())].sign) << "face " << f.idx();
      ASSERT_TRUE(std::isfinite(fr.tangent.sqrnorm()) && std::isfinite(fr.du_length) && std::isfinite(fr.dv_length));
      EXPECT_NEAR(fr.tangent.norm(), 1.0f, 1e-6f);
      EXPECT_NEAR(OpenMesh::dot(fr.tangent, m.normal(m.to_vertex_handle(h))), 0.0f, 1e-6f);
      mirrored += fr.sign < 0;
    }
  }
  EXPECT_GT(mirrored, 0u);
}

TEST(TangentFrame, ChartsTouchingAtOneUvPointKeepTheirOwnFrames) {
  // Two fans around one vertex carry the same UV there but are separated by seams: each has
  // its own frame (as MikkTSpace does), not their average.
  Soup s;
  s.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}};
  // Faces 0, 1: u along +x. Faces 2, 3: u along +y. Same UV at vertex 0, seams along 0-2 and 0-4.
  s.tris = {{0, 1, 2}, {0, 4, 1}, {0, 2, 3}, {0, 3, 4}};
  s.uvs = {{Vec2f(0.5f, 0.5f), Vec2f(1.0f, 0.5f), Vec2f(0.5f, 1.0f)},
           {Vec2f(0.5f, 0.5f), Vec2f(0.5f, 0.0f), Vec2f(1.0f, 0.5f)},
           {Vec2f(0.5f, 0.5f), Vec2f(0.9f, 0.5f), Vec2f(0.5f, 0.9f)},
           {Vec2f(0.5f, 0.5f), Vec2f(0.5f, 0.9f), Vec2f(0.1f, 0.5f)}};
  const Mesh m = build(s);
  const auto frames = compute_tangent_frames(m);
  for (auto h : m.vih_range(VertexHandle(0))) {
    if (m.is_boundary(h)) continue;
    const int f = m.face_handle(h).idx();
    const Vec3f expect = f < 2 ? Vec3f(1, 0, 0) : Vec3f(0, 1, 0);
    EXPECT_LT((frames[static_cast<size_t>(h.idx())].tangent - expect).norm(), 1e-6f) << "face " << f;
  }
}

}  // namespace
}  // namespace meso
