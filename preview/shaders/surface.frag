#version 450 core
// Per-pixel displacement on the base mesh. Methods (survey, Szirmay-Kalos & Umenhoffer):
//   0 bump      section 4.1.1: normal map only, the texture coordinate is not moved;
//   1 parallax  section 4.1.2: (u',v') = (u,v) + h(u,v) (Vx/Vz, Vy/Vz);
//   2 pom       section 4.4.2 with 4.3.1: linear search over the height slab, then one secant step.
// Heights are in object units along the base normal, positive outward (meso bake's
// displacement.exr), in [u_h_min, u_h_max]. The ray is expressed in (u, v, h) coordinates:
// per unit of object-space length it advances dot(V,t)/|dp/du| in u, dot(V,b)/|dp/dv| in v
// and dot(V,n) in h (survey eq. 5-7 with an orthonormalised frame).
in vec3 v_position;
in vec3 v_normal;
in vec3 v_tangent;
flat in float v_sign;
in vec2 v_uv;
in vec2 v_uv_scale;

uniform sampler2D u_height;   // R: displacement, object units
uniform sampler2D u_normal;   // RGB: tangent-space normal encoded n * 0.5 + 0.5
uniform vec3 u_eye;
uniform vec3 u_light;         // unit vector toward the light, object space
uniform int u_method;
uniform int u_iterations;
uniform int u_shade;          // 0 lit, 1 uv of the visible point, 2 height of the visible point
uniform float u_h_min;
uniform float u_h_max;

layout(location = 0) out vec4 out_color;

float height_at(vec2 uv) { return texture(u_height, uv).r; }

void main() {
  vec3 n = v_normal;
  vec3 t = v_tangent;
  // Interpolated normals or tangents can cancel (opposite vertex normals across a fold):
  // fall back to a frame from the triangle itself rather than normalise a zero vector.
  vec3 face_n = normalize(cross(dFdx(v_position), dFdy(v_position)));
  if (dot(n, n) < 1e-12) n = face_n;
  vec3 nn = normalize(n);
  vec3 t_perp = t - nn * dot(nn, t);
  if (dot(t_perp, t_perp) < 1e-12) {
    t_perp = abs(nn.x) < 0.9 ? cross(nn, vec3(1, 0, 0)) : cross(nn, vec3(0, 1, 0));
    t = t_perp;
  }
  vec3 b = v_sign * cross(n, t);

  // Orthonormal frame for the ray, scaled to UV units.
  vec3 tn = normalize(t_perp);
  vec3 bn = v_sign * cross(nn, tn);
  vec3 view = normalize(v_position - u_eye);  // from the eye toward the surface
  vec3 dir = vec3(dot(view, tn) / max(v_uv_scale.x, 1e-20), dot(view, bn) / max(v_uv_scale.y, 1e-20), dot(view, nn));

  vec2 uv = v_uv;
  float h = 0.0;
  if (u_method == 1 && dir.z < -1e-6) {
    h = height_at(v_uv);
    uv = v_uv + h * dir.xy / dir.z;
  } else if (u_method == 2 && dir.z < -1e-6) {
    // The ray crosses the slab from h = h_max (parameter s_in < 0, toward the eye) to
    // h = h_min; s is object-space length along the view ray from the base surface point.
    float s_in = u_h_max / dir.z;
    float s_out = u_h_min / dir.z;
    int steps = max(u_iterations, 1);
    float s_prev = s_in;
    float d_prev = dir.z * s_in - height_at(v_uv + dir.xy * s_in);  // ray height minus surface height
    float s_hit = s_out;
    for (int i = 1; i <= steps; ++i) {
      float s = mix(s_in, s_out, float(i) / float(steps));
      float d = dir.z * s - height_at(v_uv + dir.xy * s);
      if (d <= 0.0) {
        // Secant step between the last point above and the first point below the surface.
        float w = d_prev / max(d_prev - d, 1e-20);
        s_hit = mix(s_prev, s, clamp(w, 0.0, 1.0));
        break;
      }
      s_prev = s;
      d_prev = d;
    }
    uv = v_uv + dir.xy * s_hit;
    h = dir.z * s_hit;
  }

  if (u_shade == 1) {
    out_color = vec4(uv, 0.0, 1.0);
    return;
  }
  if (u_shade == 2) {
    out_color = vec4(height_at(uv), 0.0, 0.0, 1.0);
    return;
  }
  // MikkTSpace decoding with the interpolated, unnormalised vectors (tangent_frame.hpp).
  vec3 m = texture(u_normal, uv).rgb * 2.0 - 1.0;
  vec3 N = m.x * t + m.y * b + m.z * n;
  N = dot(N, N) > 1e-20 ? normalize(N) : nn;
  if (!gl_FrontFacing) N = -N;
  float diffuse = max(dot(N, u_light), 0.0);
  vec3 albedo = vec3(0.78, 0.74, 0.70);
  vec3 color = albedo * (0.12 + 0.88 * diffuse);
  out_color = vec4(pow(color, vec3(1.0 / 2.2)), 1.0);
}
