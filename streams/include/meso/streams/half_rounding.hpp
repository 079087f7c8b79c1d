// Directed rounding of float values to IEEE half (binary16), for streams written with
// --half. A stream whose values are bounds (cone ratios, pyramid minima and maxima,
// distances) stays conservative only if each value is rounded the safe way, never to the
// nearest half: rounding 1/3 to nearest gives 0.333252, below it.
#pragma once

namespace meso {

// The largest half value <= v, as a float. Saturates: v above half's largest finite value
// (65504) gives 65504, never Inf. v must be finite; -65504 > v gives -Inf.
float half_below(float v);

// The smallest half value >= v, as a float. Saturates likewise: v below -65504 gives
// -65504; 65504 < v gives +Inf (callers keep such values in range).
float half_above(float v);

}  // namespace meso
