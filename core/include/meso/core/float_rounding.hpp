// Rounding a double to float where the rounding itself matters: to see a value as a float
// file, Embree or a shader holds it, or to keep a bound that was computed for the float.
#pragma once

namespace meso {

// `v` rounded to the nearest float. Why not a plain static_cast<float>: Debian 12's GCC 12.2
// at -O2 drops that rounding when its SLP vectorizer packs two double(float(x)) values into
// one register, even through a float array: `std::array<double, 2> f(double a, double r) {
// return {static_cast<float>(r + a), static_cast<float>(r * a)}; }` compiles to no
// conversion at all (with -fno-tree-slp-vectorize, or at -O1, it converts). Found in three
// places of meso (a review of every function whose conversions the vectorizer changed), none
// of which changed an output. The empty asm takes the float in a register and gives it back
// unknown to the optimiser, so the rounding has to happen.
inline float round_to_float(double v) {
  float f = static_cast<float>(v);
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
  __asm__("" : "+x"(f));
#endif
  return f;
}

}  // namespace meso
