#include "test_support.hpp"

#include "meso/examples/parametric.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <atomic>
#include <fstream>
#include <sstream>
#include <unistd.h>

namespace meso::test {

namespace fs = std::filesystem;

TempDir::TempDir() {
  static std::atomic<int> counter{0};
  path_ = fs::temp_directory_path() / ("meso-test-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
  fs::remove_all(path_);
  fs::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary);
  f << text;
}

std::string read_text(const fs::path& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

Mesh make_seamed_cube() {
  Mesh m;
  m.request_halfedge_texcoords2D();
  VertexHandle v[8];
  for (int i = 0; i < 8; ++i) v[i] = m.add_vertex(Vec3f(float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1)));
  // Each side: 4 corners counter-clockwise seen from outside.
  const int sides[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (int s = 0; s < 6; ++s) {
    const float u0 = float(s % 3) / 3.0f, v0 = float(s / 3) / 2.0f;
    const float du = 1.0f / 3.0f * 0.8f, dv = 0.5f * 0.8f;
    const Vec2f uv[4] = {{u0 + 0.02f, v0 + 0.02f}, {u0 + 0.02f + du, v0 + 0.02f}, {u0 + 0.02f + du, v0 + 0.02f + dv},
                         {u0 + 0.02f, v0 + 0.02f + dv}};
    const int tris[2][3] = {{0, 1, 2}, {0, 2, 3}};
    for (const auto& t : tris) {
      const auto f = m.add_face(v[sides[s][t[0]]], v[sides[s][t[1]]], v[sides[s][t[2]]]);
      for (auto h : face_halfedges(m, f)) {
        const auto to = m.to_vertex_handle(h);
        for (int k = 0; k < 3; ++k)
          if (to == v[sides[s][t[k]]]) m.set_texcoord2D(h, uv[t[k]]);
      }
    }
  }
  set_face_groups(m, {"cube"}, {});
  compute_angle_weighted_normals(m);
  return m;
}

Mesh make_uv_quads(const std::vector<std::array<float, 4>>& boxes) {
  Mesh m;
  m.request_halfedge_texcoords2D();
  float z = 0;
  for (const auto& b : boxes) {
    const Vec2f uv[4] = {{b[0], b[1]}, {b[2], b[1]}, {b[2], b[3]}, {b[0], b[3]}};
    VertexHandle v[4];
    for (int k = 0; k < 4; ++k) v[k] = m.add_vertex(Vec3f(uv[k][0], uv[k][1], z));
    for (const auto& tri : {std::array<int, 3>{0, 1, 2}, std::array<int, 3>{0, 2, 3}}) {
      const FaceHandle f = m.add_face(v[tri[0]], v[tri[1]], v[tri[2]]);
      for (auto h : face_halfedges(m, f))
        for (int k = 0; k < 4; ++k)
          if (m.to_vertex_handle(h) == v[k]) m.set_texcoord2D(h, uv[k]);
    }
    z += 1;
  }
  compute_angle_weighted_normals(m);
  return m;
}

Mesh make_grid(int columns, int rows, float sx, float sy) {
  Mesh m;
  m.request_halfedge_texcoords2D();
  auto id = [&](int i, int j) { return VertexHandle(j * (columns + 1) + i); };
  for (int j = 0; j <= rows; ++j)
    for (int i = 0; i <= columns; ++i) m.add_vertex(Vec3f(sx * float(i) / float(columns), sy * float(j) / float(rows), 0));
  for (int j = 0; j < rows; ++j) {
    for (int i = 0; i < columns; ++i) {
      const VertexHandle q[4] = {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)};
      for (const auto& t : {std::array<int, 3>{0, 1, 2}, std::array<int, 3>{0, 2, 3}}) {
        const auto f = m.add_face(q[t[0]], q[t[1]], q[t[2]]);
        for (auto h : face_halfedges(m, f)) {
          const Vec3f p = m.point(m.to_vertex_handle(h));
          m.set_texcoord2D(h, Vec2f(p[0] / sx, p[1] / sy));
        }
      }
    }
  }
  set_face_groups(m, {"grid"}, {});
  compute_angle_weighted_normals(m);
  return m;
}

Mesh make_parametric(int columns, int rows, const std::function<Vec3f(double, double)>& surface, bool wrap_s, bool wrap_t) {
  return make_parametric_surface(columns, rows, surface, wrap_s, wrap_t);
}

Mesh make_sphere_band(int columns, int rows) {
  Mesh m = make_parametric(
      columns, rows,
      [](double s, double t) {
        const double a = 2 * M_PI * s, b = M_PI * (0.15 + 0.7 * t);
        return Vec3f(static_cast<float>(std::sin(b) * std::cos(a)), static_cast<float>(std::sin(b) * std::sin(a)), static_cast<float>(std::cos(b)));
      },
      true, false);
  for (auto v : m.vertices()) m.set_normal(v, m.point(v).normalized());
  return m;
}

Mesh make_plane(float a, float b, float c) {
  Mesh m = make_grid(8, 8, 2.0f, 2.0f);
  for (auto v : m.vertices()) {
    Vec3f p = m.point(v) - Vec3f(0.5f, 0.5f, 0.0f);
    p[2] = a * p[0] + b * p[1] + c;
    m.set_point(v, p);
  }
  compute_angle_weighted_normals(m);
  return m;
}

Mesh make_layers(const std::vector<std::pair<float, bool>>& layers) {
  Mesh out;
  for (const auto& [z, up] : layers) {
    const Mesh m = make_plane(0, 0, z);
    std::vector<VertexHandle> map;
    for (auto v : m.vertices()) map.push_back(out.add_vertex(m.point(v)));
    for (auto f : m.faces()) {
      std::vector<VertexHandle> vs;
      for (auto v : m.fv_range(f)) vs.push_back(map[static_cast<size_t>(v.idx())]);
      if (!up) std::reverse(vs.begin(), vs.end());
      out.add_face(vs);
    }
  }
  compute_angle_weighted_normals(out);
  return out;
}

Mesh without_faces(const Mesh& mesh, const std::function<bool(const Mesh&, FaceHandle)>& drop) {
  Mesh out;
  std::vector<VertexHandle> map(mesh.n_vertices());
  for (auto f : mesh.faces()) {
    if (drop(mesh, f)) continue;
    std::vector<VertexHandle> vs;
    for (auto v : mesh.fv_range(f)) {
      VertexHandle& m = map[static_cast<size_t>(v.idx())];
      if (!m.is_valid()) m = out.add_vertex(mesh.point(v));
      vs.push_back(m);
    }
    out.add_face(vs);
  }
  compute_angle_weighted_normals(out);
  return out;
}

std::vector<long> image_codes(const Image& image, double max_code) {
  std::vector<long> codes(image.pixels.size());
  for (size_t i = 0; i < codes.size(); ++i) codes[i] = std::lround(static_cast<double>(image.pixels[i]) * max_code);
  return codes;
}

UpCodesCheck check_codes_decode_to_up(const std::vector<long>& codes, const Image& coverage, double max_code, const std::string& label) {
  UpCodesCheck out;
  const double ideal[3] = {0.5 * max_code, 0.5 * max_code, max_code};
  EXPECT_EQ(codes.size(), 3 * coverage.texel_count()) << label << ": three channels per texel";
  if (codes.size() != 3 * coverage.texel_count()) return out;
  for (size_t i = 0; i < coverage.texel_count(); ++i) {
    if (coverage.pixels[i] == 0.0f) continue;  // outside every chart
    ++out.checked;
    bool ok = true;
    for (size_t c = 0; c < 3; ++c) {
      const double off = std::abs(static_cast<double>(codes[3 * i + c]) - ideal[c]);
      out.worst[c] = std::max(out.worst[c], off);
      ok = ok && off <= 0.5;
    }
    if (!ok && out.bad++ < 5)
      ADD_FAILURE() << label << " texel " << i % static_cast<size_t>(coverage.width) << "," << i / static_cast<size_t>(coverage.width)
                    << ": codes " << codes[3 * i] << " " << codes[3 * i + 1] << " " << codes[3 * i + 2] << ", max " << max_code;
  }
  return out;
}

}  // namespace meso::test
