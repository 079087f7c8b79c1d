// The cone search of build_cone_map compiled for two instruction sets (cone_map.cpp says
// how and why). build_cone_map picks the AVX2 one where the CPU has it; both give the same
// bytes. Private to meso_streams and its tests.
#pragma once

#include "meso/streams/cone_map.hpp"

// Where the second compilation exists: x86-64 with GCC (its `#pragma GCC target`).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define MESO_CONE_MAP_HAS_AVX2 1
#else
#define MESO_CONE_MAP_HAS_AVX2 0
#endif

namespace meso::detail {

Image build_cone_map_baseline(const HeightField& field, const ConeMapOptions& options, Progress& progress);
#if MESO_CONE_MAP_HAS_AVX2
Image build_cone_map_avx2(const HeightField& field, const ConeMapOptions& options, Progress& progress);
#endif
// Whether build_cone_map takes the AVX2 path on this CPU (AVX2, BMI1, BMI2, LZCNT, POPCNT).
bool cone_map_uses_avx2();

}  // namespace meso::detail
