#version 450 core
// The per-vertex methods (mesh, tessellation): base-mesh corners passed on to the
// tessellation stages (tess.tesc, tess.tese) unchanged; attributes as surface.vert's.
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) in vec4 in_tangent;
layout(location = 4) in vec2 in_uv_scale;

out vec3 c_position;
out vec3 c_normal;
out vec4 c_tangent;
out vec2 c_uv;
out vec2 c_uv_scale;

void main() {
  c_position = in_position;
  c_normal = in_normal;
  c_tangent = in_tangent;
  c_uv = in_uv;
  c_uv_scale = in_uv_scale;
}
