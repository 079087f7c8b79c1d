#line 1 4
// Sphere tracing (survey 4.3.4) on meso streams sdf (streams/distance_field.hpp).
// Returns the visible point's s (object length along the view ray from the base point).
// Bent rays (bend != 0, footprint.glsl): a step of length x along the arc moves the point by
// at most |D| x + |E| x^2 (D the arc's direction where it starts, 2 E its constant
// curvature term), so steps keep that within the empty ball; a ray that climbs back out of
// the height volume without a hit sets `escaped` (a silhouette).
float sphere_trace(vec3 dir, float bend, out bool escaped) {
  escaped = false;
  if (!(u_sdf_scale > 0.0) || !ray_enters(dir, bend, u_sdf_bias + u_sdf_scale)) {
    // A flat map (the plane h = bias), or a bent ray that passes over the whole volume.
    escaped = !ray_enters(dir, bend, u_sdf_bias);
    return ray_entry(dir, bend, u_sdf_bias);
  }
  // Section 4.3.4 on meso's distance field (streams/distance_field.hpp): in its space the
  // point is (u, v H/W, normalised height * relief), distances in units of u. March from the
  // top of the box by the stored distance until it vanishes.
  float span = u_sdf_scale;
  vec3 D = vec3(dir.x, dir.y * u_sdf_aspect, dir.z * u_sdf_relief / span);  // per unit s
  float len = length(D);
  // Trilinear filtering blends the 8 voxel centres around a point, and the field is exact
  // only at centres: with the 1-Lipschitz bound d(q) >= d(v) - |q - v| the blend can exceed
  // the true distance by at most one voxel diagonal (u_sdf_margin), so that much is held back.
  float s = ray_entry(dir, bend, u_sdf_bias + u_sdf_scale);  // where the ray enters the top (h = bias + scale)
  float E = bend * u_sdf_relief / span;  // half the arc's second derivative, field units
  // The field measures the distance to S', boxes as high as the highest point over their
  // texel, which can float above the surface: where it allows no step (within a margin of
  // S'), the ray is intersected exactly with the filtered surface over the texel it is in
  // (footprint.glsl, as the cone and pyramid tracers do) and, when it passes over it, moves
  // on to the texel's exit, where sphere steps resume if the field opens up again. So no
  // crossing is ever stepped over (a safe method, section 4.3), whatever the slice count.
  // Every pass of the loop counts against the budget.
  // The ray in footprint.glsl's pixel units, parametrised by s itself: o + s d.
  vec2 n = vec2(textureSize(u_height, 0));
  vec3 o = vec3(v_uv.x * n.x, (1.0 - v_uv.y) * n.y, -u_sdf_bias / span);
  vec3 d = vec3(dir.x * n.x, -dir.y * n.y, dir.z / span);
  float e = bend / span;
  // Normalised height 0, below every point of the surface (or where a bent ray escapes).
  bool escapes = false;
  float s_floor = u_sdf_bias / dir.z;
  if (bend != 0.0) {
    // From the entry point on: height z_in there, slope d.z + 2 e s.
    float z_in = min((dir.z * s + bend * s * s - u_sdf_bias) / span, 1.0);
    s_floor = s + ray_end(vec3(0.0, 0.0, z_in), vec3(0.0, 0.0, d.z + 2.0 * e * s), e, escapes);
  }
  // After a texel without a crossing, the texel ahead (tracked, as cone_trace does, so that
  // rounding at the shared edge cannot send the ray back into the texel it left).
  bool walking = false;
  ivec2 cell = ivec2(0);
  for (int i = 0; i < max(u_iterations, 1); ++i) {
    vec2 p = v_uv + dir.xy * s;
    float z = (dir.z * s + bend * s * s - u_sdf_bias) / span;  // normalised height
    if (z <= 0.0 || (escapes && s >= s_floor)) {
      escaped = escapes;
      return s_floor;
    }
    ++g_fetches;
    float step = textureLod(u_sdf, vec3(p, clamp(z, 0.0, 1.0)), 0.0).r - u_sdf_margin;
    if (step >= u_sdf_epsilon) {
      if (bend == 0.0) {
        s += step / len;
      } else {
        float l = length(vec3(D.xy, (dir.z + 2.0 * bend * s) * u_sdf_relief / span));
        s += 2.0 * step / (l + sqrt(l * l + 4.0 * abs(E) * step));
      }
      walking = false;
      continue;
    }
    if (!walking) cell = grid_cell((o + s * d).xy, d.xy);
    float tx = d.x > 0.0 ? (float(cell.x + 1) - o.x) / d.x : (d.x < 0.0 ? (float(cell.x) - o.x) / d.x : kConeFar);
    float ty = d.y > 0.0 ? (float(cell.y + 1) - o.y) / d.y : (d.y < 0.0 ? (float(cell.y) - o.y) / d.y : kConeFar);
    float s_exit = max(min(min(tx, ty), s_floor), s);
    float s_hit;
    if (footprint_hit(cell, o, d, e, s, s_exit, s_hit)) return s_hit;
    if (s_exit >= s_floor) {
      escaped = escapes;
      return s_floor;
    }
    s = s_exit;
    walking = true;
    if (tx <= s_exit) cell.x += d.x > 0.0 ? 1 : -1;
    if (ty <= s_exit) cell.y += d.y > 0.0 ? 1 : -1;
  }
  return s;
}
