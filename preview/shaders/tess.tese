#version 450 core
// The generated vertices: base attributes interpolated with the tessellation coordinates,
// the position moved along the normalised interpolated normal by the displacement map
// (GL_LINEAR, texel centres at +0.5, as the reference renderer's surface). Outputs are those
// of surface.vert, so the fragment stage shades them as the per-pixel methods do (with no
// search: the geometry is at the visible point). On a shared edge one weight is exactly 0
// and both triangles sum the same two products (`precise`: no fused multiply-add reorders
// them), so shared-edge vertices agree bitwise.
layout(triangles, equal_spacing, ccw) in;

in vec3 e_position[];
in vec3 e_normal[];
in vec4 e_tangent[];
in vec2 e_uv[];
in vec2 e_uv_scale[];

uniform sampler2D u_height;
uniform mat4 u_view_projection;

layout(std430, binding = 0) buffer VertexWork { uint vertex_fetches; };

out vec3 v_position;
out vec3 v_normal;
out vec3 v_tangent;
flat out float v_sign;
out vec2 v_uv;
out vec2 v_uv_scale;
out vec3 v_curvature_dir;  // unused by the per-vertex methods (vdm's input)
out vec2 v_curvature;

void main() {
  precise vec3 w = gl_TessCoord;
  precise vec3 p = w.x * e_position[0] + w.y * e_position[1] + w.z * e_position[2];
  precise vec3 n = w.x * e_normal[0] + w.y * e_normal[1] + w.z * e_normal[2];
  precise vec2 uv = w.x * e_uv[0] + w.y * e_uv[1] + w.z * e_uv[2];
  atomicAdd(vertex_fetches, 1u);
  float h = textureLod(u_height, uv, 0.0).r;
  vec3 nn = dot(n, n) > 0.0 ? normalize(n) : vec3(0.0);
  v_position = p + nn * h;
  v_normal = n;
  v_tangent = w.x * e_tangent[0].xyz + w.y * e_tangent[1].xyz + w.z * e_tangent[2].xyz;
  v_sign = e_tangent[0].w;  // the base triangle's first corner, as the baker takes it
  v_uv = uv;
  v_uv_scale = w.x * e_uv_scale[0] + w.y * e_uv_scale[1] + w.z * e_uv_scale[2];
  v_curvature_dir = vec3(0.0);
  v_curvature = vec2(0.0);
  gl_Position = u_view_projection * vec4(v_position, 1.0);
}
