#line 1 6
// View-dependent displacement mapping (Wang, Wang, Tong, Lin, Hu, Guo, Shum, SIGGRAPH 2003;
// survey section 6.3) on `meso streams vdm` (docs/formats.md): the table d(texel, theta, phi,
// c) holds where a view ray entering the top of the height field above a texel centre meets
// the surface, as a horizontal distance in units of u, or a miss (the ray left the height
// field bent by the base's curvature c: a silhouette). PCA-compressed:
// d = mean[dir] + sum_k w_k(texel) basis_k[dir].
//
// Geometry (vdm.hpp): the table's box is 1 wide in u, H/W deep, `relief` high, all in units
// of u (texels square). A view ray per unit object length advances dir = (du, dv, dh)
// (surface.frag's uvh_from_object), i.e. du and (H/W) dv in units of u, and dh in object
// height, i.e. dh relief/scale in units of u; theta and phi are measured in that box.
// Curvature along the view direction (survey eq. 13 and Euler's theorem): with the principal
// curvatures k1 >= k2 along d1, d2 and alpha the angle of the view's horizontal direction from
// d1, c = k1 cos^2(alpha) + k2 sin^2(alpha) per object unit, times the object length of one
// u-unit along the view to give it per unit of u (positive: the base falls away from its
// normal, as vdm.hpp's).
//
// Lookup: the weights are interpolated bilinearly at the entry point (the table is linear in
// them), directions linearly in theta (clamped), phi (wrapping) and c (clamped) over the 8
// surrounding samples, each a (rank + 1)-term dot product. Misses do not blend: the hits'
// distances are averaged with their interpolation weights, and the point is a silhouette
// (the fragment is discarded) when the misses carry more than half of the weight.

uniform sampler2DArray u_vdm_weights;  // layer l: components 4l .. 4l+3 (filtered, GL_LINEAR)
uniform sampler2D u_vdm_basis;         // (rank + 1) x directions, R: column 0 mean, k + 1 basis k (texelFetch)
uniform int u_vdm_rank;
uniform int u_vdm_theta;
uniform int u_vdm_phi;
uniform float u_vdm_theta_max;         // radians
uniform int u_vdm_curvature_count;
uniform float u_vdm_curvatures[64];    // increasing, per unit of u
uniform float u_vdm_relief;            // height range in units of u
uniform float u_vdm_scale;             // object height = bias + scale * normalised height
uniform float u_vdm_bias;
uniform float u_vdm_aspect;            // H / W of the map

const int kVdmMaxLayers = 16;  // rank <= 64 (renderer.hpp's kMaxVdmRank)

// One table entry from the interpolated weights.
float vdm_entry(vec4 w[kVdmMaxLayers], int dir) {
  float d = texelFetch(u_vdm_basis, ivec2(0, dir), 0).r;
  ++g_fetches;
  for (int k = 0; k < u_vdm_rank; ++k) {
    d += w[k / 4][k % 4] * texelFetch(u_vdm_basis, ivec2(k + 1, dir), 0).r;
    ++g_fetches;
  }
  return d;
}

// The visible point's UV for the view ray `view` (unit, object space, from the eye) through
// the base point at v_uv, in the orthonormal tangent frame tn, bn, nn; `dir` is the ray's
// advance per unit length in (u, v, object height). False: a silhouette (no hit).
bool vdm_trace(vec3 view, vec3 tn, vec3 bn, vec3 nn, vec3 dir, out vec2 uv) {
  uv = v_uv;
  if (!(u_vdm_scale > 0.0)) {
    // A flat map: the plane h = bias, where the ray meets it. (Through the table, whose
    // distances hold its own relief, 99 % of the pixels had been wrong on the demo's base
    // with a flat 128² map.)
    uv = v_uv + dir.xy * (u_vdm_bias / min(dir.z, -1e-30));
    return true;
  }
  float to_u = u_vdm_relief / max(u_vdm_scale, 1e-30);  // object height -> units of u
  vec2 h = vec2(dir.x, dir.y * u_vdm_aspect);            // horizontal advance, units of u
  float len_h = length(h);
  float theta = atan(len_h, max(-dir.z * to_u, 0.0));
  float phi = atan(h.y, h.x);
  if (phi < 0.0) phi += 6.28318531;

  // Curvature along the view direction, per unit of u: the base point moves by across (J
  // dir.xy) per unit length of the ray while the ray advances len_h in units of u.
  vec3 across = view - nn * dir.z;
  float object_per_u = len_h > 1e-20 ? length(across) / len_h : v_uv_scale.x;
  float c = view_curvature(view, nn) * object_per_u;

  // Entry point: where the ray is at the top of the height field (normalised height 1).
  vec2 entry = v_uv + dir.xy * ((u_vdm_bias + u_vdm_scale) / dir.z);

  vec4 w[kVdmMaxLayers];
  int layers = (u_vdm_rank + 3) / 4;
  for (int l = 0; l < kVdmMaxLayers; ++l) {
    w[l] = vec4(0.0);
    if (l < layers) {
      w[l] = textureLod(u_vdm_weights, vec3(entry, float(l)), 0.0);
      ++g_fetches;
    }
  }

  // Continuous table coordinates: theta_i = (i + 1/2) / n theta_max, phi_j = 2 pi j / n.
  float ti = clamp(theta / u_vdm_theta_max * float(u_vdm_theta) - 0.5, 0.0, float(u_vdm_theta - 1));
  float pj = phi / 6.28318531 * float(u_vdm_phi);
  int i0 = int(floor(ti)), i1 = min(i0 + 1, u_vdm_theta - 1);
  int j0 = int(floor(pj)) % u_vdm_phi, j1 = (j0 + 1) % u_vdm_phi;
  float fi = ti - float(i0), fj = fract(pj);
  int k0 = 0, k1 = 0;
  float fk = 0.0;
  if (u_vdm_curvature_count > 1) {
    if (c <= u_vdm_curvatures[0]) {
      k0 = k1 = 0;
    } else if (c >= u_vdm_curvatures[u_vdm_curvature_count - 1]) {
      k0 = k1 = u_vdm_curvature_count - 1;
    } else {
      while (k0 + 1 < u_vdm_curvature_count - 1 && u_vdm_curvatures[k0 + 1] <= c) ++k0;
      k1 = k0 + 1;
      fk = (c - u_vdm_curvatures[k0]) / max(u_vdm_curvatures[k1] - u_vdm_curvatures[k0], 1e-30);
    }
  }

  float hit_weight = 0.0, distance = 0.0;
  for (int corner = 0; corner < 8; ++corner) {
    int k = (corner & 4) != 0 ? k1 : k0;
    int i = (corner & 2) != 0 ? i1 : i0;
    int j = (corner & 1) != 0 ? j1 : j0;
    float weight = ((corner & 4) != 0 ? fk : 1.0 - fk) * ((corner & 2) != 0 ? fi : 1.0 - fi) * ((corner & 1) != 0 ? fj : 1.0 - fj);
    if (weight <= 0.0) continue;
    float d = vdm_entry(w, (k * u_vdm_theta + i) * u_vdm_phi + j);
    if (d > -0.5) {
      hit_weight += weight;
      distance += weight * max(d, 0.0);
    }
  }
  if (hit_weight < 0.5) return false;
  distance /= hit_weight;
  uv = entry + distance * vec2(cos(phi), sin(phi) / u_vdm_aspect);
  return true;
}
