#version 450 core
// Object space is world space in the previewer. Per-corner attributes come from
// compute_tangent_frames() (bake/tangent_frame.hpp): the MikkTSpace tangent and sign, and
// the lengths of dp/du and dp/dv (object units per UV unit) for stepping in UV space.
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) in vec4 in_tangent;
layout(location = 4) in vec2 in_uv_scale;
layout(location = 5) in vec3 in_curvature_dir;  // principal direction d1 (vdm)
layout(location = 6) in vec2 in_curvature;      // k1, k2, 1 / object units (vdm)

uniform mat4 u_view_projection;
// An affine map of normalised device x and y after the projection: (scale x, offset x,
// scale y, offset y); identity (1, 0, 1, 0) except for DIG-DM's grid pass, which renders the
// rays of every 4th pixel into a small target (dig.glsl).
uniform vec4 u_ndc_transform;

out vec3 v_position;
out vec3 v_normal;
out vec3 v_tangent;
flat out float v_sign;  // from the first corner (glProvokingVertex), as the baker takes it
out vec2 v_uv;
out vec2 v_uv_scale;
out vec3 v_curvature_dir;
out vec2 v_curvature;

void main() {
  v_position = in_position;
  v_normal = in_normal;
  v_tangent = in_tangent.xyz;
  v_sign = in_tangent.w;
  v_uv = in_uv;
  v_uv_scale = in_uv_scale;
  v_curvature_dir = in_curvature_dir;
  v_curvature = in_curvature;
  gl_Position = u_view_projection * vec4(in_position, 1.0);
  gl_Position.xy = gl_Position.xy * u_ndc_transform.xz + u_ndc_transform.yw * gl_Position.w;
}
