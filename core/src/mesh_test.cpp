#include "meso/core/mesh.hpp"

#include "test_support.hpp"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace meso
