#version 450 core
// Per-pixel displacement on the base mesh, the methods of the survey (Szirmay-Kalos &
// Umenhoffer) by section: bump 4.1.1 (normal map only), parallax 4.1.2, offset-limited 4.1.3,
// slope 4.1.4, iterative-parallax 4.2.1, steep 4.3.1, relief 4.4.1, pom 4.4.2,
// sphere-tracing 4.3.4.
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
uniform sampler3D u_sdf;      // meso streams sdf: R = distance in units of u (bound when used)
uniform float u_sdf_scale;    // object height = bias + scale * normalised height
uniform float u_sdf_bias;
uniform float u_sdf_relief;   // height range in units of u
uniform float u_sdf_aspect;   // H / W of the height map
uniform float u_sdf_epsilon;  // stop distance, units of u
uniform float u_sdf_margin;   // one voxel diagonal, units of u

// Method numbers: the order of preview_methods() in renderer.cpp.
const int kBump = 0, kParallax = 1, kOffsetLimited = 2, kSlope = 3, kIterativeParallax = 4, kSteep = 5,
          kRelief = 6, kPom = 7, kSphereTracing = 8;
const int kReliefBinarySteps = 8;

layout(location = 0) out vec4 out_color;

// Explicit level of detail: loops have no implicit derivatives (divergent control flow).
float height_at(vec2 uv) { return textureLod(u_height, uv, 0.0).r; }
vec3 normal_ts_at(vec2 uv) { return textureLod(u_normal, uv, 0.0).rgb * 2.0 - 1.0; }

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

  // Unit view vector toward the viewer in the orthonormal tangent frame (the survey's V), and
  // its advance per unit length in (u, v, h).
  vec3 to_eye = -vec3(dot(view, tn), dot(view, bn), dot(view, nn));
  vec3 to_eye_uvh = vec3(to_eye.xy / max(v_uv_scale, vec2(1e-20)), to_eye.z);

  vec2 uv = v_uv;
  bool facing = dir.z < -1e-6;  // grazing or back-facing rays keep the base point
  if (u_method == kParallax && facing) {
    // Section 4.1.2: assume the height at (u, v) holds everywhere.
    uv = v_uv + height_at(v_uv) * dir.xy / dir.z;
  } else if (u_method == kOffsetLimited && facing) {
    // Section 4.1.3: drop the division by V_z, so the offset never exceeds the height.
    uv = v_uv + height_at(v_uv) * to_eye_uvh.xy;
  } else if (u_method == kSlope && facing) {
    // Section 4.1.4: the plane through (u, v, h) with the normal-map normal, offset-limited.
    uv = v_uv + height_at(v_uv) * normal_ts_at(v_uv).z * to_eye_uvh.xy;
  } else if (u_method == kIterativeParallax && facing) {
    // Section 4.2.1: repeat the slope step from the point reached on the ray.
    vec3 uvh = vec3(v_uv, 0.0);
    for (int i = 0; i < max(u_iterations, 1); ++i) {
      uvh += (height_at(uvh.xy) - uvh.z) * normal_ts_at(uvh.xy).z * to_eye_uvh;
    }
    uv = uvh.xy;
  } else if ((u_method == kSteep || u_method == kRelief || u_method == kPom) && facing) {
    // Section 4.3.1 linear search over the height slab from h = h_max (parameter s_in < 0,
    // toward the eye) to h = h_min; s is object-space length along the view ray from the base
    // point. Steep parallax stops at the first sample below the surface; relief mapping
    // refines by binary search (4.4.1), POM by one secant step (4.4.2).
    float s_in = u_h_max / dir.z;
    float s_out = u_h_min / dir.z;
    int steps = max(u_iterations, 1);
    float s_prev = s_in;
    float d_prev = dir.z * s_in - height_at(v_uv + dir.xy * s_in);  // ray height minus surface height
    float s_hit = s_out;
    if (d_prev <= 0.0) {
      s_hit = s_in;
    } else {
      for (int i = 1; i <= steps; ++i) {
        float s = mix(s_in, s_out, float(i) / float(steps));
        float d = dir.z * s - height_at(v_uv + dir.xy * s);
        if (d <= 0.0) {
          if (u_method == kSteep) {
            s_hit = s;
          } else if (u_method == kPom) {
            float w = d_prev / max(d_prev - d, 1e-20);
            s_hit = mix(s_prev, s, clamp(w, 0.0, 1.0));
          } else {
            float above = s_prev, below = s;
            for (int j = 0; j < kReliefBinarySteps; ++j) {
              float mid = 0.5 * (above + below);
              if (dir.z * mid - height_at(v_uv + dir.xy * mid) <= 0.0) below = mid;
              else above = mid;
            }
            s_hit = 0.5 * (above + below);
          }
          break;
        }
        s_prev = s;
        d_prev = d;
      }
    }
    uv = v_uv + dir.xy * s_hit;
  } else if (u_method == kSphereTracing && facing) {
    // Section 4.3.4 on meso's distance field (streams/distance_field.hpp): in its space the
    // point is (u, v H/W, normalised height * relief), distances in units of u. March from the
    // top of the box by the stored distance until it vanishes.
    float span = max(u_sdf_scale, 1e-20);
    vec3 D = vec3(dir.x, dir.y * u_sdf_aspect, dir.z * u_sdf_relief / span);  // per unit s
    float len = length(D);
    // Trilinear filtering blends the 8 voxel centres around a point, and the field is exact
    // only at centres: with the 1-Lipschitz bound d(q) >= d(v) - |q - v| the blend can exceed
    // the true distance by at most one voxel diagonal (u_sdf_margin), so that much is held back.
    float s = (u_sdf_bias + u_sdf_scale) / dir.z;  // where the ray enters the top (h = bias + scale)
    for (int i = 0; i < max(u_iterations, 1); ++i) {
      vec2 p = v_uv + dir.xy * s;
      float z = (dir.z * s - u_sdf_bias) / span;  // normalised height
      if (z < 0.0) break;
      float step = textureLod(u_sdf, vec3(p, clamp(z, 0.0, 1.0)), 0.0).r - u_sdf_margin;
      if (step < u_sdf_epsilon) break;
      s += step / len;
    }
    // Within a margin of the surface: finish as a combined method (section 4.4) with a short
    // linear search at a quarter margin per step, then one secant step.
    float ds = 0.25 * u_sdf_margin / len;
    float d_prev = dir.z * s - height_at(v_uv + dir.xy * s);
    for (int i = 0; i < 12 && d_prev > 0.0; ++i) {
      float d = dir.z * (s + ds) - height_at(v_uv + dir.xy * (s + ds));
      if (d <= 0.0) {
        s += ds * clamp(d_prev / max(d_prev - d, 1e-20), 0.0, 1.0);
        break;
      }
      s += ds;
      d_prev = d;
    }
    uv = v_uv + dir.xy * s;
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
  vec3 m = normal_ts_at(uv);
  vec3 N = m.x * t + m.y * b + m.z * n;
  N = dot(N, N) > 1e-20 ? normalize(N) : nn;
  if (!gl_FrontFacing) N = -N;
  float diffuse = max(dot(N, u_light), 0.0);
  vec3 albedo = vec3(0.78, 0.74, 0.70);
  vec3 color = albedo * (0.12 + 0.88 * diffuse);
  out_color = vec4(pow(color, vec3(1.0 / 2.2)), 1.0);
}
