#include "meso/meshreduce/meshreduce.hpp"

#include "meso/examples/brick_wall.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace meso {
namespace {

// On a flat grid the UV is an affine function of the position (u = x / sx, v = y / sy), so
// after any reduction that keeps UVs right, every corner's UV still equals that function
// of its vertex's position, every UV triangle keeps its orientation and the outline stays.
TEST(MeshReduce, FlatGridKeepsUvsOutlineAndOrientation) {
  const float sx = 2.0f, sy = 1.0f;
  const Mesh in = test::make_grid(40, 20, sx, sy);
  ReduceOptions o;
  o.target_faces = 100;
  ReduceReport r;
  const Mesh out = reduce_mesh(in, o, &r);
  EXPECT_EQ(r.input_faces, 1600u);
  EXPECT_LE(out.n_faces(), 100u);
  EXPECT_TRUE(r.target_reached);
  ASSERT_TRUE(has_uvs(out));
  for (auto f : out.faces()) {
    EXPECT_GT(uv_double_area(out, f), 0.0f) << "face " << f.idx() << " folded in UV";
    for (auto h : face_halfedges(out, f)) {
      const Vec3f p = out.point(out.to_vertex_handle(h));
      const Vec2f uv = out.texcoord2D(h);
      EXPECT_NEAR(uv[0], p[0] / sx, 1e-6);
      EXPECT_NEAR(uv[1], p[1] / sy, 1e-6);
    }
  }
  const Box3 a = bounding_box(in), b = bounding_box(out);
  EXPECT_EQ(a.lo, b.lo);
  EXPECT_EQ(a.hi, b.hi);
  // The outline is the rectangle: every boundary vertex lies on it.
  for (auto v : out.vertices()) {
    if (!out.is_boundary(v)) continue;
    const Vec3f p = out.point(v);
    const bool on = p[0] == 0.0f || p[0] == sx || p[1] == 0.0f || p[1] == sy;
    EXPECT_TRUE(on) << p;
  }
}

TEST(MeshReduce, SeamsAreNeverTorn) {
  const Mesh cube = test::make_seamed_cube();
  ReduceOptions o;
  o.target_faces = 2;
  ReduceReport r;
  const Mesh out = reduce_mesh(cube, o, &r);
  // Every vertex of the cube is a corner of the seam network: nothing may collapse.
  EXPECT_EQ(out.n_faces(), 12u);
  EXPECT_FALSE(r.target_reached);
}

TEST(MeshReduce, TargetAboveInputIsANoOp) {
  const Mesh in = test::make_grid(4, 4);
  ReduceOptions o;
  o.target_faces = 1000;
  const Mesh out = reduce_mesh(in, o);
  EXPECT_EQ(out.n_faces(), in.n_faces());
  EXPECT_EQ(out.n_vertices(), in.n_vertices());
}

TEST(MeshReduce, BrickWallStaysCloseToItsBaseSurface) {
  BrickWallOptions w;
  w.columns = 128;
  w.rows = 64;
  const Mesh high = make_brick_wall(w);
  ReduceOptions o;
  o.target_faces = 800;
  const Mesh low = reduce_mesh(high, o);
  EXPECT_LE(low.n_faces(), 800u);
  // Every kept vertex is a vertex of the high mesh (collapses go onto existing vertices),
  // so it lies on the bricks: within the amplitude of the base cylinder.
  for (auto v : low.vertices()) {
    const Vec3f p = low.point(v);
    const float r = std::hypot(p[0], p[2] + w.bend_radius);
    EXPECT_GE(r, w.bend_radius - 1e-4f);
    EXPECT_LE(r, w.bend_radius + w.amplitude * 1.2f);
  }
}

}  // namespace
}  // namespace meso
