// bake: per texel of the base mesh's UV layout, a ray along the interpolated base normal to
// the high mesh (Embree 3); the hit gives the displacement and the high mesh's normal.
// Course notes (displacement-authoring-course.md), "Heightfield Displacement Map and
// Normal Map" and "Ray-caster".
#pragma once

#include "meso/core/image.hpp"
#include "meso/core/mesh.hpp"
#include "meso/core/progress.hpp"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace meso {

// Which of the hits along a texel's ray (both ways from the base surface, within reach)
// gives its value. A hit is front-facing when the high surface there faces the way the base
// does (geometric normal . base normal > 0).
enum class HitRule {
  nearest,             // the hit nearest to the base surface (outward on a tie)
  furthest,            // the hit furthest from it
  front_else_nearest,  // the nearest front-facing hit, else the nearest
  front_only,          // the nearest front-facing hit, else a miss
};
const char* hit_rule_name(HitRule r);

// The base surface rays start from: the flat triangles with interpolated normals, or the
// curved PN triangle of each (Vlachos et al. 2001) built from the corner positions and
// normals, for renderers that tessellate the base into that surface.
enum class BakeBasis { linear, pn };

// Which way the green (y) channel of the tangent-space normal map points. The tangent frame
// is the same (MikkTSpace) either way; engines differ only in the sign of y.
enum class NormalY {
  up,    // +y = +v: OpenGL, glTF 2.0, Blender, Unity ("Y+")
  down,  // +y = -v (green = -v): DirectX, Unreal Engine ("Y-"); up's map with y negated
};
const char* normal_y_name(NormalY y);

struct BakeOptions {
  int width = 1024, height = 1024;
  // Ray reach in object units in front of (along +normal) and behind the base surface.
  // <= 0: 5 % of the high mesh's bounding-box diagonal.
  float front = 0.0f, back = 0.0f;
  int dilate = -1;  // texels to fill around charts; < 0 fills the whole image
  HitRule hit = HitRule::nearest;
  bool ignore_backfaces = false;  // drop hits on high surfaces facing against the base
  // Hits closer than this to each other along a ray form a bunch (a fold, a decal floating
  // just above the surface): the rule picks a hit, and the value comes from the hit of its
  // bunch furthest from the base surface. Two candidates the rule ranks within this
  // distance of each other, in different bunches, make the texel ambiguous (reported).
  // Object units; <= 0: 0.1 % of the high mesh's bounding-box diagonal.
  float bunch = 0.0f;
  // Samples per texel, rounded to a square n x n (meso bake refuses other counts rather
  // than round them): stratified at the centres of the texel's n x n sub-texels,
  // box-filtered (mean displacement, mean normal renormalised). Samples may fall on any face
  // of the texel's chart; 1 samples the texel centre exactly.
  int samples = 1;
  // A cage: a mesh with the base's topology (same vertices, same faces in the same order),
  // usually the base pushed outward. Each ray then leaves the base point toward the cage's
  // corresponding point, and reaches outward exactly to it (the cage bounds the search);
  // inward it reaches `back`. The displacement stays the hit's height along the base normal
  // (its distance along the ray times the cosine of the ray's lean). Null: along the
  // interpolated normal, `front` outward.
  const Mesh* cage = nullptr;
  // Pair parts by name: a base part (face group) "wheel_low" only sees the high part(s)
  // "wheel_high", so rays never hit a neighbouring part. Names compare without case, a
  // trailing ".NNN" (Blender's duplicates) and the suffix _low/_lo/_lp resp.
  // _high/_hi/_hp. Base parts without a match see the whole high mesh (and are reported).
  bool match_by_name = false;
  BakeBasis basis = BakeBasis::linear;
  // A detail bump on the high mesh (its UVs, tiled, bilinear; channel 0, mid-grey 0.5
  // neutral): detail_scale * (b - 0.5) object units add to the displacement and its gradient
  // tilts the high normal, as in the course notes' ray-caster. Needs UVs on the high mesh.
  const Image* detail = nullptr;
  float detail_scale = 0.0f;
  // The green convention of normal_ts: down negates its y component texel for texel (after
  // the dilation: exactly up's map with y negated), and nothing else. Recorded in its metadata
  // ("space", "normal_y").
  NormalY normal_y = NormalY::up;
  // Cast the first queries of neighbouring texels together as Embree ray streams (its
  // packet kernels), where the options allow it: one sample per texel, no match_by_name with
  // several parts, a rule other than furthest, without ignore_backfaces. The same queries
  // and hit rules as false (each texel's rays on their own, the reference the tests compare
  // with), faster; Embree's packet kernels may round a hit in the last bits differently.
  bool coherent = true;
};

// Whether `cage` can serve as a cage of `base`: same vertex count and the same vertices on
// every face, in order.
bool same_topology(const Mesh& base, const Mesh& cage);

struct BakeResult {
  // Signed distance from the base surface to the high surface along the base normal, in
  // object units, positive outward. One channel.
  Image displacement;
  // The high mesh's normal in the base's tangent space (tangent_frame.hpp), components in
  // [-1, 1], three channels; (0, 0, 1) where the surfaces are parallel. y along +v, or -v
  // with options.normal_y == down.
  Image normal_ts;
  // Where the rays found the high surface: 1 channel, 1 = hit, 0.75 = a hit whose choice
  // was ambiguous, 0.5 = covered by a base face but no hit within reach (a miss), 0 =
  // outside every chart.
  Image coverage;
  size_t covered_texels = 0;  // texels some UV triangle touches (rasterize_uv), misses included
  size_t hits = 0, misses = 0;
  size_t ambiguous = 0;  // hits whose choice was ambiguous (counted in hits too)
  // Rays cast (Embree queries: intersect, occluded and multi-hit collect, each one
  // traversal), summed over rows in order: the same whatever the thread count.
  uint64_t rays = 0;
  uint64_t stream_rays = 0;  // of those, the ones cast in ray streams (BakeOptions::coherent)
  // Per base face (face order): covered texels, misses and ambiguous texels, for the
  // artist's report.
  std::vector<uint32_t> face_texels, face_misses, face_ambiguous;
  std::vector<std::string> matched_parts, unmatched_parts;  // base part names (match_by_name)
  // With a cage: its vertices lying on their base vertex (closer than the ray offset, 1e-5 of
  // the larger diagonal). A sample where the cage point meets the base point has no
  // direction toward the cage and is cast along the normal with `front` instead, so a cage
  // equal to the base is the same as no cage (the caller should say so).
  size_t cage_vertices_on_base = 0;
  float front = 0, back = 0;  // the reach actually used
  float bunch = 0;            // the bunch distance actually used
  int samples = 1;            // samples per texel actually used (a square)
  // The high surface's normal at each texel's hit in object space (unit, three channels;
  // dilated like the others).
  Image normal_os;
  float min_displacement = 0, max_displacement = 0;  // over hits
};

// Requires UVs on `low` (InputError otherwise is the caller's job: this asserts) and
// vertex normals on both meshes. Deterministic: the result does not depend on the number
// of threads. Texels that miss are filled from hit neighbours by the dilation (and counted).
BakeResult bake(const Mesh& low, const Mesh& high, const BakeOptions& options, Progress& progress = null_progress());

// Maps tangent-space normals in [-1,1] to [0,1] colours for PNG output (n * 0.5 + 0.5).
Image encode_normal_map(const Image& normal_ts);

}  // namespace meso
