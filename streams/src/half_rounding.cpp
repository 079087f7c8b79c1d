#include "meso/streams/half_rounding.hpp"

#include <Imath/half.h>

namespace meso {

namespace {

constexpr unsigned short kMaxFinite = 0x7BFF;  // 65504
constexpr unsigned short kSign = 0x8000;

// One half ulp from finite h toward +inf (up) or -inf; +-0 step to the smallest subnormal.
Imath::half next_half(Imath::half h, bool up) {
  const unsigned short bits = h.bits();
  Imath::half r;
  if ((bits & 0x7FFF) == 0)
    r.setBits(up ? 0x0001 : static_cast<unsigned short>(kSign | 0x0001));
  else
    r.setBits(static_cast<unsigned short>(bits + (up != ((bits & kSign) != 0) ? 1 : -1)));
  return r;
}

float half_toward(float v, bool up) {
  Imath::half h(v);  // to nearest; overflows to +-Inf
  if (h.isInfinity()) {
    const bool positive = !h.isNegative();
    if (positive != up) h.setBits(static_cast<unsigned short>(kMaxFinite | (positive ? 0 : kSign)));
    return static_cast<float>(h);
  }
  const float f = static_cast<float>(h);
  if (up ? f < v : f > v) h = next_half(h, up);
  return static_cast<float>(h);
}

}  // namespace

float half_below(float v) { return half_toward(v, false); }
float half_above(float v) { return half_toward(v, true); }

}  // namespace meso
