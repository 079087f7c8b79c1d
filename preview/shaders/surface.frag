#line 1 7
// The parallax family and main (see surface_common.glsl for the pieces and conventions).

// The map from object-space vectors to the ray's (u, v, h) coordinates at this fragment.
// meso bake's displaced surface is P(uv) + h N(uv), N the interpolated unit normal (bake.hpp).
// About the fragment's base point P0 (at v_uv) it is, to first order, P0 + J duv + h nn, with
// J = [dp/du dp/dv] the triangle's (exact: UVs are affine over a triangle) and nn the
// normal here; a ray P0 + s V is then (duv, h) = s M^-1 V, M = [dp/du dp/dv nn]: straight in
// (u, v, h), as every tracer below assumes. An orthonormalised tangent frame (t, b, n scaled
// by |dp/du|, |dp/dv|) equals M^-1 only where the UV axes are orthogonal and nn is the face
// normal: on the demo's reduced base it put 2.6 % of the pixels a texel or more from the
// reference's visible point at 60 degrees, against 0.8 % with M^-1 (docs/benchmarks.md).
// The frame remains the fallback where J is unknown (degenerate UVs, the per-vertex
// methods' draws) or M is nearly singular (nn within ~3 degrees of the triangle's plane).
mat3 uvh_from_object(vec3 tn, vec3 bn, vec3 nn) {
  mat3 frame = transpose(mat3(tn / max(v_uv_scale.x, 1e-20), bn / max(v_uv_scale.y, 1e-20), nn));
  if (u_face_jacobians == 0 || gl_PrimitiveID < 0 || 3 * gl_PrimitiveID + 2 >= face_jacobian.length()) return frame;
  vec4 du = face_jacobian[3 * gl_PrimitiveID], dv = face_jacobian[3 * gl_PrimitiveID + 1];
  vec4 ab = face_jacobian[3 * gl_PrimitiveID + 2];
  if (ab.w == 0.0) return frame;
  // M^-1 by cofactors, with J's columns as unit directions a, b and lengths lu, lv (no float
  // overflow or underflow for huge or tiny meshes): rows (b x n / lu, n x a / lv, a x b) / det,
  // det = n . (a x b).
  float det = dot(nn, ab.xyz);
  if (!(abs(det) > 0.05 * length(ab.xyz))) return frame;
  return transpose(mat3(cross(dv.xyz, nn) / (det * du.w), cross(nn, du.xyz) / (det * dv.w), ab.xyz / det));
}

// Self-shadowing (survey section 6): the fraction of the light seen from the visible point
// (uv, its height h). A shadow ray toward light direction L (object space) advances per unit
// length by l = to_uvh L in (u, v, h), as the view ray does; it is sampled at u_shadow_steps
// points up to the top of the height range, and blocked where the height map rises above it
// (by more than a thousandth of the range, so the surface does not shadow itself). Soft
// shadows average 8 rays toward points of a disc light around L.
float shadow_ray(vec2 uv, float h, vec3 L, mat3 to_uvh) {
  vec3 l = to_uvh * L;
  if (l.z <= 1e-6) return 1.0;  // the light is at or below the base plane: Lambert's term decides
  float s_top = (u_h_max - h) / l.z;
  float bias = 1e-3 * (u_h_max - u_h_min);
  int steps = max(u_shadow_steps, 1);
  for (int i = 1; i <= steps; ++i) {
    float s = s_top * float(i) / float(steps);
    if (height_lookup(uv + l.xy * s) > h + l.z * s + bias) return 0.0;
  }
  return 1.0;
}

float light_visibility(vec2 uv, mat3 to_uvh) {
  float h = height_lookup(uv);
  if (u_shadows == 1) return shadow_ray(uv, h, u_light, to_uvh);
  // A frame around the light direction; 8 directions on a circle at 0.7 of the light's radius.
  vec3 a = normalize(abs(u_light.z) < 0.9 ? cross(u_light, vec3(0, 0, 1)) : cross(u_light, vec3(1, 0, 0)));
  vec3 c = cross(u_light, a);
  float r = tan(u_light_size) * 0.7;
  float sum = 0.0;
  for (int k = 0; k < 8; ++k) {
    float phi = 6.2831853 * float(k) / 8.0;
    sum += shadow_ray(uv, h, normalize(u_light + r * (cos(phi) * a + sin(phi) * c)), to_uvh);
  }
  return sum / 8.0;
}

void main() {
  // Depth correction: per-pixel methods move it to the visible point below.
  gl_FragDepth = gl_FragCoord.z;
  vec3 n = v_normal;
  vec3 t = v_tangent;
  // Interpolated normals or tangents can cancel (opposite vertex normals across a fold):
  // fall back to a frame from the triangle itself rather than normalise a zero vector.
  vec3 face_n = normalize(cross(dFdx(v_position), dFdy(v_position)));
  vec2 uv_dx = dFdx(v_uv), uv_dy = dFdy(v_uv);  // here, in uniform control flow (DIG-DM's fallback)
  if (dot(n, n) < 1e-12) n = face_n;
  vec3 nn = normalize(n);
  vec3 t_perp = t - nn * dot(nn, t);
  if (dot(t_perp, t_perp) < 1e-12) {
    t_perp = abs(nn.x) < 0.9 ? cross(nn, vec3(1, 0, 0)) : cross(nn, vec3(0, 1, 0));
    t = t_perp;
  }
  vec3 b = v_sign * cross(n, t);

  // Orthonormal frame (vdm's angles, and uvh_from_object's fallback).
  vec3 tn = normalize(t_perp);
  vec3 bn = v_sign * cross(nn, tn);
  vec3 view = normalize(v_position - u_eye);  // from the eye toward the surface
  mat3 to_uvh = uvh_from_object(tn, bn, nn);
  vec3 dir = to_uvh * view;  // the view ray's advance per unit length in (u, v, h)
  // Per unit length the ray rises dir.z along nn while its base point moves by across (J
  // dir.xy): sin(theta) = |across| and cos(theta) = -dir.z in an orthonormal frame. Where nn
  // leans off the triangle the two are not orthogonal; the parallax family, the adaptive step
  // counts and the silhouettes' bend take them as if they were, over the base: the survey's
  // unit V toward the eye is -dir / ray_length, its V_z <= 1.
  vec3 across = view - dir.z * nn;
  float ray_length = sqrt(dir.z * dir.z + dot(across, across));
  g_view_cos = ray_length > 0.0 ? -dir.z / ray_length : 0.0;
  vec3 to_eye_uvh = ray_length > 0.0 ? -dir / ray_length : vec3(0.0);

  vec2 uv = v_uv;
  float amortised_fetches = 0.0;  // a share of work done outside this fragment (DIG's grid pass)
  bool facing = dir.z < -1e-6;  // grazing or back-facing rays keep the base point
  // With silhouettes on a curved base (section 5.1) the base falls away from the tangent
  // plane by c x^2 / 2 at horizontal distance x, c the curvature along the view: the ray's
  // height over the bent base is z(s) = dir.z s + bend s^2, bend = c |across|^2 / 2 (x = s
  // |across|; sin^2(theta) in an orthonormal frame).
  float bend = u_silhouettes != 0 ? 0.5 * view_curvature(view, nn) * dot(across, across) : 0.0;
  bool escaped = false;  // a safe method's ray left the surface without a hit
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
    // Section 4.2.1: repeat the slope step from the point reached on the ray. A step scales
    // the height error by 1 - n_z V_z: it converges because V_z <= 1 (with dir itself, whose
    // height rate reaches 20 where the normal leans off the triangle, it diverged).
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
    // On a curved base (`bend`, above) the search ends where the ray's height reaches h_min
    // or, when it never does, where it climbs back to h_max; a ray that meets nothing there
    // left the surface (discarded).
    float s_in, s_out;
    bool escapes;
    ray_slab(dir, bend, s_in, s_out, escapes);
    // POM adapts its step count to the view (section 4.4.2); steep and relief take the budget.
    int steps = u_method == kPom ? view_adapted_steps(u_iterations) : max(u_iterations, 1);
    float s_prev = s_in;
    float d_prev = dir.z * s_in + bend * s_in * s_in - height_at(v_uv + dir.xy * s_in);  // ray height minus surface height
    float s_hit = s_out;
    bool found = false;
    if (d_prev <= 0.0) {
      s_hit = s_in;
      found = true;
    } else {
      for (int i = 1; i <= steps; ++i) {
        float s = mix(s_in, s_out, float(i) / float(steps));
        float d = dir.z * s + bend * s * s - height_at(v_uv + dir.xy * s);
        if (d <= 0.0) {
          found = true;
          if (u_method == kSteep) {
            s_hit = s;
          } else if (u_method == kPom) {
            float w = d_prev / max(d_prev - d, 1e-20);
            s_hit = mix(s_prev, s, clamp(w, 0.0, 1.0));
          } else {
            float above = s_prev, below = s;
            for (int j = 0; j < u_binary_steps; ++j) {
              float mid = 0.5 * (above + below);
              if (dir.z * mid + bend * mid * mid - height_at(v_uv + dir.xy * mid) <= 0.0) below = mid;
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
    if (!found && (escapes || (u_silhouettes != 0 && bend != 0.0))) discard;  // the ray left the surface
    uv = v_uv + dir.xy * s_hit;
  } else if ((u_method == kCone || u_method == kRelaxedCone) && facing) {
    uv = v_uv + dir.xy * cone_trace(dir, u_method == kRelaxedCone, bend, escaped);
  } else if (u_method == kSphereTracing && facing) {
    uv = v_uv + dir.xy * sphere_trace(dir, bend, escaped);
  } else if (u_method == kPyramid && facing) {
    uv = v_uv + dir.xy * pyramid_trace(dir, bend, escaped);
  } else if (u_method == kDig && u_dig_pass == 1) {
    // The grid pass: the corner ray's depth and its fetches (nothing else is drawn).
    out_color = vec4(facing ? dig_corner_depth(dir, bend) : -1.0, float(g_fetches), 0.0, 1.0);
    return;
  } else if (u_method == kDig && facing) {
    uv = v_uv + dir.xy * dig_trace(dir, bend, uv_dx, uv_dy, amortised_fetches, escaped);
  } else if (u_method == kVdm && facing) {
    if (!vdm_trace(view, tn, bn, nn, dir, uv)) discard;  // the ray left the bent height field
  }

  // A safe method's ray that left the surface: climbed back out over a convex base, or left
  // a clamped map's footprint (silhouettes). With silhouettes the cones and the pyramid stop
  // where the ray leaves a clamped map and return that point, on the border, which the rule
  // below would keep; the linear searches go on over the clamped surface to a point off the
  // map, which it discards: so both discard such rays, straight or bent. (Sphere tracing's
  // field covers the clamped surface, and its point off the map is discarded below; without
  // silhouettes every method follows the clamped surface beyond the map.)
  if (escaped && u_silhouettes != 0) discard;

  // Silhouettes at the map's border: a visible point outside [0, 1]^2 of a map that does not
  // tile is off the surface's footprint.
  if (u_silhouettes != 0 && u_wrap == 0 && (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0))))) discard;

  // The visible point's depth, so that displaced surfaces intersect each other correctly (the
  // point where the view ray is at the visible point's height: exact for the search methods,
  // the parallax family's estimate for the others). Beyond the far plane it is held just in
  // front of it: the cleared depth, 1, would hide the pixel (a hole where a nearly grazing
  // height rate put the parallax family's estimate far behind the surface).
  if (facing && u_method != kMesh && u_method != kTessellation && u_method != kDstream && u_method != kBump) {
    vec4 clip = u_view_projection * vec4(v_position + view * (height_lookup(uv) / dir.z), 1.0);
    if (clip.w > 0.0) gl_FragDepth = clamp(0.5 * clip.z / clip.w + 0.5, 0.0, 0.99999994);
  }

  out_fetches = vec2(float(g_fetches) + amortised_fetches, 1.0);
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
  if (u_shadows != 0 && diffuse > 0.0) diffuse *= light_visibility(uv, to_uvh);
  vec3 albedo = vec3(0.78, 0.74, 0.70);
  vec3 color = albedo * (0.12 + 0.88 * diffuse);
  out_color = vec4(pow(color, vec3(1.0 / 2.2)), 1.0);
}
