#include "meso/bake/displacement_stream.hpp"
#include "meso/core/float_rounding.hpp"

#include "meso/core/error.hpp"
#include "meso/core/input_file.hpp"
#include "ray_scene.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <array>
#include <cstring>
#include <fstream>

namespace meso {

namespace {

// Index of vertex (i, j) in a triangle's list (i = 0..s, j = 0..s - i).
int vertex_index(int s, int i, int j) { return i * (s + 1) - i * (i - 1) / 2 + j; }

}  // namespace

void displacement_stream_point(const Mesh& base, int t, int s, int i, int j, OpenMesh::Vec3d& p, OpenMesh::Vec3d& n) {
  const auto hs = face_halfedges(base, FaceHandle(t));
  std::array<VertexHandle, 3> v;
  for (int k = 0; k < 3; ++k) v[static_cast<size_t>(k)] = base.to_vertex_handle(hs[static_cast<size_t>(k)]);
  auto P = [&](int k) { return OpenMesh::vector_cast<OpenMesh::Vec3d>(base.point(v[static_cast<size_t>(k)])); };
  auto N = [&](int k) { return OpenMesh::vector_cast<OpenMesh::Vec3d>(base.normal(v[static_cast<size_t>(k)])); };
  // Corner weights: a = (s - i - j) / s, b = i / s, c = j / s. On an edge (one weight zero)
  // interpolate from the edge's lower-numbered vertex: shared edges then give bit-identical
  // points in both triangles.
  const int w[3] = {s - i - j, i, j};
  int zero = -1;
  for (int k = 0; k < 3; ++k)
    if (w[k] == 0) zero = k;
  if (zero >= 0) {
    int e0 = (zero + 1) % 3, e1 = (zero + 2) % 3;
    if (v[static_cast<size_t>(e1)].idx() < v[static_cast<size_t>(e0)].idx()) std::swap(e0, e1);
    const double f = static_cast<double>(w[e1]) / s;  // from e0 toward e1
    p = P(e0) + f * (P(e1) - P(e0));
    n = N(e0) + f * (N(e1) - N(e0));
  } else {
    p = (w[0] * P(0) + w[1] * P(1) + w[2] * P(2)) / s;
    n = (w[0] * N(0) + w[1] * N(1) + w[2] * N(2)) / s;
  }
}

namespace {
DisplacementStream sample_at_scale(const Mesh& base, const Mesh& high, const DisplacementStreamOptions& o, Progress& progress);
}  // namespace

// Meshes far from unit size (near 1e20 units every ray left Embree's range) are sampled in
// the unit box: unit_scale_exponent() in ray_scene.hpp.
DisplacementStream sample_displacement_stream(const Mesh& base, const Mesh& high, const DisplacementStreamOptions& o,
                                              Progress& progress) {
  const int e = unit_scale_exponent({&base, &high});
  if (e == 0) return sample_at_scale(base, high, o, progress);
  const float to_unit = std::ldexp(1.0f, -e), from_unit = std::ldexp(1.0f, e);
  DisplacementStreamOptions so = o;
  so.front *= to_unit;
  so.back *= to_unit;
  DisplacementStream out = sample_at_scale(scaled_mesh(base, to_unit), scaled_mesh(high, to_unit), so, progress);
  for (DisplacementLevel& level : out.levels)
    for (std::vector<float>* values : {&level.value, &level.coarse})
      for (float& v : *values) v *= from_unit;
  for (float* x : {&out.front, &out.back, &out.min_value, &out.max_value}) *x *= from_unit;
  return out;
}

namespace {
DisplacementStream sample_at_scale(const Mesh& base, const Mesh& high, const DisplacementStreamOptions& o, Progress& progress) {
  DisplacementStream out;
  out.triangles = static_cast<int>(base.n_faces());
  const float reach = 0.05f * bounding_box(high).diagonal();
  out.front = o.front > 0 ? o.front : reach;
  out.back = o.back > 0 ? o.back : reach;
  const float eps = 1e-5f * std::max(bounding_box(high).diagonal(), bounding_box(base).diagonal());
  const Vec3f center = bounding_box(base).center();
  const Eigen::Vector3d origin(center[0], center[1], center[2]);
  const RayScene scene(high, origin);
  const int levels = std::clamp(o.levels, 1, 7);

  // Signed distance along n from p to the nearest hit both ways (outward on a tie), or NaN.
  auto cast = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& n) {
    const Eigen::Vector3d dir = n.normalized();
    const Vec3f d(static_cast<float>(dir.x()), static_cast<float>(dir.y()), static_cast<float>(dir.z()));
    auto at = [&](double offset) {
      const Eigen::Vector3d q = p - origin + offset * dir;
      return Vec3f(static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z()));
    };
    const auto up = scene.intersect(at(-eps), d, 0.0f, out.front + eps);
    const auto down = scene.intersect(at(eps), -d, 0.0f, out.back + eps);
    const float t_up = up.valid() ? up.t - eps : 0.0f, t_down = down.valid() ? down.t - eps : 0.0f;
    if (!up.valid() && !down.valid()) return std::nan("");
    if (up.valid() && (!down.valid() || std::abs(t_up) <= std::abs(t_down))) return static_cast<double>(t_up);
    return static_cast<double>(-t_down);
  };

  for (int l = 0; l < levels; ++l) {
    DisplacementLevel level;
    level.segments = 1 << l;
    level.value.assign(static_cast<size_t>(out.triangles) * static_cast<size_t>(level.vertices_per_triangle()), 0.0f);
    out.levels.push_back(std::move(level));
  }
  std::vector<size_t> misses(static_cast<size_t>(out.triangles), 0);
  progress.begin("dstream", static_cast<uint64_t>(out.triangles));
  tbb::parallel_for(tbb::blocked_range<int>(0, out.triangles), [&](const tbb::blocked_range<int>& range) {
    for (int t = range.begin(); t < range.end(); ++t) {
      for (DisplacementLevel& level : out.levels) {
        const int s = level.segments;
        for (int i = 0; i <= s; ++i)
          for (int j = 0; j <= s - i; ++j) {
            OpenMesh::Vec3d pm, nm;
            displacement_stream_point(base, t, s, i, j, pm, nm);
            const Eigen::Vector3d p(pm[0], pm[1], pm[2]), n(nm[0], nm[1], nm[2]);
            double d = n.norm() > 1e-12 ? cast(p, n) : std::nan("");
            if (std::isnan(d) && n.norm() > 1e-12) {
              // A point on the base's open border misses a high mesh whose border lies right
              // over it about half the time (the hit falls on the high edge's outer side by a
              // rounding): cast again from a point moved 1e-4 of the way toward the base's
              // centre, within the tangent plane. The move depends on p and n only, which
              // are bit-identical in the triangles sharing the point: still crack-free.
              const Eigen::Vector3d unit = n.normalized();
              Eigen::Vector3d inward = origin - p;
              inward -= unit * unit.dot(inward);
              d = cast(p + 1e-4 * inward, n);
            }
            if (std::isnan(d)) {
              d = 0;
              ++misses[static_cast<size_t>(t)];
            }
            level.value[static_cast<size_t>(t) * static_cast<size_t>(level.vertices_per_triangle()) +
                        static_cast<size_t>(vertex_index(s, i, j))] = static_cast<float>(d);
          }
      }
      progress.advance(1);
    }
  });
  progress.end();

  // Morph targets: what the coarser level gives at each vertex.
  for (size_t l = 0; l < out.levels.size(); ++l) {
    DisplacementLevel& level = out.levels[l];
    if (l == 0) {
      level.coarse = level.value;
      continue;
    }
    const DisplacementLevel& below = out.levels[l - 1];
    const int s = level.segments, c = below.segments;
    const size_t per = static_cast<size_t>(level.vertices_per_triangle()), cper = static_cast<size_t>(below.vertices_per_triangle());
    level.coarse.resize(level.value.size());
    for (int t = 0; t < out.triangles; ++t) {
      auto coarse_at = [&](int i, int j) { return below.value[static_cast<size_t>(t) * cper + static_cast<size_t>(vertex_index(c, i, j))]; };
      for (int i = 0; i <= s; ++i)
        for (int j = 0; j <= s - i; ++j) {
          float m;
          if (i % 2 == 0 && j % 2 == 0) m = coarse_at(i / 2, j / 2);
          else if (i % 2 == 1 && j % 2 == 0) m = 0.5f * (coarse_at((i - 1) / 2, j / 2) + coarse_at((i + 1) / 2, j / 2));
          else if (i % 2 == 0) m = 0.5f * (coarse_at(i / 2, (j - 1) / 2) + coarse_at(i / 2, (j + 1) / 2));
          else m = 0.5f * (coarse_at((i - 1) / 2, (j + 1) / 2) + coarse_at((i + 1) / 2, (j - 1) / 2));
          level.coarse[static_cast<size_t>(t) * per + static_cast<size_t>(vertex_index(s, i, j))] = m;
        }
    }
  }
  bool first = true;
  for (const DisplacementLevel& level : out.levels) {
    out.rays += 2 * level.value.size();
    for (float d : level.value) {
      if (first) out.min_value = out.max_value = d;
      out.min_value = std::min(out.min_value, d);
      out.max_value = std::max(out.max_value, d);
      first = false;
    }
  }
  for (size_t m : misses) out.misses += m;
  return out;
}
}  // namespace

namespace {
uint32_t quantise(float v, float lo, float hi) {
  if (!(hi > lo)) return 0;
  const double q = std::round((static_cast<double>(v) - lo) / (static_cast<double>(hi) - lo) * kDisplacementSteps);
  return static_cast<uint32_t>(std::clamp(q, 0.0, static_cast<double>(kDisplacementSteps)));
}
float dequantise(uint32_t q, float lo, float hi) {
  return round_to_float(lo + (static_cast<double>(hi) - lo) * q / kDisplacementSteps);  // (see float_rounding.hpp)
}
}  // namespace

DecodedVertex decode_vertex(uint64_t v, float lo, float hi) {
  DecodedVertex d;
  d.triangle = static_cast<uint32_t>(v & ((1u << 22) - 1));
  d.i = static_cast<int>((v >> 22) & 127);
  d.j = static_cast<int>((v >> 29) & 127);
  d.value = dequantise(static_cast<uint32_t>((v >> 36) & kDisplacementSteps), lo, hi);
  d.coarse = dequantise(static_cast<uint32_t>((v >> 50) & kDisplacementSteps), lo, hi);
  return d;
}

EncodedStream encode_displacement_stream(const DisplacementStream& s) {
  if (s.triangles >= (1 << 22)) throw InputError("dstream", "more than 4194303 base triangles do not fit the 22-bit triangle field");
  EncodedStream e;
  e.min_value = s.min_value;
  e.max_value = s.max_value;
  for (const DisplacementLevel& level : s.levels) {
    const int n = level.segments, per = level.vertices_per_triangle();
    e.segments.push_back(n);
    std::vector<uint64_t> out(level.value.size());
    for (int t = 0; t < s.triangles; ++t)
      for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n - i; ++j) {
          const size_t k = static_cast<size_t>(t) * static_cast<size_t>(per) + static_cast<size_t>(vertex_index(n, i, j));
          const uint64_t q = quantise(level.value[k], e.min_value, e.max_value);
          const uint64_t qc = quantise(level.coarse[k], e.min_value, e.max_value);
          out[k] = static_cast<uint64_t>(t) | (static_cast<uint64_t>(i) << 22) | (static_cast<uint64_t>(j) << 29) | (q << 36) | (qc << 50);
          const DecodedVertex d = decode_vertex(out[k], e.min_value, e.max_value);
          e.max_error = std::max({e.max_error, std::abs(static_cast<double>(d.value) - level.value[k]),
                                  std::abs(static_cast<double>(d.coarse) - level.coarse[k])});
        }
    e.vertices.push_back(std::move(out));
  }
  return e;
}

void write_displacement_stream(const EncodedStream& e, int base_vertices, int base_triangles, const std::string& path) {
  std::ofstream f(path, std::ios::binary);
  if (!f) throw InternalError(path + ": cannot open for writing");
  auto u32 = [&](uint32_t v) {
    const unsigned char b[4] = {static_cast<unsigned char>(v), static_cast<unsigned char>(v >> 8), static_cast<unsigned char>(v >> 16),
                                static_cast<unsigned char>(v >> 24)};
    f.write(reinterpret_cast<const char*>(b), 4);
  };
  auto f32 = [&](float v) {
    uint32_t bits;
    std::memcpy(&bits, &v, 4);
    u32(bits);
  };
  f.write("MESODSTR", 8);
  u32(1);  // version
  u32(static_cast<uint32_t>(e.segments.size()));
  u32(static_cast<uint32_t>(base_vertices));
  u32(static_cast<uint32_t>(base_triangles));
  f32(e.min_value);
  f32(e.max_value);
  for (size_t l = 0; l < e.segments.size(); ++l) {
    u32(static_cast<uint32_t>(e.segments[l]));
    u32(static_cast<uint32_t>(e.vertices[l].size()));
    for (uint64_t v : e.vertices[l]) {
      u32(static_cast<uint32_t>(v));
      u32(static_cast<uint32_t>(v >> 32));
    }
  }
  if (!f) throw InternalError(path + ": write failed");
}

}  // namespace meso

namespace meso {

EncodedStream read_displacement_stream(const std::string& path, int* base_vertices, int* base_triangles) {
  require_input_file(path, "a displacement stream");
  std::ifstream f(path, std::ios::binary);
  if (!f) throw InputError(path, "cannot be opened");
  auto u32 = [&](const char* what) {
    unsigned char b[4];
    if (!f.read(reinterpret_cast<char*>(b), 4)) throw InputError(path, std::string("is truncated (") + what + ")");
    return static_cast<uint32_t>(b[0]) | static_cast<uint32_t>(b[1]) << 8 | static_cast<uint32_t>(b[2]) << 16 | static_cast<uint32_t>(b[3]) << 24;
  };
  auto f32 = [&](const char* what) {
    const uint32_t bits = u32(what);
    float v;
    std::memcpy(&v, &bits, 4);
    return v;
  };
  char magic[8];
  if (!f.read(magic, 8) || std::memcmp(magic, "MESODSTR", 8) != 0) throw InputError(path, "is not a meso dstream file (no MESODSTR header)");
  const uint32_t version = u32("version");
  if (version != 1) throw InputError(path, "has dstream version " + std::to_string(version) + "; this build reads version 1");
  const uint32_t levels = u32("level count");
  const uint32_t nv = u32("vertex count"), nt = u32("triangle count");
  if (levels < 1 || levels > 7) throw InputError(path, "has " + std::to_string(levels) + " levels (1 to 7 are valid)");
  if (nt >= (1u << 22) || nv > (1u << 30)) throw InputError(path, "has implausible base mesh counts");
  EncodedStream e;
  e.min_value = f32("range");
  e.max_value = f32("range");
  if (!std::isfinite(e.min_value) || !std::isfinite(e.max_value) || e.max_value < e.min_value)
    throw InputError(path, "has an invalid quantisation range");
  // A range whose span is not a float (-3e38 to 3e38) decodes to infinite displacements.
  if (!std::isfinite(e.max_value - e.min_value)) throw InputError(path, "its quantisation range spans more than the float range");
  for (uint32_t l = 0; l < levels; ++l) {
    const uint32_t s = u32("segments"), count = u32("level size");
    if (s != (1u << l)) throw InputError(path, "level " + std::to_string(l) + " has " + std::to_string(s) + " segments; expected " + std::to_string(1u << l));
    const uint64_t per = static_cast<uint64_t>(s + 1) * (s + 2) / 2;
    if (count != per * nt) throw InputError(path, "level " + std::to_string(l) + " has " + std::to_string(count) + " vertices; expected " + std::to_string(per * nt));
    std::vector<uint64_t> vertices(count);
    for (uint32_t k = 0; k < count; ++k) {
      const uint64_t lo = u32("vertices"), hi = u32("vertices");
      vertices[k] = lo | hi << 32;
      const DecodedVertex d = decode_vertex(vertices[k], e.min_value, e.max_value);
      if (d.triangle >= nt || d.i + d.j > static_cast<int>(s))
        throw InputError(path, "vertex " + std::to_string(k) + " of level " + std::to_string(l) + " is out of range");
    }
    e.segments.push_back(static_cast<int>(s));
    e.vertices.push_back(std::move(vertices));
  }
  // More data than the header's levels (a level count lowered, data appended) is damage, not
  // something to ignore: the finest level would be dropped without a word.
  if (f.peek() != std::char_traits<char>::eof()) throw InputError(path, "has data past the end of its last level (level count " + std::to_string(levels) + ")");
  *base_vertices = static_cast<int>(nv);
  *base_triangles = static_cast<int>(nt);
  return e;
}

std::vector<Vec3f> decode_displacement_level(const Mesh& base, const EncodedStream& stream, int level, float morph) {
  const std::vector<uint64_t>& in = stream.vertices.at(static_cast<size_t>(level));
  const int s = stream.segments.at(static_cast<size_t>(level));
  std::vector<Vec3f> out(in.size());
  for (size_t k = 0; k < in.size(); ++k) {
    const DecodedVertex d = decode_vertex(in[k], stream.min_value, stream.max_value);
    OpenMesh::Vec3d p, n;
    displacement_stream_point(base, static_cast<int>(d.triangle), s, d.i, d.j, p, n);
    // (1 - m) c + m v: exactly c at m = 0 and exactly v at m = 1.
    const double m = morph;
    const double value = (1.0 - m) * d.coarse + m * d.value;
    const double len = n.norm();
    if (len > 0) p += n * (value / len);
    out[k] = Vec3f(static_cast<float>(p[0]), static_cast<float>(p[1]), static_cast<float>(p[2]));
  }
  return out;
}

}  // namespace meso
