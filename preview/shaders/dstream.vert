#version 450 core
// The dstream method: the base mesh displaced by a compressed-displacement vertex stream
// (meso streams dstream; bake/displacement_stream.hpp, docs/formats.md). One invocation per
// stream vertex (gl_VertexID = its index in the level): the 8-byte vertex gives the base
// triangle, (i, j) on its regular tessellation at s = 2^l segments, and two quantised
// displacements, the level's own and the value the coarser level interpolates there (its
// morph target). The point P and direction N are interpolated over the triangle's corners
// exactly as displacement_stream_point() does (on an edge from the edge's lower-numbered
// base vertex, so both triangles compute the same bits: crack-free), then
// position = P + ((1 - m) coarse + m value) N/|N|. The morph m is u_morph when it is >= 0,
// else driven by the distance from the eye to P: 1 up to u_lod_distance, falling linearly to
// 0 at twice that (0: the coarser level's surface, so switching levels there does not pop).
// Outputs are surface.vert's, so the fragment stage shades as for the other per-vertex
// methods (no search: the geometry is at the visible point).

struct Corner {
  vec4 position_vertex;  // xyz object position, w the base vertex index (float bits)
  vec4 normal;           // xyz the vertex normal (not normalised)
  vec4 uv_scale;         // xy UV, zw |dp/du|, |dp/dv|
  vec4 tangent;          // xyz MikkTSpace tangent, w sign
};
layout(std430, binding = 1) readonly buffer Corners { Corner corners[]; };  // 3 per base triangle, face_halfedges() order
layout(std430, binding = 2) readonly buffer Stream { uvec2 stream[]; };      // the level's vertices, low word first
layout(std430, binding = 0) buffer VertexWork { uint vertex_fetches; };

uniform mat4 u_view_projection;
uniform vec3 u_eye;
uniform int u_segments;       // 2^l of the level drawn
uniform float u_dstream_min;  // quantisation range, object units
uniform float u_dstream_max;
uniform float u_morph;        // >= 0: fixed morph; < 0: by distance
uniform float u_lod_distance; // object units (> 0 when u_morph < 0)

out vec3 v_position;
out vec3 v_normal;
out vec3 v_tangent;
flat out float v_sign;
out vec2 v_uv;
out vec2 v_uv_scale;
out vec3 v_curvature_dir;
out vec2 v_curvature;

float dequantise(uint q) { return u_dstream_min + (u_dstream_max - u_dstream_min) * float(q) / 16383.0; }

void main() {
  uvec2 bits = stream[gl_VertexID];
  atomicAdd(vertex_fetches, 1u);  // one 8-byte stream read per vertex
  int t = int(bits.x & 0x3FFFFFu);
  int i = int((bits.x >> 22) & 127u);
  int j = int(((bits.x >> 29) | (bits.y << 3)) & 127u);
  float value = dequantise((bits.y >> 4) & 16383u);
  float coarse = dequantise((bits.y >> 18) & 16383u);

  int s = u_segments;
  int w[3] = int[3](s - i - j, i, j);
  Corner c[3] = Corner[3](corners[3 * t], corners[3 * t + 1], corners[3 * t + 2]);
  int zero = w[0] == 0 ? 0 : w[1] == 0 ? 1 : w[2] == 0 ? 2 : -1;
  precise vec3 p;
  precise vec3 n;
  vec2 uv;
  vec2 uv_scale;
  vec3 tangent;
  if (zero >= 0) {
    int e0 = (zero + 1) % 3, e1 = (zero + 2) % 3;
    if (floatBitsToInt(c[e1].position_vertex.w) < floatBitsToInt(c[e0].position_vertex.w)) {
      int tmp = e0;
      e0 = e1;
      e1 = tmp;
    }
    precise float f = float(w[e1]) / float(s);  // from e0 toward e1
    p = c[e0].position_vertex.xyz + f * (c[e1].position_vertex.xyz - c[e0].position_vertex.xyz);
    n = c[e0].normal.xyz + f * (c[e1].normal.xyz - c[e0].normal.xyz);
  } else {
    p = (float(w[0]) * c[0].position_vertex.xyz + float(w[1]) * c[1].position_vertex.xyz + float(w[2]) * c[2].position_vertex.xyz) / float(s);
    n = (float(w[0]) * c[0].normal.xyz + float(w[1]) * c[1].normal.xyz + float(w[2]) * c[2].normal.xyz) / float(s);
  }
  // Attributes for shading (UVs, frames): plain barycentric interpolation.
  vec3 b = vec3(float(w[0]), float(w[1]), float(w[2])) / float(s);
  uv = b.x * c[0].uv_scale.xy + b.y * c[1].uv_scale.xy + b.z * c[2].uv_scale.xy;
  uv_scale = b.x * c[0].uv_scale.zw + b.y * c[1].uv_scale.zw + b.z * c[2].uv_scale.zw;
  tangent = b.x * c[0].tangent.xyz + b.y * c[1].tangent.xyz + b.z * c[2].tangent.xyz;

  float m = u_morph;
  if (m < 0.0) m = u_lod_distance > 0.0 ? clamp(2.0 - distance(p, u_eye) / u_lod_distance, 0.0, 1.0) : 1.0;
  float d = (1.0 - m) * coarse + m * value;
  float len = length(n);
  v_position = len > 0.0 ? p + n * (d / len) : p;
  v_normal = n;
  v_tangent = tangent;
  v_sign = c[0].tangent.w;  // the base triangle's first corner, as the baker takes it
  v_uv = uv;
  v_uv_scale = uv_scale;
  v_curvature_dir = vec3(0.0);
  v_curvature = vec2(0.0);
  gl_Position = u_view_projection * vec4(v_position, 1.0);
}
