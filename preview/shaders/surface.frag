#version 450 core
// Per-pixel displacement on the base mesh, the methods of the survey (Szirmay-Kalos &
// Umenhoffer) by section: bump 4.1.1 (normal map only), parallax 4.1.2, offset-limited 4.1.3,
// slope 4.1.4, iterative-parallax 4.2.1, steep 4.3.1, relief 4.4.1, pom 4.4.2,
// cone 4.3.5, relaxed-cone 4.4.3, sphere-tracing 4.3.4.
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
uniform sampler2D u_cone;     // meso streams cone / relaxed-cone, level 0 (bound when used), read
                              // with texelFetch only: R = texel height, G = cone ratio (units of u
                              // per unit normalised height), B = apex height (normalised)
uniform float u_cone_scale;   // object height = bias + scale * normalised height
uniform float u_cone_bias;
uniform int u_cone_wrap;      // 1: border wrap (the map tiles), 0: clamp

// Method numbers: the order of preview_methods() in renderer.cpp.
const int kBump = 0, kParallax = 1, kOffsetLimited = 2, kSlope = 3, kIterativeParallax = 4, kSteep = 5,
          kRelief = 6, kPom = 7, kCone = 8, kRelaxedCone = 9, kSphereTracing = 10;
const int kReliefBinarySteps = 8;
const int kConeBisectionSteps = 24;  // relaxed cones: halvings of the step that crossed the surface
const float kConeFar = 1e30;

layout(location = 0) out vec4 out_color;
// The measuring instrument's second output (an RG32F attachment when headless; discarded
// when no draw buffer takes it): R = texture fetches the method made to find the visible
// point, G = 1 on the mesh (the clear leaves 0 on the background).
layout(location = 1) out vec2 out_fetches;

// Fetch counter: every lookup of the height map, of a stream (cone texel, distance field
// voxel) and of the normal map where a method searches with it (slope, iterative parallax)
// adds one, a filtered lookup (4 texels blended by the sampler) as much as a texelFetch. The
// shading's own lookups at the visible point are not counted.
int g_fetches = 0;

// Explicit level of detail: loops have no implicit derivatives (divergent control flow).
float height_lookup(vec2 uv) { return textureLod(u_height, uv, 0.0).r; }
vec3 normal_ts_at(vec2 uv) { return textureLod(u_normal, uv, 0.0).rgb * 2.0 - 1.0; }
// The counted lookups of the searches.
float height_at(vec2 uv) {
  ++g_fetches;
  return height_lookup(uv);
}
vec3 normal_search_at(vec2 uv) {
  ++g_fetches;
  return normal_ts_at(uv);
}

// ---- Cone stepping (streams/cone_map.hpp; the algorithm of trace_cone_map and
// intersect_footprint in streams/src/cone_map.cpp). Pixel units as the streams use them:
// x = u W, y = (1 - v) H (rows from the top, texel (i, j) covers [i, i+1] x [j, j+1]),
// z = normalised height in [0, 1].

// k modulo n, for any sign of k (GLSL's % is undefined for negative operands).
int cone_wrap_index(int k, int n) {
  if (k < 0) k += n * ((n - 1 - k) / n);
  return k % n;
}

// Texel (i, j) of the cone map (j from the top row) under the height field's border rule.
vec3 cone_texel(ivec2 p) {
  ivec2 n = textureSize(u_cone, 0);
  if (u_cone_wrap != 0) p = ivec2(cone_wrap_index(p.x, n.x), cone_wrap_index(p.y, n.y));
  else p = clamp(p, ivec2(0), n - 1);
  ++g_fetches;
  return texelFetch(u_cone, ivec2(p.x, n.y - 1 - p.y), 0).rgb;  // GL rows are bottom first
}

// The surface S at pixel position q: bilinear through the texel centres (GL_LINEAR's
// surface, HeightField::bilinear), computed from fetched texels so that it is the exact
// surface the cones were built for, free of the sampler's reduced weight precision.
float cone_surface(vec2 q) {
  vec2 f = q - 0.5;
  vec2 f0 = floor(f);
  vec2 w = f - f0;
  ivec2 i = ivec2(f0);
  float a = cone_texel(i).r, b = cone_texel(i + ivec2(1, 0)).r;
  float c = cone_texel(i + ivec2(0, 1)).r, d = cone_texel(i + ivec2(1, 1)).r;
  return (a * (1.0 - w.x) + b * w.x) * (1.0 - w.y) + (c * (1.0 - w.x) + d * w.x) * w.y;
}

// The texel a point belongs to: the one it is in, or on an edge the one ahead along d.
ivec2 cone_cell(vec2 p, vec2 d) {
  vec2 f = floor(p);
  ivec2 c = ivec2(f);
  if (p.x == f.x && d.x < 0.0) c.x -= 1;
  if (p.y == f.y && d.y < 0.0) c.y -= 1;
  return c;
}

// The first intersection of the ray o + t d with S over texel `cell`'s footprint for t in
// [t0, t1] (the ray stays over the footprint there). The lines x = i + 1/2 and y = j + 1/2
// split the stretch into up to three pieces over each of which S is one bilinear
// polynomial (corners on the half-texel grid), so S(ray(t)) - z(t) is a quadratic in t.
bool cone_footprint_hit(ivec2 cell, vec3 o, vec3 d, float t0, float t1, out float t_hit) {
  t_hit = t1;
  float cx = kConeFar, cy = kConeFar;
  if (d.x != 0.0) cx = (float(cell.x) + 0.5 - o.x) / d.x;
  if (d.y != 0.0) cy = (float(cell.y) + 0.5 - o.y) / d.y;
  float cut[4] = float[4](t0, min(cx, cy), max(cx, cy), t1);
  for (int k = 1; k <= 2; ++k) cut[k] = clamp(cut[k], t0, t1);
  for (int k = 0; k < 3; ++k) {
    float ta = cut[k], tb = cut[k + 1];
    if (k > 0 && !(tb > ta)) continue;  // empty stretch (the first one is kept: t0 may equal t1)
    float tm = 0.5 * (ta + tb);
    vec2 m = clamp(o.xy + tm * d.xy, vec2(cell), vec2(cell) + 1.0);
    vec2 pc = vec2(m.x < float(cell.x) + 0.5 ? float(cell.x) : float(cell.x) + 0.5,
                   m.y < float(cell.y) + 0.5 ? float(cell.y) : float(cell.y) + 0.5);
    float v00 = cone_surface(pc), v10 = cone_surface(pc + vec2(0.5, 0.0));
    float v01 = cone_surface(pc + vec2(0.0, 0.5)), v11 = cone_surface(pc + vec2(0.5, 0.5));
    float pa = v10 - v00, pb = v01 - v00, pe = v00 - v10 - v01 + v11;
    // Local coordinates (s, r) in [0, 1]^2 over the piece; the parameter is tau = t - ta,
    // measured from the stretch's start to keep the coefficients small.
    vec3 a3 = o + ta * d;
    float s0 = 2.0 * (a3.x - pc.x), sd = 2.0 * d.x, r0 = 2.0 * (a3.y - pc.y), rd = 2.0 * d.y;
    float A = pe * sd * rd;
    float B = pa * sd + pb * rd + pe * (s0 * rd + r0 * sd) - d.z;
    float C = v00 + pa * s0 + pb * r0 + pe * s0 * r0 - a3.z;
    float L = tb - ta;
    if (C >= 0.0) {
      t_hit = ta;
      return true;
    }
    float best = kConeFar;
    if (abs(A) * L * L <= 1e-6 * (abs(A) * L * L + abs(B) * L + abs(C))) {
      if (B != 0.0) best = -C / B;
    } else {
      float disc = B * B - 4.0 * A * C;
      if (disc >= 0.0) {
        float q = -0.5 * (B + (B >= 0.0 ? 1.0 : -1.0) * sqrt(disc));
        float r1 = q / A, r2 = q != 0.0 ? C / q : kConeFar;
        if (r1 >= 0.0 && r1 <= L) best = min(best, r1);
        if (r2 >= 0.0 && r2 <= L) best = min(best, r2);
      }
    }
    if (best >= 0.0 && best <= L) {
      t_hit = ta + best;
      return true;
    }
    if ((A * L + B) * L + C >= 0.0) {
      // Rounding hid the root: bisect the sign change.
      float lo = 0.0, hi = L;
      for (int it = 0; it < kConeBisectionSteps; ++it) {
        float mid = 0.5 * (lo + hi);
        if ((A * mid + B) * mid + C >= 0.0) hi = mid;
        else lo = mid;
      }
      t_hit = ta + hi;
      return true;
    }
  }
  return false;
}

// Cone stepping (4.3.5) and relaxed cone stepping (4.4.3) from where the view ray enters the
// top of the height volume. Over texel p at height z >= T_p (its apex) the cone of apex
// (x, T_p) holds no surface above the ray's next stretch, so the ray advances to the cone's
// boundary; when that step would not leave p's footprint, the ray is intersected exactly with
// S over the footprint and moves on to the next texel. A relaxed cone's step may cross the
// surface, at most once: its end below the surface starts a bisection. Returns the visible
// point's s (object length along the view ray from the base point).
float cone_trace(vec3 dir, bool relaxed) {
  if (!(u_cone_scale > 0.0)) return u_cone_bias / dir.z;  // a flat map: the plane h = bias
  ivec2 size = textureSize(u_cone, 0);
  vec2 n = vec2(size);
  float s_top = (u_cone_bias + u_cone_scale) / dir.z;  // where h = bias + scale (z = 1)
  vec2 uv_top = v_uv + dir.xy * s_top;
  // The ray o + t d, t = s - s_top, in pixel units and normalised height.
  vec3 o = vec3(uv_top.x * n.x, (1.0 - uv_top.y) * n.y, 1.0);
  vec3 d = vec3(dir.x * n.x, -dir.y * n.y, dir.z / u_cone_scale);
  float horizontal = length(d.xy);
  float t_floor = 1.0 / -d.z;  // z = 0, below every point of the surface
  float t = 0.0;
  float t_out = kConeFar;  // clamp: where the ray leaves [0, W] x [0, H]
  bool clamped = u_cone_wrap == 0;
  if (clamped) {
    // The cones know nothing beyond the map: start where the ray comes over it (the top
    // entry point may lie outside) and stop where it leaves it, keeping that point.
    float t_in = 0.0;
    for (int k = 0; k < 2; ++k) {
      if (d[k] != 0.0) {
        float ta = -o[k] / d[k], tb = (n[k] - o[k]) / d[k];
        t_in = max(t_in, min(ta, tb));
        t_out = min(t_out, max(ta, tb));
      } else if (o[k] < 0.0 || o[k] > n[k]) {
        t_out = -1.0;
      }
    }
    if (t_in > min(t_out, t_floor)) return s_top;  // never over the map above the floor
    t = t_in;
  }
  ivec2 cell = cone_cell(o.xy + t * d.xy, d.xy);
  if (clamped) cell = clamp(cell, ivec2(0), size - 1);
  for (int i = 0; i < max(u_iterations, 1); ++i) {
    if (clamped && (any(lessThan(cell, ivec2(0))) || any(greaterThanEqual(cell, size)))) break;  // left the map
    vec3 p = o + t * d;
    vec3 c = cone_texel(cell);
    float ratio = c.g * n.x, apex = c.b;  // ratio in texels per unit height
    float tx = d.x > 0.0 ? (float(cell.x + 1) - o.x) / d.x : (d.x < 0.0 ? (float(cell.x) - o.x) / d.x : kConeFar);
    float ty = d.y > 0.0 ? (float(cell.y + 1) - o.y) / d.y : (d.y < 0.0 ? (float(cell.y) - o.y) / d.y : kConeFar);
    float t_exit = max(min(min(tx, ty), t_floor), t);
    float den = horizontal + ratio * -d.z;  // 0 only for a flat cone seen straight on
    float step = p.z >= apex && den > 0.0 ? ratio * (p.z - apex) / den : 0.0;
    if (t + step < t_exit || t_exit <= t) {
      // The cone does not reach beyond the footprint: intersect S over it exactly.
      float t_hit;
      if (cone_footprint_hit(cell, o, d, t, t_exit, t_hit)) {
        t = t_hit;
        break;
      }
      if (t_exit >= t_floor) {
        t = t_floor;
        break;
      }
      t = t_exit;
      // The next texel along the ray: across the edge (or corner) the ray left by.
      if (tx <= t_exit) cell.x += d.x > 0.0 ? 1 : -1;
      if (ty <= t_exit) cell.y += d.y > 0.0 ? 1 : -1;
      continue;
    }
    float tq = min(t + step, min(t_floor, t_out));
    vec3 q = o + tq * d;
    if (relaxed && cone_surface(q.xy) >= q.z) {
      // The step crossed the surface once (the relaxed cone's guarantee): bisect it.
      float lo = t, hi = tq;
      for (int it = 0; it < kConeBisectionSteps; ++it) {
        float mid = 0.5 * (lo + hi);
        vec3 r = o + mid * d;
        if (cone_surface(r.xy) >= r.z) hi = mid;
        else lo = mid;
      }
      t = hi;
      break;
    }
    t = tq;
    if (tq >= t_out) break;  // left the map (clamp)
    cell = cone_cell(q.xy, d.xy);
    if (clamped) cell = clamp(cell, ivec2(0), size - 1);
  }
  return s_top + t;
}

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
    uv = v_uv + height_at(v_uv) * normal_search_at(v_uv).z * to_eye_uvh.xy;
  } else if (u_method == kIterativeParallax && facing) {
    // Section 4.2.1: repeat the slope step from the point reached on the ray.
    vec3 uvh = vec3(v_uv, 0.0);
    for (int i = 0; i < max(u_iterations, 1); ++i) {
      uvh += (height_at(uvh.xy) - uvh.z) * normal_search_at(uvh.xy).z * to_eye_uvh;
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
  } else if ((u_method == kCone || u_method == kRelaxedCone) && facing) {
    uv = v_uv + dir.xy * cone_trace(dir, u_method == kRelaxedCone);
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
    // The field measures the distance to S', boxes as high as the highest point over their
    // texel, which can float above the surface: where it allows no step (within a margin of
    // S'), march a quarter margin at a time watching the true surface, resuming sphere steps
    // where the field opens up again, and finish with a secant step at the crossing (a
    // combined method, section 4.4). Every pass of the loop counts against the budget.
    float ds = 0.25 * u_sdf_margin / len;
    bool marching = false;  // the previous pass was a march step from s_prev, d_prev above the surface
    float s_prev = s, d_prev = 0.0;
    for (int i = 0; i < max(u_iterations, 1); ++i) {
      vec2 p = v_uv + dir.xy * s;
      float z = (dir.z * s - u_sdf_bias) / span;  // normalised height
      ++g_fetches;
      float step = textureLod(u_sdf, vec3(p, clamp(z, 0.0, 1.0)), 0.0).r - u_sdf_margin;
      if (step >= u_sdf_epsilon && z >= 0.0) {
        s += step / len;
        marching = false;
        continue;
      }
      float d = dir.z * s - height_at(p);  // ray height minus surface height
      if (d <= 0.0) {
        if (marching) s = s_prev + (s - s_prev) * clamp(d_prev / max(d_prev - d, 1e-20), 0.0, 1.0);
        break;
      }
      marching = true;
      s_prev = s;
      d_prev = d;
      s += ds;
    }
    uv = v_uv + dir.xy * s;
  }

  out_fetches = vec2(float(g_fetches), 1.0);
  if (u_shade == 1) {
    out_color = vec4(uv, 0.0, 1.0);
    return;
  }
  if (u_shade == 2) {
    out_color = vec4(height_lookup(uv), 0.0, 0.0, 1.0);
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
