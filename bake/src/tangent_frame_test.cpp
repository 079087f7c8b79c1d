#include "meso/bake/tangent_frame.hpp"

#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>

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

}  // namespace
}  // namespace meso
