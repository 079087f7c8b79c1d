#include "meso/core/mesh.hpp"

#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace meso {
namespace {

// A 3 x 2 sheet whose UVs span [0, 1]^2 has 3 object units per UV unit across and 2 down:
// the mean scale is sqrt(6 / 1).
TEST(Mesh, ObjectLengthPerUvIsTheMeanScale) {
  EXPECT_NEAR(object_length_per_uv(test::make_grid(4, 3, 3.0f, 2.0f)), std::sqrt(6.0), 1e-6);
  Mesh flat = test::make_grid(2, 2);
  flat.release_halfedge_texcoords2D();
  flat.request_halfedge_texcoords2D();  // all UVs (0, 0): no UV area
  for (auto h : flat.halfedges()) flat.set_texcoord2D(h, Vec2f(0, 0));
  EXPECT_EQ(object_length_per_uv(flat), 0.0);
}

// Areas in double: a sheet 1e12 or 1e-12 units across has the same scale per unit, where a
// float cross product gave inf (1e12) and 0 (1e-12, "has no area").
TEST(Mesh, AreasHoldAtAnyScaleAFloatCanHold) {
  for (const float s : {1e12f, 1e-12f, 1e30f, 1e-30f}) {
    const Mesh m = test::make_grid(4, 3, 3.0f * s, 2.0f * s);
    EXPECT_NEAR(object_length_per_uv(m) / s, std::sqrt(6.0), 1e-5) << s;
    double area = 0;
    for (auto f : m.faces()) area += face_area(m, f);
    EXPECT_NEAR(area / (static_cast<double>(s) * s), 6.0, 1e-5) << s;
  }
}

// A sliver whose float area rounds to 0: (0.5 + 2^-24)^2 and (0.5 + 2^-23) 0.5 differ by
// 2^-48, below float's resolution of either. In double, with the product's rounding put back,
// the area is exactly 2^-48 and positive, so the checker and the baker do not skip a face that
// covers texels along the diagonal.
TEST(Mesh, UvAreaOfASliverIsExact) {
  Mesh m;
  m.request_halfedge_texcoords2D();
  const auto v0 = m.add_vertex(Vec3f(0, 0, 0)), v1 = m.add_vertex(Vec3f(1, 1, 0)), v2 = m.add_vertex(Vec3f(1, 1, 1));
  const FaceHandle f = m.add_face(v0, v1, v2);
  const Vec2f uv[3] = {Vec2f(0, 0), Vec2f(0.5f + 0x1p-24f, 0.5f + 0x1p-23f), Vec2f(0.5f, 0.5f + 0x1p-24f)};
  const auto hs = face_halfedges(m, f);
  for (int k = 0; k < 3; ++k) m.set_texcoord2D(hs[static_cast<size_t>(k)], uv[m.to_vertex_handle(hs[static_cast<size_t>(k)]).idx()]);
  const Vec2f a = m.texcoord2D(hs[0]), b = m.texcoord2D(hs[1]), c = m.texcoord2D(hs[2]);
  const float in_float = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
  EXPECT_EQ(in_float, 0.0f) << "the case this guards";
  EXPECT_EQ(std::abs(uv_double_area(m, f)), 0x1p-48);
}

}  // namespace
}  // namespace meso
