#line 1 1
// Exact first intersection of a ray with the filtered height surface over one texel's
// footprint: the algorithm of intersect_footprint (streams/src/height_ray.cpp) that the cone
// and pyramid tracers (trace_cone_map, trace_min_max_pyramid) share. Pixel units as the
// streams use them: x = u W, y = (1 - v) H (rows from the top, texel (i, j) covers
// [i, i+1] x [j, j+1]), z = normalised height in [0, 1] (object height = u_stream_bias +
// u_stream_scale z).

// k modulo n, for any sign of k (GLSL's % is undefined for negative operands).
int grid_wrap_index(int k, int n) {
  if (k < 0) k += n * ((n - 1 - k) / n);
  return k % n;
}

// Texel (i, j) (j from the top row) under the stream's border rule, in GL's texel rows.
ivec2 grid_texel_index(ivec2 p) {
  ivec2 n = textureSize(u_height, 0);  // every stream has the height map's size (checked on load)
  if (u_stream_wrap != 0) p = ivec2(grid_wrap_index(p.x, n.x), grid_wrap_index(p.y, n.y));
  else p = clamp(p, ivec2(0), n - 1);
  return ivec2(p.x, n.y - 1 - p.y);  // GL rows are bottom first
}

// The normalised height of texel (i, j). Cone maps carry it (R, the exact value the cones were
// built from); the pyramid's tracer normalises the height map's texel.
float grid_height(ivec2 p) {
  ++g_fetches;
  ivec2 q = grid_texel_index(p);
  if (u_method == kCone || u_method == kRelaxedCone) return texelFetch(u_cone, q, 0).r;
  return (texelFetch(u_height, q, 0).r - u_stream_bias) / u_stream_scale;
}

// The surface S at pixel position q: bilinear through the texel centres (GL_LINEAR's
// surface, HeightField::bilinear), computed from fetched texels so that it is the exact
// surface the cones were built for, free of the sampler's reduced weight precision.
float grid_surface(vec2 q) {
  vec2 f = q - 0.5;
  vec2 f0 = floor(f);
  vec2 w = f - f0;
  ivec2 i = ivec2(f0);
  float a = grid_height(i), b = grid_height(i + ivec2(1, 0));
  float c = grid_height(i + ivec2(0, 1)), d = grid_height(i + ivec2(1, 1));
  return (a * (1.0 - w.x) + b * w.x) * (1.0 - w.y) + (c * (1.0 - w.x) + d * w.x) * w.y;
}

// The texel a point belongs to: the one it is in, or on an edge the one ahead along d.
ivec2 grid_cell(vec2 p, vec2 d) {
  vec2 f = floor(p);
  ivec2 c = ivec2(f);
  if (p.x == f.x && d.x < 0.0) c.x -= 1;
  if (p.y == f.y && d.y < 0.0) c.y -= 1;
  return c;
}

// Bent rays (silhouettes on a curved base, survey section 5.1): the ray keeps its straight
// horizontal path o.xy + t d.xy while its height over the bent base is
// z(t) = o.z + d.z t + e t^2 (e = 0: the straight ray; e > 0 on a convex base, which falls
// away from the ray). Every tracer below takes e.
//
// The first t > 0 at which z0 + z1 t + e t^2 comes down to 0 from z0 > 0 (0 when z0 <= 0;
// kConeFar when it never does). In the form that stays exact as e -> 0: with e = 0 it is
// z0 / -z1, the straight ray's division.
float ray_first_reach(float z0, float z1, float e) {
  if (z0 <= 0.0) return 0.0;
  if (e == 0.0) return z1 < 0.0 ? z0 / -z1 : kConeFar;
  float disc = z1 * z1 - 4.0 * e * z0;
  if (disc < 0.0) return kConeFar;
  float q = -0.5 * (z1 + (z1 >= 0.0 ? 1.0 : -1.0) * sqrt(disc));  // roots q / e and z0 / q
  float best = kConeFar;
  float r1 = q / e;
  if (r1 > 0.0) best = min(best, r1);
  if (q != 0.0 && z0 / q > 0.0) best = min(best, z0 / q);
  return best;
}

// Where a ray of height z(t) = o.z + d.z t + e t^2 ends: the first t at which it reaches the
// floor z = 0 (below every point of the surface) or, on a convex base where it never does,
// the t at which it climbs back out through the top z = 1 (`escapes`: it met nothing, the
// silhouette). o.z <= 1.
float ray_end(vec3 o, vec3 d, float e, out bool escapes) {
  float t = ray_first_reach(o.z, d.z, e);
  escapes = t >= kConeFar;
  if (escapes && e > 0.0) t = (-d.z + sqrt(max(d.z * d.z - 4.0 * e * (o.z - 1.0), 0.0))) / (2.0 * e);
  return t;
}

// Whether a ray from the base point (height dir.z s + bend s^2, object units, s the length
// along the view ray) ever comes down to object height h: an arc over a convex base may stay
// above it (then it meets nothing below h: a silhouette).
bool ray_enters(vec3 dir, float bend, float h) { return bend <= 0.0 || dir.z * dir.z + 4.0 * bend * h >= 0.0; }

// Where that ray comes down to object height h (the top of the height volume, or a flat map's
// plane): the root toward the eye, 2 h / (dir.z - sqrt(dir.z^2 + 4 bend h)), exact as
// bend -> 0 (h / dir.z). An arc of a concave base that never rises to h is below it
// everywhere: it starts at its highest point instead. (Convex arcs that never come down to h:
// ray_enters is false, and the value is the arc's lowest point.)
float ray_entry(vec3 dir, float bend, float h) {
  if (bend == 0.0) return h / dir.z;
  float disc = dir.z * dir.z + 4.0 * bend * h;
  return disc >= 0.0 ? 2.0 * h / (dir.z - sqrt(disc)) : -dir.z / (2.0 * bend);
}

// The view ray in the streams' pixel units from where it enters the height volume (z = 1, or
// a concave arc's highest point): o.xy + t d.xy, z(t) = o.z + d.z t + e t^2, t = s - s_top
// (returned). The cone and pyramid tracers start from it; call only when the stream is not
// flat and ray_enters the volume's top.
float stream_ray(vec3 dir, float bend, out vec3 o, out vec3 d, out float e) {
  vec2 n = vec2(textureSize(u_height, 0));  // every stream has the height map's size
  float s_top = ray_entry(dir, bend, u_stream_bias + u_stream_scale);
  vec2 uv_top = v_uv + dir.xy * s_top;
  e = bend / u_stream_scale;
  float z_top = bend == 0.0 ? 1.0 : min((dir.z * s_top + bend * s_top * s_top - u_stream_bias) / u_stream_scale, 1.0);
  o = vec3(uv_top.x * n.x, (1.0 - uv_top.y) * n.y, z_top);
  d = vec3(dir.x * n.x, -dir.y * n.y, (dir.z + 2.0 * bend * s_top) / u_stream_scale);
  return s_top;
}

// The stretch of a view ray (height dir.z s + bend s^2 over the base, object units) inside the
// displacement slab [u_h_min, u_h_max]: from s_in, where it comes down to h_max (on a concave
// base whose arc never rises that high, its highest point), to s_out, where it reaches h_min
// or, on a convex base where it never does, climbs back to h_max (`escapes`). The linear
// searches (steep, relief, POM, DIG-DM) march along it.
void ray_slab(vec3 dir, float bend, out float s_in, out float s_out, out bool escapes) {
  s_in = u_h_max / dir.z;
  s_out = u_h_min / dir.z;
  escapes = false;
  if (bend == 0.0) return;
  float disc_in = dir.z * dir.z + 4.0 * bend * u_h_max;
  s_in = ray_entry(dir, bend, u_h_max);
  float disc = dir.z * dir.z + 4.0 * bend * u_h_min;
  if (disc >= 0.0) {
    s_out = 2.0 * u_h_min / (dir.z - sqrt(disc));
  } else {
    // Convex base: the ray never gets down to h_min; it leaves through the top again.
    s_out = (-dir.z + sqrt(max(disc_in, 0.0))) / (2.0 * bend);
    escapes = true;
  }
}

// The first intersection of the ray o.xy + t d.xy, z(t) = o.z + d.z t + e t^2, with S over
// texel `cell`'s footprint for t in [t0, t1] (the ray stays over the footprint there). The
// lines x = i + 1/2 and y = j + 1/2 split the stretch into up to three pieces over each of
// which S is one bilinear polynomial (corners on the half-texel grid), so S(ray(t)) - z(t) is
// a quadratic in t, bent or not.
bool footprint_hit(ivec2 cell, vec3 o, vec3 d, float e, float t0, float t1, out float t_hit) {
  t_hit = t1;
  // S on the footprint's half-texel grid, g[3 b + a] at (i + a/2, j + b/2), from the 3 x 3
  // texels around it, each fetched once (9 fetches, where the pieces' corners evaluated one
  // by one would take up to 48). The same arithmetic as grid_surface() at those points (a
  // texel centre's weight is 1, an edge's 1/2 and 1/2; x first, then y), so the same values.
  float h[9];
  for (int b = 0; b < 3; ++b)
    for (int a = 0; a < 3; ++a) h[3 * b + a] = grid_height(cell + ivec2(a - 1, b - 1));
  float g[9];
  for (int b = 0; b < 3; ++b) {
    // y = j + b/2 lies between texel rows r0 and r0 + 1 of the 3 x 3 (weight wy on the
    // second): rows 0-1 at the top edge, 1-2 with weight 0 at the centre, 1-2 at the bottom.
    int r0 = b == 0 ? 0 : 1;
    float wy = b == 1 ? 0.0 : 0.5;
    for (int a = 0; a < 3; ++a) {
      int c0 = a == 0 ? 0 : 1;
      float wx = a == 1 ? 0.0 : 0.5;
      float top = h[3 * r0 + c0] * (1.0 - wx) + h[3 * r0 + c0 + 1] * wx;
      float bottom = h[3 * r0 + 3 + c0] * (1.0 - wx) + h[3 * r0 + 3 + c0 + 1] * wx;
      g[3 * b + a] = top * (1.0 - wy) + bottom * wy;
    }
  }
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
    int ax = m.x < float(cell.x) + 0.5 ? 0 : 1, ay = m.y < float(cell.y) + 0.5 ? 0 : 1;
    vec2 pc = vec2(cell) + 0.5 * vec2(ax, ay);
    float v00 = g[3 * ay + ax], v10 = g[3 * ay + ax + 1];
    float v01 = g[3 * ay + ax + 3], v11 = g[3 * ay + ax + 4];
    float pa = v10 - v00, pb = v01 - v00, pe = v00 - v10 - v01 + v11;
    // Local coordinates (s, r) in [0, 1]^2 over the piece; the parameter is tau = t - ta,
    // measured from the stretch's start to keep the coefficients small.
    // The bent ray from ta on: z(ta + tau) = z(ta) + (d.z + 2 e ta) tau + e tau^2.
    vec3 a3 = o + ta * d;
    a3.z += e * ta * ta;
    float s0 = 2.0 * (a3.x - pc.x), sd = 2.0 * d.x, r0 = 2.0 * (a3.y - pc.y), rd = 2.0 * d.y;
    float A = pe * sd * rd - e;
    float B = pa * sd + pb * rd + pe * (s0 * rd + r0 * sd) - (d.z + 2.0 * e * ta);
    float C = v00 + pa * s0 + pb * r0 + pe * s0 * r0 - a3.z;
    float L = tb - ta;
    // Grazes: where the ray passes a few float steps under the surface, the rounded
    // coefficients can put S - z just below 0 all along the stretch. A safe method must not
    // step past a crossing its arithmetic hides (bricks at 80 degrees: a ray under a brick's
    // edge by 2e-7 of the relief where it crosses a texel-centre line, between two stretches,
    // found by the double reference), so S - z within rounding of 0 (1e-6 of the terms' size,
    // ~8 float steps) counts as a crossing: at the stretch's ends and where it peaks inside.
    // A ray that passes that close above the surface is taken as touching it.
    float slack = 1e-6 * (abs(v00) + abs(v10) + abs(v01) + abs(v11) + abs(a3.z));
    if (C >= -slack) {
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
    if (A < 0.0) {
      float tau = -B / (2.0 * A);
      if (tau > 0.0 && tau < L && (A * tau + B) * tau + C >= -slack) {
        t_hit = ta + tau;
        return true;
      }
    }
    if ((A * L + B) * L + C >= -slack) {
      // Rounding hid the root: bisect the sign change.
      float lo = 0.0, hi = L;
      for (int it = 0; it < kRootBisectionSteps; ++it) {
        float mid = 0.5 * (lo + hi);
        if ((A * mid + B) * mid + C >= -slack) hi = mid;
        else lo = mid;
      }
      t_hit = ta + hi;
      return true;
    }
  }
  return false;
}
