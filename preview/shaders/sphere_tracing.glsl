#line 1 4
// Sphere tracing (survey 4.3.4) on meso streams sdf (streams/distance_field.hpp).
// Returns the visible point's s (object length along the view ray from the base point).
float sphere_trace(vec3 dir) {
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
  return s;
}
