// Pre-sampled displacement and compressed-displacement vertex streams (course notes,
// displacement-authoring-course.md, "Pre-sampled Displacement Mapping" and "Displacement
// Compression"): every base triangle tessellated regularly, the displacement of each
// tessellation vertex sampled by casting a ray against the high mesh directly (no 2D map,
// so no unique UV mapping is needed), for a chain of levels, each vertex also carrying the
// value its coarser level interpolates there so a renderer can morph between levels.
#pragma once

#include "meso/core/mesh.hpp"
#include "meso/core/progress.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace meso {

struct DisplacementStreamOptions {
  int levels = 5;  // levels 0 .. levels-1, level l with 2^l segments per edge (at most 7 levels)
  // Ray reach along +normal / -normal, object units; <= 0: 5 % of the high mesh's diagonal.
  float front = 0.0f, back = 0.0f;
};

// Level l of triangle t: with s = 2^l segments per edge, vertex (i, j), i, j >= 0,
// i + j <= s, sits at barycentrics (1 - (i + j)/s, i/s, j/s) of the corners in
// face_halfedges() order (corner a = 1 - ..., b gets i/s, c gets j/s); its position is
// P = sum b_k P_k, its direction N = normalize(sum b_k N_k) (vertex normals), and its
// displacement d the signed distance along N to the nearest high-mesh hit within reach (0
// and counted as a miss when none). Points on an edge are interpolated from the edge's
// lower-numbered vertex, so two triangles sharing the edge compute bit-identical points
// and values: the tessellation is crack-free. `coarse` is the displacement the level below
// gives at the same point: its own value at shared vertices, the mean of the two ends of
// the coarser edge a new vertex halves elsewhere (level 0: its own value).
struct DisplacementLevel {
  int segments = 1;
  // Per triangle, (s + 1)(s + 2)/2 values in the order i = 0..s, j = 0..s - i.
  std::vector<float> value, coarse;
  int vertices_per_triangle() const { return (segments + 1) * (segments + 2) / 2; }
};

struct DisplacementStream {
  int triangles = 0;
  std::vector<DisplacementLevel> levels;
  float front = 0, back = 0;
  size_t rays = 0, misses = 0;
  float min_value = 0, max_value = 0;
};

// Deterministic, parallel over triangles.
DisplacementStream sample_displacement_stream(const Mesh& base, const Mesh& high, const DisplacementStreamOptions& options,
                                              Progress& progress = null_progress());

// The compressed vertex: 8 bytes, little-endian, bit fields from the least significant:
//   triangle 22 bits | i 7 bits | j 7 bits | d 14 bits | coarse 14 bits
// with d = min + q (max - min) / 16383 (likewise coarse): |error| <= (max - min) / 32766.
// Decoding needs the base mesh (positions, vertex normals, the face order) and the level's
// segment count: position = P(t, i, j) + d N(t, i, j).
inline constexpr int kDisplacementBits = 14;
inline constexpr uint32_t kDisplacementSteps = (1u << kDisplacementBits) - 1;

struct EncodedStream {
  float min_value = 0, max_value = 0;  // the quantisation range
  std::vector<int> segments;           // per level
  std::vector<std::vector<uint64_t>> vertices;  // per level, triangle-major as DisplacementLevel
  double max_error = 0;                // largest |decoded - sampled| over all values, object units
};
EncodedStream encode_displacement_stream(const DisplacementStream& stream);

// Field accessors of one compressed vertex.
struct DecodedVertex {
  uint32_t triangle;
  int i, j;
  float value, coarse;
};
DecodedVertex decode_vertex(uint64_t v, float min_value, float max_value);

// The file `meso streams dstream` writes (docs/formats.md): header, then each level's
// vertices. Throws on I/O errors.
void write_displacement_stream(const EncodedStream& stream, int base_vertices, int base_triangles, const std::string& path);

// Reads such a file (max_error is not stored: 0). The base mesh's vertex and triangle counts
// it was made for go to *base_vertices and *base_triangles. Throws InputError naming `path`
// when it is missing, truncated, of another version, or inconsistent (segments not 2^l, a
// level's vertex count, a vertex's triangle or (i, j) out of range).
EncodedStream read_displacement_stream(const std::string& path, int* base_vertices, int* base_triangles);

// The point and direction of vertex (i, j) of triangle t at `segments` per edge, exactly as
// sample_displacement_stream computes them (object units; n interpolated, not normalised).
void displacement_stream_point(const Mesh& base, int t, int segments, int i, int j, OpenMesh::Vec3d& p, OpenMesh::Vec3d& n);

// The decoded positions of level `level`, in the stream's vertex order: P + d N/|N| with
// d = (1 - morph) coarse + morph value (morph 1: the level itself, 0: what the coarser level
// interpolates there), P and N from displacement_stream_point (a zero N gives P).
std::vector<Vec3f> decode_displacement_level(const Mesh& base, const EncodedStream& stream, int level, float morph = 1.0f);

}  // namespace meso
