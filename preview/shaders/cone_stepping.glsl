#line 1 2
// Cone stepping (survey 4.3.5) and relaxed cone stepping (4.4.3) on meso streams cone /
// relaxed-cone (streams/cone_map.hpp): the algorithm of trace_cone_map
// (streams/src/cone_map.cpp), in footprint.glsl's pixel units.

// Texel (i, j) of the cone map (j from the top row) under the map's border rule.
vec3 cone_texel(ivec2 p) {
  ++g_fetches;
  return texelFetch(u_cone, grid_texel_index(p), 0).rgb;
}

// Cone stepping (4.3.5) and relaxed cone stepping (4.4.3) from where the view ray enters the
// top of the height volume. Over texel p at height z >= T_p (its apex) the cone of apex
// (x, T_p) holds no surface above the ray's next stretch, so the ray advances to the cone's
// boundary; when that step would not leave p's footprint, the ray is intersected exactly with
// S over the footprint and moves on to the next texel. A relaxed cone's step may cross the
// surface, at most once: its end below the surface starts a bisection. Returns the visible
// point's s (object length along the view ray from the base point).
// Bent rays (bend != 0: height dir.z s + bend s^2 over a curved base, section 5.1; see
// footprint.glsl): a step goes as far as the whole arc stays inside the cone (the first root
// of a quadratic, exact for either sign of the curvature), so the method stays safe. A ray
// that climbs back out of the height volume without a hit sets `escaped` (a silhouette), as
// does, with silhouettes on, one that leaves a clamped map (which returns the point where it
// left: the surface's footprint ends there).
// Without silhouettes a clamped map's surface goes on beyond the map, its border texels'
// heights repeated outwards (clamp-to-edge, as the reference and the linear searches read
// it). A conservative cone stays safe there: S(y) = S(clamp(y)) and clamping to the map is
// non-expansive, so for a point x off the map the cone of the texel under clamp(x), with its
// apex moved to x, holds no surface either. A relaxed cone's single crossing is not known off
// the map: its steps stop at the map's edge, and off the map the ray is intersected exactly,
// a row or column of cells at a time (the surface there repeats the border's). Before, such
// rays stopped at the border: a quad mapped to UVs 1..2 had every pixel wrong.
float cone_trace(vec3 dir, bool relaxed, float bend, out bool escaped) {
  escaped = false;
  if (!(u_stream_scale > 0.0) || !ray_enters(dir, bend, u_stream_bias + u_stream_scale)) {
    // A flat map (the plane h = bias), or a bent ray that passes over the whole volume.
    escaped = !ray_enters(dir, bend, u_stream_bias);
    return ray_entry(dir, bend, u_stream_bias);
  }
  ivec2 size = textureSize(u_cone, 0);
  vec2 n = vec2(size);
  // The ray o.xy + t d.xy, z(t) = o.z + d.z t + e t^2, t = s - s_top (footprint.glsl).
  vec3 o, d;
  float e;
  float s_top = stream_ray(dir, bend, o, d, e);
  float horizontal = length(d.xy);
  bool escapes;
  float t_floor = ray_end(o, d, e, escapes);  // z = 0, below every point of the surface (or the escape)
  float t = 0.0;
  float t_out = kConeFar;  // clamp: where the ray leaves [0, W] x [0, H]
  bool clamped = u_stream_wrap == 0 && u_silhouettes != 0;  // the surface ends at the map's edge
  bool extended = u_stream_wrap == 0 && u_silhouettes == 0;  // it goes on beyond (clamp-to-edge)
  if (u_stream_wrap == 0) {
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
    if (clamped && t_in > min(t_out, t_floor)) {  // never over the map above the floor
      escaped = true;
      return s_top;
    }
    if (clamped) t = t_in;
  }
  ivec2 cell = grid_cell(o.xy + t * d.xy, d.xy);
  if (clamped) cell = clamp(cell, ivec2(0), size - 1);
  for (int i = 0; i < max(u_iterations, 1); ++i) {
    if (clamped && (any(lessThan(cell, ivec2(0))) || any(greaterThanEqual(cell, size)))) {  // left the map
      escaped = true;
      break;
    }
    vec3 p = o + t * d;
    p.z += e * t * t;
    bool off = extended && (any(lessThan(cell, ivec2(0))) || any(greaterThanEqual(cell, size)));
    // Where the ray leaves the cell's column (tx) and row (ty).
    float tx = d.x > 0.0 ? (float(cell.x + 1) - o.x) / d.x : (d.x < 0.0 ? (float(cell.x) - o.x) / d.x : kConeFar);
    float ty = d.y > 0.0 ? (float(cell.y + 1) - o.y) / d.y : (d.y < 0.0 ? (float(cell.y) - o.y) / d.y : kConeFar);
    if (off && relaxed) {
      // Off the map S(y) = S(clamp(y)): beside an edge it does not vary across the border, in
      // a corner it is the corner texel's height. The ray's stretch over the cells that clamp
      // to one border cell (to where it enters another row or column, or comes back over the
      // map) is intersected at once: in a corner with that height, beside an edge as the ray
      // moved onto the border cell's outer half (where S is constant across), whose z and
      // along-edge path are the ray's.
      ivec2 border = clamp(cell, ivec2(0), size - 1);
      bvec2 across = bvec2(cell.x != border.x, cell.y != border.y);
      vec2 t_axis = vec2(kConeFar);  // per axis: leaving the cell's row (column), or coming back over the map
      for (int k = 0; k < 2; ++k) {
        if (!across[k]) t_axis[k] = k == 0 ? tx : ty;
        else if (cell[k] < 0 && d[k] > 0.0) t_axis[k] = -o[k] / d[k];
        else if (cell[k] >= size[k] && d[k] < 0.0) t_axis[k] = (n[k] - o[k]) / d[k];
      }
      float t_r = max(min(min(t_axis.x, t_axis.y), t_floor), t);
      float t_hit;
      bool found;
      if (across.x && across.y) {
        float reach = ray_first_reach(p.z - grid_height(border), d.z + 2.0 * e * t, e);
        found = t + reach <= t_r;
        t_hit = t + reach;
      } else {
        vec3 oe = o, de = d;
        for (int k = 0; k < 2; ++k)
          if (across[k]) {
            oe[k] = cell[k] < 0 ? 0.25 : n[k] - 0.25;
            de[k] = 0.0;
          }
        found = footprint_hit(border, oe, de, e, t, t_r, t_hit);
      }
      if (found) {
        t = t_hit;
        break;
      }
      if (t_r >= t_floor) {
        t = t_floor;
        escaped = escapes;
        break;
      }
      t = t_r;
      // The next cell, by the axes the stretch ended on (not from the position, which rounding
      // may leave on this side of the line).
      for (int k = 0; k < 2; ++k)
        if (t_axis[k] <= t_r) cell[k] = across[k] ? (cell[k] < 0 ? 0 : size[k] - 1) : cell[k] + (d[k] > 0.0 ? 1 : -1);
      continue;
    }
    vec3 c = cone_texel(cell);
    float ratio = c.g * n.x, apex = c.b;  // ratio in texels per unit height
    float t_exit = max(min(min(tx, ty), t_floor), t);
    float step;
    if (e == 0.0) {
      float den = horizontal + ratio * -d.z;  // 0 only for a flat cone seen straight on
      step = p.z >= apex && den > 0.0 ? ratio * (p.z - apex) / den : 0.0;
    } else {
      // The arc stays in the cone while ratio (z(t + x) - apex) - horizontal x >= 0, a
      // quadratic in x that is >= 0 at x = 0: step to its first root.
      float slope = d.z + 2.0 * e * t;
      step = p.z >= apex ? ray_first_reach(ratio * (p.z - apex), ratio * slope - horizontal, ratio * e) : 0.0;
      // A relaxed cone admits one crossing of a descending ray only: on a convex base the
      // arc's steps end where it stops descending, and a rising ray walks the texels exactly.
      if (relaxed && e > 0.0) step = slope < 0.0 ? min(step, slope / (-2.0 * e)) : 0.0;
    }
    if (relaxed && extended) step = min(step, max(t_out - t, 0.0));  // a relaxed step ends at the map's edge
    if (t + step < t_exit || t_exit <= t) {
      // The cone does not reach beyond the footprint: intersect S over it exactly.
      float t_hit;
      if (footprint_hit(cell, o, d, e, t, t_exit, t_hit)) {
        t = t_hit;
        break;
      }
      if (t_exit >= t_floor) {
        t = t_floor;
        escaped = escapes;
        break;
      }
      t = t_exit;
      // The next texel along the ray: across the edge (or corner) the ray left by.
      if (tx <= t_exit) cell.x += d.x > 0.0 ? 1 : -1;
      if (ty <= t_exit) cell.y += d.y > 0.0 ? 1 : -1;
      continue;
    }
    float tq = min(t + step, min(t_floor, clamped ? t_out : kConeFar));
    vec3 q = o + tq * d;
    q.z += e * tq * tq;
    if (relaxed && grid_surface(q.xy) >= q.z) {
      // The step crossed the surface once (the relaxed cone's guarantee): bisect it.
      float lo = t, hi = tq;
      for (int it = 0; it < u_bisection_steps; ++it) {
        float mid = 0.5 * (lo + hi);
        vec3 r = o + mid * d;
        r.z += e * mid * mid;
        if (grid_surface(r.xy) >= r.z) hi = mid;
        else lo = mid;
      }
      t = hi;
      break;
    }
    t = tq;
    if (escapes && tq >= t_floor) {  // climbed back out of the height volume
      escaped = true;
      break;
    }
    if (clamped && tq >= t_out) {  // left the map (clamp, silhouettes)
      escaped = true;
      break;
    }
    cell = grid_cell(q.xy, d.xy);
    if (clamped) cell = clamp(cell, ivec2(0), size - 1);
  }
  return s_top + t;
}
