// uvpack check: is the UV mapping unique at a given texture resolution? (Course notes,
// "Unique Texture Mapping" and "Unique Mapping Checker".)
#pragma once

#include "meso/core/image.hpp"
#include "meso/core/mesh.hpp"
#include "meso/uvpack/uv_overlaps.hpp"

#include <cstddef>
#include <utility>
#include <vector>

namespace meso {

struct UvCheckOptions {
  int size = 1024;       // texels per side of the square texture
  double padding = 0.0;  // texels charts must keep between them (0: no padding check)
  bool overlay = true;   // make the overlay image (size^2 RGBA floats)
  // Check MIP levels 0..mip_safe (-1: not checked); size must be a multiple of 2^mip_safe.
  int mip_safe = -1;
  // The texture is sampled with repeat addressing (GL_REPEAT): padding and bilinear reads are
  // also measured across its borders (find_uv_overlaps' wrap). Clamp-to-edge if false.
  bool wrap = false;
};

// At MIP level `level`, `texels` level-k texels that a bilinear lookup inside chart `chart`
// reads hold values of chart `reads` (after dilation and box filtering, see check_uv_mapping).
struct MipViolation {
  int level = 0;
  int chart = 0, reads = 0;
  size_t texels = 0;
};

// Texels per object-space unit of one chart: sqrt(UV area in texels^2 / surface area).
struct ChartDensity {
  int chart = 0;
  double texels_per_unit = 0;
};

struct UvCheckReport {
  int width = 0, height = 0;
  size_t charts = 0;                   // UV-connected components (faces sharing UVs across an edge)
  // Exact and resolution-independent: faces whose UV interiors overlap another face's
  // (uv_overlaps.hpp), and the pairs. Sorted.
  std::vector<int> overlapping_faces;
  std::vector<std::pair<int, int>> overlap_pairs;
  // At this resolution: faces touching a texel that another chart also touches (bilinear
  // filtering would mix the charts there). Sorted.
  std::vector<int> shared_texel_faces;
  std::vector<int> flipped_faces;      // UV winding against the majority (by area) of their chart; sorted
  std::vector<int> degenerate_faces;   // zero UV area, or thinner than double arithmetic resolves at `size` (touch no texel); sorted
  std::vector<int> outside_faces;      // a UV outside [0,1]; sorted
  std::vector<ChartGap> padding_violations;  // chart pairs closer than options.padding texels
  std::vector<ChartDensity> texel_density;   // per chart with surface area
  std::vector<MipViolation> mip_violations;  // by level, chart, reads; empty unless options.mip_safe >= 0
  int mip_safe_levels = -1;            // largest K <= options.mip_safe with levels 0..K clean (-1: level 0 fails or not checked)
  size_t texels_touched = 0;           // texels touched by at least one face
  size_t texels_shared = 0;            // texels touched by two or more charts
  double utilization = 0;              // sum of the faces' UV areas / the texture's area (true coverage; overlaps count twice)
  double texel_coverage = 0;           // texels_touched / all texels
  // RGBA overlay, [0,1]: opaque red where charts share a texel, translucent blue where one
  // chart touches it, transparent elsewhere.
  Image overlay;
};

// Conservative rasterisation: a texel is touched by a face when the face's UV triangle and
// the texel's square share interior points. Bilinear filtering of a chart also reads one
// more ring of texels around those, so charts that must not mix under filtering need
// --padding of at least 1 texel (2 with the bake's dilation), which the padding check verifies.
// Mip safety (options.mip_safe = K): the map meso bake writes is predicted exactly: touched
// texels hold their chart's values, every other texel those of its nearest touched texel
// (dilation_sources, the bake's dilation, ties as it breaks them), level k+1 is the 2 x 2
// mean of level k. A level-k texel holds chart c's values alone when all its 2^k x 2^k
// level-0 texels do. A bilinear lookup at a point of chart c reads the level-k texels
// within one (Chebyshev; cut at the borders, or wrapped with options.wrap, while the
// dilation stays in the plane as the bake's does) of a level-k texel containing a texel c touches;
// each of them holding any other chart's value is a violation. A texel several charts touch
// (reported as shared) counts as holding all of their values, whichever the bake writes, so
// the verdict does not depend on the faces' order.
// Face indices are 0-based in the mesh's face order (the input file's order). Requires UVs
// and a compacted mesh (no deleted elements), as read_mesh() and reduce_mesh() return.
UvCheckReport check_uv_mapping(const Mesh& mesh, const UvCheckOptions& options);

}  // namespace meso
