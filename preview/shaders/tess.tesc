#version 450 core
// Tessellation levels per base triangle for the per-vertex methods.
//   mesh (u_tess_mode 0): brute force, one segment per texel along every edge (the
//     displacement map's resolution). GL caps a level at 64 segments: where an edge spans
//     more texels, renderer.cpp has already cut the base triangles into k x k patches.
//   tessellation (u_tess_mode 1): adaptive edge tests (survey section 3): an edge is cut per
//     texel where the displacement along it departs from linear (by u_tess_displacement of
//     the height range), at least every u_tess_normal_angle of normal change, never into
//     segments shorter than u_tess_pixels on screen, and into at most u_iterations segments.
// Each level is a function of its edge alone, evaluated the same way from both triangles
// (endpoints in a canonical order), so neighbours cut a shared edge alike: no cracks.
layout(vertices = 3) out;

in vec3 c_position[];
in vec3 c_normal[];
in vec4 c_tangent[];
in vec2 c_uv[];
in vec2 c_uv_scale[];

out vec3 e_position[];
out vec3 e_normal[];
out vec4 e_tangent[];
out vec2 e_uv[];
out vec2 e_uv_scale[];

uniform sampler2D u_height;
uniform mat4 u_view_projection;
uniform vec2 u_viewport;  // pixels
uniform int u_tess_mode;
uniform int u_iterations;
uniform float u_h_min;
uniform float u_h_max;
// The adaptive tests' knobs (PreviewOptions::tess_*).
uniform int u_tess_edge_samples;    // intervals sampled along an edge
uniform float u_tess_displacement;  // fraction of the height range
uniform float u_tess_normal_angle;  // radians
uniform float u_tess_pixels;        // shortest segment on screen, pixels

// Height fetches made by the tessellation stages (read back for the fetch statistics).
layout(std430, binding = 0) buffer VertexWork { uint vertex_fetches; };

bool before(vec3 a, vec3 b) { return a.x < b.x || (a.x == b.x && (a.y < b.y || (a.y == b.y && a.z < b.z))); }

float edge_level(int i, int j) {
  if (before(c_position[j], c_position[i])) {
    int k = i;
    i = j;
    j = k;
  }
  vec2 texels = (c_uv[j] - c_uv[i]) * vec2(textureSize(u_height, 0));
  float per_texel = max(ceil(length(texels)), 1.0);
  if (u_tess_mode == 0) return min(per_texel, 64.0);
  // Displacement change: the largest departure from the straight line between the ends.
  float ha = textureLod(u_height, c_uv[i], 0.0).r, hb = textureLod(u_height, c_uv[j], 0.0).r;
  float departure = 0.0;
  for (int k = 1; k < u_tess_edge_samples; ++k) {
    float t = float(k) / float(u_tess_edge_samples);
    departure = max(departure, abs(textureLod(u_height, mix(c_uv[i], c_uv[j], t), 0.0).r - mix(ha, hb, t)));
  }
  atomicAdd(vertex_fetches, uint(u_tess_edge_samples + 1));
  float need = departure > u_tess_displacement * (u_h_max - u_h_min) ? per_texel : 1.0;
  // Normal change.
  vec3 na = c_normal[i], nb = c_normal[j];
  float cosine = dot(na, nb) / max(length(na) * length(nb), 1e-30);
  need = max(need, ceil(acos(clamp(cosine, -1.0, 1.0)) / u_tess_normal_angle));
  // Screen-space length: no segment shorter than u_tess_pixels (ends behind the eye: no limit).
  vec4 a = u_view_projection * vec4(c_position[i], 1.0), b = u_view_projection * vec4(c_position[j], 1.0);
  if (a.w > 0.0 && b.w > 0.0) need = min(need, max(ceil(length((a.xy / a.w - b.xy / b.w) * 0.5 * u_viewport) / u_tess_pixels), 1.0));
  return clamp(need, 1.0, clamp(float(u_iterations), 1.0, 64.0));
}

void main() {
  e_position[gl_InvocationID] = c_position[gl_InvocationID];
  e_normal[gl_InvocationID] = c_normal[gl_InvocationID];
  e_tangent[gl_InvocationID] = c_tangent[gl_InvocationID];
  e_uv[gl_InvocationID] = c_uv[gl_InvocationID];
  e_uv_scale[gl_InvocationID] = c_uv_scale[gl_InvocationID];
  if (gl_InvocationID == 0) {
    // Outer level k belongs to the edge opposite corner k.
    float l0 = edge_level(1, 2), l1 = edge_level(2, 0), l2 = edge_level(0, 1);
    gl_TessLevelOuter[0] = l0;
    gl_TessLevelOuter[1] = l1;
    gl_TessLevelOuter[2] = l2;
    gl_TessLevelInner[0] = max(l0, max(l1, l2));
  }
}
