#line 1 5
// Depth-interval-grid displacement mapping, DIG-DM (Judnich & Ling, "Fast Per-Pixel
// Displacement Mapping with Screen-Space Depth Interval Grids"): two passes.
// Pass 1 (u_dig_pass = 1) renders one ray per grid corner, the pixel at the bottom-left
// corner of every 4 x 4 block (renderer.cpp maps grid texel (i, j) onto pixel (4i, 4j)), and
// stores its ray depth (section 4.2: the normalised height of the ray, 0 at the slab's bottom
// h_min, 1 at its top h_max) at the last linear-search sample above the surface, -1 where no
// mesh is; and the fetches it took. Pass 2 (u_dig_pass = 2) bounds each pixel's search to the
// interval of its block's four corner depths (eq. 1), widened by epsilon_1 = one pass-1 step
// above (the stored sample may be that far above the crossing, section 4.2), at least
// u_dig_epsilon, and epsilon_2 = one step below, then searches it linearly with the same step height (section 5.1, eq. 2:
// a fixed step, so a short interval takes few steps) and refines by one secant step. The
// budget u_iterations is the number of linear steps over the whole slab in either pass at
// grazing angles, adapted to the view as POM's (dig_steps). Blocks whose corner rays lie
// more than u_dig_fallback texels apart across the ray's path search the whole slab instead.
// Not a safe method: a feature between the corner rays that the corners all miss is missed.

uniform int u_dig_pass;     // 1: the grid, 2: the image
uniform sampler2D u_dig;    // pass 1's output: R = corner depth (-1: no mesh), G = fetches
const int kDigBlock = 4;
// epsilon_1 at least this much of the slab (eq. 1's bias for approximation error;
// PreviewOptions::dig_epsilon): a feature narrower than a block that rises above all four
// corner rays is still found when it rises less than this. Measured on minified maps (a pixel
// over ~4 texels): the default 0.1 lowers the wrong hits of rocks at 60 degrees from 1.7 % to
// 1.3 % at 16 steps for +0.5 fetches per pixel.
uniform float u_dig_epsilon;
// Texels across the ray's path between a block's corner rays beyond which the block's pixels
// search the whole slab (PreviewOptions::dig_fallback_texels; 1e30: never).
uniform float u_dig_fallback;

// The view ray's descent through the slab; `bend` bends it over a curved base (silhouettes,
// section 5.1; ray_slab in footprint.glsl). The normalised depth z of a point is its fraction
// of the descent: 1 where the ray comes in at h_max, 0 where it reaches h_min or, on a convex
// base where it never does, at its lowest point (the two cases meet there, so neighbouring
// rays' depths stay comparable, which the grid's intervals need). Such a ray's rising stretch
// after its lowest point, up to where it leaves the slab (s_exit), is searched after the
// descent by the pixel pass, as relief mapping searches it.
struct DigRay {
  vec3 dir;
  float bend, s_in, s_out, s_exit;
  bool escapes;
};
DigRay dig_ray(vec3 dir, float bend) {
  DigRay r;
  r.dir = dir;
  r.bend = bend;
  ray_slab(dir, bend, r.s_in, r.s_exit, r.escapes);
  r.s_out = r.escapes ? -dir.z / (2.0 * bend) : r.s_exit;
  return r;
}

// Object length s along the view ray at which it has normalised depth z.
float dig_s(DigRay r, float z) { return r.bend == 0.0 ? mix(u_h_min, u_h_max, z) / r.dir.z : mix(r.s_out, r.s_in, z); }

// The ray's height minus the surface's at s.
float dig_gap(DigRay r, float s) { return r.dir.z * s + r.bend * s * s - height_at(v_uv + r.dir.xy * s); }

// Linear-search steps over the whole slab, both passes: view_adapted_steps of the budget. A
// corner ray and the pixel rays of its block look almost the same way, so their counts differ
// by at most one (dig_trace widens its interval by a corner ray's step for that).
int dig_steps() { return view_adapted_steps(u_iterations); }

// Pass 1: the steep-parallax linear search (4.3.1) over the whole slab; the normalised depth
// of the last sample above the surface (1 when the first is already below).
float dig_corner_depth(vec3 dir, float bend) {
  DigRay r = dig_ray(dir, bend);
  int steps = dig_steps();
  float z_above = 1.0;
  for (int i = 0; i <= steps; ++i) {
    float z = 1.0 - float(i) / float(steps);
    if (dig_gap(r, dig_s(r, z)) <= 0.0) break;
    z_above = z;
  }
  return z_above;
}

// Pass 2: the visible point's s. `amortised` receives this pixel's share of pass 1's fetches
// (the block's corner ray over the block's 16 pixels).
float dig_trace(vec3 dir, float bend, vec2 uv_dx, vec2 uv_dy, out float amortised, out bool escaped) {
  DigRay r = dig_ray(dir, bend);
  escaped = false;
  ivec2 block = ivec2(gl_FragCoord.xy) / kDigBlock;
  float lo = 2.0, hi = -2.0;
  bool known = true;
  for (int k = 0; k < 4; ++k) {
    vec2 corner = texelFetch(u_dig, block + ivec2(k & 1, k >> 1), 0).rg;
    if (k == 0) amortised = corner.g / float(kDigBlock * kDigBlock);
    known = known && corner.r >= 0.0;
    lo = min(lo, corner.r);
    hi = max(hi, corner.r);
  }
  int steps = dig_steps();
  float step = 1.0 / float(steps);
  // epsilon_1 and epsilon_2 cover one step of the corner rays' search, whose count was
  // rounded from their own directions (dig_steps): up to one fewer than this pixel's.
  float corner_step = 1.0 / float(max(steps - 1, 1));
  // Along the ray's path the corner rays sweep the texels themselves; across it they are a
  // block apart in texture space (the screen derivatives of the UVs, in texels: `across`;
  // straight on, every way is across). Where that exceeds u_dig_fallback (minified regions),
  // a feature between them rises unseen, whatever epsilon_1: the block searches the whole
  // slab, as POM does (on the default frames of bench/preview_curves this brought DIG-DM's
  // floor at large budgets most of the way down to POM's; docs/benchmarks.md).
  vec2 texels = vec2(textureSize(u_height, 0));
  vec2 ax = uv_dx * texels, ay = uv_dy * texels, path = dir.xy * texels;
  float across = float(kDigBlock) * max(length(ax), length(ay));
  if (dot(path, path) > 0.0) {
    vec2 n = normalize(vec2(-path.y, path.x));
    across = float(kDigBlock) * max(abs(dot(ax, n)), abs(dot(ay, n)));
  }
  known = known && across <= u_dig_fallback;
  // Silhouette blocks (a corner off the mesh) and minified ones search the whole slab.
  float top = known ? min(1.0, hi + max(corner_step, u_dig_epsilon)) : 1.0;
  float bottom = known ? max(0.0, lo - corner_step) : 0.0;
  float s_prev = dig_s(r, top);
  float d_prev = dig_gap(r, s_prev);  // ray height minus surface height
  if (d_prev <= 0.0) return s_prev;
  // Fixed step height through the interval; if the crossing is not in it (the grid's
  // approximation failed), on to the slab's bottom, so a pixel is never left without a hit.
  int n = int(ceil((top - bottom) / step - 1e-4)) + int(ceil(bottom / step - 1e-4));
  // A bent ray that never reaches h_min rises back through the slab past its lowest point:
  // then on with the same step along the ray until it leaves (meeting nothing there, it
  // escapes: a silhouette).
  float ds = (r.s_out - r.s_in) * step;
  int rising = r.escapes && ds > 0.0 ? int(ceil((r.s_exit - r.s_out) / ds)) : 0;
  for (int i = 1; i <= n + rising; ++i) {
    float s = i <= n ? dig_s(r, max(top - float(i) * step, 0.0)) : min(r.s_out + float(i - n) * ds, r.s_exit);
    float d = dig_gap(r, s);
    if (d <= 0.0) {
      // The confined search is "any regular per-pixel algorithm" (paper, section 3); this
      // one refines as POM does, by one secant step between the last two samples (survey
      // 4.4.2), which costs no fetch, where the paper's relief mapping bisects (5.2).
      float w = d_prev / max(d_prev - d, 1e-20);
      return mix(s_prev, s, clamp(w, 0.0, 1.0));
    }
    s_prev = s;
    d_prev = d;
  }
  escaped = r.escapes;
  return dig_s(r, 0.0);
}
