// Helpers shared by meso's tests.
#pragma once

#include "meso/core/image.hpp"
#include "meso/core/mesh.hpp"

#include <array>
#include <filesystem>
#include <vector>
#include <functional>
#include <string>
#include <utility>

namespace meso::test {

// A fresh empty folder under the system temp folder, removed when the object dies.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

// Writes `text` to `path`.
void write_text(const std::filesystem::path& path, const std::string& text);
std::string read_text(const std::filesystem::path& path);

// A unit cube (8 welded vertices, 12 faces) whose six sides are separate UV charts laid
// out in a 3x2 grid: every edge of the cube is a UV seam.
Mesh make_seamed_cube();

// A width x height grid in the z = 0 plane from (0,0) to (sx, sy), UV = (x / sx, y / sy),
// with smooth normals (0,0,1).
Mesh make_grid(int columns, int rows, float sx = 1.0f, float sy = 1.0f);

// Separate quads, each its own UV chart: quad q spans UV box (u0, v0)-(u1, v1) = boxes[q], and
// in 3D the rectangle of the same extent in the plane z = q (two triangles; normals +z).
Mesh make_uv_quads(const std::vector<std::array<float, 4>>& boxes);

// A (columns x rows)-quad grid mapped through surface(s, t), s, t in [0, 1], UV = (s, t).
// With wrap_s (wrap_t) the last column (row) of vertices is the first one again (a closed
// surface; UVs then have a seam there). Normals: angle-weighted.
Mesh make_parametric(int columns, int rows, const std::function<Vec3f(double, double)>& surface, bool wrap_s, bool wrap_t);

// The unit sphere's band between 27 and 153 degrees from +z (away from the poles), a
// (columns x rows)-quad grid closed around z, with radial vertex normals: coarse, a base whose
// flat triangles sit inside the sphere; fine, the high surface.
Mesh make_sphere_band(int columns, int rows);

// The plane z = a x + b y + c over [-0.5, 1.5]^2 (an 8 x 8 grid, UV = (x + 0.5, y + 0.5) / 2),
// normals from the faces: the high surface of bake tests over a unit base quad.
Mesh make_plane(float a, float b, float c);

// Several horizontal planes z = c over [-0.5, 1.5]^2 in one mesh; `up` false flips a
// plane's faces (it then faces -z).
Mesh make_layers(const std::vector<std::pair<float, bool>>& layers);

// A copy of `mesh` (positions and faces; vertices renumbered, unused ones dropped) without
// the faces `drop` names, normals recomputed: a high surface with a hole.
Mesh without_faces(const Mesh& mesh, const std::function<bool(const Mesh&, FaceHandle)>& drop);

// The integer codes of an image read back from an 8- or 16-bit file: each value times
// max_code (255 or 65535), rounded.
std::vector<long> image_codes(const Image& image, double max_code);

// The identity-bake check on an encoded tangent-space normal map (rgb = n * 0.5 + 0.5, as
// codes from image_codes): every texel that `coverage` marks as inside a chart (non-zero)
// must decode to (0, 0, 1) within half a least significant bit, i.e. its codes lie within
// 1/2 of the exact (0.5, 0.5, 1) * max_code. Adds a test failure for the first few texels
// that do not, naming `label`; returns the counts and the largest offsets per channel.
struct UpCodesCheck {
  size_t checked = 0, bad = 0;
  double worst[3] = {0, 0, 0};  // largest |code - ideal| per channel, in LSB
};
UpCodesCheck check_codes_decode_to_up(const std::vector<long>& codes, const Image& coverage, double max_code, const std::string& label);

}  // namespace meso::test
