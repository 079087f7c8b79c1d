#include "meso/formats/mesh_io.hpp"

#include "meso/core/error.hpp"
#include "meso/core/mesh_arrays.hpp"
#include "meso/formats/atomic_file.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <charconv>
#include <csignal>

#include <cstdio>
#include <cstring>

#include <limits>
#include <map>
#include <random>

namespace meso {
namespace {

// Per face, the corners' (position, uv) in winding order starting from the smallest
// position, so two meshes compare equal whatever halfedge each face stores first.
std::vector<std::vector<std::pair<Vec3f, Vec2f>>> corners(const Mesh& m) {
  std::vector<std::vector<std::pair<Vec3f, Vec2f>>> out;
  for (auto f : m.faces()) {
    std::vector<std::pair<Vec3f, Vec2f>> c;
    for (auto h : face_halfedges(m, f)) c.push_back({m.point(m.to_vertex_handle(h)), has_uvs(m) ? m.texcoord2D(h) : Vec2f(0, 0)});
    auto less = [](const std::pair<Vec3f, Vec2f>& a, const std::pair<Vec3f, Vec2f>& b) {
      return std::lexicographical_compare(a.first.data(), a.first.data() + 3, b.first.data(), b.first.data() + 3);
    };
    std::rotate(c.begin(), std::min_element(c.begin(), c.end(), less), c.end());
    out.push_back(c);
  }
  return out;
}

// read_mesh must refuse `path` with an InputError whose message holds `expected`.
void expect_refused(const std::filesystem::path& path, const std::string& expected) {
  try {
    read_mesh(path);
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    return;
  }
  ADD_FAILURE() << path << " must be refused (" << expected << ")";
}

class MeshRoundTrip : public ::testing::TestWithParam<std::string> {};

TEST_P(MeshRoundTrip, KeepsPositionsFaceOrderAndSeams) {
  test::TempDir dir;
  const Mesh cube = test::make_seamed_cube();
  const auto path = dir / ("cube" + GetParam());
  write_mesh(cube, path);
  MeshReadReport report;
  const Mesh back = read_mesh(path, &report);
  EXPECT_EQ(back.n_vertices(), 8u) << "welded by position, seams kept on halfedges";
  EXPECT_EQ(back.n_faces(), 12u);
  EXPECT_EQ(report.isolated_faces, 0u);
  ASSERT_TRUE(has_uvs(back));
  const auto a = corners(cube), b = corners(back);
  ASSERT_EQ(a.size(), b.size());
  for (size_t f = 0; f < a.size(); ++f) {
    for (size_t k = 0; k < 3; ++k) {
      EXPECT_EQ(a[f][k].first, b[f][k].first) << "face " << f;
      EXPECT_NEAR(a[f][k].second[0], b[f][k].second[0], 1e-7) << "face " << f;
      EXPECT_NEAR(a[f][k].second[1], b[f][k].second[1], 1e-7) << "face " << f;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Formats, MeshRoundTrip, ::testing::Values(".obj", ".ply", ".gltf", ".glb"));

// OBJ is text: every float must read back bit for bit whatever its scale (OpenMesh's writer
// printed nine decimals, which left a mesh at 1e-6 one or two significant digits and one at
// 1e-30 only zeros). Positions with full mantissas at scales from 1e-12 to 1e7, UVs too.
// (At 1e-30 the text is exact but assimp's fast reader rounds some values by an ulp.)
// A full disk: every writer reports the failed write (exit 4) rather than a file it did not
// complete. /dev/full fails every write with ENOSPC; a link to it gives the extension that
// picks the format. (OpenMesh's PLY writer had ignored the failure: a truncated file, exit 0.)
TEST(MeshIo, AFullDiskFailsEveryWriter) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  test::TempDir dir;
  const Mesh cube = test::make_seamed_cube();
  for (const std::string ext : {".ply", ".obj", ".gltf", ".glb"}) {
    const auto path = dir / ("full" + ext);
    std::filesystem::create_symlink("/dev/full", path);
    try {
      write_mesh(cube, path);
      ADD_FAILURE() << ext << ": the write to a full disk was reported as done";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ExitCode::internal) << ext << ": " << e.what();
    }
  }
}

TEST(MeshIo, ObjKeepsEveryFloatAtAnyScale) {
  test::TempDir dir;
  for (const double scale : {1e-12, 1.2345678e-6, 0.37, 1.0, 3.3e3, 1.7e7}) {
    Mesh m = test::make_seamed_cube();
    for (auto v : m.vertices()) {
      const Vec3f p = m.point(v);
      m.set_point(v, Vec3f(static_cast<float>((p[0] + 0.1234567) * scale), static_cast<float>((p[1] - 0.7654321) * scale),
                           static_cast<float>((p[2] + 1.0 / 3.0) * scale)));
    }
    for (auto h : m.halfedges()) {
      const Vec2f t = m.texcoord2D(h);
      m.set_texcoord2D(h, Vec2f(t[0] / 3.0f + 0.01f, t[1] / 7.0f + 0.3f));
    }
    const auto path = dir / "scaled.obj";
    write_mesh(m, path);
    const Mesh back = read_mesh(path);
    const auto a = corners(m), b = corners(back);
    ASSERT_EQ(a.size(), b.size()) << "scale " << scale;
    for (size_t f = 0; f < a.size(); ++f)
      for (size_t k = 0; k < 3; ++k) {
        EXPECT_EQ(a[f][k].first, b[f][k].first) << "scale " << scale << ", face " << f;
        EXPECT_EQ(a[f][k].second, b[f][k].second) << "scale " << scale << ", face " << f;
      }
  }
}

// Every float written as its shortest text (as write_obj writes it) reads back bit for bit,
// positions and texture coordinates, at every scale: assimp's own parser misreads about one
// in ten of them at 1e-6 (e.g. "9.63967e-06" by one float step), which read_mesh corrects.
TEST(MeshIo, ObjReadsEveryShortestFloatTextExactly) {
  test::TempDir dir;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), uvs(0.0, 1.0);
  std::string text;
  std::vector<Vec3f> positions;
  std::vector<Vec2f> texcoords;
  auto number = [&](float x) {
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, x);
    text += ' ';
    text.append(buf, r.ptr);
  };
  const double scales[] = {1e-12, 1e-6, 3.7e-3, 1.0, 512.0, 1.7e7};
  const int per_scale = 600;  // triangles
  for (const double scale : scales)
    for (int i = 0; i < 3 * per_scale; ++i) {
      // Triangles of their own, each a sliver along x so that none is degenerate.
      const Vec3f p(static_cast<float>(scale * (1.0 + unit(rng))), static_cast<float>(scale * (i % 3 == 1 ? 2.5 : unit(rng) * 0.1)),
                    static_cast<float>(scale * (i % 3 == 2 ? 2.5 : unit(rng) * 0.1)));
      positions.push_back(p);
      text += 'v';
      for (int k = 0; k < 3; ++k) number(p[k]);
      text += '\n';
      const Vec2f t(static_cast<float>(uvs(rng)), static_cast<float>(uvs(rng) * (i % 2 ? 1e-5 : 1.0)));
      texcoords.push_back(t);
      text += "vt";
      for (int k = 0; k < 2; ++k) number(t[k]);
      text += '\n';
    }
  for (size_t f = 0; f < positions.size() / 3; ++f) {
    text += 'f';
    for (size_t k = 1; k <= 3; ++k) text += ' ' + std::to_string(3 * f + k) + '/' + std::to_string(3 * f + k);
    text += '\n';
  }
  test::write_text(dir / "floats.obj", text);
  const Mesh m = read_mesh(dir / "floats.obj");
  ASSERT_EQ(m.n_faces(), positions.size() / 3);
  ASSERT_EQ(m.n_vertices(), positions.size());  // all distinct: vertex i is the file's i-th
  size_t wrong_p = 0, wrong_t = 0;
  for (auto v : m.vertices()) {
    const size_t i = static_cast<size_t>(v.idx());
    for (int c = 0; c < 3; ++c) wrong_p += std::memcmp(&m.point(v)[c], &positions[i][c], sizeof(float)) != 0;
  }
  for (auto h : m.halfedges()) {
    if (m.is_boundary(h)) continue;
    const Vec2f t = m.texcoord2D(h);  // the corner at h's to-vertex
    const size_t i = static_cast<size_t>(m.to_vertex_handle(h).idx());
    for (int c = 0; c < 2; ++c) wrong_t += std::memcmp(&t[c], &texcoords[i][c], sizeof(float)) != 0;
  }
  EXPECT_EQ(wrong_p, 0u) << "of " << 3 * positions.size() << " position values";
  EXPECT_EQ(wrong_t, 0u) << "of " << 2 * texcoords.size() << " texture coordinates";
}

// The corrections never move a value that assimp read right: a vertex whose text assimp reads
// right keeps its value even when another text is misread to the same bits (an unused
// "7.83099e-06" is read as the float of "7.8309895e-06"; an unused 1e20 overflows assimp's
// integer parse to 0), and a text assimp cannot read ("+-1") is refused, naming its line.
TEST(MeshIo, ObjCorrectionsNeverMoveAValueAssimpReadRight) {
  test::TempDir dir;
  for (const char* stray : {"7.83099e-06 0 0", "100000000000000000000 0 0"}) {
    test::write_text(dir / "stray.obj", std::string("v ") + stray + "\nv 7.8309895e-06 0 0\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n"
                                        "f 2/1 4/2 5/3\nf 3/1 4/2 5/3\n");
    const Mesh m = read_mesh(dir / "stray.obj");
    std::vector<float> xs;
    for (auto v : m.vertices()) xs.push_back(m.point(v)[0]);
    EXPECT_NE(std::find(xs.begin(), xs.end(), 7.8309895e-06f), xs.end()) << stray;
    EXPECT_NE(std::find(xs.begin(), xs.end(), 0.0f), xs.end()) << stray;
  }
  // Read correctly rounded, not through a double (2^60 + 2^36 + 1 lies just above the midpoint
  // between two floats; through a double it rounds down twice).
  test::write_text(dir / "mid.obj", "v 1152921573326323713 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\n");
  EXPECT_EQ(read_mesh(dir / "mid.obj").point(VertexHandle(0))[0], 1152921642045800448.0f);
  test::write_text(dir / "sign.obj", "v +-1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\n");
  expect_refused(dir / "sign.obj", "line 1");
}

// OpenMesh leaves a new halfedge's texcoord uninitialised, and nothing sets a boundary
// halfedge's (it has no face, so no corner). OpenMesh's OBJ writer reads them anyway (valgrind
// showed its texcoord map keyed by uninitialised floats), so whatever garbage they hold reached
// the file, and a NaN among them broke the map's order. A face corner then got index 0,
// which readers refuse ("OBJ: Invalid face index", seen once in Cli.FramesWritesACurvatureMap).
// Here the boundary halfedges hold NaN on purpose: the file must read back with every corner's UV.
TEST(MeshIo, ObjIgnoresTheTexcoordsOfBoundaryHalfedges) {
  test::TempDir dir;
  Mesh grid = test::make_parametric(12, 8, [](double s, double t) { return Vec3f(float(s), float(t), 0.0f); }, false, false);
  ASSERT_TRUE(has_uvs(grid));
  size_t boundary = 0;
  for (auto h : grid.halfedges())
    if (grid.is_boundary(h)) {
      // Garbage of two kinds: NaN, and a huge value (each with its own second coordinate).
      const float x = boundary % 2 ? std::numeric_limits<float>::quiet_NaN() : 1e30f;
      grid.set_texcoord2D(h, Vec2f(x, 2.0f + static_cast<float>(boundary++)));
    }
  ASSERT_GT(boundary, 0u);
  const auto path = dir / "grid.obj";
  write_mesh(grid, path);
  const std::string text = test::read_text(path);
  EXPECT_EQ(text.find("nan"), std::string::npos) << "no garbage texcoord in the file";
  size_t vt = 0;
  for (size_t at = text.find("\nvt "); at != std::string::npos; at = text.find("\nvt ", at + 1)) ++vt;
  EXPECT_EQ(vt, 13u * 9u) << "one texcoord per grid point, no more";
  const Mesh back = read_mesh(path);
  ASSERT_EQ(back.n_faces(), grid.n_faces());
  ASSERT_TRUE(has_uvs(back));
  const auto a = corners(grid), b = corners(back);
  for (size_t f = 0; f < a.size(); ++f)
    for (size_t k = 0; k < 3; ++k) {
      EXPECT_EQ(a[f][k].first, b[f][k].first) << "face " << f;
      EXPECT_EQ(a[f][k].second, b[f][k].second) << "face " << f;
    }
}

TEST(MeshIo, GltfCarriesTangents) {
  test::TempDir dir;
  Mesh cube = test::make_seamed_cube();
  const auto prop = add_tangent_property(cube);
  for (auto h : cube.halfedges()) cube.property(prop, h) = OpenMesh::Vec4f(1, 0, 0, -1);
  write_mesh(cube, dir / "cube.gltf");
  const std::string text = test::read_text(dir / "cube.gltf");
  EXPECT_NE(text.find("\"TANGENT\""), std::string::npos);
  EXPECT_NO_THROW(read_mesh(dir / "cube.gltf"));
}

TEST(MeshIo, KeepsFaceOrderOfTheFile) {
  test::TempDir dir;
  // Faces deliberately listed in an order unrelated to their vertices.
  test::write_text(dir / "order.obj",
                   "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\n"
                   "f 2 5 6\nf 1 2 3\nf 2 6 3\nf 1 3 4\n");
  const Mesh m = read_mesh(dir / "order.obj");
  ASSERT_EQ(m.n_faces(), 4u);
  const float expected_min_x[4] = {1, 0, 1, 0};
  for (auto f : m.faces()) {
    float mx = 10;
    for (auto v : m.fv_range(f)) mx = std::min(mx, m.point(v)[0]);
    EXPECT_EQ(mx, expected_min_x[f.idx()]) << "face " << f.idx();
  }
  EXPECT_FALSE(has_uvs(m));
}

TEST(MeshIo, NonManifoldFacesAreKeptAndCounted) {
  test::TempDir dir;
  // Three triangles on one edge (1-2): the third cannot join the manifold mesh.
  test::write_text(dir / "fan.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 1 0 1\nf 1 2 3\nf 2 4 3\nf 2 3 5\n");
  MeshReadReport r;
  const Mesh m = read_mesh(dir / "fan.obj", &r);
  EXPECT_EQ(m.n_faces(), 3u);
  EXPECT_EQ(r.isolated_faces, 1u);
}

TEST(MeshIo, MissingFileIsAnInputErrorNamingIt) {
  try {
    read_mesh("/nonexistent/meso/mesh.obj");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.code(), ExitCode::bad_input);
    EXPECT_NE(std::string(e.what()).find("/nonexistent/meso/mesh.obj"), std::string::npos);
  }
}

// A pipe or a device named as a mesh is refused before it is opened (a FIFO had blocked the
// reader until the timeout).
TEST(MeshIo, PipesAndDevicesAreRefused) {
  test::TempDir dir;
  ASSERT_EQ(::mkfifo((dir / "fifo.obj").c_str(), 0600), 0);
  expect_refused(dir / "fifo.obj", "fifo.obj: is not a regular file (a pipe, socket or device)");
  expect_refused("/dev/zero", "/dev/zero: is not a regular file");
  expect_refused(dir.path(), "is a folder, not a mesh file");
}

TEST(MeshIo, GarbageIsAnInputError) {
  test::TempDir dir;
  test::write_text(dir / "garbage.ply", "this is not a mesh\n\x01\x02\x03");
  EXPECT_THROW(read_mesh(dir / "garbage.ply"), InputError);
  test::write_text(dir / "empty.obj", "# nothing\n");
  EXPECT_THROW(read_mesh(dir / "empty.obj"), InputError);
  // Each named for what it is (assimp had said "Ignoring empty face" and "No suitable reader
  // found for the file format").
  test::write_text(dir / "junk.obj", std::string("v 0 0 0\n\0\x7f\x45\x4c\x46", 13));
  test::write_text(dir / "cut.gltf", R"({"asset": {"version": "2.0"}, "meshes": [)");
  for (const auto& [file, message] : std::vector<std::pair<std::string, std::string>>{
           {"junk.obj", "is not a text file (an OBJ is text)"}, {"cut.gltf", "its glTF JSON does not parse (parse error at line 1, column 42"}}) {
    expect_refused(dir / file, (dir / file).string() + ": " + message);
  }
}

// A glTF whose extension says the other kind (text named .glb, binary named .gltf) is refused
// naming what it is; assimp had said "No suitable reader found for the file format".
TEST(MeshIo, MislabelledGltfIsNamed) {
  test::TempDir dir;
  write_mesh(test::make_seamed_cube(), dir / "cube.glb");
  write_mesh(test::make_seamed_cube(), dir / "cube.gltf");
  std::filesystem::copy_file(dir / "cube.gltf", dir / "text.glb");
  std::filesystem::copy_file(dir / "cube.glb", dir / "binary.gltf");
  expect_refused(dir / "text.glb", (dir / "text.glb").string() + ": is a text (JSON) glTF, not a binary one: name it .gltf");
  expect_refused(dir / "binary.gltf", (dir / "binary.gltf").string() + ": is a binary glTF: name it .glb");
}

// A binary glTF cut short (a download or copy interrupted) is named as such; assimp had said
// "No suitable reader found for the file format". The whole file reads.
TEST(MeshIo, CutShortGlbIsNamed) {
  test::TempDir dir;
  write_mesh(test::make_seamed_cube(), dir / "cube.glb");
  const std::string bytes = test::read_text(dir / "cube.glb");
  ASSERT_GT(bytes.size(), 100u);
  EXPECT_EQ(read_mesh(dir / "cube.glb").n_faces(), test::make_seamed_cube().n_faces());
  for (const auto& [size, message] : std::vector<std::pair<size_t, std::string>>{
           {bytes.size() - 1, "is cut short: its binary glTF header announces " + std::to_string(bytes.size()) + " bytes, the file holds " +
                                  std::to_string(bytes.size() - 1) + " bytes"},
           {8, "is cut short: 8 bytes, less than a binary glTF header (12)"}}) {
    test::write_text(dir / "cut.glb", bytes.substr(0, size));
    expect_refused(dir / "cut.glb", (dir / "cut.glb").string() + ": " + message);
  }
  // The header's length lowered with the file: the JSON chunk now runs past the end.
  std::string cut = bytes.substr(0, 40);
  const uint32_t forty = 40;
  std::memcpy(cut.data() + 8, &forty, 4);
  test::write_text(dir / "cut.glb", cut);
  expect_refused(dir / "cut.glb", (dir / "cut.glb").string() + ": is cut short: its binary glTF chunk at byte 12 announces");
}

// A PLY cut short after three of its nine vertices trips one of assimp's own assertions,
// which aborted the process: it is an unreadable file like any other.
TEST(MeshIo, TruncatedPlyIsAnInputErrorNotAnAbort) {
  test::TempDir dir;
  test::write_text(dir / "cut.ply",
                   "ply\nformat ascii 1.0\nelement vertex 9\nproperty float x\nproperty float y\nproperty float z\n"
                   "element face 8\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n");
  try {
    read_mesh(dir / "cut.ply");
    FAIL() << "a truncated PLY must be refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cut.ply"), std::string::npos) << e.what();
  }
}

// Valid OBJ statements the checks must let through as assimp reads them: a `v` continued on
// the next line with '\\', a coordinate too small for a double (0 to assimp), w and colours.
TEST(MeshIo, ObjContinuationsAndTinyNumbersRead) {
  test::TempDir dir;
  test::write_text(dir / "c.obj", "v 0 0 \\\n0\nv 1e-400 0 0\nv 1 0 0 1\nv 0 1 0 0.5 0.5 0.5\nvt 0 \\\n 0\nvt 1 0\nvt 0 1\nf 1/1 3/2 4/3\n");
  const Mesh m = read_mesh(dir / "c.obj");
  EXPECT_EQ(m.n_faces(), 1u);
  test::write_text(dir / "bad.obj", "v 0 0 0\nv 1 \\\n x 0\nv 0 1 0\nf 1 2 3\n");
  expect_refused(dir / "bad.obj", "line 2: vertex coordinate 'x'");
}

// Extents float arithmetic cannot hold are refused on reading, for every command: at 3e38
// a bake wrote Inf into every texel, at 1e-39 frames wrote Inf curvatures. Within the range,
// and without extent (one point), a mesh is read.
TEST(MeshIo, ExtentsBeyondFloatArithmeticAreRefused) {
  test::TempDir dir;
  const auto triangle = [&](const char* file, double s) {
    char text[256];
    std::snprintf(text, sizeof text, "v 0 0 0\nv %.9g 0 0\nv 0 %.9g 0\nf 1 2 3\n", s, s);
    test::write_text(dir / file, text);
    return dir / file;
  };
  for (const double bad : {3e38, 1e37, 1e-31, 1e-39}) {
    expect_refused(triangle("bad.obj", bad), "that float arithmetic holds");
  }
  for (const double good : {1e35, 1.0, 1e-29, 0.0}) EXPECT_EQ(read_mesh(triangle("good.obj", good)).n_faces(), 1u) << good;
}

// A mesh far from the origin for its size has lost its shape to float rounding when read:
// refused, naming the cause; nearer, the report says how coarse the floats are there (the
// commands warn past kWarnFloatStepPerEdge).
TEST(MeshIo, MeshesTooFarFromTheOriginForTheirSizeAreRefused) {
  test::TempDir dir;
  const Mesh grid = test::make_grid(64, 64, 2.0f, 2.0f);  // edges of 1/32, 8,192 faces
  for (const float offset : {0.0f, 1e4f, 1e6f}) {
    Mesh m = grid;
    for (auto v : m.vertices()) m.set_point(v, m.point(v) + Vec3f(offset, -offset, 0.5f * offset));
    write_mesh(m, dir / "far.obj");
    if (offset == 1e6f) {
      try {
        read_mesh(dir / "far.obj");
        ADD_FAILURE() << "a grid of 1/32-unit edges at 1e6 must be refused (floats step by 0.0625 there)";
      } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("32-bit floats step by 0.0625, and at its median edge"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("far.obj"), std::string::npos) << e.what();
      }
      continue;
    }
    MeshReadReport r;
    EXPECT_EQ(read_mesh(dir / "far.obj", &r).n_faces(), 8192u);
    EXPECT_EQ(r.largest_coordinate, offset == 0 ? 2.0 : static_cast<double>(offset) + 2.0);
    if (offset == 1e4f) {
      EXPECT_EQ(r.step_per_edge, 1.0 / 32);  // steps of 1/1024 on edges of 1/32
    }
    EXPECT_EQ(r.step_per_edge > kWarnFloatStepPerEdge, offset == 1e4f) << offset;
  }
  // Layers stacked in a box (here 20 unit grids, 2^20 units out, where floats step by 1/8 of
  // their edges) are intact: the box and the face count alone (an "edge" of the diagonal over
  // sqrt(faces)) had refused them.
  Mesh layers;
  for (int z = 0; z < 20; ++z) {
    Mesh g = test::make_grid(8, 8, 8.0f, 8.0f);
    std::vector<VertexHandle> at;
    for (auto v : g.vertices()) at.push_back(layers.add_vertex(g.point(v) + Vec3f(1048576.0f, 1048576.0f, static_cast<float>(z))));
    for (auto f : g.faces()) {
      std::vector<VertexHandle> corners;
      for (auto v : g.fv_range(f)) corners.push_back(at[static_cast<size_t>(v.idx())]);
      layers.add_face(corners);
    }
  }
  write_mesh(layers, dir / "layers.obj");
  MeshReadReport r;
  EXPECT_EQ(read_mesh(dir / "layers.obj", &r).n_faces(), 20u * 128u);
  EXPECT_EQ(r.float_step, 0.125);
  EXPECT_EQ(r.step_per_edge, 0.125);
}

// assimp reads an unparsable `vt` value as 0 and, when a face names a `vt` the file lacks,
// drops every UV of the file: both are refused, naming the line.
TEST(MeshIo, ObjTextureCoordinatesAreCheckedNotRepaired) {
  test::TempDir dir;
  const std::string quad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";
  struct Case {
    std::string file, text, message;
  };
  const std::vector<Case> bad = {
      {"nan.obj", quad + "vt 0 0\nvt nan 0\nvt 1 1\nf 1/1 2/2 3/3\n", "line 6: texture coordinate 'nan' is not a finite number"},
      {"inf.obj", quad + "vt 0 0\nvt 1 -inf\nvt 1 1\nf 1/1 2/2 3/3\n", "line 6: texture coordinate '-inf'"},
      {"float.obj", quad + "vt 0 0\nvt 1e39 0\nvt 1 1\nf 1/1 2/2 3/3\n", "line 6: texture coordinate '1e39' is not a finite number (as a float)"},
      // assimp drops a `v` it cannot parse, and the faces then name vertices out of range.
      {"vword.obj", "v 0 0 0\nv abc 0 0\nv 1 1 0\nf 1 2 3\n", "line 2: vertex coordinate 'abc' is not a finite number"},
      {"vshort.obj", "v 0 0 0\nv 1 0\nv 1 1 0\nf 1 2 3\n", "line 2: a vertex needs three coordinates"},
      {"vfloat.obj", "v 0 0 0\nv 1 0 -1e39\nv 1 1 0 # far\nf 1 2 3\n", "line 2: vertex coordinate '-1e39'"},
      {"vnan.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv nan nan nan\nf 1 2 3\n", "line 4: vertex coordinate 'nan'"},
      {"comma.obj", quad + "vt 0 0\nvt 0,5 0\nvt 1 1\nf 1/1 2/2 3/3\n", "line 6: texture coordinate '0,5'"},
      {"range.obj", quad + "vt 0 0\nvt 1 0\nvt 1 1\nf 1/1 2/2 3/3\nf 1/1 3/3 4/9\n",
       "line 9: face corner '4/9' names texture coordinate 9, but the file has 3"},
      // Corners of mixed forms: assimp gave each corner after a bare one the next corner's
      // texture coordinate (or normal).
      {"mixvt.obj", quad + "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2 3/3 4/4\n",
       "line 9: 3 of the face's 4 corners name a texture coordinate (v/vt), the others none"},
      {"mixvn.obj", quad + "vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\nvn 0 1 0\nf 1/1/1 2/2 3/3/2\n",
       "line 10: 2 of the face's 3 corners name a normal (v/vt/vn or v//vn), the others none"},
      {"zero.obj", quad + "vt 0 0\nvt 1 0\nvt 1 1\nf 1/0 2/2 3/3\n", "line 8: face corner '1/0'"},
      {"back.obj", quad + "vt 0 0\nf 1/-1 2/-2 3/-1\n", "line 6: face corner '2/-2' names texture coordinate -2, but the file has 1 before it"},
      // A damaged index, and a control byte shown (a byte flipped in a file: the message had
      // said "names texture coordinate 16, but the file has 324 before it").
      {"junk.obj", quad + "vt 0 0\nvt 1 0\nvt 1 1\nf 1/1 2/2J 3/3\n", "line 8: face corner '2/2J': its texture coordinate index '2J' is not an integer"},
      {"huge.obj", quad + "vt 0 0\nvt 1 0\nvt 1 1\nf 1/1 2/99999999999999999999 3/3\n", "line 8: face corner '2/99999999999999999999': its texture coordinate index '99999999999999999999' is out of range"},
      {"ctrl.obj", "v 0 0 0\nv 1 0 0.\x03" "5\nv 1 1 0\nf 1 2 3\n", "line 2: vertex coordinate '0.\\x035' is not a finite number"},
      // A file cut inside its last face: assimp had read it without that face, exit 0.
      {"cutf.obj", quad + "f 1 2 3\nf \n", "line 6: a face needs at least three vertices"},
      {"cutf2.obj", quad + "f 1 2 3\nf 1 3", "line 6: a face needs at least three vertices"},
      {"baref.obj", quad + "f 1 2 3\nf", "line 6: a face needs at least three vertices"},
  };
  for (const auto& c : bad) {
    test::write_text(dir / c.file, c.text);
    expect_refused(dir / c.file, (dir / c.file).string() + ": " + c.message);
  }
  // Valid: relative indices, `vt` after the faces that name it, comments, v//vn corners, '+'.
  test::write_text(dir / "ok.obj", quad + "vn 0 0 1\nvt 0 0\nvt 1 0 # two\nf 1/-2 2/-1 3/3\nvt +1 1 0\nvt 0 1\nf 1//1 3//1 4//1\n");
  const Mesh m = read_mesh(dir / "ok.obj");
  ASSERT_EQ(m.n_faces(), 2u);
  ASSERT_TRUE(m.has_halfedge_texcoords2D());
  bool saw_third = false;
  for (auto h : m.halfedges())
    if (!m.is_boundary(h) && m.texcoord2D(h) == Vec2f(1, 1)) saw_third = true;
  EXPECT_TRUE(saw_third) << "the forward-referenced vt 3 is (1, 1)";
  // Faces without vt in a textured file: read, and counted (a quad is two triangles).
  test::write_text(dir / "mixed.obj", quad + "vt 0 0\nvt 1 0\nvt 1 1\nf 1/1 2/2 3/3\nf 1 3 4\nf 1 2 3 4\n");
  MeshReadReport report;
  EXPECT_EQ(read_mesh(dir / "mixed.obj", &report).n_faces(), 4u);
  EXPECT_EQ(report.faces_without_uv, 3u);
}

// An ASCII PLY with fewer faces than its header announces: assimp made up the missing face.
TEST(MeshIo, AsciiPlyShortOfItsHeaderIsRefused) {
  test::TempDir dir;
  const std::string header = "ply\nformat ascii 1.0\ncomment made by hand\nelement vertex 4\nproperty float x\nproperty float y\n"
                             "property float z\nelement face 3\nproperty list uchar int vertex_indices\nend_header\n";
  test::write_text(dir / "few.ply", header + "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n");
  expect_refused(dir / "few.ply", "few.ply: cut short: it ends inside face 2 of the 3 its header announces");
  // All three, one a quad (two triangles).
  test::write_text(dir / "ok.ply", header + "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n4 0 1 2 3\n");
  EXPECT_EQ(read_mesh(dir / "ok.ply").n_faces(), 4u);
  // An element without properties takes no tokens, however many it announces (the walk
  // must not count to 10^15).
  std::string junk = header;
  junk.insert(junk.find("element face"), "element junk 999999999999999\n");
  test::write_text(dir / "junk.ply", junk + "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n3 0 1 3\n");
  EXPECT_EQ(read_mesh(dir / "junk.ply").n_faces(), 3u);
  // A face of fewer than three corners (assimp dropped it, or with none said "inconsistent
  // data"), and more data than the header announces (a vertex count too small: the same).
  for (const auto& [file, body, message] : std::vector<std::array<std::string, 3>>{
           {"zero.ply", "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n0\n3 0 2 3\n", "face 1 has 0 corners (a face needs at least three)"},
           {"two.ply", "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n2 0 1\n", "face 2 has 2 corners"},
           {"more.ply", "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n3 0 1 3\n3 1 2 3\n", "has more data than its header announces (from '3' on)"}}) {
    test::write_text(dir / file, header + body);
    expect_refused(dir / file, (dir / file).string() + ": " + message);
  }
}

// A binary PLY whose header announces more than its body can hold: assimp allocated the
// announced 4e9 vertices first (std::bad_alloc); it is cut short, and says so. A binary PLY
// meso wrote still reads.
TEST(MeshIo, BinaryPlyShortOfItsHeaderIsRefused) {
  test::TempDir dir;
  const std::string header = "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\n"
                             "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  test::write_text(dir / "huge.ply", header + std::string(12, '\0'));
  expect_refused(dir / "huge.ply", "huge.ply: cut short: it ends inside vertex 1 of the 4000000000 its header announces");
  write_mesh(test::make_grid(2, 2), dir / "grid.ply");
  EXPECT_EQ(read_mesh(dir / "grid.ply").n_faces(), 8u);
  // The same file without its last face's bytes.
  std::string cut = test::read_text(dir / "grid.ply");
  cut.resize(cut.size() - 13);
  test::write_text(dir / "cut.ply", cut);
  expect_refused(dir / "cut.ply", "cut.ply: cut short: it ends inside face 7 of the 8");
  // A binary face of two corners: its count byte 3 -> 2 (and one index fewer).
  std::string two = test::read_text(dir / "grid.ply");
  two.resize(two.size() - 4);
  two[two.size() - 9] = 2;
  test::write_text(dir / "two.ply", two);
  expect_refused(dir / "two.ply", (dir / "two.ply").string() + ": face 7 has 2 corners");
}

// Files assimp reads by repairing them, saying so only in its log: a glTF face indexing past
// the vertices (dropped) and an OFF face doing so (pointed elsewhere) are refused; an OFF with
// fewer faces than its header says is named as such.
TEST(MeshIo, FilesAssimpWouldRepairAreRefused) {
  test::TempDir dir;
  // Two triangles over four vertices, the second's last index 9: (0 1 2) (0 2 9).
  test::write_text(dir / "oor.gltf",
                   R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],)"
                   R"( "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}], "buffers": [{"byteLength": 72,)"
                   R"( "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAACAPwAAgD8AAAAAAAAAAAAAgD8AAAAA)"
                   R"(AAAAAAEAAAACAAAAAAAAAAIAAAAJAAAA"}], "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48},)"
                   R"( {"buffer": 0, "byteOffset": 48, "byteLength": 24}], "accessors": [{"bufferView": 0, "componentType": 5126,)"
                   R"( "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}, {"bufferView": 1, "componentType": 5125,)"
                   R"( "count": 6, "type": "SCALAR"}]})");
  test::write_text(dir / "oor.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 7\n");
  test::write_text(dir / "few.off", "OFF\n4 3 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"oor.gltf", "oor.gltf: damaged, not read (assimp: Some faces had out-of-range indices"},
      {"oor.off", "oor.off: damaged, not read (assimp: OFF: Vertex index is out of range)"},
      {"few.off", "few.off: cannot read mesh: OFF: The number of faces in the header is incorrect"},
  };
  for (const auto& [file, message] : cases) {
    expect_refused(dir / file, message);
  }
  // The same glTF with the index in range (9 -> 3, the byte before the closing "AAAA") reads.
  std::string good = test::read_text(dir / "oor.gltf");
  const size_t at = good.find("AAAAJAAAA");
  ASSERT_NE(at, std::string::npos);
  good.replace(at, 9, "AAAADAAAA");
  test::write_text(dir / "ok.gltf", good);
  EXPECT_EQ(read_mesh(dir / "ok.gltf").n_faces(), 2u);
  // assimp logs a missing material file as an error, but the geometry is whole: it reads.
  test::write_text(dir / "nomtl.obj", "mtllib missing.mtl\nusemtl foo\nv 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n");
  EXPECT_EQ(read_mesh(dir / "nomtl.obj").n_faces(), 1u);
  // ... and does not hide the real problem of a file that fails.
  test::write_text(dir / "nomtl_bad.obj", "mtllib missing.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 9\n");
  expect_refused(dir / "nomtl_bad.obj", "nomtl_bad.obj: cannot read mesh: OBJ: vertex index out of range");
}

// An OBJ with a UTF-8 byte-order mark reads (assimp missed its first line); one without
// faces says so (assimp: "Validation failed: Mesh  contains no faces").
TEST(MeshIo, ObjWithAByteOrderMarkReadsAndOneWithoutFacesSaysSo) {
  test::TempDir dir;
  test::write_text(dir / "bom.obj", "\xEF\xBB\xBFv 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nf 1/1 2/2 3/3\n");
  const Mesh m = read_mesh(dir / "bom.obj");
  EXPECT_EQ(m.n_faces(), 1u);
  EXPECT_TRUE(has_uvs(m));
  test::write_text(dir / "nofaces.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\n");
  try {
    read_mesh(dir / "nofaces.obj");
    ADD_FAILURE() << "a mesh without faces must be refused";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), (dir / "nofaces.obj").string() + ": contains no faces");
  }
}

TEST(MeshIo, NanCoordinateIsAnInputError) {
  test::TempDir dir;
  test::write_text(dir / "nan.obj", "v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n");
  try {
    read_mesh(dir / "nan.obj");
    FAIL() << "a NaN vertex must be refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("line 3: vertex coordinate 'nan' is not a finite number"), std::string::npos) << e.what();
  }
}

TEST(OutputSet, RemovesFoldersItCreatedWhenNotCommitted) {
  test::TempDir dir;
  {
    OutputSet out;
    out.write_text(dir / "a" / "b" / "report.json", "{}");
    EXPECT_TRUE(std::filesystem::exists(dir / "a" / "b"));
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "a"));
  EXPECT_TRUE(std::filesystem::exists(dir.path()));
}

TEST(OutputSet, AFolderIsNotAnOutputFile) {
  test::TempDir dir;
  std::filesystem::create_directories(dir / "taken.obj");
  OutputSet out;
  EXPECT_THROW(out.add(dir / "taken.obj"), UsageError);
  // Nor is a file a folder to write into.
  test::write_text(dir / "file", "x");
  EXPECT_THROW(out.add(dir / "file" / "maps" / "displacement.exr"), UsageError);
}

// An interrupt (SIGINT, SIGTERM, SIGHUP) during a run removes its temporaries and the
// folders it created, then ends the process by that signal. In a child process: it lists a
// written temporary in new nested folders and one in the existing folder, then signals
// itself; a committed output of an earlier set stays.
TEST(OutputSet, AnInterruptRemovesTheTemporaries) {
  test::TempDir dir;
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      remove_outputs_on_signals();
      {
        OutputSet kept;
        kept.write_text(dir / "kept.json", "{}");
        kept.commit();
      }
      OutputSet out;
      out.write_text(dir / "new" / "deeper" / "report.json", "{}");
      out.write_text(dir / "here.json", "{}");
      // As many as the largest set a command makes (preview --turntable 3600): every one is
      // listed for the handler (256 were, and an interrupted turntable left the rest).
      if (sig == SIGINT)
        for (int i = 0; i < 3600; ++i) out.write_text(dir / "frames" / ("f" + std::to_string(i) + ".png"), "x");
      ::raise(sig);
      ::_exit(99);  // not reached: the default action ends the process
    }
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == sig) << "signal " << sig << ", status " << status;
    std::vector<std::string> left;
    for (const auto& e : std::filesystem::directory_iterator(dir.path())) left.push_back(e.path().filename().string());
    EXPECT_EQ(left, std::vector<std::string>{"kept.json"}) << "signal " << sig;
  }
}

TEST(OutputSet, LeavesNothingWithoutCommit) {
  test::TempDir dir;
  {
    OutputSet out;
    write_mesh(test::make_seamed_cube(), out.add(dir / "a.obj"));
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
  {
    OutputSet out;
    write_mesh(test::make_seamed_cube(), out.add(dir / "b.obj"));
    out.commit();
  }
  EXPECT_TRUE(std::filesystem::exists(dir / "b.obj"));
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), {}), 1);
}

}  // namespace
}  // namespace meso

#include <nlohmann/json.hpp>

namespace meso {
namespace {

// glTF nodes with transforms: import flattens the hierarchy and names the face group after
// the mesh (or node).
TEST(MeshIo, FlattensNodeTransformsAndKeepsNames) {
  test::TempDir dir;
  write_mesh(test::make_seamed_cube(), dir / "cube.gltf");
  auto doc = nlohmann::json::parse(test::read_text(dir / "cube.gltf"));
  doc["meshes"][0]["name"] = "crate_high";
  // A parent translating by (10, 0, 0) and a child scaling by 2.
  doc["nodes"] = {{{"name", "parent"}, {"translation", {10.0, 0.0, 0.0}}, {"children", {1}}},
                  {{"name", "child"}, {"scale", {2.0, 2.0, 2.0}}, {"mesh", 0}}};
  test::write_text(dir / "nested.gltf", doc.dump());
  const Mesh m = read_mesh(dir / "nested.gltf");
  const Box3 b = bounding_box(m);
  EXPECT_EQ(b.lo, Vec3f(10, 0, 0));
  EXPECT_EQ(b.hi, Vec3f(12, 2, 2));
  ASSERT_EQ(group_names(m).size(), 1u);
  EXPECT_EQ(group_names(m)[0], "crate_high");
}

TEST(MeshIo, ReadsColladaInItsOwnCoordinates) {
  test::TempDir dir;
  // One triangle under a node translated by (0, 0, 5), in a Z_UP file.
  test::write_text(dir / "tri.dae", R"(<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="meter" meter="1"/><up_axis>Z_UP</up_axis></asset>
  <library_geometries>
    <geometry id="tri" name="tri_low"><mesh>
      <source id="pos"><float_array id="pos-a" count="9">0 0 0 1 0 0 0 1 0</float_array>
        <technique_common><accessor source="#pos-a" count="3" stride="3">
          <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
        </accessor></technique_common></source>
      <vertices id="v"><input semantic="POSITION" source="#pos"/></vertices>
      <triangles count="1"><input semantic="VERTEX" source="#v" offset="0"/><p>0 1 2</p></triangles>
    </mesh></geometry>
  </library_geometries>
  <library_visual_scenes><visual_scene id="s">
    <node id="n" name="n"><translate>0 0 5</translate><instance_geometry url="#tri"/></node>
  </visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>
)");
  const Mesh m = read_mesh(dir / "tri.dae");
  ASSERT_EQ(m.n_faces(), 1u);
  const Box3 b = bounding_box(m);
  EXPECT_EQ(b.lo, Vec3f(0, 0, 5));
  EXPECT_EQ(b.hi, Vec3f(1, 1, 5));
}

// assimp's PLY reader never returned from a header without end_header (every command hung).
TEST(MeshIo, PlyWithoutTheEndOfItsHeaderIsRefused) {
  test::TempDir dir;
  test::write_text(dir / "h.ply", "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n");
  expect_refused(dir / "h.ply", (dir / "h.ply").string() + ": its header has no end_header line");
}

// A node that mirrors (a negative scale) turns the winding: meso turns the triangles back,
// so the mirrored cube still faces outwards, and its faces agree with the file's normals
// (carried over by the inverse transpose). Before, it came in inside out.
TEST(MeshIo, MirroringNodesKeepTheFacesOutwards) {
  test::TempDir dir;
  write_mesh(test::make_seamed_cube(), dir / "cube.gltf");
  auto doc = nlohmann::json::parse(test::read_text(dir / "cube.gltf"));
  for (const auto& scale : {std::vector<double>{1, 1, 1}, {-1, 1, 1}, {-1, -1, -1}, {-1, -2, 1}, {1, 3, -0.5}}) {
    doc["nodes"] = {{{"name", "n"}, {"scale", scale}, {"mesh", 0}}};
    test::write_text(dir / "m.gltf", doc.dump());
    Mesh m = read_mesh(dir / "m.gltf");
    ASSERT_EQ(m.n_faces(), 12u);
    const Box3 b = bounding_box(m);
    const Vec3f centre = (b.lo + b.hi) * 0.5f;
    m.request_face_normals();
    m.update_face_normals();
    for (auto f : m.faces()) {
      Vec3f c(0, 0, 0);
      for (auto v : m.fv_range(f)) c += m.point(v) / 3.0f;
      EXPECT_GT(OpenMesh::dot(m.normal(f), c - centre), 0.0f) << "scale " << scale[0] << " " << scale[1] << " " << scale[2];
      for (auto v : m.fv_range(f)) EXPECT_GT(OpenMesh::dot(m.normal(f), m.normal(v)), 0.0f) << "the file's normals";
    }
  }
}

double triangle_area_z(const Mesh& m, FaceHandle f) {  // signed, seen from +z
  std::vector<Vec3f> p;
  for (auto v : m.fv_range(f)) p.push_back(m.point(v));
  return 0.5 * ((static_cast<double>(p[1][0]) - p[0][0]) * (static_cast<double>(p[2][1]) - p[0][1]) -
                (static_cast<double>(p[1][1]) - p[0][1]) * (static_cast<double>(p[2][0]) - p[0][0]));
}

// Polygons are split into triangles of their own winding that cover them once. assimp's
// split folded the L-shaped hexagon (four triangles over an area of 4, one facing back); 200
// random star-shaped polygons check the ear clipping that replaced it: every triangle faces
// +z and the areas sum to the polygon's (shoelace). A convex polygon is the fan from its
// first corner.
TEST(MeshIo, PolygonsAreSplitIntoTrianglesThatCoverThemOnce) {
  test::TempDir dir;
  test::write_text(dir / "l.obj", "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 1 1 0\nv 1 2 0\nv 0 2 0\nf 1 2 3 4 5 6\n");
  test::write_text(dir / "l.ply", "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\n"
                                  "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                                  "0 0 0\n2 0 0\n2 1 0\n1 1 0\n1 2 0\n0 2 0\n6 0 1 2 3 4 5\n");
  for (const char* file : {"l.obj", "l.ply"}) {
    const Mesh m = read_mesh(dir / file);
    ASSERT_EQ(m.n_faces(), 4u) << file;
    double area = 0;
    for (auto f : m.faces()) {
      EXPECT_GT(triangle_area_z(m, f), 0.0) << file;
      area += triangle_area_z(m, f);
    }
    EXPECT_EQ(area, 3.0) << file;
  }
  // Star-shaped polygons of 4 to 9 corners at random radii, polygon k in the plane z = k:
  // corner i at an angle within 0.45 steps of i steps of 2 pi / n, so that no two corners are
  // half a turn apart or more (the polygon is simple: it sees the origin).
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> radius(0.1, 1.0), jitter(-0.45, 0.45);
  std::string obj;
  std::vector<double> areas;
  int first = 1;
  for (int k = 0; k < 200; ++k) {
    const int n = 4 + k % 6;
    std::vector<double> angles;
    for (int i = 0; i < n; ++i) angles.push_back(2 * M_PI * (i + jitter(rng)) / n);
    // Float coordinates, so that the shoelace below sees what the file holds. (Kept as floats:
    // GCC 12.2 at -O2 dropped the rounding of static_cast<float> values packed into a pair of
    // doubles.)
    std::vector<std::array<float, 2>> p;
    for (const double a : angles) {
      const double r = radius(rng);
      p.push_back({static_cast<float>(r * std::cos(a)), static_cast<float>(r * std::sin(a))});
    }
    double area = 0;
    for (int i = 0; i < n; ++i) {
      const auto& [x0, y0] = p[static_cast<size_t>(i)];
      const auto& [x1, y1] = p[static_cast<size_t>((i + 1) % n)];
      area += 0.5 * (static_cast<double>(x0) * y1 - static_cast<double>(x1) * y0);
    }
    areas.push_back(area);
    char line[96];
    for (const auto& [x, y] : p) {
      std::snprintf(line, sizeof line, "v %.9g %.9g %d\n", static_cast<double>(x), static_cast<double>(y), k);
      obj += line;
    }
    obj += "f";
    for (int i = 0; i < n; ++i) obj += " " + std::to_string(first + i);
    obj += "\n";
    first += n;
  }
  // A convex pentagon last: the fan from its first corner.
  obj += "v 0 0 500\nv 1 0 500\nv 1.5 1 500\nv 0.5 1.8 500\nv -0.5 1 500\nf " + std::to_string(first) + " " + std::to_string(first + 1) + " " +
         std::to_string(first + 2) + " " + std::to_string(first + 3) + " " + std::to_string(first + 4) + "\n";
  test::write_text(dir / "stars.obj", obj);
  const Mesh m = read_mesh(dir / "stars.obj");
  std::vector<double> sum(areas.size(), 0.0);
  size_t backwards = 0;
  for (auto f : m.faces()) {
    const double a = triangle_area_z(m, f);
    backwards += a < 0;
    const auto z = static_cast<size_t>(m.point(m.to_vertex_handle(m.halfedge_handle(f)))[2]);
    if (z < sum.size()) sum[z] += a;
  }
  EXPECT_EQ(backwards, 0u);
  for (size_t k = 0; k < areas.size(); ++k) EXPECT_NEAR(sum[k], areas[k], 1e-6 * std::abs(areas[k])) << "polygon " << k;
  // The pentagon's three faces are the last, in fan order: (0, 1, 2), (0, 2, 3), (0, 3, 4).
  std::vector<std::vector<float>> xs;
  for (auto f : m.faces()) {
    std::vector<float> x;
    for (auto v : m.fv_range(f)) x.push_back(m.point(v)[0]);
    std::rotate(x.begin(), std::min_element(x.begin(), x.end()), x.end());
    xs.push_back(x);
  }
  ASSERT_GE(xs.size(), 3u);
  EXPECT_EQ(xs[xs.size() - 3], (std::vector<float>{0.0f, 1.0f, 1.5f}));
  EXPECT_EQ(xs[xs.size() - 2], (std::vector<float>{0.0f, 1.5f, 0.5f}));
  EXPECT_EQ(xs[xs.size() - 1], (std::vector<float>{-0.5f, 0.0f, 0.5f}));
}

// What assimp's glTF reader would misread is refused, naming the cause: a required extension
// it does not implement, normalised-integer texture coordinates. Extensions of materials pass.
TEST(MeshIo, GltfItCannotReadRightIsRefused) {
  test::TempDir dir;
  write_mesh(test::make_seamed_cube(), dir / "cube.gltf");
  const auto base = nlohmann::json::parse(test::read_text(dir / "cube.gltf"));
  auto doc = base;
  doc["extensionsUsed"] = {"EXT_meshopt_compression"};
  doc["extensionsRequired"] = {"EXT_meshopt_compression"};
  test::write_text(dir / "meshopt.gltf", doc.dump());
  doc = base;
  const size_t uv = doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"].get<size_t>();
  doc["accessors"][uv]["componentType"] = 5121;
  doc["accessors"][uv]["normalized"] = true;
  test::write_text(dir / "u8.gltf", doc.dump());
  for (const auto& [file, message] : std::vector<std::pair<std::string, std::string>>{
           {"meshopt.gltf", "requires the glTF extension EXT_meshopt_compression, which meso cannot read"},
           {"u8.gltf", "mesh 0 stores TEXCOORD_0 as unsigned bytes, which meso's glTF reader (assimp 5.2) misreads"}}) {
    expect_refused(dir / file, (dir / file).string() + ": " + message);
  }
  doc = base;
  doc["extensionsUsed"] = {"KHR_materials_emissive_strength"};
  doc["extensionsRequired"] = {"KHR_materials_emissive_strength"};
  test::write_text(dir / "material.gltf", doc.dump());
  EXPECT_EQ(read_mesh(dir / "material.gltf").n_faces(), 12u);
}

TEST(MeshIo, ReadsOff) {
  test::TempDir dir;
  test::write_text(dir / "quad.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n");
  const Mesh m = read_mesh(dir / "quad.off");
  EXPECT_EQ(m.n_faces(), 2u) << "the quad is triangulated in place";
  EXPECT_EQ(m.n_vertices(), 4u);
}

}  // namespace
}  // namespace meso
