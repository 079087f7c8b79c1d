// EXPERIMENT harness: meshopt_simplify, meso reduce_mesh(fast), and the flat-array prototype
// on the bench inputs of /work/main/bench/meshreduce_peers.cpp, called and measured the same
// way (weld + measure_surface_distance + count_flipped + count_non_manifold).
//   bench [--meshes bricks,torus] [--ratios 0.1,0.01,0.001] [--repeat 5] [--methods meshopt,meso,proto]
//         [--callgrind] [--endpoint] [--pass-goal 0.5] [--pass-scan 1] [--no-measure]
#include "fastcore.hpp"
#include "geometry.hpp"
#include "meshreduce_cgal_peer.hpp"
#include "meso/examples/brick_wall.hpp"
#include "meso/examples/parametric.hpp"
#include "meso/meshreduce/meshreduce.hpp"
#include "meso/meshreduce/surface_distance.hpp"

#include <meshoptimizer.h>
#include <valgrind/callgrind.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <numeric>
#include <sstream>
#include <string>
#include <unordered_map>
#include <vector>

using namespace meso;

namespace {

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

// ---- copied from bench/meshreduce_peers.cpp (meso's own bench code) ----
TriangleSoup weld(const TriangleSoup& in) {
  struct Key {
    float x, y, z;
    bool operator<(const Key& o) const { return std::memcmp(this, &o, sizeof(Key)) < 0; }
  };
  std::map<Key, uint32_t> index;
  TriangleSoup out;
  out.triangles.reserve(in.triangles.size());
  for (const auto& t : in.triangles) {
    std::array<uint32_t, 3> w{};
    for (int k = 0; k < 3; ++k) {
      const Vec3f& p = in.points[t[k]];
      const auto [it, added] = index.try_emplace(Key{p[0], p[1], p[2]}, static_cast<uint32_t>(out.points.size()));
      if (added) out.points.push_back(p);
      w[k] = it->second;
    }
    out.triangles.push_back(w);
  }
  return out;
}

size_t count_non_manifold(const TriangleSoup& s) {
  const size_t n = s.triangles.size();
  std::vector<char> bad(n, 0), repeated(n, 0);
  std::vector<uint32_t> parent(3 * n);
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](uint32_t c) {
    while (parent[c] != c) c = parent[c] = parent[parent[c]];
    return c;
  };
  auto join = [&](uint32_t a, uint32_t b) { parent[find(a)] = find(b); };
  struct Use {
    uint32_t face;
    int from;
  };
  std::unordered_map<uint64_t, std::vector<Use>> edges;
  edges.reserve(2 * n);
  for (uint32_t f = 0; f < n; ++f) {
    const auto& t = s.triangles[f];
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) {
      bad[f] = repeated[f] = 1;
      continue;
    }
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = t[k], b = t[(k + 1) % 3];
      edges[(uint64_t{std::min(a, b)} << 32) | std::max(a, b)].push_back({f, k});
    }
  }
  for (const auto& [key, uses] : edges) {
    const bool wrong = uses.size() > 2 || (uses.size() == 2 && s.triangles[uses[0].face][uses[0].from] ==
                                                                   s.triangles[uses[1].face][uses[1].from]);
    if (wrong)
      for (const Use& u : uses) bad[u.face] = 1;
    if (uses.size() != 2) continue;
    for (const uint32_t v : {static_cast<uint32_t>(key >> 32), static_cast<uint32_t>(key & 0xffffffffu)}) {
      uint32_t c[2];
      for (int i = 0; i < 2; ++i) {
        const auto& t = s.triangles[uses[i].face];
        const int k = t[0] == v ? 0 : t[1] == v ? 1 : 2;
        c[i] = 3 * uses[i].face + static_cast<uint32_t>(k);
      }
      join(c[0], c[1]);
    }
  }
  std::vector<uint32_t> group(s.points.size(), UINT32_MAX);
  std::vector<char> bowtie(s.points.size(), 0);
  for (uint32_t c = 0; c < 3 * n; ++c) {
    if (repeated[c / 3]) continue;
    const uint32_t v = s.triangles[c / 3][c % 3], root = find(c);
    if (group[v] == UINT32_MAX) group[v] = root;
    else if (group[v] != root) bowtie[v] = 1;
  }
  size_t count = 0;
  for (uint32_t f = 0; f < n; ++f) {
    const auto& t = s.triangles[f];
    count += bad[f] || bowtie[t[0]] || bowtie[t[1]] || bowtie[t[2]];
  }
  return count;
}
// ---- end of copy ----

struct Flat {
  std::vector<Vec3f> points;
  std::vector<std::array<uint32_t, 3>> tris;
  std::vector<std::array<Vec2f, 3>> uvs;
};

Flat flatten(const Mesh& m) {
  Flat f;
  f.points.reserve(m.n_vertices());
  for (auto v : m.vertices()) f.points.push_back(m.point(v));
  const bool uv = has_uvs(m);
  for (auto fh : m.faces()) {
    const auto hs = face_halfedges(m, fh);
    f.tris.push_back({static_cast<uint32_t>(m.to_vertex_handle(hs[0]).idx()), static_cast<uint32_t>(m.to_vertex_handle(hs[1]).idx()),
                      static_cast<uint32_t>(m.to_vertex_handle(hs[2]).idx())});
    if (uv) f.uvs.push_back({m.texcoord2D(hs[0]), m.texcoord2D(hs[1]), m.texcoord2D(hs[2])});
  }
  return f;
}

// The prototype's output as a meso Mesh (compacted vertices, halfedge UVs), to price the
// conversion a landing inside reduce_mesh would pay.
Mesh to_mesh(const fastcore::Output& o) {
  Mesh m;
  m.request_halfedge_texcoords2D();
  std::vector<int> map(o.points.size(), -1);
  std::vector<VertexHandle> vh;
  for (const auto& t : o.triangles)
    for (uint32_t v : t)
      if (map[v] < 0) map[v] = static_cast<int>(vh.size()), vh.push_back(m.add_vertex(o.points[v]));
  for (size_t i = 0; i < o.triangles.size(); ++i) {
    const auto& t = o.triangles[i];
    const FaceHandle f = m.add_face(vh[map[t[0]]], vh[map[t[1]]], vh[map[t[2]]]);
    if (!f.is_valid() || o.uvs.empty()) continue;
    for (auto h : m.fh_range(f)) {
      const int v = m.to_vertex_handle(h).idx();
      for (int k = 0; k < 3; ++k)
        if (map[t[k]] == v) m.set_texcoord2D(h, o.uvs[i][k]);
    }
  }
  return m;
}

std::vector<double> parse_list(const std::string& s) {
  std::vector<double> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(std::strtod(item.c_str(), nullptr));
  return out;
}
std::vector<std::string> parse_names(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(item);
  return out;
}

struct Row {
  std::string method;
  size_t faces = 0;
  double seconds = 1e30;
  SurfaceDistance d;
  size_t flipped = 0, degenerate = 0, non_manifold = 0, uv_bad = 0;
  std::string note;
};

}  // namespace

int main(int argc, char** argv) {
  std::vector<double> ratios = {0.1, 0.01, 0.001};
  std::vector<std::string> meshes_wanted = {"bricks", "torus"}, methods = {"meshopt", "meso", "proto"};
  int repeat = 5;
  bool callgrind = false, measure = true;
  fastcore::Options fo;
  fo.pass_goal = 1.0;
  fo.pass_scan = 0.5;
  double scan_e = 0.3;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() { return std::string(argv[++i]); };
    if (a == "--ratios") ratios = parse_list(value());
    else if (a == "--meshes") meshes_wanted = parse_names(value());
    else if (a == "--methods") methods = parse_names(value());
    else if (a == "--repeat") repeat = std::atoi(value().c_str());
    else if (a == "--callgrind") callgrind = true, repeat = 1, measure = false;
    else if (a == "--no-measure") measure = false;
    else if (a == "--endpoint") fo.optimal_placement = false;
    else if (a == "--pass-goal") fo.pass_goal = std::strtod(value().c_str(), nullptr);
    else if (a == "--pass-scan") fo.pass_scan = std::strtod(value().c_str(), nullptr);
    else if (a == "--scan-e") scan_e = std::strtod(value().c_str(), nullptr);
    else if (a == "--std-sort") fo.radix = false;
    else if (a == "--no-cache") fo.cache = false;
    else if (a == "--no-lean") fo.lean = false;
    else if (a == "--no-refine") fo.refine = false;
    else if (a == "--rank-cheap") fo.rank_cheap = true;
    else if (a == "--ring-lock") fo.ring_lock = true;
    else {
      std::fprintf(stderr, "unknown %s\n", a.c_str());
      return 2;
    }
  }
  auto has = [&](const std::string& m) { return std::find(methods.begin(), methods.end(), m) != methods.end(); };
  std::printf("| mesh | target | method | faces | best s | Hausdorff %% diag | RMS %% diag | flipped | degenerate | non-manifold | uv folds | note |\n");
  std::printf("|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---|\n");
  std::fflush(stdout);
  for (const auto& name : meshes_wanted) {
    const Mesh mesh = name == "bricks" ? make_brick_wall(BrickWallOptions{}) : make_smooth_torus(512, 256);
    const double diag = bounding_box(mesh).diagonal();
    const TriangleSoup input = weld(triangle_soup(mesh));
    std::unique_ptr<SurfaceDistanceReference> ref;
    if (measure) ref = std::make_unique<SurfaceDistanceReference>(input);
    const Flat flat = flatten(mesh);
    // Input UV orientation (majority sign) for the UV fold count.
    double uv_sign = 0;
    for (const auto& u : flat.uvs) uv_sign += meso::reduce::uv_cross(u[0], u[1], u[2]) > 0 ? 1 : -1;
    std::vector<unsigned> indices;
    for (const auto& t : input.triangles) indices.insert(indices.end(), t.begin(), t.end());
    for (const double ratio : ratios) {
      const size_t target = static_cast<size_t>(std::llround(ratio * static_cast<double>(mesh.n_faces())));
      std::vector<Row> rows;
      auto finish = [&](Row& r, const TriangleSoup& out_raw) {
        r.faces = out_raw.triangles.size();
        if (!measure) return;
        const TriangleSoup out = weld(out_raw);
        r.faces = out.triangles.size();
        r.d = ref->measure(out);
        const bench::FlipCount flips = bench::count_flipped(input, out);
        r.flipped = flips.flipped;
        r.degenerate = flips.degenerate;
        r.non_manifold = count_non_manifold(out);
      };
      char label[128];
      if (has("meshopt")) {
        Row r;
        r.method = "meshoptimizer";
        std::vector<unsigned> out(indices.size());
        size_t n = 0;
        for (int i = 0; i < repeat; ++i) {
          std::snprintf(label, sizeof label, "%s_%g_meshopt", name.c_str(), ratio);
          CALLGRIND_TOGGLE_COLLECT;
          const double t0 = now();
          n = meshopt_simplify(out.data(), indices.data(), indices.size(), &input.points[0][0], input.points.size(), sizeof(Vec3f), target * 3,
                               1.0f, 0, nullptr);
          r.seconds = std::min(r.seconds, now() - t0);
          CALLGRIND_TOGGLE_COLLECT;
          if (callgrind) CALLGRIND_DUMP_STATS_AT(label);
        }
        TriangleSoup soup;
        soup.points = input.points;
        for (size_t i = 0; i + 2 < n; i += 3) soup.triangles.push_back({out[i], out[i + 1], out[i + 2]});
        finish(r, soup);
        rows.push_back(r);
      }
      if (has("meso")) {
        Row r;
        r.method = "meso fast";
        Mesh out;
        ReduceReport rep;
        for (int i = 0; i < repeat; ++i) {
          ReduceOptions o;
          o.target_faces = target;
          o.quality = ReduceQuality::fast;
          std::snprintf(label, sizeof label, "%s_%g_meso", name.c_str(), ratio);
          CALLGRIND_TOGGLE_COLLECT;
          const double t0 = now();
          out = reduce_mesh(mesh, o, &rep);
          r.seconds = std::min(r.seconds, now() - t0);
          CALLGRIND_TOGGLE_COLLECT;
          if (callgrind) CALLGRIND_DUMP_STATS_AT(label);
        }
        r.note = "passes " + std::to_string(rep.passes);
        finish(r, triangle_soup(out));
        rows.push_back(r);
      }
      for (const std::string pm : {"proto", "protoE", "protoV", "protoEV", "protoB", "protoVS", "protoEVS"}) {
        if (!has(pm)) continue;
        fastcore::Options o = fo;
        if (pm == "protoE" || pm == "protoEV" || pm == "protoB" || pm == "protoEVS") o.optimal_placement = false, o.pass_scan = scan_e;
        if (pm == "protoVS" || pm == "protoEVS") o.steep_test = o.post_check = o.post_check_steep_only = true;  // (lazy_bvh did not help: steep faces occur on both meshes)
        // Bare: what meshopt_simplify keeps (positions only: no UVs, no needle guard, no
        // input-normal test; the classic 90-degree flip test, link condition, boundaries).
        const bool bare = pm == "protoB";
        if (bare) o.max_aspect_ratio = 0, o.input_normal_test = false;
        if (pm == "protoV" || pm == "protoEV") o.steep_test = o.post_check = true;
        o.target_faces = target;
        Row r;
        char mname[64];
        std::snprintf(mname, sizeof mname, "proto %s scan %.2g%s", o.optimal_placement ? "optimal" : "endpoint", o.pass_scan,
                      o.post_check_steep_only ?  " +flip verify (post-check steep faces only)" : o.steep_test ? " +flip verify" : bare ? " BARE (no UV/needle/input-normal)" : "");
        r.method = mname;
        fastcore::Output out;
        fastcore::Stats st;
        for (int i = 0; i < repeat; ++i) {
          std::snprintf(label, sizeof label, "%s_%g_%s", name.c_str(), ratio, pm.c_str());
          CALLGRIND_TOGGLE_COLLECT;
          const double t0 = now();
          out = fastcore::reduce(flat.points.data(), flat.points.size(), flat.tris.data(), flat.tris.size(),
                                 flat.uvs.empty() || bare ? nullptr : flat.uvs.data(), o, &st);
          r.seconds = std::min(r.seconds, now() - t0);
          CALLGRIND_TOGGLE_COLLECT;
          if (callgrind) CALLGRIND_DUMP_STATS_AT(label);
        }
        // Conversion costs a landing behind reduce_mesh's Mesh interface would add.
        double conv = 1e30;
        if (!callgrind)
          for (int i = 0; i < repeat; ++i) {
            const double t0 = now();
            const Flat f2 = flatten(mesh);
            const Mesh m2 = to_mesh(out);
            conv = std::min(conv, now() - t0);
            if (m2.n_faces() != out.triangles.size()) std::fprintf(stderr, "to_mesh dropped faces\n");
          }
        TriangleSoup soup;
        soup.points = out.points;
        soup.triangles = out.triangles;
        for (const auto& u : out.uvs) {
          const double a = meso::reduce::uv_cross(u[0], u[1], u[2]);
          r.uv_bad += !(a * uv_sign > 0);
        }
        char note[256];
        std::snprintf(note, sizeof note, "passes %zu, collapses %zu, eval %zu, tried %zu, dirty-skip %zu, rej link %zu chart %zu flip %zu steep %zu needle %zu uv %zu; post-check flipped %zu; Mesh<->arrays %.3f s",
                      st.passes, st.collapses, st.evaluated, st.attempted, st.skipped_dirty, st.rej_link, st.rej_chart, st.rej_flip, st.rej_steep, st.rej_needle, st.rej_uv, st.post_flipped,
                      conv);
        r.note = note;
        finish(r, soup);
        rows.push_back(r);
      }
      for (const Row& r : rows) {
        std::printf("| %s | %zu | %s | %zu | %.4f | %.4f | %.5f | %zu | %zu | %zu | %zu | %s |\n", name.c_str(), target, r.method.c_str(), r.faces,
                    r.seconds, 100 * r.d.hausdorff / diag, 100 * r.d.rms / diag, r.flipped, r.degenerate, r.non_manifold, r.uv_bad,
                    r.note.c_str());
      }
      std::fflush(stdout);
    }
  }
  return 0;
}
