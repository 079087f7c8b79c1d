#include "meso/examples/brick_wall.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace meso {

namespace {

constexpr float kBrickW = 0.24f, kBrickH = 0.08f, kMortar = 0.012f, kBevel = 0.012f;

// Integer hash (lowbias32) to a value in [0, 1): deterministic on every platform.
float hash01(int32_t x, int32_t y, uint32_t seed) {
  uint32_t h = static_cast<uint32_t>(x) * 0x8da6b343u ^ static_cast<uint32_t>(y) * 0xd8163841u ^ seed * 0xcb1ab31fu;
  h ^= h >> 16;
  h *= 0x7feb352du;
  h ^= h >> 15;
  h *= 0x846ca68bu;
  h ^= h >> 16;
  return static_cast<float>(h >> 8) * (1.0f / 16777216.0f);
}

float smooth(float t) {
  t = std::clamp(t, 0.0f, 1.0f);
  return t * t * (3.0f - 2.0f * t);
}

// Value noise with smooth interpolation, period 1 in its argument.
float value_noise(float x, float y, uint32_t seed) {
  const float fx = std::floor(x), fy = std::floor(y);
  const int32_t ix = static_cast<int32_t>(fx), iy = static_cast<int32_t>(fy);
  const float tx = smooth(x - fx), ty = smooth(y - fy);
  const float a = hash01(ix, iy, seed), b = hash01(ix + 1, iy, seed);
  const float c = hash01(ix, iy + 1, seed), d = hash01(ix + 1, iy + 1, seed);
  return (a + (b - a) * tx) + ((c + (d - c) * tx) - (a + (b - a) * tx)) * ty;
}

}  // namespace

float brick_wall_height(const BrickWallOptions& o, float x, float y) {
  const float row_f = std::floor(y / kBrickH);
  const int row = static_cast<int>(row_f);
  const float offset = (row % 2) ? 0.5f * kBrickW : 0.0f;
  const float bx = x + offset;
  const float col_f = std::floor(bx / kBrickW);
  // Distance from the point to the brick's edge (half the mortar joint already removed).
  const float lx = bx - col_f * kBrickW, ly = y - row_f * kBrickH;
  float d = std::min({lx, kBrickW - lx, ly, kBrickH - ly}) - 0.5f * kMortar;
  // The wall's border is a mortar frame as well.
  d = std::min(d, std::min({x, o.width - x, y, o.height - y}) - kMortar);
  if (d <= 0.0f) return 0.0f;
  const int col = static_cast<int>(col_f);
  // Each brick sits a little higher or lower, and its face is rough.
  const float tilt = 0.85f + 0.3f * hash01(col, row, 7u);
  const float rough = 0.5f * value_noise(x * 60.0f, y * 60.0f, 11u) + 0.25f * value_noise(x * 150.0f, y * 150.0f, 13u);
  return o.amplitude * smooth(d / kBevel) * (tilt + o.roughness * (rough - 0.375f));
}

void brick_wall_base(const BrickWallOptions& o, float x, float y, Vec3f& point, Vec3f& normal) {
  if (o.bend_radius <= 0.0f) {
    point = Vec3f(x - 0.5f * o.width, y - 0.5f * o.height, 0.0f);
    normal = Vec3f(0, 0, 1);
    return;
  }
  const float r = o.bend_radius;
  const float a = (x - 0.5f * o.width) / r;  // arc length -> angle
  normal = Vec3f(std::sin(a), 0.0f, std::cos(a));
  point = Vec3f(r * std::sin(a), y - 0.5f * o.height, r * std::cos(a) - r);
}

namespace {

Mesh make_grid(const BrickWallOptions& o, int columns, int rows, bool displaced) {
  Mesh mesh;
  mesh.request_halfedge_texcoords2D();
  std::vector<VertexHandle> vs;
  vs.reserve(static_cast<size_t>(columns + 1) * static_cast<size_t>(rows + 1));
  for (int j = 0; j <= rows; ++j) {
    for (int i = 0; i <= columns; ++i) {
      const float x = o.width * static_cast<float>(i) / static_cast<float>(columns);
      const float y = o.height * static_cast<float>(j) / static_cast<float>(rows);
      Vec3f p, n;
      brick_wall_base(o, x, y, p, n);
      if (displaced) p += n * brick_wall_height(o, x, y);
      vs.push_back(mesh.add_vertex(p));
    }
  }
  auto vid = [&](int i, int j) { return vs[static_cast<size_t>(j) * static_cast<size_t>(columns + 1) + static_cast<size_t>(i)]; };
  auto uv_of = [&](int i, int j) {
    return Vec2f(static_cast<float>(i) / static_cast<float>(columns), static_cast<float>(j) / static_cast<float>(rows));
  };
  for (int j = 0; j < rows; ++j) {
    for (int i = 0; i < columns; ++i) {
      const int tri[2][3][2] = {{{i, j}, {i + 1, j}, {i + 1, j + 1}}, {{i, j}, {i + 1, j + 1}, {i, j + 1}}};
      for (const auto& t : tri) {
        const auto f = mesh.add_face(vid(t[0][0], t[0][1]), vid(t[1][0], t[1][1]), vid(t[2][0], t[2][1]));
        for (auto h : face_halfedges(mesh, f)) {
          const int k = static_cast<int>(mesh.to_vertex_handle(h).idx());
          mesh.set_texcoord2D(h, uv_of(k % (columns + 1), k / (columns + 1)));
        }
      }
    }
  }
  set_face_groups(mesh, {displaced ? "bricks_high" : "bricks_low"}, {});
  compute_angle_weighted_normals(mesh);
  return mesh;
}

}  // namespace

Mesh make_brick_wall(const BrickWallOptions& o) { return make_grid(o, o.columns, o.rows, true); }

Mesh make_brick_wall_base(const BrickWallOptions& o, int columns, int rows) {
  return make_grid(o, columns, rows, false);
}

}  // namespace meso
