#include "meso/bake/displacement_stream.hpp"

#include "meso/core/error.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <sys/stat.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace meso {
namespace {

// A high plane z = a x + b y + c over a wide area (two triangles).
Mesh plane(float a, float b, float c) {
  Mesh m;
  auto at = [&](float x, float y) { return m.add_vertex(Vec3f(x, y, a * x + b * y + c)); };
  const auto p0 = at(-2, -2), p1 = at(3, -2), p2 = at(3, 3), p3 = at(-2, 3);
  m.add_face(p0, p1, p2);
  m.add_face(p0, p2, p3);
  compute_angle_weighted_normals(m);
  return m;
}

// Over a flat base (normal +z) and a high plane, every sample is the plane's height above
// its point, and the coarser level's interpolation of a linear function is exact too.
TEST(DisplacementStream, PlaneIsSampledExactlyAtEveryLevel) {
  const Mesh base = test::make_grid(3, 2);
  const float a = 0.02f, b = -0.01f, c = 0.003f;
  DisplacementStreamOptions o;
  o.levels = 4;
  const DisplacementStream s = sample_displacement_stream(base, plane(a, b, c), o);
  ASSERT_EQ(s.levels.size(), 4u);
  EXPECT_EQ(s.misses, 0u);
  for (const DisplacementLevel& level : s.levels) {
    const int n = level.segments;
    for (int t = 0; t < s.triangles; ++t) {
      const auto hs = face_halfedges(base, FaceHandle(t));
      Vec3f corner[3];
      for (int k = 0; k < 3; ++k) corner[k] = base.point(base.to_vertex_handle(hs[static_cast<size_t>(k)]));
      int k = 0;
      for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n - i; ++j, ++k) {
          const Vec3f p = corner[0] * (static_cast<float>(n - i - j) / n) + corner[1] * (static_cast<float>(i) / n) +
                          corner[2] * (static_cast<float>(j) / n);
          const float expect = a * p[0] + b * p[1] + c;
          const size_t at = static_cast<size_t>(t * level.vertices_per_triangle() + k);
          EXPECT_NEAR(level.value[at], expect, 1e-6f) << "level " << n << " t " << t << " (" << i << "," << j << ")";
          EXPECT_NEAR(level.coarse[at], expect, 1e-6f);
        }
    }
  }
}

// A high mesh whose open border lies exactly over the base's (the base grid lifted by 0.01):
// the samples on the border found no hit about half the time and were stored as 0, a dip to
// the base along two edges; every sample is 0.01.
TEST(DisplacementStream, BorderOverBorderIsFound) {
  const Mesh base = test::make_grid(4, 4);
  Mesh high = base;
  for (auto v : high.vertices()) high.set_point(v, high.point(v) + Vec3f(0, 0, 0.01f));
  DisplacementStreamOptions o;
  o.levels = 3;
  const DisplacementStream s = sample_displacement_stream(base, high, o);
  EXPECT_EQ(s.misses, 0u);
  for (const DisplacementLevel& level : s.levels)
    for (const float v : level.value) ASSERT_NEAR(v, 0.01f, 1e-6f);
}

// Far from unit size (near 1e20 every ray left Embree's range) the samples are those of the
// unit-size meshes, scaled.
TEST(DisplacementStream, AnyScaleAFloatHolds) {
  for (const int e : {66, -66}) {
    const float s = std::ldexp(1.0f, e);
    Mesh base = test::make_grid(4, 4);
    Mesh high = base;
    for (auto v : high.vertices()) high.set_point(v, (high.point(v) + Vec3f(0, 0, 0.01f)) * s);
    for (auto v : base.vertices()) base.set_point(v, base.point(v) * s);
    DisplacementStreamOptions o;
    o.levels = 2;
    const DisplacementStream st = sample_displacement_stream(base, high, o);
    EXPECT_EQ(st.misses, 0u) << e;
    for (const DisplacementLevel& level : st.levels)
      for (const float v : level.value) ASSERT_NEAR(v / s, 0.01f, 1e-6f) << e;
  }
}

// Two triangles sharing an edge compute the same value at every point of it, bit for bit,
// over a curved base and a bumpy high surface (coordinates that float arithmetic rounds
// differently depending on which end of the edge it starts from): crack-free tessellation.
TEST(DisplacementStream, SharedEdgesAgreeBitForBit) {
  auto band = [](int columns, int rows, double bump) {
    return test::make_parametric(
        columns, rows,
        [bump](double u, double v) {
          const double a = 2.3 * u, b = 0.4 + 1.1 * v, r = 1.3 + bump * std::sin(17 * u) * std::cos(13 * v);
          return Vec3f(static_cast<float>(r * std::sin(b) * std::cos(a)), static_cast<float>(r * std::sin(b) * std::sin(a)),
                       static_cast<float>(r * std::cos(b)));
        },
        false, false);
  };
  const Mesh base = band(7, 5, 0.0), high = band(160, 120, 0.01);
  DisplacementStreamOptions o;
  o.levels = 6;
  const DisplacementStream s = sample_displacement_stream(base, high, o);
  const DisplacementLevel& level = s.levels.back();
  const int n = level.segments;
  // Per undirected base edge, the values along it from each side, in the edge's own order.
  std::map<std::pair<int, int>, std::vector<float>> seen;
  int shared = 0;
  for (int t = 0; t < s.triangles; ++t) {
    const auto hs = face_halfedges(base, FaceHandle(t));
    int corner[3];
    for (int q = 0; q < 3; ++q) corner[q] = base.to_vertex_handle(hs[static_cast<size_t>(q)]).idx();
    auto value = [&](int i, int j) {
      int k = 0;
      for (int a = 0; a < i; ++a) k += n + 1 - a;
      return level.value[static_cast<size_t>(t * level.vertices_per_triangle() + k + j)];
    };
    // Edge (corner p -> corner q) as (i, j) positions, walked from the lower vertex index.
    const std::array<std::array<int, 2>, 3> edges{{{0, 1}, {1, 2}, {2, 0}}};
    for (const auto& e : edges) {
      int p = e[0], q = e[1];
      if (corner[q] < corner[p]) std::swap(p, q);
      std::vector<float> values;
      for (int step = 0; step <= n; ++step) {
        // Weights: corner p gets n - step, corner q gets step.
        int w[3] = {0, 0, 0};
        w[p] = n - step;
        w[q] = step;
        values.push_back(value(w[1], w[2]));
      }
      const auto [it, fresh] = seen.emplace(std::pair{corner[p], corner[q]}, values);
      if (!fresh) {
        ++shared;
        EXPECT_EQ(it->second, values) << "edge " << corner[p] << "-" << corner[q];
      }
    }
  }
  EXPECT_GT(shared, 40);
}

TEST(DisplacementStream, EncodedVerticesAreEightBytesWithinTheirBound) {
  const Mesh base = test::make_grid(2, 2);
  DisplacementStreamOptions o;
  o.levels = 3;
  const DisplacementStream s = sample_displacement_stream(base, plane(0.05f, 0.0f, -0.01f), o);
  const EncodedStream e = encode_displacement_stream(s);
  const double bound = (s.max_value - s.min_value) / (2.0 * kDisplacementSteps);
  EXPECT_LE(e.max_error, bound * 1.0001 + 1e-9);
  EXPECT_GT(e.max_error, 0.0);
  for (size_t l = 0; l < e.vertices.size(); ++l) {
    const int n = e.segments[l];
    size_t k = 0;
    for (int t = 0; t < s.triangles; ++t)
      for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n - i; ++j, ++k) {
          const DecodedVertex d = decode_vertex(e.vertices[l][k], e.min_value, e.max_value);
          EXPECT_EQ(d.triangle, static_cast<uint32_t>(t));
          EXPECT_EQ(d.i, i);
          EXPECT_EQ(d.j, j);
          EXPECT_NEAR(d.value, s.levels[l].value[k], bound * 1.0001);
        }
  }
  test::TempDir dir;
  write_displacement_stream(e, static_cast<int>(base.n_vertices()), static_cast<int>(base.n_faces()), (dir / "d.bin").string());
  size_t expected = 8 + 4 * 4 + 8;
  for (const auto& level : e.vertices) expected += 8 + 8 * level.size();
  EXPECT_EQ(std::filesystem::file_size(dir / "d.bin"), expected);
}

// The file reads back exactly; decoding gives P + d N within the quantisation bound; morph 0
// gives the coarser level's own positions bit for bit at the vertices the levels share.
TEST(DisplacementStream, FileRoundTripAndDecodedLevelsMorphToTheCoarserOne) {
  // A curved base (a piece of cylinder) under a tilted high plane.
  const Mesh base = test::make_parametric(
      3, 2, [](double u, double v) { return Vec3f(static_cast<float>(std::cos(1.2 * u)), static_cast<float>(std::sin(1.2 * u)), static_cast<float>(v)); },
      false, false);
  DisplacementStreamOptions o;
  o.levels = 4;
  const DisplacementStream s = sample_displacement_stream(base, plane(0.1f, 0.05f, 0.2f), o);
  const EncodedStream e = encode_displacement_stream(s);
  test::TempDir dir;
  const std::string file = (dir / "d.bin").string();
  write_displacement_stream(e, static_cast<int>(base.n_vertices()), static_cast<int>(base.n_faces()), file);
  int nv = 0, nt = 0;
  const EncodedStream r = read_displacement_stream(file, &nv, &nt);
  EXPECT_EQ(nv, static_cast<int>(base.n_vertices()));
  EXPECT_EQ(nt, static_cast<int>(base.n_faces()));
  EXPECT_EQ(r.min_value, e.min_value);
  EXPECT_EQ(r.max_value, e.max_value);
  EXPECT_EQ(r.segments, e.segments);
  EXPECT_EQ(r.vertices, e.vertices);

  const double bound = (s.max_value - s.min_value) / (2.0 * kDisplacementSteps);
  for (int l = 0; l < 4; ++l) {
    const std::vector<Vec3f> fine = decode_displacement_level(base, r, l);
    const int n = r.segments[static_cast<size_t>(l)];
    size_t k = 0;
    for (int t = 0; t < s.triangles; ++t)
      for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n - i; ++j, ++k) {
          OpenMesh::Vec3d p, nn;
          displacement_stream_point(base, t, n, i, j, p, nn);
          const OpenMesh::Vec3d exact = p + nn.normalized() * static_cast<double>(s.levels[static_cast<size_t>(l)].value[k]);
          EXPECT_LE((OpenMesh::vector_cast<OpenMesh::Vec3d>(fine[k]) - exact).norm(), bound + 1e-6) << l << " " << k;
        }
    if (l == 0) continue;
    const std::vector<Vec3f> morphed = decode_displacement_level(base, r, l, 0.0f), coarse = decode_displacement_level(base, r, l - 1);
    const int c = n / 2, per = (n + 1) * (n + 2) / 2, cper = (c + 1) * (c + 2) / 2;
    for (int t = 0; t < s.triangles; ++t)
      for (int i = 0, k2 = 0; i <= n; ++i)
        for (int j = 0; j <= n - i; ++j, ++k2)
          if (i % 2 == 0 && j % 2 == 0) {
            const int ci = i / 2, cj = j / 2, ck = ci * (c + 1) - ci * (ci - 1) / 2 + cj;
            EXPECT_EQ(morphed[static_cast<size_t>(t * per + k2)], coarse[static_cast<size_t>(t * cper + ck)]) << l << " " << t << " " << i << "," << j;
          }
  }

  // Bad files: one InputError naming the file.
  for (const auto& [bytes, what] : std::vector<std::pair<std::string, std::string>>{
           {"MESODSTX", "magic"}, {std::string("MESODSTR\x01\0\0\0", 12), "truncated"}}) {
    const std::string bad = (dir / "bad.bin").string();
    std::ofstream(bad, std::ios::binary) << bytes;
    try {
      read_displacement_stream(bad, &nv, &nt);
      ADD_FAILURE() << what;
    } catch (const InputError& err) {
      EXPECT_NE(std::string(err.what()).find(bad), std::string::npos) << what;
    }
  }
  EXPECT_THROW(read_displacement_stream((dir / "none.bin").string(), &nv, &nt), InputError);

  // A good file with bytes appended, with its level count lowered (the finest level had been
  // dropped without a word), or with a range whose span overflows a float (decoded to
  // infinite displacements); and a pipe (it had blocked the reader).
  const std::string good = test::read_text(file);
  std::string lowered = good;
  lowered[12] = 3;  // level count: bytes 12-15, after the magic and the version
  std::string wide = good;
  const float lo = -3e38f, hi = 3e38f;
  std::memcpy(&wide[24], &lo, 4);  // the range: after the level, vertex and triangle counts
  std::memcpy(&wide[28], &hi, 4);
  for (const auto& [bytes, what] : std::vector<std::pair<std::string, std::string>>{
           {good + "x", "has data past the end of its last level (level count 4)"},
           {lowered, "has data past the end of its last level (level count 3)"},
           {wide, "its quantisation range spans more than the float range"}}) {
    const std::string bad = (dir / "bad.bin").string();
    test::write_text(bad, bytes);
    try {
      read_displacement_stream(bad, &nv, &nt);
      ADD_FAILURE() << what;
    } catch (const InputError& err) {
      EXPECT_EQ(std::string(err.what()), bad + ": " + what);
    }
  }
  const std::string fifo = (dir / "fifo.bin").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  try {
    read_displacement_stream(fifo, &nv, &nt);
    ADD_FAILURE() << "fifo";
  } catch (const InputError& err) {
    EXPECT_EQ(std::string(err.what()), fifo + ": is not a regular file (a pipe, socket or device)");
  }
}

}  // namespace
}  // namespace meso
