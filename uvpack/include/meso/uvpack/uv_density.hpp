// Frequency-aware texel allocation for uvpack pack --density MAP: charts whose data has more
// detail get more texels. The measure is the signal's own derivative, as in signal-specialized
// parametrization (Sander, Gortler, Snyder & Hoppe, EGWR 2002): a chart whose map changes
// fast needs more texels per UV unit to keep the change per texel the same.
#pragma once

#include "meso/core/image.hpp"
#include "meso/core/mesh.hpp"

#include <cstddef>
#include <vector>

namespace meso {

struct ChartDetail {
  int chart = 0;       // uv_charts() index
  size_t texels = 0;   // map texels the chart touches alone (conservatively, as uv_check)
  double detail = 0;   // RMS gradient of the map over those texels, map values per UV unit (all channels)
  double scale = 1;    // relative linear scale to pack the chart with: detail / reference, clamped
};

// The map is sampled in the mesh's current UV layout (any resolution; texel centres at +0.5,
// v up, image.hpp). Per chart: D_c = sqrt(mean |grad f|^2) over the texels it touches alone,
// central differences where both neighbours belong to the chart, one-sided where one does.
// scale_c = clamp(D_c / D_ref, 1 / max_factor, max_factor), D_ref the RMS of D over all
// charts weighted by their texels, so that a map of uniform detail gives 1 everywhere and
// the texel budget moves from flat charts to detailed ones. Scaling a chart by scale_c keeps
// its change per texel near D_ref / (atlas scale) until the clamp. A constant map, or charts
// touching no texel alone, give 1. Deterministic. Requires UVs.
std::vector<ChartDetail> measure_chart_detail(const Mesh& mesh, const Image& map, double max_factor = 2.0);

}  // namespace meso
