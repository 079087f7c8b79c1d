// meso's tangent frames against the MikkTSpace reference: the npm package `mikktspace` (a
// WebAssembly build of the Rust port of Morten Mikkelsen's mikktspace.c), run through
// tests/mikktspace/tangents.mjs on the same corners. Meshes with UV seams, mirrored UVs and
// degenerate UV triangles. Skips when node or the package is missing (scripts/setup-deps
// installs both), except under MESO_REQUIRE_PEERS=1 (set by scripts/test), where it fails.
#include "meso/bake/tangent_frame.hpp"

#include "test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#ifndef MESO_MIKKTSPACE_DIR
#error "MESO_MIKKTSPACE_DIR must name tests/mikktspace"
#endif

namespace meso {
namespace {

namespace fs = std::filesystem;

constexpr double kPi = 3.14159265358979323846;
// Agreement required per corner. Measured: below 1e-5 degrees on every mesh here (float
// rounding of the reference), so this leaves a wide margin for other compilers and CPUs.
constexpr double kMaxAngleDeg = 1e-3;

// ---- meshes --------------------------------------------------------------------------------

struct Tri {
  std::array<int, 3> v;
  std::array<Vec2f, 3> uv;
};

Mesh build(const std::vector<Vec3f>& points, const std::vector<Tri>& tris) {
  Mesh m;
  m.request_halfedge_texcoords2D();
  for (const auto& p : points) m.add_vertex(p);
  for (const auto& t : tris) {
    const auto f = m.add_face(VertexHandle(t.v[0]), VertexHandle(t.v[1]), VertexHandle(t.v[2]));
    if (!f.is_valid()) throw std::runtime_error("non-manifold test mesh");
    for (auto h : face_halfedges(m, f))
      for (int k = 0; k < 3; ++k)
        if (m.to_vertex_handle(h).idx() == t.v[static_cast<size_t>(k)]) m.set_texcoord2D(h, t.uv[static_cast<size_t>(k)]);
  }
  set_face_groups(m, {"test"}, {});
  compute_angle_weighted_normals(m);
  return m;
}

// A (columns x rows) grid of quads through surface(i, j) (integer grid coordinates) with
// per-corner UVs uv(i, j, face-local data): two triangles per quad.
Mesh grid_mesh(int columns, int rows, const std::function<Vec3f(int, int)>& surface,
               const std::function<Vec2f(int i, int j, int qi, int qj)>& uv) {
  std::vector<Vec3f> points;
  for (int j = 0; j <= rows; ++j)
    for (int i = 0; i <= columns; ++i) points.push_back(surface(i, j));
  std::vector<Tri> tris;
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < columns; ++i) {
      const int q[4][2] = {{i, j}, {i + 1, j}, {i + 1, j + 1}, {i, j + 1}};
      for (const auto& t : {std::array<int, 3>{0, 1, 2}, std::array<int, 3>{0, 2, 3}}) {
        Tri tri;
        for (size_t k = 0; k < 3; ++k) {
          const auto& c = q[t[k]];
          tri.v[k] = c[1] * (columns + 1) + c[0];
          tri.uv[k] = uv(c[0], c[1], i, j);
        }
        tris.push_back(tri);
      }
    }
  return build(points, tris);
}

// A UV sphere with one vertex per pole; the pole corners each carry their own UV (u at the
// middle of the triangle's span), the meridian u = 0 / 1 is a seam.
Mesh uv_sphere(int columns, int rows, float r) {
  std::vector<Vec3f> points;
  auto ring = [&](int i, int j) { return 2 + (j - 1) * columns + (i % columns); };
  points.push_back(Vec3f(0, 0, -r));
  points.push_back(Vec3f(0, 0, r));
  for (int j = 1; j < rows; ++j) {
    const double th = kPi * j / rows;
    for (int i = 0; i < columns; ++i) {
      const double ph = 2 * kPi * i / columns;
      points.push_back(Vec3f(float(r * std::sin(th) * std::cos(ph)), float(r * std::sin(th) * std::sin(ph)), float(-r * std::cos(th))));
    }
  }
  auto uv = [&](int i, int j) { return Vec2f(float(i) / float(columns), float(j) / float(rows)); };
  std::vector<Tri> tris;
  for (int i = 0; i < columns; ++i) {
    const Vec2f pole_s(float(i + 0.5) / float(columns), 0.0f), pole_n(float(i + 0.5) / float(columns), 1.0f);
    tris.push_back({{0, ring(i + 1, 1), ring(i, 1)}, {pole_s, uv(i + 1, 1), uv(i, 1)}});
    tris.push_back({{1, ring(i, rows - 1), ring(i + 1, rows - 1)}, {pole_n, uv(i, rows - 1), uv(i + 1, rows - 1)}});
    for (int j = 1; j + 1 < rows; ++j) {
      tris.push_back({{ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)}, {uv(i, j), uv(i + 1, j), uv(i + 1, j + 1)}});
      tris.push_back({{ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)}, {uv(i, j), uv(i + 1, j + 1), uv(i, j + 1)}});
    }
  }
  return build(points, tris);
}

// ---- the reference ---------------------------------------------------------------------------

std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string why_no_reference() {
  if (std::system("node --version >/dev/null 2>&1") != 0) return "node is not installed (scripts/setup-deps installs it)";
  if (!fs::exists(fs::path(MESO_MIKKTSPACE_DIR) / "node_modules" / "mikktspace" / "package.json"))
    return std::string("the npm package mikktspace is not installed in ") + MESO_MIKKTSPACE_DIR + " (run scripts/setup-deps, or npm ci there)";
  return "";
}

std::string num(float x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", static_cast<double>(x));
  return buf;
}

// Corners in face order, face_halfedges() order within a face: what the reference sees.
std::vector<HalfedgeHandle> corner_order(const Mesh& m) {
  std::vector<HalfedgeHandle> order;
  for (auto f : m.faces())
    for (auto h : face_halfedges(m, f)) order.push_back(h);
  return order;
}

// Per corner of corner_order(m): x, y, z, w from the reference.
std::vector<std::array<float, 4>> reference_tangents(const Mesh& m) {
  test::TempDir dir;
  std::string pos, nrm, uv;
  for (auto h : corner_order(m)) {
    const auto v = m.to_vertex_handle(h);
    const Vec3f p = m.point(v), n = m.normal(v);
    const Vec2f t = m.texcoord2D(h);
    for (int k = 0; k < 3; ++k) {
      pos += (pos.empty() ? "" : ",") + num(p[k]);
      nrm += (nrm.empty() ? "" : ",") + num(n[k]);
    }
    for (int k = 0; k < 2; ++k) uv += (uv.empty() ? "" : ",") + num(t[k]);
  }
  test::write_text(dir / "in.json", "{\"positions\":[" + pos + "],\"normals\":[" + nrm + "],\"uvs\":[" + uv + "]}\n");
  const std::string cmd = "node " + shell_quote(std::string(MESO_MIKKTSPACE_DIR) + "/tangents.mjs") + " " +
                          shell_quote((dir / "in.json").string()) + " > " + shell_quote((dir / "out.txt").string()) + " 2> " +
                          shell_quote((dir / "err.txt").string());
  const int rc = std::system(cmd.c_str());
  if (rc != 0) throw std::runtime_error("tangents.mjs failed: " + test::read_text(dir / "err.txt"));
  std::istringstream in(test::read_text(dir / "out.txt"));
  std::vector<std::array<float, 4>> out;
  std::array<float, 4> t{};
  while (in >> t[0] >> t[1] >> t[2] >> t[3]) out.push_back(t);
  return out;
}

struct Agreement {
  size_t corners = 0, compared = 0, sign_mismatches = 0;
  double max_deg = 0, mean_deg = 0;
};

// Compares every corner except those in `skip` (corners where the reference defines no frame).
Agreement compare(const std::string& name, const Mesh& m, const std::set<int>& skip_faces = {}) {
  const auto frames = compute_tangent_frames(m);
  const auto ref = reference_tangents(m);
  const auto order = corner_order(m);
  EXPECT_EQ(ref.size(), order.size());
  Agreement a;
  a.corners = order.size();
  double sum = 0;
  for (size_t c = 0; c < std::min(ref.size(), order.size()); ++c) {
    const auto h = order[c];
    const auto& f = frames[static_cast<size_t>(h.idx())];
    // Every meso frame is finite, unit and in the tangent plane, compared or not.
    EXPECT_TRUE(std::isfinite(f.tangent.sqrnorm()) && std::isfinite(f.sign)) << name << " corner " << c;
    EXPECT_NEAR(f.tangent.norm(), 1.0f, 1e-5f) << name << " corner " << c;
    EXPECT_NEAR(OpenMesh::dot(f.tangent, m.normal(m.to_vertex_handle(h)).normalized()), 0.0f, 1e-5f) << name << " corner " << c;
    if (skip_faces.count(m.face_handle(h).idx())) continue;
    const OpenMesh::Vec3d a3(f.tangent[0], f.tangent[1], f.tangent[2]);
    const OpenMesh::Vec3d r3(ref[c][0], ref[c][1], ref[c][2]);
    const double rl = r3.norm();
    EXPECT_GT(rl, 0.5) << name << " corner " << c << ": the reference has no tangent here";
    if (!(rl > 0.5)) continue;
    const double cosang = std::clamp(OpenMesh::dot(a3, r3) / (a3.norm() * rl), -1.0, 1.0);
    const double deg = std::acos(cosang) * 180.0 / kPi;
    const bool sign_ok = (f.sign < 0) == (ref[c][3] < 0);
    EXPECT_LT(deg, kMaxAngleDeg) << name << " corner " << c << " (face " << m.face_handle(h).idx() << ", vertex "
                                 << m.to_vertex_handle(h).idx() << "): meso (" << f.tangent << ", " << f.sign << ") reference ("
                                 << ref[c][0] << " " << ref[c][1] << " " << ref[c][2] << ", " << ref[c][3] << ")";
    EXPECT_TRUE(sign_ok) << name << " corner " << c << ": sign " << f.sign << " vs reference " << ref[c][3];
    a.sign_mismatches += !sign_ok;
    a.max_deg = std::max(a.max_deg, deg);
    sum += deg;
    ++a.compared;
  }
  a.mean_deg = a.compared ? sum / double(a.compared) : 0;
  std::printf("[ mikktspace ] %-30s corners %4zu compared %4zu  max %.2e deg  mean %.2e deg  sign mismatches %zu\n", name.c_str(),
              a.corners, a.compared, a.max_deg, a.mean_deg, a.sign_mismatches);
  return a;
}

class MikkTSpaceReference : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string why = why_no_reference();
    if (why.empty()) return;
    // scripts/test installs the reference and sets MESO_REQUIRE_PEERS=1: there a missing
    // reference is a failure, so CI cannot pass without comparing against it.
    const char* require = std::getenv("MESO_REQUIRE_PEERS");
    if (require && std::string(require) == "1") FAIL() << "MikkTSpace reference required (MESO_REQUIRE_PEERS=1) but not available: " << why;
    GTEST_SKIP() << "MikkTSpace reference not available: " << why;
  }
};

// ---- the meshes compared ----------------------------------------------------------------------

TEST_F(MikkTSpaceReference, SeamedCube) {
  // Every edge a seam: each corner's frame comes from its own side only.
  compare("seamed cube", test::make_seamed_cube());
}

TEST_F(MikkTSpaceReference, CylinderWithSeam) {
  const Mesh m = test::make_parametric(
      12, 4, [](double s, double t) { return Vec3f(float(std::cos(2 * kPi * s)), float(std::sin(2 * kPi * s)), float(2 * t)); }, true,
      false);
  compare("cylinder (seam)", m);
}

TEST_F(MikkTSpaceReference, TorusWithTwoSeams) {
  const Mesh m = test::make_parametric(
      16, 10,
      [](double s, double t) {
        const double a = 2 * kPi * s, b = 2 * kPi * t, R = 1.0, r = 0.35;
        return Vec3f(float((R + r * std::cos(b)) * std::cos(a)), float((R + r * std::cos(b)) * std::sin(a)), float(r * std::sin(b)));
      },
      true, true);
  compare("torus (two seams)", m);
}

TEST_F(MikkTSpaceReference, UvSphereWithSeamAndPoles) { compare("uv sphere (seam, poles)", uv_sphere(16, 9, 1.5f)); }

// A curved strip with non-uniform (but continuous) UVs, so per-triangle tangents differ
// around each vertex and the weights of the average matter.
TEST_F(MikkTSpaceReference, DistortedUvsOnACurvedSurface) {
  const int n = 8;
  const Mesh m = grid_mesh(
      n, n,
      [&](int i, int j) {
        const double x = double(i) / n, y = double(j) / n;
        return Vec3f(float(x + 0.05 * std::sin(5 * y)), float(y), float(0.3 * std::sin(3 * x) * std::cos(2 * y)));
      },
      [&](int i, int j, int, int) {
        const double s = double(i) / n, t = double(j) / n;
        return Vec2f(float(s + 0.06 * std::sin(7 * t) + 0.04 * s * s), float(t + 0.05 * std::sin(6 * s)));
      });
  compare("distorted uvs, curved", m);
}

// The second half of the strip has mirrored UVs sharing the mirror line (no seam there).
TEST_F(MikkTSpaceReference, MirroredHalfSharingTheMirrorLine) {
  const int n = 8;
  const Mesh m = grid_mesh(
      n, 3,
      [&](int i, int j) {
        const double x = 2.0 * i / n, y = double(j) / 3;
        return Vec3f(float(x), float(y), float(0.25 * std::sin(1.3 * x) + 0.1 * y * y));
      },
      [&](int i, int j, int, int) {
        const double x = 2.0 * i / n;
        return Vec2f(float(0.5 * (x <= 1 ? x : 2 - x)), float(j) / 3.0f);
      });
  compare("mirrored half, shared line", m);
}

// The mirrored half is a separate chart: seam and mirror on the same line.
TEST_F(MikkTSpaceReference, MirroredChartBehindASeam) {
  const int n = 8;
  const Mesh m = grid_mesh(
      n, 3,
      [&](int i, int j) {
        const double x = 2.0 * i / n, y = double(j) / 3;
        return Vec3f(float(x), float(0.2 * std::cos(2 * x) + y), float(0.25 * std::sin(1.3 * x) + 0.1 * y * y));
      },
      [&](int i, int j, int qi, int) {
        const double x = 2.0 * i / n;
        const bool second = qi >= n / 2;  // chart by the quad, so the mirror line splits
        return Vec2f(float(second ? 1.0 - 0.4 * (x - 1) : 0.4 * x), float(j) / 3.0f);
      });
  compare("mirrored chart behind seam", m);
}

// A column of quads whose UVs collapse to a line (u equal on both sides): zero-area UV
// triangles between two ordinary stretches of the same chart. The reference takes the frame
// of the ordinary triangles around each vertex for their corners.
TEST_F(MikkTSpaceReference, CollapsedUvColumn) {
  const int n = 6;
  const Mesh m = grid_mesh(
      n, 4,
      [&](int i, int j) {
        const double x = double(i) / n, y = double(j) / 4;
        return Vec3f(float(x), float(y), float(0.2 * std::sin(3 * x + 2 * y)));
      },
      [&](int i, int j, int, int) {
        const int iu = i <= 2 ? i : i - 1;  // columns 2 and 3 share u
        return Vec2f(float(iu) / 8.0f, float(j) / 4.0f + 0.02f * float(iu));
      });
  compare("collapsed uv column", m);
}

// The same in a mirrored chart: the zero-area triangles take the mirrored frame (sign -1)
// of the ordinary triangles around them.
TEST_F(MikkTSpaceReference, CollapsedUvColumnInAMirroredChart) {
  const int n = 6;
  const Mesh m = grid_mesh(
      n, 4,
      [&](int i, int j) {
        const double x = double(i) / n, y = double(j) / 4;
        return Vec3f(float(x), float(y), float(0.2 * std::sin(3 * x + 2 * y)));
      },
      [&](int i, int j, int, int) {
        const int iu = i <= 2 ? i : i - 1;
        return Vec2f(1.0f - float(iu) / 8.0f, float(j) / 4.0f + 0.02f * float(iu));
      });
  compare("collapsed uv column, mirrored", m);
}

// Two charts meet along a seam but touch in UV space at one vertex, whose corners all carry
// one UV: the reference keeps the two fans apart (they are not connected through an edge
// that is not a seam), so each side gets its own frame.
TEST_F(MikkTSpaceReference, ChartsTouchingAtOneUvPoint) {
  const int n = 6, mid = 3;
  const Mesh m = grid_mesh(
      n, n,
      [&](int i, int j) {
        const double x = double(i) / n, y = double(j) / n;
        return Vec3f(float(x), float(y), float(0.3 * x * x - 0.2 * y * x));
      },
      [&](int i, int j, int qi, int) {
        const float u = float(i) / n, v = float(j) / n;
        if (qi < mid) return Vec2f(u, v);
        // The right chart: its own distortion, equal to the left chart's UV at (mid, mid) only.
        const float d = float(j - mid) / n;
        return Vec2f(u + 0.15f * d * d + 0.1f * float(i - mid) / n, v + 0.2f * float(i - mid) / n * d + 0.05f * d);
      });
  compare("charts touching at a uv point", m);
}

// One triangle whose three corners share one UV, cut off by seams: the reference leaves its
// corners without a frame (not compared); meso gives them a finite frame in the tangent plane.
TEST_F(MikkTSpaceReference, IsolatedDegenerateUvTriangle) {
  const int n = 4;
  const int bad_quad_i = 1, bad_quad_j = 1;
  Mesh m = grid_mesh(
      n, n,
      [&](int i, int j) { return Vec3f(float(i) / n, float(j) / n, float(0.1 * i * j) / n); },
      [&](int i, int j, int, int) { return Vec2f(float(i) / n, float(j) / n); });
  // Face index 2 * (j * n + i) is the quad's first triangle.
  const int bad = 2 * (bad_quad_j * n + bad_quad_i);
  for (auto h : face_halfedges(m, FaceHandle(bad))) m.set_texcoord2D(h, Vec2f(0.3f, 0.3f));
  compare("isolated degenerate uv tri", m, {bad});
}

}  // namespace
}  // namespace meso
