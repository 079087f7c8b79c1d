#version 450 core
// The fragment stage of the previewer, in pieces compiled as one shader in this order:
// surface_common.glsl (this: inputs, uniforms, the fetch counter), footprint.glsl (exact
// intersection with the bilinear surface over one texel), cone_stepping.glsl, pyramid.glsl,
// sphere_tracing.glsl, dig.glsl, vdm.glsl, surface.frag (the parallax family and main). Methods of the survey
// (Szirmay-Kalos & Umenhoffer) by section: bump 4.1.1 (normal map only), parallax 4.1.2,
// offset-limited 4.1.3, slope 4.1.4, iterative-parallax 4.2.1, steep 4.3.1, relief 4.4.1,
// pom 4.4.2, cone 4.3.5, relaxed-cone 4.4.3, pyramid 4.3.3, sphere-tracing 4.3.4, vdm 6.3;
// dig: the depth-interval-grid paper (dig.glsl). dstream (dstream.vert) is per vertex.
// Heights are in object units along the base normal, positive outward (meso bake's
// displacement.exr), in [u_h_min, u_h_max]. The ray is expressed in (u, v, h) coordinates,
// straight there: surface.frag's uvh_from_object() (survey eq. 5-7, with the triangle's own
// dp/du and dp/dv instead of an orthonormalised frame).
in vec3 v_position;
in vec3 v_normal;
in vec3 v_tangent;
flat in float v_sign;
in vec2 v_uv;
in vec2 v_uv_scale;

// Per base triangle, read at gl_PrimitiveID when u_face_jacobians is 1 (the per-pixel
// methods' draw of the base, whose primitive t is face t), entries 3t to 3t + 2: the unit
// directions a, b of dp/du and dp/dv with their lengths (object units per UV unit) in .w,
// then a x b (made in double) with .w 0 where the triangle's UVs are degenerate
// (renderer.cpp, face_jacobians()).
layout(std430, binding = 3) readonly buffer FaceJacobians { vec4 face_jacobian[]; };
uniform int u_face_jacobians;

uniform sampler2D u_height;   // R: displacement, object units
uniform sampler2D u_normal;   // RGB: tangent-space normal encoded n * 0.5 + 0.5
uniform vec3 u_eye;
uniform vec3 u_light;         // unit vector toward the light, object space
uniform int u_method;
uniform int u_iterations;
uniform int u_shade;          // 0 lit, 1 uv of the visible point, 2 height of the visible point
uniform mat4 u_view_projection;  // object space to clip space (depth correction)
uniform int u_shadows;        // 0 none, 1 hard, 2 soft (PreviewShadows)
uniform int u_shadow_steps;   // samples along a shadow ray
uniform float u_light_size;   // radians, angular radius of the soft shadows' light
uniform int u_silhouettes;    // 1: curved rays (section 5.1) and footprint discard
uniform int u_wrap;           // 1: the maps tile
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
uniform sampler2D u_pyramid;  // meso streams pyramid (bound when used): the maximum of the filtered
                              // surface over each texel of every level, the levels side by side,
                              // read with texelFetch only
uniform int u_pyramid_levels;
uniform ivec2 u_pyramid_offset[16];  // level l's texel (0, 0) in u_pyramid (rows from the top)
uniform ivec2 u_pyramid_size[16];    // level l's size in texels
// The stream of the method (cone, relaxed-cone or pyramid): its normalisation and border.
uniform float u_stream_scale;  // object height = bias + scale * normalised height
uniform float u_stream_bias;
uniform int u_stream_wrap;     // 1: border wrap (the map tiles), 0: clamp

// Method numbers: the order of preview_methods() in renderer.cpp (per-vertex methods, mesh,
// tessellation and dstream, shade the point their geometry puts there: no search here).
const int kMesh = 0, kTessellation = 1, kBump = 2, kParallax = 3, kOffsetLimited = 4, kSlope = 5,
          kIterativeParallax = 6, kSteep = 7, kRelief = 8, kPom = 9, kCone = 10, kRelaxedCone = 11,
          kPyramid = 12, kSphereTracing = 13, kDig = 14, kVdm = 15, kDstream = 16;
uniform int u_binary_steps;      // relief: halvings after the linear search (PreviewOptions::binary_steps)
uniform int u_bisection_steps;   // relaxed-cone: halvings of the step that crossed the surface

// The cosine of the view ray's angle from the base normal as the parallax family and the
// adaptive step counts take it: its height rate over its length, with the height and the base
// point's motion taken as orthogonal (set by surface.frag's main; 1 straight on, 0 grazing).
float g_view_cos = 1.0;

// Linear-search steps over the whole slab, adapted to the view (survey section 4.4.2, POM
// after Tatarchuk; DIG-DM's "adaptive linear search", its section 5): the budget at grazing
// angles, a quarter of it straight on, where a ray crosses few texels.
int view_adapted_steps(int budget) {
  float b = float(max(budget, 1));
  return max(1, int(round(mix(b, max(0.25 * b, 1.0), clamp(g_view_cos, 0.0, 1.0)))));
}
// Halvings of a cell's root interval where rounding hid a quadratic's root (footprint.glsl):
// numerical, not a quality knob (2^-24 of the step: float's resolution).
const int kRootBisectionSteps = 24;
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

in vec3 v_curvature_dir;  // principal direction d1, object space (0 where no curvature was fitted)
in vec2 v_curvature;      // k1 >= k2, 1 / object units, positive where the base falls away from its normal

// Curvature of the base along the view's horizontal direction, 1 / object units (survey
// section 5.1 with Euler's theorem): k1 cos^2(alpha) + k2 sin^2(alpha), alpha the angle from d1.
float view_curvature(vec3 view, vec3 nn) {
  vec3 across = view - nn * dot(view, nn);
  if (dot(across, across) < 1e-12 || dot(v_curvature_dir, v_curvature_dir) == 0.0) return 0.0;
  vec3 d1 = v_curvature_dir - nn * dot(v_curvature_dir, nn);
  if (dot(d1, d1) < 1e-12) return 0.0;
  float ca = dot(normalize(d1), normalize(across));
  return v_curvature.x * ca * ca + v_curvature.y * (1.0 - ca * ca);
}

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
