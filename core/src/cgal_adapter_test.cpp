// meso::Mesh is used by CGAL algorithms directly, through CGAL's BGL adapters for OpenMesh
// (no copy into a CGAL Surface_mesh). This pins that the adapters compile against meso's
// traits and give the right answers; CGAL-based stages rely on it.
#include "meso/core/mesh.hpp"

#include "test_support.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/boost/graph/graph_traits_TriMesh_ArrayKernelT.h>
#include <CGAL/boost/graph/helpers.h>
#include <CGAL/boost/graph/properties_TriMesh_ArrayKernelT.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/measure.h>

#include <gtest/gtest.h>

#include <map>

namespace meso {
namespace {

namespace PMP = CGAL::Polygon_mesh_processing;

TEST(CgalAdapter, MeasuresAndTopologyOnMesoMesh) {
  const Mesh cube = test::make_seamed_cube();
  EXPECT_TRUE(CGAL::is_closed(cube));
  EXPECT_TRUE(CGAL::is_triangle_mesh(cube));
  EXPECT_NEAR(PMP::area(cube), 6.0, 1e-12);
  EXPECT_NEAR(PMP::volume(cube), 1.0, 1e-12);

  const Mesh grid = test::make_grid(4, 3, 2.0f, 1.0f);
  EXPECT_FALSE(CGAL::is_closed(grid));
  EXPECT_NEAR(PMP::area(grid), 2.0, 1e-12);
  // Explicit face-index map: CGAL's default dynamic maps need property storage OpenMesh lacks.
  std::map<Mesh::FaceHandle, std::size_t> component;
  const auto n = PMP::connected_components(grid, boost::make_assoc_property_map(component));
  EXPECT_EQ(n, 1u);
}

}  // namespace
}  // namespace meso
