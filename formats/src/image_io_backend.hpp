// The seam between meso's image functions (image_io.hpp) and OpenImageIO.
//
// Why a loadable module: Debian's libOpenImageIO links 260 shared libraries (its format
// plugins: GDAL, OpenCV, OpenVDB, DCMTK, FFmpeg, ...). A program linked against it spends
// 0.5-1 s of CPU starting, mostly in the dynamic loader's symbol lookups, before main()
// (`meso --version` 0.7-1.0 s; a test binary without it 0.05 s). So OpenImageIO lives in
// libmeso_image_oiio.so, which image_io.cpp opens on the first image read or write: the
// commands and tests that touch no image (meshreduce, frames, most of uvpack) never load it,
// and every other one loads it once.
//
// The module exports one C function returning this table; the types cross the boundary as
// they are (one compiler, one libstdc++), and so do meso's exceptions (InputError,
// InternalError: matched by type name).
#pragma once

#include "meso/formats/image_io.hpp"

#define MESO_IMAGE_BACKEND_EXPORT __attribute__((visibility("default")))

namespace meso {

struct ImageIoBackend {
  Image (*read_image)(const std::filesystem::path&);
  void (*write_image)(const Image&, const std::filesystem::path&, PixelFormat);
  void (*write_image_levels)(const std::vector<Image>&, const std::filesystem::path&, PixelFormat);
  std::vector<Image> (*read_image_levels)(const std::filesystem::path&);
  void (*write_image_parts)(const std::vector<Image>&, const std::filesystem::path&, PixelFormat);
  std::vector<Image> (*read_image_parts)(const std::filesystem::path&);
};

}  // namespace meso

// The module's one entry point; the suffix changes with the table's layout.
extern "C" MESO_IMAGE_BACKEND_EXPORT const meso::ImageIoBackend* meso_image_io_backend_v1();
