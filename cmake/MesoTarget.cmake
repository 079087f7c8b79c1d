# meso_library(NAME SOURCES... DEPS...) and warning flags for meso's own code.

function(meso_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow=local)
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
    # GCC 12 reports -Wmaybe-uninitialized inside libstdc++ for OpenMesh's property
    # containers (PropertyT<VectorT>::push_back value-initialises); a known false positive.
    target_compile_options(${target} PRIVATE -Wno-maybe-uninitialized)
  endif()
  if(MESO_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()

# A stage library: public headers under include/meso/<stage>/, sources under src/.
function(meso_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(${name} STATIC ${ARG_SOURCES})
  target_include_directories(${name} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
  target_link_libraries(${name} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  meso_warnings(${name})
endfunction()

# meso_test(NAME SOURCES... LIBS... [GL]): a GoogleTest executable whose tests ctest
# discovers. Unit tests live beside the code they test (<stage>/src/*_test.cpp). GL marks
# tests that render through Mesa: its llvmpipe JIT keeps allocations LeakSanitizer reports
# without a usable stack, so leak checking is off for them (and only them) under ASan.
function(meso_test name)
  if(NOT MESO_BUILD_TESTS)
    return()
  endif()
  cmake_parse_arguments(ARG "GL" "" "SOURCES;LIBS" ${ARGN})
  set(_env "")
  if(ARG_GL)
    set(_env ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0")
  endif()
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} meso_test_support GTest::gtest GTest::gtest_main)
  meso_warnings(${name})
  include(GoogleTest)
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60 PROPERTIES TIMEOUT 300 ${_env})
endfunction()
