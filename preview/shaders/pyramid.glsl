#line 1 3
// Pyramidal (quadtree) displacement mapping (survey 4.3.3) on meso streams pyramid
// (streams/pyramid.hpp): every level holds, per texel, the exact maximum (G) of the filtered
// surface over the texel's footprint, so the box [footprint] x [0, max] contains the surface
// there. The traversal is the stackless form of trace_min_max_pyramid (streams/src/pyramid.cpp):
// at the current level, a box the ray passes over is skipped to where the ray leaves it (and
// the walk climbs one level, to take longer strides where the surface is low); where the ray
// comes down into the box it advances to the box's top and descends; in a level-0 footprint
// the ray is intersected exactly with the bilinear surface (footprint.glsl). Every decision is
// conservative, so the first intersection is never skipped (the safe-method guarantee); the
// budget counts loop passes. Footprint of texel x of a level with n_l texels: [x, x+1] W/n_l
// pixels (any sizes, powers of two or not: coarser maxima cover every finer texel they overlap).

// The pixel-unit exits of the ray o + t d from the cell [lo, lo + size]: (t_x, t_y).
vec2 pyramid_cell_exits(vec2 lo, vec2 size, vec3 o, vec3 d) {
  float tx = d.x > 0.0 ? (lo.x + size.x - o.x) / d.x : (d.x < 0.0 ? (lo.x - o.x) / d.x : kConeFar);
  float ty = d.y > 0.0 ? (lo.y + size.y - o.y) / d.y : (d.y < 0.0 ? (lo.y - o.y) / d.y : kConeFar);
  return vec2(tx, ty);
}

// Returns the visible point's s (object length along the view ray from the base point).
// Bent rays (bend != 0, footprint.glsl): a box is skipped when the arc's lowest point over it
// is above the box (the ends, or the vertex of a convex arc between them), and the descent to
// a box's top is the arc's first reach of it: still exact. A ray that climbs back out of the
// height volume without a hit sets `escaped` (a silhouette), as does, with silhouettes on,
// one that leaves a clamped map (which returns the point where it left).
float pyramid_trace(vec3 dir, float bend, out bool escaped) {
  escaped = false;
  if (!(u_stream_scale > 0.0) || !ray_enters(dir, bend, u_stream_bias + u_stream_scale)) {
    // A flat map (the plane h = bias), or a bent ray that passes over the whole volume.
    escaped = !ray_enters(dir, bend, u_stream_bias);
    return ray_entry(dir, bend, u_stream_bias);
  }
  vec2 n = vec2(textureSize(u_height, 0));
  // The ray o.xy + t d.xy, z(t) = o.z + d.z t + e t^2, t = s - s_top (footprint.glsl).
  vec3 o, d;
  float e;
  float s_top = stream_ray(dir, bend, o, d, e);
  bool escapes;
  float t_end = ray_end(o, d, e, escapes);  // z = 0: below every point of the surface (or the escape)
  float t_stop = t_end;                     // t_end, or where the ray leaves a clamped map
  float t = 0.0;
  if (u_stream_wrap == 0 && u_silhouettes != 0) {
    // Clamp with silhouettes: the surface's footprint is the map; start where the ray comes
    // over it and stop where it leaves it, keeping that point (as cone stepping does).
    // Without silhouettes the clamped surface goes on beyond the map (clamp-to-edge), and the
    // walk goes on over it: a cell off the map is bounded by the box of the level's border
    // cell it clamps to (its texels' surface holds every height the extension repeats), and
    // at level 0 intersected exactly (footprint_hit clamps the heights it reads).
    float t_in = 0.0, t_out = kConeFar;
    for (int k = 0; k < 2; ++k) {
      if (d[k] != 0.0) {
        float ta = -o[k] / d[k], tb = (n[k] - o[k]) / d[k];
        t_in = max(t_in, min(ta, tb));
        t_out = min(t_out, max(ta, tb));
      } else if (o[k] < 0.0 || o[k] > n[k]) {
        t_out = -1.0;
      }
    }
    if (t_in > min(t_out, t_end)) {  // never over the map above the floor
      escaped = true;
      return s_top;
    }
    t = t_in;
    t_end = min(t_end, t_out);
  }
  int top_level = u_pyramid_levels - 1;
  int atlas_rows = textureSize(u_pyramid, 0).y;
  int level = top_level;
  bool hit = false;
  for (int i = 0; i < max(u_iterations, 1) && t < t_end; ++i) {
    ivec2 size = u_pyramid_size[level];
    vec2 cs = n / vec2(size);  // the level's texel in pixels
    ivec2 cell = grid_cell((o.xy + t * d.xy) / cs, d.xy);
    vec2 exits = pyramid_cell_exits(vec2(cell) * cs, cs, o, d);
    if (min(exits.x, exits.y) <= t) {
      // Rounding put the point on the cell's far side: the next cell along the ray.
      if (exits.x <= t) cell.x += d.x > 0.0 ? 1 : -1;
      if (exits.y <= t) cell.y += d.y > 0.0 ? 1 : -1;
      exits = pyramid_cell_exits(vec2(cell) * cs, cs, o, d);
    }
    float t_exit = max(min(min(exits.x, exits.y), t_end), t);
    ivec2 fetch = u_stream_wrap != 0 ? ivec2(grid_wrap_index(cell.x, size.x), grid_wrap_index(cell.y, size.y))
                                     : clamp(cell, ivec2(0), size - 1);
    ++g_fetches;
    // The height normalisation in the shader may round a texel one ulp over the stored maximum.
    ivec2 at = u_pyramid_offset[level] + fetch;
    float box_top = texelFetch(u_pyramid, ivec2(at.x, atlas_rows - 1 - at.y), 0).r + 1e-6;
    float z_low = o.z + t_exit * d.z;  // the straight ray's lowest point over the cell: its exit
    if (e != 0.0) {
      float t_vertex = -d.z / (2.0 * e);  // a convex arc's lowest point, when between the ends
      z_low = min(z_low + e * t_exit * t_exit, o.z + t * d.z + e * t * t);
      if (e > 0.0 && t_vertex > t && t_vertex < t_exit) z_low = min(z_low, o.z + t_vertex * (d.z + e * t_vertex));
    }
    if (z_low > box_top) {
      // The ray is above the box all the way across: skip it, climb a level.
      t = t_exit;
      level = min(level + 1, top_level);
      continue;
    }
    if (e == 0.0) {
      t = max(t, (o.z - box_top) / -d.z);  // down to the box's top
    } else {
      float z = o.z + t * d.z + e * t * t;
      float reach = ray_first_reach(z - box_top, d.z + 2.0 * e * t, e);  // 0 when already inside
      if (t + reach <= t_exit) t += reach;  // (else rounding: stay, the finer levels decide)
    }
    if (level > 0) {
      --level;
      continue;
    }
    float t_hit;
    if (footprint_hit(cell, o, d, e, t, t_exit, t_hit)) {
      t = t_hit;
      hit = true;
      break;
    }
    t = t_exit;
    level = min(level + 1, top_level);
  }
  // No hit: the ray climbed back out (bent) or left a clamped map (which keeps that point).
  escaped = !hit && t >= t_end && (escapes || t_end < t_stop);
  return s_top + min(t, t_end);
}
