# Every third-party dependency meso uses, found once. All are Debian 12 packages
# (scripts/setup-deps installs them).

find_package(Threads REQUIRED)
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(TBB REQUIRED)
find_package(embree 3 REQUIRED)
find_package(OpenImageIO REQUIRED)
# Debian's OpenImageIO target lists /usr/include/opencv4 (an optional dependency of OIIO's
# own build) among its include folders; CMake rejects a target whose folder is missing, so
# drop folders that do not exist rather than install OpenCV.
foreach(_meso_target OpenImageIO::OpenImageIO OpenImageIO::OpenImageIO_Util)
  if(TARGET ${_meso_target})
    get_target_property(_meso_dirs ${_meso_target} INTERFACE_INCLUDE_DIRECTORIES)
    if(_meso_dirs)
      set(_meso_kept "")
      foreach(_meso_dir IN LISTS _meso_dirs)
        if(EXISTS "${_meso_dir}")
          list(APPEND _meso_kept "${_meso_dir}")
        endif()
      endforeach()
      set_target_properties(${_meso_target} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${_meso_kept}")
    endif()
  endif()
endforeach()
find_package(OpenEXR REQUIRED)
find_package(assimp REQUIRED)
find_package(CLI11 REQUIRED)
find_package(nlohmann_json 3 REQUIRED)
find_package(spdlog REQUIRED)
find_package(CGAL REQUIRED)
find_package(glfw3 3.3 REQUIRED)
find_package(PkgConfig REQUIRED)
pkg_check_modules(EPOXY REQUIRED IMPORTED_TARGET epoxy)
pkg_check_modules(EGL REQUIRED IMPORTED_TARGET egl)

# Debian's OpenMesh 9 ships an OpenMeshConfig.cmake whose import prefix points
# inside the cmake folder itself (include and library paths do not exist), so
# find_package(OpenMesh CONFIG) fails. Find the headers and libraries directly.
find_path(OPENMESH_INCLUDE_DIR OpenMesh/Core/Mesh/TriMeshT.hh REQUIRED)
find_library(OPENMESH_CORE_LIBRARY NAMES OpenMeshCore REQUIRED)
find_library(OPENMESH_TOOLS_LIBRARY NAMES OpenMeshTools REQUIRED)
add_library(meso_openmesh INTERFACE)
target_link_libraries(meso_openmesh INTERFACE ${OPENMESH_TOOLS_LIBRARY} ${OPENMESH_CORE_LIBRARY})
# _USE_MATH_DEFINES: OpenMesh's headers expect M_PI.
target_compile_definitions(meso_openmesh INTERFACE _USE_MATH_DEFINES)
add_library(OpenMesh::OpenMesh ALIAS meso_openmesh)

if(MESO_BUILD_TESTS)
  find_package(GTest REQUIRED)
endif()
if(MESO_BUILD_BENCH)
  find_package(benchmark REQUIRED)
endif()
