#include "meso/meshreduce/progressive.hpp"
#include "meso/meshreduce/surface_distance.hpp"

#include "meso/core/error.hpp"
#include "meso/examples/brick_wall.hpp"
#include "meso/meshreduce/meshreduce.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <set>
#include <string>
#include <vector>

namespace meso {
namespace {

// A bumpy torus (UV seams along both wrap lines) in two face groups.
Mesh make_torus(int columns, int rows) {
  Mesh m = test::make_parametric(
      columns, rows,
      [](double s, double t) {
        const double u = 2 * M_PI * s, v = 2 * M_PI * t;
        const double r = 0.35 + 0.05 * std::sin(5 * u) * std::cos(3 * v);
        const double R = 1.0 + r * std::cos(v);
        return Vec3f(float(R * std::cos(u)), float(R * std::sin(u)), float(r * std::sin(v)));
      },
      true, true);
  std::vector<int> groups;
  for (auto f : m.faces()) groups.push_back(f.idx() % 7 == 0 ? 1 : 0);
  set_face_groups(m, {"body", "trim"}, groups);
  return m;
}

// Bit-for-bit: positions, normals, faces with their corner order, corner UVs, groups.
void expect_same_mesh(const Mesh& a, const Mesh& b, const std::string& what) {
  ASSERT_EQ(a.n_vertices(), b.n_vertices()) << what;
  ASSERT_EQ(a.n_faces(), b.n_faces()) << what;
  EXPECT_EQ(std::memcmp(a.points(), b.points(), a.n_vertices() * sizeof(Vec3f)), 0) << what << ": positions";
  ASSERT_TRUE(a.has_vertex_normals() && b.has_vertex_normals()) << what;
  EXPECT_EQ(std::memcmp(a.vertex_normals(), b.vertex_normals(), a.n_vertices() * sizeof(Vec3f)), 0) << what << ": normals";
  ASSERT_EQ(has_uvs(a), has_uvs(b)) << what;
  EXPECT_EQ(group_names(a), group_names(b)) << what;
  size_t differ = 0;
  for (auto f : a.faces()) {
    const FaceHandle g(f.idx());
    differ += face_group(a, f) != face_group(b, g);
    const auto ha = face_halfedges(a, f), hb = face_halfedges(b, g);
    for (size_t k = 0; k < 3; ++k) {
      differ += a.to_vertex_handle(ha[k]) != b.to_vertex_handle(hb[k]);
      if (has_uvs(a)) differ += std::memcmp(&a.texcoord2D(ha[k]), &b.texcoord2D(hb[k]), sizeof(Vec2f)) != 0;
    }
  }
  EXPECT_EQ(differ, 0u) << what << ": faces, corner UVs or groups";
}

// The required property: level k of the record equals reducing the input directly to k,
// for the input itself, the first single collapses, levels in between, the final count and,
// when the record ran until no collapse was legal, below it (both stop at the final count).
void check_levels(const Mesh& in, size_t final_target, ReduceQuality quality = ReduceQuality::balanced) {
  ReduceOptions o;
  o.target_faces = final_target;
  o.quality = quality;
  ProgressiveMesh pm;
  ReduceReport r;
  const Mesh reduced = reduce_mesh(in, o, &r, null_progress(), &pm);
  ASSERT_EQ(pm.final_faces, reduced.n_faces());
  ASSERT_EQ(pm.collapses.size(), r.collapses);
  ASSERT_GT(r.collapses, 10u);
  // Without the record, the same output.
  expect_same_mesh(reduce_mesh(in, o), reduced, "with and without the record");
  const size_t n = in.n_faces();
  std::vector<size_t> levels = {n, n - 1, n - 2, n - 3, (n * 2) / 3, n / 3 + 1, pm.final_faces + 1, pm.final_faces};
  if (!r.target_reached) levels.push_back(0);
  for (const size_t k : levels) {
    ReduceOptions ok;
    ok.target_faces = k;
    ok.quality = quality;
    size_t replayed = 0;
    const Mesh level = progressive_level(pm, k, &replayed);
    expect_same_mesh(reduce_mesh(in, ok), level, "level " + std::to_string(k));
    EXPECT_LE(replayed, pm.collapses.size());
  }
}

TEST(Progressive, LevelsEqualDirectReductionWithUvsAndGroups) { check_levels(make_torus(48, 24), 120); }

// The fast preset's lazy keys change the order of the collapses, not the record's replay.
TEST(Progressive, LevelsEqualDirectReductionWithTheFastPreset) {
  check_levels(make_torus(48, 24), 120, ReduceQuality::fast);
  BrickWallOptions w;
  w.columns = 48;
  w.rows = 24;
  check_levels(make_brick_wall(w), 100, ReduceQuality::fast);
}

// best keeps one of two reductions: its record is the one kept, so the record's last level is
// best's output. The torus at 100 faces keeps the area-weighted run, the wall at 60 the
// uniform one (checked below, so that both branches are exercised).
TEST(Progressive, BestRecordsTheReductionItKeeps) {
  BrickWallOptions w;
  w.columns = 48;
  w.rows = 24;
  const std::pair<Mesh, size_t> cases[] = {{make_torus(48, 24), 100}, {make_brick_wall(w), 60}};
  std::set<std::string> kept;
  for (const auto& [in, target] : cases) {
    ReduceOptions o;
    o.target_faces = target;
    o.quality = ReduceQuality::best;
    ProgressiveMesh pm;
    ReduceReport r;
    const Mesh out = reduce_mesh(in, o, &r, null_progress(), &pm);
    expect_same_mesh(progressive_level(pm, out.n_faces()), out, "last level, planes " + r.planes);
    EXPECT_TRUE(r.fitted_hausdorff.empty()) << "no surface fit with a record";
    // Without the record, best also fits both candidates to the input and keeps the nearest
    // of the four: the same mesh when no fit is nearer; else a fit, nearer than the record's.
    ReduceReport r2;
    const Mesh direct = reduce_mesh(in, o, &r2);
    EXPECT_EQ(r2.candidate_hausdorff, r.candidate_hausdorff);
    if (!r2.fitted) {
      expect_same_mesh(direct, out, "with and without the record");
    } else {
      EXPECT_LT(measure_surface_distance(in, direct).hausdorff, measure_surface_distance(in, out).hausdorff);
      if (r2.planes == r.planes) {  // the same reduction, fitted: the same faces and UVs
        ASSERT_EQ(direct.n_faces(), out.n_faces());
        for (auto f : out.faces()) {
          const auto ha = face_halfedges(out, f), hb = face_halfedges(direct, f);
          for (size_t k = 0; k < 3; ++k) {
            EXPECT_EQ(out.to_vertex_handle(ha[k]), direct.to_vertex_handle(hb[k]));
            if (has_uvs(out)) {
              EXPECT_EQ(out.texcoord2D(ha[k]), direct.texcoord2D(hb[k]));
            }
          }
        }
      }
    }
    kept.insert(r.planes);
  }
  EXPECT_EQ(kept, (std::set<std::string>{"area", "uniform"}));
}

// Relief, a boundary (collapses that close boundary triangles move boundary halfedges into
// faces) and one UV chart.
TEST(Progressive, LevelsEqualDirectReductionOnTheBrickWall) {
  BrickWallOptions w;
  w.columns = 48;
  w.rows = 24;
  check_levels(make_brick_wall(w), 100);
}

TEST(Progressive, LevelsEqualDirectReductionWithoutUvs) {
  Mesh in = make_torus(40, 20);
  in.release_halfedge_texcoords2D();
  ASSERT_FALSE(has_uvs(in));
  check_levels(in, 0);  // to the end: the torus's topology stops it
}

// Locks change which collapses are made, not how they replay.
TEST(Progressive, LevelsEqualDirectReductionWithLocks) {
  const Mesh in = test::make_grid(24, 24);
  ReduceOptions o;
  o.target_faces = 30;
  o.lock_boundary = true;
  ProgressiveMesh pm;
  const Mesh out = reduce_mesh(in, o, nullptr, null_progress(), &pm);
  for (const size_t k : {size_t{1000}, size_t{700}, pm.final_faces}) {
    ReduceOptions ok = o;
    ok.target_faces = k;
    expect_same_mesh(reduce_mesh(in, ok), progressive_level(pm, k), "level " + std::to_string(k));
  }
}

TEST(Progressive, FileRoundTripIsExactAndDeterministic) {
  const Mesh in = make_torus(32, 16);
  ReduceOptions o;
  o.target_faces = 50;
  ProgressiveMesh pm, again;
  reduce_mesh(in, o, nullptr, null_progress(), &pm);
  reduce_mesh(in, o, nullptr, null_progress(), &again);
  test::TempDir dir;
  write_progressive(pm, dir / "a.pm");
  write_progressive(again, dir / "b.pm");
  const std::string bytes = test::read_text(dir / "a.pm");
  EXPECT_EQ(bytes, test::read_text(dir / "b.pm")) << "same input, same bytes";
  // The documented size: header, names, arrays, footer.
  const size_t names = 4 + 4 + 4 + 4;  // "body", "trim"
  EXPECT_EQ(bytes.size(), 72 + names + 12 * pm.positions.size() + 40 * pm.input_faces() + 16 * pm.collapses.size() +
                              8 * pm.uvs.size() + 8);
  const ProgressiveMesh back = read_progressive(dir / "a.pm");
  EXPECT_EQ(back.source, (dir / "a.pm").string());
  EXPECT_EQ(back.final_faces, pm.final_faces);
  EXPECT_EQ(back.group_names, pm.group_names);
  write_progressive(back, dir / "c.pm");
  EXPECT_EQ(bytes, test::read_text(dir / "c.pm"));
  for (const size_t k : {size_t{700}, size_t{300}, pm.final_faces})
    expect_same_mesh(progressive_level(pm, k), progressive_level(back, k), "level " + std::to_string(k));
}

TEST(Progressive, DamagedFilesAreInputErrors) {
  const Mesh in = make_torus(16, 8);
  ReduceOptions o;
  o.target_faces = 40;
  ProgressiveMesh pm;
  reduce_mesh(in, o, nullptr, null_progress(), &pm);
  test::TempDir dir;
  write_progressive(pm, dir / "good.pm");
  const std::string good = test::read_text(dir / "good.pm");
  auto expect_input_error = [&](const std::string& bytes, const std::string& problem) {
    const auto path = dir / "bad.pm";
    test::write_text(path, bytes);
    try {
      read_progressive(path);
      ADD_FAILURE() << "no error for " << problem;
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(path.string() + ": ", 0), 0u) << e.what();
      EXPECT_NE(std::string(e.what()).find(problem), std::string::npos) << e.what();
    }
  };
  expect_input_error(good.substr(0, good.size() - 1), "truncated");
  expect_input_error(good.substr(0, good.size() / 2), "truncated");
  expect_input_error(good.substr(0, 40), "truncated");
  expect_input_error(good + "x", "corrupt");
  std::string flipped = good;
  flipped[good.size() / 2] = static_cast<char>(flipped[good.size() / 2] ^ 0x10);
  expect_input_error(flipped, "checksum");
  expect_input_error("solid cube\n", "not a meso progressive mesh");
  std::string version = good;
  version[8] = 2;
  expect_input_error(version, "version 2");
  EXPECT_THROW(read_progressive(dir / "missing.pm"), InputError);
  // A header whose last-level face count the collapses cannot reach (each removes one face
  // or two), written with a valid checksum: refused on reading, before any replay.
  for (const size_t final_faces : {pm.input_faces() - pm.collapses.size() + 1, pm.input_faces() - 2 * pm.collapses.size() - 1}) {
    ProgressiveMesh off = pm;
    off.final_faces = final_faces;
    write_progressive(off, dir / "off.pm");
    expect_input_error(test::read_text(dir / "off.pm"), "corrupt header (face counts)");
  }

  // A record that reads but does not replay (an illegal collapse) is an InputError too.
  ProgressiveMesh wrong = pm;
  wrong.source = "wrong.pm";
  wrong.collapses[1] = wrong.collapses[0];  // the first collapse's edge is gone by then
  EXPECT_THROW(progressive_level(wrong, 0), InputError);
  wrong = pm;
  wrong.uvs.pop_back();
  EXPECT_THROW(progressive_level(wrong, 0), InputError);

  // A record whose mesh no reader would take (written by hand with a valid checksum): one
  // position moved to 3e38, a kept vertex recorded at 3e38, an empty mesh. They had replayed
  // into meshes meso refuses to read back, or an empty OBJ, with exit 0.
  auto expect_refused_on_replay = [&](const ProgressiveMesh& p, const std::string& problem) {
    try {
      progressive_level(p, 0);
      ADD_FAILURE() << "no error for " << problem;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(problem), std::string::npos) << e.what();
    }
  };
  wrong = pm;
  wrong.positions[0] = Vec3f(3e38f, 0, 0);
  expect_refused_on_replay(wrong, "its vertices span 3e+38 units");
  wrong = pm;
  wrong.collapses.back().position = Vec3f(-3e38f, 3e38f, 0);
  expect_refused_on_replay(wrong, "its vertices span");
  ProgressiveMesh empty;
  empty.source = "empty.pm";
  expect_refused_on_replay(empty, "contains no triangles");
}

}  // namespace
}  // namespace meso
