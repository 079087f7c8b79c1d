#include "meso/examples/parametric.hpp"

#include <array>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace meso {

Mesh make_parametric_surface(int columns, int rows, const std::function<Vec3f(double, double)>& surface, bool wrap_s, bool wrap_t,
                             const std::string& name) {
  Mesh m;
  m.request_halfedge_texcoords2D();
  const int vc = wrap_s ? columns : columns + 1, vr = wrap_t ? rows : rows + 1;
  for (int j = 0; j < vr; ++j)
    for (int i = 0; i < vc; ++i) m.add_vertex(surface(double(i) / columns, double(j) / rows));
  auto id = [&](int i, int j) { return VertexHandle((j % vr) * vc + (i % vc)); };
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < columns; ++i) {
      const int q[4][2] = {{i, j}, {i + 1, j}, {i + 1, j + 1}, {i, j + 1}};
      for (const auto& t : {std::array<int, 3>{0, 1, 2}, std::array<int, 3>{0, 2, 3}}) {
        const auto f = m.add_face(id(q[t[0]][0], q[t[0]][1]), id(q[t[1]][0], q[t[1]][1]), id(q[t[2]][0], q[t[2]][1]));
        for (auto h : face_halfedges(m, f))
          for (int k = 0; k < 3; ++k)
            if (m.to_vertex_handle(h) == id(q[t[k]][0], q[t[k]][1]))
              m.set_texcoord2D(h, Vec2f(float(q[t[k]][0]) / columns, float(q[t[k]][1]) / rows));
      }
    }
  set_face_groups(m, {name}, {});
  compute_angle_weighted_normals(m);
  return m;
}

Mesh make_surface_with_poles(int columns, int rows, const std::function<Vec3f(double, double)>& point) {
  if (columns < 3 || rows < 2) throw std::invalid_argument("make_surface_with_poles: needs columns >= 3 and rows >= 2");
  Mesh m;
  std::vector<VertexHandle> ring;
  const VertexHandle south = m.add_vertex(point(0, 0));
  for (int j = 1; j < rows; ++j)
    for (int i = 0; i < columns; ++i) ring.push_back(m.add_vertex(point(M_PI * j / rows, 2 * M_PI * i / columns)));
  const VertexHandle north = m.add_vertex(point(M_PI, 0));
  auto at = [&](int j, int i) { return ring[static_cast<size_t>((j - 1) * columns + (i % columns))]; };
  for (int i = 0; i < columns; ++i) {
    m.add_face(south, at(1, i + 1), at(1, i));
    m.add_face(north, at(rows - 1, i), at(rows - 1, i + 1));
    for (int j = 1; j + 1 < rows; ++j) {
      m.add_face(at(j, i), at(j, i + 1), at(j + 1, i + 1));
      m.add_face(at(j, i), at(j + 1, i + 1), at(j + 1, i));
    }
  }
  compute_angle_weighted_normals(m);
  return m;
}

Mesh make_smooth_torus(int columns, int rows) {
  return make_parametric_surface(
      columns, rows,
      [](double s, double t) {
        const double u = 2 * M_PI * s, v = 2 * M_PI * t;
        const double r = 0.35 + 0.04 * std::sin(3 * u) * std::cos(2 * v);
        const double R = 1.0 + r * std::cos(v);
        return Vec3f(static_cast<float>(R * std::cos(u)), static_cast<float>(R * std::sin(u)), static_cast<float>(r * std::sin(v)));
      },
      true, true, "torus");
}

}  // namespace meso
