// cone_map.cpp's search once more, as code for CPUs with AVX2 (see the top of cone_map.cpp).
#include "cone_map_search.hpp"

#if MESO_CONE_MAP_HAS_AVX2
#define MESO_CONE_MAP_AVX2 1
#include "cone_map.cpp"
#endif
